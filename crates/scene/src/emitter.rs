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

    /// The sun's light as `(d, E)`: the unit direction of travel `d` and the irradiance `E`
    /// (W/m^2) on a plane perpendicular to `d` of a `directional` emitter, whose every ray of
    /// direction `d` carries it; `None` for other emitters.
    pub fn parallel_light(&self) -> Option<(Vec3, Rgb)> {
        match self {
            Emitter::Directional { d, irradiance } => Some((*d, *irradiance)),
            _ => None,
        }
    }

    /// The shape of an area emitter.
    pub fn area_shape(&self) -> Option<u32> {
        match self {
            Emitter::Area { shape, .. } => Some(*shape),
            _ => None,
        }
    }

    /// The interval `[a, b]` of the segment `o + t d`, `t` in `[0, len]`, outside which the
    /// emitter sends no light to it: a spot light's cone ([`cone_interval`]), the whole segment
    /// for the other emitters; `None` if a spot light's cone misses the segment. Single
    /// scattering samples its distances there only.
    pub fn lit_interval(&self, o: Vec3, d: Vec3, len: f32) -> Option<(f32, f32)> {
        match self {
            Emitter::Spot { to_local, cutoff_angle, .. } => cone_interval(to_local, *cutoff_angle, o, d, len),
            _ => Some((0.0, len)),
        }
    }
}

/// The interval `[a, b]` of the parameter of the segment `o + t d`, `t` in `[0, len]`, where it
/// is inside the cone of a spot light with half-angle `cutoff` (apex at the origin of its local
/// frame, axis local `+z`; `to_local` maps world to local), or `None` if the segment misses the
/// cone. The cone is widened by a relative
/// 1e-3 so that rounding never cuts off a sliver of the beam (a wider interval costs a little
/// variance, a narrower one would bias). Cones of 89 degrees and wider: the whole segment.
///
/// With `x(t) = o + t d` in the local frame (an affine map keeps `t`), the cone is
/// `z(t) >= 0` and `z(t)^2 >= cos^2(cutoff) |x(t)|^2`, a quadratic `A t^2 + B t + C >= 0`; the
/// cone is convex, so its part of the segment is one interval whose ends are among `0`, `s` and
/// the quadratic's roots.
pub fn cone_interval(to_local: &Mat4, cutoff: f32, o: Vec3, d: Vec3, len: f32) -> Option<(f32, f32)> {
    let s = len;
    let widened = cutoff * (1.0 + 1e-3) + 1e-4;
    if widened >= 89f32.to_radians() {
        return Some((0.0, s));
    }
    let o = to_local.transform_point3(o);
    let d = to_local.transform_vector3(d);
    let c2 = widened.cos().powi(2);
    let inside = |t: f32| {
        let x = o + t * d;
        // A further relative slack for the roots, which lie on the surface up to rounding.
        x.z >= 0.0 && x.z * x.z >= c2 * x.length_squared() * (1.0 - 1e-4)
    };
    let a = d.z * d.z - c2 * d.length_squared();
    let b = 2.0 * (o.z * d.z - c2 * o.dot(d));
    let c = o.z * o.z - c2 * o.length_squared();
    let mut candidates = [0.0, s, f32::NAN, f32::NAN];
    if a.abs() > 1e-12 * d.length_squared() {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            // The numerically stable pair of roots.
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            candidates[2] = q / a;
            candidates[3] = if q != 0.0 { c / q } else { f32::NAN };
        }
    } else if b != 0.0 {
        candidates[2] = -c / b;
    }
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for t in candidates {
        if t.is_finite() && (0.0..=s).contains(&t) && inside(t) {
            lo = lo.min(t);
            hi = hi.max(t);
        }
    }
    (lo < hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bitmap::{Bitmap, FilterType, WrapMode};
    use haze_core::Sampler;

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

    fn random_spot(s: &mut Sampler) -> (Mat4, f32) {
        let origin = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - 2.0;
        let target = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - 2.0;
        let up = if (target - origin).normalize().y.abs() > 0.9 { Vec3::X } else { Vec3::Y };
        // Mitsuba's lookat frame (local +z towards the target), times a uniform scale, which
        // must not matter.
        let z = (target - origin).normalize();
        let x = up.cross(z).normalize();
        let k = 0.5 + s.next_1d();
        let to_world = Mat4::from_cols(
            (k * x).extend(0.0),
            (k * z.cross(x)).extend(0.0),
            (k * z).extend(0.0),
            origin.extend(1.0),
        );
        let cutoff = (1.0 + 80.0 * s.next_1d()).to_radians();
        (to_world, cutoff)
    }

    /// Every point of a random segment where the spot shines lies in the interval, and the
    /// interval is no longer than the lit part (up to the widening).
    #[test]
    fn cone_interval_covers_the_beam_and_little_else() {
        let mut s = Sampler::from_seed(11);
        let mut crossing = 0;
        for _ in 0..1000 {
            let (to_world, cutoff) = random_spot(&mut s);
            let to_local = to_world.inverse();
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 6.0 - 3.0;
            let d = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5).normalize();
            let len = 0.5 + 5.0 * s.next_1d();
            let at = |t: f32| o + t * d;
            let interval = cone_interval(&to_local, cutoff, o, d, len);
            let n = 2000;
            let mut lit = 0;
            for k in 0..n {
                let t = (k as f32 + 0.5) / n as f32 * len;
                let local = to_local.transform_point3(at(t));
                if local.length() > 1e-3
                    && Emitter::spot_falloff(cutoff, 0.5 * cutoff, local.normalize()) > 0.0
                {
                    lit += 1;
                    let (a, b) = interval.unwrap_or_else(|| panic!("lit at {t} but no interval"));
                    assert!(t >= a && t <= b, "lit at {t} outside [{a}, {b}]");
                }
            }
            if let Some((a, b)) = interval {
                // The ends lie on the slightly widened cone (the interval is convex's hull).
                for t in [a, b] {
                    let local = to_local.transform_point3(at(t));
                    let angle = (local.z / local.length()).clamp(-1.0, 1.0).acos();
                    assert!(
                        local.length() < 1e-4 || angle <= cutoff * 1.01 + 1e-3,
                        "end {t}: {angle} vs {cutoff}"
                    );
                }
                crossing += (lit > 0) as u32;
            }
        }
        assert!(crossing > 100, "only {crossing} segments cross a beam");
    }
}
