//! Handing freed memory back to the system between stages.
//!
//! glibc's allocator keeps the pages of freed blocks below its top for reuse, and after a large
//! block is freed it serves later blocks of that size from those pages too, so a process's
//! resident size stays at its highest stage's even when a later stage needs less. Where a stage
//! frees a large structure that the next does not reuse (the distance queries, once the band is
//! sampled), [`return_freed_pages`] gives those pages back: the next stage's peak then counts
//! only what it holds.

/// Returns the allocator's free pages to the system (glibc on Linux; nothing elsewhere). Costs a
/// walk over the free lists: milliseconds, so call it between stages, not in loops.
pub fn return_freed_pages() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases memory no allocation owns; it takes the allocator's own
    // locks and is safe to call from any thread at any time.
    unsafe {
        libc::malloc_trim(0);
    }
}
