//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)). Rays never slip between triangles that share an edge, which
//! matters here: a ray that leaks through a closed null boundary would lose track of which
//! medium it is in.

use glam::Vec3A;

/// A ray prepared for the test: the axis permutation that makes the largest direction component
/// `z`, and the shear that maps the direction onto `+z`.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    o: Vec3A,
    k: [usize; 3],
    shear: Vec3A,
}

impl WatertightRay {
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding of the sheared triangle: swap x and y when the ray points down z.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        WatertightRay { o, k: [kx, ky, kz], shear: Vec3A::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]) }
    }

    /// Returns `(t, b1, b2)` for a hit with `t_min <= t < t_max` (barycentric weights of `v1`,
    /// `v2`), `None` otherwise. Edge cases (a scaled barycentric exactly zero) are recomputed in
    /// f64, as the paper prescribes, so that shared edges are decided consistently.
    #[inline]
    pub fn intersect(
        &self,
        v0: Vec3A,
        v1: Vec3A,
        v2: Vec3A,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let s = self.shear;
        let (a, b, c) = (v0 - self.o, v1 - self.o, v2 - self.o);
        let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
        let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
        let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t = s.z * (u * a[kz] + v * b[kz] + w * c[kz]) / det;
        (t >= t_min && t < t_max).then(|| (t, v / det, w / det))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_and_misses_outside() {
        let (v0, v1, v2) = (Vec3A::new(0.0, 0.0, 1.0), Vec3A::new(1.0, 0.0, 1.0), Vec3A::new(0.0, 1.0, 1.0));
        let r = WatertightRay::new(Vec3A::new(0.25, 0.25, 0.0), Vec3A::Z);
        let (t, b1, b2) = r.intersect(v0, v1, v2, 0.0, 10.0).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (b1 - 0.25).abs() < 1e-6 && (b2 - 0.25).abs() < 1e-6);
        let r = WatertightRay::new(Vec3A::new(0.75, 0.75, 0.0), Vec3A::Z);
        assert!(r.intersect(v0, v1, v2, 0.0, 10.0).is_none());
        let r = WatertightRay::new(Vec3A::new(0.25, 0.25, 2.0), -Vec3A::Z);
        assert!((r.intersect(v0, v1, v2, 0.0, 10.0).unwrap().0 - 1.0).abs() < 1e-6);
    }

    /// A ray through the shared edge of two triangles hits at least one of them.
    #[test]
    fn shared_edges_do_not_leak() {
        let a = Vec3A::new(0.0, 0.0, 1.0);
        let b = Vec3A::new(1.0, 1.0, 1.0);
        let c = Vec3A::new(1.0, 0.0, 1.0);
        let d = Vec3A::new(0.0, 1.0, 1.0);
        for i in 0..1000 {
            let x = 0.01 + 0.98 * i as f32 / 1000.0;
            let r = WatertightRay::new(Vec3A::new(x, x, 0.0), Vec3A::new(0.001, -0.0007, 1.0).normalize());
            let hit = r.intersect(a, c, b, 0.0, 10.0).is_some() || r.intersect(a, b, d, 0.0, 10.0).is_some();
            assert!(hit, "leak at x = {x}");
        }
    }
}
