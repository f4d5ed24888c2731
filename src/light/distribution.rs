//! Piecewise-constant distributions: discrete ones (for picking lights by power) and their
//! continuous forms on [0, 1) and [0, 1)² (for sampling an environment map's pixels; pbrt-v4
//! §A.1 and `PiecewiseConstant2D`: a marginal over rows, a conditional over each row).

#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    /// cdf[i] = P(index < i); len = n + 1, last = 1.
    cdf: Vec<f32>,
    pmf: Vec<f32>,
}

impl Distribution1D {
    /// Weights must be finite and non-negative; all-zero weights give an empty distribution.
    pub fn new(weights: &[f32]) -> Self {
        let total: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if weights.is_empty() || total <= 0.0 {
            return Distribution1D::default();
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            acc += w.max(0.0) as f64;
            cdf.push((acc / total) as f32);
        }
        *cdf.last_mut().unwrap() = 1.0;
        let pmf = weights
            .iter()
            .map(|&w| (w.max(0.0) as f64 / total) as f32)
            .collect();
        Distribution1D { cdf, pmf }
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Index i with probability pmf[i], for u in [0, 1).
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> Option<(usize, f32)> {
        if self.pmf.is_empty() {
            return None;
        }
        if self.pmf.len() == 1 {
            return Some((0, 1.0));
        }
        // Largest i with cdf[i] <= u, skipping zero-probability entries.
        let mut i = self.cdf.partition_point(|&c| c <= u).saturating_sub(1);
        i = i.min(self.pmf.len() - 1);
        while self.pmf[i] == 0.0 && i + 1 < self.pmf.len() {
            i += 1;
        }
        Some((i, self.pmf[i]))
    }

    /// A point x in [0, 1) with density `pmf[i] · n` on bin i = ⌊x·n⌋ (the bin's share of
    /// the unit interval); None when the distribution is empty.
    #[inline]
    pub fn sample_continuous(&self, u: f32) -> Option<(f32, f32, usize)> {
        let (i, p) = self.sample_discrete(u)?;
        let n = self.pmf.len();
        // Where u falls within the bin's share of the cdf, remapped to [0, 1).
        let du = if p > 0.0 {
            ((u - self.cdf[i]) / p).clamp(0.0, 1.0)
        } else {
            0.5
        };
        Some((in_bin(i, du, n), p * n as f32, i))
    }

    /// The density of `sample_continuous` at x in [0, 1].
    #[inline]
    pub fn pdf_continuous(&self, x: f32) -> f32 {
        let n = self.pmf.len();
        if n == 0 || !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        let i = ((x * n as f32) as usize).min(n - 1);
        self.pmf[i] * n as f32
    }
}

/// (i + du)/n, nudged by an ulp where rounding would put it in a neighbouring bin (as the
/// densities look it up: ⌊x·n⌋ = i), so that a sample's density is the one `pdf` gives there.
#[inline]
fn in_bin(i: usize, du: f32, n: usize) -> f32 {
    let mut x = (i as f32 + du) / n as f32;
    for _ in 0..4 {
        let b = (x * n as f32) as usize;
        if b > i || x >= 1.0 {
            x = f32::from_bits(x.to_bits() - 1);
        } else if b < i {
            x = f32::from_bits(x.to_bits() + 1);
        } else {
            break;
        }
    }
    x
}

/// A piecewise-constant density on [0, 1)², constant on each of `nu × nv` cells.
#[derive(Clone, Debug, Default)]
pub struct Distribution2D {
    /// Over u within each row (v).
    conditional: Vec<Distribution1D>,
    /// Over rows, by each row's total weight.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `weights[v · nu + u]`: finite and non-negative. All-zero weights give an empty
    /// distribution, which samples nothing and has density 0 everywhere.
    pub fn new(weights: &[f32], nu: usize, nv: usize) -> Self {
        assert_eq!(weights.len(), nu * nv, "weights of a {nu}×{nv} grid");
        let conditional: Vec<Distribution1D> = weights
            .chunks_exact(nu.max(1))
            .map(Distribution1D::new)
            .collect();
        let rows: Vec<f32> = weights
            .chunks_exact(nu.max(1))
            .map(|r| r.iter().map(|&w| w.max(0.0) as f64).sum::<f64>() as f32)
            .collect();
        Distribution2D {
            conditional,
            marginal: Distribution1D::new(&rows),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.marginal.is_empty()
    }

    /// A point of [0, 1)² and its density; None when the distribution is empty.
    #[inline]
    pub fn sample(&self, u: glam::Vec2) -> Option<(glam::Vec2, f32)> {
        let (y, py, row) = self.marginal.sample_continuous(u.y)?;
        let (x, px, _) = self.conditional[row].sample_continuous(u.x)?;
        Some((glam::Vec2::new(x, y), px * py))
    }

    /// The density of `sample` at p in [0, 1]².
    #[inline]
    pub fn pdf(&self, p: glam::Vec2) -> f32 {
        let nv = self.conditional.len();
        if nv == 0 || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let row = ((p.y * nv as f32) as usize).min(nv - 1);
        self.marginal.pmf(row) * nv as f32 * self.conditional[row].pdf_continuous(p.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// Continuous samples fall in bins as often as the weights say, inside the bin the
    /// density says, and a zero-weight bin is never chosen.
    #[test]
    fn continuous_1d_follows_the_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]);
        let n = 8000;
        let mut counts = [0u32; 4];
        for k in 0..n {
            let u = (k as f32 + 0.5) / n as f32;
            let (x, pdf, i) = d.sample_continuous(u).unwrap();
            assert!((0.0..1.0).contains(&x));
            let bin = (x * 4.0) as usize;
            assert_eq!(bin, i);
            counts[bin] += 1;
            assert_eq!(pdf, d.pdf_continuous(x));
        }
        assert_eq!(counts[1], 0);
        for (c, w) in counts.iter().zip([1.0, 0.0, 3.0, 4.0]) {
            assert!((*c as f32 / n as f32 - w / 8.0).abs() < 1e-3, "{counts:?}");
        }
        // Stratified u gives stratified x: the map is monotonic.
        let xs: Vec<f32> = (0..100)
            .map(|k| d.sample_continuous(k as f32 / 100.0).unwrap().0)
            .collect();
        assert!(xs.windows(2).all(|w| w[0] <= w[1]));
    }

    /// The 2D density integrates to one (a midpoint sum over a grid finer than the cells),
    /// and every sample's density is the one `pdf` gives there.
    #[test]
    fn density_2d_integrates_to_one() {
        let (nu, nv) = (5, 3);
        let w: Vec<f32> = (0..nu * nv).map(|i| ((i * 7) % 5) as f32).collect();
        let d = Distribution2D::new(&w, nu, nv);
        let m = 60;
        let mut sum = 0.0f64;
        for j in 0..m {
            for i in 0..m {
                let p = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                sum += d.pdf(p) as f64;
            }
        }
        sum /= (m * m) as f64;
        assert!((sum - 1.0).abs() < 1e-5, "{sum}");
        for k in 0..500 {
            let u = Vec2::new((k as f32 * 0.618_034) % 1.0, (k as f32 + 0.5) / 500.0);
            let (p, pdf) = d.sample(u).unwrap();
            assert!(pdf > 0.0);
            assert!((pdf - d.pdf(p)).abs() <= 1e-5 * pdf, "{p} {pdf}");
        }
        let empty = Distribution2D::new(&[0.0; 6], 3, 2);
        assert!(empty.is_empty() && empty.sample(Vec2::splat(0.5)).is_none());
        // At a bin's very edge the sample stays in its bin (x = 0.4 would be row 2 of 5).
        let d = Distribution2D::new(&[1.0, 0.0, 1.0, 0.0, 1.0], 1, 5);
        let (p, pdf) = d.sample(Vec2::new(0.5, 2.0 / 3.0 - 1e-8)).unwrap();
        assert_eq!(pdf, d.pdf(p), "{p}");
        assert_eq!(empty.pdf(Vec2::splat(0.5)), 0.0);
    }
}
