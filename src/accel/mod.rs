//! Acceleration structures: a bounding volume hierarchy over all primitives.

pub mod bvh;
pub(crate) mod huge_pages;
pub mod timing;
pub mod wide;
pub use bvh::Bvh;
pub use timing::BuildTimes;
pub use wide::{ShadowPacket, WideBvh, PACKET};
