//! A straight piece of a ray: camera segments and VRL segments share it.

use glam::Vec3;

/// The points `o + t d` for `t` in `[0, len]`.
///
/// `d` must be a unit vector and `len >= 0` (a zero-length segment is allowed and contributes
/// nothing). Parameters along the segment (`t`, `u`, `v` in the estimators) are distances from `o`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    pub len: f32,
}

impl Segment {
    pub const fn new(o: Vec3, d: Vec3, len: f32) -> Self {
        Segment { o, d, len }
    }

    /// The segment from `a` to `b`. When `a == b` it has length zero and direction `+x`.
    pub fn from_points(a: Vec3, b: Vec3) -> Self {
        let len = (b - a).length();
        Segment { o: a, d: (b - a).normalize_or(Vec3::X), len }
    }

    /// The point at distance `t` from the start.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    #[inline]
    pub fn end(&self) -> Vec3 {
        self.at(self.len)
    }
}
