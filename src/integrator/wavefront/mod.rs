//! The path tracer sixteen paths at a time, for small scenes on CPUs with AVX-512.
//!
//! [`super::path::li`] follows one path at a time: its arithmetic on three-component vectors
//! fills three lanes of a four-lane register, its branches (which material, whether the
//! light sample counts, whether roulette ends the path) vary from path to path, and a small
//! scene's intersection tests, already sixteen triangles wide ([`crate::accel::flat`]),
//! waste a block's empty lanes. Here sixteen paths advance together, a lane each, in the
//! manner of a wavefront renderer (Laine, Karras and Aila, "Megakernels Considered Harmful:
//! Wavefront Path Tracing on GPUs", HPG 2013; Mitsuba 3's `llvm` variants): every step
//! traces all sixteen rays against each primitive in turn ([`trace`]), shades all sixteen
//! hits, samples the light for all of them and traces their shadow rays ([`nee`]), samples
//! their BSDFs ([`bsdf`]) and plays their roulette ([`path`]), with the branches turned into
//! lane masks. A lane whose path ends takes the tile's next camera sample at the next step,
//! so the lanes stay full until the tile runs out of samples. With one light sample a
//! vertex, a tile keeps [`GROUPS`] groups of sixteen paths in flight and traces their shadow
//! rays together, packed sixteen to a vector (each group's rays fill about half of one): a step
//! is [`Wavefront::front`] for every group, [`Wavefront::shadows`], then
//! [`Wavefront::back`] for every group.
//!
//! Each lane computes exactly what `path::li` computes for its camera sample, operation for
//! operation ([`simd`]): the same numbers from the same sampler ([`rng`]), the same hits,
//! the same IEEE operations in the same order. A sample's value is therefore the same bits
//! whichever of the two renders it, and so is the image (the film's fixed-point sums do not
//! depend on the order samples arrive in): on any CPU, any thread count, any split into
//! passes or machines. `tests/wavefront.rs` compares the two on scenes that take every
//! branch.
//!
//! The scenes it takes ([`Wavefront::new`]): those the path tracer traces by brute force
//! (`accel::flat`: at most 64 triangles and 4 spheres); every material Lambertian (one- or
//! two-sided, untextured), a mirror (untextured), smooth glass or black; no vertex normals;
//! one light, a triangle or a parallelogram; the `path` integrator, any number of shadow
//! rays, either sampler. The Cornell box and the TNCG15 room are such scenes. Any other
//! scene, and any CPU without AVX-512F, AVX-512DQ and BMI2, renders with `path::li`.

mod bsdf;
mod nee;
mod path;
mod rng;
mod simd;
mod trace;

use crate::camera::Camera;
use crate::film::PixelSums;
use crate::integrator::{IntegratorKind, RussianRoulette};
use crate::material::Bsdf;
use crate::render::{RenderSettings, RenderStats, TilePixel};
use crate::sampler::SamplerKind;
use crate::scene::{Scene, META_EMITTER, META_MATERIAL, SPHERE};
use rng::{LaneSampler, Pcg16, Samplers16};
use simd::{F, M, U, V3};
use trace::{Ball, Tri};

/// Most primitives the wavefront traces (by brute force, as `accel::flat` does).
pub const MAX_PRIMS: usize = 64;

/// `flags` of a primitive: its material's kind in the low two bits...
const KIND: u32 = 3;
const LAMBERT: u32 = 0;
const MIRROR: u32 = 1;
const GLASS: u32 = 2;
const BLACK: u32 = 3;
/// ...whether it is two-sided, and whether it emits.
const TWO_SIDED: u32 = 4;
const EMITTER: u32 = 8;

/// A small scene prepared for sixteen paths at a time: the primitives for the tests, and
/// per primitive what shading reads, in tables of 64 for lane lookups.
pub struct Wavefront<'a> {
    scene: &'a Scene,
    tris: Vec<Tri>,
    balls: Vec<Ball>,
    /// Triangles: vertices and unit geometric normal (also the shading normal: no vertex
    /// normals here). Spheres: centre (in `p0`) and radius.
    p0: [[f32; 64]; 3],
    p1: [[f32; 64]; 3],
    p2: [[f32; 64]; 3],
    ng: [[f32; 64]; 3],
    radius: [f32; 64],
    /// The material's colour (Lambertian albedo, mirror reflectance) and relative index of
    /// refraction (glass).
    colour: [[f32; 64]; 3],
    eta: [f32; 64],
    flags: [u32; 64],
    light: Light,
    max_depth: u32,
    rr: RussianRoulette,
    hide_emitters: bool,
    shadow_rays: u32,
    sampler: SamplerKind,
    seed: u64,
    width: u32,
}

/// The scene's one light, as `Lights::sample`, `Lights::pdf` and the planar batch read it.
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
    /// Its probability in `Lights::pdf` (the distribution's, over the one light).
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
        // (No shadow ray at all is refused by the settings; through the library it would
        // make `sample_lights` divide by zero, which the lanes do not copy.)
        if p.kind != IntegratorKind::Path || p.max_depth == Some(0) || p.shadow_rays == 0 {
            return None;
        }
        // The path tracer traces single rays by brute force exactly where the scene has a
        // flat set (`accel::flat`: at most 64 triangles and 4 spheres); elsewhere it uses the
        // BVH, which for a grazing ray may skip a primitive brute force would test. So the
        // lanes, which test every primitive, match it only where it does too.
        let n = scene.tris.len();
        if n == 0 || n > MAX_PRIMS || !scene.is_flat() || !scene.attrs.is_empty() {
            return None;
        }
        let planar = scene.lights.single_planar()?;
        let mut w = Wavefront {
            scene,
            tris: Vec::with_capacity(n),
            balls: Vec::new(),
            p0: [[0.0; 64]; 3],
            p1: [[0.0; 64]; 3],
            p2: [[0.0; 64]; 3],
            ng: [[0.0; 64]; 3],
            radius: [0.0; 64],
            colour: [[0.0; 64]; 3],
            eta: [1.0; 64],
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
            shadow_rays: p.shadow_rays,
            sampler: s.sampler,
            seed: s.seed,
            width: s.width,
        };
        for (j, &idx) in scene.tris.iter().enumerate() {
            let meta = scene.meta[j];
            let material = &scene.materials[(meta & META_MATERIAL) as usize];
            if material.texture.is_some() {
                return None;
            }
            let (kind, colour) = match &material.bsdf {
                Bsdf::Lambert(b) => (LAMBERT, b.albedo),
                Bsdf::Mirror(b) => (MIRROR, b.reflectance),
                Bsdf::Dielectric(b) => {
                    w.eta[j] = b.eta;
                    (GLASS, crate::Color::ONE)
                }
                Bsdf::Black => (BLACK, crate::Color::ZERO),
                _ => return None,
            };
            let mut flags = kind;
            if material.two_sided {
                flags |= TWO_SIDED;
            }
            for c in 0..3 {
                w.colour[c][j] = colour[c];
            }
            if idx[0] == SPHERE {
                // (Emitting spheres are lights of their own: no scene here has one.)
                if meta & META_EMITTER != 0 {
                    return None;
                }
                let sphere = scene.spheres[idx[1] as usize];
                for c in 0..3 {
                    w.p0[c][j] = sphere.center[c];
                }
                w.radius[j] = sphere.radius;
                w.flags[j] = flags;
                w.balls.push(Ball {
                    center: sphere.center.into(),
                    r2: sphere.radius * sphere.radius,
                    prim: j as u32,
                });
                continue;
            }
            if meta & META_EMITTER != 0 {
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
        // SAFETY: `new` checked that the CPU has AVX-512F, AVX-512DQ and BMI2.
        unsafe {
            match self.sampler {
                SamplerKind::Independent => self.run(Pcg16::new(), camera, pixels, sums, stats),
                _ => self.run(Samplers16::new(), camera, pixels, sums, stats),
            }
        }
    }
}

/// Whether this CPU runs the wavefront's code.
fn cpu_has_it() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("bmi2")
}

/// The state of the sixteen paths, a lane each, between steps.
struct Lanes<S> {
    o: [[f32; 16]; 3],
    d: [[f32; 16]; 3],
    beta: [[f32; 16]; 3],
    l: [[f32; 16]; 3],
    /// η² accumulated over refractions (for the roulette).
    eta2: [f32; 16],
    prev_p: [[f32; 16]; 3],
    prev_pdf: [f32; 16],
    depth: [u32; 16],
    /// The tile pixel (index into `pixels`) of each lane's sample.
    pixel: [u32; 16],
    rng: S,
    /// Lanes holding a path.
    active: M,
    /// Lanes whose path got to its vertex by a non-specular BSDF sample (for MIS on
    /// emitter hits).
    has_prev: M,
    /// Lanes whose path ended at the last step, their samples not yet on the film.
    done: M,
    /// The shadow rays of the last step's light samples, waiting to be traced.
    shadow: Shadows,
}

/// A group's shadow rays between `front` and `back` (one light sample a vertex).
struct Shadows {
    /// The lanes that sampled the light, those whose sample needs a shadow ray, and of
    /// those the ones blocked (set by `shadows`).
    nee: M,
    lanes: M,
    blocked: M,
    o: [[f32; 16]; 3],
    d: [[f32; 16]; 3],
    /// What `l += β·lit` adds: β times the contribution where the ray is clear, β·0 where
    /// it is blocked or there is no ray.
    lit: [[f32; 16]; 3],
    dark: [[f32; 16]; 3],
}

/// Groups of sixteen lanes a tile keeps in flight. Each group's light samples leave shadow
/// rays in about half its lanes (the others' paths end, or their sample lies behind the
/// surface: 58 % of them carry one in the Cornell box), so each group alone would trace
/// vectors half full; four groups' rays pack into about three. Measured on the Cornell box
/// (256², 64 spp, one thread, three rounds alternating): 1.45–1.72 s against 1.59–1.85 s
/// for one group; two groups were no faster, six or eight no faster than four.
const GROUPS: usize = 4;

impl Wavefront<'_> {
    #[target_feature(enable = "avx512f,avx512dq,bmi2")]
    unsafe fn run<S: LaneSampler + Clone>(
        &self,
        rng: S,
        camera: &Camera,
        pixels: &[TilePixel],
        sums: &mut [PixelSums],
        stats: &mut RenderStats,
    ) {
        let lanes = || Lanes {
            o: [[0.0; 16]; 3],
            d: [[0.0; 16]; 3],
            beta: [[0.0; 16]; 3],
            l: [[0.0; 16]; 3],
            eta2: [1.0; 16],
            prev_p: [[0.0; 16]; 3],
            prev_pdf: [0.0; 16],
            depth: [0; 16],
            pixel: [0; 16],
            rng: rng.clone(),
            active: 0,
            has_prev: 0,
            done: 0,
            shadow: Shadows {
                nee: 0,
                lanes: 0,
                blocked: 0,
                o: [[0.0; 16]; 3],
                d: [[0.0; 16]; 3],
                lit: [[0.0; 16]; 3],
                dark: [[0.0; 16]; 3],
            },
        };
        let mut all: [Lanes<S>; GROUPS] = std::array::from_fn(|_| lanes());
        // Several light samples a vertex are traced as each lane's packets, in `front`:
        // nothing to pool, so one group.
        let groups = if self.shadow_rays == 1 {
            &mut all[..]
        } else {
            &mut all[..1]
        };
        // The next camera sample: pixel k, sample i.
        let (mut k, mut i) = (0usize, pixels.first().map_or(0, |p| p.samples.0));
        let (mut px, mut py) = ([0f32; 16], [0f32; 16]);
        loop {
            let mut busy = false;
            for st in groups.iter_mut() {
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
                    st.rng.start(l, self.sampler, self.seed, pixel, i as u64);
                    st.pixel[l] = k as u32;
                    (px[l], py[l]) = (pix.gx as f32, pix.gy as f32);
                    fresh |= 1 << l;
                    i += 1;
                }
                if fresh != 0 {
                    self.start(camera, st, fresh, &px, &py);
                }
                if st.active != 0 {
                    self.front(st, stats);
                    busy = true;
                }
            }
            if !busy {
                break;
            }
            self.shadows(groups);
            for st in groups.iter_mut() {
                self.back(st, pixels, sums, stats);
            }
        }
    }

    /// Camera rays for the lanes of `fresh` (`Camera::generate_ray` with the sample's first
    /// request), and their paths' initial state.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    unsafe fn start<S: LaneSampler + Clone>(
        &self,
        cam: &Camera,
        st: &mut Lanes<S>,
        fresh: M,
        px: &[f32; 16],
        py: &[f32; 16],
    ) {
        let [ux, uy] = st.rng.next::<2>(fresh);
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
        F::select(fresh, F::splat(1.0), F::load(&st.eta2)).store(&mut st.eta2);
        U::select(fresh, U::splat(0), U::load(&st.depth)).store(&mut st.depth);
        st.has_prev &= !fresh;
        st.active |= fresh;
    }
}
