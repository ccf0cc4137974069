//! Light sources (Mitsuba 3 plugins `point`, `spot`, `area`, `constant`, `envmap`).

use crate::envmap::EnvMap;
use glam::{Mat4, Vec3};
use haze_core::Rgb;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// Isotropic point light; `intensity` in W/sr.
    Point { position: Vec3, intensity: Rgb },
    /// Spot light at the origin of `to_world` shining down its local `+z`. Mitsuba 3's falloff:
    /// full intensity inside `beam_width`, linear in angle down to zero at `cutoff_angle`
    /// (angles in radians, half-angles from the axis).
    Spot { to_world: Mat4, intensity: Rgb, cutoff_angle: f32, beam_width: f32 },
    /// Diffuse area light on shape `shape`, emitting `radiance` on the side its normal points to.
    Area { shape: u32, radiance: Rgb },
    /// Uniform environment radiance from every direction at infinity.
    Constant { radiance: Rgb },
    /// Radiance at infinity from a latitude-longitude image (see [`EnvMap`]).
    EnvMap(Arc<EnvMap>),
}

impl Emitter {
    /// Spot falloff for a direction `d_local` (unit, in the spot's local frame), in `[0, 1]`.
    pub fn spot_falloff(cutoff_angle: f32, beam_width: f32, d_local: Vec3) -> f32 {
        let cos_t = d_local.z;
        if cos_t <= cutoff_angle.cos() {
            return 0.0;
        }
        if cos_t >= beam_width.cos() {
            return 1.0;
        }
        ((cutoff_angle - cos_t.clamp(-1.0, 1.0).acos()) / (cutoff_angle - beam_width)).clamp(0.0, 1.0)
    }
}

impl Emitter {
    /// True for emitters at infinity (`constant`, `envmap`).
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Constant { .. } | Emitter::EnvMap(_))
    }

    /// Radiance of an environment emitter arriving from the unit direction `d` (the direction
    /// of a ray escaping to infinity); zero for other emitters.
    pub fn environment_radiance(&self, d: Vec3) -> Rgb {
        match self {
            Emitter::Constant { radiance } => *radiance,
            Emitter::EnvMap(map) => map.eval(d),
            _ => Rgb::ZERO,
        }
    }

    /// The shape of an area emitter.
    pub fn area_shape(&self) -> Option<u32> {
        match self {
            Emitter::Area { shape, .. } => Some(*shape),
            _ => None,
        }
    }
}
