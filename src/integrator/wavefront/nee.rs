//! Next-event estimation lane by lane, as `nee` computes it: one sample a vertex
//! ([`Wavefront::one_sample`]: `light_sample`; its shadow rays are left to the caller, which
//! pools them across groups of lanes), or n samples of the vertex's lattice
//! ([`Wavefront::samples`]: `any_lights`, each lane's shadow rays traced as its packets).
//! The light is sampled in the lanes where the scene has one planar light and asked of `Lights`
//! lane by lane otherwise ([`super::lights`]).

use super::bsdf::{flip_z, Microfacets};
use super::general::{lane, General};
use super::lights::Incident;
use super::simd::{F, M, U, V3};
use super::{Bits, LaneMask, Light, Wavefront};
use crate::accel::{RayPacket, PACKET};
use crate::geometry::ray::{offset_by, offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::Frame;
use crate::integrator::{Lattice, RayStats};
use crate::light::{planar_point, towards};
use crate::material::lambert;
use crate::material::sampling::cosine_hemisphere_pdf_lanes;
use crate::material::sampling::power_heuristic_lanes;
use crate::material::{rough_dielectric, TransportMode};
use crate::simd::{lanes_of, Float, Vector3};
use glam::Vec3A;

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
    pub rough: Option<&'a Microfacets<'a>>,
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
        n: F,
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
            power_heuristic_lanes(n * inc.pdf, bsdf_pdf),
        );
        let contribution = (f * inc.le).scale(mis / inc.pdf);
        (shadow, inc.o, inc.d, inc.t_max, contribution)
    }

    /// The light's contribution with `n` > 1 light samples a vertex at the non-delta
    /// vertices of lanes `lanes`, for the vertex's numbers `delta` (`any_lights`): sample j
    /// of each lane's lattice as [`Wavefront::one_sample`] computes it with the weight of n
    /// samples, the contributions of those whose shadow ray is clear summed in sample order
    /// and divided by n. The samples are computed sixteen lanes at a time, a batch of
    /// sixteen samples at once; each lane's shadow rays of a batch are traced as packets of
    /// one origin (`Scene::occluded_packet`: the BVH culls most of the scene for rays from
    /// one point towards a light, which brute force over sixteen origins cannot).
    #[inline(always)]
    pub(super) unsafe fn samples(
        &self,
        v: &Vertex,
        hits: &[Option<crate::scene::Interaction>; 16],
        lanes: M,
        delta: [F; 3],
        stats: &mut RayStats,
    ) -> V3 {
        let n = self.shadow_rays;
        let nf = F::splat(n as f32);
        // (No closures over lanes here: they would be compiled without the lanes' features.)
        let delta = [delta[0].to_array(), delta[1].to_array(), delta[2].to_array()];
        let lattice = Lattice::new(n);
        // Δ in fixed point, by axis and lane.
        let mut fixed = [[0u32; 16]; 3];
        for (a, f) in fixed.iter_mut().enumerate() {
            *f = delta[a].map(crate::integrator::nee::fixed);
        }
        let fixed = [U::load(&fixed[0]), U::load(&fixed[1]), U::load(&fixed[2])];
        let scale = F::splat(1.0 / 16_777_216.0);
        let mut sum = V3::zero();
        let mut first = 0;
        while first < n {
            let m = (n - first).min(PACKET as u32) as usize;
            // Per sample of the batch: the lanes that trace a shadow ray, and the rays
            // (by sample, axis and lane) and contributions.
            let mut shadow = [0 as Bits; PACKET];
            let mut rays = [[[[0f32; 16]; 3]; 2]; PACKET];
            let mut t_max = [[0f32; 16]; PACKET];
            let mut lit = [V3::zero(); PACKET];
            for s in 0..m {
                // Sample j's numbers, `Lattice::point` in the lanes.
                let j = first + s as u32;
                let u = if j == 0 {
                    [F::load(&delta[0]), F::load(&delta[1]), F::load(&delta[2])]
                } else {
                    let g = lattice.offsets(j);
                    let mut u = [F::zero(); 3];
                    for a in 0..3 {
                        u[a] = fixed[a].add(U::splat(g[a])).shr::<8>().to_f32() * scale;
                    }
                    u
                };
                let (sh, o, d, t, c) = self.one_sample(v, hits, lanes, u, nf);
                shadow[s] = sh.bits();
                o.store(&mut rays[s][0]);
                d.store(&mut rays[s][1]);
                t.store(&mut t_max[s]);
                lit[s] = c;
            }
            let clear = self.clear_by_lane(&shadow[..m], &rays[..m], &t_max[..m], stats);
            for s in 0..m {
                sum = V3::select(M::from_bits(clear[s]), sum + lit[s], sum);
            }
            first += m as u32;
        }
        sum.div(nf)
    }

    /// Which of the rays of a batch of samples (`shadow[s]`: the lanes that trace sample s's
    /// ray, `rays[s]` its origins and directions, `t_max[s]` how far they must be clear) are
    /// clear, by sample: each lane's rays in packets of the samples that share its origin.
    #[inline(always)]
    fn clear_by_lane(
        &self,
        shadow: &[Bits],
        rays: &[[[[f32; 16]; 3]; 2]],
        t_max: &[[f32; 16]],
        stats: &mut RayStats,
    ) -> [Bits; PACKET] {
        let mut clear = [0 as Bits; PACKET];
        let all = shadow.iter().fold(0, |a, &b| a | b);
        for l in lanes_of(u32::from(all)) {
            // This lane's samples with a shadow ray (bit s: sample s).
            let bit = |s: usize| (((shadow[s] >> l) & 1) as u32) << s;
            let mut left = (0..shadow.len()).fold(0u32, |a, s| a | bit(s));
            stats.shadow_rays += left.count_ones() as u64;
            let mut pk = RayPacket {
                o: Vec3A::ZERO,
                d: [[0.0; PACKET]; 3],
                t_max: [0.0; PACKET],
            };
            for s in lanes_of(left) {
                let d = &rays[s][1];
                (pk.d[0][s], pk.d[1][s], pk.d[2][s]) = (d[0][l], d[1][l], d[2][l]);
                pk.t_max[s] = t_max[s][l];
            }
            while left != 0 {
                // The samples whose rays leave from the first one's origin.
                pk.o = lane(&rays[left.trailing_zeros() as usize][0], l);
                let from = |s: usize| ((lane(&rays[s][0], l) == pk.o) as u32) << s;
                let same = lanes_of(left).fold(0, |a, s| a | from(s));
                let seen = same & !self.scene.occluded_packet(&pk, same);
                for s in lanes_of(seen) {
                    clear[s] |= 1 << l;
                }
                left &= !same;
            }
        }
        clear
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
        if let Some(c) = &r.coated {
            let (wo, wi) = (flip_z(v.wo, v.side), flip_z(wil, v.side));
            let (cf, pdf) = c.eval_pdf_lanes(wo, wi);
            f = V3::select(r.plastic, cf, f);
            bsdf_pdf = F::select(r.plastic, pdf, bsdf_pdf);
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
