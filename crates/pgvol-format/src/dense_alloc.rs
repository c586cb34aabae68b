//! The dense coefficient array a reader fills.
//!
//! A 256³ volume is 64 MiB; touching it for the first time costs one page fault per 4 KiB page,
//! which measured several times the cost of writing the values (`docs/format.md`, "Read speed").
//! On Linux the array is therefore marked for transparent huge pages (2 MiB), a hint the kernel
//! may ignore; the contents are the same either way.

/// A zeroed array of `len` coefficients.
pub(crate) fn zeroed(len: usize) -> Vec<f32> {
    let mut v = vec![0.0f32; len];
    #[cfg(target_os = "linux")]
    advise_huge_pages(&mut v);
    v
}

#[cfg(target_os = "linux")]
fn advise_huge_pages(v: &mut [f32]) {
    const HUGE_PAGE: usize = 2 << 20;
    let start = v.as_mut_ptr() as usize;
    let end = start + size_of_val(v);
    let (lo, hi) = (
        start.next_multiple_of(HUGE_PAGE),
        end / HUGE_PAGE * HUGE_PAGE,
    );
    if hi > lo {
        // SAFETY: [lo, hi) lies inside `v`'s allocation and is page aligned. MADV_HUGEPAGE only
        // changes how the kernel backs those pages, never their contents or the mapping; if
        // the kernel refuses (no THP support), the pages stay as they were, so the result is
        // ignored.
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
        }
    }
}
