//! Comparing two images: error metrics against a reference, and a false-colour map of the
//! difference.
//!
//! With test image A and reference B (linear RGB), over all N pixels and 3 channels:
//! - RMSE = sqrt(mean((A − B)²));
//! - relMSE = mean((A − B)² / (B² + 0.01)), the relative MSE common in the Monte Carlo
//!   rendering literature (the 0.01 keeps dark reference pixels from dominating);
//! - PSNR = 10·log10(1 / MSE) dB, with peak 1 (the white of a display-referred image);
//!   infinite when the images are equal.
//!
//! The difference image shows, per pixel, the mean over the channels of A − B on a
//! blue–white–red scale: white where they agree, pure red where A is brighter by `range` or
//! more, pure blue where B is (colours interpolated in linear RGB).

use crate::image::Image;
use crate::Color;

/// The ε of relMSE: (A − B)² / (B² + ε).
pub const REL_EPS: f64 = 1e-2;
/// The peak of PSNR.
pub const PSNR_PEAK: f64 = 1.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub mse: f64,
    pub rmse: f64,
    pub rel_mse: f64,
    pub psnr: f64,
    /// The largest |A − B| of any pixel's channel.
    pub max_abs: f64,
    /// The largest |mean over channels of A − B| of any pixel: the default range of the
    /// difference image.
    pub max_abs_mean: f64,
}

/// Error metrics of `a` against the reference `b`; Err if their sizes differ.
pub fn metrics(a: &Image, b: &Image) -> Result<Metrics, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {} × {} versus {} × {}",
            a.width, a.height, b.width, b.height
        ));
    }
    let (mut se, mut rel, mut max_abs, mut max_abs_mean) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let mut dm = 0.0;
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            let d = x - y;
            se += d * d;
            rel += d * d / (y * y + REL_EPS);
            max_abs = max_abs.max(d.abs());
            dm += d / 3.0;
        }
        max_abs_mean = max_abs_mean.max(dm.abs());
    }
    let n = (a.pixels.len() * 3).max(1) as f64;
    let mse = se / n;
    Ok(Metrics {
        mse,
        rmse: mse.sqrt(),
        rel_mse: rel / n,
        psnr: 10.0 * (PSNR_PEAK * PSNR_PEAK / mse).log10(),
        max_abs,
        max_abs_mean,
    })
}

/// The blue–white–red colour of a signed difference `d` on the scale ±`range`.
pub fn diverging(d: f64, range: f64) -> Color {
    let t = if range > 0.0 {
        (d / range).clamp(-1.0, 1.0) as f32
    } else {
        0.0
    };
    if t >= 0.0 {
        Color::new(1.0, 1.0 - t, 1.0 - t)
    } else {
        Color::new(1.0 + t, 1.0 + t, 1.0)
    }
}

/// The difference image of `a` and `b` (same size): per pixel, [`diverging`] of the mean over
/// the channels of A − B.
pub fn diff_image(a: &Image, b: &Image, range: f64) -> Image {
    let pixels = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            let d = (0..3).map(|c| p[c] as f64 - q[c] as f64).sum::<f64>() / 3.0;
            diverging(d, range)
        })
        .collect();
    Image {
        width: a.width,
        height: a.height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(v: f32) -> Image {
        let mut i = Image::new(4, 3);
        i.pixels.iter_mut().for_each(|p| *p = Color::splat(v));
        i
    }

    #[test]
    fn known_metrics() {
        let m = metrics(&constant(0.75), &constant(0.5)).unwrap();
        assert!((m.rmse - 0.25).abs() < 1e-12);
        assert!((m.rel_mse - 0.0625 / 0.26).abs() < 1e-12);
        assert!((m.psnr - 10.0 * (1.0 / 0.0625f64).log10()).abs() < 1e-9);
        assert_eq!(m.max_abs, 0.25);
        let same = metrics(&constant(0.5), &constant(0.5)).unwrap();
        assert_eq!((same.rmse, same.psnr), (0.0, f64::INFINITY));
        assert!(metrics(&constant(0.5), &Image::new(3, 4)).is_err());
    }

    #[test]
    fn colours() {
        assert_eq!(diverging(0.0, 1.0), Color::ONE);
        assert_eq!(diverging(2.0, 1.0), Color::new(1.0, 0.0, 0.0));
        assert_eq!(diverging(-1.0, 1.0), Color::new(0.0, 0.0, 1.0));
        assert_eq!(diverging(0.5, 1.0), Color::new(1.0, 0.5, 0.5));
    }
}
