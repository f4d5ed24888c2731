//! Acceleration structures: a bounding volume hierarchy over all primitives.

pub mod bvh;
pub use bvh::Bvh;
