//! A wide BVH collapsed from obvhs's binary tree: nodes of [`WIDTH`] children whose boxes are
//! stored as f32 planes of 8 lanes (structure of arrays), tested all at once by a [`NodeTest`]
//! ([`Avx2`] where the CPU has it, else the portable [`Sse`]), and each child slot naming its
//! inner node or leaf directly, for our traversal loop (`Accel::traverse` in `mod.rs`).
//!
//! obvhs builds the binary tree (PLOC, reinsertion, and its SAH leaf collapse into leaves of up
//! to [`LEAF_SIZE`] triangles: `obvhs::bvh2::builder::build_bvh2`); [`WideBvh::new`] turns it
//! into two `WIDTH`-wide trees over the same leaves (docs/performance.md §3.1): for closest-hit queries the collapse that minimises the surface area heuristic's cost
//! ([`CollapsePlan`], Ylitie, Karras and Laine 2017), and for queries that visit every box along
//! a segment (shadow rays) the greedy one, the way wide BVHs are usually built from binary ones
//! (Wald, Benthin and Boulos 2008, "Getting Rid of Packets"): a node's children are found by
//! opening, again and again, the inner child of largest surface area until there are `WIDTH`
//! children or none left to open. The binary tree's leaves stay leaves, so each holds up to four
//! triangles, one SSE packet (`WatertightRay::intersect_packet`).
//!
//! Why not obvhs's compressed wide BVH (`CwBvh`), traversed before (docs/performance.md §3.1):
//! its leaves hold at most 3 triangles (a unary 3-bit count), so one packet lane
//! in four was always empty, and its child boxes are quantised to 8 bits per plane, which we
//! decoded once into 256-byte nodes anyway. Here the boxes are the binary tree's exact f32 boxes
//! of the padded triangle boxes (`BOX_PAD` in `mod.rs`), so the node test is as conservative as
//! the padding makes it.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

/// Children per node: lanes of the node test, one AVX2 vector or [`HALVES`] SSE vectors per plane.
pub const WIDTH: usize = 4 * HALVES;
/// SSE vectors per plane of a node.
pub const HALVES: usize = 2;

/// Most triangles in a leaf: one SSE packet.
pub const LEAF_SIZE: u32 = 4;

/// Tag of a [`WideNode::children`] entry that is a leaf (the rest is the leaf's index in
/// [`WideBvh::leaves`]); untagged entries are indices of inner nodes in [`WideBvh::nodes`].
pub const LEAF: u32 = 1 << 31;

/// One plane of a node's [`WIDTH`] child boxes, lane `c` in `0[c / 4][c % 4]`: 32 bytes,
/// 32-byte aligned, so the AVX2 test reads it with one aligned 256-bit load and the SSE test
/// as its two halves.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Plane(pub [Vec4; HALVES]);

impl Plane {
    fn lane(&self, c: usize) -> f32 {
        self.0[c / 4][c % 4]
    }
}

/// One node: the child boxes as `[min x, max x, min y, max y, min z, max z]`, each plane's
/// [`WIDTH`] lanes contiguous ([`Plane`]), and what each child slot holds. An empty slot has
/// the empty box (`min = +inf`, `max = -inf`), which no ray enters: `(±inf - o) / d` is an
/// infinity of the sign that puts its entry after its exit on every axis (the inverse direction
/// is finite and non-zero, obvhs's `safe_inverse`), so no mask of valid slots is needed.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Child slot `c`: an inner node's index in [`WideBvh::nodes`], or [`LEAF`] `|` the index of
    /// a leaf in [`WideBvh::leaves`] (0 for an empty slot, never hit; the root, index 0, is
    /// nobody's child). Slots are filled in order, so `children[4] == 0` means lanes 4-7 are
    /// empty (the SSE test then skips them).
    pub children: [u32; WIDTH],
    /// `planes[p]`: plane `p` of all lanes.
    planes: [Plane; 6],
    /// The shape every triangle under child slot `c` belongs to, or [`MIXED`] (also for empty
    /// slots): a query that cannot hit a shape ([`super::Leaving`]) skips the subtrees of that
    /// shape whole. In what would otherwise be the node's padding (256 bytes either way).
    pub shapes: [u32; WIDTH],
}

/// [`WideNode::shapes`] of a subtree with triangles of more than one shape.
pub const MIXED: u32 = u32::MAX;

/// The binary tree's nodes in an order where each comes after both of its children (a
/// pre-order without recursion, reversed), whatever obvhs's layout.
fn children_first(b2: &[obvhs::bvh2::node::Bvh2Node]) -> Vec<usize> {
    let mut order = Vec::with_capacity(b2.len());
    let mut stack = if b2.is_empty() { vec![] } else { vec![0usize] };
    while let Some(n) = stack.pop() {
        order.push(n);
        if !b2[n].is_leaf() {
            let f = b2[n].first_index as usize;
            stack.extend([f, f + 1]);
        }
    }
    order.reverse();
    order
}

/// The shape of each binary node's triangles, or [`MIXED`]: `prim_shape` is each primitive's
/// shape by its index before the build (what `bvh.primitive_indices` holds).
fn subtree_shapes(bvh: &Bvh2, prim_shape: &[u32]) -> Vec<u32> {
    let b2 = &bvh.nodes;
    let mut shape = vec![MIXED; b2.len()];
    for n in children_first(b2) {
        shape[n] = if b2[n].is_leaf() {
            let run = &bvh.primitive_indices[b2[n].first_index as usize..][..b2[n].prim_count as usize];
            let first = prim_shape[run[0] as usize];
            if run.iter().all(|&i| prim_shape[i as usize] == first) {
                first
            } else {
                MIXED
            }
        } else {
            let f = b2[n].first_index as usize;
            if shape[f] == shape[f + 1] {
                shape[f]
            } else {
                MIXED
            }
        };
    }
    shape
}

impl WideNode {
    /// Child slot `c`'s box `(min, max)`, `None` for an empty slot.
    pub fn child_bounds(&self, c: usize) -> Option<(glam::Vec3, glam::Vec3)> {
        let p = |i: usize| self.planes[i].lane(c);
        let lo = glam::Vec3::new(p(0), p(2), p(4));
        let hi = glam::Vec3::new(p(1), p(3), p(5));
        (lo.cmple(hi).all()).then_some((lo, hi))
    }
}

/// A node test: the slab test of all [`WIDTH`] children of a node (Kay and Kajiya 1986) for `t`
/// in `[t_min, t_max]`. Each plane's distance is `(plane - o) * inv` in [`Sse`] and the fused
/// `plane * inv - o * inv` in [`Avx2`] (Embree's form; one rounding of the product-difference,
/// one of `o * inv` per ray): both within a few ulps of `max(|plane|, |o|) |inv|` of the exact
/// value, an error that grows with `|o|` in either form and stays far inside the boxes' padding
/// (`BOX_PAD` in `mod.rs`, ~34 ulps of the scene's largest coordinate) for origins within a few
/// times the scene's extent. Both are conservative alike, but their masks and entry distances
/// may differ in the last bits at a box's boundary. A flat box
/// (`min == max` on an axis) gets the same distance for both planes of that axis in either form,
/// and the test is `entry <= exit`, so a ray through it is never lost.
pub trait NodeTest: Copy {
    /// The ray splatted to the kernel's lanes.
    type Ray;
    /// `inv_d` is the direction's [`inverse_direction`].
    fn ray(self, o: Vec3A, inv_d: Vec3A, t_min: f32) -> Self::Ray;
    /// Bit `c` of the mask set when child `c` is hit, and each child's entry distance, by which
    /// the traversal orders and prunes them (lanes not in the mask are not meaningful).
    fn intersect(self, node: &WideNode, ray: &Self::Ray, t_max: f32) -> (u32, [f32; WIDTH]);
}

/// The componentwise inverse of a direction that [`NodeTest::ray`] expects: obvhs's
/// `safe_inverse`, finite and non-zero for every component (a `±0` component gets `±1 /
/// f32::EPSILON`, keeping its sign).
#[inline(always)]
pub fn inverse_direction(d: Vec3A) -> Vec3A {
    use obvhs::ray::safe_inverse;
    Vec3A::new(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z))
}

/// For each axis, which of the two planes is met first: chosen once per ray by the sign of
/// `1 / d`, so the slab test needs no min/max of the two plane distances. The sign of `inv_d`,
/// not of the direction: a component `-0.0` has an inverse of `-1 / f32::EPSILON`, and choosing
/// by `d < 0` (false for `-0.0`) paired the planes wrongly, so such a ray missed every box it
/// started in.
#[inline(always)]
fn near_planes(inv_d: Vec3A) -> [usize; 3] {
    [usize::from(inv_d.x < 0.0), 2 + usize::from(inv_d.y < 0.0), 4 + usize::from(inv_d.z < 0.0)]
}

/// The portable node test: each plane as two 4-lane `Vec4`s (SSE2 on x86-64, NEON on AArch64,
/// scalar elsewhere), the second half neither read nor tested when slot 4 is empty.
#[derive(Clone, Copy, Debug)]
pub struct Sse;

/// A ray prepared for [`Sse`]: the near planes, the origin and the inverse direction splatted to
/// 4 lanes.
#[derive(Clone, Copy, Debug)]
pub struct SseRay {
    near: [usize; 3],
    o: [Vec4; 3],
    inv: [Vec4; 3],
    t_min: Vec4,
}

impl NodeTest for Sse {
    type Ray = SseRay;

    #[inline(always)]
    fn ray(self, o: Vec3A, inv_d: Vec3A, t_min: f32) -> SseRay {
        SseRay {
            near: near_planes(inv_d),
            // Written out: `[0, 1, 2].map(..)` compiled to an out-of-line `try_map` call per
            // query (8% of hg-box's CPU samples, whose rays test few nodes).
            o: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(inv_d.x), Vec4::splat(inv_d.y), Vec4::splat(inv_d.z)],
            t_min: Vec4::splat(t_min),
        }
    }

    #[inline(always)]
    fn intersect(self, node: &WideNode, ray: &SseRay, t_max: f32) -> (u32, [f32; WIDTH]) {
        let t_max = Vec4::splat(t_max);
        let mut mask = 0;
        let mut entry = [Vec4::ZERO; HALVES];
        for (h, entry) in entry.iter_mut().enumerate() {
            if h > 0 && node.children[4 * h] == 0 {
                // Lanes 4h.. are empty (slots fill in order): nothing to test or read.
                *entry = Vec4::INFINITY;
                continue;
            }
            let mut lo = ray.t_min;
            let mut hi = t_max;
            for a in 0..3 {
                let n = ray.near[a];
                let t_near = (node.planes[n].0[h] - ray.o[a]) * ray.inv[a];
                let t_far = (node.planes[n ^ 1].0[h] - ray.o[a]) * ray.inv[a];
                lo = lo.max(t_near);
                hi = hi.min(t_far);
            }
            mask |= lo.cmple(hi).bitmask() << (4 * h);
            *entry = lo;
        }
        (mask, std::array::from_fn(|c| entry[c / 4][c % 4]))
    }
}

#[cfg(target_arch = "x86_64")]
pub use avx2::Avx2;

/// Not x86-64: no AVX2 kernel. Uninhabited, so the traversal's AVX2 branch is dead code.
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Copy, Debug)]
pub enum Avx2 {}

#[cfg(not(target_arch = "x86_64"))]
impl Avx2 {
    pub fn detect() -> Option<Self> {
        None
    }

    pub fn run<R>(self, _: impl FnOnce() -> R) -> R {
        match self {}
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl NodeTest for Avx2 {
    type Ray = ();
    fn ray(self, _: Vec3A, _: Vec3A, _: f32) {
        match self {}
    }
    fn intersect(self, _: &WideNode, _: &(), _: f32) -> (u32, [f32; WIDTH]) {
        match self {}
    }
}

/// The 8-lane node test (docs/performance.md §3.3): one 256-bit vector per plane and fused
/// multiply-adds, chosen at run time, so a build for any x86-64 uses it too where the CPU has
/// AVX2.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{near_planes, NodeTest, WideNode, WIDTH};
    use glam::Vec3A;
    use std::arch::x86_64::*;

    /// Proof that the CPU has AVX2 and FMA: a value exists only after [`Avx2::detect`] found
    /// both, which is what makes the `unsafe` calls of the `avx2,fma`-enabled functions below
    /// sound.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx2(());

    impl Avx2 {
        /// `Some` when the CPU has AVX2 and FMA (every AVX2 CPU of Intel and AMD has both),
        /// unless the environment variable `HAZE_FORCE_SSE` is set
        /// (non-empty): an internal switch for tests and measurements (ARCHITECTURE.md), which
        /// forces the portable kernel on every machine.
        pub fn detect() -> Option<Self> {
            let forced = std::env::var_os("HAZE_FORCE_SSE").is_some_and(|v| !v.is_empty());
            (!forced && is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
                .then_some(Avx2(()))
        }

        /// Runs `f` inside a function compiled with AVX2 enabled, so that everything `f` inlines
        /// (the whole traversal loop, its leaf tests and the [`Avx2`] node test) is compiled for
        /// AVX2 and FMA (VEX encoding, 256-bit registers). One call per query, not per node.
        /// Rust never contracts `a * b + c` into a fused operation on its own, so the inlined
        /// triangle tests compute exactly what the portable build computes; only the node
        /// test's explicit `fmsub` differs.
        #[inline(always)]
        pub fn run<R>(self, f: impl FnOnce() -> R) -> R {
            #[target_feature(enable = "avx2,fma")]
            unsafe fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: `self` exists only if `detect` found AVX2 and FMA on this CPU.
            unsafe { with_avx2(f) }
        }
    }

    /// A ray prepared for [`Avx2`]: the near planes, the inverse direction and the origin times
    /// it, splatted to 8 lanes.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx2Ray {
        near: [usize; 3],
        inv: [__m256; 3],
        o_inv: [__m256; 3],
        t_min: __m256,
    }

    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn ray(o: Vec3A, inv_d: Vec3A, t_min: f32) -> Avx2Ray {
        Avx2Ray {
            near: near_planes(inv_d),
            inv: [_mm256_set1_ps(inv_d.x), _mm256_set1_ps(inv_d.y), _mm256_set1_ps(inv_d.z)],
            o_inv: [
                _mm256_set1_ps(o.x * inv_d.x),
                _mm256_set1_ps(o.y * inv_d.y),
                _mm256_set1_ps(o.z * inv_d.z),
            ],
            t_min: _mm256_set1_ps(t_min),
        }
    }

    /// [`super::Sse`]'s test on all 8 lanes at once, each plane's distance fused (see
    /// [`NodeTest`]); the same `max`/`min` order and `<=`.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn intersect(node: &WideNode, ray: &Avx2Ray, t_max: f32) -> (u32, [f32; WIDTH]) {
        // `Plane` is 32 bytes, 32-byte aligned: an aligned load of all 8 lanes.
        let plane = |p: usize| node.planes[p].0.as_ptr().cast::<f32>();
        let mut lo = ray.t_min;
        let mut hi = _mm256_set1_ps(t_max);
        for a in 0..3 {
            let n = ray.near[a];
            // One fused operation instead of a subtraction and a product: the plane distances
            // are the start of each node's dependency chain (docs/performance.md §3.3).
            let t_near = _mm256_fmsub_ps(_mm256_load_ps(plane(n)), ray.inv[a], ray.o_inv[a]);
            let t_far = _mm256_fmsub_ps(_mm256_load_ps(plane(n ^ 1)), ray.inv[a], ray.o_inv[a]);
            lo = _mm256_max_ps(lo, t_near);
            hi = _mm256_min_ps(hi, t_far);
        }
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(lo, hi)) as u32;
        let mut entry = [0.0; WIDTH];
        _mm256_storeu_ps(entry.as_mut_ptr(), lo);
        (mask, entry)
    }

    impl NodeTest for Avx2 {
        type Ray = Avx2Ray;

        #[inline(always)]
        fn ray(self, o: Vec3A, inv_d: Vec3A, t_min: f32) -> Avx2Ray {
            // SAFETY: `self` exists only if the CPU has AVX2 and FMA.
            unsafe { ray(o, inv_d, t_min) }
        }

        #[inline(always)]
        fn intersect(self, node: &WideNode, ray: &Avx2Ray, t_max: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: as above.
            unsafe { intersect(node, ray, t_max) }
        }
    }
}

impl WideNode {
    /// Bit `c` set when child slot `c`'s subtree is all of shape `skip`.
    #[inline(always)]
    pub fn shape_mask(&self, skip: u32) -> u32 {
        let s = glam::UVec4::splat(skip);
        let lo = glam::UVec4::from_slice(&self.shapes[..4]).cmpeq(s).bitmask();
        let hi = glam::UVec4::from_slice(&self.shapes[4..]).cmpeq(s).bitmask();
        lo | hi << 4
    }

    /// `boxes`: the children's boxes (at most [`WIDTH`]), what each slot holds and the shape
    /// of its triangles ([`Self::shapes`]).
    fn new(children: &[(Aabb, u32, u32)]) -> Self {
        let lane = |c: usize, plane: usize| match children.get(c) {
            Some((b, _, _)) => {
                if plane % 2 == 0 {
                    b.min[plane / 2]
                } else {
                    b.max[plane / 2]
                }
            }
            None if plane % 2 == 0 => f32::INFINITY,
            None => f32::NEG_INFINITY,
        };
        let planes = std::array::from_fn(|plane| {
            Plane(std::array::from_fn(|h| {
                Vec4::new(
                    lane(4 * h, plane),
                    lane(4 * h + 1, plane),
                    lane(4 * h + 2, plane),
                    lane(4 * h + 3, plane),
                )
            }))
        });
        WideNode {
            planes,
            children: std::array::from_fn(|c| children.get(c).map_or(0, |x| x.1)),
            shapes: std::array::from_fn(|c| children.get(c).map_or(MIXED, |x| x.2)),
        }
    }
}

/// Traversal cost of a wide node relative to a leaf test, in the surface area heuristic of
/// [`CollapsePlan`].
const NODE_COST: f32 = 1.0;
/// Cost of a leaf's packet test.
const LEAF_COST: f32 = 0.6;

/// Which binary nodes become the children of each wide node: the collapse that minimises the
/// surface area heuristic's cost of the wide tree (Ylitie, Karras and Laine 2017, "Efficient
/// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", section 3.1), by dynamic
/// programming over the binary tree. `cost[n][i - 1]` is the least cost of binary node `n`'s
/// subtree given `i` child slots of its wide parent: one slot holds `n` as a leaf or as a wide
/// node of its own (`A(n) NODE_COST` plus its subtree spread over `WIDTH` slots), more slots may
/// instead spread `n`'s two children over them. The greedy collapse (open the largest inner
/// child until the node is full) left half of the nodes with two or three children on the peer
/// spheres (961 nodes for 3137 leaves, where 448 could hold them); this one's closest hits are
/// 3-5% faster there, but shadow rays through `null` spheres, which visit every box they cross,
/// were slower in it, so they keep the greedy tree ([`WideBvh`]).
struct CollapsePlan {
    cost: Vec<[f32; WIDTH]>,
    /// `split[n][i - 1]`: slots given to `n`'s first child when `n` spreads over `i` slots,
    /// 0 when `n` takes one slot itself.
    split: Vec<[u8; WIDTH]>,
}

impl CollapsePlan {
    fn new(b2: &[obvhs::bvh2::node::Bvh2Node]) -> Self {
        let mut cost = vec![[0.0f32; WIDTH]; b2.len()];
        let mut split = vec![[0u8; WIDTH]; b2.len()];
        for n in children_first(b2) {
            let area = b2[n].aabb.half_area();
            if b2[n].is_leaf() {
                cost[n] = [area * LEAF_COST; WIDTH];
                continue;
            }
            let (cl, cr) = (cost[b2[n].first_index as usize], cost[b2[n].first_index as usize + 1]);
            // Both children spread over `i` slots (`i >= 2`), the best split of the slots.
            let spread = |i: usize| {
                (1..i).map(|k| (cl[k - 1] + cr[i - k - 1], k)).min_by(|a, b| a.0.total_cmp(&b.0)).unwrap()
            };
            let own = area * NODE_COST + spread(WIDTH).0;
            cost[n][0] = own;
            for i in 2..=WIDTH {
                let (c, k) = spread(i);
                (cost[n][i - 1], split[n][i - 1]) = if c < own { (c, k as u8) } else { (own, 0) };
            }
        }
        CollapsePlan { cost, split }
    }

    /// The binary nodes that become the children of the wide node made for binary node `b`
    /// (inner), appended to `out`.
    fn children(&self, b2: &[obvhs::bvh2::node::Bvh2Node], b: usize, out: &mut Vec<usize>) {
        let (l, r) = (b2[b].first_index as usize, b2[b].first_index as usize + 1);
        let k = (1..WIDTH)
            .min_by(|&x, &y| {
                (self.cost[l][x - 1] + self.cost[r][WIDTH - x - 1])
                    .total_cmp(&(self.cost[l][y - 1] + self.cost[r][WIDTH - y - 1]))
            })
            .unwrap();
        self.spread(b2, l, k, out);
        self.spread(b2, r, WIDTH - k, out);
    }

    /// The roots `n`'s subtree is spread into over `i` slots.
    fn spread(&self, b2: &[obvhs::bvh2::node::Bvh2Node], n: usize, i: usize, out: &mut Vec<usize>) {
        let k = usize::from(self.split[n][i - 1]);
        if b2[n].is_leaf() || k == 0 {
            out.push(n);
        } else {
            let f = b2[n].first_index as usize;
            self.spread(b2, f, k, out);
            self.spread(b2, f + 1, i - k, out);
        }
    }
}

/// A wide tree over [`WideBvh::leaves`]: nodes (the root first, every node before its
/// children), laid out depth first with siblings together.
#[derive(Clone, Debug)]
pub struct WideTree {
    pub nodes: Vec<WideNode>,
    /// Most entries a traversal's stack can hold at once (each node visited pushes its hit
    /// children and pops one).
    pub stack_need: usize,
}

/// Two collapses of one binary tree over the same leaves: [`Self::closest`], the collapse that
/// minimises the surface area heuristic's cost ([`CollapsePlan`]), for closest-hit queries,
/// and [`Self::all`], the greedy one (open the inner child of largest area until the node is
/// full), for queries that visit every box along a segment (shadow rays collecting the
/// surfaces they cross), where the greedy tree measured faster.
#[derive(Clone, Debug)]
pub struct WideBvh {
    pub closest: WideTree,
    pub all: WideTree,
    /// Each leaf a run `(first, count)` of `primitive_indices` with `count <= LEAF_SIZE`, in
    /// the binary tree's depth-first order.
    pub leaves: Vec<(u32, u32)>,
    /// The binary tree's order of the primitives: leaf runs index into it.
    pub primitive_indices: Vec<u32>,
}

impl WideBvh {
    /// Collapses `bvh` (leaves of at most [`LEAF_SIZE`] primitives) into both [`WIDTH`]-wide
    /// trees; `prim_shape[i]` is the shape of primitive `i` (its index before the build).
    pub fn new(bvh: Bvh2, prim_shape: &[u32]) -> Self {
        let shape = subtree_shapes(&bvh, prim_shape);
        let b2 = &bvh.nodes;
        // Leaf numbers in the binary tree's depth-first order, shared by both trees.
        let mut leaf_of = vec![u32::MAX; b2.len()];
        let mut leaves: Vec<(u32, u32)> = Vec::new();
        let mut stack = if b2.is_empty() { vec![] } else { vec![0usize] };
        while let Some(n) = stack.pop() {
            if b2[n].is_leaf() {
                assert!(
                    b2[n].prim_count <= LEAF_SIZE,
                    "obvhs made a leaf of {} primitives",
                    b2[n].prim_count
                );
                leaf_of[n] = LEAF | leaves.len() as u32;
                leaves.push((b2[n].first_index, b2[n].prim_count));
            } else {
                let f = b2[n].first_index as usize;
                stack.extend([f + 1, f]);
            }
        }
        let plan = CollapsePlan::new(b2);
        let closest = collapse(b2, &leaf_of, &shape, |b, open| plan.children(b2, b, open));
        let all = collapse(b2, &leaf_of, &shape, |b, open| {
            let first = b2[b].first_index as usize;
            open.extend([first, first + 1]);
            // Open the largest inner child until the node is full.
            while open.len() < WIDTH {
                let largest = (0..open.len())
                    .filter(|&i| !b2[open[i]].is_leaf())
                    .max_by(|&i, &j| b2[open[i]].aabb.half_area().total_cmp(&b2[open[j]].aabb.half_area()));
                let Some(i) = largest else { break };
                let f = b2[open[i]].first_index as usize;
                open[i] = f;
                open.push(f + 1);
            }
        });
        WideBvh { closest, all, leaves, primitive_indices: bvh.primitive_indices }
    }
}

/// The wide tree whose node for binary node `b` (inner) has the children `children(b, out)`
/// appends to `out` (at most [`WIDTH`] binary nodes).
fn collapse(
    b2: &[obvhs::bvh2::node::Bvh2Node],
    leaf_of: &[u32],
    shape: &[u32],
    mut children: impl FnMut(usize, &mut Vec<usize>),
) -> WideTree {
    let mut nodes: Vec<WideNode> = Vec::new();
    if b2.is_empty() {
        return WideTree { nodes, stack_need: 1 };
    }
    if b2[0].is_leaf() {
        nodes.push(WideNode::new(&[(b2[0].aabb, leaf_of[0], shape[0])]));
        return WideTree { nodes, stack_need: 2 };
    }
    // (binary node, wide node to fill); every wide node is reserved when its parent is made.
    nodes.push(WideNode::new(&[]));
    let mut work = vec![(0usize, 0usize)];
    let mut open: Vec<usize> = Vec::with_capacity(WIDTH);
    while let Some((b, w)) = work.pop() {
        open.clear();
        children(b, &mut open);
        let mut slots = [(Aabb::empty(), 0u32, MIXED); WIDTH];
        for (slot, &c) in slots.iter_mut().zip(&open) {
            let what = if b2[c].is_leaf() {
                leaf_of[c]
            } else {
                nodes.push(WideNode::new(&[]));
                work.push((c, nodes.len() - 1));
                (nodes.len() - 1) as u32
            };
            *slot = (b2[c].aabb, what, shape[c]);
        }
        nodes[w] = WideNode::new(&slots[..open.len()]);
    }
    // need(node) = (children - 1) + max over inner children of need(child), over the nodes
    // in reverse order (children come after their parent).
    let mut need = vec![0usize; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        let slots = (0..WIDTH).filter(|&c| n.planes[0].lane(c) != f32::INFINITY);
        let deepest = slots
            .clone()
            .filter(|&c| n.children[c] & LEAF == 0)
            .map(|c| need[n.children[c] as usize])
            .max()
            .unwrap_or(0);
        need[i] = slots.count().saturating_sub(1) + deepest;
    }
    WideTree { stack_need: need[0] + 1, nodes }
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;
    use obvhs::bvh2::builder::build_bvh2;
    use obvhs::BvhBuildParams;

    /// What the exact slab test says of a lane, given a kernel's rounding.
    #[derive(Debug)]
    enum Exact {
        /// Hit by more than the rounding: the entry and its tolerance.
        Hit(f64, f64),
        /// Missed by more than the rounding.
        Miss,
        /// Within the rounding of the boundary: either answer is right.
        Unsure,
    }

    /// The exact slab test of lane `c` (in f64, where `(plane - o) * inv` of f32 values is
    /// exact), judged with the rounding of a kernel's f32 test: a few ulps of `(|plane| + |o|)
    /// |inv|` of the axes that decide the entry and the exit. A box flat on an axis is met where
    /// the ray crosses that plane, which both kernels compute once for both of its planes: it is
    /// hit when that crossing lies inside the other axes' interval by more than their rounding.
    fn exact_slab(node: &WideNode, c: usize, o: Vec3A, inv: Vec3A, t_min: f32, t_max: f32) -> Exact {
        let (mut lo, mut hi) = ((t_min as f64, 0.0f64), (t_max as f64, 0.0f64));
        let mut flat = None;
        for (a, near) in near_planes(inv).into_iter().enumerate() {
            let (o, inv) = (o[a] as f64, inv[a] as f64);
            let plane = |p: usize| node.planes[p].lane(c) as f64;
            let at = |x: f64| ((x - o) * inv, 8.0 * f32::EPSILON as f64 * (x.abs() + o.abs()) * inv.abs());
            if plane(near) == plane(near ^ 1) {
                flat = Some(at(plane(near)));
                continue;
            }
            let (t0, t1) = (at(plane(near)), at(plane(near ^ 1)));
            if t0.0 > lo.0 {
                lo = t0;
            }
            if t1.0 < hi.0 {
                hi = t1;
            }
        }
        let inside = |t: (f64, f64), lo: (f64, f64), hi: (f64, f64)| {
            if t.0 - t.1 > lo.0 + lo.1 && t.0 + t.1 < hi.0 - hi.1 {
                Some(true)
            } else if t.0 + t.1 < lo.0 - lo.1 || t.0 - t.1 > hi.0 + hi.1 {
                Some(false)
            } else {
                None
            }
        };
        match flat {
            Some(t) => match inside(t, lo, hi) {
                Some(true) => Exact::Hit(t.0, t.1),
                Some(false) => Exact::Miss,
                None => Exact::Unsure,
            },
            None if hi.0 - lo.0 > lo.1 + hi.1 => Exact::Hit(lo.0, lo.1),
            None if hi.0 - lo.0 < -(lo.1 + hi.1) => Exact::Miss,
            None => Exact::Unsure,
        }
    }

    /// Both node tests against the exact slab test, on random nodes of 1 to 8 boxes (some flat)
    /// and rays with `±0` direction components: a lane whose exact interval is longer than the
    /// rounding tolerance is hit, with its entry within the tolerance, one shorter than minus it
    /// is not, empty slots never are. Then rays through the middle of flat boxes, whose entry
    /// equals their exit in both kernels (`(plane - o) * inv` and `plane * inv - o * inv` give
    /// the two planes of the flat axis the same distance): both must hit them, which fails with
    /// `<` instead of `<=` in either test (checked). The AVX2 half is skipped, with one line,
    /// where the CPU has no AVX2 and FMA.
    #[test]
    fn node_tests_agree_with_the_exact_slab_test() {
        let avx = Avx2::detect();
        if avx.is_none() {
            eprintln!("skipped (AVX2 half): no AVX2 and FMA on this CPU (or HAZE_FORCE_SSE is set)");
        }
        let test = |node: &WideNode, o: Vec3A, inv: Vec3A, t_min: f32, t_max: f32| {
            let mut out = vec![Sse.intersect(node, &Sse.ray(o, inv, t_min), t_max)];
            if let Some(k) = avx {
                out.push(k.intersect(node, &k.ray(o, inv, t_min), t_max));
            }
            out
        };
        let mut s = Sampler::from_seed(17);
        let (mut hit_lanes, mut missed, mut unsure) = (0, 0, 0);
        for i in 0..20_000 {
            let r = |s: &mut Sampler| Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
            let count = 1 + i % WIDTH;
            let boxes: Vec<(Aabb, u32, u32)> = (0..count)
                .map(|c| {
                    let lo = r(&mut s) * 4.0;
                    let mut hi = lo + r(&mut s) * 2.0;
                    // Flat in one axis for every third box.
                    if c % 3 == 0 {
                        hi[c % 3] = lo[c % 3];
                    }
                    (Aabb::new(lo, hi), c as u32 + 1, MIXED)
                })
                .collect();
            let node = WideNode::new(&boxes);
            let o = r(&mut s) * 6.0 - Vec3A::ONE;
            // Aimed near the centre of one of the boxes, so that many lanes are hit.
            let aim = boxes[i % count].0.center() + (r(&mut s) - Vec3A::splat(0.5)) * 0.5;
            let mut d = (aim - o).normalize_or(Vec3A::X);
            // A zero component (either sign) in a quarter of the rays.
            if i % 4 == 0 {
                d[(i / 4) % 3] = if i % 8 == 0 { 0.0 } else { -0.0 };
            }
            let inv = inverse_direction(d);
            let t_max = if i % 5 == 0 { f32::INFINITY } else { s.next_1d() * 8.0 };
            let t_min = if i % 7 == 0 { s.next_1d() } else { 0.0 };
            let results = test(&node, o, inv, t_min, t_max);
            for c in 0..WIDTH {
                if c >= count {
                    assert!(results.iter().all(|(m, _)| m & (1 << c) == 0), "case {i}: empty slot {c} hit");
                    continue;
                }
                let exact = exact_slab(&node, c, o, inv, t_min, t_max);
                for (k, (mask, entry)) in results.iter().enumerate() {
                    let hit = mask & (1 << c) != 0;
                    match exact {
                        Exact::Hit(lo, tol) => {
                            assert!(hit, "case {i}, kernel {k}, lane {c}: {exact:?} missed");
                            assert!(
                                (entry[c] as f64 - lo).abs() <= tol,
                                "case {i}, kernel {k}, lane {c}: entry {} vs {exact:?}",
                                entry[c]
                            );
                        }
                        Exact::Miss => assert!(!hit, "case {i}, kernel {k}, lane {c}: {exact:?} hit"),
                        Exact::Unsure => {}
                    }
                }
                match exact {
                    Exact::Hit(..) => hit_lanes += 1,
                    Exact::Miss => missed += 1,
                    Exact::Unsure => unsure += 1,
                }
            }
        }
        assert!(hit_lanes > 5_000 && missed > 5_000 && unsure < 50, "{hit_lanes} {missed} {unsure}");

        // Flat boxes hit through their middle, on each axis, from both sides.
        for i in 0..3_000 {
            let r = |s: &mut Sampler| Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
            let axis = i % 3;
            let mut hi = Vec3A::splat(1.0);
            hi[axis] = 0.0;
            let node = WideNode::new(&[(Aabb::new(Vec3A::ZERO, hi), 1, MIXED)]);
            let mut aim = Vec3A::splat(0.1) + r(&mut s) * 0.8;
            aim[axis] = 0.0;
            let mut o = r(&mut s) * 4.0 - Vec3A::splat(2.0);
            o[axis] = if i % 2 == 0 { 1.0 + s.next_1d() } else { -1.0 - s.next_1d() };
            let inv = inverse_direction((aim - o).normalize());
            for (k, (mask, entry)) in test(&node, o, inv, 0.0, f32::INFINITY).into_iter().enumerate() {
                assert_eq!(mask, 1, "flat case {i}, kernel {k}");
                assert!(entry[0] > 0.0, "flat case {i}, kernel {k}");
            }
        }
    }

    /// The shape [`random_tree`] gives box `i` with centre `c`: one per half of the cube, and a
    /// third for every 50th box, so that subtrees of one shape and mixed ones both occur.
    fn box_shape(i: usize, c: Vec3A) -> u32 {
        if i % 50 == 0 {
            2
        } else {
            u32::from(c.x < 5.0)
        }
    }

    /// `count` random boxes in a cube of side 10 and both collapses of obvhs's tree over them
    /// (shapes from [`box_shape`]).
    fn random_tree(s: &mut Sampler, count: usize) -> (Vec<Aabb>, WideBvh) {
        let mut p = || Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
        let boxes: Vec<Aabb> = (0..count)
            .map(|_| {
                let c = p() * 10.0;
                Aabb::new(c, c + p() * 0.5)
            })
            .collect();
        let mut params = BvhBuildParams::slow_build();
        params.pre_split = false;
        params.max_prims_per_leaf = LEAF_SIZE;
        let shapes: Vec<u32> = boxes.iter().enumerate().map(|(i, b)| box_shape(i, b.center())).collect();
        let wide = WideBvh::new(build_bvh2(&boxes, params, &mut Default::default()), &shapes);
        (boxes, wide)
    }

    /// The surface area heuristic's cost that [`CollapsePlan`] minimises, of a whole tree:
    /// `NODE_COST` times the area of every node (the union of its child boxes) plus `LEAF_COST`
    /// times the area of every leaf's box.
    fn sah_cost(tree: &WideTree) -> f64 {
        let mut cost = 0.0f64;
        let mut work = vec![0u32];
        while let Some(x) = work.pop() {
            let node = &tree.nodes[x as usize];
            let mut bounds = Aabb::empty();
            for c in (0..WIDTH).filter(|&c| node.planes[0].lane(c) != f32::INFINITY) {
                let lane = |pl: usize| node.planes[pl].lane(c);
                let b =
                    Aabb::new(Vec3A::new(lane(0), lane(2), lane(4)), Vec3A::new(lane(1), lane(3), lane(5)));
                bounds = bounds.union(&b);
                if node.children[c] & LEAF != 0 {
                    cost += f64::from(b.half_area() * LEAF_COST);
                } else {
                    work.push(node.children[c]);
                }
            }
            cost += f64::from(bounds.half_area() * NODE_COST);
        }
        cost
    }

    /// The dynamic programme's collapse is optimal for its cost model, so no other collapse of
    /// the same binary tree, the greedy one included, costs less; and it is not worse than the
    /// greedy one by accident of equal trees: on random boxes it costs strictly less.
    #[test]
    fn sah_collapse_costs_no_more_than_the_greedy_one() {
        let mut s = Sampler::from_seed(5);
        for count in [2usize, 9, 40, 500, 3000] {
            let (_, wide) = random_tree(&mut s, count);
            let (sah, greedy) = (sah_cost(&wide.closest), sah_cost(&wide.all));
            assert!(sah <= greedy * (1.0 + 1e-5), "{count} boxes: {sah} > {greedy}");
            if count >= 500 {
                assert!(sah < greedy * 0.999, "{count} boxes: {sah} against {greedy}");
                assert!(wide.closest.nodes.len() < wide.all.nodes.len());
            }
        }
    }

    /// The primitives under `x` (a node or a [`LEAF`]-tagged leaf) of `tree`.
    fn primitives_under(wide: &WideBvh, tree: &WideTree, x: u32, out: &mut Vec<u32>) {
        if x & LEAF != 0 {
            let (first, n) = wide.leaves[(x & !LEAF) as usize];
            out.extend(&wide.primitive_indices[first as usize..(first + n) as usize]);
            return;
        }
        let node = &tree.nodes[x as usize];
        for c in (0..WIDTH).filter(|&c| node.planes[0].lane(c) != f32::INFINITY) {
            primitives_under(wide, tree, node.children[c], out);
        }
    }

    /// Each child slot names the one shape of every primitive under it, or [`MIXED`] when they
    /// have several (empty slots too), in both trees; and [`WideNode::shape_mask`] flags exactly
    /// the slots of the shape asked for.
    #[test]
    fn child_slots_name_the_shape_of_their_subtree() {
        let mut s = Sampler::from_seed(12);
        let (mut single, mut mixed) = (0, 0);
        for count in [1usize, 7, 60, 3000] {
            let (boxes, wide) = random_tree(&mut s, count);
            for tree in [&wide.closest, &wide.all] {
                for node in &tree.nodes {
                    for c in 0..WIDTH {
                        let want = if node.planes[0].lane(c) == f32::INFINITY {
                            MIXED
                        } else {
                            let mut prims = Vec::new();
                            primitives_under(&wide, tree, node.children[c], &mut prims);
                            let shape = |&i: &u32| box_shape(i as usize, boxes[i as usize].center());
                            let first = shape(&prims[0]);
                            if prims.iter().all(|i| shape(i) == first) {
                                single += 1;
                                first
                            } else {
                                mixed += 1;
                                MIXED
                            }
                        };
                        assert_eq!(node.shapes[c], want, "{count} boxes, slot {c}");
                    }
                    for skip in [0, 1, 2] {
                        let flags = (0..WIDTH).filter(|&c| node.shapes[c] == skip).fold(0, |m, c| m | 1 << c);
                        assert_eq!(node.shape_mask(skip), flags);
                    }
                }
            }
        }
        assert!(single > 100 && mixed > 20, "{single} single-shape and {mixed} mixed slots");
    }

    /// Every primitive sits in exactly one leaf, leaves hold 1 to `LEAF_SIZE` primitives, and each
    /// child box encloses everything below it.
    #[test]
    fn collapse_keeps_every_primitive_once_inside_its_boxes() {
        let mut s = Sampler::from_seed(11);
        for count in [1usize, 3, 5, 9, 40, 3000] {
            let (boxes, wide) = random_tree(&mut s, count);
            for tree in [&wide.closest, &wide.all] {
                let mut seen = vec![0u32; count];
                // (node or leaf, box of its parent's slot)
                let mut work = vec![(0u32, Aabb::LARGEST)];
                while let Some((x, outer)) = work.pop() {
                    let inside = |b: &Aabb| b.min.cmpge(outer.min).all() && b.max.cmple(outer.max).all();
                    if x & LEAF != 0 {
                        let (first, n) = wide.leaves[(x & !LEAF) as usize];
                        assert!((1..=LEAF_SIZE).contains(&n), "{n}");
                        for &i in &wide.primitive_indices[first as usize..(first + n) as usize] {
                            seen[i as usize] += 1;
                            assert!(inside(&boxes[i as usize]));
                        }
                        continue;
                    }
                    let node = &tree.nodes[x as usize];
                    for c in 0..WIDTH {
                        let lane = |pl: usize| node.planes[pl].lane(c);
                        if lane(0) == f32::INFINITY {
                            continue;
                        }
                        let b = Aabb::new(
                            Vec3A::new(lane(0), lane(2), lane(4)),
                            Vec3A::new(lane(1), lane(3), lane(5)),
                        );
                        assert!(inside(&b));
                        work.push((node.children[c], b));
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "{count}: {seen:?}");
            }
        }
    }
}
