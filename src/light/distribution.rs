//! Piecewise-constant discrete distributions (for picking lights by power).

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
}
