//! Sixteen triangles tested against one ray at once: with AVX-512 in one register, or with
//! AVX in two of eight lanes. The triangles of a small scene are tested this way by brute force
//! ([`crate::accel::flat`]). Embree's `Triangle8` and Wald, Benthin and Boulos ("Getting Rid
//! of Packets", RT 2008) test a leaf's triangles in the lanes of one register in the same
//! way. The first vertex and both edges are stored by axis, a lane per triangle, so a test
//! loads nine registers and runs the Möller–Trumbore arithmetic once for all lanes.
//!
//! The test is [`Triangle::intersect`]'s fast path in lanes ([`intersect_lanes_edges`],
//! with the edges `p1 − p0` and `p2 − p0` stored as `intersect` subtracts them), so a lane
//! it classes as a clear hit or a clear miss is one `intersect` classes so, with the same t,
//! u and v. A lane near an edge, or with a near-zero determinant, is left to `intersect`
//! itself, whose f64 test decides.

use super::triangle::intersect_lanes_edges;
use super::Triangle;
use crate::simd::{Sixteen, Vector3, V3};

/// Triangles in one block.
pub const LANES: usize = 16;

/// Sixteen triangles' first vertex and edges, by axis (576 bytes). Lanes without a
/// triangle hold NaN, which the test classes neither as a hit nor as a miss; the caller
/// masks them off.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct TriangleBlock {
    p0: [[f32; LANES]; 3],
    e1: [[f32; LANES]; 3],
    e2: [[f32; LANES]; 3],
}

impl TriangleBlock {
    /// A block of `tris` (at most [`LANES`]); the remaining lanes hold NaN.
    pub fn new(tris: &[Triangle]) -> Self {
        assert!(tris.len() <= LANES);
        let mut b = TriangleBlock {
            p0: [[f32::NAN; LANES]; 3],
            e1: [[f32::NAN; LANES]; 3],
            e2: [[f32::NAN; LANES]; 3],
        };
        for (lane, tri) in tris.iter().enumerate() {
            // The edges as `Triangle::intersect` subtracts them.
            let (e1, e2) = (tri.p1 - tri.p0, tri.p2 - tri.p0);
            for axis in 0..3 {
                b.p0[axis][lane] = tri.p0[axis];
                b.e1[axis][lane] = e1[axis];
                b.e2[axis][lane] = e2[axis];
            }
        }
        b
    }

    /// The block against the ray (`o`, `d`: its origin and direction in every lane) in
    /// the lanes of `T` ([`Sixteen`]: one AVX-512 register, or two AVX ones),
    /// [`intersect_lanes_edges`]: the lanes hit in (0, `t_max`), the lanes near an edge (to
    /// be decided by [`Triangle::intersect`]), and the lanes' t, u and v (meaningful where
    /// hit). The caller is compiled with the features of `T`.
    #[inline(always)]
    pub fn test<T: Sixteen>(&self, o: V3<T>, d: V3<T>, t_max: T) -> (T::Mask, T::Mask, [T; 3]) {
        let (p0, e1, e2) = (load(&self.p0), load(&self.e1), load(&self.e2));
        let r = intersect_lanes_edges(p0, e1, e2, o, d);
        let ahead = r.t.gt(T::zero()) & r.t.lt(t_max);
        (r.clear & ahead, r.unsure, [r.t, r.u, r.v])
    }
}

/// A row of three axes in lanes. (A function, not a closure: a closure is compiled without
/// its caller's target features.)
#[inline(always)]
fn load<T: Sixteen>(a: &[[f32; LANES]; 3]) -> V3<T> {
    V3::new(T::load(&a[0]), T::load(&a[1]), T::load(&a[2]))
}
