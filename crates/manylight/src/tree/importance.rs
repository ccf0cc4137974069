//! The stochastic cut's importance of a light cluster for one camera segment: a cheap,
//! always finite *estimate* of the cluster's contribution (not a bound; `docs/theory.md` §11,
//! (T24); docs/lightcuts.md, "Stochastic cut"). It only steers probabilities, so any error in
//! it costs variance, never bias, as long as it is positive wherever a light can contribute.
//!
//! For a light point `y` at distance `h` from the camera's line, the camera-side integral of
//! the estimators is exactly `Int_0^s du / w(u)^2 = Theta(y) / h` (`Theta` the angle the
//! camera segment subtends from `y`; `docs/theory.md` (T9), (T13)). For a cluster with power
//! centroid `c` and equivalent radius `r` (`sqrt(3)` times the power-weighted RMS distance of
//! its lights from `c`: the half-diagonal for one VRL; `stochastic::power_moments`) we take two cheap upper bounds of that integral (`Theta <=
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
use glam::Vec3;
use haze_core::{Phase, Rgb};
use std::f32::consts::PI;

/// Share of the squared equivalent radius `r^2` added to a cluster's squared distances (module
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

    /// The importance of one VRL `[o, o + len d]` (unit `d`) with summed power `power`: the
    /// node formula's terms, but with the VRL's own geometry instead of a cluster's,
    ///
    /// ```text
    /// G = min(Int_0^len pi / h(v) dv,  len s / d_min^2) / len
    /// Int pi / h(v) dv = (pi / sin) [asinh(sin (len - v0) / h0) - asinh(-sin v0 / h0)]
    /// ```
    ///
    /// with `h(v) = sqrt(h0^2 + sin^2 (v - v0)^2)` the distance from the VRL's point `v` to the
    /// camera *line* (`h0` the lines' distance, `v0` the VRL's parameter nearest that line,
    /// `sin` of the angle between the lines; `pi len / h0` for parallel lines), and `d_min`
    /// the distance between the two segments (the far-field bound `Int Int 1/d^2 <= len s /
    /// d_min^2`). A VRL that passes close to the camera segment, above all one nearly parallel
    /// to it, gets the `ln(1/h0) / sin` its true contribution has, where a point at its
    /// midpoint saw neither (measured: docs/lightcuts.md, "Choosing the importance").
    /// Transmittance and camera phase are taken at the segments' closest points.
    pub fn vrl_importance(&self, o: Vec3, d: Vec3, len: f32, power: Rgb) -> f32 {
        let seg = &self.seg;
        let floor = self.floor2.sqrt();
        if len <= floor {
            let p = o + d * (0.5 * len);
            let node = SampleNode::point(p, power);
            return self.importance(&node);
        }
        let (v, u) = closest_parameters(o, d, len, seg.o, seg.d, seg.len);
        let (y, x) = (o + d * v, seg.o + seg.d * u);
        let d_min2 = (x - y).length_squared().max(self.floor2);
        let n = d.cross(seg.d);
        let sin = n.length();
        let w0 = o - seg.o;
        let line = if sin > 1e-3 {
            let h0 = (w0.dot(n) / sin).abs().max(floor);
            let b = d.dot(seg.d);
            let v0 = (b * seg.d.dot(w0) - d.dot(w0)) / (sin * sin);
            let a = sin / h0;
            PI / sin * (asinh(a * (len - v0)) - asinh(a * -v0))
        } else {
            let h = (w0 - seg.d * w0.dot(seg.d)).length().max(floor);
            PI * len / h
        };
        let geometry = line.min(len * seg.len / d_min2) / len;
        let d_min = d_min2.sqrt();
        let tau = self.sigma_cam * u + self.sigma_conn * d_min;
        let phase = match self.g {
            None => 1.0 / (4.0 * PI),
            Some(g) => {
                let cos = ((x - y) / d_min).dot(-seg.d).clamp(-1.0, 1.0);
                let w = (0.5 * len / d_min).min(1.0);
                (1.0 - w) * haze_core::phase::hg(cos, g) + w / (4.0 * PI)
            }
        };
        let power = power * self.sigma_s;
        (power[0] + power[1] + power[2]) * geometry * (-tau).exp() * phase
    }
}

/// The stochastic cut's importance of a light cluster for a gathering surface point `x` with
/// normal `n` (`docs/theory.md` §11): the point-receiver analogue of [`ImportanceContext`],
///
/// ```text
/// I = power G exp(-sigma max(d_c - REACH r, 0)) C,    G = 1 / (d_c^2 + SPREAD r^2)
/// C = (1 - w) |cos| + w,   cos = n . (c - x) / d_c,   w = min(r / d_c, 1)
/// ```
///
/// with `d_c` the distance from `x` to the cluster's power centroid `c` (equivalent radius `r`,
/// softened as for camera segments), `sigma` the scene's mean extinction (the receiver's medium
/// is not known here; an estimate), and the receiver's cosine blended towards 1 as the cluster
/// surrounds the point. `|cos|`, not `max(cos, 0)`: a rough dielectric receives from both
/// sides, and an importance must stay positive wherever a light can contribute.
#[derive(Clone, Copy, Debug)]
pub struct PointImportance {
    x: Vec3,
    n: Vec3,
    sigma: f32,
}

/// Squared-distance floor of [`PointImportance`] (keeps coincident points finite).
const POINT_FLOOR2: f32 = 1e-12;

impl PointImportance {
    pub fn new(x: Vec3, n: Vec3, sigma: f32) -> Self {
        PointImportance { x, n, sigma }
    }

    #[inline]
    fn cosine(&self, rel: Vec3, dist: f32, r: f32) -> f32 {
        if dist <= 0.0 {
            return 1.0;
        }
        let w = (r / dist).min(1.0);
        (1.0 - w) * (self.n.dot(rel) / dist).abs() + w
    }

    /// The importance of `node` (type docs).
    #[inline]
    pub fn importance(&self, node: &SampleNode) -> f32 {
        let (c, r) = (node.center, node.radius);
        let rel = c - self.x;
        let d2 = rel.length_squared();
        let g = 1.0 / (d2 + SPREAD * r * r).max(POINT_FLOOR2);
        let d = d2.sqrt();
        let tau = self.sigma * (d - REACH * r).max(0.0);
        (node.power[0] + node.power[1] + node.power[2]) * g * (-tau).exp() * self.cosine(rel, d, r)
    }

    /// The importance of one VRL `[o, o + len d]` with summed power `power`: the exact
    /// `Int_0^len dv / |x - y(v)|^2 = (atan((len - v0) / h) - atan(-v0 / h)) / h` (`h` the
    /// distance from `x` to the VRL's line, `v0` the foot of the perpendicular), divided by
    /// `len`; transmittance and cosine at the VRL's point nearest `x`.
    pub fn vrl_importance(&self, o: Vec3, d: Vec3, len: f32, power: Rgb) -> f32 {
        if len <= 1e-6 {
            return self.importance(&SampleNode::point(o + d * (0.5 * len), power));
        }
        let w0 = self.x - o;
        let v0 = w0.dot(d);
        let h = (w0.length_squared() - v0 * v0).max(POINT_FLOOR2).sqrt();
        let line = (((len - v0) / h).atan() - (-v0 / h).atan()) / h;
        let y = o + d * v0.clamp(0.0, len);
        let rel = y - self.x;
        let dist = rel.length();
        let cosine = self.cosine(rel, dist, 0.5 * len);
        (power[0] + power[1] + power[2]) * (line / len) * (-self.sigma * dist).exp() * cosine
    }
}

/// `asinh x = sign(x) ln(|x| + sqrt(x^2 + 1))` with [`ln`]: the std version (through
/// `log1p`) was 9% of a render's time in the descents; an importance needs no more than
/// about 1e-5 relative accuracy.
#[inline]
fn asinh(x: f32) -> f32 {
    let a = x.abs();
    ln(a + (a * a + 1.0).sqrt()).copysign(x)
}

/// `ln x` for positive normal `x` to about 1e-5 relative: `x = m 2^e` with `m` in `[1, 2)`,
/// `ln m = 2 atanh(z) = 2 (z + z^3/3 + z^5/5 + z^7/7 + ...)`, `z = (m - 1)/(m + 1)` in
/// `[0, 1/3)` (truncation error below `2 z^9 / 9 < 1.2e-5`, and relative to `ln m`, which is
/// about `2 z`, below 1e-4 at the worst end; near `m = 1` the series is exact to rounding).
#[inline]
fn ln(x: f32) -> f32 {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let z = (m - 1.0) / (m + 1.0);
    let z2 = z * z;
    let ln_m = 2.0 * z * (1.0 + z2 * (1.0 / 3.0 + z2 * (1.0 / 5.0 + z2 * (1.0 / 7.0 + z2 * (1.0 / 9.0)))));
    e as f32 * std::f32::consts::LN_2 + ln_m
}

/// Parameters `(v, u)` of the closest points of the segments `[a, a + la da]` and
/// `[b, b + lb db]` (unit directions; the usual clamped solution, e.g. Ericson, "Real-Time
/// Collision Detection", 5.1.9).
fn closest_parameters(a: Vec3, da: Vec3, la: f32, b: Vec3, db: Vec3, lb: f32) -> (f32, f32) {
    let r = a - b;
    let (bb, c, f) = (da.dot(db), da.dot(r), db.dot(r));
    let denom = 1.0 - bb * bb;
    let mut v = if denom > 1e-7 { ((bb * f - c) / denom).clamp(0.0, la) } else { 0.0 };
    let mut u = bb * v + f;
    if u < 0.0 {
        u = 0.0;
        v = (-c).clamp(0.0, la);
    } else if u > lb {
        u = lb;
        v = (bb * lb - c).clamp(0.0, la);
    }
    (v, u)
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

    #[test]
    fn fast_ln_and_asinh() {
        for i in 0..2000 {
            let x = 1e-6f32 * 1.02f32.powi(i);
            let (a, b) = (ln(x), x.ln());
            assert!((a - b).abs() <= 2e-5 * b.abs().max(1.0), "ln {x}: {a} vs {b}");
            for y in [x, -x] {
                let (a, b) = (asinh(y), y.asinh());
                assert!((a - b).abs() <= 1e-4 * b.abs() + 1e-7, "asinh {y}: {a} vs {b}");
            }
        }
    }

    /// The VRL importance's geometry `Int pi / h(v) dv` is exact for skew lines: compared with a
    /// fine midpoint rule, in a clear medium (no transmittance), isotropic, with a camera
    /// segment long enough that the far-field bound never applies.
    #[test]
    fn vrl_importance_line_integral_matches_quadrature() {
        let medium =
            VrlMedium { sigma_s: Rgb::splat(1.0), sigma_t: Rgb::splat(0.0), phase: Phase::Isotropic };
        // A long camera segment, so `len s / d_min^2` is far above the line integral.
        let ctx = ImportanceContext::new(Segment::new(Vec3::new(-50.0, 0.0, 0.0), Vec3::X, 100.0), &medium);
        for (o, d, len) in [
            (Vec3::new(-1.0, 0.3, -0.5), Vec3::new(0.6, 0.0, 0.8), 2.0),
            (Vec3::new(0.0, 0.01, -1.0), Vec3::new(0.995, 0.0, 0.0998).normalize(), 3.0),
            (Vec3::new(2.0, -0.2, 0.05), Vec3::new(0.0, 1.0, 0.0), 0.4),
        ] {
            let n = 200_000;
            let quad: f64 = (0..n)
                .map(|i| {
                    let p = o + d * ((i as f32 + 0.5) / n as f32 * len);
                    PI as f64 / (p.y as f64).hypot(p.z as f64)
                })
                .sum::<f64>()
                * (len as f64 / n as f64);
            let i = ctx.vrl_importance(o, d, len, Rgb::splat(len / 3.0)) as f64;
            // power . sigma_s = len, phase 1/4pi: I = len * (line / len) / 4pi.
            let line = i * 4.0 * PI as f64;
            assert!((line / quad - 1.0).abs() < 2e-3, "{line} vs {quad}");
        }
    }

    /// A VRL crossing the camera segment nearly parallel to it is far more important than the
    /// same VRL moved away, and stays finite; a far VRL matches the point formula at its
    /// midpoint within the far-field error.
    #[test]
    fn vrl_importance_near_and_far() {
        let ctx = context(0.0);
        let d = Vec3::new(0.99, 0.141, 0.0).normalize();
        let near = ctx.vrl_importance(Vec3::new(1.0, -0.05, 0.0), d, 1.0, Rgb::splat(1.0));
        let moved = ctx.vrl_importance(Vec3::new(1.0, 1.0, 0.0), d, 1.0, Rgb::splat(1.0));
        assert!(near.is_finite() && near > 5.0 * moved, "{near} vs {moved}");
        let o = Vec3::new(1.5, 30.0, 0.0);
        let far = ctx.vrl_importance(o, Vec3::Z, 0.2, Rgb::splat(1.0));
        let mid = o + Vec3::Z * 0.1;
        let point = ctx.importance(&node(mid, mid, 1.0));
        assert!((far / point - 1.0).abs() < 0.05, "{far} vs {point}");
    }

    /// The point receiver's VRL importance integrates `1/d^2` along the VRL exactly (clear
    /// medium; its cosine factor divided out).
    #[test]
    fn point_vrl_importance_matches_quadrature() {
        let pi = PointImportance::new(Vec3::ZERO, Vec3::Y, 0.0);
        for (o, d, len) in [
            (Vec3::new(-1.0, 0.3, -0.5), Vec3::new(0.6, 0.0, 0.8), 2.0),
            (Vec3::new(0.2, 0.05, -1.0), Vec3::Z, 3.0),
        ] {
            let n = 200_000;
            let quad: f64 = (0..n)
                .map(|i| 1.0 / (o + d * ((i as f32 + 0.5) / n as f32 * len)).length_squared() as f64)
                .sum::<f64>()
                * (len as f64 / n as f64);
            // Undo the cosine and the division by len: power . 1 = 3 * len / 3.
            let y = o + d * (-o).dot(d).clamp(0.0, len);
            let cosine = pi.cosine(y, y.length(), 0.5 * len) as f64;
            let line = pi.vrl_importance(o, d, len, Rgb::splat(len / 3.0)) as f64 / cosine;
            assert!((line / quad - 1.0).abs() < 2e-3, "{line} vs {quad}");
        }
        // Finite and positive for a point on the VRL and for a point cluster at the receiver.
        let on = pi.vrl_importance(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 2.0, Rgb::splat(1.0));
        let at = pi.importance(&SampleNode::point(Vec3::ZERO, Rgb::splat(1.0)));
        assert!(on.is_finite() && on > 0.0 && at.is_finite() && at > 0.0, "{on} {at}");
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
