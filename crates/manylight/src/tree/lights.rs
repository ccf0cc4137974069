//! What the tree knows of a VRL or VPL: a summary with its box, intensity, flux bound and length.

use super::{Aabb, TreeLight};
use crate::vpl::Vpl;
use crate::vrl::{Vrl, VrlMedium};
use haze_core::Rgb;

/// Precomputed [`TreeLight`] data of one virtual light.
#[derive(Clone, Copy, Debug)]
pub struct LightSummary {
    pub bounds: Aabb,
    pub intensity: f32,
    pub flux_bound: Rgb,
    pub length: f32,
    pub power: Rgb,
}

impl TreeLight for LightSummary {
    fn bounds(&self) -> Aabb {
        self.bounds
    }
    fn intensity(&self) -> f32 {
        self.intensity
    }
    fn flux_bound(&self) -> Rgb {
        self.flux_bound
    }
    fn length(&self) -> f32 {
        self.length
    }
    fn power(&self) -> Rgb {
        self.power
    }
}

impl LightSummary {
    /// A VRL's summary. Its flux at `v` is `flux T(v) / mean(ratio T(v))` (or `flux T(v)` with a
    /// zero ratio, see `Vrl::flux_at`); per channel `c` that is
    /// `flux_c / mean_k(ratio_k T_k(v) / T_c(v))`, and each term of the mean is monotone in
    /// `v`, so its minimum over the segment is at an end: the bound takes the smaller end value
    /// of every term.
    pub fn vrl(vrl: &Vrl, medium: &VrlMedium) -> Self {
        let len = vrl.seg.len;
        let flux_bound = if vrl.ratio.is_black() {
            vrl.flux
        } else {
            let s = medium.sigma_t;
            Rgb(std::array::from_fn(|c| {
                let denom: f32 =
                    (0..3).map(|k| vrl.ratio[k] * (-(s[k] - s[c]) * len).exp().min(1.0)).sum::<f32>() / 3.0;
                if denom > 0.0 {
                    vrl.flux[c] / denom
                } else {
                    0.0
                }
            }))
        };
        LightSummary {
            bounds: Aabb::from_points(vrl.seg.o, vrl.seg.end()),
            intensity: flux_bound.max_component(),
            flux_bound,
            length: len,
            power: vrl_power(vrl, medium.sigma_t),
        }
    }

    pub fn vpl(vpl: &Vpl) -> Self {
        LightSummary {
            bounds: Aabb::from_points(vpl.p, vpl.p),
            intensity: vpl.flux.max_component(),
            flux_bound: vpl.flux,
            length: 0.0,
            power: vpl.flux,
        }
    }
}

/// `Int_0^L Phi(v) dv` by Simpson's rule on `Phi(0), Phi(L/2), Phi(L)` ([`Vrl::flux_at`]).
/// Only an importance, so its quadrature error costs variance, never bias; for a VRL whose
/// flux decays by `exp(-sigma_t L)` with `sigma_t L <= 3` (free-flight lengths mostly are)
/// the rule is within 2% of the integral. A zero-length VRL gets its flux (times a tiny
/// length) so that it keeps a positive importance.
fn vrl_power(vrl: &Vrl, sigma_t: Rgb) -> Rgb {
    let len = vrl.seg.len.max(1e-12);
    let (a, m, b) = (vrl.flux_at(sigma_t, 0.0), vrl.flux_at(sigma_t, 0.5 * len), vrl.flux_at(sigma_t, len));
    (a + m * 4.0 + b) * (len / 6.0)
}
