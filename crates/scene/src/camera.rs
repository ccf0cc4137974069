//! Perspective pinhole camera (Mitsuba 3 plugin `perspective`).

use crate::medium::MediumId;
use glam::{Mat4, Vec2, Vec3};
use haze_core::Ray;

/// Pinhole camera. Camera space follows Mitsuba: looking down `+z`, `+y` up, `+x` to the
/// *left* (so `lookat` builds `to_world` with columns `(left, up, dir, origin)`). Film pixel
/// `(0, 0)` is the top-left corner of the image.
#[derive(Clone, Debug)]
pub struct Camera {
    pub to_world: Mat4,
    /// Full horizontal field of view in degrees (the loader resolves `fov_axis` to this).
    pub fov_x_deg: f32,
    pub near_clip: f32,
    pub far_clip: f32,
    /// Medium the camera sits in (`<ref id=".."/>` inside the sensor).
    pub medium: Option<MediumId>,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// Primary ray through the film position `p` in pixel units (`[0, width) x [0, height)`).
    /// The ray starts at the near clip plane and ends at the far clip plane, as in Mitsuba.
    pub fn generate_ray(&self, p: Vec2) -> Ray {
        let tan_x = (0.5 * self.fov_x_deg.to_radians()).tan();
        let tan_y = tan_x * self.height as f32 / self.width as f32;
        let sx = 1.0 - 2.0 * p.x / self.width as f32;
        let sy = 1.0 - 2.0 * p.y / self.height as f32;
        let local = Vec3::new(sx * tan_x, sy * tan_y, 1.0);
        let inv_len = 1.0 / local.length();
        let d_local = local * inv_len;
        let o = self.to_world.transform_point3(Vec3::ZERO);
        let d = self.to_world.transform_vector3(d_local).normalize();
        // Near/far clips are distances along the camera's z axis.
        let t_near = self.near_clip / d_local.z;
        let t_far = self.far_clip / d_local.z;
        Ray { o: o + d * t_near, d, t_max: t_far - t_near }
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }
}
