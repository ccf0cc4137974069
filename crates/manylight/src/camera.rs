//! Camera rays as the many-light estimators see them: the medium intervals the ray crosses
//! (one segment per interval, through index-matched `null` boundaries) and the light it sees
//! directly when it ends on an emitter.

use crate::vrl::{Segment, VrlMedium};
use haze_core::ray::offset_origin;
use haze_core::transmittance::transmittance;
use haze_core::{Ray, Rgb};
use haze_scene::{MediumId, Scene};

/// One medium interval of a camera ray.
#[derive(Clone, Copy, Debug)]
pub struct CameraSegment {
    pub seg: Segment,
    pub medium: MediumId,
    /// Transmittance from the camera to `seg.o` (media crossed before this interval).
    pub tr_before: Rgb,
}

/// Where a camera ray ends.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraPath {
    /// Emitted radiance seen at the end of the ray (an area light's front side, or the
    /// environment), times the transmittance of everything crossed.
    pub emitted: Rgb,
    /// The ray ended on a surface that scatters light (not null, not black). Its light belongs
    /// to the `surface` component, which the many-light integrators do not estimate yet.
    pub hit_scattering_surface: bool,
}

/// Most media intervals kept per camera ray; a ray crossing more null boundaries than this keeps
/// its first `MAX_SEGMENTS` intervals (and the rest of its path is treated as blocked).
pub const MAX_SEGMENTS: usize = 64;

/// Traces `ray` from `medium` through null surfaces until it leaves the scene or meets a
/// non-null surface, appending one [`CameraSegment`] per medium interval to `out` (cleared
/// first; a caller-owned buffer so that the hot loop allocates nothing).
pub fn trace_camera_ray(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<MediumId>,
    out: &mut Vec<CameraSegment>,
) -> CameraPath {
    out.clear();
    let mut tr = Rgb::ONE;
    let mut remaining = ray.t_max;
    while out.len() < MAX_SEGMENTS {
        ray.t_max = remaining;
        let hit = scene.intersect(&ray);
        let len = hit.map_or(remaining, |h| h.t);
        if let Some(m) = medium {
            if len.is_finite() && len > 0.0 {
                out.push(CameraSegment { seg: Segment::new(ray.o, ray.d, len), medium: m, tr_before: tr });
            }
            tr *= transmittance(scene.medium(m).sigma_t, len);
        }
        let Some(h) = hit else {
            let env = scene.environment_radiance(ray.d);
            return CameraPath { emitted: tr * env, hit_scattering_surface: false };
        };
        let emitted = scene.area_radiance(h.shape, h.n, -ray.d).map_or(Rgb::ZERO, |(_, le)| tr * le);
        let shape = &scene.shapes[h.shape as usize];
        if !shape.bsdf.is_null() {
            return CameraPath { emitted, hit_scattering_surface: !shape.bsdf.is_black() };
        }
        medium = shape.medium_towards(ray.d, h.n, medium);
        let o = offset_origin(h.p, h.n, ray.d);
        remaining -= (o - ray.o).length();
        ray = Ray::new(o, ray.d);
        if tr.is_black() || remaining <= 0.0 {
            break;
        }
    }
    CameraPath::default()
}

/// The medium of a segment in the form the estimators take.
pub fn estimator_medium(scene: &Scene, id: MediumId) -> VrlMedium {
    let m = scene.medium(id);
    VrlMedium { sigma_s: m.sigma_s(), sigma_t: m.sigma_t, phase: m.phase }
}
