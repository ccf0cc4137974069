//! Memory for the large per-pass arrays that the gather reads at random (the light tree's
//! nodes, the lights): once they outgrow the caches every read is a cache miss, and with 4 KiB
//! pages also a TLB miss whose page walk (two-dimensional in a virtual machine) costs more than
//! the miss itself. Measured on 1M VRLs: the light record read at the end of a descent took as
//! long as the whole descent before its array used huge pages (docs/lightcuts.md, "Cost per
//! camera segment").

/// An empty vector with room for `n` elements whose memory, on Linux, is advised to use
/// transparent huge pages (before it is first written, so that the page faults get them).
pub(crate) fn huge_page_vec<T>(n: usize) -> Vec<T> {
    let v: Vec<T> = Vec::with_capacity(n);
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let (start, bytes) = (v.as_ptr() as usize, n * std::mem::size_of::<T>());
        let lo = start.next_multiple_of(HUGE);
        let hi = (start + bytes) / HUGE * HUGE;
        if hi > lo {
            // SAFETY: the range lies inside this vector's allocation; MADV_HUGEPAGE only changes
            // how the kernel backs it (an error, e.g. THP disabled, leaves it as it was).
            unsafe {
                libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
            }
        }
    }
    v
}
