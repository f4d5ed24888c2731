//! Statistics shared by the BSDF tests: a small random number generator, directions, the
//! mean and standard error of a sample, and the chi-square goodness-of-fit test of a
//! direction sampler against its pdf (the method of Mitsuba's and pbrt's `chi2` tests).
#![allow(dead_code)]

use glam::{Vec2, Vec3A};
use mcrt::material::{Material, TransportMode};
use mcrt::sampler::Sampler;
use std::f64::consts::PI;

pub struct Rng(pub Sampler);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(Sampler::from_state(seed, 0xb5df ^ seed))
    }
    pub fn f(&mut self) -> f32 {
        self.0.next_1d()
    }
    pub fn u2(&mut self) -> Vec2 {
        self.0.next_2d()
    }
    /// Uniform direction on the unit sphere (z = 1 − 2u, φ = 2πu'); pdf 1/(4π).
    pub fn sphere(&mut self) -> Vec3A {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * self.f();
        Vec3A::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The direction with polar angle θ (from +z, degrees) and azimuth φ (radians).
pub fn dir(theta_deg: f64, phi: f64) -> Vec3A {
    let t = theta_deg.to_radians();
    Vec3A::new(
        (t.sin() * phi.cos()) as f32,
        (t.sin() * phi.sin()) as f32,
        t.cos() as f32,
    )
}

/// The direction with cos θ = z and azimuth φ.
pub fn dir_z(z: f64, phi: f64) -> Vec3A {
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}

/// Mean and standard error of a sample (unbiased variance / n).
pub fn mean_and_stderr(xs: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut n, mut s, mut s2) = (0.0, 0.0, 0.0);
    for x in xs {
        n += 1.0;
        s += x;
        s2 += x * x;
    }
    let mean = s / n;
    let var = ((s2 - n * mean * mean) / (n - 1.0)).max(0.0);
    (mean, (var / n).sqrt())
}

/// ln Γ(x) for x > 0 (Lanczos approximation, Numerical Recipes 3rd ed. §6.1, `gammln`).
#[allow(clippy::excessive_precision)] // the published coefficients, verbatim
pub fn ln_gamma(x: f64) -> f64 {
    const COF: [f64; 14] = [
        57.1562356658629235,
        -59.5979603554754912,
        14.1360979747417471,
        -0.491913816097620199,
        0.339946499848118887e-4,
        0.465236289270485756e-4,
        -0.983744753048795646e-4,
        0.158088703224912494e-3,
        -0.210264441724104883e-3,
        0.217439618115212643e-3,
        -0.164318106536763890e-3,
        0.844182239838527433e-4,
        -0.261908384015814087e-4,
        0.368991826595316234e-5,
    ];
    let mut y = x;
    let tmp = x + 5.242_187_5; // 671/128
    let tmp = (x + 0.5) * tmp.ln() - tmp;
    let mut ser = 0.999999999999997092;
    for c in COF {
        y += 1.0;
        ser += c / y;
    }
    tmp + (2.5066282746310005 * ser / x).ln()
}

/// Regularised upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a) (Numerical Recipes
/// §6.2: the series for P when x < a + 1, else the continued fraction for Q, by Lentz's
/// method).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0);
    if x == 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = e^{−x} x^a / Γ(a) · Σ_n x^n / (a (a+1) ... (a+n)).
        let (mut ap, mut del, mut sum) = (a, 1.0 / a, 1.0 / a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        // Q(a, x) = e^{−x} x^a / Γ(a) · 1/(x + 1 − a − 1·(1 − a)/(x + 3 − a − ...)).
        const FPMIN: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / FPMIN;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < FPMIN {
                d = FPMIN;
            }
            c = b + an / c;
            if c.abs() < FPMIN {
                c = FPMIN;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - gln).exp() * h
    }
}

/// P(χ²_dof ≥ stat) = Q(dof/2, stat/2).
pub fn chi2_pvalue(stat: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, stat / 2.0)
}

/// Histogram resolution over the sphere: cos θ in [−1, 1] and φ in [0, 2π). The cos θ grid
/// has a boundary at 0, where the hemispherical pdfs have their kink.
pub const Z_BINS: usize = 10;
pub const PHI_BINS: usize = 20;
pub const SAMPLES: usize = 1_000_000;
/// Cells with a smaller expected count are pooled (the usual validity rule of the test).
pub const MIN_EXPECTED: f64 = 5.0;

pub fn bin_of(w: Vec3A) -> usize {
    let z = (w.z as f64).clamp(-1.0, 1.0);
    let i = (((z + 1.0) * 0.5 * Z_BINS as f64) as usize).min(Z_BINS - 1);
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let j = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    i * PHI_BINS + j
}

/// Expected probability of each cell: ∫∫ pdf(ω) dz dφ over the cell (dω = dz dφ), by
/// composite Simpson's rule on an 8×8 grid per cell (exact for pdfs linear in z and
/// constant in φ, like the cosine-weighted ones; accurate to ≪ 1e-4 otherwise).
pub fn cell_probabilities(pdf: &dyn Fn(Vec3A) -> f64) -> Vec<f64> {
    cell_probabilities_k(pdf, 8)
}

/// `cell_probabilities` with a K×K Simpson grid per cell (K even), for peaked pdfs.
pub fn cell_probabilities_k(pdf: &dyn Fn(Vec3A) -> f64, k_sub: usize) -> Vec<f64> {
    let ks = k_sub;
    let simpson = |k: usize| {
        if k == 0 || k == ks {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let (dz, dphi) = (2.0 / Z_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let mut p = vec![0.0; Z_BINS * PHI_BINS];
    for i in 0..Z_BINS {
        for j in 0..PHI_BINS {
            let mut s = 0.0;
            for a in 0..=ks {
                for b in 0..=ks {
                    let z = -1.0 + dz * (i as f64 + a as f64 / ks as f64);
                    let phi = dphi * (j as f64 + b as f64 / ks as f64);
                    s += simpson(a) * simpson(b) * pdf(dir_z(z, phi));
                }
            }
            p[i * PHI_BINS + j] = s * (dz / (3.0 * ks as f64)) * (dphi / (3.0 * ks as f64));
        }
    }
    p
}

/// Chi-square test of `sample` (None = no sample: counted as missing mass) against `pdf`.
/// Returns (statistic, degrees of freedom, p-value).
pub fn chi2_test(
    sample: impl FnMut(&mut Rng) -> Option<Vec3A>,
    pdf: &dyn Fn(Vec3A) -> f64,
    seed: u64,
) -> (f64, usize, f64) {
    chi2_test_k(sample, pdf, seed, 8)
}

/// `chi2_test` with the expected counts integrated on a K×K Simpson grid per cell.
pub fn chi2_test_k(
    mut sample: impl FnMut(&mut Rng) -> Option<Vec3A>,
    pdf: &dyn Fn(Vec3A) -> f64,
    seed: u64,
    k_sub: usize,
) -> (f64, usize, f64) {
    let mut rng = Rng::new(seed);
    let mut observed = vec![0.0f64; Z_BINS * PHI_BINS];
    for _ in 0..SAMPLES {
        if let Some(w) = sample(&mut rng) {
            observed[bin_of(w)] += 1.0;
        }
    }
    let expected: Vec<f64> = cell_probabilities_k(pdf, k_sub)
        .iter()
        .map(|p| p * SAMPLES as f64)
        .collect();
    // Pool the cells with small expected counts, smallest first (as Mitsuba's ChiSquare does).
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for &k in &order {
        if expected[k] == 0.0 {
            if observed[k] > 0.0 {
                // Samples where the pdf says there can be none: reject outright.
                return (f64::INFINITY, 0, 0.0);
            }
        } else if expected[k] < MIN_EXPECTED || (pool_exp > 0.0 && pool_exp < MIN_EXPECTED) {
            pool_obs += observed[k];
            pool_exp += expected[k];
        } else {
            stat += (observed[k] - expected[k]).powi(2) / expected[k];
            cells += 1;
        }
    }
    if pool_exp > 0.0 {
        stat += (pool_obs - pool_exp).powi(2) / pool_exp;
        cells += 1;
    }
    // The total is fixed by the sample count: one degree of freedom fewer than cells.
    let dof = cells - 1;
    (stat, dof, chi2_pvalue(stat, dof))
}

/// Samples `m` at `wo` through `Material::sample` and tests against `Material::pdf`.
pub fn chi2_material(m: &Material, wo: Vec3A, seed: u64) -> (f64, usize, f64) {
    chi2_test(
        |rng| {
            let u1 = rng.f();
            m.sample(wo, u1, rng.u2(), TransportMode::Radiance)
                .map(|s| s.wi)
        },
        &|wi| m.pdf(wo, wi) as f64,
        seed,
    )
}

/// Directional albedo ∫ f |cos θi| dωi (first channel) two ways: uniform sphere sampling of
/// `eval` (independent of the sampler) and the mean sample weight; (mean, stderr) of each.
pub fn albedos(
    m: &Material,
    wo: Vec3A,
    mode: TransportMode,
    n: usize,
    seed: u64,
) -> [(f64, f64); 2] {
    let mut rng = Rng::new(seed);
    let uniform = mean_and_stderr((0..n).map(|_| {
        let wi = rng.sphere();
        4.0 * PI * m.eval_mode(wo, wi, mode).x as f64 * wi.z.abs() as f64
    }));
    let sampled = mean_and_stderr((0..n).map(|_| {
        let u1 = rng.f();
        m.sample(wo, u1, rng.u2(), mode)
            .map_or(0.0, |s| s.weight.x as f64)
    }));
    [uniform, sampled]
}

/// The chi-square test of a material's direction sampling: `sampler`'s non-delta samples at
/// `wo` against `pdf_of`'s pdf (the same material unless a test wants a wrong one), with
/// `k_sub` Simpson subdivisions per cell; (statistic, degrees of freedom, p-value).
pub fn material_chi2(
    sampler: &Material,
    pdf_of: &Material,
    wo: Vec3A,
    seed: u64,
    k_sub: usize,
) -> (f64, usize, f64) {
    chi2_test_k(
        |rng| {
            let u1 = rng.f();
            sampler
                .sample(wo, u1, rng.u2(), TransportMode::Radiance)
                .filter(|s| !s.specular)
                .map(|s| s.wi)
        },
        &|wi| pdf_of.pdf(wo, wi) as f64,
        seed,
        k_sub,
    )
}
