//! The one `unsafe` call of the crate: a memory-placement hint to the operating system.
//!
//! Everything else in hce-geometry forbids `unsafe` (`#![deny(unsafe_code)]` at the crate root,
//! `forbid` on every other module, overridden only here); this module is the place to look when
//! auditing it.
#![allow(unsafe_code)]

/// Asks Linux to back fresh, untouched output memory with transparent huge pages where the
/// system allows them only on request (`/sys/kernel/mm/transparent_hugepage/enabled` set to
/// `madvise`, the common default). First-touch page faults otherwise cost more than the whole
/// subdivision: 106 MB of bunny level-3 output is 26,000 faults of 4 KiB, measured at
/// 150-240 ms on the development VM, against under 30 ms with 2 MiB pages. Elsewhere, or when
/// the kernel declines, nothing changes.
#[cfg(target_os = "linux")]
pub(crate) fn advise_huge_pages<T>(v: &mut [T]) {
    const HUGE: usize = 2 << 20;
    let bytes = std::mem::size_of_val(v);
    if bytes < 2 * HUGE {
        return;
    }
    let start = v.as_mut_ptr() as usize;
    let first = start.next_multiple_of(HUGE);
    let end = (start + bytes) / HUGE * HUGE;
    if end > first {
        // SAFETY: `madvise` takes a page-aligned address (`first` is a multiple of 2 MiB) and a
        // length; the range `first .. end` lies inside `v`'s allocation, which this function
        // borrows mutably, so no other code can be using those pages meanwhile. MADV_HUGEPAGE
        // only changes how the kernel backs the pages: their contents, addresses and validity
        // are unchanged, so no Rust reference to `v` is invalidated. The result is ignored
        // because a refusal leaves the memory as it was.
        unsafe {
            libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn advise_huge_pages<T>(_: &mut [T]) {}
