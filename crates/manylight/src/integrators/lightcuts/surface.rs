//! What the lightcut integrators add for the whole image (`docs/theory.md` §2.1): surface VPLs
//! lighting camera segments, and every light (VRLs or VPLs of both trees, surface VPLs) lighting
//! gathering surface points. **Ours, and not the tree:** these receivers sample `cut_size`
//! lights with probability proportional to their flux bound (`PowerSampler`) and weight each by
//! `1 / (k p)`, which is unbiased; cutting the tree for a point receiver is open (issue #13).

use crate::vpl::SurfaceVpl;
use haze_core::Rgb;

/// Sampling of indices `i` with probability `w_i / sum w` (a cumulative table, binary search).
#[derive(Clone, Debug, Default)]
pub struct PowerSampler {
    cdf: Vec<f64>,
}

impl PowerSampler {
    /// From non-negative weights (non-finite ones count as zero).
    pub fn new(weights: impl Iterator<Item = f32>) -> Self {
        let mut total = 0.0f64;
        let cdf = weights
            .map(|w| {
                total += if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 };
                total
            })
            .collect();
        PowerSampler { cdf }
    }

    /// `(index, probability)` for the uniform number `u` in `[0, 1)`; `None` if every weight
    /// is zero.
    pub fn sample(&self, u: f32) -> Option<(usize, f64)> {
        let total = *self.cdf.last()?;
        if total <= 0.0 {
            return None;
        }
        let t = u as f64 * total;
        let i = self.cdf.partition_point(|&c| c <= t).min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let p = (self.cdf[i] - lo) / total;
        (p > 0.0).then_some((i, p))
    }
}

/// The weight of a surface VPL in [`PowerSampler`]s: its largest flux channel.
pub fn surface_vpl_weight(v: &SurfaceVpl) -> f32 {
    v.flux.max_component()
}

/// `sum_j c(i_j) / (k p(i_j))` over `k` lights drawn by `sampler` with the uniform numbers
/// `u(j)`: an unbiased estimate of `sum_i c(i)`.
pub fn sampled_sum(
    sampler: &PowerSampler,
    k: usize,
    mut u: impl FnMut(usize) -> f32,
    mut c: impl FnMut(usize) -> Rgb,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for j in 0..k {
        if let Some((i, p)) = sampler.sample(u(j)) {
            sum += c(i) * (1.0 / (k as f64 * p)) as f32;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_sampler_probabilities_match_weights() {
        let s = PowerSampler::new([1.0f32, 0.0, 3.0, f32::NAN].into_iter());
        let mut counts = [0usize; 4];
        let n = 40_000;
        for j in 0..n {
            let (i, p) = s.sample((j as f32 + 0.5) / n as f32).unwrap();
            counts[i] += 1;
            assert!((p - [0.25, 0.0, 0.75, 0.0][i]).abs() < 1e-12);
        }
        assert_eq!(counts, [10_000, 0, 30_000, 0]);
        assert!(PowerSampler::new([0.0f32].into_iter()).sample(0.5).is_none());
        // The estimator is exact when the contributions are proportional to the weights.
        let est = sampled_sum(&s, 3, |j| [0.1, 0.6, 0.9][j], |i| Rgb::splat([2.0, 0.0, 6.0, 0.0][i]));
        assert!((est[0] - 8.0).abs() < 1e-5, "{est:?}");
    }
}
