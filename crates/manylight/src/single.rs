//! Single scattering on camera segments by next-event estimation (`docs/theory.md` §2, §6: the part of the
//! medium transport that no VRL or VPL produces).
//!
//! For every camera segment and every emitter, one sample: a point and point light is sampled
//! directly; for an area light a point `y` is first sampled on its surface by area. The camera
//! distance `u` is then sampled equiangularly towards the light point (Kulla & Fajardo 2012),
//! which cancels the `1/|x_u - y|^2` of the connection: low noise even where the segment passes
//! close to the light.
//!
//! ```text
//!   L_1 = Int_0^s T_c(u) sigma_s f_p(y -> x_u, -w_c) Tr(y, x_u) E(y -> x_u) / |x_u - y|^2 du
//! ```
//! with `E` the intensity (point, spot with falloff) or `L_e cos_y / p_area(y)` (area).

use crate::camera::{estimator_medium, CameraSegment};
use crate::vrl::sampling::{equiangular_pdf, sample_equiangular};
use glam::{Mat4, Vec2, Vec3};
use haze_core::{Rgb, Sampler};
use haze_render::integrators::transmittance_to;
use haze_scene::{Emitter, Scene};

/// One-sample estimate of single scattering along `cs` from all emitters (`constant` emitters
/// are excluded by `Scene::check_emission` before rendering).
pub fn single_scattering(scene: &Scene, cs: &CameraSegment, sampler: &mut Sampler) -> Rgb {
    let med = estimator_medium(scene, cs.medium);
    if med.sigma_s.is_black() || cs.seg.len <= 0.0 {
        return Rgb::ZERO;
    }
    let mut total = Rgb::ZERO;
    for i in 0..scene.emitters.len() {
        let u_light = sampler.next_2d();
        let u_dist = sampler.next_1d();
        let Some(light) = LightPoint::sample(scene, i, u_light) else { continue };
        // Equiangular parameters of the light point seen from the camera segment.
        let delta = (light.p - cs.seg.o).dot(cs.seg.d);
        let h = (light.p - cs.seg.at(delta)).length();
        let Some(u) = sample_equiangular(u_dist, delta, h, 0.0, cs.seg.len) else { continue };
        let pdf = equiangular_pdf(u, delta, h, 0.0, cs.seg.len);
        if pdf.is_nan() || pdf <= 0.0 {
            continue;
        }
        let x = cs.seg.at(u);
        let to_light = light.p - x;
        let dist = to_light.length();
        if dist <= 0.0 {
            continue;
        }
        let wi = to_light / dist;
        let e_val = light.emitted(-wi);
        if e_val.is_black() {
            continue;
        }
        let phase = med.phase.eval(-wi, -cs.seg.d);
        let tr = transmittance_to(scene, x, None, wi, dist, Some(cs.medium));
        let cam = med.sigma_t.exp_neg(u);
        total += cs.tr_before * cam * med.sigma_s * tr * e_val * (phase / (dist * dist * pdf));
    }
    total
}

/// A sampled point on an emitter.
struct LightPoint {
    p: Vec3,
    kind: LightKind,
}

enum LightKind {
    Point {
        intensity: Rgb,
    },
    Spot {
        to_local: Mat4,
        intensity: Rgb,
        cutoff: f32,
        beam: f32,
    },
    /// `radiance / p_area`, and the surface normal.
    Area {
        weighted_radiance: Rgb,
        n: Vec3,
    },
}

impl LightPoint {
    fn sample(scene: &Scene, i: usize, u: Vec2) -> Option<Self> {
        match &scene.emitters[i] {
            Emitter::Point { position, intensity } => {
                Some(LightPoint { p: *position, kind: LightKind::Point { intensity: *intensity } })
            }
            Emitter::Spot { to_world, intensity, cutoff_angle, beam_width } => Some(LightPoint {
                p: to_world.transform_point3(Vec3::ZERO),
                kind: LightKind::Spot {
                    to_local: to_world.inverse(),
                    intensity: *intensity,
                    cutoff: *cutoff_angle,
                    beam: *beam_width,
                },
            }),
            Emitter::Area { radiance, .. } => {
                let s = scene.sample_area_emitter_point(i, u)?;
                Some(LightPoint {
                    p: s.p,
                    kind: LightKind::Area { weighted_radiance: *radiance / s.pdf, n: s.n },
                })
            }
            Emitter::Constant { .. } | Emitter::EnvMap(_) => None,
        }
    }

    /// Intensity leaving the point in the unit direction `d` (for area lights: radiance times
    /// `cos` over the area pdf, zero behind the surface).
    fn emitted(&self, d: Vec3) -> Rgb {
        match &self.kind {
            LightKind::Point { intensity } => *intensity,
            LightKind::Spot { to_local, intensity, cutoff, beam } => {
                *intensity * Emitter::spot_falloff(*cutoff, *beam, to_local.transform_vector3(d).normalize())
            }
            LightKind::Area { weighted_radiance, n } => *weighted_radiance * n.dot(d).max(0.0),
        }
    }
}
