//! One VRL's medium-to-medium contribution to one camera segment (Novak et al. 2012; `docs/theory.md` §3-4),
//! estimated with joint importance sampling: `v` on the VRL `∝ 1/h(v)`, then `u` on the camera
//! segment equiangularly from `y_v`.
//!
//! The contribution of VRL `(y, w_l, t)` to camera segment `(x, w_c, s)` is
//!
//! ```text
//! L = Int_0^s Int_0^t  Phi(v) sigma_s_l f_l(w_l -> n) Tr_conn(y_v, x_u) / w^2
//!                      f_c(n -> -w_c) sigma_s_c T_c(u)  dv du
//! ```
//!
//! with `x_u = x + u w_c`, `y_v = y + v w_l`, `w = |x_u - y_v|`, `n = (x_u - y_v) / w`,
//! `T_c(u) = exp(-sigma_t_c u)`, phase functions of propagation directions
//! (`Phase::eval(d_in, d_out)`), `Tr_conn` (transmittance times visibility between the two
//! points) from the caller, and `Phi(v)` the light at `y_v` ([`Vrl::flux_at`]): `Phi T_l(v)`
//! with `T_l(v) = exp(-sigma_t_l v)` for a VRL of flux `Phi` at its start, or its
//! spectral-MIS form for a light-path segment whose end was sampled.

use super::sampling::{Equiangular, VrlPointSampler};
use super::Segment;
use haze_core::{Phase, Rgb, Vec2, Vec3};

/// The homogeneous medium along a segment, as the estimators see it. Used for both the camera
/// segment and the VRL (and the camera segment of a VPL).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VrlMedium {
    pub sigma_s: Rgb,
    pub sigma_t: Rgb,
    pub phase: Phase,
}

/// A virtual ray light: one medium segment of a light path.
///
/// The light arriving at distance `v` along it is ([`Vrl::flux_at`])
///
/// ```text
/// Phi(v) = flux T_l(v) / mean(ratio T_l(v))      (ratio != 0: a sampled, "short" segment)
/// Phi(v) = flux T_l(v)                            (ratio == 0: flux given at the start)
/// ```
///
/// with `T_l(v) = exp(-sigma_t_l v)` per channel. It excludes `sigma_s` at `y_v`, which the
/// estimator multiplies in (`sigma_s_l` of the integral).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vrl {
    pub seg: Segment,
    /// The light path's throughput times the emitted power, divided by the number of light
    /// paths, *leaving the segment's start* `seg.o` along `seg.d`: everything up to and
    /// including the event at the start (emission, or the previous scattering's `sigma_s` and
    /// phase over their sampling pdfs). With spectral MIS it is divided by the hero channel's
    /// pdfs only (`beta` of `lighttrace`).
    pub flux: Rgb,
    /// Spectral-MIS pdf ratios `p_c / p_hero` of the light path up to `seg.o`, for a segment
    /// whose end was sampled by hero-channel free flight, so that its point at `v` exists with
    /// probability `T_hero(v)` (`haze_core::transmittance`): the one-sample MIS weight of that
    /// point is `T_l(v) / mean(ratio T_l(v))`. `Rgb::ZERO` (never a real ratio: the hero's own
    /// is 1) means the segment's length was not sampled and `flux` is simply attenuated,
    /// `Phi(v) = flux T_l(v)`: (T2) of `docs/theory.md` as written.
    pub ratio: Rgb,
    /// Index of the medium the segment lies in (the caller's scene index).
    pub medium: u32,
    /// Scattering events of the light path before this segment (the path-length rule,
    /// `crate::depth`).
    pub events: u32,
}

impl Vrl {
    /// A VRL whose flux at the start is attenuated by `T_l(v)` (`ratio = 0`).
    pub const fn attenuated(seg: Segment, flux: Rgb, medium: u32) -> Self {
        Vrl { seg, flux, ratio: Rgb::ZERO, medium, events: 0 }
    }

    /// `Phi(v)`, the light arriving at distance `v` (type docs), in the VRL medium of
    /// extinction `sigma_t`. Zero if every `ratio T_l(v)` underflows.
    #[inline]
    pub fn flux_at(&self, sigma_t: Rgb, v: f32) -> Rgb {
        let t = exp_neg(sigma_t, v);
        if self.ratio.is_black() {
            return self.flux * t;
        }
        let m = (self.ratio * t).mean();
        if m > 0.0 {
            self.flux * t / m
        } else {
            Rgb::ZERO
        }
    }
}

/// One sample of the contribution of `vrl` to the camera segment `cam` (module docs), an
/// unbiased estimate `f(u, v) / p(u, v)` of `L`.
///
/// `u.x` picks `v` on the VRL with the `1/h` density ([`VrlPointSampler`]), `u.y` picks the
/// camera distance equiangularly from `y_v` (`h = h(v)`, the distance to the camera line).
/// Since `w^2 p(u | v) = h / Theta` (`Theta` the angle the camera segment subtends from `y_v`),
/// the estimate is computed as `f~ Theta / (h p(v))` with `f~` the integrand without its
/// `1/w^2`: no division by a small `w`, and `Theta / (h p(v)) <= pi * 1e6` however close or
/// parallel the lines are.
///
/// `connect(y_v, x_u)` returns the transmittance times visibility between the VRL point and
/// the camera point. Where the floors of [`super::sampling`] act (lines closer than `1e-6`
/// times the VRL's length, or a VRL point within `1e-6 s` of the camera line), the `1/w^2` is
/// in effect evaluated with the floored distance: a regularisation of a divergent integral,
/// negligible elsewhere. Returns zero for zero-length segments.
pub fn sample_vrl_contribution(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vrl: &Vrl,
    vrl_medium: &VrlMedium,
    u: Vec2,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if !contributes(cam, cam_medium, vrl, vrl_medium) {
        return Rgb::ZERO;
    }
    match sample_point_pair(cam, &vrl.seg, u) {
        Some(pair) => point_pair_estimate(cam, cam_medium, vrl, vrl_medium, &pair, connect),
        None => Rgb::ZERO,
    }
}

/// False when the pair cannot contribute: an empty or invalid camera segment, or no light or no
/// scattering in some channel of every product (then [`sample_vrl_contribution`] is zero).
#[inline]
pub(crate) fn contributes(cam: &Segment, cam_medium: &VrlMedium, vrl: &Vrl, vrl_medium: &VrlMedium) -> bool {
    !(cam.len.is_nan() || cam.len <= 0.0 || (vrl.flux * vrl_medium.sigma_s * cam_medium.sigma_s).is_black())
}

/// The two points of one sample of [`sample_vrl_contribution`] (its first stage, which depends
/// only on the two segments and the uniform numbers): camera distance `u` and point `x`, VRL
/// distance `v` and point `y`, and `1 / (w^2 p(u, v))`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointPair {
    pub u: f32,
    pub v: f32,
    pub x: Vec3,
    pub y: Vec3,
    pub inv_w2_pdf: f32,
}

/// First stage of [`sample_vrl_contribution`]: `v` from the `1/h` density, then `u`
/// equiangularly from `y_v`. `None` for a zero-length VRL (the estimate is zero). Split from the
/// second stage so that the brute-force loop can run the sampling of several VRLs back to back
/// (their long, independent chains of divisions, roots and transcendentals overlap), with the
/// same arithmetic, hence the same result, as the one-VRL estimator.
#[inline(always)]
pub(crate) fn sample_point_pair(cam: &Segment, vrl: &Segment, u: Vec2) -> Option<PointPair> {
    let on_vrl = VrlPointSampler::new(cam.o, cam.d, vrl)?;
    let (v, h, inv_hp) = on_vrl.sample_for_estimator(u.x as f64);
    let on_cam = Equiangular::new(on_vrl.foot(v), h, 0.0, cam.len as f64)?;
    let t_cam = on_cam.sample(u.y as f64);
    // 1 / (w^2 p(u|v) p(v)) = Theta / (h_eq p(v)) = Theta (1 / (h p(v))) (h / h_eq), with
    // `h_eq = on_cam.h` the equiangular distance, `h(v)` floored at `1e-6` of the camera segment.
    let floored = if on_cam.h > h { h / on_cam.h } else { 1.0 };
    let inv_w2_pdf = (on_cam.span * inv_hp * floored) as f32;
    let (uc, vl) = ((t_cam as f32).min(cam.len), (v as f32).min(vrl.len));
    Some(PointPair { u: uc, v: vl, x: cam.at(uc), y: vrl.at(vl), inv_w2_pdf })
}

/// Second stage of [`sample_vrl_contribution`]: the estimate `f(u, v) / p(u, v)` at a sampled
/// [`PointPair`], with the connection's transmittance and visibility from `connect(y, x)`:
/// `Phi(v) sigma_s_l f_l Tr_conn f_c sigma_s_c T_c(u)` (the integrand times `w^2`) times the
/// pair's `1 / (w^2 p(u, v))`.
#[inline]
pub(crate) fn point_pair_estimate(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vrl: &Vrl,
    vrl_medium: &VrlMedium,
    pair: &PointPair,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let PointPair { u, v, x, y, inv_w2_pdf } = *pair;
    let n = connection_direction(x - y, cam.d, vrl.seg.d);
    let phases = vrl_medium.phase.eval(vrl.seg.d, n) * cam_medium.phase.eval(n, -cam.d);
    vrl.flux_at(vrl_medium.sigma_t, v)
        * vrl_medium.sigma_s
        * connect(y, x)
        * cam_medium.sigma_s
        * exp_neg(cam_medium.sigma_t, u)
        * phases
        * inv_w2_pdf
}

/// The integrand `f(u, v)` of the contribution (module docs) at camera distance `u` and VRL
/// distance `v`, same conventions as [`sample_vrl_contribution`]; zero outside the segments.
/// Singular (not finite) where `x_u = y_v`. For tests and reference integrators.
pub fn vrl_integrand(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vrl: &Vrl,
    vrl_medium: &VrlMedium,
    u: f32,
    v: f32,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if !((0.0..=cam.len).contains(&u) && (0.0..=vrl.seg.len).contains(&v)) {
        return Rgb::ZERO;
    }
    let (x, y) = (cam.at(u), vrl.seg.at(v));
    let inv_w2_pdf = (1.0 / (x.as_dvec3() - y.as_dvec3()).length_squared()) as f32;
    point_pair_estimate(cam, cam_medium, vrl, vrl_medium, &PointPair { u, v, x, y, inv_w2_pdf }, connect)
}

/// `sigma.exp_neg(d)` (`exp(-sigma d)` per channel) with a single `exp` when the channels are
/// equal, as they are for grey extinction: the same values for a third of the work.
#[inline]
pub(crate) fn exp_neg(sigma: Rgb, d: f32) -> Rgb {
    let [r, g, b] = sigma.0;
    if r == g && g == b {
        Rgb::splat((-r * d).exp())
    } else {
        sigma.exp_neg(d)
    }
}

/// Unit direction of `r`, the light's propagation from the light point to the camera point.
/// When the two points coincide (degenerate input) any direction is as good as another: use the
/// common perpendicular of the two lines, or any perpendicular to the camera line.
pub(crate) fn connection_direction(r: Vec3, cam_d: Vec3, light_d: Vec3) -> Vec3 {
    r.try_normalize().unwrap_or_else(|| {
        cam_d.cross(light_d).try_normalize().unwrap_or_else(|| cam_d.any_orthonormal_vector())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flux_at_follows_both_conventions() {
        let seg = Segment::new(Vec3::ZERO, Vec3::X, 2.0);
        let flux = Rgb::new(1.0, 2.0, 3.0);
        // Attenuated: flux T(v).
        let a = Vrl::attenuated(seg, flux, 0);
        let sigma_t = Rgb::new(0.5, 1.0, 2.0);
        let exp = flux * sigma_t.exp_neg(0.7);
        assert!((0..3).all(|c| (a.flux_at(sigma_t, 0.7)[c] - exp[c]).abs() < 1e-6));
        // Short with spectral MIS: grey extinction cancels, leaving flux / mean(ratio).
        let s = Vrl { ratio: Rgb::new(1.0, 0.5, 1.5), ..a };
        for v in [0.0, 0.7, 2.0] {
            let f = s.flux_at(Rgb::splat(1.3), v);
            assert!((0..3).all(|c| (f[c] - flux[c]).abs() < 1e-5), "{f}");
        }
        // Chromatic: flux T / mean(ratio T), and zero once every channel underflows.
        let f = s.flux_at(sigma_t, 0.7);
        let t = sigma_t.exp_neg(0.7);
        let exp = flux * t / (s.ratio * t).mean();
        assert!((0..3).all(|c| (f[c] - exp[c]).abs() < 1e-5));
        assert_eq!(s.flux_at(Rgb::splat(1e3), 1e3), Rgb::ZERO);
    }
}
