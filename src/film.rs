//! The film: per-pixel sums of radiance samples (box filter: every sample of a pixel counts
//! equally).
//!
//! The sums are kept in fixed point (i128 integers, see [`SUM_FRAC_BITS`] and
//! [`SQ_FRAC_BITS`]) rather than in floating point. Each f32 sample is rounded once to the
//! fixed-point grid, and from then on sums are integer additions, which are associative and
//! commutative: the sums of a pixel are the same bits however its samples are grouped — on
//! any number of threads, over any number of passes, or rendered on N machines as disjoint
//! shares ([`crate::parts`]) and added up afterwards. (f64 running sums would not be:
//! `(a + b) + c` and `a + (b + c)` differ in the last bit in general, so a merge of
//! per-machine f64 sums could not reproduce a single render.) Additions wrap (two's
//! complement), so that even an intermediate overflow cancels out; the totals are right while
//! |Σ L| < 2^63 ≈ 9.2e18 and Σ L² < 2^79 ≈ 6.0e23 per pixel and channel.

use crate::image::Image;
use crate::Color;

/// Fractional bits of Σ L: samples are rounded to multiples of 2^-64 ≈ 5.4e-20, which is
/// exact for every f32 sample of magnitude at least 2^-40 ≈ 9.1e-13 (an f32 has 24
/// significant bits).
pub const SUM_FRAC_BITS: i32 = 64;
/// Fractional bits of Σ L²: squares are rounded to multiples of 2^-48 ≈ 3.6e-15.
pub const SQ_FRAC_BITS: i32 = 48;

const SUM_SCALE: f64 = (1u128 << SUM_FRAC_BITS) as f64;
const SQ_SCALE: f64 = (1u128 << SQ_FRAC_BITS) as f64;

/// A sample value in the fixed point of Σ L.
#[inline]
pub fn fixed_sum(v: f64) -> i128 {
    (v * SUM_SCALE).round() as i128
}

/// A squared sample value in the fixed point of Σ L².
#[inline]
pub fn fixed_sq(v2: f64) -> i128 {
    (v2 * SQ_SCALE).round() as i128
}

/// Σ L back to a number.
#[inline]
pub fn sum_to_f64(s: i128) -> f64 {
    s as f64 * (1.0 / SUM_SCALE)
}

/// Σ L² back to a number.
#[inline]
pub fn sq_to_f64(s: i128) -> f64 {
    s as f64 * (1.0 / SQ_SCALE)
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Σ L per pixel and channel, in units of 2^-[`SUM_FRAC_BITS`].
    pub sum: Vec<[i128; 3]>,
    /// Σ L² per pixel and channel (for the variance of the mean), in units of
    /// 2^-[`SQ_FRAC_BITS`].
    pub sum_sq: Vec<[i128; 3]>,
    /// Samples per pixel that reached the film.
    pub count: Vec<u32>,
}

/// One pixel's accumulated samples, gathered by a tile before it is written to the film.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelSums {
    pub sum: [i128; 3],
    pub sum_sq: [i128; 3],
    pub count: u32,
}

impl PixelSums {
    #[inline]
    pub fn add(&mut self, l: Color) {
        for c in 0..3 {
            let v = l[c] as f64;
            self.sum[c] = self.sum[c].wrapping_add(fixed_sum(v));
            // The square of an f32 is exact in f64.
            self.sum_sq[c] = self.sum_sq[c].wrapping_add(fixed_sq(v * v));
        }
        self.count += 1;
    }

    /// Adds another set of sums (of other samples of the same pixel).
    #[inline]
    pub fn merge(&mut self, o: &PixelSums) {
        for c in 0..3 {
            self.sum[c] = self.sum[c].wrapping_add(o.sum[c]);
            self.sum_sq[c] = self.sum_sq[c].wrapping_add(o.sum_sq[c]);
        }
        self.count += o.count;
    }
}

impl Film {
    pub fn new(width: u32, height: u32) -> Film {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![[0; 3]; n],
            sum_sq: vec![[0; 3]; n],
            count: vec![0; n],
        }
    }

    /// The running sums of pixel (x, y).
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> PixelSums {
        let i = (y * self.width + x) as usize;
        PixelSums {
            sum: self.sum[i],
            sum_sq: self.sum_sq[i],
            count: self.count[i],
        }
    }

    #[inline]
    pub fn set_pixel(&mut self, x: u32, y: u32, p: &PixelSums) {
        let i = (y * self.width + x) as usize;
        self.sum[i] = p.sum;
        self.sum_sq[i] = p.sum_sq;
        self.count[i] = p.count;
    }

    /// Adds the sums of `other`, a film of the same size holding other samples of the same
    /// pixels. The result does not depend on the order films are added in.
    pub fn add_film(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for i in 0..self.sum.len() {
            let mut p = PixelSums {
                sum: self.sum[i],
                sum_sq: self.sum_sq[i],
                count: self.count[i],
            };
            p.merge(&PixelSums {
                sum: other.sum[i],
                sum_sq: other.sum_sq[i],
                count: other.count[i],
            });
            self.sum[i] = p.sum;
            self.sum_sq[i] = p.sum_sq;
            self.count[i] = p.count;
        }
    }

    /// Σ L per pixel and channel as numbers.
    pub fn sum_f64(&self) -> Vec<[f64; 3]> {
        self.sum.iter().map(|s| s.map(sum_to_f64)).collect()
    }

    /// Σ L² per pixel and channel as numbers.
    pub fn sum_sq_f64(&self) -> Vec<[f64; 3]> {
        self.sum_sq.iter().map(|s| s.map(sq_to_f64)).collect()
    }

    /// The image: the mean of each pixel's samples.
    pub fn image(&self) -> Image {
        let pixels = self
            .sum
            .iter()
            .zip(&self.count)
            .map(|(s, &n)| {
                let k = if n > 0 { 1.0 / n as f64 } else { 0.0 };
                let s = s.map(sum_to_f64);
                Color::new((s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32)
            })
            .collect();
        Image {
            width: self.width,
            height: self.height,
            pixels,
        }
    }

    /// Per pixel and channel, the estimated variance of the pixel mean: s²/n with the
    /// unbiased sample variance s².
    pub fn variance_of_mean(&self) -> Image {
        let pixels = (0..self.sum.len())
            .map(|i| {
                let n = self.count[i] as f64;
                let mut v = [0.0f32; 3];
                if n > 1.0 {
                    for (c, v) in v.iter_mut().enumerate() {
                        let mean = sum_to_f64(self.sum[i][c]) / n;
                        let sq = sq_to_f64(self.sum_sq[i][c]);
                        let s2 = ((sq - n * mean * mean) / (n - 1.0)).max(0.0);
                        *v = (s2 / n) as f32;
                    }
                }
                Color::from_array(v)
            })
            .collect();
        Image {
            width: self.width,
            height: self.height,
            pixels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples whose f64 running sums depend on the grouping give the same fixed-point sums
    /// in any grouping and order.
    #[test]
    fn sums_do_not_depend_on_grouping() {
        let vals = [1.0e10f32, 3.0e-6, 3.0e-6, 3.0e-6, 3.0e-6, 0.1, 0.7, 1.0e-6];
        let l = |v: f32| Color::new(v, v * 0.5, -v);
        // f64: ((a + b) + ...) and the sum of two halves differ for these values.
        let seq = vals.iter().fold(0.0f64, |s, &v| s + v as f64);
        let halves = vals[..4].iter().fold(0.0f64, |s, &v| s + v as f64)
            + vals[4..].iter().fold(0.0f64, |s, &v| s + v as f64);
        assert_ne!(seq.to_bits(), halves.to_bits(), "test values too easy");
        let mut one = PixelSums::default();
        vals.iter().for_each(|&v| one.add(l(v)));
        for split in 0..=vals.len() {
            let (mut a, mut b) = (PixelSums::default(), PixelSums::default());
            vals[..split].iter().for_each(|&v| a.add(l(v)));
            vals[split..].iter().rev().for_each(|&v| b.add(l(v)));
            b.merge(&a);
            assert_eq!(b, one, "split at {split}");
        }
        assert_eq!(one.count, vals.len() as u32);
        let expect: f64 = vals.iter().map(|&v| v as f64).sum();
        assert!((sum_to_f64(one.sum[0]) - expect).abs() <= 1e-9 * expect);
        assert!((sum_to_f64(one.sum[2]) + expect).abs() <= 1e-9 * expect);
    }
}
