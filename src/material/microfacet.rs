//! Microfacet distributions, Beckmann and GGX (Trowbridge–Reitz), anisotropic, with Smith's
//! separable shadowing–masking and visible-normal sampling. The conventions are those of
//! Mitsuba 3's `MicrofacetDistribution` (include/mitsuba/render/microfacet.h), which the
//! rough BSDFs must match; one type serves both distributions, so the BSDFs have one code
//! path.
//!
//! - D(m): Beckmann, exp(−(m_x²/αu² + m_y²/αv²)/cos²θm) / (π αu αv cos⁴θm) (Beckmann and
//!   Spizzichino 1963; Walter et al., "Microfacet Models for Refraction through Rough
//!   Surfaces", EGSR 2007, eq. 25); GGX, 1 / (π αu αv (m_x²/αu² + m_y²/αv² + m_z²)²)
//!   (Trowbridge and Reitz 1975; Walter et al. 2007, eq. 33). The anisotropic forms are
//!   Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT
//!   3(2), 2014, eqs. 82 and 85.
//! - Λ(v), with a = 1/(α tan θ) and α the roughness projected on v's azimuth: Beckmann,
//!   (erf(a) − 1)/2 + exp(−a²)/(2a√π) (Heitz 2014, eq. 83); GGX, (−1 + √(1 + 1/a²))/2
//!   (eq. 86).
//! - G1(v, m) = 1/(1 + Λ(v)), zero when v sees the back of the microfacet (χ⁺(v·m / v·n)).
//!   For Beckmann, like Mitsuba, the rational approximation of Walter et al. 2007, eq. 27
//!   (< 0.35 % relative error; 1 for a ≥ 1.6); for GGX the exact 2/(1 + √(1 + 1/a²)).
//! - G(wo, wi, m) = G1(wo, m)·G1(wi, m): the separable form, as in Mitsuba (Walter et al.
//!   2007, eq. 23), not the height-correlated one.
//! - Visible normals D_wo(m) = G1(wo, m)·|wo·m|·D(m)/cos θo (Heitz and d'Eon, "Importance
//!   Sampling Microfacet-Based BSDFs using the Distribution of Visible Normals", EGSR 2014)
//!   are sampled by stretching wo to the configuration α = 1, sampling the slopes visible
//!   from it, and unstretching. GGX: Heitz, "Sampling the GGX Distribution of Visible
//!   Normals", JCGT 7(4), 2018, with the concentric disk map (the paper allows any
//!   area-preserving map; it is the one Mitsuba's `sample_visible_11` uses, so that
//!   quadratures over the warped square, like the rough plastic's transmittance table, see
//!   the same nodes). Beckmann: Jakob, "An Improved Visible Normal Sampling Routine for the
//!   Beckmann Distribution" (2014), a Newton inversion of the slope CDF in the erf domain
//!   that is continuous in the sample, as Mitsuba's `sample_visible_11`.

use super::sampling::disk_concentric;
use crate::simd::math::{exp, ln, poly};
use crate::simd::{Float, Vector3};
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

/// Which normal distribution (Mitsuba's `distribution` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetType {
    /// Gaussian random surfaces; Mitsuba's default.
    Beckmann,
    /// Trowbridge–Reitz, long-tailed.
    Ggx,
}

impl MicrofacetType {
    /// `beckmann` or `ggx`, in any case (as Mitsuba, which lowercases the value).
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "beckmann" => Some(MicrofacetType::Beckmann),
            "ggx" => Some(MicrofacetType::Ggx),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            MicrofacetType::Beckmann => "beckmann",
            MicrofacetType::Ggx => "ggx",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub kind: MicrofacetType,
    /// Roughness along the tangent (x) and bitangent (y) of the shading frame.
    pub alpha_u: f32,
    pub alpha_v: f32,
}

/// 1/√π.
const INV_SQRT_PI: f32 = 0.564_189_6;

impl Microfacet {
    /// Roughness below 1e-4 is clamped to 1e-4, as in Mitsuba (`configure()`).
    pub fn new(kind: MicrofacetType, alpha_u: f32, alpha_v: f32) -> Self {
        Microfacet {
            kind,
            alpha_u: alpha_u.max(1e-4),
            alpha_v: alpha_v.max(1e-4),
        }
    }

    /// Sets the roughness (a textured one, per hit), clamped as [`Microfacet::new`] does.
    #[inline]
    pub fn set_alpha(&mut self, alpha_u: f32, alpha_v: f32) {
        *self = Self::new(self.kind, alpha_u, alpha_v);
    }

    #[inline]
    pub fn set_alpha_u(&mut self, alpha_u: f32) {
        self.set_alpha(alpha_u, self.alpha_v);
    }

    #[inline]
    pub fn set_alpha_v(&mut self, alpha_v: f32) {
        self.set_alpha(self.alpha_u, alpha_v);
    }

    pub fn ggx(alpha_u: f32, alpha_v: f32) -> Self {
        Self::new(MicrofacetType::Ggx, alpha_u, alpha_v)
    }

    pub fn beckmann(alpha_u: f32, alpha_v: f32) -> Self {
        Self::new(MicrofacetType::Beckmann, alpha_u, alpha_v)
    }

    /// The normal distribution D(m) (zero for m below the surface; like Mitsuba, values with
    /// D·cos θm ≤ 1e-20 are flushed to zero).
    #[inline]
    pub fn d(&self, m: Vec3A) -> f32 {
        match self.kind {
            MicrofacetType::Beckmann => self.as_beckmann().d(m),
            MicrofacetType::Ggx => self.as_ggx().d(m),
        }
    }

    /// This distribution as GGX of one lane.
    #[inline(always)]
    fn as_ggx(&self) -> Ggx<f32> {
        Ggx {
            alpha_u: self.alpha_u,
            alpha_v: self.alpha_v,
        }
    }

    /// This distribution as Beckmann's of one lane.
    #[inline(always)]
    fn as_beckmann(&self) -> Beckmann<f32> {
        Beckmann {
            alpha_u: self.alpha_u,
            alpha_v: self.alpha_v,
        }
    }

    /// Smith's Λ(v), exact (for Beckmann, `g1` uses Walter's approximation of 1/(1 + Λ)).
    #[inline]
    pub fn lambda(&self, v: Vec3A) -> f32 {
        let t2 = tan_alpha2(self.alpha_u, self.alpha_v, v);
        if t2 == 0.0 {
            return 0.0;
        }
        match self.kind {
            MicrofacetType::Beckmann => {
                // (erf(a) − 1)/2 + exp(−a²)/(2a√π), with erf(a) − 1 = −erfc(a) taken as it is
                // rather than from erf (which would cancel to nothing for large a).
                let a = (1.0 / t2).sqrt();
                0.5 * (exp(-a * a) * INV_SQRT_PI / a - erfc_pos(a))
            }
            MicrofacetType::Ggx => 0.5 * (-1.0 + (1.0 + t2).sqrt()),
        }
    }

    /// Smith's masking G1(v, m) ≈ 1/(1 + Λ(v)), zero when v and the macro-normal disagree
    /// about the side of m (Mitsuba's `smith_g1`).
    #[inline]
    pub fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        match self.kind {
            MicrofacetType::Beckmann => self.as_beckmann().g1(v, m),
            MicrofacetType::Ggx => self.as_ggx().g1(v, m),
        }
    }

    /// The separable shadowing–masking G1(wo, m)·G1(wi, m).
    #[inline]
    pub fn g(&self, wo: Vec3A, wi: Vec3A, m: Vec3A) -> f32 {
        self.g1(wo, m) * self.g1(wi, m)
    }

    /// Samples a microfacet normal from the distribution of normals visible from `wo`
    /// (`wo.z > 0`).
    #[inline]
    pub fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        match self.kind {
            MicrofacetType::Ggx => self.as_ggx().sample_visible(wo, u.x, u.y),
            MicrofacetType::Beckmann => self.as_beckmann().sample_visible(wo, u.x, u.y),
        }
    }

    /// Density of `sample_visible` over microfacet normals: D_wo(m) = G1(wo, m)·|wo·m|·D(m)
    /// / cos θo (Heitz and d'Eon 2014, eq. 2).
    #[inline]
    pub fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.d(m) * self.g1(wo, m) * wo.dot(m).abs() / wo.z
    }
}

/// A microfacet distribution over any lanes: what the rough BSDFs' maths is written over,
/// once for one path ([`Microfacet`], either kind) and for lanes of paths ([`Ggx`]).
pub trait Distribution<V: Vector3> {
    /// D(m), flushed to zero as [`Microfacet::d`].
    fn d(&self, m: V) -> V::F;
    /// Smith's G1(v, m), as [`Microfacet::g1`].
    fn g1(&self, v: V, m: V) -> V::F;
    /// A normal visible from `wo` (`wo.z > 0`) for the numbers (`ux`, `uy`).
    fn sample_visible(&self, wo: V, ux: V::F, uy: V::F) -> V;
    /// D_wo(m), as [`Microfacet::pdf_visible`].
    #[inline(always)]
    fn pdf_visible(&self, wo: V, m: V) -> V::F {
        let zero = V::F::zero();
        let p = self.d(m) * self.g1(wo, m) * wo.dot(m).abs() / wo.z();
        V::F::select(wo.z().le(zero), zero, p)
    }
}

impl Distribution<Vec3A> for Microfacet {
    #[inline(always)]
    fn d(&self, m: Vec3A) -> f32 {
        Microfacet::d(self, m)
    }
    #[inline(always)]
    fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        Microfacet::g1(self, v, m)
    }
    #[inline(always)]
    fn sample_visible(&self, wo: Vec3A, ux: f32, uy: f32) -> Vec3A {
        Microfacet::sample_visible(self, wo, Vec2::new(ux, uy))
    }
    #[inline(always)]
    fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        Microfacet::pdf_visible(self, wo, m)
    }
}

/// GGX of roughness (`alpha_u`, `alpha_v`) in each lane, clamped as [`Microfacet::new`]
/// clamps it: [`Microfacet`]'s GGX, whose methods call these.
#[derive(Clone, Copy, Debug)]
pub struct Ggx<F> {
    pub alpha_u: F,
    pub alpha_v: F,
}

impl<V: Vector3> Distribution<V> for Ggx<V::F> {
    #[inline(always)]
    fn d(&self, m: V) -> V::F {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (x, y) = (m.x() / au, m.y() / av);
        let t = (x * x + y * y) + m.z() * m.z();
        let one = V::F::splat(1.0);
        flush(one / (V::F::splat(PI) * au * av * t * t), m.z())
    }

    #[inline(always)]
    fn g1(&self, v: V, m: V) -> V::F {
        let one = V::F::splat(1.0);
        let t2 = tan_alpha2(self.alpha_u, self.alpha_v, v);
        visible(v, m, t2, V::F::splat(2.0) / (one + (one + t2).sqrt()))
    }

    /// Heitz 2018, listing 1, with the disk point's first coordinate along −T1 and T1 = y at
    /// normal incidence: the orientation of Mitsuba's slope-space form (`sample_visible_11`,
    /// whose azimuth frame is that of `Frame3f::sincos_phi`), so that the same random numbers
    /// give Mitsuba's normal.
    #[inline(always)]
    fn sample_visible(&self, wo: V, ux: V::F, uy: V::F) -> V {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (zero, one, k) = (V::F::zero(), V::F::splat(1.0), V::F::splat);
        // Stretch wo to the configuration with α = 1 (the hemisphere).
        let vh = stretch(au, av, wo);
        // An orthonormal basis around vh (T1 is perpendicular to the plane of incidence).
        let len2 = vh.x() * vh.x() + vh.y() * vh.y();
        let t1 = V::select(
            len2.gt(k(4.0 * f32::EPSILON / 2.0)),
            V::new(-vh.y(), vh.x(), zero).div(len2.sqrt()),
            V::new(zero, one, zero),
        );
        let t2 = vh.cross(t1);
        // A point on the disk, squeezed onto the part of the projected hemisphere visible
        // from vh.
        let (px, py) = disk_concentric(ux, uy);
        let s = k(0.5) * (one + vh.z());
        let p1 = px;
        let p2 = (one - s) * (one - p1 * p1).max_num(zero).sqrt() + s * py;
        // Reproject onto the hemisphere, then unstretch.
        let up = (one - p1 * p1 - p2 * p2).max_num(zero).sqrt();
        let nh = t2.scale(p2) - t1.scale(p1) + vh.scale(up);
        V::new(au * nh.x(), av * nh.y(), nh.z().max_num(zero)).normalize()
    }
}

/// Beckmann's distribution of roughness (`alpha_u`, `alpha_v`) in each lane, clamped as
/// [`Microfacet::new`] clamps it: [`Microfacet`]'s Beckmann, whose methods call these.
#[derive(Clone, Copy, Debug)]
pub struct Beckmann<F> {
    pub alpha_u: F,
    pub alpha_v: F,
}

impl<V: Vector3> Distribution<V> for Beckmann<V::F> {
    #[inline(always)]
    fn d(&self, m: V) -> V::F {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (x, y) = (m.x() / au, m.y() / av);
        let xy = x * x + y * y;
        let c2 = m.z() * m.z();
        let pi = V::F::splat(PI);
        flush(exp(-xy / c2) / (pi * au * av * c2 * c2), m.z())
    }

    /// Walter's rational approximation of 1/(1 + Λ) (1 for a ≥ 1.6).
    #[inline(always)]
    fn g1(&self, v: V, m: V) -> V::F {
        let (one, k) = (V::F::splat(1.0), V::F::splat);
        let t2 = tan_alpha2(self.alpha_u, self.alpha_v, v);
        let a = (one / t2).sqrt();
        // (The rational function only where a lane needs it.)
        let near = !a.ge(k(1.6));
        let mut g = one;
        if V::F::any(near) {
            let r = (k(3.535) * a + k(2.181) * a * a) / (one + k(2.276) * a + k(2.577) * a * a);
            g = V::F::select(near, r, one);
        }
        visible(v, m, t2, g)
    }

    /// Heitz and d'Eon 2014 (stretch, sample slopes for α = 1, rotate, unstretch) with
    /// Jakob's slope sampler; Mitsuba's `sample` with `sample_visible`.
    #[inline(always)]
    fn sample_visible(&self, wo: V, ux: V::F, uy: V::F) -> V {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (zero, one, k) = (V::F::zero(), V::F::splat(1.0), V::F::splat);
        let w = stretch(au, av, wo);
        // The azimuth of the stretched direction (Mitsuba's `Frame3f::sincos_phi`).
        let s2 = w.x() * w.x() + w.y() * w.y();
        let along = s2.le(k(4.0 * f32::EPSILON / 2.0));
        let inv = one / s2.sqrt();
        let sin_phi = V::F::select(along, zero, clamp(w.y() * inv, -one, one));
        let cos_phi = V::F::select(along, one, clamp(w.x() * inv, -one, one));
        let (sx, sy) = beckmann_slopes_11(w.z(), ux, uy);
        let x = (cos_phi * sx - sin_phi * sy) * au;
        let y = (sin_phi * sx + cos_phi * sy) * av;
        V::new(-x, -y, one).normalize()
    }
}

/// `f32::clamp` over lanes: `lo` below it, `hi` above it, x itself otherwise (NaN too).
#[inline(always)]
fn clamp<T: Float>(x: T, lo: T, hi: T) -> T {
    T::select(x.lt(lo), lo, T::select(x.gt(hi), hi, x))
}

/// Beckmann's distribution in the lanes of `beckmann`, GGX in the others, each of roughness
/// (`alpha_u`, `alpha_v`): the wavefront's, whose lanes hold different materials. Each
/// method computes a distribution's value only where a lane has it.
#[derive(Clone, Copy, Debug)]
pub struct Either<F: Float> {
    pub beckmann: F::Mask,
    pub alpha_u: F,
    pub alpha_v: F,
}

impl<F: Float> Either<F> {
    /// The two distributions, and which of them the lanes have: (any Beckmann, any GGX).
    #[inline(always)]
    fn parts(&self) -> (Beckmann<F>, Ggx<F>, bool, bool) {
        let (alpha_u, alpha_v) = (self.alpha_u, self.alpha_v);
        (
            Beckmann { alpha_u, alpha_v },
            Ggx { alpha_u, alpha_v },
            F::any(self.beckmann),
            F::any(!self.beckmann),
        )
    }
}

impl<V: Vector3> Distribution<V> for Either<V::F> {
    #[inline(always)]
    fn d(&self, m: V) -> V::F {
        match self.parts() {
            (b, _, true, false) => b.d(m),
            (_, g, false, _) => g.d(m),
            (b, g, true, true) => V::F::select(self.beckmann, b.d(m), g.d(m)),
        }
    }

    #[inline(always)]
    fn g1(&self, v: V, m: V) -> V::F {
        match self.parts() {
            (b, _, true, false) => b.g1(v, m),
            (_, g, false, _) => g.g1(v, m),
            (b, g, true, true) => V::F::select(self.beckmann, b.g1(v, m), g.g1(v, m)),
        }
    }

    #[inline(always)]
    fn sample_visible(&self, wo: V, ux: V::F, uy: V::F) -> V {
        match self.parts() {
            (b, _, true, false) => b.sample_visible(wo, ux, uy),
            (_, g, false, _) => g.sample_visible(wo, ux, uy),
            (b, g, true, true) => V::select(
                self.beckmann,
                b.sample_visible(wo, ux, uy),
                g.sample_visible(wo, ux, uy),
            ),
        }
    }
}

/// G1 where v sees the front of m (v and the macro-normal agree about m's side), of value
/// `g` but 1 at normal incidence (t2, (α tan θ)², zero); zero elsewhere.
#[inline(always)]
fn visible<V: Vector3>(v: V, m: V, t2: V::F, g: V::F) -> V::F {
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let g = V::F::select(t2.eq(zero), one, g);
    V::F::select((v.dot(m) * v.z()).le(zero), zero, g)
}

/// `wo` stretched to the configuration with α = 1, unit length.
#[inline(always)]
fn stretch<V: Vector3>(alpha_u: V::F, alpha_v: V::F, wo: V) -> V {
    V::new(alpha_u * wo.x(), alpha_v * wo.y(), wo.z()).normalize()
}

/// D where D·cos θm > 1e-20, else zero (Mitsuba's flush; NaN, m in the plane, fails the
/// comparison too).
#[inline(always)]
fn flush<T: Float>(d: T, cos_m: T) -> T {
    T::select((d * cos_m).gt(T::splat(1e-20)), d, T::zero())
}

/// (α tan θ)² of v, α projected on v's azimuth; zero at normal incidence.
#[inline(always)]
fn tan_alpha2<V: Vector3>(alpha_u: V::F, alpha_v: V::F, v: V) -> V::F {
    let (x, y) = (alpha_u * v.x(), alpha_v * v.y());
    let xy = x * x + y * y;
    let zero = V::F::zero();
    V::F::select(xy.eq(zero), zero, xy / (v.z() * v.z()))
}

/// The slopes of a Beckmann surface of α = 1 visible from a direction at cos θ = `cos_theta`
/// in the xz-plane (Jakob 2014): the x slope inverts its CDF, 1 + x + tan θ·exp(−erfinv(x)²)/√π
/// over its maximum, in the erf domain x = erf(slope) by three Newton steps from the exact
/// solution for θ = π/2; the y slope is Gaussian, independent. Mitsuba's `sample_visible_11`.
#[inline(always)]
fn beckmann_slopes_11<T: Float>(cos_theta: T, ux: T, uy: T) -> (T, T) {
    let (zero, one, k) = (T::zero(), T::splat(1.0), T::splat);
    let tan_theta = (one - cos_theta * cos_theta).max_num(zero).sqrt() / cos_theta;
    let cot_theta = one / tan_theta;
    // The search interval [−1, maxval] in the erf domain.
    let maxval = erf(cot_theta);
    let (lo, hi) = (k(1e-6), k(1.0 - 1e-6));
    let (ux, uy) = (ux.max_num(lo).min_num(hi), uy.max_num(lo).min_num(hi));
    let mut x = maxval - (maxval + one) * erf((-ln(ux)).sqrt());
    // Normalisation of the CDF.
    let c = k(INV_SQRT_PI);
    let target = ux * (one + maxval + c * tan_theta * exp(-cot_theta * cot_theta));
    for _ in 0..3 {
        let slope = erfinv(x);
        let value = one + x + c * tan_theta * exp(-slope * slope) - target;
        let derivative = one - slope * tan_theta;
        x = x - value / derivative;
    }
    (erfinv(x), erfinv(k(2.0) * uy - one))
}

/// The error function: 1 − erfc(|x|), signed (absolute error below 2·10⁻⁷: the fit's 1.2·10⁻⁷
/// and f32's rounding).
#[inline(always)]
fn erf<T: Float>(x: T) -> T {
    (T::splat(1.0) - erfc_pos(x.abs())).copysign(x)
}

/// erfc(z) for z ≥ 0, the fit with a fractional error below 1.2·10⁻⁷ everywhere of Numerical
/// Recipes (2nd ed., §6.2, `erfcc`: t·exp(−z² + P(t)), t = 1/(1 + z/2), a Chebyshev fit),
/// in f32 (Dr.Jit's `erf`, which Mitsuba's sampler uses, is a fit of this order too). It
/// replaced a 28-term Chebyshev series to double precision, whose recurrence is a chain of
/// 27 dependent steps: with the Newton step of `erfinv`, seven of them a Beckmann sample
/// took half the time of a Cornell box of rough conductors.
#[allow(clippy::excessive_precision)]
#[inline(always)]
fn erfc_pos<T: Float>(z: T) -> T {
    let (one, k) = (T::splat(1.0), T::splat);
    let t = one / (one + k(0.5) * z);
    let p = poly(
        t,
        [
            -1.265_512_23,
            1.000_023_68,
            0.374_091_96,
            0.096_784_18,
            -0.186_288_06,
            0.278_868_07,
            -1.135_203_98,
            1.488_515_87,
            -0.822_152_23,
            0.170_872_77,
        ],
    );
    t * exp(p - z * z)
}

/// The inverse error function on (−1, 1) (±∞ at ±1): Giles, "Approximating the erfinv
/// function", GPU Computing Gems Jade Edition, 2011, the single-precision polynomials
/// (relative error about 4·10⁻⁷; Dr.Jit's `erfinv`, as Mitsuba's sampler uses it), both
/// branches evaluated and one chosen, as lanes must.
// (The coefficients as Giles prints them, some with more digits than an f32 holds.)
#[allow(clippy::excessive_precision)]
#[inline(always)]
fn erfinv<T: Float>(x: T) -> T {
    let (one, k) = (T::splat(1.0), T::splat);
    let w = -ln((one - x) * (one + x));
    let central = poly(
        w - k(2.5),
        [
            1.501_409_41,
            0.246_640_727,
            -0.004_177_681_64,
            -0.001_253_725_03,
            0.000_218_580_87,
            -4.391_506_54e-06,
            -3.523_387_7e-06,
            3.432_739_39e-07,
            2.810_226_36e-08,
        ],
    );
    // The tail (|x| > 0.9966) only where a lane needs it.
    let far = !w.lt(k(5.0));
    if !T::any(far) {
        return central * x;
    }
    let t = w.sqrt() - k(3.0);
    let tail = poly(
        t,
        [
            2.832_976_82,
            1.001_674_06,
            0.009_438_870_47,
            -0.007_622_461_3,
            0.005_739_507_73,
            -0.003_673_428_44,
            0.001_349_343_22,
            0.000_100_950_558,
            -0.000_200_214_257,
        ],
    );
    let r = T::select(far, tail, central) * x;
    let r = T::select(x.ge(one), k(f32::INFINITY), r);
    T::select(x.le(-one), k(f32::NEG_INFINITY), r)
}

/// Reflects `wo` about the microfacet normal `m`.
#[inline]
pub fn reflect_about(wo: Vec3A, m: Vec3A) -> Vec3A {
    reflect_about_lanes(wo, m)
}

/// [`reflect_about`] over any lanes.
#[inline(always)]
pub fn reflect_about_lanes<V: Vector3>(wo: V, m: V) -> V {
    m.scale(V::F::splat(2.0) * wo.dot(m)) - wo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// erfc and erf against Python's `math.erfc` and `math.erf` (to double precision), and
    /// erfinv as erf's inverse: each within the error its fit claims and f32's rounding. (A coefficient off by
    /// 10⁻⁵, in either fit's either branch, fails it.)
    #[test]
    fn error_functions_match_known_values() {
        for (x, erf_x, erfc_x) in [
            (1e-4, 0.00011283791633342487, 0.9998871620836666),
            (0.1, 0.1124629160182849, 0.8875370839817152),
            (0.5, 0.5204998778130465, 0.4795001221869535),
            (1.0, 0.8427007929497149, 0.15729920705028513),
            (1.5, 0.9661051464753108, 0.033894853524689274),
            (2.0, 0.9953222650189527, 0.004677734981047265),
            (3.0, 0.9999779095030014, 2.2090496998585438e-05),
            (4.0, 0.9999999845827421, 1.541725790028002e-08),
        ] {
            let x = x as f32;
            let e = erfc_pos(x) as f64;
            // The fit's error, plus f32's: e^(P − z²) turns the exponent's rounding (half an
            // ulp of about z² + 1.3) into a relative error, and the rest rounds a few times.
            let ulp = f32::EPSILON as f64 / 2.0;
            let tol = 1.2e-7 + ((x * x) as f64 + 1.3) * ulp + 4.0 * ulp;
            assert!(
                (e - erfc_x).abs() <= tol * erfc_x,
                "erfc({x}) = {e}, not {erfc_x}"
            );
            // erf = 1 − erfc: erfc's error, and the subtraction's rounding.
            assert!(
                (erf(x) as f64 - erf_x).abs() <= 2.5e-7,
                "erf({x}) = {}, not {erf_x}",
                erf(x)
            );
            assert_eq!(erf(-x), -erf(x));
        }
        // erf to double precision by its Maclaurin series, for erfinv's reference.
        let erf_series = |y: f64| {
            let (mut term, mut sum) = (y, y);
            for n in 1..80 {
                term *= -y * y / n as f64;
                sum += term / (2 * n + 1) as f64;
            }
            sum * 2.0 / std::f64::consts::PI.sqrt()
        };
        assert!((erf_series(1.0) - 0.8427007929497149).abs() < 1e-14);
        for i in 1..300 {
            // y from 0.01 to 2.99: erf(y) from 0.011 to 1 − 2.6e-5.
            let y = i as f64 * 0.01;
            let x = erf_series(y) as f32;
            let back = erfinv(x) as f64;
            // The slope of erfinv at x, times x's own rounding, bounds what it can undo.
            let slope = std::f64::consts::PI.sqrt() / 2.0 * (y * y).exp();
            let tol = 1e-6 * y + slope * (f32::EPSILON as f64) * x as f64;
            assert!((back - y).abs() <= tol, "erfinv(erf({y})) = {back}");
            assert_eq!(erfinv(-x), -erfinv(x));
        }
    }
}
