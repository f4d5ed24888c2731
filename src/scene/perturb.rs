//! The partial derivatives dp/du and dp/dv at a hit, where a normal- or bump-mapped material
//! needs them (Mitsuba 3's conventions: mesh.cpp and sphere.cpp), and the perturbed shading
//! normal made from them ([`crate::material::normal_map`]). Hits of other materials skip all
//! of this.

use super::{Interaction, Scene};
use crate::geometry::{Ray, Triangle};
use crate::material::normal_map::{perturbed_normal, HitGeometry};
use glam::{Vec2, Vec3A, Vec4};
use std::f32::consts::{PI, TAU};

impl Scene {
    /// Perturbs the shading normal of `si`, a hit of triangle `tri` (vertex texture
    /// coordinates `uvs`, if its mesh has them) with a normal- or bump-mapped material;
    /// `tangent` is the interpolated vertex tangent (glTF's TANGENT), where the mesh has
    /// them and the material a normal map.
    ///
    /// `si` is taken and given back by value: through a reference, the caller's interaction
    /// lived in memory on every hit, and was copied twice more on its way out of
    /// [`Scene::intersect`]; so, it is copied only on this path.
    #[cold]
    pub(super) fn perturb_triangle(
        &self,
        mut si: Interaction,
        ray: &Ray,
        tri: &Triangle,
        uvs: Option<[Vec2; 3]>,
        tangent: Option<Vec4>,
    ) -> Interaction {
        let (dpdu, dpdv) = triangle_partials(tri, uvs, si.ng);
        self.perturb(&mut si, ray, dpdu, dpdv, tangent);
        si
    }

    /// Perturbs the shading normal of `si`, a hit of a sphere of radius `radius` (by value,
    /// as in [`Scene::perturb_triangle`]).
    #[cold]
    /// The partials are those of its texture coordinates, in its own frame (`frame`), taken
    /// at its outward normal.
    pub(super) fn perturb_sphere(
        &self,
        mut si: Interaction,
        ray: &Ray,
        radius: f32,
        frame: &super::SphereFrame,
    ) -> Interaction {
        let outward = if frame.flip { -si.ng } else { si.ng };
        let (dpdu, dpdv) = sphere_partials(frame.local(outward), radius);
        let (dpdu, dpdv) = (frame.world(dpdu), frame.world(dpdv));
        self.perturb(&mut si, ray, dpdu, dpdv, None);
        si
    }

    fn perturb(
        &self,
        si: &mut Interaction,
        ray: &Ray,
        dpdu: Vec3A,
        dpdv: Vec3A,
        tangent: Option<Vec4>,
    ) {
        let m = &self.materials[si.material as usize];
        let mut h = HitGeometry {
            ng: si.ng,
            ns: si.ns,
            dpdu,
            dpdv,
            uv: si.uv,
            wi: -ray.d.normalize(),
            bitangent_sign: 1.0,
        };
        if let Some(t) = tangent {
            h = h.with_tangent(t);
        }
        si.ns = perturbed_normal(m.normal_map, m.bump, &h, &self.textures);
    }
}

/// dp/du and dp/dv of a triangle: from its texture coordinates where given and not
/// degenerate (an arbitrary basis around `n` where degenerate), else of its barycentric
/// parametrization (edges p1 − p0 and p2 − p0), as Mitsuba's meshes.
pub(crate) fn triangle_partials(
    tri: &Triangle,
    uvs: Option<[Vec2; 3]>,
    n: Vec3A,
) -> (Vec3A, Vec3A) {
    let (e1, e2) = (tri.p1 - tri.p0, tri.p2 - tri.p0);
    let Some([t0, t1, t2]) = uvs else {
        return (e1, e2);
    };
    let (d0, d1) = (t1 - t0, t2 - t0);
    let det = d0.x * d1.y - d0.y * d1.x;
    if det == 0.0 {
        let f = crate::geometry::Frame::from_normal(n);
        return (f.s, f.t);
    }
    let inv = 1.0 / det;
    ((e1 * d1.y - e2 * d0.y) * inv, (e2 * d0.x - e1 * d1.x) * inv)
}

/// dp/du and dp/dv of a sphere of radius `r` at unit normal `n`, for u = φ/2π and v = θ/π.
pub(crate) fn sphere_partials(n: Vec3A, r: f32) -> (Vec3A, Vec3A) {
    let dpdu = Vec3A::new(-n.y, n.x, 0.0) * (TAU * r);
    let rd = (n.x * n.x + n.y * n.y).sqrt();
    let dpdv = if rd == 0.0 {
        Vec3A::X // the poles (Mitsuba's choice)
    } else {
        Vec3A::new(n.z * n.x / rd, n.z * n.y / rd, -rd)
    };
    (dpdu, dpdv * (PI * r))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_partials_from_uvs_and_barycentrics() {
        let tri = Triangle::new(
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 4.0, 0.0),
        );
        // u along x over 2 units, v along y over 4: dp/du = (2, 0, 0), dp/dv = (0, 4, 0).
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let (du, dv) = triangle_partials(&tri, Some(uvs), Vec3A::Z);
        assert_eq!(
            (du, dv),
            (Vec3A::new(2.0, 0.0, 0.0), Vec3A::new(0.0, 4.0, 0.0))
        );
        // Swapped coordinates swap the partials.
        let uvs = [Vec2::ZERO, Vec2::Y, Vec2::X];
        let (du, dv) = triangle_partials(&tri, Some(uvs), Vec3A::Z);
        assert_eq!(
            (du, dv),
            (Vec3A::new(0.0, 4.0, 0.0), Vec3A::new(2.0, 0.0, 0.0))
        );
        let (du, dv) = triangle_partials(&tri, None, Vec3A::Z);
        assert_eq!((du, dv), (tri.p1 - tri.p0, tri.p2 - tri.p0));
    }

    #[test]
    fn sphere_partials_match_finite_differences() {
        let r = 1.7;
        let point = |u: f32, v: f32| {
            let (phi, theta) = (u * TAU, v * PI);
            Vec3A::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ) * r
        };
        let (u, v, h) = (0.3f32, 0.4f32, 1e-3f32);
        let n = point(u, v) / r;
        let (du, dv) = sphere_partials(n, r);
        let fu = (point(u + h, v) - point(u - h, v)) / (2.0 * h);
        let fv = (point(u, v + h) - point(u, v - h)) / (2.0 * h);
        assert!((du - fu).length() < 1e-2 * fu.length(), "{du} vs {fu}");
        assert!((dv - fv).length() < 1e-2 * fv.length(), "{dv} vs {fv}");
    }
}
