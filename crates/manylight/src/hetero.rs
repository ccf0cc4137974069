//! Heterogeneous media in the many-light estimators (`docs/theory.md` §12.5, (T31)-(T33)).
//!
//! The joint sampling of the VRL estimator (`1/h` on the VRL, then equiangular on the camera
//! segment) and the equiangular sampling of the VPL, surface-VPL and VRL-to-point estimators
//! depend on geometry only, never on the medium, so they stay exact (normalised densities whose
//! pdfs the estimators divide by) in any medium. What a heterogeneous medium changes is the
//! integrand: `sigma_s` at the sampled points and the transmittances along the camera segment,
//! along the VRL and on the connection, which have no closed form. Each is replaced by an
//! unbiased estimate: `sigma_s(x)` is evaluated exactly, each transmittance by ratio tracking
//! (T30) with random numbers of its own; independent unbiased estimates multiply to an unbiased
//! estimate of the product (T32), so the estimators stay unbiased.
//!
//! To reuse the homogeneous estimators unchanged, a heterogeneous medium is passed to them as
//! the *neutral* medium (`sigma_s = 1`, `sigma_t = 0`, its phase function): every homogeneous
//! factor is then 1, and the connection callback, which sees both sampled points, multiplies in
//! the heterogeneous factors `sigma_s(x) T(0, u)` of each side ([`along`]). The pass-level media
//! table keeps a homogeneous *proxy* of the medium for the light tree's importance
//! (`crate::camera::estimator_medium`: the mean majorant); the proxy only steers probabilities.
//!
//! Scenes without heterogeneous media never reach this module (the callers branch once per
//! camera segment or light evaluation on [`any`]), so their images are bit for bit as before.

use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::vpl::{SurfaceVpl, Vpl};
use crate::vrl::{Segment, Vrl, VrlMedium};
use glam::{Vec2, Vec3};
use haze_core::{Rgb, Sampler};
use haze_render::integrators::transmittance_to_sampled;
use haze_scene::hetero::Heterogeneous;
use haze_scene::{MediumId, Scene};

/// True if any medium of the scene is heterogeneous.
#[inline]
pub(crate) fn any(scene: &Scene) -> bool {
    scene.media.iter().any(|m| !m.is_homogeneous())
}

/// Separates the ratio-tracking streams of light evaluations from every other stream.
const TRACK_STREAM: u64 = 0x7261_7469_6f5f_7472;

/// The random numbers of one light evaluation's ratio tracking, from the uniform numbers that
/// sample its points and a salt of the light (so that two lights with equal numbers still track
/// independently). Every estimate is unbiased whatever the numbers; deterministic per light and
/// camera segment, so an exhaustive lightcut still equals the brute-force sum.
#[inline]
pub(crate) fn tracker(u: Vec2, salt: Vec3) -> Sampler {
    let a = ((u.x.to_bits() as u64) << 32) | u.y.to_bits() as u64;
    let b = [salt.x, salt.y, salt.z].iter().fold(0u64, |k, v| haze_core::rng::mix64(k ^ v.to_bits() as u64));
    Sampler::new(TRACK_STREAM, a, b)
}

/// The estimators' view of medium `id` (`m` its entry of the pass's media table): `m` if
/// homogeneous; for a heterogeneous one the neutral medium (module docs) and its coefficients.
#[inline]
pub(crate) fn view<'a>(
    scene: &'a Scene,
    m: &VrlMedium,
    id: MediumId,
) -> (VrlMedium, Option<&'a Heterogeneous>) {
    match scene.medium(id).hetero.as_deref() {
        None => (*m, None),
        Some(h) => (VrlMedium { sigma_s: Rgb::ONE, sigma_t: Rgb::ZERO, phase: m.phase }, Some(h)),
    }
}

/// `sigma_s(x) T(seg.o, x)` for a point `x` of `seg` in the heterogeneous medium `h` (T31):
/// `sigma_s` exactly, the transmittance from the segment's start by ratio tracking (T30). Zero,
/// with no tracking, where the medium does not scatter.
#[inline]
pub(crate) fn along(h: &Heterogeneous, seg: &Segment, x: Vec3, s: &mut Sampler) -> Rgb {
    let (_, sigma_s) = h.coefficients(x);
    if sigma_s.is_black() {
        return Rgb::ZERO;
    }
    let t = (x - seg.o).dot(seg.d).clamp(0.0, seg.len);
    sigma_s * h.transmittance(seg.o, seg.d, 0.0, t, s)
}

/// Transmittance and visibility from `y` (in medium `from`) to `x` with ratio tracking from `s`
/// (`crate::integrators::connect` with the caller's numbers).
#[inline]
pub(crate) fn connect(scene: &Scene, from: MediumId, y: Vec3, x: Vec3, s: &mut Sampler) -> Rgb {
    let v = x - y;
    let dist = v.length();
    if dist <= 0.0 {
        return Rgb::ZERO;
    }
    transmittance_to_sampled(scene, y, None, v / dist, dist, Some(from), s)
}

/// VRL -> camera segment in a scene with heterogeneous media (T33): the joint estimator of
/// `docs/theory.md` §4.3 with the neutral media, times the heterogeneous factors of both sides.
pub(crate) fn vrl_to_segment(
    scene: &Scene,
    cs: &CameraSegment,
    media: &[VrlMedium],
    vrl: &Vrl,
    u: Vec2,
) -> Rgb {
    let (cam_m, cam_h) = view(scene, &media[cs.medium as usize], cs.medium);
    let (vrl_m, vrl_h) = view(scene, &media[vrl.medium as usize], vrl.medium);
    let mut s = tracker(u, vrl.seg.o);
    crate::vrl::sample_vrl_contribution(&cs.seg, &cam_m, vrl, &vrl_m, u, |y, x| {
        let mut f = Rgb::ONE;
        if let Some(h) = vrl_h {
            f *= along(h, &vrl.seg, y, &mut s);
        }
        if let Some(h) = cam_h {
            if !f.is_black() {
                f *= along(h, &cs.seg, x, &mut s);
            }
        }
        if f.is_black() {
            return f;
        }
        f * connect(scene, vrl.medium, y, x, &mut s)
    })
}

/// VRL -> gathering surface point (T33 with the receiver's BSDF in place of the camera side).
pub(crate) fn vrl_to_point(scene: &Scene, gp: &GatherPoint, media: &[VrlMedium], vrl: &Vrl, u: f32) -> Rgb {
    let (vrl_m, vrl_h) = view(scene, &media[vrl.medium as usize], vrl.medium);
    let mut s = tracker(Vec2::new(u, 0.5), vrl.seg.o + gp.p);
    crate::vrl::surface::sample_vrl_to_point(
        gp.p,
        |d| gp.reflectance(d),
        vrl,
        &vrl_m,
        u,
        |y, x| {
            let f = match vrl_h {
                Some(h) => along(h, &vrl.seg, y, &mut s),
                None => Rgb::ONE,
            };
            if f.is_black() {
                return f;
            }
            f * connect(scene, vrl.medium, y, x, &mut s)
        },
    )
}

/// Medium VPL -> camera segment (T33 without the VRL side: the VPL's flux holds its own
/// `sigma_s`).
pub(crate) fn vpl_to_segment(
    scene: &Scene,
    cs: &CameraSegment,
    media: &[VrlMedium],
    vpl: &Vpl,
    u: Vec2,
    clamp: Option<f32>,
) -> Rgb {
    let (cam_m, cam_h) = view(scene, &media[cs.medium as usize], cs.medium);
    let mut s = tracker(u, vpl.p);
    let phase = &media[vpl.medium as usize].phase;
    crate::vpl::sample_vpl_contribution(&cs.seg, &cam_m, vpl, phase, u.x, clamp, |y, x| {
        let f = match cam_h {
            Some(h) => along(h, &cs.seg, x, &mut s),
            None => Rgb::ONE,
        };
        if f.is_black() {
            return f;
        }
        f * connect(scene, vpl.medium, y, x, &mut s)
    })
}

/// Surface VPL -> camera segment (T12c with the camera side of T33).
pub(crate) fn surface_vpl_to_segment(
    scene: &Scene,
    vpl: &SurfaceVpl,
    cs: &CameraSegment,
    cam_medium: &VrlMedium,
    u: Vec2,
    clamp: Option<f32>,
) -> Rgb {
    let (cam_m, cam_h) = view(scene, cam_medium, cs.medium);
    let mut s = tracker(u, vpl.p);
    let bsdf = &scene.shapes[vpl.shape as usize].bsdf;
    crate::vpl::sample_point_light_to_segment(
        &cs.seg,
        &cam_m,
        vpl.p,
        |w| vpl.intensity(bsdf, w),
        u.x,
        clamp,
        |_, x| {
            let f = match cam_h {
                Some(h) => along(h, &cs.seg, x, &mut s),
                None => Rgb::ONE,
            };
            if f.is_black() {
                return f;
            }
            let v = x - vpl.p;
            let dist = v.length();
            if dist <= 0.0 {
                return Rgb::ZERO;
            }
            let d = v / dist;
            let medium = scene.shapes[vpl.shape as usize].medium_towards(d, vpl.n, vpl.medium);
            f * transmittance_to_sampled(scene, vpl.p, Some(vpl.n), d, dist, medium, &mut s)
        },
    )
}
