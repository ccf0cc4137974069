//! Heterogeneous media in the many-light estimators (`docs/theory.md` §12.5, (T31)-(T35)).
//!
//! The joint sampling of the VRL estimator (`1/h` on the VRL, then equiangular on the camera
//! segment) and the equiangular sampling of the VPL, surface-VPL and VRL-to-point estimators
//! depend on geometry only, never on the medium, so they stay exact (normalised densities whose
//! pdfs the estimators divide by) in any medium. On a heterogeneous segment each distance is
//! drawn from the one-sample mixture (T35) of that geometric density and the marched density
//! (T34), a tabulated `sigma_s T` that follows where the medium is, for variance only (the
//! estimate divides by the mixture pdf). What a heterogeneous medium changes is the
//! integrand: `sigma_s` at the sampled points and the transmittances along the camera segment,
//! along the VRL and on the connection, which have no closed form. Each is replaced by an
//! unbiased estimate: `sigma_s(x)` is evaluated exactly, each transmittance by ratio tracking
//! (T30) with random numbers of its own; independent unbiased estimates multiply to an unbiased
//! estimate of the product (T32), so the estimators stay unbiased.
//!
//! To reuse the homogeneous estimator's second stage (`point_pair_estimate`) unchanged, a heterogeneous medium is passed to them as
//! the *neutral* medium (`sigma_s = 1`, `sigma_t = 0`, its phase function): every homogeneous
//! factor is then 1, and the connection callback, which sees both sampled points, multiplies in
//! the heterogeneous factors `sigma_s(x) T(0, u)` of each side ([`along`]). The pass-level media
//! table keeps a homogeneous *proxy* of the medium for the light tree's importance
//! (`crate::camera::estimator_medium`: the mean majorant); the proxy only steers probabilities.
//!
//! Scenes without heterogeneous media never reach this module's estimates (the callers branch
//! once per camera segment or light evaluation on [`any`]), so their images are bit for bit as
//! before; [`scattering_factors`] gives both kinds their `T sigma_s`, exactly in a homogeneous
//! medium.

use crate::camera::CameraSegment;
use crate::vpl::{SurfaceVpl, Vpl};
use crate::vrl::estimator::{connection_direction, contributes, point_pair_estimate, PointPair};
use crate::vrl::sampling::{Equiangular, VrlPointSampler};
use crate::vrl::{Segment, Vrl, VrlMedium};
use glam::{Vec2, Vec3};
use haze_core::streams::TRACK_STREAM;
use haze_core::{Rgb, Sampler};
use haze_render::integrators::transmittance_to_sampled;
use haze_scene::hetero::Heterogeneous;
use haze_scene::marched::MarchedDistance;
use haze_scene::{Medium, MediumId, Scene};

/// True if any medium of the scene is heterogeneous.
#[inline]
pub(crate) fn any(scene: &Scene) -> bool {
    scene.media.iter().any(|m| !m.is_homogeneous())
}

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
    match scene.medium(id).as_grid() {
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

/// `T(seg.o, x) sigma_s(x)` at `x = seg.at(v)` in medium `med`, as two factors that the
/// estimators multiply in turn (each keeps its own order of rounding): in a homogeneous medium
/// exactly `(exp(-sigma_t v), sigma_s)`; in a grid `(sigma_s(x) T(v), 1)`, `T` by ratio
/// tracking from `s` ([`along`], (T31)). `None` where a grid gives zero (it does not scatter at
/// `x`, or the estimate is zero): the caller's estimate is zero.
#[inline]
pub(crate) fn scattering_factors(
    med: &Medium,
    seg: &Segment,
    v: f32,
    x: Vec3,
    s: &mut Sampler,
) -> Option<(Rgb, Rgb)> {
    match med.as_grid() {
        None => {
            let (sigma_t, sigma_s) = med.coefficients(x);
            Some((sigma_t.exp_neg(v), sigma_s))
        }
        Some(h) => Some(along(h, seg, x, s)).filter(|f| !f.is_black()).map(|f| (f, Rgb::ONE)),
    }
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

/// The share of the geometric strategy (`1/h`, equiangular) in the one-sample mixture with the
/// marched density (T34) on a heterogeneous segment.
const GEOMETRIC_SHARE: f64 = 0.5;

/// The bound cut's factor of medium `id` (`m` its entry of the pass's media table), per channel:
/// `sigma_s f_max` of (T15) for a homogeneous medium; for a heterogeneous one the largest
/// `sigma_s(x) f_max` (the global majorant times the albedo volume's maximum, both bounds, T28)
/// divided by the geometric share `a` of the mixture (T35) ((T36)), since the mixture's weights stay
/// within `1/a` of the geometric ones (`docs/theory.md` §12.5, "The bound cut"). Ratio-tracking
/// estimates of transmittance (T30) never exceed 1 under a true majorant, so (T15)'s
/// `T_c <= 1` and the VRL's `Phi(0)` still bound them.
pub(crate) fn bound_factor(scene: &Scene, m: &VrlMedium, id: MediumId) -> Rgb {
    let medium = scene.medium(id);
    if medium.is_homogeneous() {
        m.sigma_s * m.phase.max_value()
    } else {
        medium.majorant() * medium.albedo_bound() * medium.phase.max_value() * (1.0 / GEOMETRIC_SHARE as f32)
    }
}

/// The marched density (T34) along `seg` in `h`, if it has one.
#[inline]
fn marched_distance(h: Option<&Heterogeneous>, seg: &Segment) -> Option<MarchedDistance> {
    h.and_then(|h| MarchedDistance::new(h, seg.o, seg.d, seg.len))
}

/// A distance `t` on `seg` towards the point `p` and `1 / (w^2 p(t))` (`w = |seg(t) - p|`),
/// times `min(1, c w^2)` under the clamp `c`: equiangular sampling (T8), (T9), or with the
/// marched density `maj` the one-sample mixture (T35)
/// `p = a p_eq + (1 - a) p_med`, for which `w^2 p = a h / Theta + (1 - a) p_med w^2`, so the
/// weight stays below `Theta / (a h)` (no division by a small `w`). `None` for a degenerate
/// segment.
fn towards(
    seg: &Segment,
    maj: Option<&MarchedDistance>,
    p: Vec3,
    u: f32,
    clamp: Option<f32>,
) -> Option<(f32, f32)> {
    let c = seg.d.as_dvec3();
    let r = (p - seg.o).as_dvec3();
    let foot = r.dot(c);
    let eq = Equiangular::new(foot, (r - foot * c).length(), 0.0, seg.len as f64)?;
    let (t, w2p) = match maj {
        None => {
            let t = eq.sample(u as f64);
            (t, eq.h / eq.span)
        }
        Some(m) => {
            let a = GEOMETRIC_SHARE;
            let u = u as f64;
            let t = if u < a { eq.sample(u / a) } else { m.sample(((u - a) / (1.0 - a)) as f32) as f64 };
            let t = t.clamp(0.0, seg.len as f64);
            let w2 = eq.h * eq.h + (t - foot) * (t - foot);
            (t, a * eq.h / eq.span + (1.0 - a) * m.pdf(t as f32) as f64 * w2)
        }
    };
    let mut g = 1.0 / w2p;
    if let Some(clamp) = clamp {
        let w2 = eq.h * eq.h + (t - foot) * (t - foot);
        g *= (clamp as f64 * w2).min(1.0);
    }
    (g.is_finite() && g > 0.0).then_some(((t as f32).min(seg.len), g as f32))
}

/// The camera side of a light point's estimate at `x = cs.seg(t)`: `sigma_s(x) T_c(t)` exactly in
/// a homogeneous camera medium `m`, by (T31) in a heterogeneous one.
#[inline]
fn camera_side(
    cs: &CameraSegment,
    m: &VrlMedium,
    h: Option<&Heterogeneous>,
    x: Vec3,
    t: f32,
    s: &mut Sampler,
) -> Rgb {
    match h {
        Some(h) => along(h, &cs.seg, x, s),
        None => m.sigma_s * m.sigma_t.exp_neg(t),
    }
}

/// VRL -> camera segment in a scene with heterogeneous media (T33): `v` on the VRL from the `1/h`
/// density (T6) mixed with the VRL's marched density (T34) when its medium is heterogeneous,
/// then `u` on the camera segment towards `y_v` by [`towards`]; the estimate is (T33) with the
/// mixture pdfs (T35).
pub(crate) fn vrl_to_segment(
    scene: &Scene,
    cs: &CameraSegment,
    media: &[VrlMedium],
    vrl: &Vrl,
    u: Vec2,
) -> Rgb {
    let (cam_m, cam_h) = view(scene, &media[cs.medium as usize], cs.medium);
    let (vrl_m, vrl_h) = view(scene, &media[vrl.medium as usize], vrl.medium);
    if !contributes(&cs.seg, &cam_m, vrl, &vrl_m) {
        return Rgb::ZERO;
    }
    let Some(on_vrl) = VrlPointSampler::new(cs.seg.o, cs.seg.d, &vrl.seg) else { return Rgb::ZERO };
    let (v, pdf_v) = match marched_distance(vrl_h, &vrl.seg) {
        None => on_vrl.sample_f64(u.x as f64),
        Some(m) => {
            let a = GEOMETRIC_SHARE;
            let ux = u.x as f64;
            let v = if ux < a {
                on_vrl.sample_f64(ux / a).0
            } else {
                m.sample(((ux - a) / (1.0 - a)) as f32) as f64
            };
            let v = v.clamp(0.0, vrl.seg.len as f64);
            (v, a * on_vrl.pdf_f64(v) + (1.0 - a) * m.pdf(v as f32) as f64)
        }
    };
    if pdf_v.is_nan() || pdf_v <= 0.0 {
        return Rgb::ZERO;
    }
    let y = vrl.seg.at(v as f32);
    let maj_c = marched_distance(cam_h, &cs.seg);
    let Some((t, g)) = towards(&cs.seg, maj_c.as_ref(), y, u.y, None) else { return Rgb::ZERO };
    let pair = PointPair { u: t, v: v as f32, x: cs.seg.at(t), y, inv_w2_pdf: g / pdf_v as f32 };
    let mut s = tracker(u, vrl.seg.o);
    point_pair_estimate(&cs.seg, &cam_m, vrl, &vrl_m, &pair, |y, x| {
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

/// VRL -> gathering surface point `x` (T12b with the VRL side of T33; `receiver(d)` the point's
/// `f(wi, d) |cos d|`, as `GatherPoint::reflectance`): `v` towards `x` by [`towards`] on the VRL.
pub(crate) fn vrl_to_point(
    scene: &Scene,
    x: Vec3,
    receiver: impl Fn(Vec3) -> Rgb,
    media: &[VrlMedium],
    vrl: &Vrl,
    u: f32,
) -> Rgb {
    let (vrl_m, vrl_h) = view(scene, &media[vrl.medium as usize], vrl.medium);
    let seg = &vrl.seg;
    if !(seg.len > 0.0 && seg.len.is_finite()) || (vrl.flux * vrl_m.sigma_s).is_black() {
        return Rgb::ZERO;
    }
    let maj = marched_distance(vrl_h, seg);
    let Some((v, g)) = towards(seg, maj.as_ref(), x, u, None) else { return Rgb::ZERO };
    let y = seg.at(v);
    let n = connection_direction(x - y, seg.d, seg.d.any_orthonormal_vector());
    let f = receiver(-n);
    if f.is_black() {
        return Rgb::ZERO;
    }
    let mut s = tracker(Vec2::new(u, 0.5), seg.o + x);
    let light = match vrl_h {
        Some(h) => along(h, seg, y, &mut s),
        None => vrl_m.sigma_s,
    };
    if light.is_black() {
        return Rgb::ZERO;
    }
    vrl.flux_at(vrl_m.sigma_t, v)
        * light
        * f
        * connect(scene, vrl.medium, y, x, &mut s)
        * vrl_m.phase.eval(seg.d, n)
        * g
}

/// A point light at `p` of intensity `intensity(n)` -> camera segment (T13, T12c with the camera
/// side of T33): `u` towards `p` by [`towards`]; `connect(x, s)` the transmittance to `x`.
#[allow(clippy::too_many_arguments)]
fn point_light_to_segment(
    scene: &Scene,
    cs: &CameraSegment,
    cam_medium: &VrlMedium,
    p: Vec3,
    intensity: impl Fn(Vec3) -> Rgb,
    u: Vec2,
    clamp: Option<f32>,
    mut connect: impl FnMut(Vec3, &mut Sampler) -> Rgb,
) -> Rgb {
    let (cam_m, cam_h) = view(scene, cam_medium, cs.medium);
    if cs.seg.len.is_nan() || cs.seg.len <= 0.0 || cam_m.sigma_s.is_black() {
        return Rgb::ZERO;
    }
    let maj_c = marched_distance(cam_h, &cs.seg);
    let Some((t, g)) = towards(&cs.seg, maj_c.as_ref(), p, u.x, clamp) else { return Rgb::ZERO };
    let x = cs.seg.at(t);
    let n = connection_direction(x - p, cs.seg.d, cs.seg.d.any_orthonormal_vector());
    let i = intensity(n);
    if i.is_black() {
        return Rgb::ZERO;
    }
    let mut s = tracker(u, p);
    let cam = camera_side(cs, &cam_m, cam_h, x, t, &mut s);
    if cam.is_black() {
        return Rgb::ZERO;
    }
    i * cam * connect(x, &mut s) * cam_m.phase.eval(n, -cs.seg.d) * g
}

/// Medium VPL -> camera segment (T13 with the camera side of T33: the VPL's flux holds its own
/// `sigma_s`).
pub(crate) fn vpl_to_segment(
    scene: &Scene,
    cs: &CameraSegment,
    media: &[VrlMedium],
    vpl: &Vpl,
    u: Vec2,
    clamp: Option<f32>,
) -> Rgb {
    if vpl.flux.is_black() {
        return Rgb::ZERO;
    }
    let phase = &media[vpl.medium as usize].phase;
    let cam_medium = &media[cs.medium as usize];
    point_light_to_segment(
        scene,
        cs,
        cam_medium,
        vpl.p,
        |n| vpl.flux * phase.eval(vpl.d_in, n),
        u,
        clamp,
        |x, s| connect(scene, vpl.medium, vpl.p, x, s),
    )
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
    let bsdf = &scene.shapes[vpl.shape as usize].bsdf;
    point_light_to_segment(
        scene,
        cs,
        cam_medium,
        vpl.p,
        |w| vpl.intensity(bsdf, w),
        u,
        clamp,
        |x, s| {
            let v = x - vpl.p;
            let dist = v.length();
            if dist <= 0.0 {
                return Rgb::ZERO;
            }
            let d = v / dist;
            let medium = scene.medium_leaving(vpl.shape, vpl.p, vpl.n, d, vpl.medium);
            transmittance_to_sampled(scene, vpl.p, Some(vpl.n), d, dist, medium, s)
        },
    )
}

/// A distance on the camera segment for single scattering towards the light point `p`, on
/// `[a, b]` (the spot's interval) or, mixed with the camera medium's marched density (T34), (T35),
/// anywhere on the segment; with its pdf. `None` if none exists.
pub(crate) fn single_distance(
    h: &Heterogeneous,
    seg: &Segment,
    p: Vec3,
    ab: (f32, f32),
    u: f32,
) -> Option<(f32, f32)> {
    let delta = (p - seg.o).dot(seg.d);
    let dist = (p - seg.at(delta)).length();
    let (a, b) = ab;
    let eq_pdf = |t: f32| crate::vrl::sampling::equiangular_pdf(t, delta, dist, a, b);
    let Some(m) = MarchedDistance::new(h, seg.o, seg.d, seg.len) else {
        let t = crate::vrl::sampling::sample_equiangular(u, delta, dist, a, b)?;
        return Some((t, eq_pdf(t)));
    };
    let share = GEOMETRIC_SHARE as f32;
    let t = if u < share {
        crate::vrl::sampling::sample_equiangular(u / share, delta, dist, a, b)?
    } else {
        m.sample((u - share) / (1.0 - share))
    };
    Some((t, share * eq_pdf(t) + (1.0 - share) * m.pdf(t)))
}
