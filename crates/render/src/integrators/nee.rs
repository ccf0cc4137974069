//! Shadow rays through media and index-matched (`null`) boundaries.

use glam::Vec3;
use haze_core::ray::offset_origin;
use haze_core::transmittance::transmittance;
use haze_core::{Frame, Ray, Rgb};
use haze_scene::{MediumId, Scene};

/// Transmittance from `p` along the unit direction `d` over distance `dist` (infinite for
/// environment light), starting in `medium`. Null surfaces are crossed (changing medium where
/// the shape declares media, as Mitsuba 3 does), thin dielectrics too, scaled by their
/// transmittance (Mitsuba's `eval_null_transmission`); any other surface blocks. Homogeneous media
/// give the exact Beer-Lambert factor, so this is deterministic.
///
/// `n_start` is the geometric normal at `p` when `p` is on a surface (used to offset the origin),
/// `None` in a medium.
pub fn transmittance_to(
    scene: &Scene,
    p: Vec3,
    n_start: Option<Vec3>,
    d: Vec3,
    dist: f32,
    mut medium: Option<MediumId>,
) -> Rgb {
    let mut tr = Rgb::ONE;
    let mut origin = match n_start {
        Some(n) => offset_origin(p, n, d),
        None => p,
    };
    // Shorten towards the light's surface so the light's own shape does not occlude.
    let mut remaining =
        if dist.is_finite() { dist * (1.0 - 1e-4) - (origin - p).length() } else { f32::INFINITY };
    for _ in 0..256 {
        let ray = Ray { o: origin, d, t_max: remaining };
        let hit = scene.intersect(&ray);
        let seg = hit.map_or(remaining, |h| h.t);
        if let Some(m) = medium {
            tr *= beer_lambert(scene.medium(m).sigma_t, seg);
            if tr.is_black() {
                return Rgb::ZERO;
            }
        }
        let Some(h) = hit else { return tr };
        let shape = &scene.shapes[h.shape as usize];
        if !shape.bsdf.is_null() {
            // A thin dielectric passes light with its transmittance; other surfaces block.
            let wi = Frame::from_normal(h.ns).to_local(-d);
            tr *= shape.bsdf.null_transmission(wi, h.uv);
            if tr.is_black() {
                return Rgb::ZERO;
            }
        }
        medium = shape.medium_towards(d, h.n, medium);
        origin = offset_origin(h.p, h.n, d);
        if remaining.is_finite() {
            remaining -= (origin - ray.o).length();
            if remaining <= 0.0 {
                return tr;
            }
        }
    }
    // A ray that keeps hitting null surfaces 256 times is caught in degenerate geometry.
    Rgb::ZERO
}

/// [`transmittance`] with a single `exp` for grey extinction (equal channels), the common
/// case: the same values for a third of the work on every shadow and connection ray.
#[inline]
fn beer_lambert(sigma_t: Rgb, d: f32) -> Rgb {
    let [r, g, b] = sigma_t.0;
    if r == g && g == b && d.is_finite() {
        Rgb::splat((-r * d).exp())
    } else {
        transmittance(sigma_t, d)
    }
}
