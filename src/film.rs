//! The film: per-pixel sums of radiance samples (box filter: every sample of a pixel counts
//! equally), kept in f64 so that sums over many passes stay exact enough to merge.

use crate::image::Image;
use crate::Color;

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Σ L per pixel and channel.
    pub sum: Vec<[f64; 3]>,
    /// Σ L² per pixel and channel (for the variance of the mean).
    pub sum_sq: Vec<[f64; 3]>,
    /// Samples per pixel that reached the film.
    pub count: Vec<u32>,
}

/// One pixel's accumulated samples, gathered by a tile before it is written to the film.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelSums {
    pub sum: [f64; 3],
    pub sum_sq: [f64; 3],
    pub count: u32,
}

impl PixelSums {
    #[inline]
    pub fn add(&mut self, l: Color) {
        for c in 0..3 {
            let v = l[c] as f64;
            self.sum[c] += v;
            self.sum_sq[c] += v * v;
        }
        self.count += 1;
    }
}

impl Film {
    pub fn new(width: u32, height: u32) -> Film {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
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

    /// The image: the mean of each pixel's samples.
    pub fn image(&self) -> Image {
        let pixels = self
            .sum
            .iter()
            .zip(&self.count)
            .map(|(s, &n)| {
                let k = if n > 0 { 1.0 / n as f64 } else { 0.0 };
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
                    for c in 0..3 {
                        let mean = self.sum[i][c] / n;
                        let s2 = ((self.sum_sq[i][c] - n * mean * mean) / (n - 1.0)).max(0.0);
                        v[c] = (s2 / n) as f32;
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
