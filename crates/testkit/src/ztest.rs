//! Per-pixel z-test of a rendered image against a reference, both with noise.
//!
//! For every pixel channel, `z = (mean - ref) / sqrt(var_mean + var_ref)` where `var_mean` is the
//! variance of the rendered pixel's mean (sample variance / sample count) and `var_ref` the
//! reference's noise. Under the null hypothesis (both estimate the same value) `z` is standard
//! normal. With `n` channel-pixels tested, a Sidak-corrected per-test level
//! `alpha_1 = 1 - (1 - alpha)^(1/n)` keeps the family-wise false-alarm rate at `alpha`; we allow a
//! small fraction of failing channel-pixels (Mitsuba 3's render tests allow 0.25%) because
//! per-pixel variance estimates from few samples are themselves noisy, and add a second gate on
//! the image mean, where noise averages out and a systematic error shows clearly.

use statrs::distribution::{ContinuousCDF, Normal};
use std::fmt;

/// Outcome of [`z_test`].
#[derive(Clone, Debug)]
pub struct ZTestReport {
    pub tested: usize,
    pub failed: usize,
    pub threshold: f64,
    /// z-score of the image mean (all pixels and channels) against the reference mean.
    pub mean_z: f64,
    pub mean: f64,
    pub reference_mean: f64,
    pub max_abs_z: f64,
}

impl ZTestReport {
    pub fn failed_fraction(&self) -> f64 {
        self.failed as f64 / self.tested.max(1) as f64
    }
    /// Passes when at most `max_failed_fraction` of channel-pixels fail the Sidak-corrected test
    /// and the image-mean z-score is below `mean_z_limit`.
    pub fn passed(&self, max_failed_fraction: f64, mean_z_limit: f64) -> bool {
        self.failed_fraction() <= max_failed_fraction && self.mean_z.abs() <= mean_z_limit
    }
}

impl fmt::Display for ZTestReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} of {} channel-pixels fail |z| > {:.2} ({:.3}%), max |z| = {:.2}; image mean {:.6} vs reference {:.6}, mean z = {:.2}",
            self.failed,
            self.tested,
            self.threshold,
            100.0 * self.failed_fraction(),
            self.max_abs_z,
            self.mean,
            self.reference_mean,
            self.mean_z
        )
    }
}

/// The two-sided z threshold of a level-`alpha` test Sidak-corrected over `tests` tests:
/// `Phi^-1(1 - alpha_1 / 2)` with `alpha_1 = 1 - (1 - alpha)^(1 / tests)`.
pub fn sidak_threshold(alpha: f64, tests: usize) -> f64 {
    let alpha_1 = 1.0 - (1.0 - alpha).powf(1.0 / tests as f64);
    Normal::standard().inverse_cdf(1.0 - alpha_1 / 2.0)
}

/// Per-pixel z-test. All slices hold the same number of values (pixels x channels).
/// `var_mean[i]` is the variance of `mean[i]` as an estimator; `var_ref[i]` the reference's.
/// A channel-pixel where both variances are zero passes only if the values agree to 1e-6.
pub fn z_test(mean: &[f32], var_mean: &[f32], reference: &[f32], var_ref: &[f32], alpha: f64) -> ZTestReport {
    let n = mean.len();
    assert!(var_mean.len() == n && reference.len() == n && var_ref.len() == n);
    let alpha_1 = 1.0 - (1.0 - alpha).powf(1.0 / n as f64);
    let threshold = Normal::standard().inverse_cdf(1.0 - alpha_1 / 2.0);
    let (mut failed, mut max_abs_z) = (0usize, 0.0f64);
    let (mut sum, mut sum_ref, mut var_sum) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..n {
        let (m, r) = (mean[i] as f64, reference[i] as f64);
        let v = var_mean[i] as f64 + var_ref[i] as f64;
        sum += m;
        sum_ref += r;
        var_sum += v;
        let bad = if v > 0.0 {
            let z = (m - r).abs() / v.sqrt();
            max_abs_z = max_abs_z.max(z);
            z > threshold
        } else {
            (m - r).abs() > 1e-6
        };
        failed += bad as usize;
    }
    // The pixel means are independent, so Var(sum) = sum of variances.
    let mean_z = if var_sum > 0.0 { (sum - sum_ref) / var_sum.sqrt() } else { 0.0 };
    ZTestReport {
        tested: n,
        failed,
        threshold,
        mean_z,
        mean: sum / n as f64,
        reference_mean: sum_ref / n as f64,
        max_abs_z,
    }
}

/// Estimates the per-pixel noise variance of a converged reference image from its local
/// roughness: the variance of the difference between a pixel and the mean of its 4-neighbours,
/// scaled by `4/5` (for independent noise of variance `s^2`, `Var(x - mean4) = s^2 (1 + 1/4)`).
/// Image structure inflates this estimate, which makes the z-test more lenient only where the
/// reference has edges. Returns one variance per channel-pixel.
pub fn reference_noise_from_roughness(
    reference: &[f32],
    width: usize,
    height: usize,
    channels: usize,
) -> Vec<f32> {
    let idx = |x: usize, y: usize, c: usize| (y * width + x) * channels + c;
    let mut out = vec![0.0f32; reference.len()];
    for y in 0..height {
        for x in 0..width {
            for c in 0..channels {
                let mut acc = 0.0f32;
                let mut k = 0;
                for (dx, dy) in [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < width && (ny as usize) < height {
                        acc += reference[idx(nx as usize, ny as usize, c)];
                        k += 1;
                    }
                }
                let d = reference[idx(x, y, c)] - acc / k as f32;
                out[idx(x, y, c)] = d * d * 0.8;
            }
        }
    }
    out
}

/// Guards a per-pixel variance estimate against pixels whose few samples all missed the
/// rare, bright part of their integrand (then the sample variance is zero or far too small,
/// and any difference looks infinitely significant). Each channel-pixel's variance becomes the
/// larger of its own and the mean over its 3x3 neighbourhood: the variance field of a render is
/// spatially smooth except at edges, where the neighbourhood is the better estimate.
pub fn pool_variance(var: &[f32], width: usize, height: usize, channels: usize) -> Vec<f32> {
    let idx = |x: usize, y: usize, c: usize| (y * width + x) * channels + c;
    let mut out = vec![0.0f32; var.len()];
    for y in 0..height {
        for x in 0..width {
            for c in 0..channels {
                let (mut acc, mut k) = (0.0f32, 0);
                for ny in y.saturating_sub(1)..(y + 2).min(height) {
                    for nx in x.saturating_sub(1)..(x + 2).min(width) {
                        acc += var[idx(nx, ny, c)];
                        k += 1;
                    }
                }
                out[idx(x, y, c)] = var[idx(x, y, c)].max(acc / k as f32);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_bias_and_accepts_noise() {
        let n = 10_000;
        let mut state = 1u64;
        let mut gauss = move || {
            // Box-Muller from a small LCG.
            let mut u = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            ((-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()) as f32
        };
        let reference = vec![1.0f32; n];
        let var = vec![0.01f32; n];
        let zero = vec![0.0f32; n];
        let good: Vec<f32> = (0..n).map(|_| 1.0 + 0.1 * gauss()).collect();
        let r = z_test(&good, &var, &reference, &zero, 0.01);
        assert!(r.passed(0.0025, 5.0), "{r}");
        let biased: Vec<f32> = good.iter().map(|v| v * 1.02).collect();
        let r = z_test(&biased, &var, &reference, &zero, 0.01);
        assert!(!r.passed(0.0025, 5.0), "{r}");
    }
}
