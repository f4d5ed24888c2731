//! Next-event estimation lane by lane: one sample a vertex as `nee::one_sample` computes it
//! (its shadow rays are left to the caller, which pools them across groups of lanes), the
//! light sampled in the lanes where the scene has one planar light and asked of `Lights`
//! lane by lane otherwise ([`super::lights`]); or, with one planar light, n samples as the
//! planar batch does (`nee::planar::planar::<true>`, Lambertian vertices), the samples
//! computed sixteen lanes at a time and each lane's shadow rays traced as its own packets.

use super::bsdf::{flip_z, Microfacets};
use super::general::{lane, General};
use super::lights::Incident;
use super::simd::{F, M, V3};
use super::{Bits, LaneMask, Light, Wavefront};
use crate::accel::{RayPacket, PACKET};
use crate::geometry::ray::{offset_by, offset_push, offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::Frame;
use crate::integrator::nee::{lambert_weight, shadow_dir, wrap};
use crate::integrator::{sample_lights_at, RayStats};
use crate::light::{planar_point, towards};
use crate::material::lambert;
use crate::material::{rough_dielectric, TransportMode};
use crate::material::sampling::cosine_hemisphere_pdf_lanes;
use crate::material::sampling::power_heuristic_lanes;
use crate::simd::{Float, Vector3};
use glam::Vec3A;
use std::f32::consts::{FRAC_1_PI, PI};

/// A vertex of each lane: the point, its error bound and geometric normal, the frame, the
/// direction to the last vertex (local), its material's colour, its rough materials (where
/// a lane has one), and the side of the surface the path is on
/// (`Material::orient`: `oriented` lanes, `side` ±1).
pub struct Vertex<'a> {
    pub p: V3,
    pub p_err: V3,
    pub ng: V3,
    pub frame: Frame<V3>,
    pub wo: V3,
    pub albedo: V3,
    pub rough: Option<&'a Microfacets>,
    pub general: Option<&'a General<'a>>,
    pub oriented: M,
    pub side: F,
}

impl Wavefront<'_> {
    /// One light sample at the non-delta vertices of lanes `lanes` (`one_sample`:
    /// `Lights::sample`, `Material::eval_pdf`, the shadow ray of `spawn_ray_to_light`, the
    /// power heuristic), `u` its numbers, `hits` the lanes' hits where the lanes read the
    /// scene's ([`super::Trace::Scene`]): the lanes whose sample needs a shadow ray (the
    /// others contribute nothing), the rays' origins, directions and how far they must be
    /// clear, and the samples' contributions where the ray is clear.
    #[inline(always)]
    pub(super) unsafe fn one_sample(
        &self,
        v: &Vertex,
        hits: &[Option<crate::scene::Interaction>; 16],
        lanes: M,
        u: [F; 3],
    ) -> (M, V3, V3, F, V3) {
        let one = F::splat(1.0);
        let inc = match &self.light {
            Some(lt) => planar_sample(lt, v, u),
            None => self.light_samples(hits, lanes, u),
        };
        // `Material::eval_pdf` on the side the path is on: `Lambert::eval` and `pdf`, or the
        // rough conductor's; the rough dielectric's and the general materials' from either
        // side.
        let wil = v.frame.to_local(inc.wi);
        let (f, bsdf_pdf) = eval_pdf(v, wil);
        let f = f.scale(wil.z.abs());
        let shadow = lanes & inc.ok & !f.is_zero();
        let mis = F::select(
            inc.delta,
            one,
            power_heuristic_lanes(one * inc.pdf, bsdf_pdf),
        );
        let contribution = (f * inc.le).scale(mis / inc.pdf);
        (shadow, inc.o, inc.d, inc.t_max, contribution)
    }

    /// The light's contribution at the Lambertian vertices of lanes `lanes` with `n` > 1
    /// light samples each, as the planar batch computes it (`planar_in::<_, true>`): the
    /// samples of a rank-1 lattice shifted by `u`, the power heuristic's weight over the
    /// light pdf in its rearranged form, the weights summed in four running sums by sample
    /// index mod 4. Zero in lanes not `oriented` (`sample_lights` returns there before the
    /// batch) and in lanes not in `lanes`.
    ///
    /// The samples are computed sixteen lanes at a time, sample by sample; the shadow rays
    /// are traced lane by lane, each lane's as the packets of one origin that the batch
    /// traces (`Scene::occluded_packet`: the BVH culls most of the scene for rays that
    /// share an origin, which brute force over sixteen origins cannot).
    #[inline(always)]
    pub(super) unsafe fn batch(
        &self,
        v: &Vertex,
        lanes: M,
        [du, dv, _]: [F; 3],
        stats: &mut RayStats,
    ) -> V3 {
        let lanes = lanes & v.oriented;
        if !lanes.any() {
            return V3::zero();
        }
        let zero = F::zero();
        let Some(lt) = &self.light else {
            return V3::zero();
        };
        let n = self.shadow_rays;
        let nf = n as f32;
        let (a, b, c) = (V3::splat(lt.a), V3::splat(lt.b), V3::splat(lt.c));
        let (nl, off) = (V3::splat(lt.normal), V3::splat(lt.offset));
        let ns = v.frame.n;
        // The two possible origins, above and below the surface (`offset_ray_origin`).
        let push = offset_push(v.ng, v.p_err);
        let above = offset_by(v.p, push, v.ng, v.ng);
        let below = offset_by(v.p, push, v.ng, -v.ng);
        let (mut above_a, mut below_a) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
        above.store(&mut above_a);
        below.store(&mut below_a);
        let (inv_n, neg_area) = (F::splat(1.0 / nf), F::splat(-lt.area));
        let k = F::splat(nf * nf * PI * PI);
        let mut acc = [zero; 4];
        let mut first = 0;
        while first < n {
            let m = (n - first).min(PACKET as u32) as usize;
            // Per sample of this batch: its weight, the lanes it counts in (`good`) and
            // whose ray leaves below the surface, and the rays' directions (by sample,
            // axis and lane).
            let mut weight = [zero; PACKET];
            let (mut good, mut under) = ([0 as Bits; PACKET], [0 as Bits; PACKET]);
            let mut dirs = [[[0f32; 16]; 3]; PACKET];
            for s in 0..m {
                let j = first + s as u32;
                // Sample j of the lattice shifted by Δ, wrapped into [0, 1).
                let u = wrap(du + F::splat(j as f32) * inv_n);
                let w = wrap(dv + F::splat(crate::integrator::lattice_v(j)));
                let q = planar_point(a, b, c, lt.triangle, u, w);
                let d = q - v.p;
                let dist2 = d.dot(d);
                let down = v.ng.dot(d).lt(zero);
                let (faces, w) = lambert_weight(d, dist2, (nl, neg_area), (ns, v.side), k);
                under[s] = down.bits();
                good[s] = (lanes & dist2.gt(zero) & faces).bits();
                weight[s] = w;
                shadow_dir(q, (nl, off), down, (above, below)).store(&mut dirs[s]);
            }
            // Each lane's shadow rays, in up to two packets by the side they leave from.
            let mut visible = [0 as Bits; PACKET];
            let mut ll = lanes.bits();
            while ll != 0 {
                let lane = ll.trailing_zeros() as usize;
                ll &= ll - 1;
                let bit = |x: &[Bits; PACKET]| {
                    (0..m).fold(0u32, |acc, s| acc | (((x[s] >> lane) & 1) as u32) << s)
                };
                let (ok, down) = (bit(&good), bit(&under));
                let mut pk = RayPacket {
                    o: Vec3A::ZERO,
                    d: [[0.0; PACKET]; 3],
                    t_max: [1.0 - SHADOW_EPSILON; PACKET],
                };
                for (s, dir) in dirs.iter().enumerate().take(m) {
                    for (row, axis) in pk.d.iter_mut().zip(dir) {
                        row[s] = axis[lane];
                    }
                }
                let mut seen = 0;
                for (origin, active) in [(&above_a, ok & !down), (&below_a, ok & down)] {
                    if active != 0 {
                        pk.o = Vec3A::new(origin[0][lane], origin[1][lane], origin[2][lane]);
                        stats.shadow_rays += active.count_ones() as u64;
                        seen |= active & !self.scene.occluded_packet(&pk, active);
                    }
                }
                for (s, vis) in visible.iter_mut().enumerate().take(m) {
                    *vis |= (((seen >> s) & 1) as Bits) << lane;
                }
            }
            for s in 0..m {
                let r = &mut acc[(first as usize + s) % 4];
                *r = *r + F::select(M::from_bits(visible[s]), weight[s], zero);
            }
            first += m as u32;
        }
        let sum = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        let e = (v.albedo.scale(F::splat(FRAC_1_PI)) * V3::splat(lt.radiance)).scale(sum);
        V3::select(lanes, e.div(F::splat(nf)), V3::zero())
    }
}

impl Wavefront<'_> {
    /// The light's contribution with `n` > 1 light samples a vertex at the vertices of
    /// lanes `lanes` (the hits in `hits`: [`super::Trace::Scene`]) that the planar batch does
    /// not take (other lights, other materials): each lane's `sample_lights_at`, the path
    /// tracer's own next-event estimation for the lane's numbers `[du, dv, dw]`, its shadow
    /// rays traced as it traces them. Zero in the other lanes.
    #[inline(always)]
    pub(super) fn several(
        &self,
        v: &Vertex,
        hits: &[Option<crate::scene::Interaction>; 16],
        lanes: M,
        [du, dv, dw]: [F; 3],
        stats: &mut RayStats,
    ) -> V3 {
        let (du, dv, dw) = (du.to_array(), dv.to_array(), dw.to_array());
        let wo = v.wo.to_arrays();
        let mut e = [[0f32; 16]; 3];
        for l in crate::simd::lanes_of(u32::from(lanes.bits())) {
            let si = hits[l].as_ref().expect("a hit where a light is sampled");
            // (`Scene::material_at`, as the path tracer finds it, where the lane has not
            // already found it.)
            let at;
            let material = match v.general.and_then(|g| g.material(l)) {
                Some(m) => m,
                None => {
                    at = self.scene.material_at(si);
                    &at
                }
            };
            let frame = Frame::from_normal(si.ns);
            let delta = [du[l], dv[l], dw[l]];
            let n = self.shadow_rays;
            let c = sample_lights_at(self.scene, si, &frame, lane(&wo, l), material, n, delta, stats);
            (e[0][l], e[1][l], e[2][l]) = (c.x, c.y, c.z);
        }
        V3::load(&e)
    }
}

/// A sample of the one planar light `lt` at each lane's vertex (`AreaLight::sample_point`
/// and `Lights::sample`, which gives the one light probability one), for the numbers `[ux,
/// uy, _]`, and its shadow ray (`spawn_ray_to`, both ends pushed off their surfaces).
#[inline(always)]
fn planar_sample(lt: &Light, v: &Vertex, [ux, uy, _]: [F; 3]) -> Incident {
    let (zero, one) = (F::zero(), F::splat(1.0));
    let (la, lb, lc) = (V3::splat(lt.a), V3::splat(lt.b), V3::splat(lt.c));
    let pl = planar_point(la, lb, lc, lt.triangle, ux, uy);
    let ln = V3::splat(lt.normal);
    let (dl, dist2, wi, cos_l, pdf) = towards(v.p, pl, ln, one, F::splat(lt.area));
    let so = offset_ray_origin(v.p, v.p_err, v.ng, dl);
    let target = offset_by(pl, V3::splat(lt.offset), ln, so - pl);
    Incident {
        ok: !dist2.eq(zero) & !cos_l.le(zero),
        wi,
        le: V3::splat(lt.radiance),
        pdf,
        delta: M::none(),
        o: so,
        d: target - so,
        t_max: F::splat(1.0 - SHADOW_EPSILON),
    }
}

/// f(wo, wi) and the pdf of sampling `wil` (local) at each lane's vertex
/// (`Material::eval_pdf`): zero where the vertex is not `oriented`.
#[inline(always)]
fn eval_pdf(v: &Vertex, wil: V3) -> (V3, F) {
    let wz = wil.z * v.side;
    let mut f = lambert::eval(v.albedo, wz);
    let mut bsdf_pdf = cosine_hemisphere_pdf_lanes(wz);
    if let Some(r) = v.rough {
        if r.metal.any() {
            let (wo, wi) = (flip_z(v.wo, v.side), flip_z(wil, v.side));
            f = V3::select(r.metal, r.conductor.eval_lanes(wo, wi), f);
            bsdf_pdf = F::select(r.metal, r.conductor.pdf_lanes(wo, wi), bsdf_pdf);
        }
        if r.glass.any() {
            let distr = &r.conductor.distr;
            let mode = TransportMode::Radiance;
            let (g, _) = rough_dielectric::eval_lanes(distr, r.eta, v.wo, wil, mode);
            let pdf = rough_dielectric::pdf_lanes(distr, r.eta, v.wo, wil);
            f = V3::select(r.glass, V3 { x: g, y: g, z: g }, f);
            bsdf_pdf = F::select(r.glass, pdf, bsdf_pdf);
        }
    }
    if let Some(g) = v.general {
        let (gf, pdf) = g.eval_pdf(v.wo, wil);
        f = V3::select(g.glossy, gf, f);
        bsdf_pdf = F::select(g.glossy, pdf, bsdf_pdf);
    }
    (
        V3::select(v.oriented, f, V3::zero()),
        F::select(v.oriented, bsdf_pdf, F::zero()),
    )
}
