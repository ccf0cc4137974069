//! Ray intersection acceleration over all shapes.
//! TEMPORARY brute force until the BVH crate is chosen (see tools/bvh-candidates).

use crate::scene::SurfaceInteraction;
use crate::shape::{Geometry, Shape};
use glam::{Vec2, Vec3};
use haze_core::Ray;

pub struct Accel {
    lo: Vec3,
    hi: Vec3,
}

impl Accel {
    pub fn build(shapes: &[Shape]) -> Self {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for s in shapes {
            if let Geometry::Mesh(m) = &s.geometry {
                for p in &m.positions {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
        }
        Accel { lo, hi }
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    pub fn intersect(&self, shapes: &[Shape], ray: &Ray) -> Option<SurfaceInteraction> {
        let mut best: Option<SurfaceInteraction> = None;
        let mut t_max = ray.t_max;
        for (si, s) in shapes.iter().enumerate() {
            if let Geometry::Mesh(m) = &s.geometry {
                for i in 0..m.indices.len() {
                    let [p0, p1, p2] = m.vertices(i);
                    if let Some((t, b1, b2)) = intersect_triangle(ray, p0, p1, p2, t_max) {
                        t_max = t;
                        let n = m.face_normal(i);
                        best = Some(SurfaceInteraction {
                            t,
                            p: ray.at(t),
                            n,
                            ns: n,
                            uv: Vec2::new(b1, b2),
                            shape: si as u32,
                            prim: i as u32,
                        });
                    }
                }
            }
        }
        best
    }

    pub fn occluded(&self, shapes: &[Shape], ray: &Ray) -> bool {
        self.intersect(shapes, ray).is_some()
    }
}

/// Möller-Trumbore ray-triangle test; returns `(t, b1, b2)`.
fn intersect_triangle(
    ray: &Ray,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = ray.d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.o - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = ray.d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t > 0.0 && t < t_max).then_some((t, u, v))
}
