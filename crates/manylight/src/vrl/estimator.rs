//! One VRL's medium-to-medium contribution to one camera segment (Novak et al. 2012; notes §2),
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
    /// `Phi(v) = flux T_l(v)`: the integral of notes §2 as written.
    pub ratio: Rgb,
    /// Index of the medium the segment lies in (the caller's scene index).
    pub medium: u32,
}

impl Vrl {
    /// A VRL whose flux at the start is attenuated by `T_l(v)` (`ratio = 0`).
    pub const fn attenuated(seg: Segment, flux: Rgb, medium: u32) -> Self {
        Vrl { seg, flux, ratio: Rgb::ZERO, medium }
    }

    /// `Phi(v)`, the light arriving at distance `v` (type docs), in the VRL medium of
    /// extinction `sigma_t`. Zero if every `ratio T_l(v)` underflows.
    #[inline]
    pub fn flux_at(&self, sigma_t: Rgb, v: f32) -> Rgb {
        let t = sigma_t.exp_neg(v);
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
    if cam.len.is_nan() || cam.len <= 0.0 || (vrl.flux * vrl_medium.sigma_s * cam_medium.sigma_s).is_black() {
        return Rgb::ZERO;
    }
    let Some(on_vrl) = VrlPointSampler::new(cam.o, cam.d, &vrl.seg) else {
        return Rgb::ZERO;
    };
    let (v, p_v) = on_vrl.sample_f64(u.x as f64);
    let Some(on_cam) = Equiangular::new(on_vrl.foot(v), on_vrl.h(v), 0.0, cam.len as f64) else {
        return Rgb::ZERO;
    };
    let t_cam = on_cam.sample(u.y as f64);
    // 1 / (w^2 p(u|v) p(v)) = Theta / (h p(v)); `on_cam.h` is `h(v)`, floored like the pdf's.
    let inv_w2_pdf = (on_cam.span / (on_cam.h * p_v)) as f32;
    let (uc, vl) = ((t_cam as f32).min(cam.len), (v as f32).min(vrl.seg.len));
    let (x, y) = (cam.at(uc), vrl.seg.at(vl));
    terms_without_inverse_square(cam, cam_medium, vrl, vrl_medium, uc, vl, x, y, connect) * inv_w2_pdf
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
    let w2 = (x.as_dvec3() - y.as_dvec3()).length_squared();
    terms_without_inverse_square(cam, cam_medium, vrl, vrl_medium, u, v, x, y, connect) / w2 as f32
}

/// `Phi(v) sigma_s_l f_l Tr_conn f_c sigma_s_c T_c(u)`: the integrand times `w^2`.
#[allow(clippy::too_many_arguments)]
fn terms_without_inverse_square(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vrl: &Vrl,
    vrl_medium: &VrlMedium,
    u: f32,
    v: f32,
    x: Vec3,
    y: Vec3,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let n = connection_direction(x - y, cam.d, vrl.seg.d);
    let phases = vrl_medium.phase.eval(vrl.seg.d, n) * cam_medium.phase.eval(n, -cam.d);
    vrl.flux_at(vrl_medium.sigma_t, v)
        * vrl_medium.sigma_s
        * connect(y, x)
        * cam_medium.sigma_s
        * cam_medium.sigma_t.exp_neg(u)
        * phases
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
