//! Pearson chi-square goodness-of-fit tests for sampling routines.

use crate::quadrature::integrate;
use glam::Vec3;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::fmt;

/// Result of a chi-square test: statistic, degrees of freedom and p-value.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Samples that fell where the pdf is zero (a hard failure whatever the p-value).
    pub outside_support: usize,
}

impl Chi2Result {
    /// Passes when `p >= alpha` and no sample fell outside the pdf's support.
    pub fn passed(&self, alpha: f64) -> bool {
        self.p_value >= alpha && self.outside_support == 0
    }
}

impl fmt::Display for Chi2Result {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chi2 = {:.2}, dof = {}, p = {:.4}, samples outside support = {}",
            self.statistic, self.dof, self.p_value, self.outside_support
        )
    }
}

/// Chi-square test of observed counts against expected counts. Bins whose expected count is
/// below 5 are pooled (the usual validity rule), as Mitsuba's `chi2` module does.
pub fn chi2_test(observed: &[f64], expected: &[f64]) -> Chi2Result {
    assert_eq!(observed.len(), expected.len());
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut stat = 0.0;
    let mut bins = 0usize;
    let mut outside = 0usize;
    for &i in &idx {
        if expected[i] == 0.0 {
            if observed[i] > 0.0 {
                outside += observed[i] as usize;
            }
            continue;
        }
        if expected[i] < 5.0 || pool_e > 0.0 && pool_e < 5.0 {
            pool_o += observed[i];
            pool_e += expected[i];
            if pool_e >= 5.0 {
                stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                bins += 1;
                pool_o = 0.0;
                pool_e = 0.0;
            }
            continue;
        }
        stat += (observed[i] - expected[i]).powi(2) / expected[i];
        bins += 1;
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        bins += 1;
    }
    let dof = bins.saturating_sub(1).max(1);
    let p_value = 1.0 - ChiSquared::new(dof as f64).unwrap().cdf(stat);
    Chi2Result { statistic: stat, dof, p_value, outside_support: outside }
}

/// Chi-square test of a direction sampler against its pdf (per steradian). The sphere is cut
/// into `N_COS x N_PHI` bins of equal solid angle in `(cos theta, phi)`; expected counts come
/// from integrating `pdf` over each bin with a 4x4 midpoint rule per sub-cell (8x8 sub-cells).
pub fn chi2_sphere(mut sample: impl FnMut() -> Vec3, pdf: impl Fn(Vec3) -> f32, n: usize) -> Chi2Result {
    const N_COS: usize = 40;
    const N_PHI: usize = 80;
    let mut observed = vec![0.0f64; N_COS * N_PHI];
    let mut outside = 0usize;
    let bin_of = |d: Vec3| -> usize {
        let c = (((d.z.clamp(-1.0, 1.0) + 1.0) * 0.5 * N_COS as f32) as usize).min(N_COS - 1);
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += 2.0 * std::f32::consts::PI;
        }
        let p = ((phi / (2.0 * std::f32::consts::PI) * N_PHI as f32) as usize).min(N_PHI - 1);
        c * N_PHI + p
    };
    for _ in 0..n {
        let d = sample();
        if !d.is_finite() || (d.length() - 1.0).abs() > 1e-3 {
            outside += 1;
            continue;
        }
        observed[bin_of(d)] += 1.0;
    }
    let sub = 8;
    let dc = 2.0 / N_COS as f64;
    let dp = 2.0 * std::f64::consts::PI / N_PHI as f64;
    let mut expected = vec![0.0f64; N_COS * N_PHI];
    for c in 0..N_COS {
        for p in 0..N_PHI {
            let mut acc = 0.0f64;
            for i in 0..sub {
                for j in 0..sub {
                    let z = -1.0 + dc * (c as f64 + (i as f64 + 0.5) / sub as f64);
                    let phi = dp * (p as f64 + (j as f64 + 0.5) / sub as f64);
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    acc += pdf(d) as f64;
                }
            }
            expected[c * N_PHI + p] = acc / (sub * sub) as f64 * dc * dp * n as f64;
        }
    }
    let mut r = chi2_test(&observed, &expected);
    r.outside_support += outside;
    r
}

/// Chi-square test of a sampler on the interval `[a, b]` against a density `pdf` (per unit
/// length), with `bins` equal bins and expected counts from a 16-point midpoint rule per bin.
/// Samples outside `[a, b]` count as outside the support.
pub fn chi2_interval(
    mut sample: impl FnMut() -> f64,
    pdf: impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    bins: usize,
    n: usize,
) -> Chi2Result {
    let w = (b - a) / bins as f64;
    let sub = 16;
    interval_test(&mut sample, a, b, bins, n, |i| {
        (0..sub).map(|j| pdf(a + w * (i as f64 + (j as f64 + 0.5) / sub as f64))).sum::<f64>() / sub as f64
            * w
    })
}

/// [`chi2_interval`] with expected counts from adaptive quadrature of the pdf over each bin,
/// split at `peaks`: for densities with peaks narrower than a bin's midpoint rule resolves.
pub fn chi2_interval_peaked(
    mut sample: impl FnMut() -> f64,
    pdf: impl Fn(f64) -> f64,
    a: f64,
    b: f64,
    peaks: &[f64],
    bins: usize,
    n: usize,
) -> Chi2Result {
    let w = (b - a) / bins as f64;
    interval_test(&mut sample, a, b, bins, n, |i| {
        integrate(&pdf, a + w * i as f64, a + w * (i + 1) as f64, peaks, 1e-9)
    })
}

/// Counts `n` samples in `bins` equal bins of `[a, b]` and tests the counts against
/// `n * probability(i)` for bin `i`; samples outside `[a, b]` count as outside the support.
fn interval_test(
    sample: &mut dyn FnMut() -> f64,
    a: f64,
    b: f64,
    bins: usize,
    n: usize,
    probability: impl Fn(usize) -> f64,
) -> Chi2Result {
    let w = (b - a) / bins as f64;
    let mut observed = vec![0.0f64; bins];
    let mut outside = 0usize;
    for _ in 0..n {
        let x = sample();
        if !(x >= a && x <= b) {
            outside += 1;
            continue;
        }
        observed[(((x - a) / w) as usize).min(bins - 1)] += 1.0;
    }
    let expected: Vec<f64> = (0..bins).map(|i| probability(i) * n as f64).collect();
    let mut r = chi2_test(&observed, &expected);
    r.outside_support += outside;
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_test_accepts_right_and_rejects_wrong_density() {
        let mut state = 12345u64;
        let mut uni = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // x = sqrt(u) has density 2x on [0, 1].
        let mut s1 = uni;
        let ok = chi2_interval(|| s1().sqrt(), |x| 2.0 * x, 0.0, 1.0, 50, 100_000);
        assert!(ok.passed(0.01), "{ok}");
        let bad = chi2_interval(|| uni().sqrt(), |_| 1.0, 0.0, 1.0, 50, 100_000);
        assert!(!bad.passed(0.01), "{bad}");
    }
}
