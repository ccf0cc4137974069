//! A distance density along a segment of a heterogeneous medium that follows the medium itself:
//! the in-scattering integrand's `sigma_s(x) T(0, x)`, tabulated by ray marching (Kulla &
//! Fajardo 2012, "Importance sampling techniques for path tracing in participating media", Section 4.2,
//! which builds the same table for its equiangular/density product). `docs/theory.md` §12.5,
//! (T34).
//!
//! The segment `[0, len]` is cut into [`MARCH_CELLS`] equal cells; cell `k` takes the grey
//! (channel-mean) `sigma_t,k` and `sigma_s,k` at its midpoint and the optical depth `tau_k` of
//! the cells before it, and gets the mass of `sigma_s e^{-tau_k - sigma_t s}` over its width `D`:
//!
//! ```text
//! m_k = sigma_s,k / sigma_t,k e^{-tau_k} (1 - e^{-sigma_t,k D})      (sigma_s,k D e^{-tau_k} if sigma_t,k = 0)
//! p(t) = m_k / (D sum_j m_j)                                            for t in cell k
//! ```
//!
//! The density is a deterministic function of the segment, so another strategy's sample can
//! evaluate it (the one-sample mixtures, (T35)). It is only a proposal: it is zero in cells
//! whose midpoint has no medium, so it must be mixed with a strategy of full support (the
//! geometric ones), which keeps every estimate unbiased.
//!
//! Why not the majorant's exponential (the first tentative collision of delta tracking): in a
//! grid whose majorant is loose (the peers' noisy `sigmat.vol` collapses to one global cell,
//! `sigma_maj` about 10 times the mean) that density has decayed by `e^{-7}` half-way through
//! the medium, where the true transmittance is still high, so the few samples that land there
//! carry weights of thousands of times the mean: on Mitsuba 3's `test_hetero_sigmat` the top
//! 1% of single-scattering samples held 68% of a pixel's value.

use crate::hetero::Heterogeneous;
use glam::Vec3;

/// Cells of the table: a fixed count, so the table lives on the stack (the estimators build
/// one per light evaluation) and costs `MARCH_CELLS` lookups of the medium.
pub const MARCH_CELLS: usize = 32;

/// The tabulated density of a segment `o + t d`, `t` in `[0, len]`.
#[derive(Clone, Debug)]
pub struct MarchedDistance {
    len: f32,
    /// Cumulative masses, `cdf[0] = 0`, `cdf[MARCH_CELLS]` the total.
    cdf: [f32; MARCH_CELLS + 1],
}

impl MarchedDistance {
    /// `None` where the midpoints see no scattering medium (or the segment is degenerate).
    pub fn new(h: &Heterogeneous, o: Vec3, d: Vec3, len: f32) -> Option<Self> {
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let width = len / MARCH_CELLS as f32;
        let mut cdf = [0.0f32; MARCH_CELLS + 1];
        let mut tau = 0.0f32;
        for k in 0..MARCH_CELLS {
            let (sigma_t, sigma_s) = h.coefficients(o + d * ((k as f32 + 0.5) * width));
            let (st, ss) = (sigma_t.mean(), sigma_s.mean());
            let mass = if st * width > 1e-4 {
                ss / st * (-tau).exp() * -(-st * width).exp_m1()
            } else {
                ss * width * (-tau).exp()
            };
            tau += st * width;
            cdf[k + 1] = cdf[k] + mass.max(0.0);
        }
        let total = cdf[MARCH_CELLS];
        (total > 0.0 && total.is_finite()).then_some(MarchedDistance { len, cdf })
    }

    /// A distance with density [`Self::pdf`], by inversion of the piecewise-linear CDF.
    pub fn sample(&self, u: f32) -> f32 {
        let target = u * self.cdf[MARCH_CELLS];
        // The first cell whose upper cumulative mass exceeds the target (cells of zero mass
        // are never chosen).
        let k = self.cdf[1..].partition_point(|&c| c <= target).min(MARCH_CELLS - 1);
        let mass = self.cdf[k + 1] - self.cdf[k];
        let frac = if mass > 0.0 { ((target - self.cdf[k]) / mass).clamp(0.0, 1.0) } else { 0.5 };
        let width = self.len / MARCH_CELLS as f32;
        ((k as f32 + frac) * width).min(self.len)
    }

    /// `p(t)` per unit length; 0 outside `[0, len]`.
    pub fn pdf(&self, t: f32) -> f32 {
        if !(0.0..=self.len).contains(&t) {
            return 0.0;
        }
        let width = self.len / MARCH_CELLS as f32;
        let k = ((t / width) as usize).min(MARCH_CELLS - 1);
        (self.cdf[k + 1] - self.cdf[k]) / (self.cdf[MARCH_CELLS] * width)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hetero::MajorantGrid;
    use crate::volume::{Filter, Grid, Volume, VolumeData, Wrap};
    use glam::Affine3A;
    use haze_core::{Rgb, Sampler};
    use std::sync::Arc;

    fn medium() -> Heterogeneous {
        // A slab of dense cells in a thin medium: the density the table must follow.
        let res = [8u32, 4, 4];
        let data: Vec<f32> =
            (0..res[0] * res[1] * res[2]).map(|i| if (i % 8) == 5 { 3.0 } else { 0.2 }).collect();
        let grid = Grid { res, channels: 1, data, bbox: (Vec3::ZERO, Vec3::ONE) };
        let sigma_t = Volume::new(
            VolumeData::Grid { grid: Arc::new(grid), filter: Filter::Nearest, wrap: Wrap::Clamp },
            Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)),
        );
        let majorants = MajorantGrid::build(&sigma_t, 2.0, [1; 3]);
        Heterogeneous { sigma_t, albedo: Volume::constant(Rgb::splat(0.8)), scale: 2.0, majorants }
    }

    /// The pdf integrates to 1, sampling follows it (chi-square over the cells), a table of
    /// the density alone (no transmittance) is told apart, and the dense slab gets the mass.
    #[test]
    fn marched_distance_samples_its_pdf() {
        use haze_testkit::chi2::chi2_test;
        let h = medium();
        let (o, d, len) = (Vec3::new(-0.3, 0.5, 0.5), Vec3::X, 2.6);
        let m = MarchedDistance::new(&h, o, d, len).expect("the segment crosses the medium");
        let steps = 100_000;
        let integral: f64 =
            (0..steps).map(|i| m.pdf((i as f32 + 0.5) * len / steps as f32) as f64).sum::<f64>() * len as f64
                / steps as f64;
        assert!((integral - 1.0).abs() < 1e-3, "pdf integrates to {integral}");
        let bins = MARCH_CELLS;
        let width = len / bins as f32;
        let expected_p: Vec<f64> =
            (0..bins).map(|k| (m.pdf((k as f32 + 0.5) * width) * width) as f64).collect();
        let n = 50_000;
        let mut s = Sampler::from_seed(5);
        let mut counts = vec![0.0f64; bins];
        for _ in 0..n {
            let t = m.sample(s.next_1d());
            counts[((t / width) as usize).min(bins - 1)] += 1.0;
        }
        let nonzero: Vec<usize> = (0..bins).filter(|&k| expected_p[k] > 0.0).collect();
        let obs: Vec<f64> = nonzero.iter().map(|&k| counts[k]).collect();
        let exp: Vec<f64> = nonzero.iter().map(|&k| expected_p[k] * n as f64).collect();
        let r = chi2_test(&obs, &exp);
        assert!(r.passed(0.01), "{r:?}");
        assert!(nonzero.len() == counts.iter().filter(|&&c| c > 0.0).count(), "a zero-mass cell was sampled");
        // Without the transmittance factor the cells behind the slab would weigh as much as
        // those before it: the chi-square must see it.
        let flat: Vec<f64> = nonzero
            .iter()
            .map(|&k| {
                let (_, ss) = h.coefficients(o + d * ((k as f32 + 0.5) * width));
                ss.mean() as f64
            })
            .collect();
        let total: f64 = flat.iter().sum();
        let exp_flat: Vec<f64> = flat.iter().map(|f| f / total * n as f64).collect();
        assert!(!chi2_test(&obs, &exp_flat).passed(0.01), "a table without transmittance went unnoticed");
        // Outside the box there is no medium: no mass before x = 0 or after x = 2.
        assert_eq!(m.pdf(0.1), 0.0);
        assert_eq!(m.pdf(2.5), 0.0);
    }
}
