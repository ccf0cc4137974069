//! Rays with a parametric extent.

use glam::Vec3;

/// A ray `o + t d` for `t` in `[0, t_max)`. `d` is unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub t_max: f32,
}

impl Ray {
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray { o, d, t_max: f32::INFINITY }
    }
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Offset a point leaving a surface with geometric normal `n` in direction `d`, so that the
/// next intersection test does not find the surface it starts on. The offset is relative to the
/// point's magnitude because f32 spacing grows with it.
pub fn offset_origin(p: Vec3, n: Vec3, d: Vec3) -> Vec3 {
    let scale = crate::RAY_EPSILON * (1.0 + p.abs().max_element());
    if n.dot(d) >= 0.0 {
        p + n * scale
    } else {
        p - n * scale
    }
}
