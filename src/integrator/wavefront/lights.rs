//! Lights other than one planar light (several lights, spheres, meshes, textured radiance,
//! point, spot and directional lights, environments): what the path tracer asks of
//! `Lights` at a vertex, asked for each lane, a lane at a time, with the path tracer's own
//! functions (`Lights::sample` and `Interaction::spawn_ray_to_light` for the light sample,
//! `emitted` on emitter hits, `escaped` for rays that leave the scene). The lanes keep the
//! rest (the BSDF's value and pdf, MIS, the shadow rays, which they trace together), so
//! these lanes compute the path tracer's bits by construction.

use super::general::lane;
use super::simd::{F, M, V3};
use super::{Bits, LaneMask, Wavefront};
use crate::integrator::{emitted, escaped};
use crate::scene::Interaction;
use crate::simd::lanes_of;
use glam::{Vec2, Vec3A};

/// Each lane's previous vertex for MIS on what its ray finds: the lanes that got here by a
/// non-delta BSDF sample, the vertex and that sample's pdf.
pub struct Prev {
    pub lanes: M,
    pub p: V3,
    pub pdf: F,
}

impl Prev {
    /// `PathState::prev` of lane `l`.
    #[inline(always)]
    fn of(&self, p: &[[f32; 16]; 3], pdf: &[f32; 16], l: usize) -> Option<(Vec3A, f32)> {
        (self.lanes.bits() & 1 << l != 0).then(|| (lane(p, l), pdf[l]))
    }
}

/// The lanes' light samples: where there is one, its direction (world), radiance, pdf
/// (solid angle, with the light's choice), whether the light is a delta, and its shadow
/// ray (origin, direction, clear up to `t_max`).
pub struct Incident {
    pub ok: M,
    pub wi: V3,
    pub le: V3,
    pub pdf: F,
    pub delta: M,
    pub o: V3,
    pub d: V3,
    pub t_max: F,
}

impl Wavefront<'_> {
    /// What rays `d` of lanes `lanes` that leave the scene see (`escaped`).
    #[inline(always)]
    pub(super) fn escaped_lanes(&self, d: V3, lanes: M, prev: &Prev) -> V3 {
        let (d, pp, ppdf) = (d.to_arrays(), prev.p.to_arrays(), prev.pdf.to_array());
        let mut e = [[0f32; 16]; 3];
        for l in lanes_of(u32::from(lanes.bits())) {
            let le = escaped(self.scene, lane(&d, l), prev.of(&pp, &ppdf, l), self.shadow_rays);
            (e[0][l], e[1][l], e[2][l]) = (le.x, le.y, le.z);
        }
        V3::load(&e)
    }

    /// The emission seen at the hits of lanes `lanes` (the caller's emitters) along their
    /// rays `d` (`emitted`, which itself returns zero at a surface that emits nothing).
    #[inline(always)]
    pub(super) fn emitted_lanes(
        &self,
        hits: &[Option<Interaction>; 16],
        d: V3,
        lanes: M,
        prev: &Prev,
    ) -> V3 {
        let (d, pp, ppdf) = (d.to_arrays(), prev.p.to_arrays(), prev.pdf.to_array());
        let mut e = [[0f32; 16]; 3];
        for l in lanes_of(u32::from(lanes.bits())) {
            let Some(si) = hits[l].as_ref() else {
                continue;
            };
            let le = emitted(self.scene, si, lane(&d, l), prev.of(&pp, &ppdf, l), self.shadow_rays);
            (e[0][l], e[1][l], e[2][l]) = (le.x, le.y, le.z);
        }
        V3::load(&e)
    }

    /// A light sample at the hits of lanes `lanes` for the numbers `[ux, uy, u_sel]`
    /// (`Lights::sample`, `Interaction::spawn_ray_to_light`).
    #[inline(always)]
    pub(super) fn light_samples(
        &self,
        hits: &[Option<Interaction>; 16],
        lanes: M,
        [ux, uy, u_sel]: [F; 3],
    ) -> Incident {
        let (ux, uy, u_sel) = (ux.to_array(), uy.to_array(), u_sel.to_array());
        let mut v = [[[0f32; 16]; 3]; 4];
        let [wi, le, o, d] = &mut v;
        let (mut pdf, mut t_max) = ([1f32; 16], [0f32; 16]);
        let (mut ok, mut delta): (Bits, Bits) = (0, 0);
        for l in lanes_of(u32::from(lanes.bits())) {
            let si = hits[l].as_ref().expect("a hit where a light is sampled");
            let u = Vec2::new(ux[l], uy[l]);
            let Some(ls) = self.scene.lights.sample(si.p, u_sel[l], u) else {
                continue;
            };
            let (ray, t) = si.spawn_ray_to_light(&ls);
            ok |= 1 << l;
            delta |= (ls.delta as Bits) << l;
            for (a, x) in [(&mut *wi, ls.wi), (&mut *le, Vec3A::from(ls.le)), (&mut *o, ray.o), (&mut *d, ray.d)] {
                (a[0][l], a[1][l], a[2][l]) = (x.x, x.y, x.z);
            }
            (pdf[l], t_max[l]) = (ls.pdf, t);
        }
        Incident {
            ok: M::from_bits(ok),
            wi: V3::load(wi),
            le: V3::load(le),
            pdf: F::load(&pdf),
            delta: M::from_bits(delta),
            o: V3::load(o),
            d: V3::load(d),
            t_max: F::load(&t_max),
        }
    }
}
