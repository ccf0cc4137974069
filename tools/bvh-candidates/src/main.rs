//! bvh-candidates: measure BVH / ray-triangle crates for haze on a procedural ~1M-triangle mesh.
//!
//! cargo run --release -- [--tris N] [--rays N] [--brute N] [--reps N]
//!
//! Candidates:
//!   * obvhs 0.4 CwBvh (compressed wide BVH8, PLOC build, `medium_build` preset)
//!   * obvhs 0.4 Bvh2  (binary BVH, PLOC build, `medium_build` preset)
//!   * bvh 0.13 (svenstaro; binned-SAH build; the crate has no closest-hit query, so
//!     closest-hit / occlusion use a small hand-written stack traversal over `bvh.nodes`,
//!     plus the crate's own `traverse_iterator` on a subset of rays for reference)
//!   * parry3d 0.31 TriMesh (dimforge; its own BVH, `cast_local_ray_and_get_normal`,
//!     `intersects_local_ray`)
//!
//! Correctness: every candidate's closest-hit t is compared with obvhs-CwBvh on all rays and
//! with a brute-force f64 reference on a subset of rays (relative tolerance 1e-4).

mod haze_api;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

// ---------------------------------------------------------------------------------------------
// Counting allocator: live-bytes deltas give a memory estimate for each acceleration structure.
// ---------------------------------------------------------------------------------------------
struct Counting;
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            let now = LIVE.fetch_add(l.size(), Relaxed) + l.size();
            PEAK.fetch_max(now, Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) };
        LIVE.fetch_sub(l.size(), Relaxed);
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if !q.is_null() {
            if new >= l.size() {
                let now = LIVE.fetch_add(new - l.size(), Relaxed) + (new - l.size());
                PEAK.fetch_max(now, Relaxed);
            } else {
                LIVE.fetch_sub(l.size() - new, Relaxed);
            }
        }
        q
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;
fn live() -> usize {
    LIVE.load(Relaxed)
}
fn mb(b: usize) -> f64 {
    b as f64 / (1024.0 * 1024.0)
}

// ---------------------------------------------------------------------------------------------
// Deterministic RNG (SplitMix64) and procedural mesh
// ---------------------------------------------------------------------------------------------
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f32()
    }
    fn unit_vec(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

type Tri = [Vec3; 3];

/// ~97% of `n`: a finely tessellated, noise-displaced UV sphere (closed surface);
/// the rest: small randomly oriented triangles scattered in and around the sphere.
fn gen_mesh(n: usize, seed: u64) -> (Vec<Tri>, usize) {
    let mut tris = Vec::with_capacity(n);
    // sphere tri count = 2 * nlon * (nlat - 1) with nlon = 2 * nlat  => ~4 nlat^2
    let nlat = (((n as f64) * 0.97 / 4.0).sqrt() as usize).max(3);
    let nlon = 2 * nlat;
    let disp = |theta: f32, phi: f32| -> f32 {
        1.0 + 0.08 * (7.0 * theta).sin() * (5.0 * phi).sin()
            + 0.03 * (23.0 * theta + 1.3).sin() * (17.0 * phi + 0.7).cos()
            + 0.01 * (61.0 * theta).cos() * (47.0 * phi + 2.1).sin()
    };
    let vert = |i: usize, j: usize| -> Vec3 {
        let theta = std::f32::consts::PI * i as f32 / nlat as f32; // 0..pi
        let phi = std::f32::consts::TAU * (j % nlon) as f32 / nlon as f32;
        let r = disp(theta, phi);
        Vec3::new(r * theta.sin() * phi.cos(), r * theta.cos(), r * theta.sin() * phi.sin())
    };
    for i in 0..nlat {
        for j in 0..nlon {
            let (a, b, c, d) = (vert(i, j), vert(i, j + 1), vert(i + 1, j), vert(i + 1, j + 1));
            if i == 0 {
                tris.push([a, d, c]);
            } else if i == nlat - 1 {
                tris.push([a, b, c]);
            } else {
                tris.push([a, b, c]);
                tris.push([b, d, c]);
            }
        }
    }
    let n_sphere = tris.len().min(n);
    let mut rng = Rng(seed);
    while tris.len() < n {
        let c = Vec3::new(rng.range(-1.3, 1.3), rng.range(-1.3, 1.3), rng.range(-1.3, 1.3));
        let s = rng.range(0.005, 0.03);
        tris.push([c + rng.unit_vec() * s, c + rng.unit_vec() * s, c + rng.unit_vec() * s]);
    }
    tris.truncate(n);
    (tris, n_sphere)
}

fn bounds(tris: &[Tri]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in tris {
        for v in t {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    (lo, hi)
}

#[derive(Clone, Copy)]
struct R {
    o: Vec3,
    d: Vec3, // normalized
}

/// Pinhole camera outside the mesh, scanline order (coherent-ish).
fn camera_rays(n: usize) -> Vec<R> {
    let w = (n as f64).sqrt() as usize;
    let h = n.div_ceil(w);
    let eye = Vec3::new(0.4, 0.9, 3.2);
    let fwd = (Vec3::ZERO - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (45f32.to_radians() * 0.5).tan();
    let mut v = Vec::with_capacity(n);
    'o: for y in 0..h {
        for x in 0..w {
            if v.len() == n {
                break 'o;
            }
            let px = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * tan;
            let py = (1.0 - (y as f32 + 0.5) / h as f32 * 2.0) * tan;
            v.push(R { o: eye, d: (fwd + right * px + up * py).normalize() });
        }
    }
    v
}

/// Uniform origins inside the mesh bounding box, uniform directions.
fn random_rays(n: usize, lo: Vec3, hi: Vec3, seed: u64) -> Vec<R> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| R {
            o: Vec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z)),
            d: rng.unit_vec(),
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Plain Möller–Trumbore (no culling), used by the hand-written bvh-0.13 traversal.
// ---------------------------------------------------------------------------------------------
#[inline(always)]
fn mt(t: &Tri, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> f32 {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return f32::INFINITY;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return f32::INFINITY;
    }
    let tt = e2.dot(q) * inv;
    if tt >= tmin && tt <= tmax { tt } else { f32::INFINITY }
}

/// Per-ray precomputation for the watertight ray/triangle test of
/// Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2013.
#[derive(Clone, Copy)]
pub struct WtRay {
    o: Vec3,
    k: [usize; 3],
    s: Vec3,
}
impl WtRay {
    #[inline(always)]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        let a = d.abs();
        let kz = if a.x > a.y { if a.x > a.z { 0 } else { 2 } } else if a.y > a.z { 1 } else { 2 };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self { o, k: [kx, ky, kz], s: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]) }
    }
    /// Returns t (INFINITY on miss) and the barycentric weights of (v1, v2).
    #[inline(always)]
    pub fn intersect(&self, v0: Vec3, v1: Vec3, v2: Vec3, tmin: f32, tmax: f32) -> (f32, f32, f32) {
        let [kx, ky, kz] = self.k;
        let (a, b, c) = (v0 - self.o, v1 - self.o, v2 - self.o);
        let (ax, ay) = (a[kx] - self.s.x * a[kz], a[ky] - self.s.y * a[kz]);
        let (bx, by) = (b[kx] - self.s.x * b[kz], b[ky] - self.s.y * b[kz]);
        let (cx, cy) = (c[kx] - self.s.x * c[kz], c[ky] - self.s.y * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // exact fallback on edges
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return (f32::INFINITY, 0.0, 0.0);
        }
        let det = u + v + w;
        if det == 0.0 {
            return (f32::INFINITY, 0.0, 0.0);
        }
        let t = (u * self.s.z * a[kz] + v * self.s.z * b[kz] + w * self.s.z * c[kz]) / det;
        if t >= tmin && t <= tmax { (t, v / det, w / det) } else { (f32::INFINITY, 0.0, 0.0) }
    }
}

/// f64 brute-force reference.
fn brute_f64(tris: &[Tri], r: &R) -> f64 {
    brute_f64_id(tris, r).0
}
/// (t, triangle index or usize::MAX)
fn brute_f64_id(tris: &[Tri], r: &R) -> (f64, usize) {
    let mut id = usize::MAX;
    let o = r.o.as_dvec3();
    let d = r.d.as_dvec3();
    let mut best = f64::INFINITY;
    for (i, t) in tris.iter().enumerate() {
        let (a, b, c) = (t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3());
        let e1 = b - a;
        let e2 = c - a;
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let tt = e2.dot(q) * inv;
        if tt > 0.0 && tt < best {
            best = tt;
            id = i;
        }
    }
    (best, id)
}

// ---------------------------------------------------------------------------------------------
// Candidate interface
// ---------------------------------------------------------------------------------------------
trait Cand: Sync {
    /// closest hit: (t, original triangle index); t = INFINITY on miss
    fn closest(&self, r: &R, tmax: f32) -> (f32, u32);
    fn occluded(&self, r: &R, tmax: f32) -> bool;
}

// ---- obvhs ----------------------------------------------------------------------------------
mod cand_obvhs {
    use super::*;
    use obvhs::{
        BvhBuildParams,
        bvh2::{Bvh2, builder::build_bvh2_from_tris},
        cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
        ray::{Ray, RayHit},
        triangle::Triangle,
    };

    pub fn to_obvhs(tris: &[Tri]) -> Vec<Triangle> {
        // glam::Vec3 -> glam::Vec3A (obvhs uses 16-byte Vec3A)
        tris.iter()
            .map(|t| Triangle { v0: t[0].into(), v1: t[1].into(), v2: t[2].into() })
            .collect()
    }

    fn reorder(tris: &[Triangle], idx: &[u32]) -> Vec<Triangle> {
        idx.iter().map(|&i| tris[i as usize]).collect()
    }

    pub struct Cw {
        pub bvh: CwBvh,
        pub tris: Vec<Triangle>, // reordered by bvh.primitive_indices
    }
    impl Cw {
        pub fn build(tris: &[Triangle], params: BvhBuildParams) -> CwBvh {
            build_cwbvh_from_tris(tris, params, &mut Duration::default())
        }
        pub fn new(bvh: CwBvh, tris: &[Triangle]) -> Self {
            let tris = reorder(tris, &bvh.primitive_indices);
            Self { bvh, tris }
        }
        /// bytes held by the CwBvh itself (by Vec capacity)
        pub fn nodes_bytes(&self) -> usize {
            self.bvh.nodes.capacity() * std::mem::size_of_val(&self.bvh.nodes[0])
                + self.bvh.primitive_indices.capacity() * 4
                + self.bvh.exact_node_aabbs.as_ref().map_or(0, |v| v.capacity() * 32)
        }
        /// closest hit with barycentrics (what haze would call)
        pub fn closest_bary(&self, r: &R, tmin: f32, tmax: f32) -> Option<(f32, u32, glam::Vec2)> {
            let ray = Ray::new(r.o.into(), r.d.into(), tmin, tmax);
            let mut hit = RayHit::none();
            if self.bvh.ray_traverse(ray, &mut hit, |ray, id| self.tris[id].intersect(ray)) {
                let id = hit.primitive_id as usize;
                let bary = self.tris[id].compute_barycentric(&ray);
                Some((hit.t, self.bvh.primitive_indices[id], bary))
            } else {
                None
            }
        }
    }
    impl Cand for Cw {
        #[inline]
        fn closest(&self, r: &R, tmax: f32) -> (f32, u32) {
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            let mut hit = RayHit::none();
            if self.bvh.ray_traverse(ray, &mut hit, |ray, id| self.tris[id].intersect(ray)) {
                (hit.t, self.bvh.primitive_indices[hit.primitive_id as usize])
            } else {
                (f32::INFINITY, u32::MAX)
            }
        }
        #[inline]
        fn occluded(&self, r: &R, tmax: f32) -> bool {
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            !self.bvh.ray_traverse_miss(ray, |ray, id| self.tris[id].intersect(ray))
        }
    }

    /// Same CwBvh, but the leaf test is the watertight intersector (obvhs lets the caller
    /// supply the primitive test as a closure).
    pub struct CwWt<'a>(pub &'a Cw);
    impl Cand for CwWt<'_> {
        #[inline]
        fn closest(&self, r: &R, tmax: f32) -> (f32, u32) {
            let cw = self.0;
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            let wr = WtRay::new(r.o, r.d);
            let mut hit = RayHit::none();
            if cw.bvh.ray_traverse(ray, &mut hit, |ray, id| {
                let t = &cw.tris[id];
                wr.intersect(t.v0.into(), t.v1.into(), t.v2.into(), ray.tmin, ray.tmax).0
            }) {
                (hit.t, cw.bvh.primitive_indices[hit.primitive_id as usize])
            } else {
                (f32::INFINITY, u32::MAX)
            }
        }
        #[inline]
        fn occluded(&self, r: &R, tmax: f32) -> bool {
            let cw = self.0;
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            let wr = WtRay::new(r.o, r.d);
            !cw.bvh.ray_traverse_miss(ray, |ray, id| {
                let t = &cw.tris[id];
                wr.intersect(t.v0.into(), t.v1.into(), t.v2.into(), ray.tmin, ray.tmax).0
            })
        }
    }

    pub struct B2 {
        pub bvh: Bvh2,
        pub tris: Vec<Triangle>,
    }
    impl B2 {
        pub fn build(tris: &[Triangle], params: BvhBuildParams) -> Bvh2 {
            build_bvh2_from_tris(tris, params, &mut Duration::default())
        }
        pub fn new(bvh: Bvh2, tris: &[Triangle]) -> Self {
            let tris = reorder(tris, &bvh.primitive_indices);
            Self { bvh, tris }
        }
    }
    impl B2 {
        pub fn nodes_bytes(&self) -> usize {
            self.bvh.nodes.capacity() * std::mem::size_of_val(&self.bvh.nodes[0])
                + self.bvh.primitive_indices.capacity() * 4
                + self.bvh.primitive_indices_freelist.capacity() * 4
                + self.bvh.primitives_to_nodes.capacity() * 4
                + self.bvh.parents.capacity() * 4
        }
    }
    impl Cand for B2 {
        #[inline]
        fn closest(&self, r: &R, tmax: f32) -> (f32, u32) {
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            let mut hit = RayHit::none();
            if self.bvh.ray_traverse(ray, &mut hit, |ray, id| self.tris[id].intersect(ray)) {
                (hit.t, self.bvh.primitive_indices[hit.primitive_id as usize])
            } else {
                (f32::INFINITY, u32::MAX)
            }
        }
        #[inline]
        fn occluded(&self, r: &R, tmax: f32) -> bool {
            let ray = Ray::new(Vec3A::from(r.o), Vec3A::from(r.d), 0.0, tmax);
            !self.bvh.ray_traverse_miss(ray, |ray, id| self.tris[id].intersect(ray))
        }
    }
}

// ---- bvh (svenstaro) ------------------------------------------------------------------------
mod cand_bvh {
    use super::*;
    use bvh::aabb::{Aabb, Bounded};
    use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
    use bvh::bvh::{Bvh, BvhNode};
    use nalgebra::{Point3, Vector3};

    /// bvh 0.13 needs a mutable per-shape `node_index` slot (BHShape).
    pub struct Shape {
        pub aabb: Aabb<f32, 3>,
        pub node: usize,
    }
    impl Bounded<f32, 3> for Shape {
        fn aabb(&self) -> Aabb<f32, 3> {
            self.aabb
        }
    }
    impl BHShape<f32, 3> for Shape {
        fn set_bh_node_index(&mut self, i: usize) {
            self.node = i;
        }
        fn bh_node_index(&self) -> usize {
            self.node
        }
    }
    pub fn shapes(tris: &[Tri]) -> Vec<Shape> {
        tris.iter()
            .map(|t| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                Shape {
                    aabb: Aabb::with_bounds(
                        Point3::new(lo.x, lo.y, lo.z),
                        Point3::new(hi.x, hi.y, hi.z),
                    ),
                    node: 0,
                }
            })
            .collect()
    }
    pub fn build(shapes: &mut [Shape], par: bool) -> Bvh<f32, 3> {
        if par { Bvh::build_par(shapes) } else { Bvh::build(shapes) }
    }

    /// Flattened copy of the crate's node array for a cache-friendlier hand traversal
    /// (the enum nodes are 80+ bytes each, with usize links).
    pub struct Cb<'a> {
        pub bvh: Bvh<f32, 3>,
        pub shapes: &'a [Shape],
        pub tris: &'a [Tri],
    }

    #[inline(always)]
    fn slab(a: &Aabb<f32, 3>, o: Vec3, inv: Vec3, tmax: f32) -> f32 {
        let lo = Vec3::new(a.min.x, a.min.y, a.min.z);
        let hi = Vec3::new(a.max.x, a.max.y, a.max.z);
        let t0 = (lo - o) * inv;
        let t1 = (hi - o) * inv;
        let tn = t0.min(t1).max_element().max(0.0);
        let tf = t0.max(t1).min_element().min(tmax);
        if tn <= tf { tn } else { f32::INFINITY }
    }

    impl Cb<'_> {
        #[inline(always)]
        fn trav(&self, r: &R, mut tmax: f32, any: bool) -> (f32, u32) {
            let nodes = &self.bvh.nodes;
            let inv = r.d.recip();
            let mut best = (f32::INFINITY, u32::MAX);
            let mut stack = [0usize; 128];
            let mut sp = 0usize;
            // root may itself be a leaf (1 triangle); handle uniformly
            stack[sp] = 0;
            sp += 1;
            while sp > 0 {
                sp -= 1;
                let mut ni = stack[sp];
                loop {
                    match &nodes[ni] {
                        BvhNode::Leaf { shape_index, .. } => {
                            let t = mt(&self.tris[*shape_index], r.o, r.d, 0.0, tmax);
                            if t < tmax {
                                tmax = t;
                                best = (t, *shape_index as u32);
                                if any {
                                    return best;
                                }
                            }
                            break;
                        }
                        BvhNode::Node {
                            child_l_index, child_l_aabb, child_r_index, child_r_aabb, ..
                        } => {
                            let tl = slab(child_l_aabb, r.o, inv, tmax);
                            let tr = slab(child_r_aabb, r.o, inv, tmax);
                            match (tl.is_finite(), tr.is_finite()) {
                                (false, false) => break,
                                (true, false) => ni = *child_l_index,
                                (false, true) => ni = *child_r_index,
                                (true, true) => {
                                    let (near, far) = if tl <= tr {
                                        (*child_l_index, *child_r_index)
                                    } else {
                                        (*child_r_index, *child_l_index)
                                    };
                                    stack[sp] = far;
                                    sp += 1;
                                    ni = near;
                                }
                            }
                        }
                    }
                }
            }
            best
        }

        /// The crate's own API: iterate all shapes whose AABB the ray hits (no tmax pruning).
        pub fn closest_crate_iter(&self, r: &R, tmax: f32) -> (f32, u32) {
            let ray = bvh::ray::Ray::new(
                Point3::new(r.o.x, r.o.y, r.o.z),
                Vector3::new(r.d.x, r.d.y, r.d.z),
            );
            let mut best = (f32::INFINITY, u32::MAX);
            let base = self.shapes.as_ptr();
            for s in self.bvh.traverse_iterator(&ray, self.shapes) {
                let i = unsafe { (s as *const Shape).offset_from(base) } as usize;
                let t = mt(&self.tris[i], r.o, r.d, 0.0, tmax.min(best.0));
                if t < best.0 {
                    best = (t, i as u32);
                }
            }
            best
        }
    }
    impl Cand for Cb<'_> {
        fn closest(&self, r: &R, tmax: f32) -> (f32, u32) {
            self.trav(r, tmax, false)
        }
        fn occluded(&self, r: &R, tmax: f32) -> bool {
            self.trav(r, tmax, true).0 < tmax
        }
    }
}

// ---- parry3d --------------------------------------------------------------------------------
mod cand_parry {
    use super::*;
    use parry3d::math::Vector as PV; // glamx 0.3 => glam 0.33 Vec3 (NOT the same type as glam 0.34)
    use parry3d::query::{Ray, RayCast};
    use parry3d::shape::TriMesh;

    pub fn build(tris: &[Tri]) -> TriMesh {
        let verts: Vec<PV> =
            tris.iter().flat_map(|t| t.iter().map(|v| PV::new(v.x, v.y, v.z))).collect();
        let idx: Vec<[u32; 3]> =
            (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        TriMesh::new(verts, idx).expect("trimesh")
    }
    pub struct Cp {
        pub mesh: TriMesh,
    }
    impl Cand for Cp {
        fn closest(&self, r: &R, tmax: f32) -> (f32, u32) {
            let ray = Ray::new(PV::new(r.o.x, r.o.y, r.o.z), PV::new(r.d.x, r.d.y, r.d.z));
            match self.mesh.cast_local_ray_and_get_normal(&ray, tmax, false) {
                Some(h) => (h.time_of_impact, h.subshape),
                None => (f32::INFINITY, u32::MAX),
            }
        }
        fn occluded(&self, r: &R, tmax: f32) -> bool {
            let ray = Ray::new(PV::new(r.o.x, r.o.y, r.o.z), PV::new(r.d.x, r.d.y, r.d.z));
            self.mesh.intersects_local_ray(&ray, tmax)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Measurement helpers
// ---------------------------------------------------------------------------------------------
fn pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap()
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let t = Instant::now();
    let v = f();
    (v, t.elapsed())
}

static REPS: AtomicUsize = AtomicUsize::new(3);
/// run `f` REPS times; return the last result and the best (minimum) time
fn best_of<T>(mut f: impl FnMut() -> T) -> (T, Duration) {
    let mut best = Duration::MAX;
    let mut last = None;
    for _ in 0..REPS.load(Relaxed).max(1) {
        drop(last.take());
        let (v, d) = timed(&mut f);
        best = best.min(d);
        last = Some(v);
    }
    (last.unwrap(), best)
}

/// Untimed full pass (for correctness data).
fn closest_all(c: &dyn Cand, rays: &[R], tmax: f32, p: &rayon::ThreadPool) -> Vec<(f32, u32)> {
    p.install(|| {
        let mut out = Vec::with_capacity(rays.len());
        rays.par_iter().with_min_len(4096).map(|r| c.closest(r, tmax)).collect_into_vec(&mut out);
        out
    })
}
fn occluded_all(c: &dyn Cand, rays: &[R], tmax: f32, p: &rayon::ThreadPool) -> Vec<bool> {
    p.install(|| {
        let mut out = Vec::with_capacity(rays.len());
        rays.par_iter().with_min_len(4096).map(|r| c.occluded(r, tmax)).collect_into_vec(&mut out);
        out
    })
}
/// One timed pass; returns Mrays/s.
fn time_rays(c: &dyn Cand, rays: &[R], tmax: f32, occl: bool, p: &rayon::ThreadPool) -> f64 {
    p.install(|| {
        let t = Instant::now();
        if occl {
            let n = rays.par_iter().with_min_len(4096).filter(|r| c.occluded(r, tmax)).count();
            std::hint::black_box(n);
        } else {
            let s: f64 = rays.par_iter().with_min_len(4096).map(|r| c.closest(r, tmax).0.min(1e9) as f64).sum();
            std::hint::black_box(s);
        }
        rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6
    })
}

fn t_mismatch(a: f32, b: f32) -> bool {
    match (a.is_finite(), b.is_finite()) {
        (false, false) => false,
        (true, true) => (a - b).abs() > 1e-4 * a.abs().max(b.abs()).max(1e-6),
        _ => true,
    }
}

struct Row {
    name: String,
    build1: Option<f64>,
    build2: Option<f64>,
    mem_mb: f64,
    note: String,
    // [camera closest, random closest, camera occl, random occl] x [1T, 2T]
    thr: [[f64; 2]; 4],
    mism_cam: usize,
    mism_rnd: usize,
    mism_occ: usize,
    brute_bad: usize,
    /// on the rays where any two candidates disagree, wrong vs f64 brute force: (true hit on sphere, other)
    arb: (usize, usize),
    struct_mb: f64,
}

fn main() {
    let mut ntris = 1_000_000usize;
    let mut nrays = 1_000_000usize;
    let mut nbrute = 256usize;
    let args: Vec<String> = std::env::args().collect();
    let mut i = 1;
    while i < args.len() {
        let val = || args.get(i + 1).and_then(|s| s.replace('_', "").parse::<usize>().ok()).expect("number");
        match args[i].as_str() {
            "--tris" => { ntris = val(); i += 1; }
            "--rays" => { nrays = val(); i += 1; }
            "--brute" => { nbrute = val(); i += 1; }
            "--reps" => { REPS.store(val(), Relaxed); i += 1; }
            "-h" | "--help" => {
                println!("usage: bvh-candidates [--tris N] [--rays N] [--brute N] [--reps N]");
                return;
            }
            a => panic!("unknown arg {a}"),
        }
        i += 1;
    }
    let nthreads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let p1 = pool(1);
    let pn = pool(nthreads);

    println!("# bvh-candidates: {ntris} triangles, {nrays} rays per set, {nthreads} threads\n");
    let ((tris, n_sphere), dt) = timed(|| gen_mesh(ntris, 0x4A5E));
    println!("mesh: {n_sphere} displaced-sphere triangles (closed surface) + {} scattered small triangles", ntris - n_sphere);
    let (lo, hi) = bounds(&tris);
    println!("mesh generated in {:.2}s, bbox {lo:?}..{hi:?}", dt.as_secs_f64());
    let cam = camera_rays(nrays);
    let rnd = random_rays(nrays, lo, hi, 0xBEEF);
    let occ_tmax_rnd = 0.25 * (hi - lo).length(); // shadow-ray-like finite segments
    let inf = f32::INFINITY;

    // brute-force f64 reference on a subset
    let stride = (nrays / nbrute.max(1)).max(1);
    let sub: Vec<usize> = (0..nrays).step_by(stride).take(nbrute).collect();
    let (ref_cam, ref_rnd): (Vec<f64>, Vec<f64>) = {
        let (v, d) = timed(|| {
            pn.install(|| {
                let a: Vec<f64> = sub.par_iter().map(|&k| brute_f64(&tris, &cam[k])).collect();
                let b: Vec<f64> = sub.par_iter().map(|&k| brute_f64(&tris, &rnd[k])).collect();
                (a, b)
            })
        });
        println!("brute-force f64 reference on {} + {} rays in {:.1}s", sub.len(), sub.len(), d.as_secs_f64());
        v
    };
    let brute_bad = |res_cam: &[(f32, u32)], res_rnd: &[(f32, u32)]| -> usize {
        sub.iter()
            .enumerate()
            .filter(|(j, k)| {
                t_mismatch(res_cam[**k].0, ref_cam[*j] as f32) || t_mismatch(res_rnd[**k].0, ref_rnd[*j] as f32)
            })
            .count()
    };

    let mut rows: Vec<Row> = Vec::new();
    let all_results: std::cell::RefCell<Vec<(Vec<(f32, u32)>, Vec<(f32, u32)>)>> = Default::default();
    let reference: std::cell::RefCell<Option<(Vec<(f32, u32)>, Vec<(f32, u32)>)>> = Default::default();

    let measure = |name: &str, c: &dyn Cand, build1, build2, mem_mb, struct_mb: f64, note: String, rows: &mut Vec<Row>| {
        eprintln!("  correctness pass: {name} ...");
        let cc1 = closest_all(c, &cam, inf, &pn);
        let rc1 = closest_all(c, &rnd, inf, &pn);
        let oc = occluded_all(c, &cam, inf, &pn);
        let or = occluded_all(c, &rnd, occ_tmax_rnd, &pn);
        if reference.borrow().is_none() {
            *reference.borrow_mut() = Some((cc1.clone(), rc1.clone()));
        }
        let refb = reference.borrow();
        let (rc, rr) = refb.as_ref().unwrap();
        let mism_cam = cc1.iter().zip(rc).filter(|(a, b)| t_mismatch(a.0, b.0)).count();
        let mism_rnd = rc1.iter().zip(rr).filter(|(a, b)| t_mismatch(a.0, b.0)).count();
        // occlusion must agree with this candidate's own closest hit
        let mism_occ = oc.iter().zip(&cc1).filter(|(o, h)| **o != h.0.is_finite()).count()
            + or.iter().zip(&rc1).filter(|(o, h)| **o != (h.0 < occ_tmax_rnd)).count();
        let bb = brute_bad(&cc1, &rc1);
        all_results.borrow_mut().push((cc1.clone(), rc1.clone()));
        let hits_cam = cc1.iter().filter(|h| h.0.is_finite()).count();
        let hits_rnd = rc1.iter().filter(|h| h.0.is_finite()).count();
        eprintln!("    hits: camera {hits_cam}, random {hits_rnd}; occluded random {}", or.iter().filter(|o| **o).count());
        rows.push(Row {
            name: name.into(),
            build1,
            build2,
            mem_mb,
            note,
            thr: [[0.0; 2]; 4],
            mism_cam,
            mism_rnd,
            mism_occ,
            brute_bad: bb,
            arb: (0, 0),
            struct_mb: struct_mb,
        });
    };

    // ---------------- obvhs ----------------
    let otris = cand_obvhs::to_obvhs(&tris);
    let (cw, b) = {
        use obvhs::BvhBuildParams as P;
        eprintln!("obvhs CwBvh: building ...");
        let (_, b1) = best_of(|| p1.install(|| cand_obvhs::Cw::build(&otris, P::medium_build())));
        let before = live();
        let (bvh, b2) = best_of(|| pn.install(|| cand_obvhs::Cw::build(&otris, P::medium_build())));
        let mem = live() - before;
        let (_, f2) = best_of(|| pn.install(|| cand_obvhs::Cw::build(&otris, P::fast_build())));
        let cw = cand_obvhs::Cw::new(bvh, &otris);
        let note = format!(
            "{} nodes x 80 B; fast_build(): {:.2}s",
            cw.bvh.nodes.len(),
            f2.as_secs_f64()
        );
        eprintln!("   node bytes {:.1} MB (allocator delta {:.1} MB)", mb(cw.nodes_bytes()), mb(mem));
        // barycentric sanity check on a few camera hits: P = w*v0 + u*v1 + v*v2 ?
        let mut max_err = 0f32;
        let mut max_err_raw = 0f32;
        let mut max_err_fix = 0f32;
        for r in cam.iter().step_by(997).take(500) {
            if let Some((t, prim, b)) = cw.closest_bary(r, 0.0, inf) {
                let tr = &tris[prim as usize];
                let p = r.o + r.d * t;
                let q = tr[0] * (1.0 - b.x - b.y) + tr[1] * b.x + tr[2] * b.y;
                max_err = max_err.max((p - q).length());
                // raw Möller–Trumbore barycentrics for comparison
                let e1 = tr[1] - tr[0];
                let e2 = tr[2] - tr[0];
                let pv = r.d.cross(e2);
                let inv = 1.0 / e1.dot(pv);
                let s = r.o - tr[0];
                let u = s.dot(pv) * inv;
                let v = r.d.dot(s.cross(e1)) * inv;
                let q2 = tr[0] * (1.0 - u - v) + tr[1] * u + tr[2] * v;
                max_err_raw = max_err_raw.max((p - q2).length());
                // obvhs' convention without the normalize(): e1=v0-v1, e2=v2-v0, ng=e1 x e2
                let (a0, a1, a2) = (tr[0], tr[1], tr[2]);
                let (f1, f2) = (a0 - a1, a2 - a0);
                let ng = f1.cross(f2);
                let rr = r.d.cross(a0 - r.o);
                let (bu, bv) = (rr.dot(f2) / ng.dot(r.d), rr.dot(f1) / ng.dot(r.d));
                let q3 = a0 * (1.0 - bu - bv) + a1 * bu + a2 * bv;
                max_err_fix = max_err_fix.max((p - q3).length());
            }
        }
        eprintln!(
            "   barycentric check: obvhs Triangle::compute_barycentric max |P - P(bary)| = {max_err:.3e}; own MT = {max_err_raw:.3e}; obvhs formula w/o normalize = {max_err_fix:.3e}"
        );
        measure(
            "obvhs 0.4 CwBvh (medium_build)",
            &cw,
            Some(b1.as_secs_f64()),
            Some(b2.as_secs_f64()),
            mb(mem),
            mb(cw.nodes_bytes()),
            note,
            &mut rows,
        );
        measure(
            "obvhs 0.4 CwBvh + watertight closure",
            &cand_obvhs::CwWt(&cw),
            None,
            None,
            0.0,
            mb(cw.nodes_bytes()),
            "same CwBvh as above; leaf test = Woop et al. 2013 watertight intersector passed as the closure".into(),
            &mut rows,
        );

        eprintln!("obvhs Bvh2: building ...");
        let (_, b1) = best_of(|| p1.install(|| cand_obvhs::B2::build(&otris, P::medium_build())));
        let before = live();
        let (bvh, b2) = best_of(|| pn.install(|| cand_obvhs::B2::build(&otris, P::medium_build())));
        let mem = live() - before;
        let b = cand_obvhs::B2::new(bvh, &otris);
        let note = format!("{} nodes x {} B", b.bvh.nodes.len(), std::mem::size_of_val(&b.bvh.nodes[0]));
        measure(
            "obvhs 0.4 Bvh2 (medium_build)",
            &b,
            Some(b1.as_secs_f64()),
            Some(b2.as_secs_f64()),
            mb(mem),
            mb(b.nodes_bytes()),
            note,
            &mut rows,
        );
        (cw, b)
    };
    drop(otris);

    // ---------------- bvh 0.13 ----------------
    let mut shapes = cand_bvh::shapes(&tris);
    let cb = {
        eprintln!("bvh 0.13: building ...");
        let (_, b1) = best_of(|| p1.install(|| cand_bvh::build(&mut shapes, false)));
        let before = live();
        let (bvh, b2) = best_of(|| pn.install(|| cand_bvh::build(&mut shapes, true)));
        let mem = live() - before;
        let note = format!(
            "{} nodes x {} B (+{} B/shape for the BHShape node slot+AABB); hand-written traversal",
            bvh.nodes.len(),
            std::mem::size_of_val(&bvh.nodes[0]),
            std::mem::size_of::<cand_bvh::Shape>()
        );
        let bvh_bytes = bvh.nodes.capacity() * std::mem::size_of_val(&bvh.nodes[0]);
        let cb = cand_bvh::Cb { bvh, shapes: &shapes, tris: &tris };
        // the crate's own iterator API, on a subset (no tmax pruning => slow)
        let nsub = 20_000.min(nrays);
        let (res, d) = timed(|| p1.install(|| cam[..nsub].iter().map(|r| cb.closest_crate_iter(r, inf)).collect::<Vec<_>>()));
        let (res2, d2) = timed(|| p1.install(|| rnd[..nsub].iter().map(|r| cb.closest_crate_iter(r, inf)).collect::<Vec<_>>()));
        let crate_iter = (nsub as f64 / d.as_secs_f64() / 1e6, nsub as f64 / d2.as_secs_f64() / 1e6);
        let refb = reference.borrow();
        let (rc, rr) = refb.as_ref().unwrap();
        let m1 = res.iter().zip(rc).filter(|(a, b)| t_mismatch(a.0, b.0)).count()
            + res2.iter().zip(rr).filter(|(a, b)| t_mismatch(a.0, b.0)).count();
        eprintln!(
            "   bvh crate traverse_iterator closest-hit (1T, {nsub} rays): camera {:.3} Mrays/s, random {:.3} Mrays/s, mismatches {m1}",
            crate_iter.0, crate_iter.1
        );
        drop(refb);
        measure("bvh 0.13 (SAH, own traversal)", &cb, Some(b1.as_secs_f64()), Some(b2.as_secs_f64()), mb(mem), mb(bvh_bytes), note, &mut rows);
        rows.last_mut().unwrap().note += &format!(
            "; crate traverse_iterator (1T): {:.3}/{:.3} Mrays/s cam/rnd",
            crate_iter.0, crate_iter.1
        );
        cb
    };

    // ---------------- parry3d ----------------
    let cp = {
        eprintln!("parry3d: building ...");
        let before = live();
        let (mesh, b1) = best_of(|| cand_parry::build(&tris));
        let mem = live() - before;
        let cp = cand_parry::Cp { mesh };
        measure(
            "parry3d 0.31 TriMesh",
            &cp,
            Some(b1.as_secs_f64()),
            None,
            mb(mem),
            mb(mem),
            "single-threaded build (no parallel builder for TriMesh); memory = everything TriMesh::new allocated, incl. its own copy of 3 vertices + 1 index triple per triangle".into(),
            &mut rows,
        );
        cp
    };

    // ---------------- timing: interleaved, best of REPS ----------------
    {
        let cww = cand_obvhs::CwWt(&cw);
        let cands: Vec<&dyn Cand> = vec![&cw, &cww, &b, &cb, &cp];
        assert_eq!(cands.len(), rows.len());
        let reps = REPS.load(Relaxed).max(1);
        let workloads: [(&[R], f32, bool); 4] =
            [(&cam, inf, false), (&rnd, inf, false), (&cam, inf, true), (&rnd, occ_tmax_rnd, true)];
        let (_, d) = timed(|| {
            for (w, &(rays, tmax, occl)) in workloads.iter().enumerate() {
                for (pi, p) in [&p1, &pn].iter().enumerate() {
                    for _ in 0..reps {
                        for (ci, c) in cands.iter().enumerate() {
                            let m = time_rays(*c, rays, tmax, occl, p);
                            let e = &mut rows[ci].thr[w][pi];
                            *e = e.max(m);
                        }
                    }
                }
            }
        });
        eprintln!("timing: {reps} interleaved reps done in {:.0}s", d.as_secs_f64());
    }

    // ---------------- consensus arbitration ----------------
    // every ray on which any two candidates disagree is judged by f64 brute force
    let results = all_results.into_inner();
    let mut disputed: Vec<(bool, usize)> = Vec::new(); // (is_random_set, ray index)
    for k in 0..nrays {
        let dc = results.iter().any(|r| t_mismatch(r.0[k].0, results[0].0[k].0));
        let dr = results.iter().any(|r| t_mismatch(r.1[k].0, results[0].1[k].0));
        if dc {
            disputed.push((false, k));
        }
        if dr {
            disputed.push((true, k));
        }
    }
    let cap = 2000;
    if disputed.len() > cap {
        eprintln!("note: {} disputed rays, judging the first {cap}", disputed.len());
        disputed.truncate(cap);
    }
    let (truth, d) = timed(|| {
        pn.install(|| {
            disputed
                .par_iter()
                .map(|&(isr, k)| brute_f64_id(&tris, if isr { &rnd[k] } else { &cam[k] }))
                .collect::<Vec<(f64, usize)>>()
        })
    });
    eprintln!("judged {} disputed rays by brute force in {:.1}s", disputed.len(), d.as_secs_f64());
    for (ci, row) in rows.iter_mut().enumerate() {
        let res = &results[ci];
        let mut wrong = (0, 0);
        for (&(isr, k), &(bf, bid)) in disputed.iter().zip(&truth) {
            let t = if isr { res.1[k].0 } else { res.0[k].0 };
            if t_mismatch(t, bf as f32) {
                if bid < n_sphere { wrong.0 += 1 } else { wrong.1 += 1 }
            }
        }
        row.arb = wrong;
    }
    let n_disp_closed = truth.iter().filter(|t| t.1 < n_sphere).count();
    for (j, (&(isr, k), (bf, bid))) in disputed.iter().zip(&truth).enumerate().take(12) {
        let r = if isr { &rnd[k] } else { &cam[k] };
        let ts: Vec<String> = results.iter().map(|res| format!("{:.5}", if isr { res.1[k].0 } else { res.0[k].0 })).collect();
        eprintln!(
            "  disputed #{j} {} o={:?} d={:?}: brute t={bf:.5} tri {bid} ({}), candidates [{}]",
            if isr { "random" } else { "camera" },
            r.o,
            r.d,
            if *bid < n_sphere { "sphere" } else { "scatter/miss" },
            ts.join(", ")
        );
    }

    // ---------------- report ----------------
    let f = |x: Option<f64>| x.map(|v| format!("{v:.2}")).unwrap_or_else(|| "n/a".into());
    println!("\n## Build ({ntris} tris)\n");
    println!("| candidate | build 1 thread (s) | build {nthreads} threads (s) | structure size (MB) | heap still held after build (MB) | notes |");
    println!("|---|---:|---:|---:|---:|---|");
    for r in &rows {
        println!("| {} | {} | {} | {:.0} | {:.0} | {} |", r.name, f(r.build1), f(r.build2), r.struct_mb, r.mem_mb, r.note);
    }
    println!("\n## Throughput (Mrays/s, {nrays} rays per set; 1 thread / {nthreads} threads; best of {} interleaved reps)\n", REPS.load(Relaxed));
    println!("| candidate | closest, camera | closest, random-inside | occlusion, camera (tmax=inf) | occlusion, random (tmax={occ_tmax_rnd:.2}) |");
    println!("|---|---:|---:|---:|---:|");
    for r in &rows {
        let c = |k: usize| format!("{:.2} / {:.2}", r.thr[k][0], r.thr[k][1]);
        println!("| {} | {} | {} | {} | {} |", r.name, c(0), c(1), c(2), c(3));
    }
    println!("\n## Correctness\n");
    println!(
        "t mismatch = hit/miss differs or |dt| > 1e-4 relative. Reference for the full sets = {}. Disputed rays = rays on which any two candidates disagree; each is judged by an f64 Möller–Trumbore brute force over all triangles. Brute-force subset = {} camera + {} random rays spread over the sets.\n",
        rows[0].name,
        sub.len(),
        sub.len()
    );
    println!(
        "| candidate | closest mismatches vs ref, camera | closest mismatches vs ref, random | wrong vs f64 brute force: {} disputed rays whose true hit is on the closed sphere (= leaks) | wrong: {} disputed rays whose true hit is a scattered open triangle or a miss (edge grazing) | occlusion vs own closest-hit | mismatches on the brute-force subset |",
        n_disp_closed,
        disputed.len() - n_disp_closed
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        println!("| {} | {} | {} | {} | {} | {} | {} |", r.name, r.mism_cam, r.mism_rnd, r.arb.0, r.arb.1, r.mism_occ, r.brute_bad);
    }
    println!("\npeak heap: {:.0} MB", mb(PEAK.load(Relaxed)));
}
