//! Acceleration structures: a bounding volume hierarchy over all primitives.

pub mod bvh;
#[cfg(target_arch = "x86_64")]
pub mod flat;
pub(crate) mod huge_pages;
pub mod timing;
pub mod wide;
pub use bvh::Bvh;
pub use timing::BuildTimes;
pub use wide::{RayPacket, WideBvh, PACKET};

/// What answers a scene's single-ray queries (`Scene::intersect`, `Scene::occluded`), chosen
/// when the scene is built (`Scene::build_with`). It is part of the scene, not a render
/// setting: brute force tests every primitive, while the BVH's box tests may pass over a
/// primitive that a grazing ray touches, so the two can differ in the last bits of an
/// image, and a render must be resumed with the queries it began with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SingleRays {
    /// Brute force ([`flat`]) where the scene has few enough primitives and no opacity
    /// masks and the CPU has AVX; the BVH elsewhere.
    #[default]
    Auto,
    /// The BVH, whatever the scene's size.
    Bvh,
    /// Brute force with this kernel whatever the scene's size, up to
    /// [`flat::FLAT_MAX_SLOTS`] triangles; the BVH beyond, with masks, or where the CPU does
    /// not run the kernel. For the benchmarks that compare the kernels.
    #[cfg(target_arch = "x86_64")]
    Flat(flat::Kernel),
}

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
