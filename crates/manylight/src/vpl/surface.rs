//! Surface VPLs (the non-delta surface vertices of light paths) and their contribution to a
//! camera segment, with the camera distance sampled equiangularly towards the VPL
//! (`docs/theory.md` §5.2, (T12c)):
//!
//! ```text
//! L = Int_0^s I(n) Tr(p, x_u) / w^2 f_c(n, -w_c) sigma_s_c T_c(u) du,   I(n) = Phi f_p(n, w_p) |n_p . n|
//! ```

use crate::vrl::estimator::connection_direction;
use crate::vrl::{Segment, VrlMedium};
use haze_core::{Frame, Rgb, Vec3};
use haze_scene::texture::TexPoint;
use haze_scene::{Bsdf, MediumId};

/// A surface VPL: one non-delta surface vertex of a light path.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceVpl {
    pub p: Vec3,
    /// Geometric normal (for the origin offset of connections and the media of each side).
    pub n: Vec3,
    /// Shading frame.
    pub frame: Frame,
    /// Unit direction towards the previous light-path vertex, local to `frame`.
    pub w_prev: Vec3,
    /// Light arriving at `p` (`beta / mean(r)`), in watts.
    pub flux: Rgb,
    pub shape: u32,
    /// Where the BSDF's textures are looked up (`SurfaceInteraction::tex`).
    pub tex: TexPoint,
    /// The medium the light path arrived in.
    pub medium: Option<MediumId>,
    /// Scattering events of the light path before this vertex (the path-length rule,
    /// `crate::depth`).
    pub events: u32,
}

impl SurfaceVpl {
    /// Intensity towards the unit world direction `w`: `Phi f(w, w_prev) |cos w|`, with the
    /// radiance-mode BSDF taking `w` as the camera side (`Bsdf::eval(w, w_prev)` includes
    /// `|cos w_prev|`, divided out), which is right for refraction too (no adjoint factor).
    #[inline]
    pub fn intensity(&self, bsdf: &Bsdf, w: Vec3) -> Rgb {
        let cos_prev = self.w_prev.z.abs();
        if cos_prev < 1e-7 {
            return Rgb::ZERO;
        }
        let wl = self.frame.to_local(w);
        self.flux * bsdf.eval(wl, self.w_prev, self.tex) * (wl.z.abs() / cos_prev)
    }
}

/// One sample of a point light's contribution to the camera segment `cam`: `p` the light point,
/// `intensity(n)` its intensity along the unit propagation direction `n`. `u` picks the camera
/// distance equiangularly from `p` (`p(u) = h / (Theta w^2)`), so the estimate is
/// `I Tr f_c sigma_s_c T_c(u) * Theta / h` (T12c), with `1/w^2` replaced by `min(1/w^2, c)`
/// under `geometry_clamp = Some(c)` (biased). `h` is floored at `1e-6 s` as in docs/theory.md §5.
pub fn sample_point_light_to_segment(
    cam: &Segment,
    cam_medium: &VrlMedium,
    p: Vec3,
    intensity: impl Fn(Vec3) -> Rgb,
    u: f32,
    geometry_clamp: Option<f32>,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if cam.len.is_nan() || cam.len <= 0.0 || cam_medium.sigma_s.is_black() {
        return Rgb::ZERO;
    }
    let Some((uc, g_over_pdf)) = super::estimator::sample_distance_towards(cam, p, u, geometry_clamp) else {
        return Rgb::ZERO;
    };
    terms_without_geometry(cam, cam_medium, p, &intensity, uc, connect) * g_over_pdf
}

/// The integrand of [`sample_point_light_to_segment`] at `u` (zero outside the segment); for
/// tests.
pub fn point_light_to_segment_integrand(
    cam: &Segment,
    cam_medium: &VrlMedium,
    p: Vec3,
    intensity: impl Fn(Vec3) -> Rgb,
    u: f32,
    connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    if !(0.0..=cam.len).contains(&u) {
        return Rgb::ZERO;
    }
    let w2 = (cam.at(u).as_dvec3() - p.as_dvec3()).length_squared();
    terms_without_geometry(cam, cam_medium, p, &intensity, u, connect) * (1.0 / w2) as f32
}

fn terms_without_geometry(
    cam: &Segment,
    cam_medium: &VrlMedium,
    p: Vec3,
    intensity: &impl Fn(Vec3) -> Rgb,
    u: f32,
    mut connect: impl FnMut(Vec3, Vec3) -> Rgb,
) -> Rgb {
    let x = cam.at(u);
    let n = connection_direction(x - p, cam.d, cam.d.any_orthonormal_vector());
    let i = intensity(n);
    if i.is_black() {
        return Rgb::ZERO;
    }
    i * connect(p, x) * cam_medium.sigma_s * cam_medium.sigma_t.exp_neg(u) * cam_medium.phase.eval(n, -cam.d)
}
