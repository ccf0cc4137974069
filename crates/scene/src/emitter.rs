//! Light sources (Mitsuba 3 plugins `point`, `spot`, `area`, `constant`, `envmap`, `directional`,
//! `projector`).

use crate::envmap::EnvMap;
use crate::projector::Projector;
use crate::texture::Texture;
use glam::{Mat4, Vec2, Vec3};
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
        /// Mitsuba 3's `texture`: an image projected through the cone, multiplying the
        /// intensity ([`Emitter::spot_texture`]); `None` for a plain spot.
        texture: Option<Texture>,
    },
    /// Diffuse area light on shape `shape`, emitting `radiance` on the side its normal points to:
    /// a constant, or (Mitsuba 3's textured `area`) a texture looked up at the surface point's
    /// [`TexPoint`](crate::texture::TexPoint), a hit's or a sampled point's.
    Area { shape: u32, radiance: Texture },
    /// Uniform environment radiance from every direction at infinity.
    Constant { radiance: Rgb },
    /// Radiance at infinity from a latitude-longitude image (see [`EnvMap`]).
    EnvMap(Arc<EnvMap>),
    /// Mitsuba 3's `directional` (the sun): parallel light travelling along the unit direction
    /// `d`, delivering `irradiance` (W/m^2) to a surface perpendicular to `d`. A delta light at
    /// infinity: next-event estimation is the only way to it, no ray hits it.
    Directional { d: Vec3, irradiance: Rgb },
    /// Mitsuba 3's `projector`: a delta position light projecting an image ([`Projector`]).
    Projector(Box<Projector>),
}

impl Emitter {
    /// The spot light of [`Emitter::Spot`] (angles in radians).
    pub fn spot(
        to_world: Mat4,
        intensity: Rgb,
        cutoff_angle: f32,
        beam_width: f32,
        texture: Option<Texture>,
    ) -> Self {
        Emitter::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
            to_local: to_world.inverse(),
            cos_cutoff: cutoff_angle.cos(),
            cos_beam: beam_width.cos(),
            texture,
        }
    }

    /// A textured spot's factor for the direction `d_local` (unit, local frame; inside the
    /// cone): the texture at `uv = 1/2 + (x, y) / (2 z tan(cutoff_angle))`, the cone's
    /// cross-section mapped onto the unit square (Mitsuba 3's `spot.cpp`, checked on its
    /// `sample_direction`). 1 without a texture.
    pub fn spot_texture(texture: &Option<Texture>, cutoff_angle: f32, d_local: Vec3) -> Rgb {
        match texture {
            None => Rgb::ONE,
            Some(t) => {
                let k = 0.5 / (d_local.z * cutoff_angle.tan());
                t.eval(Vec2::new(0.5 + d_local.x * k, 0.5 + d_local.y * k))
            }
        }
    }

    /// True for a spot with a `texture` (the many-light methods have no such light).
    pub fn is_textured_spot(&self) -> bool {
        matches!(self, Emitter::Spot { texture: Some(_), .. })
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
        matches!(
            self,
            Emitter::Point { .. }
                | Emitter::Spot { .. }
                | Emitter::Directional { .. }
                | Emitter::Projector(_)
        )
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bitmap::{Bitmap, FilterType, WrapMode};

    /// A 2x2 texture seen through a 30-degree spot: each quadrant of the cone gets the texel
    /// Mitsuba 3.9.1 gives it (`spot` with a `nearest` bitmap, `sample_direction` from the
    /// points `3 (+-0.2, +-0.2, 1)`): +x+y white, -x+y blue, +x-y green, -x-y red.
    #[test]
    fn spot_texture_quadrants_match_mitsuba() {
        let texels =
            vec![Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 1.0, 0.0), Rgb::new(0.0, 0.0, 1.0), Rgb::ONE];
        let b = Bitmap::new(2, 2, texels, FilterType::Nearest, WrapMode::Repeat, glam::Affine2::IDENTITY)
            .unwrap();
        let t = Some(Texture::Bitmap(Arc::new(b)));
        let cutoff = 30f32.to_radians();
        let at = |x: f32, y: f32| Emitter::spot_texture(&t, cutoff, Vec3::new(x, y, 1.0).normalize());
        assert_eq!(at(0.2, 0.2), Rgb::ONE);
        assert_eq!(at(-0.2, 0.2), Rgb::new(0.0, 0.0, 1.0));
        assert_eq!(at(0.2, -0.2), Rgb::new(0.0, 1.0, 0.0));
        assert_eq!(at(-0.2, -0.2), Rgb::new(1.0, 0.0, 0.0));
        // The cone's edge reaches the square's edge: tan(30 deg) along x is u = 1.
        let edge = Vec3::new(cutoff.tan(), 0.0, 1.0).normalize();
        let k = 0.5 / (edge.z * cutoff.tan());
        assert!((0.5 + edge.x * k - 1.0).abs() < 1e-6);
        assert_eq!(Emitter::spot_texture(&None, cutoff, edge), Rgb::ONE);
    }
}
