//! Ray intersection for the analytic shapes (`sphere`, `disk`).

use glam::{Mat4, Vec2, Vec3};
use haze_core::Ray;

/// Closest `t` in `(t_min_rel, t_max)` where the ray meets the sphere. Solved in f64: the
/// quadratic loses precision for rays that start far from small spheres.
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: f32) -> Option<f32> {
    let o = (ray.o - center).as_dvec3();
    let d = ray.d.as_dvec3();
    let r = radius as f64;
    let b = o.dot(d);
    let c = o.length_squared() - r * r;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    // Numerically stable roots (pbrt-v4, "Ray Tracing Gems" ch. 7).
    let q = if b > 0.0 { -b - sq } else { -b + sq };
    let (mut t0, mut t1) = (c / q, q);
    if q == 0.0 {
        t0 = -b;
        t1 = -b;
    }
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let eps = 1e-6 * (1.0 + o.length());
    for t in [t0, t1] {
        if t > eps && t < ray.t_max as f64 {
            return Some(t as f32);
        }
    }
    None
}

/// haze's `uv` of the sphere point with unit normal `n` (as flipped by `flip_normals`):
/// `u = atan2(n_z, n_x) / 2pi + 1/2`, `v = acos(n_y) / pi` (not Mitsuba's sphere mapping).
#[inline]
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let phi = n.z.atan2(n.x);
    Vec2::new(phi * 0.5 * haze_core::INV_PI + 0.5, n.y.clamp(-1.0, 1.0).acos() * haze_core::INV_PI)
}

/// haze's `uv` of the point `local` of the unit disk: `u = r`, `v = atan2(y, x) / 2pi + 1/2`.
#[inline]
pub fn disk_uv(local: Vec2) -> Vec2 {
    Vec2::new(local.length(), local.y.atan2(local.x) * 0.5 * haze_core::INV_PI + 0.5)
}

/// Intersection with the disk `to_world(unit disk in z = 0)`; returns `t` and the local
/// position (for `uv`).
pub fn intersect_disk(ray: &Ray, to_world: &Mat4, inv: &Mat4) -> Option<(f32, Vec2)> {
    let o = inv.transform_point3(ray.o);
    let d = inv.transform_vector3(ray.d);
    if d.z.abs() < 1e-12 {
        return None;
    }
    let t = -o.z / d.z;
    let p = o + d * t;
    if !(t > 0.0 && t < ray.t_max) || p.x * p.x + p.y * p.y > 1.0 {
        return None;
    }
    // t is in world units because the direction was transformed, not renormalised.
    let _ = to_world;
    Some((t, Vec2::new(p.x, p.y)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_hits_from_outside_and_inside() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!((intersect_sphere(&r, Vec3::ZERO, 1.0).unwrap() - 4.0).abs() < 1e-5);
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!((intersect_sphere(&r, Vec3::ZERO, 2.0).unwrap() - 2.0).abs() < 1e-5);
        let r = Ray::new(Vec3::new(0.0, 3.0, -5.0), Vec3::Z);
        assert!(intersect_sphere(&r, Vec3::ZERO, 1.0).is_none());
    }

    #[test]
    fn disk_hit_respects_radius_and_scale() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::IDENTITY,
            Vec3::new(0.0, 0.0, 1.0),
        );
        let inv = m.inverse();
        let r = Ray::new(Vec3::new(1.5, 0.0, -1.0), Vec3::Z);
        let (t, _) = intersect_disk(&r, &m, &inv).unwrap();
        assert!((t - 2.0).abs() < 1e-5);
        let r = Ray::new(Vec3::new(2.5, 0.0, -1.0), Vec3::Z);
        assert!(intersect_disk(&r, &m, &inv).is_none());
    }
}
