//! Shading frames and BSDF sampling, lane by lane: `Frame`, `Material::orient` and
//! `Material::sample` for the Lambertian, mirror and glass BSDFs, each operation the scalar
//! code's ([`crate::geometry::Frame`], [`crate::material`]).

use super::simd::{F, M, V3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

/// `Frame::from_normal` (Duff et al. 2017) of unit normals `n`.
#[derive(Clone, Copy)]
pub struct Frame16 {
    pub s: V3,
    pub t: V3,
    pub n: V3,
}

impl Frame16 {
    #[inline(always)]
    pub fn new(n: V3) -> Frame16 {
        let one = F::splat(1.0);
        let sign = F::copysign(one, n.z);
        let a = F::splat(-1.0) / (sign + n.z);
        let b = (n.x * n.y) * a;
        Frame16 {
            s: V3 {
                x: one + ((sign * n.x) * n.x) * a,
                y: sign * b,
                z: (-sign) * n.x,
            },
            t: V3 {
                x: b,
                y: sign + (n.y * n.y) * a,
                z: -n.y,
            },
            n,
        }
    }
    #[inline(always)]
    pub fn to_local(self, v: V3) -> V3 {
        V3 {
            x: v.dot(self.s),
            y: v.dot(self.t),
            z: v.dot(self.n),
        }
    }
    #[inline(always)]
    pub fn to_world(self, v: V3) -> V3 {
        (self.s.scale(v.x) + self.t.scale(v.y)) + self.n.scale(v.z)
    }
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

/// `sampling::square_to_cosine_hemisphere` (the concentric map, then z = √(1 − r²)).
#[inline(always)]
pub fn cosine_hemisphere(ux: F, uy: F) -> V3 {
    let (zero, one) = (F::zero(), F::splat(1.0));
    let (ox, oy) = (F::splat(2.0) * ux - one, F::splat(2.0) * uy - one);
    let centre = ox.eq(zero) & oy.eq(zero);
    let xmaj = ox.abs().gt(oy.abs());
    let r = F::select(xmaj, ox, oy);
    let ratio = F::select(xmaj, oy, ox) / F::select(xmaj, ox, oy);
    let (sn, cs) = sin_cos_quarter(F::splat(FRAC_PI_4) * ratio);
    let x = F::select(centre, zero, F::select(xmaj, r * cs, r * sn));
    let y = F::select(centre, zero, F::select(xmaj, r * sn, r * cs));
    let z = (one - (x * x + y * y)).max_num(zero).sqrt();
    V3 { x, y, z }
}

/// `dielectric::fresnel_dielectric(cos_i, eta)`.
#[inline(always)]
pub fn fresnel_dielectric(cos_i: F, eta: F) -> F {
    let one = F::splat(1.0);
    // `f32::clamp(-1, 1)`, NaN kept.
    let c = F::select(cos_i.lt(-one), -one, cos_i);
    let c = F::select(c.gt(one), one, c);
    let inside = c.lt(F::zero());
    let e = F::select(inside, one / eta, eta);
    let c = F::select(inside, -c, c);
    let sin2_i = one - c * c;
    let sin2_t = sin2_i / (e * e);
    let cos_t = (one - sin2_t).max_num(F::zero()).sqrt();
    let r_parl = (e * c - cos_t) / (e * c + cos_t);
    let r_perp = (c - e * cos_t) / (c + e * cos_t);
    let f = F::splat(0.5) * (r_parl * r_parl + r_perp * r_perp);
    F::select(sin2_t.ge(one), one, f)
}

/// `dielectric::refract_local(wi, eta)`: the refracted direction, the relative index
/// crossed, and the lanes where it exists (no total internal reflection).
#[inline(always)]
pub fn refract(wi: V3, eta: F) -> (V3, F, M) {
    let (zero, one) = (F::zero(), F::splat(1.0));
    let inside = wi.z.lt(zero);
    let e = F::select(inside, one / eta, eta);
    let cos_i = F::select(inside, -wi.z, wi.z);
    // The normal, +z or −z (whose x and y are −0, as `-Vec3A::Z` has them).
    let nxy = F::select(inside, F::splat(-0.0), zero);
    let nz = F::select(inside, -one, one);
    let sin2_i = (one - cos_i * cos_i).max_num(zero);
    let sin2_t = sin2_i / (e * e);
    let ok = !sin2_t.ge(one);
    let cos_t = (one - sin2_t).sqrt();
    let k = cos_i / e - cos_t;
    let w = V3 {
        x: (-wi.x) / e + k * nxy,
        y: (-wi.y) / e + k * nxy,
        z: (-wi.z) / e + k * nz,
    };
    (w, e, ok)
}

/// The lanes' BSDF samples (`Material::sample` in radiance mode).
pub struct Sample {
    /// Lanes with a sample (the others end their path).
    pub ok: M,
    /// Local direction, throughput weight, solid-angle pdf (0 for delta lobes), relative
    /// index of refraction crossed (1 for reflection).
    pub wi: V3,
    pub weight: V3,
    pub pdf: F,
    pub eta: F,
}

/// The BSDF samples of lanes with Lambertian (`lambert`), mirror (`mirror`) and glass
/// (`glass`) materials: `colour` the albedo or reflectance, `eta` the glass's index,
/// `oriented` and `side` what `Material::orient` gives (glass: every lane, side 1).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn sample(
    wo: V3,
    [ux, uy, u1]: [F; 3],
    colour: V3,
    eta: F,
    (lambert, mirror, glass): (M, M, M),
    oriented: M,
    side: F,
) -> Sample {
    let (zero, one) = (F::zero(), F::splat(1.0));
    // Lambertian: the cosine-weighted hemisphere on the side `wo` is on.
    let h = cosine_hemisphere(ux, uy);
    let lambert_ok = lambert & oriented & !h.z.le(zero);
    let pdf = F::select(lambert, h.z.max_num(zero) * F::splat(FRAC_1_PI), zero);
    // Mirror: `reflect_local` of wo on its side, then back (`Mirror::sample`).
    let mirrored = V3 {
        x: -wo.x,
        y: -wo.y,
        z: (wo.z * side) * side,
    };
    // Glass (`Dielectric::sample`): reflect with probability F, else refract.
    let f = fresnel_dielectric(wo.z, eta);
    let reflects = u1.lt(f);
    let (refracted, etap, refracts) = refract(wo, eta);
    let glass_ok = glass & (reflects | refracts);
    let glass_reflects = glass & reflects;
    let reflected = V3 {
        x: -wo.x,
        y: -wo.y,
        z: wo.z,
    };
    let scale = one / (etap * etap);
    let wi = V3::select(
        lambert,
        V3 {
            x: h.x,
            y: h.y,
            z: h.z * side,
        },
        V3::select(
            mirror,
            mirrored,
            V3::select(glass_reflects, reflected, refracted),
        ),
    );
    let weight = V3::select(
        lambert | mirror,
        colour,
        V3::select(
            glass_reflects,
            V3::splat([1.0; 3]),
            V3 {
                x: scale,
                y: scale,
                z: scale,
            },
        ),
    );
    Sample {
        ok: lambert_ok | (mirror & oriented) | glass_ok,
        wi,
        weight,
        pdf,
        eta: F::select(glass & !reflects, etap, one),
    }
}
