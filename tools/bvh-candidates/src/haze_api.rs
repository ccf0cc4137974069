//! The usage snippet recommended for haze, compiled and tested here (`cargo test --release`).
//! `glam030` stands in for haze's glam 0.30; obvhs 0.4.0 is built on glam 0.34 (`glam` here).
#![allow(dead_code)]

use glam::Vec3A; // glam 0.34 = the glam obvhs 0.4.0 uses
use glam030 as hg; // haze's glam 0.30
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle,
};

#[inline]
fn v3a(v: hg::Vec3) -> Vec3A {
    Vec3A::from_array(v.to_array()) // different glam versions = different types: copy
}

pub struct MeshBvh {
    bvh: CwBvh,
    tris: Vec<Triangle>, // stored in BVH leaf order (bvh.primitive_indices)
}

impl MeshBvh {
    pub fn new(tris: &[[hg::Vec3; 3]]) -> Self {
        let t: Vec<Triangle> =
            tris.iter().map(|t| Triangle { v0: v3a(t[0]), v1: v3a(t[1]), v2: v3a(t[2]) }).collect();
        // feature "parallel": runs on the current rayon pool
        let bvh = build_cwbvh_from_tris(&t, BvhBuildParams::medium_build(), &mut Default::default());
        let tris = bvh.primitive_indices.iter().map(|&i| t[i as usize]).collect();
        Self { bvh, tris }
    }

    /// Closest hit in [tmin, tmax): (t, original triangle index, (b1, b2)) with
    /// P = (1 - b1 - b2) * v0 + b1 * v1 + b2 * v2. t is in units of |d| (d need not be normalized).
    pub fn closest_hit(&self, o: hg::Vec3, d: hg::Vec3, tmin: f32, tmax: f32) -> Option<(f32, u32, hg::Vec2)> {
        let ray = Ray::new(v3a(o), v3a(d), tmin, tmax);
        let mut hit = RayHit::none();
        if !self.bvh.ray_traverse(ray, &mut hit, |r, i| self.tris[i].intersect(r)) {
            return None;
        }
        let i = hit.primitive_id as usize; // index into BVH order
        let tri = &self.tris[i];
        // Triangle::compute_barycentric (0.4.0) normalizes the normal => wrongly scaled; do it here:
        let (e1, e2) = (tri.v0 - tri.v1, tri.v2 - tri.v0);
        let r = ray.direction.cross(tri.v0 - ray.origin);
        let inv = 1.0 / e1.cross(e2).dot(ray.direction);
        Some((hit.t, self.bvh.primitive_indices[i], hg::Vec2::new(r.dot(e2) * inv, r.dot(e1) * inv)))
    }

    /// Any hit in [tmin, tmax) (early exit).
    pub fn occluded(&self, o: hg::Vec3, d: hg::Vec3, tmin: f32, tmax: f32) -> bool {
        let ray = Ray::new(v3a(o), v3a(d), tmin, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, i| self.tris[i].intersect(r)) // note: returns true on MISS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hv(v: glam::Vec3) -> hg::Vec3 {
        hg::Vec3::from_array(v.to_array())
    }

    #[test]
    fn snippet_agrees_with_brute_force_and_barycentrics_reconstruct() {
        let (tris, _) = crate::gen_mesh(20_000, 7);
        let htris: Vec<[hg::Vec3; 3]> = tris.iter().map(|t| [hv(t[0]), hv(t[1]), hv(t[2])]).collect();
        let m = MeshBvh::new(&htris);
        let (lo, hi) = crate::bounds(&tris);
        let rays = crate::random_rays(2000, lo, hi, 3);
        let mut hits = 0;
        for r in &rays {
            let bf = crate::brute_f64(&tris, r);
            let got = m.closest_hit(hv(r.o), hv(r.d), 0.0, f32::INFINITY);
            match got {
                Some((t, prim, b)) => {
                    hits += 1;
                    assert!(!crate::t_mismatch(t, bf as f32), "t {t} vs brute {bf}");
                    let tr = &htris[prim as usize];
                    let p = hv(r.o) + hv(r.d) * t;
                    let q = tr[0] * (1.0 - b.x - b.y) + tr[1] * b.x + tr[2] * b.y;
                    assert!((p - q).length() < 1e-4, "barycentrics off: {}", (p - q).length());
                    // occlusion consistent with closest hit, including tmax/tmin clipping
                    assert!(m.occluded(hv(r.o), hv(r.d), 0.0, t * 1.001));
                    assert!(!m.occluded(hv(r.o), hv(r.d), 0.0, t * 0.999));
                    assert!(m.closest_hit(hv(r.o), hv(r.d), t * 1.001, f32::INFINITY).map_or(true, |h| h.0 > t));
                }
                None => assert!(bf.is_infinite()),
            }
        }
        assert!(hits > 500);
    }

    #[test]
    fn single_triangle() {
        let m = MeshBvh::new(&[[hg::Vec3::ZERO, hg::Vec3::X, hg::Vec3::Y]]);
        let h = m.closest_hit(hg::vec3(0.25, 0.25, 1.0), hg::vec3(0.0, 0.0, -2.0), 0.0, f32::INFINITY);
        let (t, prim, b) = h.unwrap();
        assert_eq!(prim, 0);
        assert!((t - 0.5).abs() < 1e-6); // t in units of |d| = 2
        assert!((b - hg::vec2(0.25, 0.25)).length() < 1e-6);
        // back face is hit too (no culling)
        assert!(m.closest_hit(hg::vec3(0.25, 0.25, -1.0), hg::vec3(0.0, 0.0, 1.0), 0.0, f32::INFINITY).is_some());
    }

    #[test]
    fn empty_mesh() {
        // obvhs 0.4.0 builds an empty CwBvh without panicking and traversal reports a miss
        let m = MeshBvh::new(&[]);
        assert!(m.closest_hit(hg::Vec3::ZERO, hg::Vec3::X, 0.0, f32::INFINITY).is_none());
        assert!(!m.occluded(hg::Vec3::ZERO, hg::Vec3::X, 0.0, f32::INFINITY));
    }
}
