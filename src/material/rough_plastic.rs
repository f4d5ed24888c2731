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

use super::dielectric::{fresnel_dielectric, fresnel_refraction};
use super::microfacet::{reflect_about, Microfacet, MicrofacetType};
use super::plastic::mean;
use super::sampling::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use super::BsdfSample;
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
    /// Linear interpolation in the table (Mitsuba's `lerp_gather`).
    #[inline]
    pub fn transmittance(&self, cos_theta: f32) -> f32 {
        let x = cos_theta * (TRANSMITTANCE_RES - 1) as f32;
        let i = (x.max(0.0) as usize).min(TRANSMITTANCE_RES - 2);
        let t = x - i as f32;
        let (a, b) = (self.transmittance[i], self.transmittance[i + 1]);
        a + (b - a) * t
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
fn coating_integral(
    distr: &Microfacet,
    wi: Vec3A,
    eta: f32,
    rule: &(Vec<f64>, Vec<f64>),
    transmit: bool,
) -> f32 {
    let (x, w) = rule;
    let n = x.len();
    let mut sum = 0.0f64;
    for a in 0..n {
        for b in 0..n {
            let u = Vec2::new((x[a] * 0.5 + 0.5) as f32, (x[b] * 0.5 + 0.5) as f32);
            let m = distr.sample_visible(wi, u);
            let wi_m = wi.dot(m);
            let v = if transmit {
                let (f, cos_t, _, eta_ti) = fresnel_refraction(wi_m, eta);
                let wt = m * (wi_m * eta_ti + cos_t) - wi * eta_ti;
                if wt.z * wi.z >= 0.0 {
                    0.0
                } else {
                    distr.g1(wt, m) * (1.0 - f)
                }
            } else {
                let wr = reflect_about(wi, m);
                if wr.z <= 0.0 {
                    0.0
                } else {
                    distr.g1(wr, m) * fresnel_dielectric(wi_m, eta)
                }
            };
            sum += v as f64 * w[a] * w[b] * 0.25;
        }
    }
    sum as f32
}

/// The table's rows (one cos θ each) are independent integrals, computed in parallel at
/// scene load (a few tens of milliseconds each table on one core) and summed in order, so
/// the table is the same bits on any number of threads.
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

/// The coating table for (distribution, α, η), computed on first use (tens of milliseconds)
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

    pub fn table(&self) -> &'static CoatingTable {
        self.table
    }

    #[inline]
    fn prob_specular(&self, t_o: f32) -> f32 {
        let w = self.specular_sampling_weight;
        let ps = (1.0 - t_o) * w;
        let pd = t_o * (1.0 - w);
        ps / (ps + pd)
    }

    /// wo.z > 0 required (one-sided).
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distr.d(h);
        let f = fresnel_dielectric(wo.dot(h), self.eta);
        let g = self.distr.g(wo, wi, h);
        let spec = self.specular_reflectance * (f * d * g / (4.0 * wo.z * wi.z));
        let t_o = self.table.transmittance(wo.z);
        let t_i = self.table.transmittance(wi.z);
        let rho = self.diffuse_reflectance;
        let r_int = self.table.internal_reflectance;
        let base = if self.nonlinear {
            rho / (Color::ONE - rho * r_int)
        } else {
            rho / (1.0 - r_int)
        };
        spec + base * (FRAC_1_PI * self.inv_eta2 * t_o * t_i)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.prob_specular(self.table.transmittance(wo.z));
        let h = (wo + wi).normalize();
        let spec = self.distr.d(h) * self.distr.g1(wo, h) / (4.0 * wo.z);
        ps * spec + (1.0 - ps) * cosine_hemisphere_pdf(wi.z)
    }

    #[inline]
    pub fn sample(&self, wo: Vec3A, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let ps = self.prob_specular(self.table.transmittance(wo.z));
        let wi = if u1 < ps {
            reflect_about(wo, self.distr.sample_visible(wo, u2))
        } else {
            square_to_cosine_hemisphere(u2)
        };
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval(wo, wi) * (wi.z / pdf),
            pdf,
            specular: false,
            eta: 1.0,
        })
    }
}
