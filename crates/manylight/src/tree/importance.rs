//! The stochastic cut's importance of a light cluster for one camera segment: a cheap,
//! always finite *estimate* of the cluster's contribution (not a bound; `docs/theory.md` §11,
//! (T24); docs/lightcuts.md, "Stochastic cut"). It only steers probabilities, so any error in
//! it costs variance, never bias, as long as it is positive wherever a light can contribute.
//!
//! For a light point `y` at distance `h` from the camera's line, the camera-side integral of
//! the estimators is exactly `Int_0^s du / w(u)^2 = Theta(y) / h` (`Theta` the angle the
//! camera segment subtends from `y`; `docs/theory.md` (T9), (T13)). We evaluate it at the
//! cluster's box centre `c` with two cheap upper bounds instead of the angle,
//!
//! ```text
//! G = min(pi / h_c, s / d_c^2)        (Theta <= pi;  w(u) >= d_c)
//! ```
//!
//! with `h_c` the distance from `c` to the camera line and `d_c` to the camera segment, both
//! clamped below at the box's half-diagonal `r` (a cluster around the camera line sees it at
//! every distance from 0 to `r`; averaging `pi / h` over a disc of radius `r` gives `2 pi / r`,
//! the same order as `pi / r`) and at a floor `1e-4 s`. This imitates the clamped
//! `1/d^2` of pbrt-v4's and Cycles' light trees; for two lines the exact double integral of
//! `1/d^2` grows only like `ln(1/h)` near the camera line, so the clamp loses little.
//!
//! ```text
//! I = (power . sigma_s_cam) G exp(-sigma_cam max(t_c - r, 0) - sigma_conn max(d_c - r, 0)) f_cam
//! ```
//!
//! `power` is the cluster's summed `Int Phi dv` per channel (flux for VPLs), `t_c` the distance
//! along the camera segment to the point nearest `c` (camera-side transmittance), the second
//! exponent the nearest possible connection through the least extinction, and `f_cam` the
//! camera medium's phase function at the centre's direction, blended towards isotropic as the
//! box grows around that point (`w = min(r / d_c, 1)` of the weight goes to `1 / 4 pi`). The
//! light-side phase is left out: within a cluster the VRL directions spread.

use super::stochastic::SampleNode;
use crate::vrl::{Segment, VrlMedium};
use haze_core::{Phase, Rgb};
use std::f32::consts::PI;

/// Everything the importance needs about one camera segment.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceContext {
    seg: Segment,
    /// `sigma_s` of the camera medium, per channel.
    sigma_s: Rgb,
    /// Mean extinction of the camera medium (camera-side transmittance).
    sigma_cam: f32,
    /// Mean of the least extinction any connection may cross (0 with vacuum in the scene).
    sigma_conn: f32,
    /// The camera medium's HG asymmetry, if its phase is HG.
    g: Option<f32>,
    /// Square of the distance floor `1e-4 s` (keeps point clusters on the line finite).
    floor2: f32,
}

impl ImportanceContext {
    /// The context of camera segment `seg` in `camera` medium, with `sigma_t_min` the least
    /// extinction along any connection (as the bounds take it).
    pub fn new(seg: Segment, camera: &VrlMedium, sigma_t_min: Rgb) -> Self {
        let g = match camera.phase {
            Phase::HenyeyGreenstein { g } if g != 0.0 => Some(g),
            _ => None,
        };
        let floor = (1e-4 * seg.len).max(1e-7);
        ImportanceContext {
            seg,
            sigma_s: camera.sigma_s,
            sigma_cam: camera.sigma_t.mean(),
            sigma_conn: sigma_t_min.mean(),
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
        let r2 = r * r;
        let h2 = perp2.max(r2).max(self.floor2);
        let d2 = dc2.max(r2).max(self.floor2);
        let geometry = (PI / h2.sqrt()).min(seg.len / d2);
        let dc = dc2.sqrt();
        let tau = self.sigma_cam * (t - r).max(0.0) + self.sigma_conn * (dc - r).max(0.0);
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
        ImportanceContext::new(Segment::new(Vec3::ZERO, Vec3::X, 4.0), &medium, Rgb::splat(0.2))
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
        let exact = 3.0 * 0.5 * (theta / 30.0) * (-(1.0 * 2.0 + 0.2 * 30.0f32)).exp() / (4.0 * PI);
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
