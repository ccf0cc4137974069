//! Light sources (Mitsuba 3 plugins `point`, `spot`, `area`, `constant`, `envmap`, `directional`).

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
    /// (angles in radians, half-angles from the axis). Made by [`Emitter::spot`], which
    /// derives the last three fields once (next-event estimation reads them per sample).
    Spot {
        to_world: Mat4,
        intensity: Rgb,
        cutoff_angle: f32,
        beam_width: f32,
        /// The inverse of `to_world`.
        to_local: Mat4,
        /// `cutoff_angle.cos()` and `beam_width.cos()`.
        cos_cutoff: f32,
        cos_beam: f32,
    },
    /// Diffuse area light on shape `shape`, emitting `radiance` on the side its normal points to.
    Area { shape: u32, radiance: Rgb },
    /// Uniform environment radiance from every direction at infinity.
    Constant { radiance: Rgb },
    /// Radiance at infinity from a latitude-longitude image (see [`EnvMap`]).
    EnvMap(Arc<EnvMap>),
    /// Mitsuba 3's `directional` (the sun): parallel light travelling along the unit direction
    /// `d`, delivering `irradiance` (W/m^2) to a surface perpendicular to `d`. A delta light at
    /// infinity: next-event estimation is the only way to it, no ray hits it.
    Directional { d: Vec3, irradiance: Rgb },
}

impl Emitter {
    /// The spot light of [`Emitter::Spot`] (angles in radians).
    pub fn spot(to_world: Mat4, intensity: Rgb, cutoff_angle: f32, beam_width: f32) -> Self {
        Emitter::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
            to_local: to_world.inverse(),
            cos_cutoff: cutoff_angle.cos(),
            cos_beam: beam_width.cos(),
        }
    }

    /// Spot falloff for a direction `d_local` (unit, in the spot's local frame), in `[0, 1]`.
    pub fn spot_falloff(cutoff_angle: f32, beam_width: f32, d_local: Vec3) -> f32 {
        Self::spot_falloff_cos(cutoff_angle, beam_width, cutoff_angle.cos(), beam_width.cos(), d_local)
    }

    /// [`Self::spot_falloff`] with the cosines of the two angles given (`cos_cutoff`,
    /// `cos_beam` of [`Emitter::Spot`]): the same value without two `cos` calls.
    #[inline]
    pub fn spot_falloff_cos(
        cutoff_angle: f32,
        beam_width: f32,
        cos_cutoff: f32,
        cos_beam: f32,
        d_local: Vec3,
    ) -> f32 {
        let cos_t = d_local.z;
        if cos_t <= cos_cutoff {
            return 0.0;
        }
        if cos_t >= cos_beam {
            return 1.0;
        }
        ((cutoff_angle - cos_t.clamp(-1.0, 1.0).acos()) / (cutoff_angle - beam_width)).clamp(0.0, 1.0)
    }
}

impl Emitter {
    /// True for emitters that no ray can hit by chance (`point`, `spot`, `directional`): next-event estimation
    /// is the only way to their light, so no MIS weight involves them.
    pub fn is_delta(&self) -> bool {
        matches!(self, Emitter::Point { .. } | Emitter::Spot { .. } | Emitter::Directional { .. })
    }

    /// True for the emitters that escaping rays see (`constant`, `envmap`): radiance at
    /// infinity from every direction of their support.
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Constant { .. } | Emitter::EnvMap(_))
    }

    /// True for emitters at infinity (`constant`, `envmap`, `directional`): their light enters
    /// the scene from outside its bounding sphere, from no point of it.
    pub fn is_infinite(&self) -> bool {
        self.is_environment() || matches!(self, Emitter::Directional { .. })
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
