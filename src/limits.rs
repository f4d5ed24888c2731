//! Upper bounds on every count a user gives, as a flag or as a scene-file key, so that no
//! number can make a render, a load or a thread pool endless (README, "Limits").
//!
//! Each bound is far above what a render needs and low enough that one sample's work, one
//! photon pass or the threads stay finite. The flags are checked in `main.rs`
//! ([`check`] naming the flag); the scene readers check their keys with file, line and column;
//! [`crate::resolve_settings`] checks the resolved values once more.

/// Image width and height in pixels (the film's memory is checked separately).
pub const MAX_SIZE: u64 = 1 << 20;
/// Samples per pixel (with `--time` or `--target-noise` the count may be open-ended).
pub const MAX_SPP: u64 = 1 << 24;
/// Shadow rays per path vertex: their cost multiplies every sample's.
pub const MAX_SHADOW_RAYS: u64 = 1024;
/// Longest path in segments (besides -1, unlimited).
pub const MAX_DEPTH: u64 = 1 << 16;
/// First bounce of the throughput Russian roulette: a path with survival probability 1
/// before it (a closed mirror box) is as long as this.
pub const MAX_RR_DEPTH: u64 = 1024;
/// Largest fixed Russian-roulette survival probability: paths of 1/(1 − p) = 10⁴ segments on
/// average.
pub const MAX_RR_SURVIVAL: f32 = 0.9999;
/// Worker threads.
pub const MAX_THREADS: u64 = 1024;
/// Photons emitted for a photon map, or in one SPPM iteration.
pub const MAX_PHOTONS: u64 = 1_000_000_000;
/// Photons in one radiance estimate (k nearest).
pub const MAX_GATHER_PHOTONS: u64 = 4096;
/// Final-gather rays per camera sample.
pub const MAX_FINAL_GATHER: u64 = 1024;
/// SPPM iterations.
pub const MAX_ITERATIONS: u64 = 1 << 20;
/// Instances of shape groups in one scene (each costs about 180 bytes: its transforms and
/// its share of the top-level BVH).
pub const MAX_INSTANCES: u64 = 1 << 24;
/// Exposure in stops, either way (2^64 turns any radiance into white or black already).
pub const MAX_EXPOSURE: f32 = 64.0;

/// Refuses `value` above `max` (and below `min`), naming it (`what`: a flag such as
/// `--spp`, or a scene key).
pub fn check(what: &str, value: u64, min: u64, max: u64) -> Result<(), String> {
    if value < min {
        return Err(format!("{what} must be at least {min}, got {value}"));
    }
    if value > max {
        return Err(format!(
            "{what} must be at most {max}, got {value} (see README, \"Limits\")"
        ));
    }
    Ok(())
}
