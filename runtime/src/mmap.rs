//! The one `unsafe` call of the crate: mapping a large input file read-only.
//!
//! Everything else in hce-runtime forbids `unsafe` (`#![deny(unsafe_code)]` at the crate root,
//! `forbid` on every other module, overridden only here); this module is the place to look when
//! auditing it.
#![allow(unsafe_code)]

use std::fs::File;

/// Maps `file` read-only for [`crate::asset`], which parses it and copies out everything it
/// keeps before the map is dropped.
pub(crate) fn map_read_only(file: &File) -> std::io::Result<memmap2::Mmap> {
    // SAFETY: `Mmap::map` is unsafe because the mapped bytes may change underneath a `&[u8]` if
    // another process writes or truncates the file while it is mapped. The map is read-only,
    // never written through, and lives only while the asset is parsed (the caller copies out
    // everything it keeps). Truncation during that window can fault the read (SIGBUS): the
    // usual caveat of memory-mapped input, accepted for large files because reading them would
    // double their memory for no benefit. Concurrent rewrites of an asset being opened are
    // outside what `Asset::open` promises to handle.
    unsafe { memmap2::Mmap::map(file) }
}
