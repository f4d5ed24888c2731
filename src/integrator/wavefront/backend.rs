// The part of a backend's module that both backends share, included by `avx512.rs` and
// `avx2.rs` after each defines `lanes_fn!` and its `simd` module: the lanes' code, compiled
// once in each, and the entry from `super::Wavefront::render_tile`.

use super::*;

#[path = "bsdf.rs"]
mod bsdf;
#[path = "general.rs"]
mod general;
#[path = "lanes.rs"]
mod lanes;
#[path = "lights.rs"]
mod lights;
#[path = "nee.rs"]
mod nee;
#[path = "path.rs"]
mod path;
#[path = "rng.rs"]
mod rng;

use lanes::{Lanes, POOL};

/// The scene prepared for the lanes, seen by the code compiled for this backend.
pub(super) struct Wavefront<'a>(pub &'a super::Wavefront<'a>);

impl<'a> std::ops::Deref for Wavefront<'a> {
    type Target = super::Wavefront<'a>;
    fn deref(&self) -> &super::Wavefront<'a> {
        self.0
    }
}

impl Wavefront<'_> {
    /// `super::Wavefront::render_tile`.
    ///
    /// # Safety
    /// The CPU must have the features this backend's `lanes_fn!` enables.
    pub(super) unsafe fn render(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        match self.sampler {
            SamplerKind::Independent => self.run(rng::Pcg16::new(), camera, pixels, sums, stats),
            SamplerKind::Sobol => self.run(rng::Sobol16::new(), camera, pixels, sums, stats),
        }
    }
}
