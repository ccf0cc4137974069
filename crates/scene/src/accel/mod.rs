//! Ray queries over all shapes: triangles of every mesh in one bounding volume hierarchy
//! (built by `obvhs`, chosen by measurement: docs/performance.md §3.1), tested with
//! a watertight triangle test; analytic spheres and disks tested directly (scenes have few of
//! them).
//!
//! obvhs builds a binary tree with leaves of up to 4 triangles; the 8-wide trees the traversal
//! reads and the traversal are ours (docs/performance.md §3.1, §3.2): [`wide`]
//! collapses the binary tree twice over the same leaves (one collapse for closest hits, one for
//! shadow rays: §3.1) into nodes of 8 f32 child boxes tested at once (in one
//! AVX2 vector per plane where the CPU has AVX2, detected when the `Accel` is built, else in two
//! SSE vectors: docs/performance.md §3.3), the loop
//! ([`Accel::traverse`]) visits the nearest hit child first and prunes pushed children by their
//! entry distance, and each leaf's 1-4 triangles are tested at once in SSE lanes
//! ([`WatertightRay::intersect_packet`], bit-identical to the scalar test).
//!
//! A watertight triangle test is not enough for a watertight traversal (issue 16, "the leak":
//! paths escaped closed cube rooms). Two things in the BVH lost hits, and both are handled here
//! rather than in obvhs:
//! - A ray-box test is not conservative: its slab distances carry rounding error, and a
//!   face of an axis-aligned mesh has a flat box (zero thickness), so a ray through an edge
//!   shared by two flat boxes could miss both. Every triangle's box is therefore padded by
//!   [`BOX_PAD`] times the largest coordinate in the scene (far more than the few ulps the
//!   slab test can be off, even with obvhs's clamped `1/d` for near-axis directions). The
//!   node boxes are the binary tree's, which enclose these padded boxes.
//! - obvhs's node test (used before our traversal, docs/performance.md §3.2) clamped the entry distance of every box to
//!   `1e-4` (`cwbvh::node::EPSILON`), so a box the ray leaves before `t = 1e-4` was skipped: a wall
//!   just in front of a point in a medium, or the adjacent wall at a corner. The traversal ray
//!   therefore starts [`ORIGIN_BACKOFF`] behind the real origin, and the triangle tests (from
//!   the real origin) report their distances in that shifted parametrisation. Our node test
//!   ([`wide::WideNode::intersect`]) starts boxes at `t = 0` of that ray; the back-off is kept
//!   as a second guard.
//!
//! Camera rays, which all leave the pinhole, are answered without the tree from a grid of leaf
//! lists over the film ([`CameraGrid`], `camera_grid.rs`).
//!
//! Coordinates whose magnitude the triangle test cannot handle are refused when the scene is
//! built ([`MAX_COORDINATE`]).

mod camera_grid;
mod watertight;
mod wide;

pub use camera_grid::CameraGrid;

pub use watertight::{PacketHits, TriPacket, TriSoa, WatertightRay};
use wide::{Avx2, NodeTest, WideBvh, WideTree, LEAF, LEAF_SIZE, WIDTH};

use crate::interaction::SurfaceInteraction;
use crate::shape::analytic::{disk_uv, intersect_disk, intersect_sphere, sphere_uv};
use crate::shape::{Geometry, Shape};
use glam::{Mat4, Vec2, Vec3, Vec3A};
use haze_core::Ray;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::mem::MaybeUninit;

/// Every triangle's BVH box grows by this times the largest coordinate magnitude in the scene,
/// on every side (see the module documentation). About 34 ulps: cheap in overlap, far more than
/// the rounding error of a slab test.
const BOX_PAD: f32 = 2e-6;

/// The traversal ray starts this far (in units of `t`; directions are unit length) behind the
/// real origin, twice obvhs's fixed box `tmin` of `1e-4`.
const ORIGIN_BACKOFF: f32 = 2e-4;

/// Largest coordinate magnitude of scene geometry haze accepts. obvhs's compressed wide BVH
/// (traversed before our own wide trees, docs/performance.md §3.1) stored node boxes with an 8-bit exponent and
/// panicked on a cube scaled by `1e30`. The watertight triangle test multiplies
/// three coordinate differences, which overflows f32 beyond about `7e12`; rays then pass
/// through walls. `1e12` keeps every product finite for rays within the scene.
pub const MAX_COORDINATE: f32 = 1e12;

/// A triangle with the shape and primitive it came from, while the BVH is built.
#[derive(Clone, Copy, Debug)]
struct TriRef {
    /// The vertices, transposed for [`WatertightRay::intersect_soa`].
    v: TriSoa,
    shape: u32,
    prim: u32,
    /// The unit face normal, flipped as the mesh says (`TriangleMesh::face_normal`).
    n: Vec3,
    /// The shape stops shadow rays (neither `null` nor a thin dielectric, see
    /// [`Accel::shadow_hits`]).
    blocks: bool,
}

/// Where a triangle of a leaf came from.
#[derive(Clone, Copy, Debug, Default)]
struct TriId {
    shape: u32,
    prim: u32,
}

/// A surface a shadow ray passes through (see [`Accel::shadow_hits`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadowHit {
    pub t: f32,
    /// The leaf's index times 4 plus the triangle's lane in it.
    tri: u32,
    b1: f32,
    b2: f32,
}

/// A shape a ray cannot hit, or none: a ray that leaves a face of a mesh whose triangles all lie
/// behind that face's plane, away from the ray (a convex mesh left outwards, a flat one left on
/// either side: `Scene::leaving`, `shape/convex.rs`), cannot meet the mesh again. Queries given
/// one skip every subtree of that shape's triangles without testing its boxes
/// ([`wide::WideNode::shapes`]); the answer is the same, for fewer node visits and leaf tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leaving(u32);

/// [`Leaving::NONE`]'s id: neither a shape's index nor [`wide::MIXED`].
const NO_SHAPE: u32 = u32::MAX - 1;

impl Leaving {
    /// Nothing to skip.
    pub const NONE: Leaving = Leaving(NO_SHAPE);

    /// The ray cannot hit mesh `shape` (the caller's guarantee).
    pub fn shape(shape: u32) -> Self {
        debug_assert!(shape < NO_SHAPE);
        Leaving(shape)
    }
}

/// Most surfaces [`Accel::probe`] collects.
pub const MAX_PROBE_HITS: usize = 8;

/// A surface crossed by [`Accel::probe`]'s segment: its distance, shape and geometric normal,
/// and the hit for [`Accel::interaction`].
#[derive(Clone, Copy, Debug)]
pub struct ProbeHit {
    pub t: f32,
    pub shape: u32,
    pub n: Vec3,
    pub hit: PreliminaryHit,
}

impl ProbeHit {
    /// A placeholder for the slots of an output array.
    pub const EMPTY: ProbeHit = ProbeHit {
        t: 0.0,
        shape: 0,
        n: Vec3::ZERO,
        hit: PreliminaryHit(Hit::Triangle { leaf: 0, lane: 0, t: 0.0, b1: 0.0, b2: 0.0 }),
    };
}

/// Most pass-through surfaces [`Accel::shadow_hits`] collects before it gives up.
pub const MAX_SHADOW_HITS: usize = 8;

/// The closest hit of a ray before its surface interaction is built
/// ([`Accel::intersect_preliminary`]); [`Accel::interaction`] completes it.
#[derive(Clone, Copy, Debug)]
pub struct PreliminaryHit(Hit);

#[derive(Clone, Copy, Debug)]
enum Hit {
    /// A triangle: its leaf, lane, distance and barycentrics.
    Triangle { leaf: u32, lane: u32, t: f32, b1: f32, b2: f32 },
    /// An analytic sphere or disk, whose interaction comes with its test.
    Done(SurfaceInteraction),
}

impl PreliminaryHit {
    /// Distance along the ray.
    #[inline]
    pub fn t(&self) -> f32 {
        match self.0 {
            Hit::Triangle { t, .. } => t,
            Hit::Done(si) => si.t,
        }
    }
}

/// Outcome of [`Accel::shadow_hits`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowQuery {
    /// A blocking surface lies on the ray (the traversal stopped at the first one found).
    Blocked,
    /// Nothing blocks; this many pass-through hits were stored, in no particular order.
    Clear(usize),
    /// The ray needs the general answer: more than [`MAX_SHADOW_HITS`] pass-through surfaces,
    /// or an analytic shape that does not block (its second intersection is not collected).
    Unsupported,
}

#[derive(Clone, Debug)]
enum Analytic {
    Sphere { shape: u32, center: Vec3, radius: f32, flip: bool },
    Disk { shape: u32, to_world: Mat4, inv: Mat4, normal: Vec3 },
}

/// A pushed child of the traversal: a node or [`LEAF`]-tagged leaf, and where the ray enters
/// its box.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    node: u32,
    t: f32,
}

/// Entries of the traversal's fixed stack; trees that may need more get one of their size
/// ([`WideBvh::stack_need`]).
const STACK: usize = 64;

/// Triangle hits closer than this to the ray origin are ignored. Rays leaving a surface start
/// at an offset origin (`haze_core::ray::offset_origin`), so this only has to exclude hits at
/// the origin itself.
const T_MIN: f32 = 0.0;

/// A distance `t` from the real origin as a distance along the traversal ray, rounded up so
/// that the traversal never prunes a box that holds a hit at `t`.
fn shifted(t: f32) -> f32 {
    (t + ORIGIN_BACKOFF) * (1.0 + 4.0 * f32::EPSILON)
}

/// How far [`pull_inside`] moves a hit point, relative to its largest coordinate (about 30 f32
/// spacings).
const PULL_INSIDE: f32 = 4e-6;

/// Moves a hit point `p` on triangle `v` towards the triangle's centroid by about
/// `PULL_INSIDE (1 + |p|)` (at most half way). A hit at an edge, rounded, can lie on or past
/// the plane of the adjacent face; offset along its own normal only
/// ([`haze_core::ray::offset_origin`]) it would then start the next ray on or outside that face,
/// and at the inside corner of a closed room the ray leaves the room. Pulled inside its own
/// triangle, the point is clear of every other face's plane by many spacings.
fn pull_inside(p: Vec3, v: [Vec3; 3]) -> Vec3 {
    let to_centroid = (v[0] + v[1] + v[2]) / 3.0 - p;
    let len = to_centroid.length();
    let step = PULL_INSIDE * (1.0 + p.abs().max_element());
    if len > 0.0 && len.is_finite() {
        p + to_centroid * (step / len).min(0.5)
    } else {
        p
    }
}

/// The hit of the analytic shape `a` in `(0, ray.t_max)`, with its interaction.
#[inline(always)]
fn analytic_hit(a: &Analytic, ray: &Ray) -> Option<PreliminaryHit> {
    match a {
        Analytic::Sphere { shape, center, radius, flip } => {
            let t = intersect_sphere(ray, *center, *radius)?;
            let p = ray.at(t);
            let n = (p - *center).normalize();
            let n = if *flip { -n } else { n };
            let uv = sphere_uv(n);
            Some(PreliminaryHit(Hit::Done(SurfaceInteraction {
                t,
                p,
                n,
                ns: n,
                uv,
                shape: *shape,
                prim: 0,
                bary: Vec2::ZERO,
            })))
        }
        Analytic::Disk { shape, to_world, inv, normal } => {
            let (t, local) = intersect_disk(ray, to_world, inv)?;
            let uv = disk_uv(local);
            Some(PreliminaryHit(Hit::Done(SurfaceInteraction {
                t,
                p: ray.at(t),
                n: *normal,
                ns: *normal,
                uv,
                shape: *shape,
                prim: 0,
                bary: Vec2::ZERO,
            })))
        }
    }
}

/// Asks the CPU to bring `x`'s two cache lines (a [`LeafIds`]) into L1; no-op elsewhere.
#[inline(always)]
fn prefetch(x: &LeafIds) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = (x as *const LeafIds).cast::<i8>();
        // SAFETY: a prefetch is a hint; it never faults, and both addresses are inside `x`.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.add(64));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// A BVH leaf as the traversal reads it: its triangles transposed for
/// [`WatertightRay::intersect_packet`] and which of them block shadow rays (176 bytes on
/// x86-64). Where each triangle came from is in [`LeafIds`], read once per query for the hit:
/// with the ids and normals in the leaf (256 bytes) every leaf test touched lines of a larger
/// array, and the queries were slower although the hit's ids then came without a cache miss
/// (docs/performance.md §3.1: roughdielectric_spot -5..-7.5%, the rooms -1..-1.6%).
#[derive(Clone, Copy, Debug)]
struct Leaf {
    packet: TriPacket,
    /// Bit `i` set when triangle `i` stops shadow rays ([`TriRef::blocks`]).
    blocks: u32,
}

/// Where the triangles of the leaf with the same index came from: two cache lines, which the
/// closest-hit query prefetches when it finds a hit, so that the surface interaction built
/// after it (often at once) does not wait for them.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct LeafIds {
    ids: [TriId; 4],
    /// Each triangle's [`TriRef::n`], computed once at build: normalising it per hit (a square
    /// root and a division in the chain that ends the query) was a few percent of hg-box.
    normals: [Vec3; 4],
    /// Each triangle's vertex indices in its mesh (for vertex normals and uvs), copied here so
    /// that the interaction's loads of those do not wait for a load of the mesh's index array.
    indices: [[u32; 3]; 4],
}

// `prefetch` fetches exactly two lines.
const _: () = assert!(std::mem::size_of::<LeafIds>() == 128);

/// `$body` with `$k` bound to the query's node-test kernel. The kernel is chosen once per query,
/// not per node: with AVX2 the whole query, its traversal loop and leaf tests included, runs
/// inside one AVX2-enabled function (`Avx2::run`); otherwise with the portable `wide::Sse`.
macro_rules! with_kernel {
    ($accel:ident, $k:ident => $body:expr) => {
        match $accel.avx2 {
            Some($k) => $k.run(
                #[inline(always)]
                || $body,
            ),
            None => {
                let $k = wide::Sse;
                $body
            }
        }
    };
}

pub struct Accel {
    /// The wide tree collapsed from obvhs's binary tree ([`wide`]): what traversal reads.
    bvh: Option<WideBvh>,
    /// Every BVH leaf's triangles as one packet, in [`WideBvh::leaves`]' order.
    leaves: Vec<Leaf>,
    /// [`LeafIds`] of each of `leaves`.
    leaf_ids: Vec<LeafIds>,
    analytic: Vec<Analytic>,
    lo: Vec3,
    hi: Vec3,
    /// The 8-lane AVX2 node test when the CPU has it ([`Avx2::detect`]), else the portable one.
    avx2: Option<Avx2>,
}

/// BVH build settings: obvhs' `slow_build` (wider PLOC search, more reinsertion: a tree that
/// traverses faster) up to a million triangles, and `medium_build` above. Without pre-splitting
/// in both: a split triangle would sit in several leaves, and [`Accel::shadow_hits`] must see
/// each surface once. Leaves of up to [`LEAF_SIZE`] triangles (one packet), merged by obvhs's
/// SAH leaf collapse with a node traversal cost of 2 triangle tests: obvhs's default 3 made
/// leaves of four large wall triangles in the room scenes, whose box every ray enters (foggy-room
/// and bench-fog-shadow 13-15% slower than with 2; 1 and 0.5 measured like 2 there and 2-7%
/// slower than 3 on the peer spheres; docs/performance.md §3.1).
fn build_params(triangles: usize) -> BvhBuildParams {
    let mut p =
        if triangles <= 1_000_000 { BvhBuildParams::slow_build() } else { BvhBuildParams::medium_build() };
    if triangles <= 1_000_000 {
        // PLOC's full search at every depth (`slow_build` searches only 1 neighbour in the top
        // levels) over 32 neighbours instead of 24: on the rays logged from the peer renders,
        // 7-10% faster closest hits inside the glass spheres (docs/performance.md §3.1), for
        // +0.1-0.2 s of build at 400k triangles.
        p.search_depth_threshold = 0;
        p.ploc_search_distance = obvhs::ploc::PlocSearchDistance::VeryHigh;
    }
    p.pre_split = false;
    p.max_prims_per_leaf = LEAF_SIZE;
    p.collapse_traversal_cost = 2.0;
    p
}

/// One [`Leaf`] per leaf of `bvh`, in its order: `tris` are the triangles in the order of
/// `bvh.primitive_indices`, which the leaf runs index.
fn leaf_packets(bvh: &WideBvh, tris: &[TriRef], shapes: &[Shape]) -> (Vec<Leaf>, Vec<LeafIds>) {
    let indices = |t: &TriRef| match &shapes[t.shape as usize].geometry {
        Geometry::Mesh(m) => m.indices[t.prim as usize],
        _ => unreachable!("triangles come from meshes"),
    };
    bvh.leaves
        .iter()
        .map(|&(first, count)| {
            let run = &tris[first as usize..(first + count) as usize];
            let soa: Vec<TriSoa> = run.iter().map(|t| t.v).collect();
            let blocks = run.iter().enumerate().fold(0, |m, (lane, t)| m | u32::from(t.blocks) << lane);
            let ids = std::array::from_fn(|lane| {
                run.get(lane).map_or(TriId::default(), |t| TriId { shape: t.shape, prim: t.prim })
            });
            let normals = std::array::from_fn(|lane| run.get(lane).map_or(Vec3::ZERO, |t| t.n));
            let indices = std::array::from_fn(|lane| run.get(lane).map_or([0; 3], indices));
            (Leaf { packet: TriPacket::new(&soa), blocks }, LeafIds { ids, normals, indices })
        })
        .collect()
}

/// `ray`, read one `f32` at a time (volatile loads, which the compiler does not merge into
/// vector loads): see [`Accel::intersect_preliminary`].
#[inline(always)]
fn ray_by_fields(ray: &Ray) -> Ray {
    // SAFETY: each pointer comes from a reference to an initialised, aligned f32 field.
    let f = |x: &f32| unsafe { std::ptr::read_volatile(x) };
    Ray {
        o: Vec3::new(f(&ray.o.x), f(&ray.o.y), f(&ray.o.z)),
        d: Vec3::new(f(&ray.d.x), f(&ray.d.y), f(&ray.d.z)),
        t_max: f(&ray.t_max),
    }
}

impl Accel {
    pub fn build(shapes: &[Shape]) -> Self {
        let mut flat = Vec::new();
        let mut refs = Vec::new();
        let mut analytic = Vec::new();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (si, s) in shapes.iter().enumerate() {
            match &s.geometry {
                Geometry::Mesh(m) => {
                    for i in 0..m.indices.len() {
                        let [a, b, c] = m.vertices(i);
                        for p in [a, b, c] {
                            lo = lo.min(p);
                            hi = hi.max(p);
                        }
                        flat.push(Triangle { v0: a.into(), v1: b.into(), v2: c.into() });
                        refs.push(TriRef {
                            v: TriSoa::new(a.into(), b.into(), c.into()),
                            shape: si as u32,
                            prim: i as u32,
                            n: m.face_normal(i),
                            blocks: s.blocks_shadow_rays(),
                        });
                    }
                }
                Geometry::Sphere { center, radius, flip_normals } => {
                    lo = lo.min(*center - Vec3::splat(*radius));
                    hi = hi.max(*center + Vec3::splat(*radius));
                    analytic.push(Analytic::Sphere {
                        shape: si as u32,
                        center: *center,
                        radius: *radius,
                        flip: *flip_normals,
                    });
                }
                Geometry::Disk { to_world, flip_normals } => {
                    let ex = to_world.transform_vector3(Vec3::X);
                    let ey = to_world.transform_vector3(Vec3::Y);
                    let o = to_world.transform_point3(Vec3::ZERO);
                    for p in [o + ex + ey, o - ex - ey, o + ex - ey, o - ex + ey] {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    let n = ex.cross(ey).normalize();
                    analytic.push(Analytic::Disk {
                        shape: si as u32,
                        to_world: *to_world,
                        inv: to_world.inverse(),
                        normal: if *flip_normals { -n } else { n },
                    });
                }
            }
        }
        let (bvh, (leaves, leaf_ids)) = if flat.is_empty() {
            (None, (Vec::new(), Vec::new()))
        } else {
            let magnitude = flat
                .iter()
                .map(|t| t.v0.abs().max(t.v1.abs()).max(t.v2.abs()).max_element())
                .fold(0.0f32, f32::max);
            let pad = Vec3A::splat(BOX_PAD * magnitude + f32::MIN_POSITIVE);
            let boxes: Vec<Aabb> = flat
                .iter()
                .map(|t| {
                    let b = t.aabb();
                    Aabb::new(b.min - pad, b.max + pad)
                })
                .collect();
            let prim_shape: Vec<u32> = refs.iter().map(|t| t.shape).collect();
            let wide = WideBvh::new(
                build_bvh2(&boxes, build_params(flat.len()), &mut Default::default()),
                &prim_shape,
            );
            let tris: Vec<TriRef> = wide.primitive_indices.iter().map(|&i| refs[i as usize]).collect();
            let leaves = leaf_packets(&wide, &tris, shapes);
            (Some(wide), leaves)
        };
        Accel { bvh, leaves, leaf_ids, analytic, lo, hi, avx2: Avx2::detect() }
    }

    /// Front-to-back traversal of the decoded nodes for the traversal ray from `o` along `d`
    /// (the backed-off origin, see the module documentation) up to `t_max`, skipping the subtrees
    /// of the shape `leaving` names ([`Leaving`]). `test(leaf, t_max)`
    /// tests the triangles of a leaf the ray reaches and returns the new `t_max` in the
    /// traversal's parametrisation (below the old one for a closer hit), or `None` to end the
    /// traversal.
    ///
    /// The nearest hit child of a node is visited first, the others kept on a stack with their
    /// entry distance and skipped when popped beyond the current `t_max` (after Embree, Wald et
    /// al. 2014, "Embree: A Kernel Framework for Efficient CPU Ray Tracing", section 4.2, which
    /// sorts all hit children). obvhs's `traverse!` instead visits children in an order fixed
    /// per ray octant and cannot prune a pushed group by distance, so a closest-hit ray tested
    /// boxes and leaves behind its hit (docs/performance.md §3.2).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn traverse<const ORDERED: bool, K: NodeTest>(
        &self,
        kernel: K,
        wide: &WideTree,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        leaving: Leaving,
        test: impl FnMut(u32, &Leaf, f32) -> Option<f32>,
    ) {
        // Uninitialised: zeroing the 512-byte stack cost a `memset` call per query (2.5% of
        // hg-box's CPU samples); the loop reads only entries below `sp`, which it wrote.
        let mut small = [const { MaybeUninit::<Entry>::uninit() }; STACK];
        let mut large = Vec::new();
        let stack: &mut [MaybeUninit<Entry>] = if wide.stack_need <= STACK {
            &mut small
        } else {
            // A degenerate tree (deeper than any scene measured needs): a stack of its size.
            large.resize(wide.stack_need.min(wide.nodes.len() * WIDTH + 1), MaybeUninit::uninit());
            &mut large
        };
        // One call site per kernel, so that `test` is inlined into the loop. The leaf tests
        // (and `Avx2::run`'s closures) are `#[inline(always)]`: compiled into both kernels'
        // copies of the loop, rustc otherwise left them out of line (the binary's symbols),
        // and then out of the AVX2 function.
        self.traverse_with::<ORDERED, K>(kernel, wide, o, d, t_max, leaving, stack, test);
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn traverse_with<const ORDERED: bool, K: NodeTest>(
        &self,
        kernel: K,
        wide: &WideTree,
        o: Vec3A,
        d: Vec3A,
        mut t_max: f32,
        leaving: Leaving,
        stack: &mut [MaybeUninit<Entry>],
        mut test: impl FnMut(u32, &Leaf, f32) -> Option<f32>,
    ) {
        let inv = wide::inverse_direction(d);
        let ray = kernel.ray(o, inv, 0.0);
        // Entries `0..sp` are always initialised: each push writes `stack[sp]` before `sp`
        // grows, and every read below is of an index `< sp` (or `== sp` just after a push).
        let read = |stack: &[MaybeUninit<Entry>], i: usize| {
            // SAFETY: `i` is below the count of entries written (the invariant above).
            unsafe { stack[i].assume_init() }
        };
        let mut sp = 0usize;
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                let leaf = cur & !LEAF;
                match test(leaf, &self.leaves[leaf as usize], t_max) {
                    Some(t) => t_max = t,
                    None => return,
                }
            } else {
                let node = &wide.nodes[cur as usize];
                let (mut mask, t_near) = kernel.intersect(node, &ray, t_max);
                if leaving != Leaving::NONE {
                    mask &= !node.shape_mask(leaving.0);
                }
                if mask != 0 {
                    let c = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = node.children[c];
                        continue;
                    }
                    // Exactly two: the farther pushed, the nearer taken, the choice the general
                    // case below makes, without its loop (Embree's `traverseClosestHit` special
                    // case; 2% fewer ns per query on the rays replayed from the glass peers).
                    if ORDERED && mask & (mask - 1) == 0 {
                        let c2 = mask.trailing_zeros() as usize;
                        let (near, far) = if t_near[c2] < t_near[c] { (c2, c) } else { (c, c2) };
                        stack[sp] = MaybeUninit::new(Entry { node: node.children[far], t: t_near[far] });
                        sp += 1;
                        cur = node.children[near];
                        continue;
                    }
                    // Two or more hit children: onto the stack, the nearest swapped to the top
                    // and taken next. The others are popped in any order but each still
                    // pruned by its entry distance (a full insertion sort cost more in branch
                    // mispredictions than it saved in visits, measured).
                    let mut best = sp;
                    let mut best_t = t_near[c];
                    stack[sp] = MaybeUninit::new(Entry { node: node.children[c], t: best_t });
                    sp += 1;
                    while mask != 0 {
                        let c = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let t = t_near[c];
                        stack[sp] = MaybeUninit::new(Entry { node: node.children[c], t });
                        if ORDERED && t < best_t {
                            best = sp;
                            best_t = t;
                        }
                        sp += 1;
                    }
                    sp -= 1;
                    cur = read(stack, best).node;
                    stack[best] = stack[sp];
                    continue;
                }
            }
            // Next: the nearest pushed child still in front of the closest hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let e = read(stack, sp);
                if !ORDERED || e.t <= t_max {
                    cur = e.node;
                    break;
                }
            }
        }
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    /// Closest hit with `t` in `(0, ray.t_max)`, as a complete surface interaction.
    pub fn intersect(&self, shapes: &[Shape], ray: &Ray) -> Option<SurfaceInteraction> {
        self.intersect_preliminary(ray).map(|h| self.interaction(shapes, &h))
    }

    /// The closest hit of [`Self::intersect`], with only its distance computed: the rest
    /// ([`Self::interaction`]: hit point, normals, uv) waits until the caller knows it needs
    /// the surface. A path in a medium mostly scatters before the surface it would hit, and
    /// then the interaction is never built (Mitsuba 3 splits its queries the same way,
    /// `PreliminaryIntersection` and `compute_surface_interaction`).
    pub fn intersect_preliminary(&self, ray: &Ray) -> Option<PreliminaryHit> {
        // Its callers (a camera ray's first query among them: one per path) mostly write the
        // ray just before the call, in pieces of the compiler's choosing; a vector load that
        // spans two of those stores cannot be forwarded from them and waits until both reach
        // the cache. Read component by component, every load lies inside one store. Measured:
        // `volpath` on bench-fog-shadow (4.2 M short paths) ran about 2% slower otherwise.
        let ray = ray_by_fields(ray);
        with_kernel!(self, k => self.intersect_with(k, &ray, Leaving::NONE))
    }

    /// [`Self::intersect_preliminary`] for a ray that cannot hit the shape `leaving` names: the
    /// same answer, without visiting that shape's subtrees. Always inlined: this is the query
    /// of every walk's legs after the first (`haze_render::walker`), and compiled into each
    /// walker's loop it keeps the ray in registers (out of line, with four walks calling it,
    /// `volpath` ran about 3% slower on short paths).
    #[inline(always)]
    pub fn intersect_preliminary_leaving(&self, ray: &Ray, leaving: Leaving) -> Option<PreliminaryHit> {
        with_kernel!(self, k => self.intersect_with(k, ray, leaving))
    }

    #[inline(always)]
    fn intersect_with<K: NodeTest>(&self, kernel: K, ray: &Ray, leaving: Leaving) -> Option<PreliminaryHit> {
        // The closest hit so far and its distance, in the real parametrisation; the traversal
        // only sees the shifted distances, for pruning.
        let mut t_max = ray.t_max;
        let mut best: Option<PreliminaryHit> = None;
        if let Some(bvh) = &self.bvh {
            let o: Vec3A = ray.o.into();
            let d: Vec3A = ray.d.into();
            // Prepared on the first triangle test: most connection and shadow rays in media
            // test no triangle at all, only node boxes.
            let mut wt: Option<WatertightRay> = None;
            self.traverse::<true, K>(
                kernel,
                &bvh.closest,
                o - d * ORIGIN_BACKOFF,
                d,
                shifted(t_max),
                leaving,
                #[inline(always)]
                |index, leaf, shifted_max| {
                    let wt = wt.get_or_insert_with(|| WatertightRay::new(o, d));
                    Some(match self.leaf_hit(wt, index, leaf, t_max) {
                        Some(h) => {
                            t_max = h.t();
                            best = Some(h);
                            shifted(t_max)
                        }
                        None => shifted_max,
                    })
                },
            );
        }
        self.closest_analytic(ray, t_max, best)
    }

    /// [`Self::intersect_preliminary`] for a ray from the camera's pinhole, from `grid`'s list of
    /// the ray's cell ([`CameraGrid`], the same answer); rays the grid cannot answer go through
    /// the tree.
    pub fn intersect_camera(&self, grid: &CameraGrid, ray: &Ray) -> Option<PreliminaryHit> {
        let Some((list, from_apex)) = grid.list(ray) else {
            return self.intersect_preliminary(ray);
        };
        // Prepared on the first triangle test: a flight cut short in a medium often ends
        // before the first leaf.
        let mut wt: Option<WatertightRay> = None;
        let mut t_max = ray.t_max;
        let mut best: Option<PreliminaryHit> = None;
        for &(leaf, near) in list {
            // No point of this leaf or the ones after it lies closer than `near` to the pinhole,
            // and the ray's points before `t_max` lie within `from_apex + t_max` of it.
            if near > from_apex + t_max {
                break;
            }
            let wt = wt.get_or_insert_with(|| WatertightRay::new(ray.o.into(), ray.d.into()));
            if let Some(h) = self.leaf_hit(wt, leaf, &self.leaves[leaf as usize], t_max) {
                t_max = h.t();
                best = Some(h);
            }
        }
        self.closest_analytic(ray, t_max, best)
    }

    /// The closest hit among the triangles of `leaf` (number `index`) before `t_max`, if any;
    /// the leaf's ids are prefetched for the surface interaction that often follows.
    #[inline(always)]
    fn leaf_hit(&self, wt: &WatertightRay, index: u32, leaf: &Leaf, t_max: f32) -> Option<PreliminaryHit> {
        let hits = wt.intersect_packet(&leaf.packet, T_MIN, t_max);
        let lane = hits.closest()?;
        prefetch(&self.leaf_ids[index as usize]);
        let (b1, b2) = hits.barycentrics(lane);
        Some(PreliminaryHit(Hit::Triangle { leaf: index, lane: lane as u32, t: hits.t[lane], b1, b2 }))
    }

    /// The closest of `best` (the closest triangle hit, at `t_max`, if any) and the analytic
    /// shapes' hits before `t_max`.
    #[inline(always)]
    fn closest_analytic(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut best: Option<PreliminaryHit>,
    ) -> Option<PreliminaryHit> {
        for a in &self.analytic {
            if let Some(h) = analytic_hit(a, &Ray { t_max, ..*ray }) {
                t_max = h.t();
                best = Some(h);
            }
        }
        best
    }

    /// The complete surface interaction of a hit from [`Self::intersect_preliminary`].
    #[inline]
    pub fn interaction(&self, shapes: &[Shape], h: &PreliminaryHit) -> SurfaceInteraction {
        match h.0 {
            Hit::Triangle { leaf, lane, t, b1, b2 } => {
                self.triangle_interaction(shapes, leaf, lane as usize, t, b1, b2)
            }
            Hit::Done(si) => si,
        }
    }

    fn triangle_interaction(
        &self,
        shapes: &[Shape],
        leaf: u32,
        lane: usize,
        t: f32,
        b1: f32,
        b2: f32,
    ) -> SurfaceInteraction {
        let ids = &self.leaf_ids[leaf as usize];
        let leaf = &self.leaves[leaf as usize];
        let tri = ids.ids[lane];
        let Geometry::Mesh(m) = &shapes[tri.shape as usize].geometry else {
            unreachable!("triangles come from meshes")
        };
        let b0 = 1.0 - b1 - b2;
        let v = leaf.packet.triangle(lane);
        let [v0, v1, v2] = [0, 1, 2].map(|j| Vec3::from(v.vertex(j)));
        // Barycentric interpolation is more precise than o + t d far from the origin.
        let p = pull_inside(v0 * b0 + v1 * b1 + v2 * b2, [v0, v1, v2]);
        let n = ids.normals[lane];
        let idx = || ids.indices[lane].map(|i| i as usize);
        let ns = match &m.normals {
            Some(ns) => {
                let idx = idx();
                let s = (ns[idx[0]] * b0 + ns[idx[1]] * b1 + ns[idx[2]] * b2).normalize_or_zero();
                let s = if m.flip_normals { -s } else { s };
                if s == Vec3::ZERO {
                    n
                } else {
                    s
                }
            }
            None => n,
        };
        let uv = match &m.uvs {
            Some(uv) => {
                let idx = idx();
                uv[idx[0]] * b0 + uv[idx[1]] * b1 + uv[idx[2]] * b2
            }
            None => Vec2::new(b1, b2),
        };
        SurfaceInteraction { t, p, n, ns, uv, shape: tri.shape, prim: tri.prim, bary: Vec2::new(b1, b2) }
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        with_kernel!(self, k => self.occluded_with(k, ray))
    }

    #[inline(always)]
    fn occluded_with<K: NodeTest>(&self, kernel: K, ray: &Ray) -> bool {
        if let Some(bvh) = &self.bvh {
            let o: Vec3A = ray.o.into();
            let d: Vec3A = ray.d.into();
            let mut wt: Option<WatertightRay> = None;
            let mut blocked = false;
            self.traverse::<false, K>(
                kernel,
                &bvh.all,
                o - d * ORIGIN_BACKOFF,
                d,
                shifted(ray.t_max),
                Leaving::NONE,
                #[inline(always)]
                |_, leaf, shifted_max| {
                    let wt = wt.get_or_insert_with(|| WatertightRay::new(o, d));
                    if wt.intersect_packet(&leaf.packet, T_MIN, ray.t_max).mask != 0 {
                        blocked = true;
                        None
                    } else {
                        Some(shifted_max)
                    }
                },
            );
            if blocked {
                return true;
            }
        }
        self.analytic.iter().any(|a| match a {
            Analytic::Sphere { center, radius, .. } => intersect_sphere(ray, *center, *radius).is_some(),
            Analytic::Disk { to_world, inv, .. } => intersect_disk(ray, to_world, inv).is_some(),
        })
    }

    /// One traversal for a shadow ray: stops at the first blocking surface (any hit, in whatever
    /// order the BVH meets it), otherwise stores every pass-through surface (`null`, thin
    /// dielectric) within `(0, ray.t_max)` in `hits`. With the surfaces in `t` order, a shadow
    /// ray through null boundaries then costs one traversal instead of one per boundary.
    pub fn shadow_hits(
        &self,
        shapes: &[Shape],
        ray: &Ray,
        hits: &mut [ShadowHit; MAX_SHADOW_HITS],
    ) -> ShadowQuery {
        self.shadow_hits_leaving(shapes, ray, Leaving::NONE, hits)
    }

    /// [`Self::shadow_hits`] for a ray that cannot hit the shape `leaving` names: the same
    /// answer, without visiting that shape's subtrees.
    pub fn shadow_hits_leaving(
        &self,
        shapes: &[Shape],
        ray: &Ray,
        leaving: Leaving,
        hits: &mut [ShadowHit; MAX_SHADOW_HITS],
    ) -> ShadowQuery {
        with_kernel!(self, k => self.shadow_hits_with(k, shapes, ray, leaving, hits))
    }

    #[inline(always)]
    fn shadow_hits_with<K: NodeTest>(
        &self,
        kernel: K,
        shapes: &[Shape],
        ray: &Ray,
        leaving: Leaving,
        hits: &mut [ShadowHit; MAX_SHADOW_HITS],
    ) -> ShadowQuery {
        for a in &self.analytic {
            let (shape, t) = match a {
                Analytic::Sphere { shape, center, radius, .. } => {
                    (*shape, intersect_sphere(ray, *center, *radius))
                }
                Analytic::Disk { shape, to_world, inv, .. } => {
                    (*shape, intersect_disk(ray, to_world, inv).map(|h| h.0))
                }
            };
            if !shapes[shape as usize].blocks_shadow_rays() {
                return ShadowQuery::Unsupported;
            }
            if t.is_some() {
                return ShadowQuery::Blocked;
            }
        }
        let Some(bvh) = &self.bvh else { return ShadowQuery::Clear(0) };
        let o: Vec3A = ray.o.into();
        let d: Vec3A = ray.d.into();
        let mut wt: Option<WatertightRay> = None;
        let (mut n, mut overflow) = (0usize, false);
        let mut blocked = false;
        // The same back-off and real-parametrisation tests as `intersect` and `occluded` (the
        // closed-room leak: obvhs skips boxes the ray leaves before its t = 1e-4).
        self.traverse::<false, K>(
            kernel,
            &bvh.all,
            o - d * ORIGIN_BACKOFF,
            d,
            shifted(ray.t_max),
            leaving,
            #[inline(always)]
            |index, leaf, shifted_max| {
                let wt = wt.get_or_insert_with(|| WatertightRay::new(o, d));
                let found = wt.intersect_packet(&leaf.packet, T_MIN, ray.t_max);
                let mut m = found.mask;
                while m != 0 {
                    let lane = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let blocks = leaf.blocks & (1 << lane) != 0;
                    if blocks || n == MAX_SHADOW_HITS {
                        overflow = !blocks;
                        blocked = true;
                        return None;
                    }
                    let (b1, b2) = found.barycentrics(lane);
                    hits[n] = ShadowHit { t: found.t[lane], tri: index * 4 + lane as u32, b1, b2 };
                    n += 1;
                }
                Some(shifted_max)
            },
        );
        match (blocked, overflow) {
            (false, _) => ShadowQuery::Clear(n),
            (true, false) => ShadowQuery::Blocked,
            (true, true) => ShadowQuery::Unsupported,
        }
    }

    /// The surface interaction of a hit from [`Self::shadow_hits`].
    pub fn shadow_interaction(&self, shapes: &[Shape], h: &ShadowHit) -> SurfaceInteraction {
        self.triangle_interaction(shapes, h.tri / 4, (h.tri % 4) as usize, h.t, h.b1, h.b2)
    }

    /// The shape and geometric normal of a hit from [`Self::shadow_hits`]: all a shadow ray
    /// needs to cross a `null` surface (the medium it enters), read from the leaf without the
    /// hit point, shading normal and uv of [`Self::shadow_interaction`] (`n` is the same vector).
    pub fn shadow_crossing(&self, h: &ShadowHit) -> (u32, Vec3) {
        let ids = &self.leaf_ids[(h.tri / 4) as usize];
        let lane = (h.tri % 4) as usize;
        (ids.ids[lane].shape, ids.normals[lane])
    }

    /// The primitive (triangle index in its mesh) of a hit from [`Self::shadow_hits`].
    pub fn shadow_prim(&self, h: &ShadowHit) -> u32 {
        self.leaf_ids[(h.tri / 4) as usize].ids[(h.tri % 4) as usize].prim
    }

    /// Every surface the short segment `ray` (`t` in `(0, ray.t_max)`) crosses, blocking or
    /// not, up to [`MAX_PROBE_HITS`] (the rest are dropped), in no particular order: how
    /// `Scene::boundary_at` finds the surfaces that touch at a point
    /// (`crate::coincident`). Returns how many were stored.
    pub fn probe(&self, ray: &Ray, out: &mut [ProbeHit; MAX_PROBE_HITS]) -> usize {
        with_kernel!(self, k => self.probe_with(k, ray, out))
    }

    #[inline(always)]
    fn probe_with<K: NodeTest>(&self, kernel: K, ray: &Ray, out: &mut [ProbeHit; MAX_PROBE_HITS]) -> usize {
        let mut n = 0usize;
        if let Some(bvh) = &self.bvh {
            let o: Vec3A = ray.o.into();
            let d: Vec3A = ray.d.into();
            let mut wt: Option<WatertightRay> = None;
            self.traverse::<false, K>(
                kernel,
                &bvh.all,
                o - d * ORIGIN_BACKOFF,
                d,
                shifted(ray.t_max),
                Leaving::NONE,
                #[inline(always)]
                |index, leaf, shifted_max| {
                    let wt = wt.get_or_insert_with(|| WatertightRay::new(o, d));
                    let found = wt.intersect_packet(&leaf.packet, T_MIN, ray.t_max);
                    let mut m = found.mask;
                    while m != 0 && n < MAX_PROBE_HITS {
                        let lane = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let (b1, b2) = found.barycentrics(lane);
                        let ids = &self.leaf_ids[index as usize];
                        out[n] = ProbeHit {
                            t: found.t[lane],
                            shape: ids.ids[lane].shape,
                            n: ids.normals[lane],
                            hit: PreliminaryHit(Hit::Triangle {
                                leaf: index,
                                lane: lane as u32,
                                t: found.t[lane],
                                b1,
                                b2,
                            }),
                        };
                        n += 1;
                    }
                    (n < MAX_PROBE_HITS).then_some(shifted_max)
                },
            );
        }
        for a in &self.analytic {
            if n == MAX_PROBE_HITS {
                break;
            }
            if let Some(h) = analytic_hit(a, ray) {
                let Hit::Done(si) = h.0 else { unreachable!("analytic hits come with their interaction") };
                out[n] = ProbeHit { t: si.t, shape: si.shape, n: si.n, hit: h };
                n += 1;
            }
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::shape::{cube_mesh, TriangleMesh};
    use glam::Mat4;
    use haze_core::Sampler;

    fn shape(geometry: Geometry) -> Shape {
        Shape { name: "s".into(), geometry, bsdf: Bsdf::Null, interior: None, exterior: None, emitter: None }
    }

    /// The node tests to run: the portable one, and the AVX2 one where the CPU has it.
    fn kernels() -> Vec<Option<Avx2>> {
        [None].into_iter().chain(Avx2::detect().map(Some)).collect()
    }

    /// What a ray's queries return, to compare the kernels' answers bit for bit: the closest
    /// hit's `t`, primitive and point, and the shadow query's answer with its hits' `t`. The
    /// node tests may differ in the last bits at a box's boundary (`wide::NodeTest`), but both
    /// are conservative and the triangle tests are shared, so the answers must not.
    fn answers(accel: &Accel, shapes: &[Shape], ray: &Ray) -> String {
        let h =
            accel.intersect(shapes, ray).map(|h| (h.t.to_bits(), h.prim, h.p.to_array().map(f32::to_bits)));
        let mut hits = [ShadowHit::default(); MAX_SHADOW_HITS];
        let q = accel.shadow_hits(shapes, ray, &mut hits);
        let ts: Vec<u32> = match q {
            ShadowQuery::Clear(n) => hits[..n].iter().map(|h| h.t.to_bits()).collect(),
            _ => Vec::new(),
        };
        format!("{h:?} {} {q:?} {ts:?}", accel.occluded(ray))
    }

    /// The BVH agrees with a brute-force loop over all triangles on random rays.
    #[test]
    fn bvh_matches_brute_force() {
        // A deep tree and a tree of a few leaves.
        for (count, scale) in [(2000, 10.0), (30, 2.0)] {
            bvh_matches_brute_force_with(count, scale, false);
        }
        // The stack for trees deeper than the fixed one holds.
        bvh_matches_brute_force_with(2000, 10.0, true);
    }

    fn bvh_matches_brute_force_with(count: usize, scale: f32, deep_stack: bool) {
        let mut s = Sampler::from_seed(1);
        let mut tris = Vec::new();
        for _ in 0..count {
            let c = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * scale;
            let e = |s: &mut Sampler| Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5);
            tris.push([c + e(&mut s), c + e(&mut s), c + e(&mut s)]);
        }
        let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
        let indices = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let shapes = vec![shape(Geometry::Mesh(TriangleMesh::new(positions, None, None, indices, false)))];
        let mut accel = Accel::build(&shapes);
        if deep_stack {
            let bvh = accel.bvh.as_mut().unwrap();
            bvh.closest.stack_need = usize::MAX;
            bvh.all.stack_need = usize::MAX;
        }
        let kernels = kernels();
        for _ in 0..2000 {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * scale;
            let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let ray = Ray::new(o, d);
            let wt = WatertightRay::new(o.into(), d.into());
            let brute = tris
                .iter()
                .filter_map(|t| wt.intersect(t[0].into(), t[1].into(), t[2].into(), 1e-7, f32::INFINITY))
                .map(|h| h.0)
                .fold(f32::INFINITY, f32::min);
            let mut first = None;
            for &k in &kernels {
                accel.avx2 = k;
                let got = accel.intersect(&shapes, &ray).map_or(f32::INFINITY, |h| h.t);
                assert!(got == brute || (got - brute).abs() < 1e-5 * brute, "{got} vs {brute}");
                assert!(!accel.occluded(&Ray { t_max: brute, ..ray }));
                if brute.is_finite() {
                    assert!(accel.occluded(&Ray { t_max: brute * 1.001 + 1e-5, ..ray }));
                }
                // Both kernels' answers bit for bit alike, here and on a segment ending near the
                // hit.
                let a = (
                    answers(&accel, &shapes, &ray),
                    answers(&accel, &shapes, &Ray { t_max: brute * 0.999, ..ray }),
                );
                assert_eq!(*first.get_or_insert_with(|| a.clone()), a, "{k:?}");
            }
        }
    }

    /// A ray leaving a convex mesh outwards gets the same answers (closest hit, shadow query,
    /// bit for bit, both kernels) whether or not it names the mesh as [`Leaving`], and in this
    /// scene (a convex sphere, a cube beside it, a soup of triangles around both) such rays
    /// never hit the sphere again; a ray that names a mesh it does hit (a misuse) finds none of
    /// it, so the skip really prunes its subtrees.
    #[test]
    fn leaving_a_convex_mesh_skips_it_with_the_same_answers() {
        use crate::shape::convex::{clear_sides, uv_sphere, MIN_COSINE};
        let sphere = uv_sphere(24, 1.0);
        assert!(clear_sides(&sphere).front);
        let cube = cube_mesh(
            &Mat4::from_scale_rotation_translation(
                Vec3::splat(0.4),
                glam::Quat::IDENTITY,
                Vec3::new(1.8, 0.2, 0.0),
            ),
            false,
        );
        let mut s = Sampler::from_seed(21);
        let mut soup = Vec::new();
        for _ in 0..300 {
            let c = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5) * 6.0;
            if c.length() < 1.3 {
                continue;
            }
            let e = |s: &mut Sampler| (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5) * 0.6;
            soup.extend([c + e(&mut s), c + e(&mut s), c + e(&mut s)]);
        }
        let soup_indices = (0..soup.len() as u32 / 3).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let soup = TriangleMesh::new(soup, None, None, soup_indices, false);
        let shapes: Vec<Shape> =
            [sphere.clone(), cube, soup].into_iter().map(|m| shape(Geometry::Mesh(m))).collect();
        let mut accel = Accel::build(&shapes);
        let (mut outward, mut others_hit) = (0, 0);
        for &k in &kernels() {
            accel.avx2 = k;
            for i in 0..4000 {
                // A point on a random triangle of the sphere, and a direction leaving it outwards.
                let tri = (s.next_1d() * sphere.indices.len() as f32) as usize % sphere.indices.len();
                let [a, b, c] = sphere.vertices(tri);
                let bary = haze_core::sampling::sample_uniform_triangle(s.next_2d());
                let p = a + (b - a) * bary.x + (c - a) * bary.y;
                let n = sphere.face_normal(tri);
                let mut d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                if d.dot(n) < 0.0 {
                    d = -d;
                }
                // Some rays exactly along the cube's direction, so that many hit something.
                if i % 4 == 0 {
                    d = (Vec3::new(1.8, 0.2, 0.0) - p).normalize();
                    if d.dot(n) <= 0.0 {
                        continue;
                    }
                }
                if d.dot(n) < MIN_COSINE {
                    continue;
                }
                outward += 1;
                let ray = Ray::new(haze_core::ray::offset_origin(p, n, d), d);
                let plain = accel.intersect_preliminary(&ray).map(|h| accel.interaction(&shapes, &h));
                assert!(plain.is_none_or(|h| h.shape != 0), "case {i}: the sphere hit itself");
                others_hit += plain.is_some() as u32;
                let skipped = accel
                    .intersect_preliminary_leaving(&ray, Leaving::shape(0))
                    .map(|h| accel.interaction(&shapes, &h));
                let key = |h: Option<SurfaceInteraction>| h.map(|h| (h.t.to_bits(), h.shape, h.prim));
                assert_eq!(key(plain), key(skipped), "case {i}");
                let mut hits = [ShadowHit::default(); MAX_SHADOW_HITS];
                for t_max in [0.5, 3.0, f32::INFINITY] {
                    let seg = Ray { t_max, ..ray };
                    let a = accel.shadow_hits(&shapes, &seg, &mut hits);
                    let b = accel.shadow_hits_leaving(&shapes, &seg, Leaving::shape(0), &mut hits);
                    assert_eq!(a, b, "case {i}, t_max {t_max}");
                }
            }
            // Misuse: rays from outside aimed at the sphere, naming it, do not find it.
            for _ in 0..200 {
                let o = haze_core::sampling::sample_uniform_sphere(s.next_2d()) * 2.5;
                let ray = Ray::new(o, -o.normalize());
                let plain = accel.intersect_preliminary(&ray).map(|h| accel.interaction(&shapes, &h));
                let skipped = accel
                    .intersect_preliminary_leaving(&ray, Leaving::shape(0))
                    .map(|h| accel.interaction(&shapes, &h));
                assert!(plain.is_some());
                assert!(skipped.is_none_or(|h| h.shape != 0));
            }
        }
        assert!(outward > 4000 && others_hit > 500, "{outward} outward rays, {others_hit} hit another shape");
    }

    /// `shadow_hits` on a scene of `null` meshes finds every triangle the segment crosses (the
    /// brute-force set of `t`s), a blocking mesh stops it, and `shadow_crossing` names the same
    /// shape and geometric normal as the full `shadow_interaction`; `intersect_preliminary`
    /// has the distance of `intersect`.
    #[test]
    fn shadow_hits_and_crossings_match_brute_force() {
        let mut s = Sampler::from_seed(9);
        let mut meshes: Vec<Vec<[Vec3; 3]>> = vec![Vec::new(); 3];
        for k in 0..60 {
            let c = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0;
            let e = |s: &mut Sampler| Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5);
            meshes[k % 3].push([c + e(&mut s), c + e(&mut s), c + e(&mut s)]);
        }
        let mesh = |tris: &[[Vec3; 3]], flip: bool| {
            let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
            let indices = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            Geometry::Mesh(TriangleMesh::new(positions, None, None, indices, flip))
        };
        // Shapes 0 and 1 are null (one with flipped normals), shape 2 blocks.
        let mut shapes = vec![shape(mesh(&meshes[0], false)), shape(mesh(&meshes[1], true))];
        shapes.push(Shape {
            bsdf: Bsdf::Diffuse { reflectance: crate::Texture::Constant(haze_core::Rgb::splat(0.5)) },
            ..shape(mesh(&meshes[2], false))
        });
        let accel = Accel::build(&shapes);
        let (mut clear, mut blocked) = (0, 0);
        for _ in 0..3000 {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0;
            let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let ray = Ray { t_max: 0.2 + 2.0 * s.next_1d(), ..Ray::new(o, d) };
            let wt = WatertightRay::new(o.into(), d.into());
            let crossed = |tris: &[[Vec3; 3]]| -> Vec<f32> {
                tris.iter()
                    .filter_map(|t| wt.intersect(t[0].into(), t[1].into(), t[2].into(), T_MIN, ray.t_max))
                    .map(|h| h.0)
                    .collect()
            };
            let mut want: Vec<f32> = [&meshes[0], &meshes[1]].iter().flat_map(|m| crossed(m)).collect();
            want.sort_by(f32::total_cmp);
            let blocks = !crossed(&meshes[2]).is_empty();
            let mut hits = [ShadowHit::default(); MAX_SHADOW_HITS];
            match accel.shadow_hits(&shapes, &ray, &mut hits) {
                ShadowQuery::Blocked => {
                    assert!(blocks, "blocked without a blocker on the segment");
                    blocked += 1;
                }
                ShadowQuery::Clear(n) => {
                    assert!(!blocks, "a blocker on the segment was missed");
                    let mut got: Vec<f32> = hits[..n].iter().map(|h| h.t).collect();
                    got.sort_by(f32::total_cmp);
                    assert_eq!(got, want);
                    for h in &hits[..n] {
                        let si = accel.shadow_interaction(&shapes, h);
                        assert_eq!(accel.shadow_crossing(h), (si.shape, si.n));
                        assert!(si.shape < 2);
                    }
                    clear += usize::from(n > 0);
                }
                ShadowQuery::Unsupported => assert!(want.len() >= MAX_SHADOW_HITS),
            }
            let full = accel.intersect(&shapes, &ray).map(|h| h.t);
            assert_eq!(accel.intersect_preliminary(&ray).map(|h| h.t()), full);
        }
        // Both outcomes were exercised, with crossings.
        assert!(clear > 50 && blocked > 50, "{clear} clear with crossings, {blocked} blocked");
    }

    /// The wide tree with its 4-triangle leaves returns exactly the brute-force closest hit
    /// (the same watertight test, so the same `t` bits) for the rays that stress a traversal:
    /// rays starting on a triangle (hits at `t` near 0), rays grazing a tessellated plane (in
    /// its plane, or a hair above or below it), and axis-aligned rays whose zero components
    /// are `-0.0` (their inverse is `-1 / f32::EPSILON`: the near plane must follow its sign).
    /// With both node tests where the CPU has AVX2 and FMA, whose answers must agree bit for
    /// bit.
    #[test]
    fn wide_tree_matches_brute_force_on_surfaces_and_grazing_rays() {
        let mut s = Sampler::from_seed(5);
        let mut tris: Vec<[Vec3; 3]> = Vec::new();
        // A 24 x 24 grid of quads in the plane z = 1 over [0, 6]^2 ...
        let n = 24;
        let g = |i: usize, j: usize| Vec3::new(i as f32 * 0.25, j as f32 * 0.25, 1.0);
        for i in 0..n {
            for j in 0..n {
                tris.push([g(i, j), g(i + 1, j), g(i + 1, j + 1)]);
                tris.push([g(i, j), g(i + 1, j + 1), g(i, j + 1)]);
            }
        }
        // ... and random triangles above and below it.
        for _ in 0..1500 {
            let c = Vec3::new(s.next_1d() * 6.0, s.next_1d() * 6.0, s.next_1d() * 2.0);
            let e =
                |s: &mut Sampler| Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5) * 0.6;
            tris.push([c + e(&mut s), c + e(&mut s), c + e(&mut s)]);
        }
        let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
        let indices = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let shapes = vec![shape(Geometry::Mesh(TriangleMesh::new(positions, None, None, indices, false)))];
        let mut accel = Accel::build(&shapes);
        let kernels = kernels();
        let (mut found, mut cases) = (0, 0);
        for i in 0..6000 {
            let (o, d) = match i % 3 {
                // From a point on a random triangle, in a random direction.
                0 => {
                    let t = tris[(s.next_1d() * tris.len() as f32) as usize % tris.len()];
                    let (u, v) = (s.next_1d(), s.next_1d());
                    let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                    (
                        t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v,
                        haze_core::sampling::sample_uniform_sphere(s.next_2d()),
                    )
                }
                // Grazing the grid: in its plane (z = 1, d.z = +-0) or a hair off it.
                1 => {
                    let o = Vec3::new(s.next_1d() * 6.0, s.next_1d() * 6.0, 1.0);
                    let phi = s.next_1d() * std::f32::consts::TAU;
                    let dz = [0.0, -0.0, 1e-6, -1e-6][(i / 3) % 4];
                    let o = if i % 2 == 0 { o } else { o + Vec3::new(0.0, 0.0, 1e-6) };
                    (o, Vec3::new(phi.cos(), phi.sin(), dz).normalize())
                }
                // Axis-aligned, the other components -0.0 or +0.0.
                _ => {
                    let o = Vec3::new(s.next_1d() * 6.0, s.next_1d() * 6.0, s.next_1d() * 2.0);
                    let axis = (i / 3) % 3;
                    let z = if (i / 9) % 2 == 0 { -0.0 } else { 0.0 };
                    let mut d = Vec3::splat(z);
                    d[axis] = if (i / 18) % 2 == 0 { 1.0 } else { -1.0 };
                    (o, d)
                }
            };
            let ray = Ray::new(o, d);
            let wt = WatertightRay::new(o.into(), d.into());
            let brute = tris
                .iter()
                .filter_map(|t| wt.intersect(t[0].into(), t[1].into(), t[2].into(), T_MIN, f32::INFINITY))
                .map(|h| h.0)
                .fold(f32::INFINITY, f32::min);
            let mut first = None;
            for &k in &kernels {
                accel.avx2 = k;
                let got = accel.intersect(&shapes, &ray).map_or(f32::INFINITY, |h| h.t);
                assert_eq!(
                    got.to_bits(),
                    brute.to_bits(),
                    "case {i} ({k:?}): o {o}, d {d}: {got} vs {brute}"
                );
                assert!(!accel.occluded(&Ray { t_max: brute, ..ray }), "case {i} ({k:?})");
                if brute.is_finite() {
                    assert!(accel.occluded(&Ray { t_max: brute * 1.001 + 1e-5, ..ray }), "case {i} ({k:?})");
                }
                let a = answers(&accel, &shapes, &ray);
                assert_eq!(*first.get_or_insert_with(|| a.clone()), a, "case {i} ({k:?})");
            }
            found += usize::from(brute.is_finite());
            cases += 1;
        }
        // Enough hits to mean something, and enough misses to check for false hits.
        assert!(found > cases / 3 && found < cases - cases / 10, "{found} hits of {cases}");
    }

    /// Rays from inside a closed cube always find the boundary (no leaks through edges).
    #[test]
    fn closed_cube_is_watertight() {
        let shapes = vec![shape(Geometry::Mesh(cube_mesh(&Mat4::IDENTITY, false)))];
        let accel = Accel::build(&shapes);
        let mut s = Sampler::from_seed(2);
        for _ in 0..20_000 {
            let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let h = accel.intersect(&shapes, &Ray::new(Vec3::ZERO, d)).expect("ray leaked out of the cube");
            assert!(h.n.dot(d) > 0.0);
        }
    }

    /// Geometry up to `MAX_COORDINATE` builds (obvhs panicked on a cube scaled by 1e30, which
    /// the loader now refuses) and rays from inside still find the walls.
    #[test]
    fn huge_coordinates_up_to_the_limit_build_and_hold() {
        for scale in [1e-6f32, 1.0, 1e10, MAX_COORDINATE] {
            let m = Mat4::from_scale(Vec3::splat(scale));
            let shapes = vec![shape(Geometry::Mesh(cube_mesh(&m, false)))];
            let accel = Accel::build(&shapes);
            let mut s = Sampler::from_seed(3);
            for _ in 0..2000 {
                let d = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let h = accel
                    .intersect(&shapes, &Ray::new(Vec3::ZERO, d))
                    .unwrap_or_else(|| panic!("{scale}: leaked along {d}"));
                assert!((h.t / scale - 1.0) > -1e-3 && h.t / scale < 1.8, "{scale}: t = {}", h.t);
            }
        }
    }

    #[test]
    fn spheres_and_disks_are_found() {
        let shapes = vec![
            shape(Geometry::Sphere { center: Vec3::new(0.0, 0.0, 5.0), radius: 1.0, flip_normals: false }),
            shape(Geometry::Disk {
                to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, 2.0)),
                flip_normals: false,
            }),
        ];
        let accel = Accel::build(&shapes);
        let h = accel.intersect(&shapes, &Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
        assert_eq!(h.shape, 1);
        assert!((h.t - 2.0).abs() < 1e-5);
        // Aimed at the sphere's centre past the disk's rim: the normal faces back along the ray.
        let d = Vec3::new(-2.0, 0.0, 5.0).normalize();
        let h = accel.intersect(&shapes, &Ray::new(Vec3::new(2.0, 0.0, 0.0), d)).unwrap();
        assert_eq!(h.shape, 0);
        assert!((h.n + d).length() < 1e-3, "{:?}", h.n);
        assert!((h.t - (Vec3::new(2.0, 0.0, 0.0) - Vec3::new(0.0, 0.0, 5.0)).length() + 1.0).abs() < 1e-4);
    }
}
