//! One VRL's medium-to-medium contribution to one camera segment (Novak et al. 2012; notes §2),
//! estimated with joint importance sampling: `v` on the VRL `∝ 1/h(v)`, then `u` on the camera
//! segment equiangularly from `y_v`.
//!
//! The contribution of VRL `(y, w_l, t, Phi)` to camera segment `(x, w_c, s)` is
//!
//! ```text
//! L = Int_0^s Int_0^t  Phi sigma_s_l T_l(v) f_l(w_l -> n) Tr_conn(y_v, x_u) / w^2
//!                      f_c(n -> -w_c) sigma_s_c T_c(u)  dv du
//! ```
//!
//! with `x_u = x + u w_c`, `y_v = y + v w_l`, `w = |x_u - y_v|`, `n = (x_u - y_v) / w`,
//! `T_l(v) = exp(-sigma_t_l v)`, `T_c(u) = exp(-sigma_t_c u)`, phase functions of propagation
//! directions (`Phase::eval(d_in, d_out)`) and `Tr_conn` (transmittance times visibility
//! between the two points) from the caller.

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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vrl {
    pub seg: Segment,
    /// `Phi`: the light path's throughput times the emitted power, divided by the number of
    /// light paths, *leaving the segment's start* `seg.o` along `seg.d`. It includes everything
    /// up to and including the event at the start (emission, or the previous scattering's
    /// `sigma_s` and phase over their sampling pdfs), and neither the transmittance along this
    /// segment nor `sigma_s` at the point `y_v` that the estimator picks: those are the
    /// `T_l(v)` and `sigma_s_l` of the integral. A VPL at distance `v` on this segment, reached
    /// by free-flight sampling with pdf `p(v)`, has flux `Phi T_l(v) sigma_s_l / p(v)`.
    pub flux: Rgb,
    /// Index of the medium the segment lies in (the caller's scene index).
    pub medium: u32,
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
    if !(cam.len > 0.0) || (vrl.flux * vrl_medium.sigma_s * cam_medium.sigma_s).is_black() {
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

/// `Phi sigma_s_l T_l(v) f_l Tr_conn f_c sigma_s_c T_c(u)`: the integrand times `w^2`.
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
    vrl.flux
        * vrl_medium.sigma_s
        * vrl_medium.sigma_t.exp_neg(v)
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
