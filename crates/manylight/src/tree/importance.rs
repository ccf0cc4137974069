//! The stochastic cut's importance of a light cluster for one camera segment: a cheap,
//! always finite *estimate* of the cluster's contribution (not a bound; `docs/theory.md` §11,
//! (T24); docs/lightcuts.md, "Stochastic cut"). It only steers probabilities, so any error in
//! it costs variance, never bias, as long as it is positive wherever a light can contribute.
//!
//! For a light point `y` at distance `h` from the camera's line, the camera-side integral of
//! the estimators is exactly `Int_0^s du / w(u)^2 = Theta(y) / h` (`Theta` the angle the
//! camera segment subtends from `y`; `docs/theory.md` (T9), (T13)). For a cluster with box
//! centre `c` and half-diagonal `r` we take two cheap upper bounds of that integral (`Theta <=
//! pi`; `w(u) >= d`) at *softened* distances,
//!
//! ```text
//! G = min(pi / sqrt(h_c^2 + SPREAD r^2), s / (d_c^2 + SPREAD r^2))
//! ```
//!
//! with `h_c` the distance from `c` to the camera line and `d_c` to the camera segment (both
//! also floored at `1e-4 s`). Why softened: a cluster's lights lie around `c`, so the sum over
//! them of `1 / h` is near `1 / h_c` far away and near the mean of `1 / h` over the cluster's
//! cross-section when the camera line goes through it (for a uniform disc of radius `rho`
//! that mean is `2 / rho`; `1 / sqrt(h_c^2 + rho^2 / 4)` has both limits and no kink). A hard
//! clamp at `r` (what we had, and roughly what pbrt-v4's and Cycles' light trees do with
//! `1/d^2`) makes a parent's importance disagree with its children's: every inner node near
//! the camera line gets the same `pi / r` whatever its lights, and the errors of the descent's
//! choices multiply along the path. `SPREAD` is measured (below); for two lines the exact
//! double integral of `1/d^2` grows only like `ln(1/h)` near the camera line, so a finite
//! value there loses little.
//!
//! ```text
//! I = (power . sigma_s_cam) G exp(-sigma_cam max(t_c - REACH r, 0) - sigma_conn max(d_c - REACH r, 0)) f_cam
//! ```
//!
//! `power` is the cluster's summed `Int Phi dv` per channel (flux for VPLs), `t_c` the distance
//! along the camera segment to the point nearest `c` (camera-side transmittance), the second
//! exponent the nearest connection through the camera medium (see `new`), and `f_cam` the
//! camera medium's phase function at the centre's direction, blended towards isotropic as the
//! box grows around that point (`w = min(r / d_c, 1)` of the weight goes to `1 / 4 pi`). The
//! light-side phase is left out: within a cluster the VRL directions spread, and evaluating it
//! at a leaf's midpoint made the selection worse on hg-box (g = 0.5) in the probe.
//!
//! The constants were chosen with a selection-variance probe (docs/lightcuts.md, "Choosing
//! the importance"): for sampled camera segments it evaluates every light's mean contribution
//! `c_i` and the descent's probability `p_i` and reports `sum c_i^2 / p_i / (sum c_i)^2 - 1`,
//! the relative variance that light selection adds to one sample.

use super::stochastic::SampleNode;
use crate::vrl::{Segment, VrlMedium};
use haze_core::{Phase, Rgb};
use std::f32::consts::PI;

/// Share of the squared half-diagonal `r^2` added to a cluster's squared distances (module
/// docs). Measured with the selection-variance probe (docs/lightcuts.md, "Choosing the
/// importance"): 1/16 to 1/8 are best on all five scenes, 1/4 costs up to 25% more variance,
/// the former hard clamp at `r` 2-15x.
const SPREAD: f32 = 1.0 / 16.0;
/// Share of `r` by which a cluster's transmittance distances are shortened: the mean of
/// `exp(-sigma d)` over a spread of distances exceeds its value at the mean distance (Jensen),
/// so a cluster's lights are effectively nearer. 1/4 measured best (1/2 and 0 within 10% on
/// four scenes; 0 costs 2x on the smoke room; the former 1: 1.3-1.8x).
const REACH: f32 = 0.25;

/// Everything the importance needs about one camera segment.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceContext {
    seg: Segment,
    /// `sigma_s` of the camera medium, per channel.
    sigma_s: Rgb,
    /// Mean extinction of the camera medium (camera-side transmittance).
    sigma_cam: f32,
    /// Mean extinction assumed along the connection: the camera medium's (see `new`).
    sigma_conn: f32,
    /// The camera medium's HG asymmetry, if its phase is HG.
    g: Option<f32>,
    /// Square of the distance floor `1e-4 s` (keeps point clusters on the line finite).
    floor2: f32,
}

impl ImportanceContext {
    /// The context of camera segment `seg` in `camera` medium.
    ///
    /// The connection's transmittance is estimated with the camera medium's extinction: a
    /// connection starts in that medium and, in the scenes VRLs are made for, stays in it. The
    /// bounds must take the least extinction of the scene instead (0 as soon as there is vacuum
    /// anywhere), but an importance only steers probabilities: with vacuum beside a medium
    /// (hg-box: a haze cube in vacuum), taking 0 made far lights look up to `e^5` too important
    /// and the one light per cut node was mostly a useless far one. Where a connection does
    /// leave the camera medium the estimate is off by that medium's transmittance; the cut's
    /// flux-only share keeps every light's probability positive.
    pub fn new(seg: Segment, camera: &VrlMedium) -> Self {
        let g = match camera.phase {
            Phase::HenyeyGreenstein { g } if g != 0.0 => Some(g),
            _ => None,
        };
        let floor = (1e-4 * seg.len).max(1e-7);
        ImportanceContext {
            seg,
            sigma_s: camera.sigma_s,
            sigma_cam: camera.sigma_t.mean(),
            sigma_conn: camera.sigma_t.mean(),
            g,
            floor2: floor * floor,
        }
    }

    /// The importance `I` of `node` (module docs): finite, and positive when the node has
    /// power in a channel where the camera medium scatters (unless the transmittance
    /// underflows, which the sampler's power share covers).
    #[inline]
    pub fn importance(&self, node: &SampleNode) -> f32 {
        let seg = &self.seg;
        let (c, r) = (node.center, node.radius);
        let rel = c - seg.o;
        let along = rel.dot(seg.d);
        let perp2 = (rel.length_squared() - along * along).max(0.0);
        let t = along.clamp(0.0, seg.len);
        let beyond = along - t;
        let dc2 = perp2 + beyond * beyond;
        // A cluster spread around its centre: the mean of `1 / h` over its lights is close to
        // `1 / sqrt(h_c^2 + SPREAD r^2)` (module docs).
        let spread = SPREAD * r * r;
        let h2 = (perp2 + spread).max(self.floor2);
        let d2 = (dc2 + spread).max(self.floor2);
        let geometry = (PI / h2.sqrt()).min(seg.len / d2);
        let dc = dc2.sqrt();
        let reach = REACH * r;
        let tau = self.sigma_cam * (t - reach).max(0.0) + self.sigma_conn * (dc - reach).max(0.0);
        let phase = match self.g {
            None => 1.0 / (4.0 * PI),
            Some(g) => {
                // cos between the light's propagation (c -> nearest camera point) and -d.
                let cos = if dc > 0.0 { (beyond / dc).clamp(-1.0, 1.0) } else { 0.0 };
                let w = if dc > 0.0 { (r / dc).min(1.0) } else { 1.0 };
                (1.0 - w) * haze_core::phase::hg(cos, g) + w / (4.0 * PI)
            }
        };
        let power = node.power * self.sigma_s;
        (power[0] + power[1] + power[2]) * geometry * (-tau).exp() * phase
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::build::build_median_split;
    use crate::tree::lights::LightSummary;
    use crate::tree::stochastic::SampleTree;
    use crate::tree::Aabb;
    use glam::Vec3;

    fn node(lo: Vec3, hi: Vec3, power: f32) -> SampleNode {
        let light = LightSummary {
            bounds: Aabb { lo, hi },
            intensity: power,
            flux_bound: Rgb::splat(power),
            length: 0.0,
            power: Rgb::splat(power),
        };
        *SampleTree::new(&build_median_split(&[light], 0)).node(0)
    }

    fn context(g: f32) -> ImportanceContext {
        let medium = VrlMedium {
            sigma_s: Rgb::splat(0.5),
            sigma_t: Rgb::splat(1.0),
            phase: if g == 0.0 { Phase::Isotropic } else { Phase::HenyeyGreenstein { g } },
        };
        ImportanceContext::new(Segment::new(Vec3::ZERO, Vec3::X, 4.0), &medium)
    }

    /// For a point far from the segment the importance is close to the exact
    /// `Theta / h` times transmittance (within the far-field error of `s / d^2`).
    #[test]
    fn far_point_matches_exact_geometry() {
        let ctx = context(0.0);
        let p = Vec3::new(2.0, 30.0, 0.0);
        let i = ctx.importance(&node(p, p, 1.0));
        let theta = {
            let (a, b) = (Vec3::ZERO - p, Vec3::new(4.0, 0.0, 0.0) - p);
            a.cross(b).length().atan2(a.dot(b))
        };
        let exact = 3.0 * 0.5 * (theta / 30.0) * (-(1.0 * 2.0 + 1.0 * 30.0f32)).exp() / (4.0 * PI);
        assert!((i / exact - 1.0).abs() < 0.02, "{i} vs {exact}");
    }

    /// Finite and positive for a point on the segment and a box around it.
    #[test]
    fn finite_on_the_camera_line() {
        let ctx = context(0.7);
        for n in [
            node(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), 1.0),
            node(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0),
            node(Vec3::new(6.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0), 1.0),
        ] {
            let i = ctx.importance(&n);
            assert!(i.is_finite() && i > 0.0, "{i}");
        }
    }

    /// Importance falls with distance and with the camera-side transmittance.
    #[test]
    fn monotone_in_distance() {
        let ctx = context(0.0);
        let at = |y: f32, x: f32| {
            let p = Vec3::new(x, y, 0.0);
            ctx.importance(&node(p, p, 1.0))
        };
        assert!(at(0.5, 2.0) > at(1.0, 2.0) && at(1.0, 2.0) > at(4.0, 2.0));
        assert!(at(1.0, 0.5) > at(1.0, 3.5));
    }

    /// With forward scattering (g > 0) light arriving from beyond the segment's end (travelling
    /// back towards the camera) matters more than light from behind the camera.
    #[test]
    fn camera_phase_prefers_forward_scattering() {
        let ctx = context(0.8);
        let ahead = Vec3::new(8.0, 0.5, 0.0);
        let behind = Vec3::new(-4.0, 0.5, 0.0);
        let plain = context(0.0);
        let ratio = |c: &ImportanceContext, p: Vec3| c.importance(&node(p, p, 1.0));
        assert!(
            ratio(&ctx, ahead) / ratio(&plain, ahead) > 10.0 * ratio(&ctx, behind) / ratio(&plain, behind)
        );
    }
}
