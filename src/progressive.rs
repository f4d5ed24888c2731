//! Long renders: progressive passes under budgets (samples, time, noise), interruption between
//! steps of a tile's samples, and the noise estimate that `--target-noise` and `--adaptive` use.
//!
//! # Passes
//!
//! A render is a sequence of passes. Each pass renders, for every pixel i, the samples
//! [next[i], target[i]) of that pixel's sample sequence and advances next[i]
//! ([`render_ranges`]). A sample depends only on (seed, pixel, index) and the film's sums are
//! exact integers, so any stopping point leaves every pixel with a *prefix* [0, next[i]) of its
//! samples, and continuing from there (in this process, or after a checkpoint in another) ends
//! with the same bits as one uninterrupted render. No sample is ever thrown away.
//!
//! Pass sizes: the samples done (the smallest next[i]) roughly double with each pass — 1, 2,
//! 4, 8, … — so the first image comes fast and the noise checks are cheap; a pass is made
//! smaller to fit the time left, the `--write-partial` interval, the `--spp` cap, and, once the
//! noise can be estimated, the samples that the estimate predicts are still needed.
//!
//! # Noise
//!
//! For pixel i with channel means m_c and estimated variances of the mean v_c
//! ([`Film::variance_of_mean`]), μ_i = (m_R + m_G + m_B)/3, σ²_i = (v_R + v_G + v_B)/3 and the
//! relative standard error r_i = σ_i / max(μ_i, ε), with ε = 1% of the image's mean μ (so that
//! black and nearly black pixels count as if they had 1% of the average brightness instead of
//! dividing by zero). The image's error is the root mean square E = sqrt(mean_i r_i²): the
//! expected relative RMS difference from the converged image. `--target-noise T` stops once
//! E ≤ T, measured only when every pixel has at least [`MIN_NOISE_SPP`] samples (variance
//! estimates from fewer are unreliable). With `--adaptive`, passes after that render only the
//! pixels with r_i > T, each as many more samples as r_i ∝ 1/√n predicts it needs (at most
//! doubling); the others keep all their samples and stop.

use crate::film::Film;
use crate::integrator;
use crate::render::{render_ranges, RenderError, RenderSettings, RenderStats};
use crate::scene::Scene;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Samples every pixel needs before the noise estimate is used.
pub const MIN_NOISE_SPP: u32 = 16;

/// When a render stops.
#[derive(Clone, Debug, Default)]
pub struct Budget {
    /// At most this many samples per pixel (None: no limit).
    pub spp: Option<u32>,
    /// Wall-clock time for the passes and for making the integrator ready (photon maps).
    pub time: Option<Duration>,
    /// Stop when the relative standard error E falls to this.
    pub target_noise: Option<f64>,
    /// Spend passes after the first noise estimate only on pixels above the target.
    pub adaptive: bool,
    /// Keep passes shorter than this (the `--write-partial` interval).
    pub max_pass: Option<Duration>,
}

/// Why the render stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// Every pixel has its `spp` samples.
    Spp,
    /// The time budget is spent.
    Time,
    /// The noise estimate E met the target.
    Noise(f64),
    /// SIGINT or SIGTERM (the cancel flag).
    Interrupted,
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Spp => write!(f, "spp reached"),
            Stop::Time => write!(f, "time budget spent"),
            Stop::Noise(e) => write!(f, "noise target met (relative error {e:.4})"),
            Stop::Interrupted => write!(f, "interrupted"),
        }
    }
}

/// The relative standard error of the image (E) and of each pixel (r_i), as defined in the
/// module documentation.
pub fn relative_error(film: &Film) -> (f64, Vec<f64>) {
    let mean = film.image();
    let var = film.variance_of_mean();
    let mu: Vec<f64> = mean
        .pixels
        .iter()
        .map(|p| (p.x as f64 + p.y as f64 + p.z as f64) / 3.0)
        .collect();
    let n = mu.len().max(1) as f64;
    let eps = (0.01 * mu.iter().sum::<f64>() / n).max(f64::MIN_POSITIVE);
    let r: Vec<f64> = mu
        .iter()
        .zip(&var.pixels)
        .map(|(&m, v)| {
            let s2 = (v.x as f64 + v.y as f64 + v.z as f64) / 3.0;
            s2.sqrt() / m.max(eps)
        })
        .collect();
    let e = (r.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    (e, r)
}

/// The root mean square of the per-pixel errors `r` over each pixel's 3 × 3 neighbourhood
/// (within the image): what `--adaptive` decides by. A single pixel's estimate from few
/// samples is itself noisy, worst where a rare bright path has not been found yet; pooling
/// it with its neighbours' keeps such a pixel rendering while the region around it is noisy.
pub fn window_error(r: &[f64], width: u32, height: u32) -> Vec<f64> {
    let (w, h) = (width as i64, height as i64);
    let mut out = Vec::with_capacity(r.len());
    for y in 0..h {
        for x in 0..w {
            let (mut s, mut n) = (0.0, 0.0);
            for yy in (y - 1).max(0)..=(y + 1).min(h - 1) {
                for xx in (x - 1).max(0)..=(x + 1).min(w - 1) {
                    s += r[(yy * w + xx) as usize].powi(2);
                    n += 1.0;
                }
            }
            out.push((s / n).sqrt());
        }
    }
    out
}

/// What [`render_progressive`] did.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub stop: Stop,
    pub stats: RenderStats,
    pub passes: u32,
    /// The last noise estimate E (None if never measured).
    pub noise: Option<f64>,
}

/// Called after each pass with the film and the per-pixel samples done.
pub type AfterPass<'a, E> = dyn FnMut(&Film, &[u32]) -> Result<(), E> + 'a;

/// Renders passes into `film` (with per-pixel sample indices `next`, see the module
/// documentation) until the budget is spent or `cancel` is set. After each pass that rendered
/// anything, `after_pass(film, next)` runs (for partial images and checkpoints); an error
/// from it ends the render. The integrator is made ready once (photon maps are built before
/// the first pass, inside the time budget) and renders every pass; a stop or a spent budget
/// while it is made ready ends with [`RenderError::Interrupted`].
#[allow(clippy::too_many_arguments)]
pub fn render_progressive<E: From<RenderError>>(
    scene: &Scene,
    s: &RenderSettings,
    film: &mut Film,
    next: &mut [u32],
    budget: &Budget,
    cancel: &AtomicBool,
    after_pass: &mut AfterPass<'_, E>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Outcome, E> {
    let start = Instant::now();
    let deadline = budget.time.map(|t| start + t);
    let stop = || cancel.load(Ordering::SeqCst) || deadline.is_some_and(|d| Instant::now() >= d);
    // Stopped while it was being made ready (photon tracing): [`RenderError::Interrupted`];
    // the film and `next` are untouched.
    let integrator = integrator::prepare(scene, s, &stop)?;
    let cap = budget.spp.unwrap_or(u32::MAX);
    let npix = next.len().max(1) as f64;
    let mut stats = RenderStats::default();
    let mut passes = 0;
    let mut noise = None;
    // The integrator's setup counts in the outcome, not in the pass rate below.
    let out = |stop, pass_stats: RenderStats, passes, noise| {
        let mut stats = integrator.setup_stats();
        stats.add(&pass_stats);
        Ok(Outcome {
            stop,
            stats,
            passes,
            noise,
        })
    };
    loop {
        if cancel.load(Ordering::SeqCst) {
            return out(Stop::Interrupted, stats, passes, noise);
        }
        let done = next.iter().copied().min().unwrap_or(cap);
        if next.iter().all(|&n| n >= cap) {
            return out(Stop::Spp, stats, passes, noise);
        }
        // Per-pixel errors, once they can be trusted.
        let mut per_pixel = None;
        if let Some(t) = budget.target_noise {
            if done >= MIN_NOISE_SPP {
                let (e, r) = relative_error(film);
                noise = Some(e);
                if e <= t {
                    return out(Stop::Noise(e), stats, passes, noise);
                }
                per_pixel = Some((e, r));
            }
        }
        let now = Instant::now();
        if deadline.is_some_and(|d| now >= d) {
            return out(Stop::Time, stats, passes, noise);
        }
        // Pass size: double the samples done, within the limits.
        let mut k = done.max(1) as f64;
        let rate = if stats.samples > 0 {
            stats.samples as f64 / stats.elapsed.as_secs_f64().max(1e-6)
        } else {
            0.0
        };
        let fit = |secs: f64| (secs * rate / npix).floor().max(1.0);
        // The adaptive passes' limit per pixel: the time left and the pass length.
        let mut k_time = f64::INFINITY;
        if rate > 0.0 {
            if let Some(d) = deadline {
                k_time = k_time.min(fit((d - now).as_secs_f64()));
            }
            if let Some(m) = budget.max_pass {
                k_time = k_time.min(fit(m.as_secs_f64()));
            }
        }
        k = k.min(k_time);
        if let (Some(t), Some((e, _))) = (budget.target_noise, &per_pixel) {
            // E ∝ 1/√n: n·(E/T)² samples in all (but at least n/8 more, so that the last
            // steps are not many tiny passes).
            let more = (done as f64 * ((e / t).powi(2) - 1.0)).ceil();
            k = k.min(more.max((done / 8).max(1) as f64));
        }
        let k = k as u32;
        let uniform = (done as u64 + k as u64).min(cap as u64) as u32;
        let targets: Vec<u32> = match (&per_pixel, budget.adaptive, budget.target_noise) {
            (Some((_, r)), true, Some(t)) => next
                .iter()
                .zip(&window_error(r, film.width, film.height))
                .map(|(&n, &ri)| {
                    if ri <= t {
                        return n;
                    }
                    // Between n/8 and n more (and within the time left).
                    let more = (n as f64 * ((ri / t).powi(2) - 1.0)).ceil();
                    let more = more.clamp((n / 8).max(1) as f64, n.max(1) as f64);
                    let more = more.min(k_time) as u64;
                    (n as u64 + more).min(cap as u64) as u32
                })
                .collect(),
            _ => next.iter().map(|&n| n.max(uniform)).collect(),
        };
        if targets.iter().zip(next.iter()).all(|(t, n)| t <= n) {
            // Adaptive: every pixel below the target that could take more is at the cap.
            return out(Stop::Spp, stats, passes, noise);
        }
        let st = render_ranges(
            &*integrator,
            scene,
            s,
            film,
            next,
            &|i| targets[i],
            &stop,
            progress,
        )?;
        stats.add(&st);
        passes += 1;
        after_pass(film, next)?;
    }
}

/// Parses a duration: a number with an optional unit, `ms`, `s` (the default), `m` or `h`
/// ("90s", "10m", "1.5h", "250ms", "30").
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let bad = || format!("expected a duration such as 90s, 10m, 2h or 250ms, got '{text}'");
    let v: f64 = num.parse().map_err(|_| bad())?;
    let scale = match unit.trim() {
        "" | "s" => 1.0,
        "ms" => 1e-3,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(bad()),
    };
    let secs = v * scale;
    if !(secs.is_finite() && secs > 0.0 && secs < 1e12) {
        return Err(format!("the duration must be positive, got '{text}'"));
    }
    Ok(Duration::from_secs_f64(secs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("90s"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_duration("10m"), Ok(Duration::from_secs(600)));
        assert_eq!(parse_duration("2h"), Ok(Duration::from_secs(7200)));
        assert_eq!(parse_duration("1.5h"), Ok(Duration::from_secs(5400)));
        assert_eq!(parse_duration("30"), Ok(Duration::from_secs(30)));
        assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
        for bad in ["", "s", "10x", "-5s", "0", "1e3", "abc"] {
            assert!(parse_duration(bad).is_err(), "{bad:?}");
        }
    }
}
