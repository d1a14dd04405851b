//! The `extern "C"` functions the module exports. The only `unsafe` of the crate: turning the
//! caller's pointer and length back into the buffer [`hce_alloc`] handed out.

use crate::{geometry_hash, load, refine, result, tables};

/// A zeroed buffer of at least `bytes` bytes, word-aligned, for a request; free it with
/// [`hce_free`] and the same `bytes`.
#[no_mangle]
pub extern "C" fn hce_alloc(bytes: usize) -> *mut u32 {
    let buffer = vec![0u32; bytes.div_ceil(4)].into_boxed_slice();
    Box::into_raw(buffer).cast()
}

/// Frees a buffer of [`hce_alloc`] or a result.
///
/// # Safety
/// `ptr` and `bytes` must be those of one buffer from [`hce_alloc`] (or a result, with
/// `4 * words`), freed once.
#[no_mangle]
pub unsafe extern "C" fn hce_free(ptr: *mut u32, bytes: usize) {
    let words = std::ptr::slice_from_raw_parts_mut(ptr, bytes.div_ceil(4));
    // SAFETY: by the contract above, a boxed slice of exactly these words.
    drop(unsafe { Box::from_raw(words) });
}

/// # Safety
/// `ptr` must point at `bytes` readable bytes from [`hce_alloc`].
unsafe fn request<'a>(ptr: *const u32, bytes: usize) -> &'a [u32] {
    // SAFETY: by the contract above.
    unsafe { std::slice::from_raw_parts(ptr, bytes / 4) }
}

fn give(words: Vec<u32>) -> *mut u32 {
    Box::into_raw(words.into_boxed_slice()).cast()
}

/// [`crate::load`] on the request frame at `ptr`.
///
/// # Safety
/// `ptr` and `bytes` as [`hce_free`] requires, the buffer filled by the caller.
#[no_mangle]
pub unsafe extern "C" fn hce_load(ptr: *const u32, bytes: usize) -> *mut u32 {
    // SAFETY: by the contract above.
    give(result(load(unsafe { request(ptr, bytes) })))
}

/// [`crate::tables`] on the request frame at `ptr`.
///
/// # Safety
/// As [`hce_load`].
#[no_mangle]
pub unsafe extern "C" fn hce_tables(ptr: *const u32, bytes: usize) -> *mut u32 {
    // SAFETY: by the contract above.
    give(result(tables(unsafe { request(ptr, bytes) })))
}

/// [`crate::geometry_hash`] on the request frame at `ptr`.
///
/// # Safety
/// As [`hce_load`].
#[no_mangle]
pub unsafe extern "C" fn hce_geometry_hash(ptr: *const u32, bytes: usize) -> *mut u32 {
    // SAFETY: by the contract above.
    give(result(geometry_hash(unsafe { request(ptr, bytes) })))
}

/// [`crate::refine`] on the request frame at `ptr`.
///
/// # Safety
/// As [`hce_load`].
#[no_mangle]
pub unsafe extern "C" fn hce_refine(ptr: *const u32, bytes: usize) -> *mut u32 {
    // SAFETY: by the contract above.
    give(result(refine(unsafe { request(ptr, bytes) })))
}
