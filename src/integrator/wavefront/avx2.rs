//! The lanes on AVX2: sixteen f32 lanes in two registers ([`simd`], `simd_avx2.rs`), and every
//! function that runs them compiled for AVX2, BMI1, BMI2 and POPCNT, for CPUs without
//! AVX-512.
//!
//! The code of the lanes (`bsdf.rs`, `lanes.rs`, `nee.rs`, `path.rs`, `rng.rs`,
//! `trace.rs`) is written once and compiled twice, here and in [`super::avx512`], each time
//! over that backend's `simd` and with its target features (`lanes_fn!`), so that the
//! intrinsics inline into it.

#![allow(clippy::duplicate_mod)]

macro_rules! lanes_fn {
    ($($f:tt)*) => {
        #[target_feature(enable = "avx2,bmi1,bmi2,popcnt")]
        $($f)*
    };
}

use super::*;

#[path = "bsdf.rs"]
mod bsdf;
#[path = "lanes.rs"]
mod lanes;
#[path = "nee.rs"]
mod nee;
#[path = "path.rs"]
mod path;
#[path = "rng.rs"]
mod rng;
#[path = "simd_avx2.rs"]
mod simd;
#[path = "trace.rs"]
mod trace;

use lanes::{Lanes, GROUPS};

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
    /// The CPU must have AVX2, BMI1, BMI2 and POPCNT.
    pub(super) unsafe fn render(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        match self.sampler {
            SamplerKind::Independent => self.run(rng::Pcg16::new(), camera, pixels, sums, stats),
            _ => self.run(rng::Samplers16::new(), camera, pixels, sums, stats),
        }
    }
}
