//! The one place that turns a command's error into its documented exit status (SPEC.md
//! Appendix E.1, README.md, `hce --help`). Subcommands return typed errors (wrapped in
//! `anyhow::Error`, with context); none picks a status or calls `process::exit`. A new
//! subcommand only has to return its errors: the classifier walks each error's chain of
//! causes and recognises the workspace's error types.

use std::process::ExitCode;

/// Exit statuses shared by every subcommand (also in SPEC.md Appendix E.1 and README.md).
pub const EXIT_CODES: &str = "\
Exit status:
  0  success (for `validate`: the file is valid)
  1  internal or other error (also: no GPU adapter, or no display for `view`)
  2  usage error (bad arguments)
  3  invalid input (unreadable bytes, failed validation)
  4  I/O error (file missing, unreadable or unwritable)";

/// The classes of failure of SPEC.md Appendix E.1, with their statuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// 1: internal or other error.
    Other = 1,
    /// 2: bad or missing arguments.
    Usage = 2,
    /// 3: bytes that cannot be read, or a file that fails validation.
    Invalid = 3,
    /// 4: a file is missing or cannot be read, or an output cannot be written.
    Io = 4,
}

impl From<Status> for ExitCode {
    fn from(s: Status) -> ExitCode {
        ExitCode::from(s as u8)
    }
}

/// A usage error found after argument parsing (a combination of flags clap cannot check, or a
/// value only the input makes invalid): exits 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Usage(pub String);

/// `e`, a bad argument found by a parser outside clap, as a [`Usage`] error. (Only the GPU
/// commands have such arguments.)
#[cfg_attr(not(feature = "gpu"), allow(dead_code))]
pub fn usage(e: anyhow::Error) -> anyhow::Error {
    Usage(format!("{e:#}")).into()
}

/// The input was read and found unacceptable (an image `hce compare` cannot use, or a file whose
/// problems `hce validate` already printed): exits 3.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Invalid(pub String);

/// An input could not be read or an output could not be written, with no `std::io::Error` to
/// carry (the message says why): exits 4.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Io(pub String);

/// Why a file could not be loaded (`hce inspect`, `hce validate`): I/O (exit 4) or invalid
/// content (exit 3).
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{0}")]
    Io(String),
    #[error("{0}")]
    Invalid(String),
}

impl LoadError {
    pub fn message(&self) -> &str {
        match self {
            LoadError::Io(m) | LoadError::Invalid(m) => m,
        }
    }
}

/// The documented status of `e`. A cause whose type fixes the status decides (the outermost
/// one); otherwise any I/O error among the causes makes it 4, any error of unacceptable input
/// makes it 3, and anything else is 1.
pub fn classify(e: &anyhow::Error) -> Status {
    if let Some(s) = e.chain().find_map(decisive) {
        return s;
    }
    if e.chain().any(is_io) {
        Status::Io
    } else if e.chain().any(is_invalid_input) {
        Status::Invalid
    } else {
        Status::Other
    }
}

/// The status of one error whose type (or variant) fixes it whatever its causes.
fn decisive(c: &(dyn std::error::Error + 'static)) -> Option<Status> {
    use hce_bake::PipelineError;
    use hce_geometry::refine::RefineError;
    if c.is::<Usage>() {
        return Some(Status::Usage);
    }
    if c.is::<Invalid>() {
        return Some(Status::Invalid);
    }
    if c.is::<Io>() {
        return Some(Status::Io);
    }
    if let Some(e) = c.downcast_ref::<LoadError>() {
        return Some(match e {
            LoadError::Io(_) => Status::Io,
            LoadError::Invalid(_) => Status::Invalid,
        });
    }
    if let Some(e) = c.downcast_ref::<PipelineError>() {
        return match e {
            PipelineError::OutputExtension { .. } | PipelineError::Levels(_) => Some(Status::Usage),
            PipelineError::Bake(hce_bake::BakeError::InvalidParameter(_)) => Some(Status::Usage),
            PipelineError::Object { .. } => Some(Status::Invalid),
            PipelineError::Write(_) | PipelineError::FileWrite(_) => Some(Status::Io),
            PipelineError::Output(hce_bake::OutputError::Write(_)) => Some(Status::Io),
            PipelineError::Output(_) => Some(Status::Other),
            // Transparent variants: their inner error is not in the chain of causes.
            PipelineError::Import(hce_meshio::scene::ImportError::Io { .. }) => Some(Status::Io),
            PipelineError::Import(_) | PipelineError::Bake(_) => Some(Status::Invalid),
        };
    }
    if let Some(e) = c.downcast_ref::<hce_geometry::SubdivError>() {
        return Some(subdiv_status(e));
    }
    // `hce render --level 7` on a multiresolution object: the level is the caller's argument.
    #[cfg(feature = "gpu")]
    if let Some(hce_runtime::gpu::GpuError::LevelTooHigh { .. }) = c.downcast_ref() {
        return Some(Status::Usage);
    }
    if let Some(e) = c.downcast_ref::<RefineError>() {
        return Some(match e {
            RefineError::Subdiv(s) => subdiv_status(s),
            RefineError::Object(_)
            | RefineError::Colour(_)
            | RefineError::Split(_)
            | RefineError::Adaptive(_) => Status::Invalid,
        });
    }
    None
}

/// Reading or writing a file failed.
fn is_io(c: &(dyn std::error::Error + 'static)) -> bool {
    c.is::<std::io::Error>()
        || c.is::<hce_meshio::FileWriteError>()
        || matches!(
            c.downcast_ref::<hce_runtime::AssetError>(),
            Some(hce_runtime::AssetError::Io { .. })
        )
}

/// Bytes were read but are not acceptable input.
fn is_invalid_input(c: &(dyn std::error::Error + 'static)) -> bool {
    c.is::<hce_meshio::ImportError>()
        || c.is::<hce_bake::BakeError>()
        || c.is::<hce_geometry::TopologyError>()
        || c.is::<hce_format::ReadError>()
        || c.is::<hce_format::GltfError>()
        || c.is::<hce_runtime::AssetError>()
}

/// A level out of range is the caller's argument (2); anything else is the mesh's (3).
fn subdiv_status(e: &hce_geometry::SubdivError) -> Status {
    match e {
        hce_geometry::SubdivError::Level(_) => Status::Usage,
        _ => Status::Invalid,
    }
}

/// The status of a panic that ends the command quietly, from the panic's message, or `None` for
/// a panic that is a bug (left to the default hook). A reader that closes the pipe early
/// (`hce inspect x.glb | head`) makes `println!` panic with "failed printing to stdout: Broken
/// pipe": the reader's choice, not a crash, but the output was not all written, so the status is
/// that of an output that cannot be written (4), never success; a pipeline under
/// `set -o pipefail` does not take a cut-off listing for a whole one.
pub fn quiet_panic_status(message: &str) -> Option<Status> {
    (message.starts_with("failed printing to std") && message.contains("Broken pipe"))
        .then_some(Status::Io)
}

/// Prints `e` with its causes and returns its status.
pub fn report(e: &anyhow::Error) -> ExitCode {
    eprintln!("error: {}", message(e));
    classify(e).into()
}

/// `e` and its causes joined by `: `, leaving out a cause whose text is already there (many
/// error types print their source in their own message).
pub fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for c in e.chain() {
        let part = c.to_string();
        if text.is_empty() {
            text = part;
        } else if !text.contains(&part) {
            text = format!("{text}: {part}");
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn an_error_of_no_known_type_is_other() {
        assert_eq!(classify(&anyhow::anyhow!("no GPU adapter")), Status::Other);
        assert_eq!(ExitCode::from(Status::Other), ExitCode::from(1));
    }

    #[test]
    fn causes_decide_through_context() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e = anyhow::Error::new(io).context("reading x.obj");
        assert_eq!(classify(&e), Status::Io);
        let level: anyhow::Error = hce_geometry::SubdivError::Level(7).into();
        assert_eq!(classify(&level.context("x.hce: object 0")), Status::Usage);
        let refine = hce_geometry::refine::RefineError::Subdiv(hce_geometry::SubdivError::Level(7));
        assert_eq!(classify(&anyhow::Error::new(refine)), Status::Usage);
        let tables = hce_geometry::SubdivError::Tables("edge 3".into());
        assert_eq!(classify(&anyhow::Error::new(tables)), Status::Invalid);
        let usage: Result<(), Usage> = Err(Usage("--size 0x0".into()));
        assert_eq!(
            classify(&usage.context("render").unwrap_err()),
            Status::Usage
        );
    }

    #[test]
    fn a_decisive_type_wins_over_an_io_cause() {
        // A pipeline's output-extension error is a usage error whatever it wraps.
        let e = hce_bake::PipelineError::OutputExtension {
            path: "x.png".into(),
        };
        assert_eq!(classify(&anyhow::Error::new(e)), Status::Usage);
    }

    #[test]
    fn a_closed_pipe_ends_with_the_status_of_an_unwritable_output() {
        let closed = "failed printing to stdout: Broken pipe (os error 32)";
        assert_eq!(quiet_panic_status(closed), Some(Status::Io));
        assert_eq!(
            quiet_panic_status("failed printing to stderr: Broken pipe (os error 32)"),
            Some(Status::Io)
        );
        assert_ne!(Status::Io as i32, 0);
        // A full disk is not the reader's choice, and any other panic is a bug: no quiet end.
        let full = "failed printing to stdout: No space left on device (os error 28)";
        assert_eq!(quiet_panic_status(full), None);
        assert_eq!(
            quiet_panic_status("index out of bounds: the len is 3"),
            None
        );
    }

    #[test]
    fn a_message_names_each_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e = anyhow::Error::new(io).context("x.obj: gone");
        assert_eq!(message(&e), "x.obj: gone");
        let e = anyhow::anyhow!("gone").context("x.obj");
        assert_eq!(message(&e), "x.obj: gone");
    }
}
