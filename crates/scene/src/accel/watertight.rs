//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)). Rays never slip between triangles that share an edge, which
//! matters here: a ray that leaks through a closed null boundary would lose track of which
//! medium it is in.

use glam::{Vec3A, Vec4, Vec4Swizzles};

/// A triangle's vertices transposed, `[xs, ys, zs]` with lane `i` from vertex `i` (lane 3
/// unused): the layout [`WatertightRay::intersect_soa`] shears all three vertices in at once.
#[derive(Clone, Copy, Debug)]
pub struct TriSoa(pub [Vec4; 3]);

impl TriSoa {
    pub fn new(v0: Vec3A, v1: Vec3A, v2: Vec3A) -> Self {
        TriSoa([
            Vec4::new(v0.x, v1.x, v2.x, 0.0),
            Vec4::new(v0.y, v1.y, v2.y, 0.0),
            Vec4::new(v0.z, v1.z, v2.z, 0.0),
        ])
    }

    /// Vertex `i` (0, 1 or 2).
    #[inline]
    pub fn vertex(&self, i: usize) -> Vec3A {
        let [x, y, z] = self.0;
        Vec3A::new(x[i], y[i], z[i])
    }
}

/// Up to four triangles transposed across SSE lanes, `v[axis][vertex]` with lane `i` from
/// triangle `i`: the layout [`WatertightRay::intersect_packet`] tests four triangles in at once.
/// Lanes past `count` hold copies of the first triangle and are masked out.
#[derive(Clone, Copy, Debug)]
pub struct TriPacket {
    v: [[Vec4; 3]; 3],
    count: u32,
}

impl TriPacket {
    /// `tris` holds 1 to 4 triangles.
    pub fn new(tris: &[TriSoa]) -> Self {
        assert!((1..=4).contains(&tris.len()), "a packet holds 1 to 4 triangles");
        let lane = |i: usize| &tris[i.min(tris.len() - 1)];
        let v = std::array::from_fn(|axis| {
            std::array::from_fn(|vertex| {
                Vec4::new(
                    lane(0).0[axis][vertex],
                    lane(1).0[axis][vertex],
                    lane(2).0[axis][vertex],
                    lane(3).0[axis][vertex],
                )
            })
        });
        TriPacket { v, count: tris.len() as u32 }
    }

    pub fn count(&self) -> u32 {
        self.count
    }

    /// Triangle `lane` in the layout of [`WatertightRay::intersect_soa`].
    pub fn triangle(&self, lane: usize) -> TriSoa {
        TriSoa(self.v.map(|axis| Vec4::new(axis[0][lane], axis[1][lane], axis[2][lane], 0.0)))
    }
}

/// The hits of [`WatertightRay::intersect_packet`]: bit `i` of `mask` set when lane `i` hit,
/// with its distance in `t[i]` and its barycentrics from [`Self::barycentrics`].
#[derive(Clone, Copy, Debug)]
pub struct PacketHits {
    pub mask: u32,
    pub t: [f32; 4],
    /// The scaled barycentrics `v`, `w` and their denominator `det`: divided only for the hit
    /// that is kept (two divisions fewer per tested leaf).
    v: [f32; 4],
    w: [f32; 4],
    det: [f32; 4],
}

impl PacketHits {
    /// `(b1, b2)` of lane `i`, the weights of vertices 1 and 2.
    #[inline]
    pub fn barycentrics(&self, i: usize) -> (f32, f32) {
        (self.v[i] / self.det[i], self.w[i] / self.det[i])
    }

    /// The hit lane with the smallest `t` (the highest lane among equals), if any.
    #[inline]
    pub fn closest(&self) -> Option<usize> {
        let mut best: Option<usize> = None;
        let mut m = self.mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            if best.is_none_or(|b| self.t[i] <= self.t[b]) {
                best = Some(i);
            }
        }
        best
    }
}

/// A ray prepared for the test: the axis permutation that makes the largest direction component
/// `z`, and the shear that maps the direction onto `+z`.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    o: Vec3A,
    k: [u8; 3],
    shear: Vec3A,
    /// `o` in the permuted axes `(o[kx], o[ky], o[kz])`, for the transposed test. (Kept small:
    /// the ray is built lazily inside the traversal closure, and a larger struct measurably
    /// slowed every traversal.)
    o_perm: [f32; 3],
}

impl WatertightRay {
    #[inline]
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
        WatertightRay {
            o,
            k: [kx as u8, ky as u8, kz as u8],
            shear: Vec3A::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
            o_perm: [o[kx], o[ky], o[kz]],
        }
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
        let [kx, ky, kz] = self.k.map(usize::from);
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

    /// [`Self::intersect`] on a transposed triangle: the same f32 operations in the same order
    /// (so bit for bit the same results), the three vertices sheared and the three edge
    /// functions computed in SSE lanes instead of one by one through runtime component indices.
    #[inline]
    pub fn intersect_soa(&self, tri: &TriSoa, t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k.map(usize::from);
        let s = self.shear;
        let [ox, oy, oz] = self.o_perm.map(Vec4::splat);
        // Lanes (a, b, c) of the vertices relative to the origin, in ray-permuted axes.
        let pz = tri.0[kz] - oz;
        let px = tri.0[kx] - ox;
        let py = tri.0[ky] - oy;
        let xs = px - Vec4::splat(s.x) * pz;
        let ys = py - Vec4::splat(s.y) * pz;
        // (u, v, w) = (cx by - cy bx, ax cy - ay cx, bx ay - by ax).
        let uvw = xs.zxyw() * ys.yzxw() - ys.zxyw() * xs.yzxw();
        let (mut u, mut v, mut w) = (uvw.x, uvw.y, uvw.z);
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, bx, cx) = (xs.x as f64, xs.y as f64, xs.z as f64);
            let (ay, by, cy) = (ys.x as f64, ys.y as f64, ys.z as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t = s.z * (u * pz.x + v * pz.y + w * pz.z) / det;
        (t >= t_min && t < t_max).then(|| (t, v / det, w / det))
    }

    /// [`Self::intersect_soa`] on the triangles of a packet at once: the same f32 operations per
    /// lane, so bit for bit the same hits; lanes with an edge function exactly zero are
    /// recomputed by the scalar test (its f64 path). One branch on the lane mask replaces the
    /// per-triangle inside/outside branch, which the CPU cannot predict. Always inlined: as a
    /// call, its result went through memory and cost ~10% of hg-box's render time.
    #[inline(always)]
    pub fn intersect_packet(&self, p: &TriPacket, t_min: f32, t_max: f32) -> PacketHits {
        let [kx, ky, kz] = self.k.map(usize::from);
        let (sx, sy, sz) = (Vec4::splat(self.shear.x), Vec4::splat(self.shear.y), Vec4::splat(self.shear.z));
        let [ox, oy, oz] = self.o_perm.map(Vec4::splat);
        // Vertices a, b, c relative to the origin, sheared, each over the four triangles.
        let [az, bz, cz] = p.v[kz].map(|v| v - oz);
        let [ax, bx, cx] = [0, 1, 2].map(|j| (p.v[kx][j] - ox) - sx * [az, bz, cz][j]);
        let [ay, by, cy] = [0, 1, 2].map(|j| (p.v[ky][j] - oy) - sy * [az, bz, cz][j]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let lanes = (1u32 << p.count) - 1;
        let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        let edge = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).bitmask() & lanes;
        let mut mask = !(neg & pos).bitmask() & lanes & !edge;
        let mut hits = PacketHits { mask: 0, t: [0.0; 4], v: [0.0; 4], w: [0.0; 4], det: [1.0; 4] };
        if mask != 0 {
            let det = u + v + w;
            let t = sz * (u * az + v * bz + w * cz) / det;
            let ok = det.cmpne(zero) & t.cmpge(Vec4::splat(t_min)) & t.cmplt(Vec4::splat(t_max));
            mask &= ok.bitmask();
            (hits.t, hits.v, hits.w, hits.det) = (t.to_array(), v.to_array(), w.to_array(), det.to_array());
        }
        let mut e = edge;
        while e != 0 {
            let i = e.trailing_zeros() as usize;
            e &= e - 1;
            if let Some((t, b1, b2)) = self.intersect_soa(&p.triangle(i), t_min, t_max) {
                mask |= 1 << i;
                // Already divided: a denominator of 1 keeps them bit for bit.
                (hits.t[i], hits.v[i], hits.w[i], hits.det[i]) = (t, b1, b2, 1.0);
            }
        }
        hits.mask = mask;
        hits
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

    /// The transposed test gives exactly the scalar test's results on random triangles and rays,
    /// edge cases included (vertices on a coarse grid make many edge functions exactly zero).
    #[test]
    fn transposed_test_is_bit_identical() {
        let mut s = haze_core::Sampler::from_seed(3);
        let g = |s: &mut haze_core::Sampler| (s.next_1d() * 8.0).floor() * 0.25 - 1.0;
        for i in 0..200_000 {
            let mut p = || Vec3A::new(g(&mut s), g(&mut s), g(&mut s));
            let (v0, v1, v2, o) = (p(), p(), p(), p() * 2.0);
            let d = Vec3A::new(g(&mut s), g(&mut s), g(&mut s) + if i % 2 == 0 { 0.01 } else { 0.0 });
            if d == Vec3A::ZERO {
                continue;
            }
            let r = WatertightRay::new(o, d.normalize());
            let a = r.intersect(v0, v1, v2, 0.0, f32::INFINITY);
            let soa = TriSoa::new(v0, v1, v2);
            let b = r.intersect_soa(&soa, 0.0, f32::INFINITY);
            let bits = |h: Option<(f32, f32, f32)>| h.map(|h| [h.0, h.1, h.2].map(f32::to_bits));
            assert_eq!(bits(a), bits(b));
        }
    }

    /// Packets give exactly the scalar test's hits, lane by lane, on the same grid-aligned
    /// triangles (exact zeros included), for packets of 1 to 4 triangles.
    #[test]
    fn packet_test_is_bit_identical() {
        let mut s = haze_core::Sampler::from_seed(4);
        let g = |s: &mut haze_core::Sampler| (s.next_1d() * 8.0).floor() * 0.25 - 1.0;
        let mut hits = 0;
        for i in 0..50_000 {
            let mut p = || Vec3A::new(g(&mut s), g(&mut s), g(&mut s));
            let tris: Vec<TriSoa> = (0..1 + i % 4).map(|_| TriSoa::new(p(), p(), p())).collect();
            let o = p() * 2.0;
            // Grid directions (exact zeros) and, every third case, a direction at a vertex of one
            // of the triangles (hits).
            let d = match i % 3 {
                0 => Vec3A::new(g(&mut s), g(&mut s), g(&mut s) + 0.01),
                1 => Vec3A::new(g(&mut s), g(&mut s), g(&mut s)),
                _ => tris[i % tris.len()].vertex(i % 3) - o,
            };
            if d == Vec3A::ZERO {
                continue;
            }
            let r = WatertightRay::new(o, d.normalize());
            let (t_min, t_max) = if i % 5 < 3 { (0.0, f32::INFINITY) } else { (0.1, 1.5) };
            let packet = TriPacket::new(&tris);
            let got = r.intersect_packet(&packet, t_min, t_max);
            assert_eq!(got.mask >> tris.len(), 0, "padding lanes must not hit");
            for (lane, tri) in tris.iter().enumerate() {
                let want = r.intersect_soa(tri, t_min, t_max).map(|h| [h.0, h.1, h.2].map(f32::to_bits));
                let have = (got.mask & (1 << lane) != 0).then(|| {
                    let (b1, b2) = got.barycentrics(lane);
                    [got.t[lane], b1, b2].map(f32::to_bits)
                });
                assert_eq!(want, have, "case {i}, lane {lane}");
                hits += want.is_some() as u32;
            }
        }
        assert!(hits > 10_000, "{hits} hits: the test exercises too few");
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
