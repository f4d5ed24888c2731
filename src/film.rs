//! The film: per-pixel sums of radiance samples (box filter: every sample of a pixel counts
//! equally), and splats: contributions that an estimator adds to any pixel (light tracing
//! and bidirectional methods connect a light path to the camera wherever it projects), kept
//! in a second set of sums normalised by the number of paths traced rather than by each
//! pixel's sample count (Veach 1997, §10.3.3).
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

/// The f32 `v` times 2^`frac`, rounded half away from zero, as `fixed_sum` would give it for
/// `v as f64` (saturating like `as i128`), computed from the bits of `v` with integer
/// operations only: an f32 is m·2^e with a 24-bit m, so the product is a shift of m. The f64
/// path calls a software f64 → i128 conversion for every channel of every sample.
#[inline(always)]
fn fixed_from_f32(v: f32, frac: i32) -> i128 {
    let bits = v.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32;
    let (m, e) = if exp == 0 {
        (bits & 0x7f_ffff, -149) // subnormal
    } else {
        ((bits & 0x7f_ffff) | 0x80_0000, exp - 150)
    };
    let mag = shift_round(m as u128, e + frac, 24);
    match (bits >> 31 != 0, mag) {
        (true, i128::MAX) => i128::MIN, // saturated, as `as i128` saturates
        (true, _) => -mag,
        (false, _) => mag,
    }
}

/// v² times 2^`frac`, rounded, for an f32 `v` (the square is exact: a 48-bit m²).
#[inline(always)]
fn fixed_sq_from_f32(v: f32, frac: i32) -> i128 {
    let bits = v.to_bits() & 0x7fff_ffff;
    let exp = (bits >> 23) as i32;
    let (m, e) = if exp == 0 {
        (bits & 0x7f_ffff, -149)
    } else {
        ((bits & 0x7f_ffff) | 0x80_0000, exp - 150)
    };
    shift_round(m as u128 * m as u128, 2 * e + frac, 48)
}

/// m·2^s rounded half up, for m < 2^`width`; saturates at i128::MAX as `as i128` does.
#[inline(always)]
fn shift_round(m: u128, s: i32, width: i32) -> i128 {
    if m == 0 {
        0
    } else if s >= 0 {
        // m·2^s needs 128 − lz + s bits; 127 fit in an i128.
        if s >= m.leading_zeros() as i32 {
            i128::MAX
        } else {
            (m << s) as i128
        }
    } else if -s > width {
        0 // below half a unit
    } else {
        let r = -s as u32;
        ((m + (1u128 << (r - 1))) >> r) as i128
    }
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
    /// Σ of splatted contributions per pixel and channel, in the fixed point of `sum`; empty
    /// until the first splat, so a film without splats carries nothing for them.
    pub splat: Vec<[i128; 3]>,
    /// Paths whose splats `splat` holds: each pixel's value is its samples' mean plus its
    /// splats' sum divided by this.
    pub splat_paths: u64,
}

/// Splats made by one worker, added to the film in one step ([`Film::add_splats`]) so that
/// workers share no lock per splat. The film's sums are integers, so the image is the same
/// bits in whatever order workers add their splats.
#[derive(Clone, Debug, Default)]
pub struct Splats {
    /// (pixel index, contribution).
    pub values: Vec<(u32, Color)>,
    /// Paths traced, whether or not they splatted anything.
    pub paths: u64,
}

impl Splats {
    /// A contribution `l` to pixel (x, y) of a `width`-pixel-wide film.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, width: u32, l: Color) {
        self.values.push((y * width + x, l));
    }
}

/// One pixel's accumulated samples, gathered by a tile before it is written to the film.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelSums {
    pub sum: [i128; 3],
    pub sum_sq: [i128; 3],
    pub count: u32,
}

impl PixelSums {
    #[inline(always)]
    pub fn add(&mut self, l: Color) {
        // (An array, not `l[c]`: where the loop stays a loop, Vec3's index is a match.)
        for (c, v) in l.to_array().into_iter().enumerate() {
            // Equal to fixed_sum(v as f64) and fixed_sq((v as f64)²), without floats.
            self.sum[c] = self.sum[c].wrapping_add(fixed_from_f32(v, SUM_FRAC_BITS));
            self.sum_sq[c] = self.sum_sq[c].wrapping_add(fixed_sq_from_f32(v, SQ_FRAC_BITS));
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
            splat: Vec::new(),
            splat_paths: 0,
        }
    }

    /// Adds a worker's splats; non-finite contributions are dropped (and counted), as
    /// non-finite samples are.
    pub fn add_splats(&mut self, s: &Splats) -> u64 {
        if self.splat.is_empty() && !s.values.is_empty() {
            self.splat = vec![[0; 3]; self.sum.len()];
        }
        let mut dropped = 0;
        for &(i, l) in &s.values {
            if !l.is_finite() {
                dropped += 1;
                continue;
            }
            let p = &mut self.splat[i as usize];
            for c in 0..3 {
                p[c] = p[c].wrapping_add(fixed_from_f32(l[c], SUM_FRAC_BITS));
            }
        }
        self.splat_paths += s.paths;
        dropped
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
        if !other.splat.is_empty() {
            if self.splat.is_empty() {
                self.splat = vec![[0; 3]; self.sum.len()];
            }
            for (a, b) in self.splat.iter_mut().zip(&other.splat) {
                for c in 0..3 {
                    a[c] = a[c].wrapping_add(b[c]);
                }
            }
        }
        self.splat_paths += other.splat_paths;
    }

    /// Σ L per pixel and channel as numbers.
    pub fn sum_f64(&self) -> Vec<[f64; 3]> {
        self.sum.iter().map(|s| s.map(sum_to_f64)).collect()
    }

    /// Σ L² per pixel and channel as numbers.
    pub fn sum_sq_f64(&self) -> Vec<[f64; 3]> {
        self.sum_sq.iter().map(|s| s.map(sq_to_f64)).collect()
    }

    /// The image: the mean of each pixel's samples, plus its splats over the paths traced.
    pub fn image(&self) -> Image {
        let ks = if self.splat_paths > 0 {
            1.0 / self.splat_paths as f64
        } else {
            0.0
        };
        let pixels = self
            .sum
            .iter()
            .zip(&self.count)
            .enumerate()
            .map(|(i, (s, &n))| {
                let k = if n > 0 { 1.0 / n as f64 } else { 0.0 };
                let mut v = s.map(|x| sum_to_f64(x) * k);
                if let Some(sp) = self.splat.get(i) {
                    for c in 0..3 {
                        v[c] += sum_to_f64(sp[c]) * ks;
                    }
                }
                Color::new(v[0] as f32, v[1] as f32, v[2] as f32)
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

    /// The integer conversions give exactly what the f64 ones give, for every kind of f32:
    /// zero, subnormals, values that round at half a unit, ordinary and huge ones.
    #[test]
    fn integer_conversion_matches_f64() {
        let mut vals = vec![
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.5,
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
        ];
        vals.extend([
            f32::MAX,
            f32::MIN,
            2.0f32.powi(-64),
            2.0f32.powi(-65),
            3.0 * 2.0f32.powi(-66),
        ]);
        vals.extend([
            2.0f32.powi(-24),
            2.0f32.powi(-25),
            1.5 * 2.0f32.powi(-25),
            9.2e18,
            3e38,
        ]);
        // And a million pseudo-random finite bit patterns over the whole range.
        let mut x = 0x1234_5678_9abc_def0u64;
        while vals.len() < 1_000_000 {
            x = crate::sampler::mix64(x);
            let v = f32::from_bits(x as u32);
            if v.is_finite() {
                vals.push(v);
            }
        }
        for v in vals {
            assert_eq!(
                fixed_from_f32(v, SUM_FRAC_BITS),
                fixed_sum(v as f64),
                "Σ of {v:e}"
            );
            let v2 = v as f64 * v as f64;
            assert_eq!(
                fixed_sq_from_f32(v, SQ_FRAC_BITS),
                fixed_sq(v2),
                "Σ² of {v:e}"
            );
        }
    }

    /// A sample's channels go to their own sums: red to `sum[0]`, green to `sum[1]`, blue to
    /// `sum[2]`, their squares likewise, and each sample counts once.
    #[test]
    fn pixel_sums_keep_the_channels_apart() {
        let samples = [
            [0.25f32, 3.0, 1e-3],
            [0.5, -2.0, 7.0],
            [1e-30, 0.0, 65504.0],
        ];
        let mut s = PixelSums::default();
        for [r, g, b] in samples {
            s.add(Color::new(r, g, b));
        }
        for c in 0..3 {
            let sum: i128 = samples.iter().map(|v| fixed_sum(v[c] as f64)).sum();
            let sq: i128 = samples
                .iter()
                .map(|v| fixed_sq(v[c] as f64 * v[c] as f64))
                .sum();
            assert_eq!((s.sum[c], s.sum_sq[c]), (sum, sq), "channel {c}");
        }
        assert_eq!(s.count, 3);
    }

    /// Splats added by workers in any order, and films added in any order, give the same
    /// bits; the image is each pixel's mean plus its splats over the paths traced.
    #[test]
    fn splats_do_not_depend_on_order() {
        let vals = [1.0e10f32, 3.0e-6, 3.0e-6, 0.1, 0.7, 1.0e-6, 2.5];
        let mut workers: Vec<Splats> = (0..3).map(|_| Splats::default()).collect();
        for (k, &v) in vals.iter().enumerate() {
            workers[k % 3].add((k % 2) as u32, 1, 2, Color::new(v, -v, 0.5 * v));
            workers[k % 3].paths += 2;
        }
        workers[1].add(0, 0, 2, Color::new(f32::NAN, 0.0, 0.0));
        let film_of = |order: &[usize]| {
            let mut f = Film::new(2, 2);
            let mut dropped = 0;
            for &w in order {
                dropped += f.add_splats(&workers[w]);
            }
            (f, dropped)
        };
        let (a, da) = film_of(&[0, 1, 2]);
        let (b, db) = film_of(&[2, 0, 1]);
        assert_eq!((da, db), (1, 1));
        assert!(a == b, "splat order changed the film");
        assert_eq!(a.splat_paths, 2 * vals.len() as u64);
        // Two films, each with some of the splats, added in either order.
        let (mut c, _) = film_of(&[0]);
        let (d, _) = film_of(&[1, 2]);
        let (mut d2, _) = film_of(&[1, 2]);
        c.add_film(&d);
        d2.add_film(&film_of(&[0]).0);
        assert!(c == a && d2 == a, "film addition changed the splats");
        // The image: pixel (1, 1) has the odd-indexed values, pixel (0, 1) the even ones.
        let mut px = PixelSums::default();
        px.add(Color::splat(4.0));
        let mut e = a.clone();
        e.set_pixel(1, 1, &px);
        let img = e.image();
        let odd: f64 = vals.iter().skip(1).step_by(2).map(|&v| v as f64).sum();
        let want = 4.0 + odd / a.splat_paths as f64;
        assert!(
            (img.pixels[3].x as f64 - want).abs() <= 1e-6 * want,
            "{:?}",
            img.pixels[3]
        );
        assert_eq!(
            img.pixels[1],
            Color::ZERO,
            "a pixel without samples or splats"
        );
    }

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
