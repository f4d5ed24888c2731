//! Large build arrays on transparent huge pages, where Linux offers them to those that ask
//! (`/sys/kernel/mm/transparent_hugepage/enabled` set to `madvise`, as on Debian and the
//! development machine). A 10 M-triangle build fills about 2 GB of fresh memory; in 4 KiB
//! pages that is half a million page faults, which took about a fifth of the build's CPU
//! time in the kernel (`perf record`), and with 2 MiB pages the build took 15 % less wall
//! time (`cargo bench --bench scale`, alternating the kernel setting). Elsewhere, and for
//! small arrays, these are plain `Vec`s.

/// An empty vector with room for `n` items, its whole 2 MiB pages advised to be huge ones.
pub fn with_capacity<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    advise(v.as_ptr() as usize, n * std::mem::size_of::<T>());
    v
}

/// A vector of `n` zeros (from fresh zeroed memory, not written), advised as above.
pub fn zeroed(n: usize) -> Vec<u32> {
    let v = vec![0u32; n];
    advise(v.as_ptr() as usize, n * 4);
    v
}

/// An empty vector with room for `n` items, of which only scattered parts will be written:
/// advised never to be backed by huge pages, so that memory is taken only for the 4 KiB
/// pages written (a kernel that backs memory with huge pages would fill 2 MiB around each).
pub fn sparse<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    #[cfg(target_os = "linux")]
    // SAFETY: the range is the vector's allocation, and MADV_NOHUGEPAGE is advice about how
    // to back it, which leaves its contents as they are.
    unsafe {
        madvise_pages(
            v.as_ptr() as usize,
            n * std::mem::size_of::<T>(),
            PAGE,
            libc::MADV_NOHUGEPAGE,
        );
    }
    v
}

/// Gives the whole pages of `start..start + len` back to the system, which reads as zeros
/// from then on (Linux; elsewhere nothing happens): so that memory the build is done with
/// serves its next arrays while still warm, rather than those arrays taking fresh memory.
///
/// # Safety
/// The range must lie inside an allocation of this process, whose contents there nobody
/// reads again (or only as zeros, where zeros are valid values).
pub unsafe fn release(start: usize, len: usize) {
    // SAFETY: the caller's promise; MADV_DONTNEED on private anonymous memory leaves it
    // mapped, reading as zeros.
    #[cfg(target_os = "linux")]
    unsafe {
        madvise_pages(start, len, PAGE, libc::MADV_DONTNEED);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, len);
}

/// The sizes of a page and of a huge page (x86-64 and most AArch64 kernels).
#[cfg(target_os = "linux")]
const PAGE: usize = 4096;
pub const HUGE_PAGE: usize = 2 << 20;

/// `madvise(advice)` over the whole `page`-aligned pages inside `start..start + len` (none
/// where it holds no whole page).
///
/// # Safety
/// The range must lie inside an allocation of this process, and the advice must leave it
/// as its users expect.
#[cfg(target_os = "linux")]
unsafe fn madvise_pages(start: usize, len: usize, page: usize, advice: libc::c_int) {
    let lo = (start + page - 1) & !(page - 1);
    let hi = (start + len) & !(page - 1);
    if hi > lo {
        // SAFETY: the caller's promise.
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, advice);
        }
    }
}

/// Asks for huge pages over the 2 MiB-aligned part of `start..start + len`. Only the
/// kernel's choice of page size changes, never the memory's contents, and a kernel that
/// cannot oblige (no THP, or disabled) returns an error that changes nothing, so it is
/// ignored.
#[cfg(target_os = "linux")]
fn advise(start: usize, len: usize) {
    // Arrays smaller than this are left alone (a huge page could hold most of one).
    const MIN_BYTES: usize = 8 << 20;
    if len >= MIN_BYTES {
        // SAFETY: the range lies inside an allocation this process owns, and MADV_HUGEPAGE
        // is advice about how to back it, which leaves its contents as they are.
        unsafe { madvise_pages(start, len, HUGE_PAGE, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: usize, _len: usize) {}

#[cfg(test)]
mod tests {
    #[test]
    fn vectors_keep_their_contents() {
        let mut v: Vec<u64> = super::with_capacity(3 << 20);
        assert!(v.capacity() >= 3 << 20 && v.is_empty());
        v.extend(0..3 << 20);
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as u64));
        let z = super::zeroed(5 << 20);
        assert_eq!(z.len(), 5 << 20);
        assert!(z.iter().all(|&x| x == 0));
    }
}
