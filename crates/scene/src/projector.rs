//! Mitsuba 3's `projector` emitter: a pinhole that projects an image (`irradiance`) into the
//! scene, the reciprocal of the `perspective` camera (same direction-to-image mapping).

use crate::texture::Texture;
use glam::{Mat4, Vec2, Vec3};
use haze_core::{Rgb, PI};

/// A projector at the origin of `to_world`, looking down its local `+z`. Its image plane lies
/// at local `z = 1`, spanning `[-tan_x, tan_x] x [-tan_y, tan_y]`; `irradiance` is the
/// irradiance that image delivers to that plane (times `scale`), so a constant image lights a
/// plane facing the projector uniformly.
#[derive(Clone, Debug, PartialEq)]
pub struct Projector {
    pub to_world: Mat4,
    /// The inverse of `to_world`.
    pub to_local: Mat4,
    pub irradiance: Texture,
    pub scale: f32,
    /// `tan(fov_x / 2)` and `tan_x / aspect` (the image's width over its height).
    pub tan_x: f32,
    pub tan_y: f32,
}

impl Projector {
    /// `fov_x_deg`: the horizontal field of view; `aspect`: the image's width over its height
    /// (1 for a constant irradiance, as Mitsuba's one-texel "resolution").
    pub fn new(to_world: Mat4, irradiance: Texture, scale: f32, fov_x_deg: f32, aspect: f32) -> Self {
        let tan_x: f32 = crate::camera::half_slope(fov_x_deg);
        Projector { to_world, to_local: to_world.inverse(), irradiance, scale, tan_x, tan_y: tan_x / aspect }
    }

    /// The projector's position.
    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }

    /// The image coordinates of the local direction `d` (any length): Mitsuba 3's perspective
    /// mapping, `uv = (1/2 - x / (2 z tan_x), 1/2 - y / (2 z tan_y))` (checked against Mitsuba
    /// 3.9.1's `sample_direction`); `None` behind the projector or outside the image.
    pub fn uv(&self, d: Vec3) -> Option<Vec2> {
        if d.z <= 0.0 {
            return None;
        }
        let uv = Vec2::new(0.5 - d.x / (2.0 * d.z * self.tan_x), 0.5 - d.y / (2.0 * d.z * self.tan_y));
        (uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0).then_some(uv)
    }

    /// The radiant intensity (W/sr) towards the unit local direction `d`:
    /// `pi scale E(uv) / cos^3(theta)`, the intensity that gives irradiance `pi scale E` at the
    /// image plane `z = 1` (a solid angle there is `cos^3(theta)` times the plane's area).
    /// Mitsuba 3's `projector.cpp` `sample_direction` returns the same divided by `dist^2`,
    /// written `pi scale E / (z^2 cos(theta))`. Zero outside the image.
    pub fn intensity(&self, d: Vec3) -> Rgb {
        match self.uv(d) {
            Some(uv) => self.irradiance.eval(uv) * (PI * self.scale / (d.z * d.z * d.z)),
            None => Rgb::ZERO,
        }
    }

    /// The mean over the RGB channels of the emitted power: the intensity integrated over the
    /// image's solid angle, `pi scale mean(E) (2 tan_x) (2 tan_y)` (Mitsuba's `sample_ray`
    /// weight `pi sensor_area` over the texture's pdf). For a bitmap `mean(E)` is its mean.
    pub fn power(&self) -> f32 {
        PI * self.scale * self.irradiance.mean().mean() * 4.0 * self.tan_x * self.tan_y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1 (`scalar_rgb`): a projector at the origin looking down `+z`, fov 90,
    /// constant irradiance 1, scale 2: `sample_direction` from `(0.2, 0.1, 1)` gives uv
    /// `(0.4, 0.4)` for a square image and the value 6.43835 (`pi 2 sqrt(1.05)`, the intensity
    /// over the squared distance 1.05).
    #[test]
    fn matches_mitsuba_sample_direction() {
        let p = Projector::new(Mat4::IDENTITY, Rgb::ONE.into(), 2.0, 90.0, 1.0);
        let x = Vec3::new(0.2, 0.1, 1.0);
        let uv = p.uv(x).unwrap();
        assert!((uv - Vec2::new(0.4, 0.45)).length() < 1e-6, "{uv}");
        let value = p.intensity(x.normalize())[0] / x.length_squared();
        assert!((value - 6.43835).abs() < 1e-4, "{value}");
        // Mitsuba's uv for an image 1.4925 times as wide as high (its `flower.bmp`).
        let wide = Projector::new(Mat4::IDENTITY, Rgb::ONE.into(), 1.0, 90.0, 1.4925);
        assert!((wide.uv(x).unwrap().y - 0.425373).abs() < 1e-4);
        assert!(p.uv(Vec3::new(1.1, 0.0, 1.0)).is_none() && p.uv(-x).is_none());
    }

    /// The power is the intensity integrated over the sphere (quadrature over directions).
    #[test]
    fn power_is_the_integrated_intensity() {
        let p = Projector::new(Mat4::IDENTITY, Rgb::new(0.5, 1.0, 2.0).into(), 1.5, 60.0, 1.3);
        let n = 400;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                // Uniform on the upper hemisphere in (cos theta, phi): dw = dcos dphi.
                let c = (i as f32 + 0.5) / n as f32;
                let phi = 2.0 * PI * (j as f32 + 0.5) / n as f32;
                let s = (1.0 - c * c).sqrt();
                let d = Vec3::new(s * phi.cos(), s * phi.sin(), c);
                sum += p.intensity(d).mean() as f64;
            }
        }
        let integral = sum * 2.0 * std::f64::consts::PI / (n * n) as f64;
        assert!((integral / p.power() as f64 - 1.0).abs() < 0.01, "{integral} vs {}", p.power());
    }
}
