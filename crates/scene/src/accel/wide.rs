//! obvhs's compressed 8-wide nodes with their child boxes decoded to f32, for a cheaper node test.
//!
//! A `CwBvhNode` stores each child box as 8-bit offsets on a per-node power-of-two grid (Ylitie,
//! Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs", section 3.1). obvhs converts those 48 bytes to floats on every node test, which was
//! about a third of all traversal time on the Mitsuba peer scenes (docs/performance.md,
//! "Traversal of the peer scenes"). [`WideNode`] keeps the same tree, child order and
//! metadata, with the boxes decoded once at build time, so obvhs's `traverse!` loop (its stack,
//! octant child order and leaf encoding) runs unchanged over [`WideBvh::nodes`]; only the node
//! test is ours.
//!
//! The decoded boxes are the quantised ones (which obvhs rounds outwards, so they enclose the
//! exact child boxes) up to one rounding of `p + 2^e q`, far below the pad every triangle's box
//! carries (`BOX_PAD`). The exact boxes instead would save only ~1.5% of node and leaf visits
//! on the peer scenes (measured with `examples/accel_bench.rs`) and leave less slack.

use glam::{BVec4A, Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;

/// One node: the 8 child boxes as `[min x, max x, min y, max y, min z, max z]`, each 8 lanes in
/// two `Vec4`s, and obvhs's fields that `traverse!` and the hit mask read.
#[derive(Clone, Copy, Debug)]
pub struct WideNode {
    planes: [[Vec4; 2]; 6],
    /// Read by obvhs's `traverse!` macro: index of the first child node.
    pub child_base_idx: u32,
    /// Read by obvhs's `traverse!` macro: index of the first primitive of the leaf children.
    pub primitive_base_idx: u32,
    /// Read by obvhs's `traverse!` macro: which children are inner nodes.
    pub imask: u8,
    /// Each leaf child's bits of the hit mask (its primitives' run in the low 24 bits, the same
    /// for every ray octant); 0 for inner children and empty slots.
    leaf_bits: [u32; 8],
    /// Index (into the caller's leaf array) of this node's first leaf child, in primitive order.
    pub leaf_base: u32,
    /// Bit `i` set when a leaf child's primitives start at `primitive_base_idx + i`, so the
    /// leaf holding local primitive `j` is `leaf_base + popcount(leaf_starts & (2^(j+1) - 1)) - 1`.
    pub leaf_starts: u32,
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
    /// `boxes[c]`: the box of child `c` (anything for an empty slot: its child bits are zero, so
    /// it never adds to the hit mask).
    fn new(n: &CwBvhNode, boxes: &[Aabb; 8], leaf_base: u32) -> Self {
        let planes = std::array::from_fn(|i| {
            let a = i / 2;
            let lane = |c: usize| if i % 2 == 0 { boxes[c].min[a] } else { boxes[c].max[a] };
            [Vec4::new(lane(0), lane(1), lane(2), lane(3)), Vec4::new(lane(4), lane(5), lane(6), lane(7))]
        });
        WideNode {
            planes,
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            imask: n.imask,
            leaf_bits: std::array::from_fn(|c| {
                let meta = u32::from(n.child_meta[c]);
                if n.imask & (1 << c) != 0 {
                    // The octant trick of `intersect` relies on obvhs's encoding of inner children.
                    assert_eq!(meta, 0b0010_0000 | (24 + c as u32), "obvhs changed its node encoding");
                    0
                } else {
                    (meta >> 5) << (meta & 0b11111)
                }
            }),
            leaf_base,
            leaf_starts: leaf_children(n).fold(0, |m, (offset, _)| m | 1 << offset),
        }
    }

    /// The leaf holding local primitive `j` (`primitive_id - primitive_base_idx`), as an index
    /// into the caller's leaf array.
    #[inline(always)]
    pub fn leaf(&self, j: u32) -> u32 {
        self.leaf_base + (self.leaf_starts & ((2u32 << j) - 1)).count_ones() - 1
    }

    /// The slab test of all 8 children (Kay and Kajiya 1986) for `t` in `[ray.t_min, t_max]`,
    /// returned as obvhs's node hit mask (`CwBvhNode::intersect_ray`): inner children in the top
    /// byte at their octant-ordered slot, leaf primitives as bits of the low 24.
    #[inline(always)]
    pub fn intersect(&self, ray: &WideRay, t_max: f32, oct_inv4: u32) -> u32 {
        let t_max = Vec4::splat(t_max);
        let half = |h: usize| -> BVec4A {
            let mut lo = ray.t_min;
            let mut hi = t_max;
            for a in 0..3 {
                let n = ray.near[a];
                let t_near = (self.planes[n][h] - ray.o[a]) * ray.inv[a];
                let t_far = (self.planes[n ^ 1][h] - ray.o[a]) * ray.inv[a];
                lo = lo.max(t_near);
                hi = hi.min(t_far);
            }
            lo.cmple(hi)
        };
        let mask = half(0).bitmask() | half(1).bitmask() << 4;
        if mask == 0 {
            return 0;
        }
        // obvhs (`get_child_and_index_bits`) puts inner child `c`, stored with metadata
        // `24 + c`, at bit `24 + (c ^ o)` for the ray octant `o`: permute the inner children's
        // bits by that XOR, one swap per set bit of `o`.
        let o = oct_inv4 & 7;
        let mut inner = mask & u32::from(self.imask);
        if o & 1 != 0 {
            inner = ((inner & 0x55) << 1) | ((inner >> 1) & 0x55);
        }
        if o & 2 != 0 {
            inner = ((inner & 0x33) << 2) | ((inner >> 2) & 0x33);
        }
        if o & 4 != 0 {
            inner = ((inner & 0x0f) << 4) | ((inner >> 4) & 0x0f);
        }
        // Leaf children: their runs. (A branch-free loop over all 8 slots measured no faster on
        // the peer scenes and slower on small ones, where few children are hit.)
        let mut leaves = 0u32;
        let mut hit_leaves = mask & !u32::from(self.imask);
        while hit_leaves != 0 {
            leaves |= self.leaf_bits[hit_leaves.trailing_zeros() as usize];
            hit_leaves &= hit_leaves - 1;
        }
        inner << 24 | leaves
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
    /// Named `nodes` for obvhs's `traverse!` macro, which indexes `$cwbvh.nodes`.
    pub nodes: Vec<WideNode>,
}

impl WideBvh {
    /// `leaf_base[i]`: where node `i`'s leaf children start in the caller's leaf array, which
    /// holds every node's leaf children in node order, each node's by primitive offset.
    pub fn new(bvh: &CwBvh, leaf_base: &[u32]) -> Self {
        let nodes = bvh.nodes.iter().zip(leaf_base);
        WideBvh {
            nodes: nodes
                .map(|(n, &b)| WideNode::new(n, &std::array::from_fn(|c| n.child_aabb(c)), b))
                .collect(),
        }
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
                let (a, b) = (w.intersect(&wr, t_max, oct), n.intersect_ray(&r, oct));
                hits += b.count_ones();
                differ += (a ^ b).count_ones();
            }
        }
        assert!(hits > 20_000, "{hits}");
        assert!(differ * 10_000 < hits, "{differ} of {hits} hit bits differ");
    }
}
