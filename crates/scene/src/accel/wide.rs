//! obvhs's compressed 8-wide nodes with their child boxes decoded to f32, for a cheaper node test,
//! and each child slot resolved to the inner node or leaf it holds, for our traversal loop
//! (`Accel::traverse` in `mod.rs`).
//!
//! A `CwBvhNode` stores each child box as 8-bit offsets on a per-node power-of-two grid (Ylitie,
//! Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs", section 3.1). obvhs converts those 48 bytes to floats on every node test, which was
//! about a third of all traversal time on the Mitsuba peer scenes (docs/performance.md,
//! "Traversal of the peer scenes"). [`WideNode`] keeps the same tree with the boxes decoded
//! once at build time; instead of obvhs's child metadata (octant-permuted inner children, leaf
//! primitive runs) each slot holds the index of its node or leaf directly.
//!
//! The decoded boxes are the quantised ones (which obvhs rounds outwards, so they enclose the
//! exact child boxes) up to one rounding of `p + 2^e q`, far below the pad every triangle's box
//! carries (`BOX_PAD`). The exact boxes instead would save only ~1.5% of node and leaf visits
//! on the peer scenes (measured with `examples/accel_bench.rs`) and leave less slack.

use glam::{BVec4A, Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;

/// Tag of a [`WideNode::children`] entry that is a leaf (the rest is the leaf's index in the
/// caller's leaf array); untagged entries are indices of inner nodes in [`WideBvh::nodes`].
pub const LEAF: u32 = 1 << 31;

/// One node: the 8 child boxes as `[min x, max x, min y, max y, min z, max z]`, each 8 lanes in
/// two `Vec4`s, and what each child slot holds.
#[derive(Clone, Copy, Debug)]
pub struct WideNode {
    planes: [[Vec4; 2]; 6],
    /// Child slot `c`: an inner node's index in [`WideBvh::nodes`], or [`LEAF`] `|` the index of
    /// a leaf in the caller's leaf array (anything for an empty slot, which `valid` masks out).
    pub children: [u32; 8],
    /// Bit `c` set when slot `c` holds a child.
    valid: u32,
}

/// A ray prepared for [`WideNode::intersect`]: for each axis, which of the two planes is met
/// first (`near`), the origin and the inverse direction splatted to 4 lanes.
#[derive(Clone, Copy, Debug)]
pub struct WideRay {
    near: [usize; 3],
    o: [Vec4; 3],
    inv: [Vec4; 3],
    t_min: Vec4,
}

impl WideRay {
    /// `inv_d` is the componentwise inverse of the direction, finite (obvhs's `safe_inverse`).
    #[inline]
    pub fn new(o: Vec3A, d: Vec3A, inv_d: Vec3A, t_min: f32) -> Self {
        let near = [0, 1, 2].map(|a| 2 * a + usize::from(d[a] < 0.0));
        WideRay {
            near,
            o: [0, 1, 2].map(|a| Vec4::splat(o[a])),
            inv: [0, 1, 2].map(|a| Vec4::splat(inv_d[a])),
            t_min: Vec4::splat(t_min),
        }
    }
}

impl WideNode {
    /// `boxes[c]`: the box of child `c` (anything for an empty slot); `leaf_base`: the index in
    /// the caller's leaf array of this node's first leaf child, the node's leaf children being
    /// numbered by their primitive offset.
    fn new(n: &CwBvhNode, boxes: &[Aabb; 8], leaf_base: u32) -> Self {
        let planes = std::array::from_fn(|i| {
            let a = i / 2;
            let lane = |c: usize| if i % 2 == 0 { boxes[c].min[a] } else { boxes[c].max[a] };
            [Vec4::new(lane(0), lane(1), lane(2), lane(3)), Vec4::new(lane(4), lane(5), lane(6), lane(7))]
        });
        let leaf_starts: u32 = leaf_children(n).fold(0, |m, (offset, _)| m | 1 << offset);
        let mut valid = 0;
        let children = std::array::from_fn(|c| {
            let meta = u32::from(n.child_meta[c]);
            if n.imask & (1 << c) != 0 {
                // obvhs (`traverse!`): inner children are stored from `child_base_idx` on, in
                // slot order.
                valid |= 1 << c;
                n.child_base_idx + (u32::from(n.imask) & ((1 << c) - 1)).count_ones()
            } else if meta != 0 {
                valid |= 1 << c;
                let offset = meta & 0b11111;
                LEAF | (leaf_base + (leaf_starts & ((2u32 << offset) - 1)).count_ones() - 1)
            } else {
                0
            }
        });
        WideNode { planes, children, valid }
    }

    /// The slab test of all 8 children (Kay and Kajiya 1986) for `t` in `[ray.t_min, t_max]`:
    /// bit `c` of the mask set when child `c` is hit, and each child's entry distance (lanes
    /// 0-3 and 4-7), by which the traversal orders and prunes them.
    #[inline(always)]
    pub fn intersect(&self, ray: &WideRay, t_max: f32) -> (u32, [Vec4; 2]) {
        let t_max = Vec4::splat(t_max);
        let half = |h: usize| -> (BVec4A, Vec4) {
            let mut lo = ray.t_min;
            let mut hi = t_max;
            for a in 0..3 {
                let n = ray.near[a];
                let t_near = (self.planes[n][h] - ray.o[a]) * ray.inv[a];
                let t_far = (self.planes[n ^ 1][h] - ray.o[a]) * ray.inv[a];
                lo = lo.max(t_near);
                hi = hi.min(t_far);
            }
            (lo.cmple(hi), lo)
        };
        let (m0, lo0) = half(0);
        let (m1, lo1) = half(1);
        ((m0.bitmask() | m1.bitmask() << 4) & self.valid, [lo0, lo1])
    }
}

/// The leaf children of `n` as `(offset, count)`: their first primitive's offset from
/// `primitive_base_idx` and their number of primitives, in no particular order. A leaf child's
/// metadata byte holds the offset in its low 5 bits and the count in unary in its high 3
/// (obvhs `CwBvhNode::child_meta`).
pub fn leaf_children(n: &CwBvhNode) -> impl Iterator<Item = (u32, u32)> + '_ {
    (0..8).filter(|c| n.imask & (1 << c) == 0 && n.child_meta[*c] != 0).map(|c| {
        let meta = n.child_meta[c];
        (u32::from(meta & 0b11111), (meta >> 5).count_ones())
    })
}

/// The nodes of a [`CwBvh`], decoded; primitive indices stay the `CwBvh`'s.
#[derive(Clone, Debug)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    /// Most entries a traversal's stack can hold at once (each node visited pushes its hit
    /// children and pops one), or `usize::MAX` when the tree is not laid out parents first.
    pub stack_need: usize,
}

impl WideBvh {
    /// `leaf_base[i]`: where node `i`'s leaf children start in the caller's leaf array, which
    /// holds every node's leaf children in node order, each node's by primitive offset.
    pub fn new(bvh: &CwBvh, leaf_base: &[u32]) -> Self {
        let nodes: Vec<WideNode> = bvh
            .nodes
            .iter()
            .zip(leaf_base)
            .map(|(n, &b)| WideNode::new(n, &std::array::from_fn(|c| n.child_aabb(c)), b))
            .collect();
        // need(node) = (children - 1) + max over inner children of need(child), over the
        // nodes in reverse order (obvhs stores children after their parent; checked).
        let mut need = vec![0usize; nodes.len()];
        let mut ordered = true;
        for i in (0..nodes.len()).rev() {
            let n = &nodes[i];
            let slots = (0..8).filter(|c| n.valid & (1 << c) != 0);
            let mut deepest = 0;
            for c in slots.clone() {
                let child = n.children[c];
                if child & LEAF == 0 {
                    ordered &= child as usize > i && (child as usize) < nodes.len();
                    deepest = deepest.max(need.get(child as usize).copied().unwrap_or(0));
                }
            }
            need[i] = slots.count().saturating_sub(1) + deepest;
        }
        let stack_need = if ordered { need.first().map_or(0, |n| n + 1) } else { usize::MAX };
        WideBvh { nodes, stack_need }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;
    use obvhs::aabb::Aabb;
    use obvhs::cwbvh::builder::build_cwbvh;
    use obvhs::ray::Ray;
    use obvhs::BvhBuildParams;

    /// The decoded node test agrees with obvhs's on every node of a random tree for random rays,
    /// up to rays that graze a box (where the two roundings may differ).
    #[test]
    fn node_test_matches_obvhs() {
        let mut s = Sampler::from_seed(11);
        let p = |s: &mut Sampler| Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
        let boxes: Vec<Aabb> = (0..3000)
            .map(|_| {
                let c = p(&mut s);
                Aabb::new(c, c + Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.5)
            })
            .collect();
        let bvh = build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Default::default());
        let wide = WideBvh::new(&bvh, &vec![0; bvh.nodes.len()]);
        let (mut hits, mut differ) = (0u32, 0u32);
        for _ in 0..3000 {
            let o = p(&mut s);
            let d = Vec3A::from(haze_core::sampling::sample_uniform_sphere(s.next_2d()));
            let t_max = s.next_1d() * 12.0;
            let r = Ray::new(o, d, 0.0, t_max);
            let oct = ((d.x >= 0.0) as u32 * 0x04040404)
                | ((d.y >= 0.0) as u32 * 0x02020202)
                | ((d.z >= 0.0) as u32 * 0x01010101);
            let wr = WideRay::new(o, d, r.inv_direction, 1e-4);
            for (n, w) in bvh.nodes.iter().zip(&wide.nodes) {
                let theirs = n.intersect_ray(&r, oct);
                let ours = w.intersect(&wr, t_max).0;
                // obvhs's mask: inner child `c` at bit `24 + (c ^ octant)`, a leaf child as
                // its run of primitive bits.
                for c in 0..8 {
                    let meta = u32::from(n.child_meta[c]);
                    let hit = if n.imask & (1 << c) != 0 {
                        theirs >> (24 + (c as u32 ^ (oct & 7))) & 1 != 0
                    } else {
                        theirs & ((meta >> 5) << (meta & 0b11111)) != 0
                    };
                    hits += u32::from(hit);
                    differ += u32::from(hit != (ours >> c & 1 != 0));
                }
            }
        }
        assert!(hits > 20_000, "{hits}");
        assert!(differ * 10_000 < hits, "{differ} of {hits} hit bits differ");
    }
}
