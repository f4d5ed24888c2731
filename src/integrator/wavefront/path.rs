//! One step of sixteen paths: a pass of `path::li`'s loop for each lane (the hit, its
//! emission, the light sample, the BSDF sample, the roulette), and the samples of the paths
//! that end, to the film.

use super::bsdf;
use super::nee::Vertex;
use super::rng::LaneSampler;
use super::simd::{F, M, U, V3};
use super::{Bits, LaneMask, Lanes, Trace, Wavefront, POOL};
use crate::accel::flat::{Flat, Hits};
use crate::scene::{Interaction, META_MATERIAL};
use super::bsdf::Microfacets;
use super::general::{At, General};
use super::lights::Prev;
use super::{BECKMANN, BLACK, EMITTER, GENERAL, GLASS, KIND, LAMBERT, MIRROR, ROUGH, ROUGH_GLASS};
use super::ROUGH_PLASTIC;
use super::TWO_SIDED;
use crate::material::microfacet::Either;
use crate::material::rough_conductor::RoughConductor;
use crate::material::rough_plastic::Coated;
use crate::film::PixelSums;
use crate::geometry::ray::offset_ray_origin;
use crate::geometry::sphere::surface_point;
use crate::geometry::triangle::barycentric_point;
use crate::geometry::Frame;
use crate::light::area_pdf;
use crate::material::sampling::power_heuristic_lanes;
use crate::simd::{lanes_of, Float, Vector3};
use crate::render::{RenderStats, TilePixel};

/// What a step reads of the lanes' hits: the lanes that hit something, and at their hits
/// the point, its error bound, the unit geometric and shading normals, and the material's
/// flags (with `EMITTER` where the primitive emits), colour and η, and with
/// [`Trace::Lanes`] the primitive (for [`Wavefront::conductor`]).
struct Surface {
    hit: M,
    p: V3,
    p_err: V3,
    ng: V3,
    ns: V3,
    flags: U,
    colour: V3,
    eta: F,
    prim: U,
}

impl Wavefront<'_> {
    /// The lanes' hits by brute force ([`Trace::Lanes`]).
    ///
    /// # Safety
    /// The CPU must have the backend's features (`Flat::closest_lanes`).
    #[inline(always)]
    unsafe fn surface_lanes(&self, o: V3, d: V3, active: M) -> Surface {
        let scene = self.scene;
        let flat = self.flat();
        let h = flat.closest_lanes(o, d, active, |ray, p, t| scene.hit(ray, p, t));
        let prim = U::of_f32(h.prim);
        let (p, p_err, ng) = self.hit_point(flat, &h, prim, o, d);
        Surface {
            hit: h.hit,
            p,
            p_err,
            ng,
            ns: ng,
            flags: U::lookup64(&self.flags, prim),
            colour: V3::lookup64(&self.colour, prim),
            eta: F::lookup64(&self.eta, prim),
            prim,
        }
    }

    /// The scene's brute-force set, which [`Trace::Lanes`] traces.
    #[inline(always)]
    fn flat(&self) -> &Flat {
        self.flat.expect("the lanes trace only scenes traced by brute force")
    }

    /// The rough conductors at the lanes' hits `sf` (`hits` with [`Trace::Scene`]), read
    /// only where a lane has one or a rough dielectric (whose microfacets they hold too): by
    /// primitive from the tables, or from each hit's material. A lane's reflectance is its
    /// colour; lanes without one hold values no lane reads.
    #[inline(always)]
    fn conductor(
        &self,
        sf: &Surface,
        hits: &[Option<Interaction>; 16],
    ) -> RoughConductor<Either<F>, V3> {
        let (alpha_u, alpha_v, eta, k) = match self.trace {
            Trace::Lanes => {
                let t = &self.rough;
                (
                    F::lookup64(&t.alpha[0], sf.prim),
                    F::lookup64(&t.alpha[1], sf.prim),
                    V3::lookup64(&t.eta, sf.prim),
                    V3::lookup64(&t.k, sf.prim),
                )
            }
            Trace::Scene => {
                let (mut alpha, mut eta, mut k) = ([[0f32; 16]; 2], [[0f32; 16]; 3], [[0f32; 16]; 3]);
                let mut m = sf.hit.bits();
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let Some(si) = &hits[l] else {
                        continue;
                    };
                    let r = &self.materials[si.material as usize].rough;
                    (alpha[0][l], alpha[1][l]) = (r.alpha[0], r.alpha[1]);
                    for a in 0..3 {
                        (eta[a][l], k[a][l]) = (r.eta[a], r.k[a]);
                    }
                }
                (F::load(&alpha[0]), F::load(&alpha[1]), V3::load(&eta), V3::load(&k))
            }
        };
        RoughConductor {
            distr: Either {
                beckmann: sf.flags.any(BECKMANN),
                alpha_u,
                alpha_v,
            },
            eta,
            k,
            specular_reflectance: sf.colour,
        }
    }

    /// The rough plastics at the hits of lanes `lanes` of `sf` (`hits` with [`Trace::Scene`]),
    /// of distributions `distr` ([`Wavefront::conductor`]'s): each lane's coating read from
    /// its material's. Lanes without one hold the first table and values no lane reads.
    #[inline(always)]
    fn coated(
        &self,
        sf: &Surface,
        hits: &[Option<Interaction>; 16],
        lanes: M,
        distr: Either<F>,
    ) -> Coated<'_, Either<F>, V3> {
        let mut prims = [0u32; 16];
        sf.prim.store(&mut prims);
        let (mut specular, mut v) = ([[0f32; 16]; 3], [[0f32; 16]; 4]);
        let mut nonlinear: Bits = 0;
        for l in lanes_of(u32::from(lanes.bits())) {
            let index = match (self.trace, &hits[l]) {
                (Trace::Scene, Some(si)) => si.material as usize,
                (Trace::Lanes, _) => (self.scene.meta[prims[l] as usize] & META_MATERIAL) as usize,
                // (Every lane with a material has a hit.)
                (Trace::Scene, None) => continue,
            };
            let c = &self.materials[index].coat;
            for (s, &x) in specular.iter_mut().zip(&c.specular) {
                s[l] = x;
            }
            let values = [c.weight, c.inv_eta2, c.first, c.internal_reflectance];
            for (v, x) in v.iter_mut().zip(values) {
                v[l] = x;
            }
            nonlinear |= (c.nonlinear as Bits) << l;
        }
        Coated {
            distr,
            eta: sf.eta,
            diffuse_reflectance: sf.colour,
            specular_reflectance: V3::load(&specular),
            nonlinear: M::from_bits(nonlinear),
            specular_sampling_weight: F::load(&v[0]),
            inv_eta2: F::load(&v[1]),
            transmittance: &self.coatings,
            first: F::load(&v[2]),
            internal_reflectance: F::load(&v[3]),
        }
    }

    /// The `GENERAL` materials at the hits of lanes `lanes` ([`General`]), if any lane has
    /// one: by primitive ([`Trace::Lanes`]: constant materials) or each hit's material.
    #[inline(always)]
    fn general<'s>(
        &'s self,
        sf: &Surface,
        hits: &[Option<Interaction>; 16],
        lanes: M,
    ) -> Option<General<'s>> {
        if !lanes.any() {
            return None;
        }
        let mut prims = [0u32; 16];
        sf.prim.store(&mut prims);
        let scene = self.scene;
        Some(General::new(lanes, |l| {
            let si = match self.trace {
                Trace::Lanes => None,
                Trace::Scene => hits[l].as_ref(),
            };
            let index = match si {
                Some(si) => si.material as usize,
                None => (scene.meta[prims[l] as usize] & META_MATERIAL) as usize,
            };
            match (&self.resolved[index], si) {
                (Some(m), _) => At::Scene(m),
                (None, Some(si)) => At::Hit(scene.material_at(si)),
                (None, None) => unreachable!("brute force takes constant materials only"),
            }
        }))
    }

    /// The lanes' hits by the scene's own queries ([`Trace::Scene`]): the values of each
    /// active lane's interaction in `hits` (`Scene::intersect`'s, as the path tracer's).
    #[inline(always)]
    fn surface_scene(&self, hits: &[Option<Interaction>; 16], active: Bits) -> Surface {
        let mut v = [[[0f32; 16]; 3]; 5];
        let [p, p_err, ng, ns, colour] = &mut v;
        let (mut flags, mut eta) = ([0u32; 16], [1f32; 16]);
        let mut hit: Bits = 0;
        let mut m = active;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let Some(si) = &hits[l] else {
                continue;
            };
            hit |= 1 << l;
            let sh = &self.materials[si.material as usize];
            let material = &self.scene.materials[si.material as usize];
            let c = sh.colour_at(material, &self.scene.textures, si.uv);
            // (Arrays, not `si.p[a]`: where the loop stays a loop, a vector's index is a
            // match.)
            let [sp, se, sg, sn] = [si.p, si.p_err, si.ng, si.ns].map(|v| v.to_array());
            for a in 0..3 {
                (p[a][l], p_err[a][l]) = (sp[a], se[a]);
                (ng[a][l], ns[a][l]) = (sg[a], sn[a]);
                colour[a][l] = c[a];
            }
            let emits = si.light != crate::scene::NO_LIGHT;
            flags[l] = sh.flags | if emits { EMITTER } else { 0 };
            eta[l] = sh.eta;
        }
        Surface {
            hit: M::from_bits(hit),
            p: V3::load(p),
            p_err: V3::load(p_err),
            ng: V3::load(ng),
            ns: V3::load(ns),
            flags: U::load(&flags),
            colour: V3::load(colour),
            eta: F::load(&eta),
            prim: U::splat(0),
        }
    }

    /// The hit points of `h` (primitives `prim`) in `flat`: `Scene::interaction`'s point,
    /// error bound and unit normal, for a triangle (`Triangle::point`) or a sphere
    /// (`Sphere::surface_point`).
    #[inline(always)]
    fn hit_point(&self, flat: &Flat, h: &Hits<F>, prim: U, o: V3, d: V3) -> (V3, V3, V3) {
        let (p0, p1, p2) = (
            V3::lookup64(&self.p0, prim),
            V3::lookup64(&self.p1, prim),
            V3::lookup64(&self.p2, prim),
        );
        let (tp, t_err) = barycentric_point(p0, p1, p2, h.u, h.v);
        let tn = V3::lookup64(&self.ng, prim);
        if !flat.has_spheres() {
            return (tp, t_err, tn);
        }
        // Spheres: the hit reprojected onto the surface (p0 holds the centre).
        let r = F::lookup64(&self.radius, prim);
        let (sp, sn, s_err) = surface_point(p0, r, o + d.scale(h.t));
        (
            V3::select(h.sphere, sp, tp),
            V3::select(h.sphere, s_err, t_err),
            V3::select(h.sphere, sn, tn),
        )
    }

    // (The target features are repeated so that the closures inside get them too.)
    lanes_fn! {
    /// The first half of a step of every active path of a group: a vertex, as one pass of
    /// `path::li`'s loop, but for the one shadow ray of its light sample, which is left in
    /// `st.shadow` for [`Self::shadows`] to trace with the other groups' (several light
    /// samples a vertex are traced here, each lane's as packets), and the samples of the
    /// paths that end, which [`Self::back`] adds to the film once the shadow rays are in.
    #[inline]
    pub(super) unsafe fn front<S: LaneSampler>(&self, st: &mut Lanes<S>, stats: &mut RenderStats) {
        let bits = st.active;
        let active = M::from_bits(bits);
        let (zero, one) = (F::zero(), F::splat(1.0));
        let o = V3::load(&st.o);
        let d = V3::load(&st.d);
        let mut beta = V3::load(&st.beta);
        let mut l = V3::load(&st.l);
        let mut eta2 = F::load(&st.eta2);
        let depth = U::load(&st.depth);
        stats.rays.rays += bits.count_ones() as u64;
        let sf = match self.trace {
            Trace::Lanes => unsafe { self.surface_lanes(o, d, active) },
            Trace::Scene => self.surface_scene(&st.hits, bits),
        };
        let hidden = if self.hide_emitters {
            depth.eq(U::splat(0))
        } else {
            M::none()
        };
        let prev = Prev {
            lanes: M::from_bits(st.has_prev),
            p: V3::load(&st.prev_p),
            pdf: F::load(&st.prev_pdf),
        };
        // A ray that leaves the scene: what the environment lights send back along it
        // (`escaped`; β·0 without one, which is not nothing where β is not finite).
        let miss = active & !sf.hit;
        let env = match self.light {
            Some(_) => V3::zero(),
            None => self.escaped_lanes(d, miss & !hidden, &prev),
        };
        l = V3::select(miss & !hidden, l + beta * env, l);
        let mut done = miss;
        let (hit, p, p_err, ng, flags) = (sf.hit, sf.p, sf.p_err, sf.ng, sf.flags);
        let kind = |k: u32| hit & flags.masked_eq(KIND, k);

        // Emission (`emitted`), weighted against light sampling where the path got here by
        // a non-specular BSDF sample.
        let nd = -d;
        let e = match &self.light {
            Some(lt) => {
                let emitter = hit & flags.any(EMITTER);
                let le = V3::select(
                    emitter & ng.dot(nd).gt(zero),
                    V3::splat(lt.radiance),
                    V3::zero(),
                );
                let light_pdf = area_pdf(prev.p, p, ng, F::splat(lt.pmf), F::splat(lt.area));
                let rays = F::splat(self.shadow_rays as f32);
                let mis = power_heuristic_lanes(prev.pdf, rays * light_pdf);
                V3::select(emitter & prev.lanes, le.scale(mis), le)
            }
            None => self.emitted_lanes(&st.hits, d, hit & flags.any(EMITTER) & !hidden, &prev),
        };
        l = V3::select(hit & !hidden, l + beta * e, l);

        // The path's length, and black bodies.
        let last = depth.add(U::splat(1)).ge(U::splat(self.max_depth));
        let mut cont = hit & !last & !kind(BLACK);
        let general = self.general(&sf, &st.hits, cont & kind(GENERAL));
        if let Some(g) = &general {
            cont &= !kind(GENERAL) | g.lanes;
        }
        done |= hit & !cont;

        // The shading frame and `Material::orient`: the side the BSDF is seen from (glass:
        // both), none for a one-sided material seen from behind.
        let frame = Frame::from_normal(sf.ns);
        let wo = frame.to_local(nd);
        let (lambert, mirror, glass) = (kind(LAMBERT), kind(MIRROR), kind(GLASS));
        let (metal, frosted, plastic) = (kind(ROUGH), kind(ROUGH_GLASS), kind(ROUGH_PLASTIC));
        let rough = if (metal | frosted | plastic).any() {
            let conductor = self.conductor(&sf, &st.hits);
            // (Not `then` and a closure: it would be compiled without the lanes' features.)
            let coated = if plastic.any() {
                Some(self.coated(&sf, &st.hits, plastic, conductor.distr))
            } else {
                None
            };
            Some(Microfacets {
                metal,
                glass: frosted,
                plastic,
                coated,
                conductor,
                eta: sf.eta,
            })
        } else {
            None
        };
        // (Both glasses are seen from either side; the general materials orient themselves.)
        let clear = glass | frosted;
        let front = wo.z.gt(zero);
        let own = general.as_ref().map_or(M::none(), |g| g.lanes);
        let oriented = clear | front | (wo.z.lt(zero) & flags.any(TWO_SIDED)) | own;
        let side = F::select(clear | front, one, F::splat(-1.0));
        let colour = sf.colour;

        // Next-event estimation at the non-specular vertices (Lambertian, rough, and general
        // materials with a non-delta lobe): with one light sample, its shadow ray and the
        // two values `l += β·lit` can add (β times the sample's contribution, or β·0 if it
        // is blocked) wait for `shadows`.
        let non_delta = lambert | metal | frosted | plastic;
        let non_delta = non_delta | general.as_ref().map_or(M::none(), |g| g.glossy);
        // (Without lights, `PathState::step` samples none and draws no numbers for them.)
        let nee = if self.scene.lights.is_empty() {
            M::none()
        } else {
            cont & non_delta
        };
        st.shadow.lanes = 0;
        st.shadow.nee = nee.bits();
        if nee.any() {
            let u = st.rng.next::<3>(nee);
            let v = Vertex {
                p,
                p_err,
                ng,
                frame,
                wo,
                albedo: colour,
                rough: rough.as_ref(),
                general: general.as_ref(),
                oriented,
                side,
            };
            if self.shadow_rays == 1 {
                let (lanes, o, d, t_max, contribution) = self.one_sample(&v, &st.hits, nee, u, one);
                stats.rays.shadow_rays += lanes.count() as u64;
                let sh = &mut st.shadow;
                sh.lanes = lanes.bits();
                o.store(&mut sh.o);
                d.store(&mut sh.d);
                t_max.store(&mut sh.t_max);
                (beta * contribution).store(&mut sh.lit);
                (beta * V3::zero()).store(&mut sh.dark);
            } else {
                let lit = self.samples(&v, &st.hits, nee, u, &mut stats.rays);
                l = V3::select(nee, l + beta * lit, l);
                st.shadow.nee = 0;
            }
        }

        // The BSDF sample (one request for the direction, the lobe and the roulette).
        let [ux, uy, u1, u_rr] = st.rng.next::<4>(cont);
        let eta = sf.eta;
        let bs = bsdf::sample(
            wo,
            [ux, uy, u1],
            colour,
            eta,
            (lambert, mirror, glass),
            rough.as_ref(),
            general.as_ref(),
            oriented,
            side,
        );
        let mut alive = cont & bs.ok;
        beta = V3::select(alive, beta * bs.weight, beta);
        eta2 = F::select(alive, eta2 * (bs.eta * bs.eta), eta2);
        // `Frame::to_world` and `spawn_ray`.
        let wi = frame.to_world(bs.wi);
        let no = offset_ray_origin(p, p_err, ng, wi);
        let depth = depth.add(U::splat(1));
        // Russian roulette.
        let (survives, rr_beta) = self.rr.play(beta, eta2, |s| depth.ge(U::splat(s)), u_rr);
        alive &= survives;
        beta = V3::select(alive, rr_beta, beta);
        alive &= !beta.is_zero();
        done |= cont & !alive;

        no.store(&mut st.o);
        wi.store(&mut st.d);
        beta.store(&mut st.beta);
        l.store(&mut st.l);
        eta2.store(&mut st.eta2);
        p.store(&mut st.prev_p);
        bs.pdf.store(&mut st.prev_pdf);
        depth.store(&mut st.depth);
        // After a specular bounce the next emitter hit takes no MIS weight.
        st.has_prev = (alive & bs.glossy).bits();
        st.active = alive.bits();
        st.done = done.bits();
    }
    }

    lanes_fn! {
    /// The second half of a group's step, once `shadows` has traced its shadow rays: the
    /// light samples' values added (`l += β·lit`, after the vertex's emission and before
    /// the next vertex's, as `path::li` adds them), and the samples of the paths that ended
    /// added to the film.
    #[inline]
    pub(super) unsafe fn back<S: LaneSampler>(
        &self,
        st: &mut Lanes<S>,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        let mut l = V3::load(&st.l);
        let sh = &mut st.shadow;
        if sh.nee != 0 {
            let lit = V3::select(
                M::from_bits(sh.lanes & !sh.blocked),
                V3::load(&sh.lit),
                V3::load(&sh.dark),
            );
            l = V3::select(M::from_bits(sh.nee), l + lit, l);
            l.store(&mut st.l);
            (sh.nee, sh.lanes) = (0, 0);
        }
        let done = st.done;
        if done == 0 {
            return;
        }
        let ls = [l.x.to_array(), l.y.to_array(), l.z.to_array()];
        let finite = l.is_finite().bits();
        let mut m = done;
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let k = st.pixel[lane] as usize;
            if finite & (1 << lane) != 0 {
                sums[k].add(crate::Color::new(ls[0][lane], ls[1][lane], ls[2][lane]));
            } else {
                stats.dropped += 1;
                let (x, y) = (pixels[k].x, pixels[k].y);
                if stats.first_dropped.is_none_or(|q| (y, x) < (q.1, q.0)) {
                    stats.first_dropped = Some((x, y));
                }
            }
        }
        st.done = 0;
    }
    }

    lanes_fn! {
    /// The shadow rays `front` left in the groups, traced together: packed sixteen to a
    /// vector (where each group alone fills about half of one), each against every
    /// primitive (`Scene::occluded`'s answers), the answers unpacked into each group's
    /// `blocked` lanes. (`rays`: room for [`Trace::Scene`]'s rays, kept from step to step.)
    #[inline]
    pub(super) unsafe fn shadows<S: LaneSampler>(
        &self,
        groups: &mut [Lanes<S>],
        rays: &mut Vec<crate::geometry::Ray>,
    ) {
        use std::arch::x86_64::{_pdep_u64, _pext_u64};
        // The rays, packed: origin and direction by axis. Room for every group's sixteen,
        // their answers a bit each of a u64.
        const ROOM: usize = 16 * POOL;
        const { assert!(ROOM <= 64, "more shadow rays than bits in the answer") };
        let mut o = [[0f32; ROOM + 16]; 3];
        let mut d = [[0f32; ROOM + 16]; 3];
        let mut t_max = [0f32; ROOM + 16];
        let mut n = 0;
        // The packed rays that leave a path's first vertex (bit k: ray k).
        let mut first = 0u64;
        for g in groups.iter() {
            let sh = &g.shadow;
            if sh.lanes == 0 {
                continue;
            }
            // (After `front`, a path's depth counts the vertex it sampled the light from.)
            let at_first = (0..16).fold(0u64, |m, l| m | ((g.depth[l] == 1) as u64) << l);
            first |= _pext_u64(at_first, sh.lanes as u64) << n;
            // The lanes past the packed ones are overwritten by the next group's, or never
            // read.
            for axis in 0..3 {
                F::load(&sh.o[axis]).compress_to(sh.lanes, &mut o[axis], n);
                F::load(&sh.d[axis]).compress_to(sh.lanes, &mut d[axis], n);
            }
            F::load(&sh.t_max).compress_to(sh.lanes, &mut t_max, n);
            n += sh.lanes.count_ones() as usize;
        }
        // Their answers, a bit a ray.
        let blocked = match self.trace {
            Trace::Lanes => self.occluded_lanes(&o, &d, &t_max, n),
            Trace::Scene => self.occluded_scene(&o, &d, &t_max, n, first, rays),
        };
        let mut at = 0;
        for g in groups.iter_mut() {
            let sh = &mut g.shadow;
            sh.blocked = _pdep_u64(blocked >> at, sh.lanes as u64) as Bits;
            at += sh.lanes.count_ones();
        }
    }
    }

    /// Which of the `n` packed shadow rays (clear up to `t_max`) are blocked, a bit a ray,
    /// sixteen at a time against every primitive ([`Trace::Lanes`]).
    ///
    /// # Safety
    /// The CPU must have the backend's features (`Flat::occluded_lanes`).
    #[inline(always)]
    unsafe fn occluded_lanes<const ROOM: usize>(
        &self,
        o: &[[f32; ROOM]; 3],
        d: &[[f32; ROOM]; 3],
        t_max: &[f32; ROOM],
        n: usize,
    ) -> u64 {
        let (scene, flat) = (self.scene, self.flat());
        let mut blocked = 0u64;
        for first in (0..n).step_by(16) {
            let lanes = M::from_bits(if n - first >= 16 {
                Bits::MAX
            } else {
                (1 << (n - first)) - 1
            });
            let v = |a: &[[f32; ROOM]; 3]| V3 {
                x: F::load_at(&a[0], first),
                y: F::load_at(&a[1], first),
                z: F::load_at(&a[2], first),
            };
            let b = flat.occluded_lanes(v(o), v(d), F::load_at(t_max, first), lanes, |ray, p, t| {
                scene.hit(ray, p, t)
            });
            blocked |= (b.bits() as u64) << first;
        }
        blocked
    }

    /// Which of the `n` packed shadow rays (clear up to `t_max`) are blocked, a bit a ray,
    /// by the scene's own query ([`Trace::Scene`]).
    /// Those from paths' first vertices (bits of `first`), consecutive samples of a pixel
    /// towards the lights, sixteen to a packet (`Scene::occluded_origins`); the others
    /// together (`Scene::occluded_many`, interleaved where the scene outgrows the cache).
    #[inline(always)]
    fn occluded_scene<const ROOM: usize>(
        &self,
        o: &[[f32; ROOM]; 3],
        d: &[[f32; ROOM]; 3],
        t_max: &[f32; ROOM],
        n: usize,
        first: u64,
        rays: &mut Vec<crate::geometry::Ray>,
    ) -> u64 {
        let ray = |k: usize| {
            let v = |a: &[[f32; ROOM]; 3]| glam::Vec3A::new(a[0][k], a[1][k], a[2][k]);
            crate::geometry::Ray::new(v(o), v(d))
        };
        let mut blocked = 0u64;
        // Each part's rays in packed order, and where each sits among them.
        let mut traced = |part: u64, rays: &mut Vec<crate::geometry::Ray>, packets: bool| {
            let mut at = [0usize; ROOM];
            let mut t = [0f32; ROOM];
            rays.clear();
            for (j, k) in crate::simd::lanes_of64(part).enumerate() {
                at[j] = k;
                t[j] = t_max[k];
                rays.push(ray(k));
            }
            let m = rays.len();
            let mut out = [false; ROOM];
            if packets {
                self.scene.occluded_origins(rays, &t[..m], &mut out[..m]);
            } else {
                self.scene.occluded_many(rays, &t[..m], &mut out[..m]);
            }
            for j in 0..m {
                blocked |= (out[j] as u64) << at[j];
            }
        };
        let all = if n == 64 { !0 } else { (1u64 << n) - 1 };
        traced(first & all, rays, true);
        traced(!first & all, rays, false);
        blocked
    }
}
