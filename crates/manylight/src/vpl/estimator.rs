//! One VPL's contribution to one camera segment, with the camera distance sampled
//! equiangularly towards the VPL (Kulla & Fajardo 2012; `docs/theory.md` §5).
//!
//! The contribution of VPL `(p, d_in, Phi)` to camera segment `(x, w_c, s)` is
//!
//! ```text
//! L = Int_0^s  Phi f_l(d_in -> n) Tr_conn(p, x_u) G(w) f_c(n -> -w_c) sigma_s_c T_c(u)  du
//! ```
//!
//! with `x_u = x + u w_c`, `w = |x_u - p|`, `n = (x_u - p) / w`, `T_c(u) = exp(-sigma_t_c u)`,
//! phase functions of propagation directions, `Tr_conn` (transmittance times visibility) from
//! the caller, and `G(w) = 1/w^2`, or `min(1/w^2, clamp)` when clamped.

use crate::vrl::estimator::connection_direction;
use crate::vrl::sampling::Equiangular;
use crate::vrl::{Segment, VrlMedium};
use haze_core::{Phase, Rgb, Vec3};

/// A virtual point light: one scattering vertex of a light path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    pub p: Vec3,
    /// Unit propagation direction of the light arriving at `p` (the phase function at `p` turns
    /// it towards the camera point).
    pub d_in: Vec3,
    /// `Phi`: the light path's throughput at the vertex times the emitted power, divided by the
    /// number of light paths, *including* the transmittance up to `p` and `sigma_s` at `p` over
    /// the free-flight pdf, but not the phase function at `p` (the estimator evaluates it
    /// towards the camera point). For a vertex at distance `v` on an attenuated VRL
    /// (`ratio = 0`) of flux `Phi_vrl`, reached with free-flight pdf `p(v)`:
    /// `Phi_vrl T_l(v) sigma_s / p(v)`; with spectral MIS, `lighttrace`'s `beta sigma_s / mean(r)`.
    pub flux: Rgb,
    /// Index of the medium the vertex lies in (the caller's scene index).
    pub medium: u32,
    /// Scattering events of the light path before this vertex (the path-length rule,
    /// `crate::depth`).
    pub events: u32,
}

/// One sample of the contribution of `vpl` to the camera segment `cam` (module docs): `u` picks
/// the camera distance equiangularly from `p` (`p(u) = h / (Theta w^2)`), and the estimate is
/// computed as `f~ Theta / h` with `f~` the integrand without `G`, so nothing divides by a
/// small `w`. `vpl_phase` is the phase function of the medium at `p`.
///
/// `geometry_clamp`: `Some(c)` replaces `1/w^2` by `min(1/w^2, c)` (units 1/length^2), the
/// classic VPL clamping (Keller 1997; Hasan et al. 2009): it removes the fireflies of VPLs
/// close to the camera ray at the price of a bias (energy lost near the VPL) that does not
/// vanish with more samples. `None` is unbiased.
///
/// `connect(p, x_u)` returns the transmittance times visibility between the two points. A VPL
/// within `1e-6 s` of the camera line is treated as if at that distance (the integral of
/// `1/w^2` through the point diverges). Returns zero for a zero-length camera segment.
pub fn sample_vpl_contribution(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vpl: &Vpl,
    vpl_phase: &Phase,
    u: f32,
    geometry_clamp: Option<f32>,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if cam.len.is_nan() || cam.len <= 0.0 || (vpl.flux * cam_medium.sigma_s).is_black() {
        return Rgb::ZERO;
    }
    let Some((uc, g_over_pdf)) = sample_distance_towards(cam, vpl.p, u, geometry_clamp) else {
        return Rgb::ZERO;
    };
    terms_without_geometry(cam, cam_medium, vpl, vpl_phase, uc, cam.at(uc), connect) * g_over_pdf
}

/// Samples the camera distance `u` towards the point `p` equiangularly (Kulla & Fajardo 2012)
/// and returns it with the geometry term over its pdf, `G(w) / p(u) = Theta / h * min(1, c w^2)`
/// (`w^2 = h^2 + (u - foot)^2`, `c` the optional clamp). `None` where the equiangular
/// distribution does not exist (a degenerate segment). Shared by every point-light-to-segment
/// estimator.
pub(crate) fn sample_distance_towards(
    cam: &Segment,
    p: Vec3,
    u: f32,
    geometry_clamp: Option<f32>,
) -> Option<(f32, f32)> {
    let c = cam.d.as_dvec3();
    let r = (p - cam.o).as_dvec3();
    let foot = r.dot(c);
    let eq = Equiangular::new(foot, (r - foot * c).length(), 0.0, cam.len as f64)?;
    let t = eq.sample(u as f64);
    let mut g_over_pdf = eq.span / eq.h;
    if let Some(clamp) = geometry_clamp {
        let w2 = eq.h * eq.h + (t - foot) * (t - foot);
        g_over_pdf *= (clamp as f64 * w2).min(1.0);
    }
    Some(((t as f32).min(cam.len), g_over_pdf as f32))
}

/// The integrand of the contribution (module docs) at camera distance `u`, same conventions as
/// [`sample_vpl_contribution`] (including the optional clamp); zero outside the segment and
/// singular (not finite) where `x_u = p` without clamping. For tests and reference integrators.
pub fn vpl_integrand(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vpl: &Vpl,
    vpl_phase: &Phase,
    u: f32,
    geometry_clamp: Option<f32>,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if !(0.0..=cam.len).contains(&u) {
        return Rgb::ZERO;
    }
    let x = cam.at(u);
    let w2 = (x.as_dvec3() - vpl.p.as_dvec3()).length_squared();
    let g = geometry_clamp.map_or(1.0 / w2, |c| (1.0 / w2).min(c as f64));
    terms_without_geometry(cam, cam_medium, vpl, vpl_phase, u, x, connect) * g as f32
}

/// `Phi f_l Tr_conn f_c sigma_s_c T_c(u)`: the integrand without `G`.
fn terms_without_geometry(
    cam: &Segment,
    cam_medium: &VrlMedium,
    vpl: &Vpl,
    vpl_phase: &Phase,
    u: f32,
    x: Vec3,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let n = connection_direction(x - vpl.p, cam.d, vpl.d_in);
    let phases = vpl_phase.eval(vpl.d_in, n) * cam_medium.phase.eval(n, -cam.d);
    vpl.flux * connect(vpl.p, x) * cam_medium.sigma_s * cam_medium.sigma_t.exp_neg(u) * phases
}
