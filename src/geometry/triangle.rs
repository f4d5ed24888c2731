//! Triangles and the Möller–Trumbore ray–triangle test.

use super::ray::{gamma, Ray};
use crate::simd::{Float, Vector3, V3};
use glam::{DVec3, Vec3A, Vec4};

/// A triangle stored by its vertices (Möller and Trumbore, "Fast, Minimum Storage
/// Ray/Triangle Intersection", JGT 2(1), 1997, derive the edges on the fly).
///
/// Vertices rather than precomputed edges: two triangles sharing an edge then share its exact
/// endpoints, which the watertightness fallback in [`Triangle::intersect`] relies on.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub p0: Vec3A,
    pub p1: Vec3A,
    pub p2: Vec3A,
}

/// Barycentric coordinates closer than this to an edge are recomputed in f64.
const EDGE_EPS: f32 = 1e-4;

/// The lanes of u·det and v·det in [`Triangle::intersect`]'s four dot products...
const UV_LANES: glam::BVec4A = glam::BVec4A::from_array([false, true, true, false]);
/// ...and the bounds of the others for its early misses: none for det (NaN compares false),
/// and for t·det the least positive float, below which (and not NaN) is at most 0, as
/// neither Rust nor mcrt sets the CPU to read subnormals as zero.
const T_LANE: Vec4 = Vec4::new(f32::NAN, 0.0, 0.0, f32::from_bits(1));

/// The x + y + z sums of four products: lane i is (a_i.x + a_i.y) + a_i.z, the order of
/// glam's `Vec3A::dot`, so each equals the dot product it replaces bit for bit. A 4×4
/// transpose and two additions instead of four horizontal sums (the fourth lanes, whatever
/// they hold, are never added).
#[inline(always)]
fn dot4(a: [Vec3A; 4]) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let [a0, a1, a2, a3]: [__m128; 4] = a.map(Into::into);
        // SAFETY: SSE is part of x86-64.
        unsafe {
            let t0 = _mm_unpacklo_ps(a0, a1); // x0 x1 y0 y1
            let t1 = _mm_unpacklo_ps(a2, a3); // x2 x3 y2 y3
            let t2 = _mm_unpackhi_ps(a0, a1); // z0 z1 w0 w1
            let t3 = _mm_unpackhi_ps(a2, a3); // z2 z3 w2 w3
            let x = _mm_movelh_ps(t0, t1);
            let y = _mm_movehl_ps(t1, t0);
            let z = _mm_movelh_ps(t2, t3);
            Vec4::from(_mm_add_ps(_mm_add_ps(x, y), z))
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec4::from_array(a.map(|v| (v.x + v.y) + v.z))
    }
}

impl Triangle {
    pub fn new(p0: Vec3A, p1: Vec3A, p2: Vec3A) -> Self {
        Triangle { p0, p1, p2 }
    }

    #[inline]
    pub fn vertices(&self) -> [Vec3A; 3] {
        [self.p0, self.p1, self.p2]
    }

    /// Returns (t, u, v) of the hit with t in (0, t_max); u and v are the barycentric weights
    /// of the second and third vertex. Hits on either face count.
    ///
    /// In f32, Möller–Trumbore evaluates an edge shared by two triangles with different
    /// expressions, so a ray through the edge can miss both (about 3 % of rays aimed at a
    /// quad's diagonal did). Near an edge the test is therefore repeated in f64 from the same
    /// f32 vertices: differences and products of f32 values are exact in f64, so both
    /// triangles see the edge on the same side except for rays within ~1e-16 of it.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let e1 = self.p1 - self.p0;
        let e2 = self.p2 - self.p0;
        let s = ray.o - self.p0;
        let p = ray.d.cross(e2);
        let q = s.cross(e1);
        // det = e1·p, and u, v and t times det: four dot products in one transposed sum.
        let dots = dot4([e1 * p, s * p, ray.d * q, e2 * q]);
        let [det, u_det, v_det, t_det] = dots.to_array();
        // Most tests miss: the hit point lies outside the triangle or behind the origin.
        // Those are told from the signs of u·det, v·det and t·det against det, before the
        // division (which issues one every few cycles): u·det·sign(det) < −ε|det| is
        // u < −ε up to rounding, and such a u (or v) is a miss for the f64 test too; t·det
        // of the other sign than det (or 0) is t ≤ 0 exactly, as the quotient keeps its
        // sign. NaNs pass on to the tests below, as before (NaN lanes compare false).
        // The three lanes are compared at once and decided by one branch: three branches
        // on them mispredicted about twice as often (callgrind's branch simulation).
        // (Times ±1 is exact: it is the sign flip.)
        let flipped = dots * 1f32.copysign(det);
        let bound = -EDGE_EPS * det.abs();
        if flipped
            .cmplt(Vec4::select(UV_LANES, Vec4::splat(bound), T_LANE))
            .any()
        {
            return None;
        }
        let inv_det = 1.0 / det;
        let u = u_det * inv_det;
        let v = v_det * inv_det;
        let w = 1.0 - u - v;
        // The fast path decides clear hits and misses; anything near an edge (or a ray nearly
        // in the triangle's plane, where inv_det is huge or infinite and u or v may be NaN)
        // goes to f64.
        if u > EDGE_EPS && v > EDGE_EPS && w > EDGE_EPS {
            let t = t_det * inv_det;
            return (t > 0.0 && t < t_max).then_some((t, u, v));
        }
        if u < -EDGE_EPS || v < -EDGE_EPS || u + v > 1.0 + EDGE_EPS {
            return None;
        }
        self.intersect_f64(ray, t_max)
    }

    #[cold]
    fn intersect_f64(&self, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
        let d = |v: Vec3A| DVec3::new(v.x as f64, v.y as f64, v.z as f64);
        let (p0, p1, p2) = (d(self.p0), d(self.p1), d(self.p2));
        let (o, dir) = (d(ray.o), d(ray.d));
        let (e1, e2) = (p1 - p0, p2 - p0);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let s = o - p0;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = (e2.dot(q) / det) as f32;
        (t > 0.0 && t < t_max).then_some((t, u as f32, v as f32))
    }

    /// Unnormalised geometric normal (right-hand rule over p0, p1, p2).
    #[inline]
    pub fn normal_unnormalized(&self) -> Vec3A {
        (self.p1 - self.p0).cross(self.p2 - self.p0)
    }

    pub fn area(&self) -> f32 {
        0.5 * self.normal_unnormalized().length()
    }

    /// Whether `area()` is positive, without its square root (the square root of a
    /// positive number, halved, is positive; NaN is not).
    #[inline]
    pub fn has_area(&self) -> bool {
        self.normal_unnormalized().length_squared() > 0.0
    }

    /// The point with barycentric weights (1-u-v, u, v) and its floating-point error bound
    /// (pbrt-v4 §6.8.4: γ(7) times the sum of the magnitudes of the weighted vertices).
    #[inline]
    pub fn point(&self, u: f32, v: f32) -> (Vec3A, Vec3A) {
        barycentric_point(self.p0, self.p1, self.p2, u, v)
    }

    /// Uniform point on the triangle from two uniform numbers (the square-root
    /// parameterisation, Shirley and Chiu 1997), returned as barycentric (u, v).
    #[inline]
    pub fn sample_uniform(u: glam::Vec2) -> (f32, f32) {
        let su = u.x.sqrt();
        (1.0 - su, u.y * su)
    }
}

/// What [`intersect_lanes`] decides in each lane.
pub struct LaneHits<T: Float> {
    /// The distance and the barycentric weights u and v, meaningful in the `clear` lanes.
    pub t: T,
    pub u: T,
    pub v: T,
    /// Lanes whose point lies clearly inside the triangle: there [`Triangle::intersect`]
    /// answers (t, u, v) where 0 < t < t_max, else None.
    pub clear: T::Mask,
    /// Lanes near an edge (or NaN), which `intersect` decides in f64: the caller asks it.
    /// The lanes neither clear nor unsure miss.
    pub unsure: T::Mask,
}

/// [`Triangle::intersect`]'s fast path in lanes: rays (`o`, `d`) against a triangle
/// (`p`: its vertices), each lane its own ray, or its own triangle, or both. The same IEEE
/// operations in the same order as `intersect` (glam's cross product, dot products summed as
/// (x + y) + z), so each lane gets `intersect`'s answer wherever it is not unsure. Without
/// `intersect`'s early misses (in lanes both sides of a branch are paid): the lanes they
/// end (u or v below about −ε, or t ≤ 0) are not clear here, and any that rounding leaves
/// unsure `intersect` ends.
#[inline(always)]
pub fn intersect_lanes<T: Float>(p: [V3<T>; 3], o: V3<T>, d: V3<T>) -> LaneHits<T> {
    intersect_lanes_edges(p[0], p[1] - p[0], p[2] - p[0], o, d)
}

/// [`intersect_lanes`] of the triangle with first vertex `p0` and edges `e1` = p1 − p0 and
/// `e2` = p2 − p0 (as `intersect` subtracts them), for the callers that store the edges:
/// the small scenes' brute force ([`crate::accel::flat`]) and the wavefront's.
#[inline(always)]
pub fn intersect_lanes_edges<T: Float>(
    p0: V3<T>,
    e1: V3<T>,
    e2: V3<T>,
    o: V3<T>,
    d: V3<T>,
) -> LaneHits<T> {
    let s = o - p0;
    let pv = d.cross(e2);
    let q = s.cross(e1);
    let inv_det = T::splat(1.0) / e1.dot(pv);
    let u = s.dot(pv) * inv_det;
    let v = d.dot(q) * inv_det;
    let w = T::splat(1.0) - u - v;
    let eps = T::splat(EDGE_EPS);
    let clear = u.gt(eps) & v.gt(eps) & w.gt(eps);
    let out = u.lt(-eps) | v.lt(-eps) | (u + v).gt(T::splat(1.0 + EDGE_EPS));
    LaneHits {
        t: e2.dot(q) * inv_det,
        u,
        v,
        clear,
        unsure: !(clear | out),
    }
}

/// [`Triangle::point`] over any lanes, for the vertices `p0`, `p1`, `p2`.
#[inline(always)]
pub fn barycentric_point<V: Vector3>(p0: V, p1: V, p2: V, u: V::F, v: V::F) -> (V, V) {
    let w = V::F::splat(1.0) - u - v;
    let (a, b, c) = (p0.scale(w), p1.scale(u), p2.scale(v));
    let err = (a.abs() + b.abs() + c.abs()).scale(V::F::splat(gamma(7)));
    (a + b + c, err)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every lane of `intersect_lanes` that is not unsure gets `intersect`'s answer, bit for
    /// bit, with its lanes of rays against one triangle or of triangles against one ray:
    /// random triangles (some degenerate or tiny), rays aimed inside, outside and within
    /// rounding of edges and vertices, and some from the triangle's plane.
    #[test]
    fn intersect_lanes_agrees_with_intersect() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut point = |s: f32| Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * s;
        let mut cases = Vec::new();
        for n in 0..40_000 {
            let p0 = point(2.0);
            let (mut p1, mut p2) = (p0 + point(2.0), p0 + point(2.0));
            match n % 10 {
                0 => p2 = p0 + (p1 - p0) * 0.37, // collinear
                1 => (p1, p2) = (p0 + point(1e-6), p0 + point(1e-6)),
                _ => {}
            }
            let tri = Triangle::new(p0, p1, p2);
            // Barycentrics: anywhere near the triangle, or on an edge or vertex give or take
            // a few ulps.
            let (mut u, mut v) = (point(1.2).x + 0.4, point(1.2).y + 0.4);
            match n % 6 {
                0 => u = 0.0,
                1 => (u, v) = (1.0 - v, v),
                2 => (u, v) = (1.0, 0.0),
                _ => {}
            }
            let nudge = point(4e-6);
            let target = tri.point(u + nudge.x, v + nudge.y).0;
            let o = if n % 7 == 0 {
                p0 + (p1 - p0) * 0.5 + point(4.0) * 1e-3 // near the plane
            } else {
                point(8.0)
            };
            let t_max = if n % 3 == 0 {
                1e3
            } else {
                point(4.0).x.abs() + 0.5
            };
            cases.push((tri, Ray::new(o, target - o), t_max));
        }
        let (mut hits, mut unsure, mut misses) = (0, 0, 0);
        let mut check = |tri: &Triangle, ray: &Ray, t_max: f32, r: &LaneHits<Vec4>, k: usize| {
            let want = tri.intersect(ray, t_max);
            if r.unsure.test(k) {
                unsure += 1;
                return;
            }
            let (t, u, v) = (r.t[k], r.u[k], r.v[k]);
            let got = (r.clear.test(k) && t > 0.0 && t < t_max).then_some((t, u, v));
            let bits = |h: Option<(f32, f32, f32)>| h.map(|(t, u, v)| [t, u, v].map(f32::to_bits));
            assert_eq!(bits(got), bits(want), "{tri:?} {ray:?} {t_max}");
            if got.is_some() {
                hits += 1;
            } else {
                misses += 1;
            }
        };
        let lanes = |f: &dyn Fn(usize) -> Vec3A| {
            V3::new(
                Vec4::from_array(std::array::from_fn(|k| f(k).x)),
                Vec4::from_array(std::array::from_fn(|k| f(k).y)),
                Vec4::from_array(std::array::from_fn(|k| f(k).z)),
            )
        };
        for c in cases.chunks_exact(4) {
            // Four rays against the first triangle...
            let tri = &c[0].0;
            let p = tri.vertices().map(V3::broadcast);
            let r = intersect_lanes(p, lanes(&|k| c[k].1.o), lanes(&|k| c[k].1.d));
            for (k, (_, ray, t_max)) in c.iter().enumerate() {
                check(tri, ray, *t_max, &r, k);
            }
            // ...and the first ray against four triangles.
            let (ray, t_max) = (&c[0].1, c[0].2);
            let p = [0, 1, 2].map(|j| lanes(&|k| c[k].0.vertices()[j]));
            let r = intersect_lanes(p, V3::broadcast(ray.o), V3::broadcast(ray.d));
            for (k, (tri, _, _)) in c.iter().enumerate() {
                check(tri, ray, t_max, &r, k);
            }
        }
        assert!(
            hits > 2_000 && misses > 20_000 && unsure > 4_000,
            "{hits} hits, {misses} misses, {unsure} unsure"
        );
    }

    /// `has_area` says what `area() > 0` says, for ordinary, tiny, degenerate and non-finite
    /// triangles.
    #[test]
    fn has_area_agrees_with_area() {
        let v = |x: f32, y: f32, z: f32| Vec3A::new(x, y, z);
        let mut tris = vec![
            Triangle::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)),
            Triangle::new(v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), v(2.0, 2.0, 2.0)),
            Triangle::new(v(1.0, 2.0, 3.0), v(1.0, 2.0, 3.0), v(1.0, 2.0, 3.0)),
            Triangle::new(v(0.0, 0.0, 0.0), v(f32::NAN, 0.0, 0.0), v(0.0, 1.0, 0.0)),
            Triangle::new(
                v(0.0, 0.0, 0.0),
                v(f32::INFINITY, 0.0, 0.0),
                v(0.0, 1.0, 0.0),
            ),
        ];
        for e in [1e-3f32, 1e-10, 1e-19, 1e-20, 1e-22, 1e-23, 1e-30, 1e-38] {
            tris.push(Triangle::new(
                v(0.0, 0.0, 0.0),
                v(e, 0.0, 0.0),
                v(0.0, e, 0.0),
            ));
            tris.push(Triangle::new(
                v(1.0, 1.0, 1.0),
                v(1.0 + e, 1.0, 1.0),
                v(1.0, 1.0 + e, 1.0),
            ));
        }
        let mut kinds = [0; 2];
        for t in &tris {
            assert_eq!(t.has_area(), t.area() > 0.0, "{t:?}");
            kinds[t.has_area() as usize] += 1;
        }
        assert!(kinds[0] >= 4 && kinds[1] >= 4, "both kinds: {kinds:?}");
    }
}
