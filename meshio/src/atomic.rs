//! The one way hce writes a file: into a temporary file beside the destination, flushed to disk,
//! then renamed over it, so that a reader (a viewer watching the output, a build system, the
//! next `hce` command) never sees half a file, and a failed write leaves the old file in place.
//! The rename is atomic because the temporary file is in the destination's own directory, on
//! the same file system.

use std::io::Write;
use std::path::{Path, PathBuf};

/// A file that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write: {source}", path.display())]
pub struct FileWriteError {
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

/// Writes `bytes` to a temporary file in `path`'s directory, then renames it to `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileWriteError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams a file through `fill` into a buffered temporary file in `path`'s directory,
/// flushes it to disk, then renames it to `path`. On any error the temporary file is removed.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), FileWriteError> {
    let tmp = AtomicFile::create(path)?;
    let filled = (|| {
        let mut f = std::io::BufWriter::with_capacity(1 << 20, tmp.file());
        fill(&mut f)?;
        f.flush()
    })();
    match filled {
        Ok(()) => tmp.commit(),
        Err(source) => Err(tmp.error(source)),
    }
}

/// A file being written atomically, for writers that need the file itself (positioned writes
/// from another thread, as the streamed GLB of [`crate::export`]): a temporary file in the
/// destination's directory, renamed over it by [`AtomicFile::commit`] once flushed to disk,
/// and removed if it is dropped before.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    file: Option<std::fs::File>,
}

impl AtomicFile {
    /// Creates the temporary file for `path`.
    pub fn create(path: &Path) -> Result<Self, FileWriteError> {
        let io = |source| FileWriteError {
            path: path.to_owned(),
            source,
        };
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
            _ => PathBuf::from("."),
        };
        let name = path.file_name().ok_or_else(|| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the path names no file",
            ))
        })?;
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.tmp", std::process::id()));
        let tmp = dir.join(tmp_name);
        let file = std::fs::File::create(&tmp).map_err(io)?;
        Ok(Self {
            path: path.to_owned(),
            tmp,
            file: Some(file),
        })
    }

    /// The temporary file (unbuffered).
    pub fn file(&self) -> &std::fs::File {
        self.file.as_ref().expect("the file is open until commit")
    }

    /// `source` as the error of writing the destination.
    pub fn error(&self, source: std::io::Error) -> FileWriteError {
        FileWriteError {
            path: self.path.clone(),
            source,
        }
    }

    /// Flushes the file to disk and renames it over the destination; on error the temporary
    /// file is removed and the destination left as it was.
    pub fn commit(mut self) -> Result<(), FileWriteError> {
        let file = self.file.take().expect("the file is open until commit");
        let result = file.sync_all().and_then(|()| {
            drop(file);
            std::fs::rename(&self.tmp, &self.path)
        });
        match result {
            Ok(()) => {
                // Renamed: nothing left to remove.
                self.tmp = PathBuf::new();
                Ok(())
            }
            Err(source) => Err(self.error(source)),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        self.file = None;
        if !self.tmp.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_replaced_whole_and_no_temporary_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.hce");
        std::fs::write(&path, b"old contents").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("scene.hce")]);
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.obj");
        std::fs::write(&path, b"old").unwrap();
        let e = write_atomic_with(&path, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(
            e.to_string().contains("out.obj: cannot write: disk full"),
            "{e}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let missing = dir.path().join("no/such/dir/x.hce");
        let e = write_atomic(&missing, b"x").unwrap_err();
        assert!(e.to_string().contains("no/such/dir/x.hce"), "{e}");
    }
}
