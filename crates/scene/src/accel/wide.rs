//! obvhs's compressed 8-wide nodes with their child boxes decoded to f32, for a cheaper node test.
//!
//! A `CwBvhNode` stores each child box as 8-bit offsets on a per-node power-of-two grid (Ylitie,
//! Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs", section 3.1). obvhs converts those 48 bytes to floats on every node test, which was
//! about a third of all traversal time on the Mitsuba peer scenes (docs/performance.md,
//! "Traversal"). [`WideNode`] keeps the same tree, child order and metadata, with the boxes
//! decoded once at build time, so obvhs's `traverse!` loop (its stack, octant child order and
//! leaf encoding) runs unchanged over [`WideBvh::nodes`]; only the node test is ours.
//!
//! The decoded boxes are the quantised ones (which enclose the exact child boxes) up to one
//! rounding of `p + 2^e q`, far below the pad every triangle's box carries (`BOX_PAD`).

use glam::{BVec4A, Vec3A, Vec4};
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
    child_meta: [u8; 8],
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
    fn decode(n: &CwBvhNode) -> Self {
        let e = n.compute_extent();
        let p = Vec3A::from(n.p);
        let q = [n.child_min_x, n.child_max_x, n.child_min_y, n.child_max_y, n.child_min_z, n.child_max_z];
        let planes = std::array::from_fn(|i| {
            let a = i / 2;
            let lane = |c: usize| p[a] + e[a] * f32::from(q[i][c]);
            [Vec4::new(lane(0), lane(1), lane(2), lane(3)), Vec4::new(lane(4), lane(5), lane(6), lane(7))]
        });
        WideNode {
            planes,
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            imask: n.imask,
            child_meta: n.child_meta,
        }
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
        let mut mask = half(0).bitmask() | half(1).bitmask() << 4;
        if mask == 0 {
            return 0;
        }
        let (child_bits8, bit_index8) = self.child_and_index_bits(oct_inv4);
        let mut hit_mask = 0u32;
        while mask != 0 {
            let c = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let child_bits = ((child_bits8 >> (8 * c)) & 0xff) as u32;
            let bit_index = ((bit_index8 >> (8 * c)) & 0xff) as u32;
            hit_mask |= child_bits << bit_index;
        }
        hit_mask
    }

    /// obvhs's `CwBvhNode::get_child_and_index_bits` over this node's metadata.
    #[inline(always)]
    fn child_and_index_bits(&self, oct_inv4: u32) -> (u64, u64) {
        let meta = CwBvhNode { child_meta: self.child_meta, ..Default::default() };
        meta.get_child_and_index_bits(oct_inv4)
    }
}

/// The nodes of a [`CwBvh`], decoded; primitive indices stay the `CwBvh`'s.
#[derive(Clone, Debug)]
pub struct WideBvh {
    /// Named `nodes` for obvhs's `traverse!` macro, which indexes `$cwbvh.nodes`.
    pub nodes: Vec<WideNode>,
}

impl WideBvh {
    pub fn new(bvh: &CwBvh) -> Self {
        WideBvh { nodes: bvh.nodes.iter().map(WideNode::decode).collect() }
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

    /// The decoded node test agrees with obvhs's on every node of a random tree, for random rays,
    /// except for boxes the ray only grazes (where the two roundings may differ).
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
        let wide = WideBvh::new(&bvh);
        let (mut same, mut differ) = (0u32, 0u32);
        for _ in 0..500 {
            let o = p(&mut s);
            let d = Vec3A::from(haze_core::sampling::sample_uniform_sphere(s.next_2d()));
            let t_max = s.next_1d() * 12.0;
            let r = Ray::new(o, d, 0.0, t_max);
            let oct = ((d.x >= 0.0) as u32 * 0x04040404)
                | ((d.y >= 0.0) as u32 * 0x02020202)
                | ((d.z >= 0.0) as u32 * 0x01010101);
            let wr = WideRay::new(o, d, r.inv_direction, 1e-4);
            for (n, w) in bvh.nodes.iter().zip(&wide.nodes) {
                if n.intersect_ray(&r, oct) == w.intersect(&wr, t_max, oct) {
                    same += 1;
                } else {
                    differ += 1;
                }
            }
        }
        assert!(same > 100_000, "{same}");
        assert!(differ * 10_000 < same, "{differ} of {same} node tests differ");
    }
}
