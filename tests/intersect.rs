//! Ray–primitive intersection, robust spawning of secondary rays, and the BVH.
//!
//! Reference values are computed independently in f64 from the exact f32 inputs the renderer
//! sees (the ray's f32 origin and direction, the f32 vertices), so the tolerances only have
//! to cover the f32 rounding of the code under test: a few units of γ(n) = nu/(1 − nu),
//! u = 2⁻²⁴ (pbrt-v4 eq. 6.11), scaled by the condition number of the computation at hand.

use glam::{DVec3, Vec3, Vec3A};
use mcrt::geometry::mesh::TriangleMesh;
use mcrt::geometry::{Ray, Sphere, Triangle};
use mcrt::material::{Bsdf, Lambert, Material};
use mcrt::sampler::Sampler;
use mcrt::scene::desc::{GeometryDesc, SceneDesc, ShapeDesc};
use mcrt::scene::{Interaction, Scene};
use mcrt::Color;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// Unit roundoff of f32.
const U: f64 = f32::EPSILON as f64 * 0.5;

struct Rng(Sampler);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(Sampler::from_state(seed, 0x5eed ^ seed))
    }
    fn f(&mut self) -> f32 {
        self.0.next_1d()
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    /// Uniform direction on the unit sphere (z = 1 − 2u, φ = 2πu').
    fn dir(&mut self) -> Vec3A {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * self.f();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
    /// Uniform point in the unit ball (rejection).
    fn ball(&mut self) -> Vec3A {
        loop {
            let p = Vec3A::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }
    /// A random rotation (from two random orthogonal directions).
    fn rotation(&mut self) -> glam::Mat3 {
        let a = Vec3::from(self.dir());
        let b = a.cross(Vec3::from(self.dir())).normalize();
        glam::Mat3::from_cols(a, b, a.cross(b))
    }
}

fn d64(v: Vec3A) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

fn material() -> Material {
    Material::new(
        Bsdf::Lambert(Lambert {
            albedo: Color::splat(0.5),
        }),
        true,
    )
}

fn mesh_shape(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> ShapeDesc {
    ShapeDesc {
        geometry: GeometryDesc::Mesh(TriangleMesh {
            tangents: None,
            positions,
            normals: None,
            uvs: None,
            indices,
        }),
        material: 0,
        emission: None,
    }
}

fn sphere_shape(center: Vec3, radius: f32) -> ShapeDesc {
    ShapeDesc {
        geometry: GeometryDesc::Sphere { center, radius },
        material: 0,
        emission: None,
    }
}

fn build(shapes: Vec<ShapeDesc>) -> Scene {
    Scene::build(SceneDesc {
        materials: vec![material()],
        shapes,
        ..Default::default()
    })
}

/// A cube of half-edge `h` around `c`, rotated by `rot`; 12 triangles wound so that the
/// geometric normals (right-hand rule) face outward.
fn cube_shape(c: Vec3, h: f32, rot: glam::Mat3) -> ShapeDesc {
    let mut positions = Vec::new();
    for i in 0..8 {
        let s = |b: u32| if i & b != 0 { 1.0 } else { -1.0 };
        positions.push(c + rot * (Vec3::new(s(1), s(2), s(4)) * h));
    }
    // Faces as quads (outward by the right-hand rule), split along one diagonal.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut indices = Vec::new();
    for q in quads {
        indices.push([q[0], q[1], q[2]]);
        indices.push([q[0], q[2], q[3]]);
    }
    mesh_shape(positions, indices)
}

/// Exact (f64) ray–sphere roots for the f32 ray and sphere, sorted; None if it misses.
fn sphere_roots64(o: Vec3A, d: Vec3A, c: Vec3A, r: f32) -> Option<(f64, f64)> {
    let (o, d, c, r) = (d64(o), d64(d), d64(c), r as f64);
    let f = o - c;
    let a = d.length_squared();
    let b = f.dot(d);
    // Δ/a = r² − |f − (f·d/a) d|² (Haines et al., Ray Tracing Gems ch. 7, eq. 10), in f64.
    let l = f - d * (b / a);
    let disc = r * r - l.length_squared();
    if disc < 0.0 {
        return None;
    }
    let tc = -b / a; // closest approach
    let half = (disc / a).sqrt();
    Some((tc - half, tc + half))
}

/// Exact (f64) ray–plane-of-triangle distance and barycentrics (Cramer's rule).
fn triangle_ref64(tri: &Triangle, o: Vec3A, d: Vec3A) -> (f64, f64, f64) {
    let [p0, p1, p2] = tri.vertices().map(d64);
    let (o, d) = (d64(o), d64(d));
    let (e1, e2, s) = (p1 - p0, p2 - p0, o - p0);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    let u = s.dot(pv) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    (e2.dot(q) / det, u, v)
}

// ---------------------------------------------------------------------------------------------
// Triangles
// ---------------------------------------------------------------------------------------------

/// Rays aimed at random interior points of random triangles, from either face, hit at the
/// distance and barycentrics of the exact solution; rays aimed outside, away, or with t_max
/// short of the hit miss.
#[test]
fn triangle_hits_and_misses() {
    let mut rng = Rng::new(1);
    let mut max_err = 0.0f64;
    for _ in 0..20_000 {
        let c = rng.ball() * 10.0;
        let [p0, p1, p2] = [0; 3].map(|_| c + rng.ball());
        let tri = Triangle::new(p0, p1, p2);
        let n = tri.normal_unnormalized().normalize();
        if tri.area() < 0.05 {
            continue; // keep the conditioning of the checks below moderate
        }
        // A point well inside (all barycentrics ≥ 0.05), approached from either side.
        let (u, v) = (rng.range(0.05, 0.9), rng.range(0.05, 0.9));
        if u + v > 0.95 {
            continue;
        }
        let target = p0 * (1.0 - u - v) + p1 * u + p2 * v;
        let mut w = rng.dir();
        if w.dot(n).abs() < 0.2 {
            continue; // grazing rays have their own test
        }
        if rng.f() < 0.5 {
            w = -w; // half of the rays arrive at the back face (triangles are double-sided)
        }
        let dist = rng.range(0.1, 5.0);
        let o = target + w * dist;
        let ray = Ray::new(o, (target - o).normalize());
        let (t_ref, u_ref, v_ref) = triangle_ref64(&tri, ray.o, ray.d);
        let (t, uh, vh) = tri
            .intersect(&ray, f32::INFINITY)
            .unwrap_or_else(|| panic!("missed an interior point: {tri:?} {ray:?}"));
        // Möller–Trumbore's t, u, v are ratios of triple products of vectors of length up to
        // |s| = |o − v0| ≲ 7 and edges ≳ 0.3, with det ≳ 0.2·|e1 × e2| (|cos θ| ≥ 0.2): their
        // absolute errors are a few u·|s|/(|cos θ|·sin of the triangle's angles) — measured
        // below 1e-5 here. 1e-4 leaves a margin while still catching any formula error.
        let (et, eu, ev) = (
            (t as f64 - t_ref).abs(),
            (uh as f64 - u_ref).abs(),
            (vh as f64 - v_ref).abs(),
        );
        max_err = max_err.max(et).max(eu).max(ev);
        assert!(et <= 1e-4 * t_ref.max(1.0), "t {t} vs {t_ref}");
        assert!(
            eu < 1e-4 && ev < 1e-4,
            "(u, v) = ({uh}, {vh}) vs ({u_ref}, {v_ref})"
        );
        // t_max is exclusive and limits the search.
        assert!(tri.intersect(&ray, t * (1.0 - 1e-5)).is_none());
        // The opposite direction sees nothing (t must be positive).
        assert!(tri.intersect(&Ray::new(o, -ray.d), f32::INFINITY).is_none());
        // A point clearly outside the triangle (beyond the edge v0–v1, i.e. v < 0) misses.
        let outside = p0 * (1.0 - u) + p1 * u - (p2 - p0) * 0.05;
        let ray = Ray::new(o, (outside - o).normalize());
        assert!(
            tri.intersect(&ray, f32::INFINITY).is_none(),
            "hit outside the triangle"
        );
    }
    eprintln!("triangle hits: largest error in t, u, v: {max_err:.2e}");
}

/// The same ray hits a triangle at the same t from the front and from the back (reversed
/// winding), and the scene reports the geometric normal of the winding, unflipped.
#[test]
fn triangles_are_double_sided() {
    let (p0, p1, p2) = (
        Vec3A::new(0.0, 0.0, 0.0),
        Vec3A::new(1.0, 0.0, 0.0),
        Vec3A::new(0.0, 1.0, 0.0),
    );
    let front = Triangle::new(p0, p1, p2); // normal +z
    let back = Triangle::new(p0, p2, p1); // normal −z
    let ray = Ray::new(Vec3A::new(0.25, 0.25, 2.0), Vec3A::new(0.0, 0.0, -1.0));
    assert_eq!(front.intersect(&ray, f32::INFINITY).unwrap().0, 2.0);
    assert_eq!(back.intersect(&ray, f32::INFINITY).unwrap().0, 2.0);
    let up = Ray::new(Vec3A::new(0.25, 0.25, -3.0), Vec3A::new(0.0, 0.0, 1.0));
    assert_eq!(front.intersect(&up, f32::INFINITY).unwrap().0, 3.0);
    let scene = build(vec![mesh_shape(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        vec![[0, 1, 2]],
    )]);
    let si = scene
        .intersect(&up)
        .expect("back-face hit through the scene");
    assert_eq!(
        si.ng,
        Vec3A::Z,
        "ng is the winding's normal, not flipped toward the ray"
    );
    assert!((si.p - Vec3A::new(0.25, 0.25, 0.0)).length() < 1e-6);
}

/// Grazing rays (1e-3 to 1e-1 rad off the plane) still hit at the right distance; a ray
/// exactly in the plane cannot hit (det = 0).
#[test]
fn grazing_rays_hit_triangles_at_the_right_t() {
    let mut rng = Rng::new(2);
    let tri = Triangle::new(
        Vec3A::new(-1.0, -1.0, 0.0),
        Vec3A::new(3.0, -1.0, 0.0),
        Vec3A::new(-1.0, 3.0, 0.0),
    );
    let mut hits = 0;
    for i in 0..2000 {
        let angle = 10f32.powf(rng.range(-3.0, -1.0)); // elevation above the plane
        let phi = rng.range(0.0, std::f32::consts::TAU);
        let side = if i % 2 == 0 { 1.0 } else { -1.0 };
        // Target: a point well inside (the incircle region); origin 2 units back along −w.
        let target = Vec3A::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 0.0);
        let w = Vec3A::new(
            angle.cos() * phi.cos(),
            angle.cos() * phi.sin(),
            side * angle.sin(),
        );
        let ray = Ray::new(target + w * 2.0, -w);
        let (t_ref, _, _) = triangle_ref64(&tri, ray.o, ray.d);
        let (t, _, _) = tri
            .intersect(&ray, f32::INFINITY)
            .expect("grazing ray missed");
        // t = h / sin(angle): its relative condition number is ~1/angle times the relative
        // error of the height h = o.z (exact here) and of the cross products (a few u):
        // tolerance 64·u/angle.
        assert!(
            ((t as f64 - t_ref) / t_ref).abs() <= 64.0 * U / angle as f64 + 1e-6,
            "angle {angle}: t {t} vs {t_ref}"
        );
        hits += 1;
    }
    assert_eq!(hits, 2000);
    let in_plane = Ray::new(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X);
    assert!(tri.intersect(&in_plane, f32::INFINITY).is_none());
}

/// Watertightness: a ray through the shared diagonal of a quad must hit one of its two
/// triangles. The rays are aimed at points of the diagonal (rounded to f32, so they land
/// within an ulp on either side of it) from both sides of random planar quads at three scales.
/// A watertight test (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT
/// 2(1), 2013; pbrt-v4 §6.5.3) never lets such a ray through; Möller–Trumbore evaluates the
/// shared edge with different floating-point expressions in the two triangles (u of one,
/// v of the other) and can reject both.
#[test]
fn rays_through_a_shared_edge_never_fall_through() {
    let mut rng = Rng::new(3);
    let (mut rays, mut through, mut scene_through) = (0u32, 0u32, 0u32);
    for quad in 0..60 {
        let s = [1e-3f32, 1.0, 1e4][quad % 3];
        let c = rng.ball() * 10.0 * s;
        let rot = rng.rotation();
        // A parallelogram in a random plane. The two triangles share the f32 vertices p0
        // and p2 exactly, which is all watertightness asks; the quad need not be exactly
        // planar after rounding.
        let (a, b) = (rng.range(0.3, 1.0) * s, rng.range(0.3, 1.0) * s);
        let sk = rng.range(-0.3, 0.3) * s;
        let local = [
            Vec3::new(-a - sk, -b, 0.0),
            Vec3::new(a - sk, -b, 0.0),
            Vec3::new(a + sk, b, 0.0),
            Vec3::new(-a + sk, b, 0.0),
        ];
        let p: Vec<Vec3> = local.iter().map(|q| Vec3::from(c) + rot * *q).collect();
        let pa: Vec<Vec3A> = p.iter().map(|&q| q.into()).collect();
        let ta = Triangle::new(pa[0], pa[1], pa[2]);
        let tb = Triangle::new(pa[0], pa[2], pa[3]);
        let n = ta.normal_unnormalized().normalize();
        let scene = build(vec![mesh_shape(p.clone(), vec![[0, 1, 2], [0, 2, 3]])]);
        for i in 0..500 {
            let f = (i as f32 + 0.5) / 500.0;
            let target = pa[0] + (pa[2] - pa[0]) * f;
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            let o = target + (rng.ball() * 0.8 + n * side) * (2.0 * s);
            let ray = Ray::new(o, (target - o).normalize());
            rays += 1;
            if ta.intersect(&ray, f32::INFINITY).is_none()
                && tb.intersect(&ray, f32::INFINITY).is_none()
            {
                through += 1;
            }
            if scene.intersect(&ray).is_none() {
                scene_through += 1;
            }
        }
    }
    eprintln!("shared edge: {through} of {rays} rays fell through (scene: {scene_through})");
    assert_eq!(
        through, 0,
        "{through} of {rays} rays through the shared diagonal hit neither triangle"
    );
    assert_eq!(scene_through, 0);
}

/// The same defect in a closed mesh: rays from the centre of a cube along its face normals
/// pass through the face centres, which lie on the diagonals splitting the faces into
/// triangles. None may escape.
#[test]
fn rays_from_inside_a_closed_cube_never_escape() {
    let mut rng = Rng::new(33);
    let mut escaped = 0;
    for k in 0..300 {
        let s = [1e-3f32, 1.0, 1e4][k % 3];
        let c = Vec3::from(rng.ball()) * 10.0 * s;
        let rot = rng.rotation();
        let scene = build(vec![cube_shape(c, s, rot)]);
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            let ray = Ray::new(c.into(), (rot * axis).into());
            if scene.intersect(&ray).is_none() {
                escaped += 1;
            }
        }
    }
    assert_eq!(
        escaped, 0,
        "{escaped} of 1800 rays from the centre of a closed cube escaped through a face centre"
    );
}

// ---------------------------------------------------------------------------------------------
// Spheres
// ---------------------------------------------------------------------------------------------

/// From inside a sphere every ray hits the far side, at the positive root.
#[test]
fn rays_from_inside_a_sphere_hit_the_far_side() {
    let mut rng = Rng::new(4);
    let mut max_err = 0.0f64;
    for i in 0..20_000 {
        let scale = [1e-3f32, 1.0, 1e3][i % 3];
        let sph = Sphere {
            center: rng.ball() * 3.0 * scale,
            radius: rng.range(0.5, 2.0) * scale,
        };
        let o = sph.center + rng.ball() * (0.99 * sph.radius);
        let ray = Ray::new(o, rng.dir());
        let (t0, t1) = sphere_roots64(ray.o, ray.d, sph.center, sph.radius).unwrap();
        assert!(t0 < 0.0 && t1 > 0.0);
        let t = sph
            .intersect(&ray, f32::INFINITY)
            .expect("ray from inside missed") as f64;
        // The reference uses the f32 ray exactly, so only the rounding inside `intersect`
        // counts: f = o − c, the projections and the root are each good to a few u of
        // |f| + r ≤ 2r, i.e. a few 1e-7 r. Allow 1e-5 r (≈ 170 u·r).
        let err = (t - t1).abs() / sph.radius as f64;
        max_err = max_err.max(err);
        assert!(err <= 1e-5, "t {t} vs far root {t1} (near {t0})");
    }
    eprintln!("inside sphere: largest error {:.1} u·r", max_err / U);
}

/// Rays passing the sphere at distance r(1 ± 1e-3) from its centre miss and hit; the hit of
/// a nearly tangent ray is at the tangent point.
#[test]
fn tangent_rays() {
    let mut rng = Rng::new(5);
    for _ in 0..5000 {
        let sph = Sphere {
            center: rng.ball() * 5.0,
            radius: rng.range(0.2, 2.0),
        };
        let d = rng.dir();
        let perp = d.cross(rng.dir()).normalize();
        let back = rng.range(1.0, 10.0) * sph.radius;
        for (k, should_hit) in [(1.0 + 1e-3, false), (1.0 - 1e-3, true)] {
            let o = sph.center + perp * (sph.radius * k) - d * back;
            let ray = Ray::new(o, d);
            let hit = sph.intersect(&ray, f32::INFINITY);
            assert_eq!(hit.is_some(), should_hit, "offset {k}: {hit:?}");
            if let Some(t) = hit {
                // The chord half-length is r·√(1 − k²) ≈ 0.045 r, so t is within it of the
                // tangent point at distance `back`.
                let (t0, _) = sphere_roots64(ray.o, ray.d, sph.center, sph.radius).unwrap();
                assert!((t as f64 - t0).abs() <= 1e-4 * sph.radius as f64 + 1e-5 * back as f64);
                assert!((t - back).abs() <= 0.05 * sph.radius);
            }
        }
    }
}

/// A sphere of radius 1e-2 at distance 1e4: the discriminant b² − ac of the textbook
/// quadratic cancels catastrophically (b² ≈ 1e8, its ulp ≈ 8 ≫ r²|d|² = 1e-4), while the form
/// r² − |f − (f·d̂)d̂|² of Haines et al. (Ray Tracing Gems ch. 7, eq. 10) keeps it. Rays aimed
/// within 0.6 r of the centre must hit at the near root to ~1e-5 relative.
#[test]
fn tiny_sphere_far_away() {
    let mut rng = Rng::new(6);
    let (mut naive_wrong, mut n) = (0, 0);
    for _ in 0..5000 {
        let dir_c = rng.dir();
        let center = dir_c * 1e4;
        let sph = Sphere {
            center,
            radius: 1e-2,
        };
        let o = rng.ball() * 10.0;
        let aim = center + dir_c.cross(rng.dir()).normalize() * (rng.range(0.0, 0.6) * sph.radius);
        let ray = Ray::new(o, (aim - o).normalize());
        // Rounding the aim point (half an ulp of 1e4 ≈ 5e-4 per axis) and the direction
        // (u·1e4 ≈ 6e-4) moves the ray by at most ~2e-3 at the sphere: still inside r.
        let Some((t0, _)) = sphere_roots64(ray.o, ray.d, sph.center, sph.radius) else {
            panic!("reference misses: the aim was not inside the sphere");
        };
        let t = sph
            .intersect(&ray, f32::INFINITY)
            .expect("far tiny sphere missed") as f64;
        assert!(((t - t0) / t0).abs() <= 1e-5, "t {t} vs {t0}");
        // The same rays through the textbook formula, to show the test has teeth.
        n += 1;
        if naive_sphere(&ray, &sph).is_none_or(|tn| ((tn as f64 - t0) / t0).abs() > 1e-5) {
            naive_wrong += 1;
        }
    }
    eprintln!("tiny far sphere: textbook quadratic wrong on {naive_wrong} of {n} rays");
    assert!(
        naive_wrong > n / 10,
        "the textbook quadratic should fail on these rays"
    );
}

/// The textbook root t = (−b − √(b² − 4ac)) / 2a, for comparison only.
fn naive_sphere(ray: &Ray, s: &Sphere) -> Option<f32> {
    let f = ray.o - s.center;
    let (a, b, c) = (
        ray.d.dot(ray.d),
        2.0 * f.dot(ray.d),
        f.dot(f) - s.radius * s.radius,
    );
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    Some((-b - disc.sqrt()) / (2.0 * a))
}

// ---------------------------------------------------------------------------------------------
// Self-intersection of spawned rays
// ---------------------------------------------------------------------------------------------

/// Scene scales for the self-intersection tests: (object size, object position). The first
/// three scale the whole scene by 1e-3, 1 and 1e4; the last puts a small object far from the
/// origin, where the hit points' absolute error dominates.
fn scales() -> Vec<(f32, Vec3)> {
    let off = Vec3::new(3.0, -2.0, 5.0);
    vec![
        (1e-3, off * 1e-3),
        (1.0, off),
        (1e4, off * 1e4),
        (1e-2, off * 1e2),
    ]
}

/// The offset of a spawned origin from the hit point stays within a few error bounds.
fn check_offset(si: &Interaction, o: Vec3A) {
    let bound = 2.0 * (si.p_err.x + si.p_err.y + si.p_err.z)
        + 4.0 * f32::EPSILON * si.p.abs().max_element();
    assert!(
        (o - si.p).length() <= bound,
        "offset {} > {bound}",
        (o - si.p).length()
    );
}

/// Shoots rays from outside and from inside a closed convex object (sphere or cube, whose
/// geometric normals face outward) and, at every hit, spawns rays in random directions on
/// both sides. Leaving outward, a ray must not hit the object again (it is convex); going
/// inward it must hit a different part of the surface (`inward_ok` judges the hit of an
/// inward ray). Returns the number of (outward, inward) failures.
fn check_convex(
    scene: &Scene,
    center: Vec3A,
    size: f32,
    inward_ok: impl Fn(&Interaction, &Ray, Option<&Interaction>) -> bool,
    seed: u64,
) -> (u32, u32) {
    let mut rng = Rng::new(seed);
    let (mut bad_out, mut bad_in) = (0, 0);
    for k in 0..600 {
        let from_inside = k % 2 == 1;
        let o = if from_inside {
            center + rng.ball() * (0.3 * size)
        } else {
            center + rng.dir() * (4.0 * size)
        };
        let aim = center + rng.ball() * (0.7 * size);
        let ray = Ray::new(
            o,
            if from_inside {
                rng.dir()
            } else {
                (aim - o).normalize()
            },
        );
        let Some(si) = scene.intersect(&ray) else {
            assert!(!from_inside, "a ray from inside escaped the closed object");
            continue;
        };
        for _ in 0..8 {
            let w = rng.dir();
            let spawned = si.spawn_ray(w);
            check_offset(&si, spawned.o);
            let hit = scene.intersect(&spawned);
            if w.dot(si.ng) > 0.0 {
                if hit.is_some() {
                    bad_out += 1;
                }
            } else if !inward_ok(&si, &spawned, hit.as_ref()) {
                bad_in += 1;
            }
        }
    }
    (bad_out, bad_in)
}

#[test]
fn spawned_rays_do_not_reintersect_spheres() {
    for (i, (size, pos)) in scales().into_iter().enumerate() {
        let scene = build(vec![sphere_shape(pos, size)]);
        let c = Vec3A::from(pos);
        let (bad_out, bad_in) = check_convex(
            &scene,
            c,
            size,
            // Inward rays must hit the far root of the exact quadratic for the spawned ray:
            // the near root is within the offset (≈ γ(5)(|c| + r)) of t = 0, the far one at
            // the chord length 2r|cos θ|. Accept the hit if it is closer to the far root.
            |_, ray, h| {
                let (t0, t1) = sphere_roots64(ray.o, ray.d, c, size).unwrap();
                h.is_some_and(|h| (h.t as f64 - t1).abs() < (h.t as f64 - t0).abs())
            },
            100 + i as u64,
        );
        assert_eq!(
            (bad_out, bad_in),
            (0, 0),
            "size {size} at {pos}: (re-hits outward, wrong inward hits)"
        );
    }
}

/// Whether a hit point on the cube (centre c, half-edge h, rotation rot) lies within four
/// times its error bound of an edge. There it may as well be on the adjacent face, and rays
/// that leave through that face at once are legitimate (at an edge, the cube's interior is
/// the wedge below both faces).
fn near_cube_edge(si: &Interaction, c: Vec3A, h: f32, rot: glam::Mat3) -> bool {
    let a = (rot.transpose() * Vec3::from(si.p - c)).abs();
    // Distance to the nearest edge: the half-edge minus the middle |local coordinate|.
    let edge_dist = h - (a.x + a.y + a.z - a.max_element() - a.min_element());
    edge_dist < 4.0 * si.p_err.length()
}

#[test]
fn spawned_rays_do_not_reintersect_cubes() {
    for (i, (size, pos)) in scales().into_iter().enumerate() {
        let mut rng = Rng::new(200 + i as u64);
        let rot = rng.rotation();
        let scene = build(vec![cube_shape(pos, size, rot)]);
        let c = Vec3A::from(pos);
        let (bad_out, bad_in) = check_convex(
            &scene,
            c,
            size,
            // An inward ray must land on another face (faces are orthogonal or opposite),
            // except near an edge (see `near_cube_edge`).
            |si, _, h| near_cube_edge(si, c, size, rot) || h.is_some_and(|h| h.ng.dot(si.ng) < 0.5),
            300 + i as u64,
        );
        assert_eq!(
            (bad_out, bad_in),
            (0, 0),
            "size {size} at {pos}: (re-hits outward, wrong inward hits)"
        );
    }
}

/// An open single triangle: a ray spawned from it to either side can never hit it again.
#[test]
fn spawned_rays_do_not_reintersect_a_triangle() {
    for (i, (size, pos)) in scales().into_iter().enumerate() {
        let mut rng = Rng::new(400 + i as u64);
        let mut bad = 0;
        for _ in 0..40 {
            let p: Vec<Vec3> = (0..3)
                .map(|_| pos + Vec3::from(rng.ball()) * size)
                .collect();
            let scene = build(vec![mesh_shape(p.clone(), vec![[0, 1, 2]])]);
            let centroid = Vec3A::from((p[0] + p[1] + p[2]) / 3.0);
            for _ in 0..50 {
                let o = centroid + rng.dir() * (2.0 * size);
                let aim = centroid + rng.ball() * (0.3 * size);
                let Some(si) = scene.intersect(&Ray::new(o, (aim - o).normalize())) else {
                    continue;
                };
                for _ in 0..8 {
                    let spawned = si.spawn_ray(rng.dir());
                    check_offset(&si, spawned.o);
                    if scene.intersect(&spawned).is_some()
                        || scene.occluded(&spawned, f32::INFINITY)
                    {
                        bad += 1;
                    }
                }
            }
        }
        assert_eq!(
            bad, 0,
            "size {size} at {pos}: spawned rays re-hit their triangle"
        );
    }
}

/// Shadow rays between two points on the inside of a closed cube or sphere (next-event
/// estimation in a closed room) must be unoccluded; with a blocker on the segment, occluded.
/// The shadow ray, evaluated at t = 1, lands on the target (within its offset).
#[test]
fn shadow_rays_between_surface_points() {
    for (i, (size, pos)) in scales().into_iter().enumerate() {
        let mut rng = Rng::new(500 + i as u64);
        let c = Vec3A::from(pos);
        let rot = rng.rotation();
        for (scene, is_cube) in [
            (build(vec![cube_shape(pos, size, rot)]), true),
            (build(vec![sphere_shape(pos, size)]), false),
        ] {
            let mut bad = 0;
            let mut pts = Vec::new();
            while pts.len() < 200 {
                let ray = Ray::new(c + rng.ball() * (0.3 * size), rng.dir());
                pts.push(scene.intersect(&ray).expect("closed object"));
            }
            for pair in pts.chunks(2) {
                let (a, b) = (&pair[0], &pair[1]);
                if a.ng.dot(b.ng) > 0.99 {
                    continue; // same face of the cube: the segment lies in its plane
                }
                let near_edge = |p| near_cube_edge(p, c, size, rot);
                if is_cube && (near_edge(a) || near_edge(b)) {
                    continue; // the segment may legitimately graze the adjacent face
                }
                for (x, y) in [(a, b), (b, a)] {
                    let (ray, t_max) = x.spawn_ray_to(y.p, y.p_err, y.ng);
                    let miss = (ray.at(1.0) - y.p).length();
                    let bound = 4.0 * (y.p_err.length() + f32::EPSILON * y.p.abs().max_element());
                    assert!(miss <= bound, "shadow ray ends {miss} from its target");
                    if scene.occluded(&ray, t_max) {
                        bad += 1;
                    }
                }
            }
            assert_eq!(
                bad, 0,
                "size {size}: shadow rays inside a closed object were occluded"
            );
        }
        // A blocker: a small sphere (radius 0.1) at the centre of a cube blocks the segment
        // between two points of opposite faces that passes 0.06 from the centre. (The points
        // are off the faces' centres, which lie on the diagonals shared by their triangles:
        // see `rays_through_a_shared_edge_never_fall_through`.)
        let rot = rng.rotation();
        let scene = build(vec![
            cube_shape(pos, size, rot),
            sphere_shape(pos, 0.1 * size),
        ]);
        let axis = Vec3A::from(rot * Vec3::X);
        let off = Vec3A::from(rot * Vec3::new(0.0, 0.05, -0.03)) * size;
        let a = scene
            .intersect(&Ray::new(c + off + axis * (0.5 * size), axis))
            .unwrap();
        let b = scene
            .intersect(&Ray::new(c + off - axis * (0.5 * size), -axis))
            .unwrap();
        let (ray, t_max) = a.spawn_ray_to(b.p, b.p_err, b.ng);
        assert!(scene.occluded(&ray, t_max), "size {size}: blocker not seen");
        assert!(
            scene.intersect(&ray).is_some_and(|h| h.t < 0.6),
            "size {size}: blocker not hit first"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// BVH
// ---------------------------------------------------------------------------------------------

/// A soup of random triangles (sizes 0.01 to 2, log-uniform) and spheres in a ball of radius 10,
/// with the primitives kept aside for brute force.
struct Soup {
    scene: Scene,
    tris: Vec<Triangle>,
    spheres: Vec<Sphere>,
}

impl Soup {
    fn new(rng: &mut Rng, n_tris: u32, n_spheres: u32) -> Soup {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        let mut tris = Vec::new();
        for i in 0..n_tris {
            let c = Vec3::from(rng.ball()) * 10.0;
            let size = 10f32.powf(rng.range(-2.0, 0.3));
            let p = [0; 3].map(|_| c + Vec3::from(rng.ball()) * size);
            positions.extend_from_slice(&p);
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
            tris.push(Triangle::new(p[0].into(), p[1].into(), p[2].into()));
        }
        let mut shapes = vec![mesh_shape(positions, indices)];
        let mut spheres = Vec::new();
        for _ in 0..n_spheres {
            let s = Sphere {
                center: rng.ball() * 10.0,
                radius: rng.range(0.05, 0.5),
            };
            shapes.push(sphere_shape(s.center.into(), s.radius));
            spheres.push(s);
        }
        let scene = build(shapes);
        assert_eq!(scene.prim_count(), tris.len() + spheres.len());
        Soup {
            scene,
            tris,
            spheres,
        }
    }

    /// The nearest hit in (0, t_max) over all primitives, by the same primitive tests the
    /// scene uses (so the BVH must reproduce it bit for bit).
    fn brute(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let tris = self
            .tris
            .iter()
            .map(|tri| tri.intersect(ray, t_max).map(|h| h.0));
        let spheres = self.spheres.iter().map(|s| s.intersect(ray, t_max));
        tris.chain(spheres).flatten().min_by(f32::total_cmp)
    }

    /// Compares closest hit and any-hit (with a random t_max) with brute force: Ok(whether
    /// the ray hit anything), or Err describing the disagreement.
    fn check(&self, ray: &Ray, rng: &mut Rng) -> Result<bool, String> {
        let expected = self.brute(ray, f32::INFINITY);
        let got = self.scene.intersect(ray).map(|h| h.t);
        if got != expected {
            return Err(format!(
                "closest hit {got:?}, brute force {expected:?}: {ray:?}"
            ));
        }
        let t_max = rng.range(0.0, 40.0);
        let (got, expected) = (
            self.scene.occluded(ray, t_max),
            self.brute(ray, t_max).is_some(),
        );
        if got != expected {
            return Err(format!(
                "occluded {got}, brute force {expected}, t_max {t_max}: {ray:?}"
            ));
        }
        Ok(expected)
    }
}

/// Runs `check` over rays, and fails listing the disagreements.
fn check_rays(soup: &Soup, rays: impl Iterator<Item = Ray>, rng: &mut Rng) -> u32 {
    let (mut n, mut hits, mut bad) = (0, 0, Vec::new());
    for ray in rays {
        n += 1;
        match soup.check(&ray, rng) {
            Ok(hit) => hits += hit as u32,
            Err(e) => bad.push(e),
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {n} rays disagree with brute force, e.g.\n{}",
        bad.len(),
        bad[..bad.len().min(5)].join("\n")
    );
    hits
}

/// Random rays for a `Soup`: from inside the cloud in random directions, or from outside
/// towards it; with `axis_parallel`, every tenth along an axis (two positive zero components).
fn cloud_rays(rng: &mut Rng, n: usize, axis_parallel: bool) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let o = if i % 2 == 0 {
                rng.ball() * 12.0
            } else {
                rng.dir() * 30.0
            };
            let d = if axis_parallel && i % 10 == 0 {
                let mut a = [0.0f32; 3];
                a[(i / 10) % 3] = if rng.f() < 0.5 { 1.0 } else { -1.0 };
                Vec3A::from_array(a)
            } else if i % 2 == 0 {
                rng.dir()
            } else {
                (rng.ball() * 8.0 - o).normalize()
            };
            Ray::new(o, d)
        })
        .collect()
}

/// The BVH's closest hit and any-hit agree exactly with brute force over every primitive,
/// for a few thousand random small triangles and some spheres, with random rays from inside
/// and outside the cloud, including axis-parallel directions (infinite reciprocals).
#[test]
fn bvh_matches_brute_force() {
    let mut rng = Rng::new(7);
    let soup = Soup::new(&mut rng, 4000, 50);
    let rays = cloud_rays(&mut rng, 4000, true);
    let hits = check_rays(&soup, rays.into_iter(), &mut rng);
    // The test must exercise both outcomes.
    eprintln!("BVH: {hits} of 4000 rays hit");
    assert!(hits > 400 && hits < 3600, "{hits} hits");
}

/// Inputs of at least `bvh::CLUSTER_MIN` primitives are built over small clusters of them;
/// that tree too must agree exactly with brute force.
#[test]
fn clustered_bvh_matches_brute_force() {
    let mut rng = Rng::new(11);
    let soup = Soup::new(&mut rng, mcrt::accel::bvh::CLUSTER_MIN as u32 + 500, 30);
    let rays = cloud_rays(&mut rng, 1500, false);
    let hits = check_rays(&soup, rays.into_iter(), &mut rng);
    assert!(hits > 150 && hits < 1350, "{hits} hits");
}

/// The clustered build runs in parallel (radix sort, clusters, subtrees, collapse); the tree
/// must not depend on the threads: built on one, two and three, the scenes report the same
/// SAH cost and size and give every ray the same closest hit, bit for bit.
#[test]
fn clustered_bvh_is_the_same_on_any_thread_count() {
    let n = mcrt::accel::bvh::CLUSTER_MIN as u32 * 3;
    let soups: Vec<Soup> = [1, 2, 3]
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Soup::new(&mut Rng::new(12), n, 20))
        })
        .into_iter()
        .collect();
    let rays = cloud_rays(&mut Rng::new(13), 3000, false);
    let summary = |s: &Soup| {
        let hits: Vec<Option<(u32, [u32; 3])>> = rays
            .iter()
            .map(|r| {
                s.scene
                    .intersect(r)
                    .map(|h| (h.t.to_bits(), h.p.to_array().map(f32::to_bits)))
            })
            .collect();
        (
            s.scene.bvh.sah_cost().to_bits(),
            s.scene.memory_bytes(),
            hits,
        )
    };
    let first = summary(&soups[0]);
    assert!(first.2.iter().filter(|h| h.is_some()).count() > 300);
    for (threads, s) in [2, 3].iter().zip(&soups[1..]) {
        assert!(
            summary(s) == first,
            "the tree built on {threads} threads differs"
        );
    }
}

/// Directions with a component of −0.0 (as `-Vec3A::Y` has, or any negated zero) are
/// directions like any other: the ray is parallel to that slab, and its reciprocal is −∞.
/// The traversal must treat the slab by the sign of the reciprocal (pbrt-v4's
/// `dirIsNeg = invDir < 0`), not by `d < 0.0`, which is false for −0.0.
#[test]
fn bvh_handles_negative_zero_direction_components() {
    let mut rng = Rng::new(77);
    let soup = Soup::new(&mut rng, 2000, 20);
    let rays: Vec<Ray> = (0..3000)
        .map(|i| {
            let o = rng.ball() * 12.0;
            let mut a = if i % 3 == 0 {
                // Axis-parallel, e.g. −Y = (−0, −1, −0).
                let mut a = [0.0f32; 3];
                a[(i / 3) % 3] = if rng.f() < 0.5 { 1.0 } else { -1.0 };
                a.map(|c| -c)
            } else {
                // In a coordinate plane, the third component −0.0.
                rng.dir().to_array()
            };
            if i % 3 != 0 {
                a[(i / 3) % 3] = -0.0;
            }
            Ray::new(o, Vec3A::from_array(a).normalize())
        })
        .collect();
    let hits = check_rays(&soup, rays.into_iter(), &mut rng);
    assert!(hits > 100, "{hits} hits");
}

/// Direction `d` as it is, or for `case` % 11 below 3 an awkward one for a box test: axis
/// `k % 3` of it 0.0 or −0.0, or only that axis, ±1.
fn awkward(rng: &mut Rng, d: Vec3A, case: usize, k: usize) -> [f32; 3] {
    let mut d = d.to_array();
    match case % 11 {
        0 => d[k % 3] = 0.0,
        1 => d[k % 3] = -0.0,
        2 => {
            d = [0.0; 3];
            d[k % 3] = if rng.f() < 0.5 { 1.0 } else { -1.0 };
        }
        _ => {}
    }
    d
}

/// Shadow-ray packets (sixteen rays from one origin, traced together, with AVX or AVX-512
/// where the CPU has it) give each ray exactly the answer of its own traversal and of brute force: rays
/// to points in the cloud and beyond it, with axis-parallel directions and −0.0 components
/// among them, random `t_max` per lane, and random sets of active lanes.
#[test]
fn shadow_packets_match_single_rays() {
    use mcrt::accel::{RayPacket, PACKET};
    let mut rng = Rng::new(8);
    let soup = Soup::new(&mut rng, 3000, 40);
    let (mut occluded, mut lanes) = (0, 0);
    for i in 0..3000 {
        let o = if i % 2 == 0 {
            rng.ball() * 12.0
        } else {
            rng.dir() * 30.0
        };
        // A target region: small (coherent rays, as next-event estimation sends) or large.
        let (c, r) = (rng.ball() * 10.0, if i % 3 == 0 { 8.0 } else { 0.5 });
        let mut pk = RayPacket {
            o,
            d: [[0.0; PACKET]; 3],
            t_max: [0.0; PACKET],
        };
        // Some packets aim at points on one triangle's edges (the lanes `intersect_lanes`
        // leaves to the f64 test), beyond the triangle so that it is the blocker.
        let tri = soup.tris[(rng.f() * soup.tris.len() as f32) as usize % soup.tris.len()];
        for lane in 0..PACKET {
            let target = if i % 5 == 1 {
                let (a, b) = [(tri.p0, tri.p1), (tri.p1, tri.p2), (tri.p2, tri.p0)][lane % 3];
                o + (a + (b - a) * rng.f() - o) * 1.5
            } else {
                c + rng.ball() * r
            };
            let d = awkward(&mut rng, target - o, i + lane, lane);
            (pk.d[0][lane], pk.d[1][lane], pk.d[2][lane]) = (d[0], d[1], d[2]);
            pk.t_max[lane] = if rng.f() < 0.5 {
                1.0 - 1e-4
            } else {
                rng.range(0.0, 3.0)
            };
        }
        let active = if i % 4 == 0 {
            (rng.f() * (1 << PACKET) as f32) as u32
        } else {
            (1 << PACKET) - 1
        };
        let got = soup.scene.occluded_packet(&pk, active);
        // (Where the CPU has AVX-512 the call above used it; eight lanes and one too.)
        for lanes in [1, 8] {
            let other = soup.scene.occluded_packet_with(&pk, active, lanes);
            assert_eq!(other, got, "packet {i}: {lanes} lanes and 16 differ");
        }
        for lane in 0..PACKET {
            let want_lane = active & (1 << lane) != 0;
            let ray = pk.ray(lane);
            let single = want_lane && soup.scene.occluded(&ray, pk.t_max[lane]);
            let brute = want_lane && soup.brute(&ray, pk.t_max[lane]).is_some();
            assert_eq!(
                got & (1 << lane) != 0,
                single,
                "packet {i} lane {lane} (active {active:#x}): {ray:?}, t_max {}",
                pk.t_max[lane]
            );
            assert_eq!(single, brute, "packet {i} lane {lane}: {ray:?}");
            occluded += single as u32;
            lanes += want_lane as u32;
        }
    }
    eprintln!("packets: {occluded} of {lanes} rays occluded");
    assert!(occluded > lanes / 10 && occluded < lanes * 9 / 10);
}

/// Shadow rays each from its own origin, traced sixteen to a packet
/// (`Scene::occluded_origins`; box tests sixteen, eight or one lane at a time) give each
/// ray exactly the answer of its own traversal and of brute force: origins near one another
/// (a pixel's first vertices) or spread over the cloud, targets in a small or a large
/// region, axis-parallel directions and −0.0 components among them, random `t_max` per ray,
/// batches of 1 to 40 rays (full and partial packets).
#[test]
fn shadow_rays_of_own_origins_match_single_rays() {
    use mcrt::accel::PACKET;
    let mut rng = Rng::new(9);
    let soup = Soup::new(&mut rng, 3000, 40);
    let (mut occluded, mut total) = (0, 0);
    for i in 0..2000 {
        let centre = rng.ball() * 12.0;
        let spread = [0.01, 0.3, 10.0][i % 3];
        let (c, r) = (rng.ball() * 10.0, if i % 4 == 0 { 8.0 } else { 0.5 });
        // Up to two and a half packets.
        let n = 1 + i % (5 * PACKET / 2);
        let mut rays = Vec::new();
        let mut t_max = Vec::new();
        for k in 0..n {
            let o = centre + rng.ball() * spread;
            let target = c + rng.ball() * r;
            let d = awkward(&mut rng, target - o, i + k, k);
            rays.push(Ray::new(o, Vec3A::from_array(d)));
            t_max.push(if rng.f() < 0.5 {
                1.0 - 1e-4
            } else {
                rng.range(0.0, 3.0)
            });
        }
        let mut got = vec![false; n];
        soup.scene.occluded_origins(&rays, &t_max, &mut got);
        for lanes in [1, 8] {
            let mut other = vec![false; n];
            soup.scene
                .occluded_origins_with(&rays, &t_max, lanes, &mut other);
            assert_eq!(other, got, "batch {i}: {lanes} lanes and 16 differ");
        }
        for (k, (ray, &t)) in rays.iter().zip(&t_max).enumerate() {
            let single = soup.scene.occluded(ray, t);
            assert_eq!(got[k], single, "batch {i} ray {k}: {ray:?}, t_max {t}");
            assert_eq!(single, soup.brute(ray, t).is_some(), "batch {i} ray {k}");
            occluded += single as u32;
            total += 1;
        }
    }
    eprintln!("own origins: {occluded} of {total} rays occluded");
    assert!(occluded > total / 10 && occluded < total * 9 / 10);
}

// ---------------------------------------------------------------------------------------------
// Brute force for small scenes against the BVH
// ---------------------------------------------------------------------------------------------

/// Everything a hit tells shading, as bits.
fn hit_bits(h: &Option<Interaction>) -> Option<Vec<u32>> {
    h.map(|h| {
        let mut v: Vec<u32> = [h.p, h.p_err, h.ng, h.ns]
            .iter()
            .flat_map(|x| x.to_array())
            .chain([h.t, h.uv.x, h.uv.y])
            .map(f32::to_bits)
            .collect();
        v.extend([h.material, h.light]);
        v
    })
}

/// Small scenes trace single rays by brute force where the CPU has AVX (`accel::flat`), and
/// the answers are the BVH's bit for bit, ties included (both keep, of equally near hits,
/// the lowest primitive): the example scenes, a box of cubes and spheres, and a doubled
/// wall (every hit on it a tie). Rays from points inside the scenes' bounds and from points
/// on their surfaces, each also as a shadow ray ending before and past its hit.
#[test]
fn brute_force_and_the_bvh_agree() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scenes: Vec<(String, SceneDesc)> = ["scenes/cornell-box.toml", "scenes/tncg15.toml"]
        .iter()
        .map(|f| (f.to_string(), mcrt::load_scene(&root.join(f)).unwrap()))
        .collect();
    let mut r = Rng::new(77);
    let mut shapes = vec![cube_shape(Vec3::ZERO, 2.0, glam::Mat3::IDENTITY)];
    for _ in 0..3 {
        let c = Vec3::from(r.ball());
        shapes.push(cube_shape(c, 0.3, r.rotation()));
        shapes.push(sphere_shape(Vec3::from(r.ball()), 0.4));
    }
    // Twice the same quad.
    let quad = || {
        mesh_shape(
            vec![
                Vec3::new(-1.5, -1.5, 0.5),
                Vec3::new(1.5, -1.5, 0.5),
                Vec3::new(1.5, 1.5, 0.5),
                Vec3::new(-1.5, 1.5, 0.5),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    };
    shapes.push(quad());
    shapes.push(quad());
    scenes.push((
        "cubes, spheres and a doubled wall".into(),
        SceneDesc {
            materials: vec![material()],
            shapes,
            ..Default::default()
        },
    ));
    let mut flat_seen = 0;
    for (name, desc) in scenes {
        let brute = Scene::build(desc.clone());
        flat_seen += brute.is_flat() as u32;
        let bvh = Scene::build_with(desc, mcrt::accel::SingleRays::Bvh);
        let b = bvh.bvh.bounds().unwrap();
        let (mut hits, mut blocked) = (0, 0);
        for i in 0..40_000 {
            let o = b.min + (b.max - b.min) * Vec3A::new(r.f(), r.f(), r.f());
            let mut ray = Ray::new(o, r.dir());
            if i % 2 == 1 {
                // From the surface the first ray meets, as a bounce leaves it.
                if let Some(h) = bvh.intersect(&ray) {
                    let d = r.dir();
                    ray = h.spawn_ray(if d.dot(h.ng) * ray.d.dot(h.ng) > 0.0 {
                        -d
                    } else {
                        d
                    });
                }
            }
            let (want, got) = (bvh.intersect(&ray), brute.intersect(&ray));
            assert_eq!(hit_bits(&got), hit_bits(&want), "{name}, ray {i}: {ray:?}");
            let t = want.map_or(1e3, |h| h.t) * if i % 3 == 0 { 0.5 } else { 1.5 };
            let occluded = bvh.occluded(&ray, t);
            assert_eq!(brute.occluded(&ray, t), occluded, "{name}, ray {i}");
            hits += want.is_some() as u32;
            blocked += occluded as u32;
        }
        assert!(
            hits > 20_000 && blocked > 5_000,
            "{name}: {hits} hits, {blocked} blocked"
        );
    }
    // Brute force took all three scenes (up to 64 triangles) where the CPU has AVX, none
    // elsewhere.
    #[cfg(target_arch = "x86_64")]
    let want = if std::arch::is_x86_feature_detected!("avx") {
        3
    } else {
        0
    };
    #[cfg(not(target_arch = "x86_64"))]
    let want = 0;
    assert_eq!(flat_seen, want, "scenes traced by brute force");
}
