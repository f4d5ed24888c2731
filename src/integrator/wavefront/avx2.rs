//! The lanes on AVX2: sixteen f32 lanes in two registers ([`simd`], `simd_avx2.rs`), and every
//! function that runs them compiled for AVX2, BMI1, BMI2 and POPCNT, for CPUs without
//! AVX-512.
//!
//! The code of the lanes (`bsdf.rs`, `lanes.rs`, `nee.rs`, `path.rs`, `rng.rs`,
//! declared in `backend.rs`) is written once and compiled twice, here and in
//! [`super::avx512`], each time over that backend's `simd` and with its target features
//! (`lanes_fn!`), so that the intrinsics inline into it.

#![allow(clippy::duplicate_mod)]

macro_rules! lanes_fn {
    ($($f:tt)*) => {
        #[target_feature(enable = "avx2,bmi1,bmi2,popcnt")]
        $($f)*
    };
}

#[path = "simd_avx2.rs"]
mod simd;

include!("backend.rs");
