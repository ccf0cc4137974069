//! One VRL's contribution to a gathering surface point, with the VRL point sampled
//! equiangularly towards the surface point (`docs/theory.md` §5.1, (T12a), (T12b)):
//!
//! ```text
//! L = Int_0^t Phi(v) sigma_s_l f_l(w_l, n) Tr(y_v, x) R(-n) / w^2 dv
//! ```
//!
//! with `y_v = o + v w_l`, `w = |x - y_v|`, `n = (x - y_v) / w` and `R(d)` the receiver's
//! `f(wi, d) |cos d|` towards the unit direction `d` from `x` (the caller's BSDF at `x`).

use super::estimator::connection_direction;
use super::sampling::Equiangular;
use super::{Vrl, VrlMedium};
use haze_core::{Rgb, Vec3};

/// One sample of the contribution of `vrl` to the surface point `x`: `u` picks `v` on the VRL
/// equiangularly from `x`, so `1/(w^2 p(v)) = Theta / h` (T9) and the estimate is
/// `Phi(v) sigma_s_l f_l Tr R * Theta / h` (T12b), with `h` floored at `1e-6` of the VRL's
/// length as in docs/theory.md §4.1. `connect(y, x)` is the transmittance times visibility.
pub fn sample_vrl_to_point(
    x: Vec3,
    receiver: impl Fn(Vec3) -> Rgb,
    vrl: &Vrl,
    vrl_medium: &VrlMedium,
    u: f32,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let seg = &vrl.seg;
    if !(seg.len > 0.0 && seg.len.is_finite()) || (vrl.flux * vrl_medium.sigma_s).is_black() {
        return Rgb::ZERO;
    }
    let d = seg.d.as_dvec3();
    let r = (x - seg.o).as_dvec3();
    let foot = r.dot(d);
    let Some(eq) = Equiangular::new(foot, (r - foot * d).length(), 0.0, seg.len as f64) else {
        return Rgb::ZERO;
    };
    let v = (eq.sample(u as f64) as f32).min(seg.len);
    // `Phi(v) sigma_s_l f_l(w_l, n) Tr R(-n)`: the integrand without `1/w^2`.
    let y = seg.at(v);
    let n = connection_direction(x - y, seg.d, seg.d.any_orthonormal_vector());
    let f = receiver(-n);
    if f.is_black() {
        return Rgb::ZERO;
    }
    let phase = vrl_medium.phase.eval(seg.d, n);
    vrl.flux_at(vrl_medium.sigma_t, v)
        * vrl_medium.sigma_s
        * f
        * connect(y, x)
        * phase
        * (eq.span / eq.h) as f32
}
