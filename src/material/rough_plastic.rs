//! Rough plastic: a diffuse base under a rough (Beckmann or GGX) dielectric coating, as
//! Mitsuba 3's `roughplastic` (isotropic only, like Mitsuba's). The coating
//! reflects by the microfacet BRDF f_s = F(wo·h)·D(h)·G(wo, wi, h)/(4 cos θo cos θi) (Walter et
//! al., EGSR 2007, eq. 20); the base is seen through it as
//!
//!   f_d = ρ'/π · T(θo)·T(θi) / η²,  ρ' = ρ/(1 − R_int)  (ρ/(1 − ρ R_int) with `nonlinear`),
//!
//! where T(θ) is the rough coating's total transmittance from outside at incidence θ and
//! R_int its internal diffuse reflectance; this is the approximation of Kelemen and
//! Szirmay-Kalos, "A Microfacet Based Coupled Specular-Matte BRDF Model with Importance
//! Sampling", Eurographics 2001, in Mitsuba's form. Like Mitsuba, T is tabulated at 64
//! evenly spaced cos θ (linear interpolation) and R_int is a single number, both computed
//! once per (distribution, α, η) by Gauss–Legendre quadrature over the visible-normal sampling square
//! (Mitsuba's `eval_transmittance` and `eval_reflectance` in microfacet.h). The tables are
//! cached for the life of the program and referenced by a `&'static`, so the BSDF stays
//! `Copy` and small and evaluation allocates nothing.
//!
//! Lobe selection: the specular lobe with probability (1 − T(θo))·w / ((1 − T(θo))·w +
//! T(θo)·(1 − w)), w = s̄/(d̄ + s̄); the diffuse one cosine-weighted. `pdf` is the mixture.
//!
//! The maths is written once over lanes ([`Coated`]): one path's BSDF runs it in one lane,
//! the wavefront in sixteen, each lane reading its own coating table.

use super::dielectric::{fresnel_dielectric_lanes, fresnel_refraction_lanes};
use super::microfacet::MicrofacetType;
use super::microfacet::{reflect_about_lanes, Distribution, Microfacet};
use super::plastic::mean;
use super::sampling::{cosine_hemisphere, cosine_hemisphere_pdf_lanes};
use super::BsdfSample;
use crate::simd::{Float, Mask, Vector3};
use crate::Color;
use glam::{Vec2, Vec3A};
use std::f32::consts::FRAC_1_PI;
use std::sync::Mutex;

/// Resolution of the transmittance table (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub const TRANSMITTANCE_RES: usize = 64;

/// The precomputed coating terms for one (α, η).
#[derive(Debug)]
pub struct CoatingTable {
    /// T(cos θ) at cos θ = max(k/63, 1e-6), k = 0..63.
    pub transmittance: [f32; TRANSMITTANCE_RES],
    /// R_int: the coating's diffuse reflectance from inside.
    pub internal_reflectance: f32,
}

impl CoatingTable {
    /// Linear interpolation in the table ([`lerp_table`]).
    #[inline]
    pub fn transmittance(&self, cos_theta: f32) -> f32 {
        lerp_table(&self.transmittance, 0.0, cos_theta)
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton's method on the three-term
/// recurrence of the Legendre polynomials; Numerical Recipes 3rd ed. §4.6, `gauleg`).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    let m = n.div_ceil(2);
    for i in 0..m {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut pp;
        loop {
            let (mut p1, mut p2) = (1.0, 0.0);
            for j in 0..n {
                let p3 = p2;
                p2 = p1;
                p1 = ((2.0 * j as f64 + 1.0) * z * p2 - j as f64 * p3) / (j as f64 + 1.0);
            }
            pp = n as f64 * (z * p1 - p2) / (z * z - 1.0);
            let z1 = z;
            z = z1 - p1 / pp;
            if (z - z1).abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * pp * pp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// ∫ over visible normals of the energy leaving through the interface (`transmit`) or
/// reflected back (`!transmit`), seen from `wi` (wi.z > 0), by n×n Gauss–Legendre quadrature
/// on the sampling square (`rule`: [`gauss_legendre`]`(n)`): E[G1(w', m)·(1 − F or F)].
/// The integrand is evaluated sixteen points at a time where the CPU has AVX-512 or AVX
/// ([`coating_terms`] in lanes: the same bits) and summed in order in f64 either way, so the
/// table does not depend on the CPU.
fn coating_integral(
    distr: &Microfacet,
    wi: Vec3A,
    eta: f32,
    rule: &(Vec<f64>, Vec<f64>),
    transmit: bool,
) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if rule.0.len().is_multiple_of(16) {
        // SAFETY: each form runs only where the CPU has its features.
        if crate::cpu::avx512() {
            return unsafe { lanes::integral_avx512(distr, wi, eta, rule, transmit) };
        }
        if std::arch::is_x86_feature_detected!("avx") {
            return unsafe { lanes::integral_avx(distr, wi, eta, rule, transmit) };
        }
    }
    integral_one_by_one(distr, wi, eta, rule, transmit)
}

/// [`coating_integral`] a point at a time.
fn integral_one_by_one(
    distr: &Microfacet,
    wi: Vec3A,
    eta: f32,
    rule: &(Vec<f64>, Vec<f64>),
    transmit: bool,
) -> f32 {
    let (x, w) = rule;
    let mut sum = 0.0f64;
    for a in 0..x.len() {
        for b in 0..x.len() {
            let (ux, uy) = ((x[a] * 0.5 + 0.5) as f32, (x[b] * 0.5 + 0.5) as f32);
            let v = coating_terms(distr, wi, eta, ux, uy, transmit);
            sum += v as f64 * w[a] * w[b] * 0.25;
        }
    }
    sum as f32
}

/// [`coating_integral`]'s integrand at the sampling-square points (`ux`, `uy`) of the lanes.
#[inline(always)]
fn coating_terms<V, D>(distr: &D, wi: V, eta: V::F, ux: V::F, uy: V::F, transmit: bool) -> V::F
where
    V: Vector3,
    D: Distribution<V>,
{
    let (zero, one) = (V::F::zero(), V::F::splat(1.0));
    let m = distr.sample_visible(wi, ux, uy);
    let wi_m = wi.dot(m);
    if transmit {
        let (f, cos_t, _, eta_ti) = fresnel_refraction_lanes(wi_m, eta);
        let wt = m.scale(wi_m * eta_ti + cos_t) - wi.scale(eta_ti);
        V::F::select(
            (wt.z() * wi.z()).ge(zero),
            zero,
            distr.g1(wt, m) * (one - f),
        )
    } else {
        let wr = reflect_about_lanes(wi, m);
        let v = distr.g1(wr, m) * fresnel_dielectric_lanes(wi_m, eta);
        V::F::select(wr.z().le(zero), zero, v)
    }
}

/// [`coating_integral`] sixteen points at a time.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use super::coating_terms;
    use crate::material::microfacet::{Beckmann, Distribution, Ggx, Microfacet, MicrofacetType};
    use crate::simd::{Sixteen, Vector3, V3};
    use glam::Vec3A;

    /// The sum over the square with `F` lanes along its second axis, as the scalar loop
    /// adds it.
    #[inline(always)]
    fn integral<F: Sixteen>(
        distr: &Microfacet,
        wi: Vec3A,
        eta: f32,
        (x, w): &(Vec<f64>, Vec<f64>),
        transmit: bool,
    ) -> f32 {
        let (alpha_u, alpha_v) = (F::splat(distr.alpha_u), F::splat(distr.alpha_v));
        match distr.kind {
            MicrofacetType::Ggx => sum(&Ggx { alpha_u, alpha_v }, wi, eta, x, w, transmit),
            MicrofacetType::Beckmann => {
                sum(&Beckmann { alpha_u, alpha_v }, wi, eta, x, w, transmit)
            }
        }
    }

    #[inline(always)]
    fn sum<F: Sixteen, D: Distribution<V3<F>>>(
        distr: &D,
        wi: Vec3A,
        eta: f32,
        x: &[f64],
        w: &[f64],
        transmit: bool,
    ) -> f32 {
        let (wi, eta) = (V3::<F>::broadcast(wi), F::splat(eta));
        let mut total = 0.0f64;
        for a in 0..x.len() {
            let ux = F::splat((x[a] * 0.5 + 0.5) as f32);
            for b0 in (0..x.len()).step_by(16) {
                let uy = F::load(&std::array::from_fn(|k| (x[b0 + k] * 0.5 + 0.5) as f32));
                let v = coating_terms(distr, wi, eta, ux, uy, transmit).to_array();
                for (k, v) in v.into_iter().enumerate() {
                    total += v as f64 * w[a] * w[b0 + k] * 0.25;
                }
            }
        }
        total as f32
    }

    /// # Safety
    /// The CPU must have AVX-512F and AVX-512DQ.
    #[target_feature(enable = "avx512f,avx512dq")]
    pub unsafe fn integral_avx512(
        distr: &Microfacet,
        wi: Vec3A,
        eta: f32,
        rule: &(Vec<f64>, Vec<f64>),
        transmit: bool,
    ) -> f32 {
        integral::<crate::simd::avx512::F>(distr, wi, eta, rule, transmit)
    }

    /// # Safety
    /// The CPU must have AVX.
    #[target_feature(enable = "avx")]
    pub unsafe fn integral_avx(
        distr: &Microfacet,
        wi: Vec3A,
        eta: f32,
        rule: &(Vec<f64>, Vec<f64>),
        transmit: bool,
    ) -> f32 {
        integral::<crate::simd::avx2::F>(distr, wi, eta, rule, transmit)
    }
}

/// The table's rows (one cos θ each) are independent integrals, computed in parallel at
/// scene load (a few milliseconds a table on one core in lanes, tens a point at a time)
/// and summed in order, so the table is the same bits on any number of threads.
fn compute_table(kind: MicrofacetType, alpha: f32, eta: f32) -> CoatingTable {
    use rayon::prelude::*;
    let distr = Microfacet::new(kind, alpha, alpha);
    let rule_t = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let rule_r = gauss_legendre(if 1.0 / eta > 1.0 { 32 } else { 128 });
    let rows: Vec<(f32, f32)> = (0..TRANSMITTANCE_RES)
        .into_par_iter()
        .map(|k| {
            let mu = (k as f32 / (TRANSMITTANCE_RES - 1) as f32).max(1e-6);
            let wi = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            (
                coating_integral(&distr, wi, eta, &rule_t, true),
                coating_integral(&distr, wi, 1.0 / eta, &rule_r, false) * mu,
            )
        })
        .collect();
    let mut transmittance = [0.0f32; TRANSMITTANCE_RES];
    let mut r_sum = 0.0f64;
    for (t, &(tk, rk)) in transmittance.iter_mut().zip(&rows) {
        *t = tk;
        r_sum += rk as f64;
    }
    CoatingTable {
        transmittance,
        internal_reflectance: (2.0 * r_sum / TRANSMITTANCE_RES as f64) as f32,
    }
}

type CacheEntry = ((MicrofacetType, u32, u32), &'static CoatingTable);
static CACHE: Mutex<Vec<CacheEntry>> = Mutex::new(Vec::new());

/// The coating table for (distribution, α, η), computed on first use (milliseconds)
/// and kept for the life of the program.
pub fn coating_table(kind: MicrofacetType, alpha: f32, eta: f32) -> &'static CoatingTable {
    let alpha = alpha.max(1e-4);
    let key = (kind, alpha.to_bits(), eta.to_bits());
    if let Some(&(_, t)) = CACHE.lock().unwrap().iter().find(|(k, _)| *k == key) {
        return t;
    }
    // Computed outside the lock; a racing thread may compute the same table, only one is kept.
    let table = compute_table(kind, alpha, eta);
    let mut cache = CACHE.lock().unwrap();
    if let Some(&(_, t)) = cache.iter().find(|(k, _)| *k == key) {
        return t;
    }
    let t: &'static CoatingTable = Box::leak(Box::new(table));
    cache.push((key, t));
    t
}

#[derive(Clone, Copy, Debug)]
pub struct RoughPlastic {
    pub distr: Microfacet,
    /// Index of the coating over that of the outside (`int_ior / ext_ior`).
    pub eta: f32,
    pub diffuse_reflectance: Color,
    pub specular_reflectance: Color,
    pub nonlinear: bool,
    /// w = s̄/(d̄ + s̄) from the constructor's reflectances (see `Plastic`).
    pub specular_sampling_weight: f32,
    inv_eta2: f32,
    table: &'static CoatingTable,
}

impl RoughPlastic {
    /// The first construction for a given (distribution, α, η) computes the coating table
    /// (see the module documentation); later ones reuse it.
    pub fn new(
        kind: MicrofacetType,
        alpha: f32,
        eta: f32,
        diffuse: Color,
        specular: Color,
        nonlinear: bool,
    ) -> Self {
        let (d, s) = (mean(diffuse), mean(specular));
        let distr = Microfacet::new(kind, alpha, alpha);
        RoughPlastic {
            distr,
            eta,
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            nonlinear,
            specular_sampling_weight: s / (d + s),
            inv_eta2: 1.0 / (eta * eta),
            table: coating_table(kind, distr.alpha_u, eta),
        }
    }

    /// The coating's table, shared by every rough plastic of this (distribution, α, η).
    pub fn table(&self) -> &'static CoatingTable {
        self.table
    }

    /// This BSDF as one lane of [`Coated`], whose maths it runs.
    #[inline(always)]
    pub fn coated(&self) -> Coated<'static, Microfacet, Color> {
        Coated {
            distr: self.distr,
            eta: self.eta,
            diffuse_reflectance: self.diffuse_reflectance,
            specular_reflectance: self.specular_reflectance,
            nonlinear: self.nonlinear,
            specular_sampling_weight: self.specular_sampling_weight,
            inv_eta2: self.inv_eta2,
            transmittance: &self.table.transmittance,
            first: 0.0,
            internal_reflectance: self.table.internal_reflectance,
        }
    }

    /// wo.z > 0 required (one-sided).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        self.coated().eval_lanes(wo, wi)
    }

    /// `eval` and `pdf` together, sharing what they share.
    #[inline]
    pub fn eval_pdf(&self, wo: Vec3A, wi: Vec3A) -> (Color, f32) {
        self.coated().eval_pdf_lanes(wo, wi)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        self.coated().pdf_lanes(wo, wi)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let (wi, weight, pdf, ok) = self.coated().sample_lanes(wo, u1, u2.x, u2.y);
        ok.then_some(BsdfSample {
            wi,
            weight,
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}

/// Rough plastics in lanes, the maths written once: one path's is [`RoughPlastic::coated`]
/// (distribution [`Microfacet`], colours [`Color`]), sixteen paths' the wavefront's
/// (`Either<F>`, `V3`), each lane with its own parameters and coating table.
#[derive(Clone, Copy)]
pub struct Coated<'t, D, C: Vector3> {
    pub distr: D,
    pub eta: C::F,
    pub diffuse_reflectance: C,
    pub specular_reflectance: C,
    pub nonlinear: Mask<C>,
    pub specular_sampling_weight: C::F,
    pub inv_eta2: C::F,
    /// Transmittance tables of [`TRANSMITTANCE_RES`] entries one after another (one, or
    /// those of all the lanes' materials); each lane's starts at `first`, a whole number.
    pub transmittance: &'t [f32],
    pub first: C::F,
    /// R_int of each lane's coating.
    pub internal_reflectance: C::F,
}

impl<D, C: Vector3> Coated<'_, D, C> {
    /// The lanes' coating transmittances at `cos_theta` ([`lerp_table`]).
    #[inline(always)]
    fn transmittance(&self, cos_theta: C::F) -> C::F {
        lerp_table(self.transmittance, self.first, cos_theta)
    }

    /// The specular lobe's probability, given T(θo).
    #[inline(always)]
    fn prob_specular(&self, t_o: C::F) -> C::F {
        let (one, w) = (C::F::splat(1.0), self.specular_sampling_weight);
        let ps = (one - t_o) * w;
        let pd = t_o * (one - w);
        ps / (ps + pd)
    }

    /// What f and the pdf share for a pair of directions: the half vector h, D(h) and
    /// G1(wo, h).
    #[inline(always)]
    fn pair<V>(&self, wo: V, wi: V) -> (V, C::F, C::F)
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let h = (wo + wi).normalize();
        (h, self.distr.d(h), self.distr.g1(wo, h))
    }

    /// f of a pair (h, D(h), G1(wo, h)), given T(θo) and T(θi): the coating's microfacet
    /// reflection plus the base seen through it.
    #[inline(always)]
    fn value<V>(&self, wo: V, wi: V, (h, d, g1_o): (V, C::F, C::F), t_o: C::F, t_i: C::F) -> C
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let one = C::F::splat(1.0);
        let f = fresnel_dielectric_lanes(wo.dot(h), self.eta);
        let g = g1_o * self.distr.g1(wi, h);
        let spec = self
            .specular_reflectance
            .scale(f * d * g / (C::F::splat(4.0) * wo.z() * wi.z()));
        let (rho, r_int) = (self.diffuse_reflectance, self.internal_reflectance);
        let mut base = rho.div(one - r_int);
        if C::F::any(self.nonlinear) {
            let (x, y, z) = (rho.x(), rho.y(), rho.z());
            let nonlinear = C::new(
                x / (one - x * r_int),
                y / (one - y * r_int),
                z / (one - z * r_int),
            );
            base = C::select(self.nonlinear, nonlinear, base);
        }
        spec + base.scale(C::F::splat(FRAC_1_PI) * self.inv_eta2 * t_o * t_i)
    }

    /// The pdf of a pair (h, D(h), G1(wo, h)), given the specular lobe's probability: the
    /// mixture of visible normals reflected and the cosine.
    #[inline(always)]
    fn density<V: Vector3<F = C::F>>(
        &self,
        wo: V,
        wi: V,
        (_, d, g1_o): (V, C::F, C::F),
        ps: C::F,
    ) -> C::F {
        let one = C::F::splat(1.0);
        let spec = d * g1_o / (C::F::splat(4.0) * wo.z());
        ps * spec + (one - ps) * cosine_hemisphere_pdf_lanes(wi.z())
    }

    /// f(wo, wi) and the pdf of sampling wi: zero unless both directions are above the
    /// surface.
    #[inline(always)]
    pub fn eval_pdf_lanes<V>(&self, wo: V, wi: V) -> (C, C::F)
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let zero = C::F::zero();
        let none = C::new(zero, zero, zero);
        let ok = !wo.z().le(zero) & !wi.z().le(zero);
        if !C::F::any(ok) {
            return (none, zero);
        }
        let pair = self.pair(wo, wi);
        let t_o = self.transmittance(wo.z());
        let f = self.value(wo, wi, pair, t_o, self.transmittance(wi.z()));
        let pdf = self.density(wo, wi, pair, self.prob_specular(t_o));
        (C::select(ok, f, none), C::F::select(ok, pdf, zero))
    }

    /// f(wo, wi) alone ([`Coated::eval_pdf_lanes`]'s).
    #[inline(always)]
    pub fn eval_lanes<V>(&self, wo: V, wi: V) -> C
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        self.eval_pdf_lanes(wo, wi).0
    }

    /// The pdf alone ([`Coated::eval_pdf_lanes`]'s).
    #[inline(always)]
    pub fn pdf_lanes<V>(&self, wo: V, wi: V) -> C::F
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        self.eval_pdf_lanes(wo, wi).1
    }

    /// A direction for the numbers `u1` (the lobe) and (`ux`, `uy`): the direction, the
    /// weight f·cos θi/pdf, the pdf, and the lanes where there is a sample.
    #[inline(always)]
    pub fn sample_lanes<V>(&self, wo: V, u1: C::F, ux: C::F, uy: C::F) -> (V, C, C::F, Mask<V>)
    where
        V: Vector3<F = C::F>,
        D: Distribution<V>,
    {
        let zero = C::F::zero();
        let above = !wo.z().le(zero);
        if !C::F::any(above) {
            return (wo, C::new(zero, zero, zero), zero, above);
        }
        let t_o = self.transmittance(wo.z());
        let ps = self.prob_specular(t_o);
        let specular = u1.lt(ps);
        let mut wi = wo;
        if C::F::any(specular) {
            wi = reflect_about_lanes(wo, self.distr.sample_visible(wo, ux, uy));
        }
        if C::F::any(!specular) {
            wi = V::select(specular, wi, cosine_hemisphere(ux, uy));
        }
        // The pdf and f as `eval_pdf_lanes` computes them, T(θo) looked up once.
        let pair = self.pair(wo, wi);
        let below = wi.z().le(zero);
        let pdf = C::F::select(below, zero, self.density(wo, wi, pair, ps));
        // (A NaN pdf has no sample.)
        let ok = above & pdf.gt(zero);
        let f = self.value(wo, wi, pair, t_o, self.transmittance(wi.z()));
        let f = C::select(below, C::new(zero, zero, zero), f);
        (wi, f.scale(wi.z() / pdf), pdf, ok)
    }
}

/// A table of [`TRANSMITTANCE_RES`] values at evenly spaced cos θ in [0, 1], starting at
/// `first` in `values`, linearly interpolated at `cos_theta` (Mitsuba's `lerp_gather`).
#[inline(always)]
pub fn lerp_table<F: Float>(values: &[f32], first: F, cos_theta: F) -> F {
    let k = F::splat;
    let x = cos_theta * k((TRANSMITTANCE_RES - 1) as f32);
    // (`max_num` takes NaN to 0.)
    let i = x
        .max_num(F::zero())
        .trunc()
        .min_num(k((TRANSMITTANCE_RES - 2) as f32));
    let t = x - i;
    let (a, b) = (
        F::gather(values, first + i),
        F::gather(values, first + i + k(1.0)),
    );
    a + (b - a) * t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integrals in lanes (AVX-512 or AVX, where this CPU has them) are the one-by-one
    /// loop's bits, for both distributions, both integrals, grazing to normal incidence.
    #[test]
    fn coating_integrals_in_lanes_are_the_loops() {
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (alpha, eta, n) in [(0.1, 1.5, 32), (0.45, 1.0 / 1.33, 128), (0.02, 2.1, 16)] {
                let distr = Microfacet::new(kind, alpha, alpha);
                let rule = gauss_legendre(n);
                for mu in [1e-6f32, 0.05, 0.4, 0.93, 1.0] {
                    let wi = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                    for transmit in [true, false] {
                        let lanes = coating_integral(&distr, wi, eta, &rule, transmit);
                        let one = integral_one_by_one(&distr, wi, eta, &rule, transmit);
                        // (Near normal incidence most of the energy is transmitted.)
                        let least = if mu > 0.9 && transmit { 0.5 } else { 0.0 };
                        assert!(
                            (least..=1.0001).contains(&one),
                            "{kind:?} {alpha} {mu}: {one}"
                        );
                        assert_eq!(
                            lanes.to_bits(),
                            one.to_bits(),
                            "{kind:?} {alpha} {eta} {mu}"
                        );
                    }
                }
            }
        }
    }
}
