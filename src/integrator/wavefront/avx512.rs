//! The lanes on AVX-512: sixteen f32 lanes to a register ([`simd`], `simd.rs`), and every
//! function that runs them compiled for AVX-512F, AVX-512DQ and BMI2.
//!
//! The code of the lanes (`bsdf.rs`, `lanes.rs`, `nee.rs`, `path.rs`, `rng.rs`,
//! declared in `backend.rs`) is written once and compiled twice, here and in
//! [`super::avx2`], each time over that backend's `simd` and with its target features
//! (`lanes_fn!`), so that the intrinsics inline into it.

#![allow(clippy::duplicate_mod)]

macro_rules! lanes_fn {
    ($($f:tt)*) => {
        #[target_feature(enable = "avx512f,avx512dq,bmi2")]
        $($f)*
    };
}

#[path = "simd.rs"]
mod simd;

include!("backend.rs");
