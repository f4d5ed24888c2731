//! The path tracer sixteen paths at a time, for small diffuse scenes on CPUs with AVX-512.
//!
//! [`super::path::li`] follows one path at a time: its arithmetic on three-component vectors
//! fills three lanes of a four-lane register, its branches (which material, whether the
//! light sample counts, whether roulette ends the path) vary from path to path, and a small
//! scene's intersection tests, already sixteen triangles wide ([`crate::accel::flat`]),
//! waste a block's empty lanes. Here sixteen paths advance together, a lane each, in the
//! manner of a wavefront renderer (Laine, Karras and Aila, "Megakernels Considered Harmful:
//! Wavefront Path Tracing on GPUs", HPG 2013; Mitsuba 3's `llvm` variants): every step
//! traces all sixteen rays against each triangle in turn ([`trace`]), shades all sixteen
//! hits, samples the light for all of them and traces their shadow rays, samples their
//! BSDFs and plays their roulette, with the branches turned into lane masks. A lane whose
//! path ends takes the tile's next camera sample at the next step, so the lanes stay full
//! until the tile runs out of samples.
//!
//! Each lane computes exactly what `path::li` computes for its camera sample, operation for
//! operation ([`simd`]): the same numbers from the same PCG32 stream ([`rng`]), the same
//! hits, the same IEEE operations in the same order. A sample's value is therefore the same
//! bits whichever of the two renders it, and so is the image (the film's fixed-point sums do
//! not depend on the order samples arrive in): on any CPU, any thread count, any split into
//! passes or machines. `tests/determinism.rs` compares the two on scenes that exercise every
//! branch.
//!
//! The scenes it takes ([`Wavefront::new`]): at most [`MAX_TRIANGLES`] triangles and no
//! spheres; every material Lambertian (one- or two-sided, untextured) or black; no vertex
//! normals; one light, a triangle or a parallelogram; the `path` integrator with one shadow
//! ray a vertex and the independent sampler. Any other scene, and any CPU without AVX-512F
//! and AVX-512DQ, renders with `path::li` as before. The Cornell box is such a scene.

mod rng;
mod simd;
mod trace;

use crate::camera::Camera;
use crate::film::PixelSums;
use crate::geometry::ray::{gamma, SHADOW_EPSILON};
use crate::integrator::{IntegratorKind, RussianRoulette};
use crate::material::Bsdf;
use crate::render::{RenderSettings, RenderStats, TilePixel};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::{Scene, SPHERE};
use rng::Rng16;
use simd::{F, M, U, V3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};
use trace::Tri;

/// Most triangles the wavefront traces (by brute force, as `accel::flat` does).
pub const MAX_TRIANGLES: usize = 64;

/// `flags` bits of a triangle's material and emission.
const TWO_SIDED: u32 = 1;
const BLACK: u32 = 2;
const EMITTER: u32 = 4;

/// A small diffuse scene prepared for sixteen paths at a time: per triangle (by slot, in
/// primitive order) what the tests and the shading read, in tables of 64 for lane lookups.
pub struct Wavefront<'a> {
    scene: &'a Scene,
    tris: Vec<Tri>,
    p0: [[f32; 64]; 3],
    p1: [[f32; 64]; 3],
    p2: [[f32; 64]; 3],
    /// Unit geometric normal (also the shading normal: no vertex normals here).
    ng: [[f32; 64]; 3],
    albedo: [[f32; 64]; 3],
    flags: [u32; 64],
    light: Light,
    max_depth: u32,
    rr: RussianRoulette,
    hide_emitters: bool,
    seed: u64,
    width: u32,
}

/// The scene's one light, as `Lights::sample` and `Lights::pdf` read it.
#[derive(Clone, Copy)]
struct Light {
    /// A point is `a + b·u + c·v` (parallelogram) or `a·w + b·u + c·v` (triangle).
    a: [f32; 3],
    b: [f32; 3],
    c: [f32; 3],
    triangle: bool,
    normal: [f32; 3],
    /// `offset_ray_origin`'s push off the light (`PlanarLight::offset`).
    offset: [f32; 3],
    area: f32,
    radiance: [f32; 3],
    /// Its probability in `Lights::pdf` (1 when it is the only light with power).
    pmf: f32,
}

impl<'a> Wavefront<'a> {
    /// The wavefront for rendering `scene` with `s`, if the scene, the settings and the CPU
    /// are ones it takes (see the module comment); None otherwise.
    pub fn new(scene: &'a Scene, s: &RenderSettings) -> Option<Wavefront<'a>> {
        if !scene.wavefront_allowed || !cpu_has_it() {
            return None;
        }
        let p = &s.params;
        if p.kind != IntegratorKind::Path
            || p.shadow_rays != 1
            || p.max_depth == Some(0)
            || s.sampler != SamplerKind::Independent
        {
            return None;
        }
        let n = scene.tris.len();
        if n == 0 || n > MAX_TRIANGLES || !scene.attrs.is_empty() {
            return None;
        }
        let planar = scene.lights.single_planar()?;
        let mut w = Wavefront {
            scene,
            tris: Vec::with_capacity(n),
            p0: [[0.0; 64]; 3],
            p1: [[0.0; 64]; 3],
            p2: [[0.0; 64]; 3],
            ng: [[0.0; 64]; 3],
            albedo: [[0.0; 64]; 3],
            flags: [0; 64],
            light: Light {
                a: planar.a.into(),
                b: planar.b.into(),
                c: planar.c.into(),
                triangle: planar.triangle,
                normal: planar.normal.into(),
                offset: planar.offset.into(),
                area: planar.area,
                radiance: planar.radiance.into(),
                pmf: scene.lights.pmf(0),
            },
            max_depth: p.max_depth.unwrap_or(u32::MAX),
            rr: p.rr,
            hide_emitters: p.hide_emitters,
            seed: s.seed,
            width: s.width,
        };
        for (j, &idx) in scene.tris.iter().enumerate() {
            if idx[0] == SPHERE {
                return None;
            }
            let meta = scene.meta[j];
            let material = &scene.materials[(meta & crate::scene::META_MATERIAL) as usize];
            if material.texture.is_some() {
                return None;
            }
            let mut flags = 0;
            match &material.bsdf {
                Bsdf::Lambert(b) => {
                    for c in 0..3 {
                        w.albedo[c][j] = b.albedo[c];
                    }
                }
                Bsdf::Black => flags |= BLACK,
                _ => return None,
            }
            if material.two_sided {
                flags |= TWO_SIDED;
            }
            if meta & crate::scene::META_EMITTER != 0 {
                flags |= EMITTER;
            }
            w.flags[j] = flags;
            let tri = scene.triangle(idx);
            // As `Triangle::intersect` and `Scene::interaction` compute them.
            let (e1, e2) = (tri.p1 - tri.p0, tri.p2 - tri.p0);
            let ng = tri.normal_unnormalized().normalize();
            for c in 0..3 {
                w.p0[c][j] = tri.p0[c];
                w.p1[c][j] = tri.p1[c];
                w.p2[c][j] = tri.p2[c];
                w.ng[c][j] = ng[c];
            }
            w.tris.push(Tri {
                p0: tri.p0.into(),
                e1: e1.into(),
                e2: e2.into(),
                prim: j as u32,
            });
        }
        Some(w)
    }

    /// Renders the samples of one tile's pixels into their sums: pixel k's samples
    /// `pixels[k].samples`, added to `sums[k]`.
    pub fn render_tile(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        assert_eq!(pixels.len(), sums.len());
        // SAFETY: `new` checked that the CPU has AVX-512F and AVX-512DQ.
        unsafe { self.run(camera, pixels, sums, stats) }
    }
}

/// Whether this CPU runs the wavefront's code.
fn cpu_has_it() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
}

/// The state of the sixteen paths, a lane each, between steps.
struct Lanes {
    o: [[f32; 16]; 3],
    d: [[f32; 16]; 3],
    beta: [[f32; 16]; 3],
    l: [[f32; 16]; 3],
    prev_p: [[f32; 16]; 3],
    prev_pdf: [f32; 16],
    depth: [u32; 16],
    /// The tile pixel (index into `pixels`) of each lane's sample.
    pixel: [u32; 16],
    rng: Rng16,
    /// Lanes holding a path.
    active: M,
    /// Lanes whose path got to its vertex by a BSDF sample (for MIS on emitter hits).
    has_prev: M,
}

/// Power heuristic with β = 2, lane by lane as `sampling::power_heuristic`.
#[inline(always)]
fn power_heuristic(f: F, g: F) -> F {
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    let (zero, inf) = (F::zero(), F::splat(f32::INFINITY));
    let r = F::select(sum.eq(zero), zero, f2 / sum);
    F::select(f2.abs().eq(inf), F::splat(1.0), r)
}

/// `sampling::sin_cos_quarter`, lane by lane.
#[inline(always)]
fn sin_cos_quarter(x: F) -> (F, F) {
    let k = F::splat;
    let z = x * x;
    let s = ((((k(-1.951_529_6e-4) * z + k(8.332_161e-3)) * z - k(1.666_665_5e-1)) * z) * x) + x;
    let c = ((((k(2.443_315_7e-5) * z - k(1.388_731_6e-3)) * z + k(4.166_664_6e-2)) * z) * z
        - k(0.5) * z)
        + k(1.0);
    (s, c)
}

impl Wavefront<'_> {
    #[target_feature(enable = "avx512f,avx512dq")]
    unsafe fn run(
        &self,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        let mut st = Lanes {
            o: [[0.0; 16]; 3],
            d: [[0.0; 16]; 3],
            beta: [[0.0; 16]; 3],
            l: [[0.0; 16]; 3],
            prev_p: [[0.0; 16]; 3],
            prev_pdf: [0.0; 16],
            depth: [0; 16],
            pixel: [0; 16],
            rng: Rng16::new(),
            active: 0,
            has_prev: 0,
        };
        // The next camera sample: pixel k, sample i.
        let (mut k, mut i) = (0usize, pixels.first().map_or(0, |p| p.samples.0));
        let (mut px, mut py) = ([0f32; 16], [0f32; 16]);
        loop {
            // Free lanes take the next samples.
            let mut fresh: M = 0;
            let mut free = !st.active;
            while free != 0 {
                while k < pixels.len() && i >= pixels[k].samples.1 {
                    k += 1;
                    i = pixels.get(k).map_or(0, |p| p.samples.0);
                }
                if k == pixels.len() {
                    break;
                }
                let l = free.trailing_zeros() as usize;
                free &= free - 1;
                let pix = &pixels[k];
                let pixel = pix.gy as u64 * self.width as u64 + pix.gx as u64;
                let (state, inc) =
                    Sampler::for_sample(SamplerKind::Independent, self.seed, pixel, i as u64)
                        .pcg_words();
                st.rng.state[l] = state;
                st.rng.inc[l] = inc;
                st.pixel[l] = k as u32;
                (px[l], py[l]) = (pix.gx as f32, pix.gy as f32);
                fresh |= 1 << l;
                i += 1;
            }
            if fresh != 0 {
                self.start(camera, &mut st, fresh, &px, &py);
            }
            if st.active == 0 {
                break;
            }
            self.step(&mut st, pixels, sums, stats);
        }
    }

    /// Camera rays for the lanes of `fresh` (`Camera::generate_ray` with the sample's first
    /// two numbers), and their paths' initial state.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    unsafe fn start(&self, cam: &Camera, st: &mut Lanes, fresh: M, px: &[f32; 16], py: &[f32; 16]) {
        let ux = st.rng.next_1d(fresh);
        let uy = st.rng.next_1d(fresh);
        let s = (F::load(px) + ux) / F::splat(cam.width as f32);
        let t = (F::load(py) + uy) / F::splat(cam.height as f32);
        let v = |a: glam::Vec3A| V3::splat(a.into());
        let p = ((v(cam.tl) + v(cam.right).scale(s)) + v(cam.down).scale(t))
            + v(cam.twist).scale(s * t);
        let eye = v(cam.eye);
        let d = (p - eye).normalize();
        let keep = |a: &mut [[f32; 16]; 3], x: V3| V3::select(fresh, x, V3::load(a)).store(a);
        keep(&mut st.o, eye);
        keep(&mut st.d, d);
        keep(&mut st.beta, V3::splat([1.0; 3]));
        keep(&mut st.l, V3::zero());
        U::select(fresh, U::splat(0), U::load(&st.depth)).store(&mut st.depth);
        st.has_prev &= !fresh;
        st.active |= fresh;
    }

    /// One step of every active path: a vertex, as one pass of `path::li`'s loop.
    // (The target features are repeated so that the closures inside get them too.)
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    unsafe fn step(
        &self,
        st: &mut Lanes,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        let active = st.active;
        let (zero, one) = (F::zero(), F::splat(1.0));
        let o = V3::load(&st.o);
        let d = V3::load(&st.d);
        let mut beta = V3::load(&st.beta);
        let mut l = V3::load(&st.l);
        let depth = U::load(&st.depth);
        stats.rays.rays += active.count_ones() as u64;
        let h = trace::closest(self.scene, &self.tris, o, d, active);
        let hidden = if self.hide_emitters {
            depth.eq(U::splat(0))
        } else {
            0
        };
        // A ray that leaves the scene: these scenes have no environment light, so it adds
        // β·0, as `escaped` returns (which is not nothing where β is not finite).
        let miss = active & !h.hit;
        l = V3::select(miss & !hidden, l + beta * V3::zero(), l);
        let mut done = miss;
        let hit = h.hit;

        // The hit: `Scene::interaction`'s point, error bound and normal.
        let slot = h.slot;
        let (p0, p1, p2) = (
            V3::lookup64(&self.p0, slot),
            V3::lookup64(&self.p1, slot),
            V3::lookup64(&self.p2, slot),
        );
        let (u, v) = (h.u, h.v);
        let w = (one - u) - v;
        let (a, b, c) = (p0.scale(w), p1.scale(u), p2.scale(v));
        let p = (a + b) + c;
        let p_err = ((a.abs() + b.abs()) + c.abs()).scale(F::splat(gamma(7)));
        let ng = V3::lookup64(&self.ng, slot);
        let flags = U::lookup64(&self.flags, slot);
        let albedo = V3::lookup64(&self.albedo, slot);
        let lt = &self.light;

        // Emission (`emitted`), weighted against light sampling where the path got here by
        // a BSDF sample.
        let emitter = hit & flags.any(EMITTER);
        let nd = -d;
        let le = V3::select(
            emitter & ng.dot(nd).gt(zero),
            V3::splat(lt.radiance),
            V3::zero(),
        );
        let prev_p = V3::load(&st.prev_p);
        let dd = p - prev_p;
        let dist2 = dd.dot(dd);
        let cos_l = (-ng.dot(dd)).max_num(zero) / dist2.sqrt();
        let light_pdf = F::select(
            cos_l.le(zero),
            zero,
            (F::splat(lt.pmf) * dist2) / (cos_l * F::splat(lt.area)),
        );
        let mis = power_heuristic(F::load(&st.prev_pdf), one * light_pdf);
        let e = V3::select(emitter & st.has_prev, le.scale(mis), le);
        l = V3::select(hit & !hidden, l + beta * e, l);

        // The path's length, and black bodies.
        let last = depth.add(U::splat(1)).ge(U::splat(self.max_depth));
        let cont = hit & !last & !flags.any(BLACK);
        done |= hit & !cont;

        // The shading frame (`Frame::from_normal`) and wo.
        let n = ng;
        let sign = F::sign_of(n.z);
        let fa = F::splat(-1.0) / (sign + n.z);
        let fb = (n.x * n.y) * fa;
        let fs = V3 {
            x: one + ((sign * n.x) * n.x) * fa,
            y: sign * fb,
            z: (-sign) * n.x,
        };
        let ft = V3 {
            x: fb,
            y: sign + (n.y * n.y) * fa,
            z: -n.y,
        };
        let to_local = |x: V3| V3 {
            x: x.dot(fs),
            y: x.dot(ft),
            z: x.dot(n),
        };
        let wo = to_local(nd);
        // `Material::orient`: the side the BSDF is seen from, None for a one-sided
        // material seen from behind.
        let front = wo.z.gt(zero);
        let oriented = front | (wo.z.lt(zero) & flags.any(TWO_SIDED));
        let side = F::select(front, one, F::splat(-1.0));

        // Next-event estimation: one sample of the light (`one_sample`).
        let ux = st.rng.next_1d(cont);
        let uy = st.rng.next_1d(cont);
        let _u_select = st.rng.next_1d(cont); // one light: chosen with probability one
        let (la, lb, lc) = (V3::splat(lt.a), V3::splat(lt.b), V3::splat(lt.c));
        let pl = if lt.triangle {
            let su = ux.sqrt();
            let (bu, bv) = (one - su, uy * su);
            (la.scale((one - bu) - bv) + lb.scale(bu)) + lc.scale(bv)
        } else {
            (la + lb.scale(ux)) + lc.scale(uy)
        };
        let ln = V3::splat(lt.normal);
        let dl = pl - p;
        let dist2 = dl.dot(dl);
        let wi = dl.div(dist2.sqrt());
        let cos_l = -ln.dot(wi);
        let pdf = (one * dist2) / (cos_l * F::splat(lt.area));
        let wil = to_local(wi);
        let wz = wil.z * side;
        let f = V3::select(
            oriented & !wz.le(zero),
            albedo.scale(F::splat(FRAC_1_PI)),
            V3::zero(),
        );
        let bsdf_pdf = F::select(oriented, wz.max_num(zero) * F::splat(FRAC_1_PI), zero);
        let f = f.scale(wil.z.abs());
        let shadow = cont & !dist2.eq(zero) & !cos_l.le(zero) & !f.is_zero();
        // The shadow ray (`spawn_ray_to`), both ends pushed off their surfaces.
        let off = ng.scale(F::splat(2.0) * ng.abs().dot(p_err));
        let so = V3::select(dl.dot(ng).lt(zero), p - off, p + off);
        let loff = V3::splat(lt.offset);
        let target = V3::select((so - pl).dot(ln).lt(zero), pl - loff, pl + loff);
        let sd = target - so;
        let mis = power_heuristic(one * pdf, bsdf_pdf);
        let contribution = (f * V3::splat(lt.radiance)).scale(mis / pdf);
        stats.rays.shadow_rays += shadow.count_ones() as u64;
        let blocked = if shadow != 0 {
            trace::occluded(
                self.scene,
                &self.tris,
                so,
                sd,
                F::splat(1.0 - SHADOW_EPSILON),
                shadow,
            )
        } else {
            0
        };
        let lit = V3::select(shadow & !blocked, contribution, V3::zero());
        l = V3::select(cont, l + beta * lit, l);

        // The BSDF sample (`Lambert::sample`: the cosine-weighted hemisphere by the
        // concentric map).
        let ux = st.rng.next_1d(cont);
        let uy = st.rng.next_1d(cont);
        let _u_lobe = st.rng.next_1d(cont);
        let u_rr = st.rng.next_1d(cont);
        let mut alive = cont & oriented;
        let (ox, oy) = (F::splat(2.0) * ux - one, F::splat(2.0) * uy - one);
        let centre = ox.eq(zero) & oy.eq(zero);
        let xmaj = ox.abs().gt(oy.abs());
        let r = F::select(xmaj, ox, oy);
        let (sn, cs) = sin_cos_quarter(
            F::splat(FRAC_PI_4) * (F::select(xmaj, oy, ox) / F::select(xmaj, ox, oy)),
        );
        let dx = F::select(centre, zero, F::select(xmaj, r * cs, r * sn));
        let dy = F::select(centre, zero, F::select(xmaj, r * sn, r * cs));
        let z = (one - (dx * dx + dy * dy)).max_num(zero).sqrt();
        alive &= !z.le(zero);
        let pdf = z.max_num(zero) * F::splat(FRAC_1_PI);
        let wl = V3 {
            x: dx,
            y: dy,
            z: z * side,
        };
        beta = V3::select(alive, beta * albedo, beta);
        // `Frame::to_world` and `spawn_ray`.
        let wi = (fs.scale(wl.x) + ft.scale(wl.y)) + n.scale(wl.z);
        let no = V3::select(wi.dot(ng).lt(zero), p - off, p + off);
        let depth = depth.add(U::splat(1));
        // Russian roulette.
        match self.rr {
            RussianRoulette::Fixed(q) => {
                let q = F::splat(q);
                alive &= !u_rr.ge(q);
                beta = V3::select(alive, beta.div(q), beta);
            }
            RussianRoulette::Throughput { start } => {
                let plays = alive & depth.ge(U::splat(start));
                // (The roulette's η² is 1: Lambertian samples do not refract.)
                let q = beta.max_element().min_num(F::splat(0.95));
                alive &= !(plays & u_rr.ge(q));
                beta = V3::select(plays & alive, beta.div(q), beta);
            }
        }
        alive &= !beta.is_zero();
        done |= cont & !alive;

        // The paths that ended: their samples to the film.
        if done != 0 {
            let ls = [l.x.to_array(), l.y.to_array(), l.z.to_array()];
            let finite = l.is_finite();
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
        }

        no.store(&mut st.o);
        wi.store(&mut st.d);
        beta.store(&mut st.beta);
        l.store(&mut st.l);
        p.store(&mut st.prev_p);
        pdf.store(&mut st.prev_pdf);
        depth.store(&mut st.depth);
        st.has_prev |= alive;
        st.active = alive;
    }
}
