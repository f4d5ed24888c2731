//! Acceleration structures: a bounding volume hierarchy over all primitives.

pub mod bvh;
#[cfg(target_arch = "x86_64")]
pub mod flat;
pub(crate) mod huge_pages;
pub mod timing;
pub mod wide;
pub use bvh::Bvh;
pub use timing::BuildTimes;
pub use wide::{ShadowPacket, WideBvh, PACKET};

/// Asks the CPU to bring `p`'s cache line in (a hint: it reads nothing the program sees).
#[inline(always)]
pub(crate) fn prefetch<T>(p: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint; it reads nothing the program sees.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch(p as *const T as *const i8, _MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
