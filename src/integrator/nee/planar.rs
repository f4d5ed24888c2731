//! Next-event estimation when the scene's only light is a triangle or a parallelogram
//! (`Lights::single_planar`, the case of most test scenes and of the TNCG15 room): a batch's
//! samples, BSDF values and MIS weights computed several lanes at a time, with everything the
//! samples share (the light's corners and offset, the material's side, a Lambertian BSDF's
//! colour) worked out once per vertex.
//!
//! The body is written once over [`Lanes`]: eight lanes with AVX where the CPU has it
//! (checked at run time; the binary is built for plain x86-64), four (glam's `Vec4`)
//! elsewhere. Each lane computes the same IEEE operations either way and the weights are
//! summed four lanes at a time in the same order, so both give the same bits. Ten shadow
//! rays, Figure 3.3's, take two eight-lane steps instead of three four-lane ones.

use super::lanes::Lanes;
use super::{RayStats, BATCH};
use crate::accel::{RayPacket, PACKET};
use crate::geometry::ray::{offset_by, offset_ray_origin, SHADOW_EPSILON};
use crate::geometry::Frame;
use crate::light::{planar_point, PlanarLight};
use crate::material::sampling::power_heuristic;
use crate::material::{Bsdf, Material};
use crate::scene::{Interaction, Scene};
use crate::simd::{Float, Mask, Vector3, V3};
use crate::Color;
use glam::{Vec3A, Vec4};
use std::f32::consts::{FRAC_1_PI, PI};

/// frac(j·(φ − 1)) for j < 256 (and seven more, for loads of eight), from `G1`: the
/// lattice's second coordinate, by table so that a vector of lanes loads it at once. Past 256
/// samples a vertex reuses them (each sample stays uniform; only the set's spread suffers).
static LATTICE_V: [f32; 263] = {
    let mut t = [0.0; 263];
    let mut j = 0;
    while j < 263 {
        t[j] = ((j as u32 % 256).wrapping_mul(super::G1) >> 8) as f32 * (1.0 / 16_777_216.0);
        j += 1;
    }
    t
};

/// A vertex's batch: the light, the shading point, its frame and material, the direction
/// the path arrived from (local), the number of samples and the lattice's shift Δ.
#[derive(Clone, Copy)]
pub(super) struct Vertex<'a> {
    pub scene: &'a Scene,
    pub light: &'a PlanarLight,
    pub si: &'a Interaction,
    pub frame: &'a Frame,
    pub wo: Vec3A,
    pub material: &'a Material,
    pub n: u32,
    pub delta: [f32; 3],
}

/// The batch's estimate, divided by `n`; `LAMBERT`: the material is Lambertian and `wo` is
/// on a side it reflects on (`sample_lights` checked).
#[inline(never)]
pub(super) fn planar<const LAMBERT: bool>(v: &Vertex, stats: &mut RayStats) -> Color {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, checked just above.
        return unsafe { planar_avx::<LAMBERT>(v, stats) };
    }
    planar_in::<Vec4, LAMBERT>(v, stats)
}

/// [`planar`] eight lanes at a time; the CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn planar_avx<const LAMBERT: bool>(v: &Vertex, stats: &mut RayStats) -> Color {
    planar_in::<super::lanes::F8, LAMBERT>(v, stats)
}

/// (Δ + offset) mod 1 for Δ and offsets in [0, 1): one subtraction, exact by Sterbenz's lemma.
#[inline(always)]
pub(crate) fn wrap<T: Float>(x: T) -> T {
    let one = T::splat(1.0);
    T::select(x.ge(one), x - one, x)
}

/// A Lambertian vertex's weight for the light point at offset `d` from it (`dist2` its
/// squared length), over the light pdf and without ρ/π: the power heuristic's, in the form
/// that spares the divider. With f·|cos| = (ρ/π)·c and p_bsdf = c/π, c the cosine on the lit
/// side, and p_light = r²/(cos_l·A), the power heuristic's weight over p_light,
/// c·(n·p_light)²/((n·p_light)² + p_bsdf²)/p_light, is n²π²·t/(n²π² + t²) (`k` = n²π²) with
/// t = c·cos_l·A/r² = (c·r)(cos_l·A·r)/(r²)²: no square root, one division for 1/r² and one
/// for the weight; finite, and 0 where t is (a light seen edge-on), as the limit is. Also the
/// lanes where the light and the surface face each other. `nl` is the light's normal, `ns`
/// the shading normal, `side` ±1 the side the path is on.
#[inline(always)]
pub(crate) fn lambert_weight<V: Vector3>(
    d: V,
    dist2: V::F,
    (nl, neg_area): (V, V::F),
    (ns, side): (V, V::F),
    k: V::F,
) -> (Mask<V>, V::F) {
    let zero = V::F::zero();
    let a_l = nl.dot(d) * neg_area; // cos_l·A·r
    let a_s = ns.dot(d) * side; // c·r
    let inv = V::F::splat(1.0) / dist2;
    let t = (a_l * a_s) * (inv * inv);
    (a_l.gt(zero) & a_s.gt(zero), (k * t) / (k + t * t))
}

/// The shadow ray to light point `q` (the light's normal `nl`, its push `off`): from the
/// origin on the side it leaves (`below` where `under`, else `above`) to `q` pushed off the
/// light towards it (`offset_ray_origin` at both ends); its direction, to be clear up to
/// 1 − `SHADOW_EPSILON`.
#[inline(always)]
pub(crate) fn shadow_dir<V: Vector3>(
    q: V,
    (nl, off): (V, V),
    under: Mask<V>,
    (above, below): (V, V),
) -> V {
    let o = V::select(under, below, above);
    offset_by(q, off, nl, o - q) - o
}

/// The batch over lanes `V`. The estimator is the general path's (`AreaLight::sample_point`,
/// `Lights::sample`, `Interaction::spawn_ray_to`, the power heuristic): the same points,
/// rays and weights, the weights' algebra rearranged to spare the divider (see the comments
/// below), so the values agree to rounding, not bit for bit.
#[inline(always)]
fn planar_in<V: Lanes, const LAMBERT: bool>(vx: &Vertex, stats: &mut RayStats) -> Color {
    let Vertex {
        scene,
        light,
        si,
        frame,
        wo,
        material,
        n,
        delta,
    } = *vx;
    // Lambertian: the albedo and the side `wo` is on (`sample_lights` checked it is lit).
    let (albedo, side) = match (&material.bsdf, material.orient(wo)) {
        (Bsdf::Lambert(b), Some(side)) => (b.albedo, side),
        _ => (Color::ZERO, 1.0),
    };
    let p = si.p;
    // The two possible ray origins, above and below the surface (`offset_ray_origin`).
    let origins = [
        offset_ray_origin(p, si.p_err, si.ng, si.ng),
        offset_ray_origin(p, si.p_err, si.ng, -si.ng),
    ];
    let sp = V3::<V>::broadcast;
    let (a, b, c) = (sp(light.a), sp(light.b), sp(light.c));
    let (nl, off) = (sp(light.normal), sp(light.offset));
    // (−n_l·x is n_l·x negated exactly: each product and sum only changes sign.)
    let nl_neg = sp(-light.normal);
    let (ps, ns, ng) = (sp(p), sp(frame.n), sp(si.ng));
    let (o_above, o_below) = (sp(origins[0]), sp(origins[1]));
    let (du, dv) = (V::splat(delta[0]), V::splat(delta[1]));
    let nf = n as f32;
    let (inv_n, area, neg_area) = (
        V::splat(1.0 / nf),
        V::splat(light.area),
        V::splat(-light.area),
    );
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let side = V::splat(side);
    let n2pi2 = V::splat(nf * nf * PI * PI);
    let mut acc = Vec4::ZERO;
    let mut sum = Color::ZERO;
    let mut i = 0;
    while i < n {
        let m = (n - i).min(BATCH as u32);
        let steps = m.div_ceil(V::N as u32) as usize;
        let mut pk = RayPacket {
            o: origins[0],
            d: [[0.0; PACKET]; 3],
            t_max: [1.0 - SHADOW_EPSILON; PACKET],
        };
        let mut wi = [[0f32; BATCH]; 3];
        let (mut pdf, mut cos_s, mut weight_s) = ([0f32; BATCH], [0f32; BATCH], [0f32; BATCH]);
        // Lambertian weights, a vector of lanes at a time (at most BATCH / 4 vectors).
        let mut weight = [zero; BATCH / 4];
        // Bit l: sample i + l is usable, its ray leaves below the surface.
        let (mut ok, mut below) = (0u32, 0u32);
        for (h, wh) in weight.iter_mut().enumerate().take(steps) {
            let first = h * V::N;
            let j = i + first as u32;
            let jv = V::splat(j as f32) + V::index();
            let u = wrap(du + jv * inv_n);
            let k = (j % 256) as usize;
            let v = wrap(dv + V::load(&LATTICE_V[k..]));
            let q = planar_point(a, b, c, light.triangle, u, v);
            let d = q - ps;
            let dist2 = d.dot(d);
            let under = ng.dot(d).lt(zero);
            let mut good = jv.lt(V::splat(nf)) & dist2.gt(zero);
            // The divider, not the arithmetic, bounds this loop (divisions and square roots
            // issue one every few cycles and wait a dozen), so each lane pays as few as it can.
            if LAMBERT {
                let (faces, w) = lambert_weight(d, dist2, (nl, neg_area), (ns, side), n2pi2);
                good = good & faces;
                *wh = w;
            } else {
                // The pdf is carried as its reciprocal x = 1/p_light = cos_l·A/r².
                let inv_r = one / dist2.sqrt();
                let w = d.scale(inv_r);
                let cos_l = nl_neg.dot(w);
                let x_l = cos_l * area * (inv_r * inv_r);
                good = good & cos_l.gt(zero);
                (one / x_l).store(&mut pdf[first..]);
                ns.dot(w).store(&mut cos_s[first..]);
                w.x.store(&mut wi[0][first..]);
                w.y.store(&mut wi[1][first..]);
                w.z.store(&mut wi[2][first..]);
            }
            let dir = shadow_dir(q, (nl, off), under, (o_above, o_below));
            dir.x.store(&mut pk.d[0][first..]);
            dir.y.store(&mut pk.d[1][first..]);
            dir.z.store(&mut pk.d[2][first..]);
            ok |= V::bits(good) << first;
            below |= V::bits(under) << first;
        }
        // Other BSDFs, sample by sample.
        let mut colour = [Color::ZERO; BATCH];
        if !LAMBERT {
            let mut mm = ok;
            while mm != 0 {
                let l = mm.trailing_zeros() as usize;
                mm &= mm - 1;
                let w = Vec3A::new(wi[0][l], wi[1][l], wi[2][l]);
                let local = Vec3A::new(w.dot(frame.s), w.dot(frame.t), cos_s[l]);
                let (f, bsdf_pdf) = material.eval_pdf(wo, local);
                let f = f * cos_s[l].abs();
                if f == Color::ZERO {
                    ok &= !(1 << l);
                }
                colour[l] = f;
                weight_s[l] = power_heuristic(nf * pdf[l], bsdf_pdf) / pdf[l];
            }
        }
        // The shadow rays, in up to two packets by the side of the surface they leave
        // (almost always one).
        let mut visible = 0;
        for (s, active) in [ok & !below, ok & below].into_iter().enumerate() {
            if active != 0 {
                pk.o = origins[s];
                stats.shadow_rays += active.count_ones() as u64;
                visible |= active & !scene.occluded_packet(&pk, active);
            }
        }
        // Contributions summed in a fixed order: Lambertian weights four lanes at a time
        // (no chain of dependent scalar additions), the others sample by sample.
        if LAMBERT {
            for (h, wv) in weight.iter().enumerate().take(steps) {
                let on = V::mask_of(visible >> (h * V::N));
                acc = V::select(on, *wv, zero).add_to(acc);
            }
        } else {
            while visible != 0 {
                let l = visible.trailing_zeros() as usize;
                visible &= visible - 1;
                sum += colour[l] * weight_s[l];
            }
        }
        i += m;
    }
    let sum = if LAMBERT {
        albedo * FRAC_1_PI * light.radiance * acc.element_sum()
    } else {
        sum * light.radiance
    };
    sum / nf
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::sampler::Sampler;
    use std::path::Path;

    /// A room lit by one planar light (a parallelogram, or a triangle) with a Lambertian and
    /// a glossy material.
    fn scene(light: &str) -> Scene {
        let text = format!(
            r#"
[material.white]
type = "lambert"
albedo = [0.8, 0.7, 0.6]
[material.rough]
type = "roughconductor"
material = "Cu"
alpha_u = 0.2
alpha_v = 0.2
[[camera]]
name = "main"
type = "perspective"
origin = [0, 0, 0]
target = [1, 0, 0]
up = [0, 0, 1]
fov = 60
[[shape]]
type = "mesh"
material = "white"
positions = [[-5, -5, -2], [5, -5, -2], [5, 5, -2], [-5, 5, -2]]
indices = [[0, 1, 2], [0, 2, 3]]
[[shape]]
type = "sphere"
material = "rough"
center = [1, 1, -1]
radius = 0.8
[[shape]]
type = "mesh"
material = "white"
emission = [5, 5, 5]
{light}
"#
        );
        let desc = crate::scene::toml::parse_toml(Path::new("test.toml"), &text).unwrap();
        Scene::build(desc)
    }

    /// `lattice_v`, which the wavefront reads sample by sample, is the table's value for
    /// every sample index.
    #[test]
    fn lattice_v_is_the_table() {
        for j in 0..1000u32 {
            let t = LATTICE_V[(j % 256) as usize];
            assert_eq!(
                super::super::lattice_v(j).to_bits(),
                t.to_bits(),
                "sample {j}"
            );
        }
    }

    /// The eight-lane and four-lane batches give the same bits at random vertices, for
    /// Lambertian and other materials, parallelogram and triangle lights, and sample counts
    /// that fill a vector, leave lanes empty, and need more than one batch.
    #[test]
    fn lane_widths_agree_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            let quad = r#"positions = [[-1, -1, 3], [1, -1, 3], [1, 1, 3], [-1, 1, 3]]
indices = [[0, 2, 1], [0, 3, 2]]"#;
            let tri = r#"positions = [[-1, -1, 3], [1, -1, 3], [0, 1, 3]]
indices = [[0, 2, 1]]"#;
            let mut compared = 0;
            for light in [quad, tri] {
                let scene = scene(light);
                let planar_light = scene.lights.single_planar().expect("one planar light");
                let mut sampler = Sampler::from_state(7, 0);
                for k in 0..400 {
                    let [x, y, z] = sampler.next_3d();
                    let d = Vec3A::new(x - 0.5, y - 0.5, -z - 0.2).normalize();
                    let ray = Ray::new(Vec3A::new(0.0, 0.0, 1.0), d);
                    let Some(si) = scene.intersect(&ray) else {
                        continue;
                    };
                    let material = &scene.materials[si.material as usize];
                    let frame = Frame::from_normal(si.ns);
                    let wo = frame.to_local(-ray.d);
                    let n = [2, 8, 10, 16, 21][k % 5];
                    let (mut s4, mut s8) = (RayStats::default(), RayStats::default());
                    let vx = Vertex {
                        scene: &scene,
                        light: planar_light,
                        si: &si,
                        frame: &frame,
                        wo,
                        material,
                        n,
                        delta: sampler.next_3d(),
                    };
                    let run = |lambert: bool, stats: &mut RayStats, avx: bool| match (lambert, avx)
                    {
                        (true, false) => planar_in::<Vec4, true>(&vx, stats),
                        (false, false) => planar_in::<Vec4, false>(&vx, stats),
                        // SAFETY: the CPU has AVX, checked above.
                        (true, true) => unsafe { planar_avx::<true>(&vx, stats) },
                        (false, true) => unsafe { planar_avx::<false>(&vx, stats) },
                    };
                    let lambert = matches!(material.bsdf, Bsdf::Lambert(_));
                    if lambert && material.orient(wo).is_none() {
                        continue;
                    }
                    let a = run(lambert, &mut s4, false);
                    let b = run(lambert, &mut s8, true);
                    assert_eq!(
                        a.to_array().map(f32::to_bits),
                        b.to_array().map(f32::to_bits),
                        "vertex {k} ({n} samples): {a:?} with four lanes, {b:?} with eight"
                    );
                    assert_eq!(s4.shadow_rays, s8.shadow_rays);
                    compared += (a.max_element() > 0.0) as u32;
                }
            }
            assert!(compared > 300, "{compared} lit vertices compared");
        }
    }
}
