//! Building the light tree. The paper's three parallel steps (Vibert et al. 2019, "Light tree"):
//!
//! 1. **Partition by sorting**: Morton codes of the lights' box centres, sorted in parallel, cut
//!    into groups of at most `group_size` consecutive lights.
//! 2. **Local agglomerative trees**, one per group in parallel, repeatedly merging the pair with
//!    the smallest metric `d(A, B) = I(A ∪ B) diag(box(A ∪ B))^2` (notes §5). Pairs are found by
//!    PLOC's local search (Meister & Bittner 2018): each cluster looks for its best partner among
//!    `radius` neighbours on each side in Morton order, and mutual best pairs merge.
//! 3. **Agglomerative top**: the same merging over the groups' roots.
//!
//! Walter et al. 2008's heap-and-kd-tree build is exact but sequential and degrades to O(N^2)
//! with overlapping clusters (long VRLs overlap a lot), which is why the paper partitions first.
//! [`build_median_split`] is the simple top-down baseline the benchmark compares against.

use super::{Aabb, LightTree, Node, TreeLight, NONE};
use haze_core::rng::mix64;
use rayon::prelude::*;

#[derive(Clone, Copy, Debug)]
pub struct BuildSettings {
    /// Most lights per group of step 1.
    pub group_size: usize,
    /// PLOC search radius (neighbours on each side in Morton order).
    pub radius: usize,
    /// Seed of the representatives' random choice.
    pub seed: u64,
}

impl Default for BuildSettings {
    fn default() -> Self {
        BuildSettings { group_size: 1024, radius: 16, seed: 0 }
    }
}

fn leaf<L: TreeLight>(i: usize, l: &L) -> Node {
    Node {
        bounds: l.bounds(),
        intensity: l.intensity(),
        flux_bound: l.flux_bound(),
        l_max: l.length(),
        rep: i as u32,
        left: NONE,
        right: NONE,
        count: 1,
    }
}

/// Merges two nodes; the representative is the left one's with probability `I_l / (I_l + I_r)`,
/// drawn from a hash of the seed and both representatives (independent of thread scheduling).
fn merge(a: &Node, b: &Node, ia: u32, ib: u32, seed: u64) -> Node {
    let total = a.intensity + b.intensity;
    let u = (mix64(seed ^ mix64(((a.rep as u64) << 32) | b.rep as u64)) >> 40) as f32 / (1u64 << 24) as f32;
    let rep = if total > 0.0 {
        if u * total < a.intensity {
            a.rep
        } else {
            b.rep
        }
    } else if u < 0.5 {
        a.rep
    } else {
        b.rep
    };
    Node {
        bounds: a.bounds.union(&b.bounds),
        intensity: total,
        flux_bound: a.flux_bound + b.flux_bound,
        l_max: a.l_max.max(b.l_max),
        rep,
        left: ia,
        right: ib,
        count: a.count + b.count,
    }
}

/// `d(A, B) = I(A ∪ B) diag(box(A ∪ B))^2`.
#[inline]
fn metric(a: &Node, b: &Node) -> f32 {
    let d = a.bounds.union(&b.bounds).diagonal();
    (a.intensity + b.intensity) * d * d
}

/// 30-bit Morton code of a point inside `scene` (10 bits per axis).
fn morton(p: glam::Vec3, scene: &Aabb) -> u32 {
    let ext = (scene.hi - scene.lo).max(glam::Vec3::splat(1e-30));
    let q = ((p - scene.lo) / ext).clamp(glam::Vec3::ZERO, glam::Vec3::ONE) * 1023.0;
    let spread = |v: u32| {
        let mut x = v & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    (spread(q.x as u32) << 2) | (spread(q.y as u32) << 1) | spread(q.z as u32)
}

/// PLOC over `clusters` (indices into `nodes`, in spatial order), appending merged nodes to
/// `nodes`; returns the root's index.
fn ploc(nodes: &mut Vec<Node>, mut clusters: Vec<u32>, radius: usize, seed: u64) -> u32 {
    let mut best = Vec::new();
    while clusters.len() > 1 {
        let n = clusters.len();
        best.clear();
        for i in 0..n {
            let (mut bj, mut bd) = (usize::MAX, f32::INFINITY);
            let a = &nodes[clusters[i] as usize];
            for j in i.saturating_sub(radius)..(i + radius + 1).min(n) {
                if j == i {
                    continue;
                }
                let d = metric(a, &nodes[clusters[j] as usize]);
                // Ties broken towards the lower index so that mutual pairs are found consistently.
                if d < bd || (d == bd && j < bj) {
                    bd = d;
                    bj = j;
                }
            }
            best.push(bj);
        }
        let mut next = Vec::with_capacity(n / 2 + 1);
        for i in 0..n {
            let j = best[i];
            if j != usize::MAX && best[j] == i {
                if i < j {
                    let (ia, ib) = (clusters[i], clusters[j]);
                    let m = merge(&nodes[ia as usize], &nodes[ib as usize], ia, ib, seed);
                    let id = nodes.len() as u32;
                    nodes.push(m);
                    next.push(id);
                }
            } else {
                next.push(clusters[i]);
            }
        }
        if next.len() == n {
            // No mutual pair (possible only with exact ties): merge the first two to progress.
            let (ia, ib) = (next[0], next[1]);
            let m = merge(&nodes[ia as usize], &nodes[ib as usize], ia, ib, seed);
            nodes.push(m);
            next[0] = nodes.len() as u32 - 1;
            next.remove(1);
        }
        clusters = next;
    }
    clusters[0]
}

/// The paper's three-step parallel build (module docs).
pub fn build_agglomerative<L: TreeLight>(lights: &[L], settings: &BuildSettings) -> LightTree {
    let n = lights.len();
    if n == 0 {
        return LightTree::default();
    }
    let leaves: Vec<Node> = lights.par_iter().enumerate().map(|(i, l)| leaf(i, l)).collect();
    let scene = leaves.iter().fold(Aabb::EMPTY, |acc, l| acc.union(&l.bounds));
    // Step 1: sort by Morton code (ties by index, so the order is deterministic).
    let mut order: Vec<(u32, u32)> =
        leaves.par_iter().enumerate().map(|(i, l)| (morton(l.bounds.center(), &scene), i as u32)).collect();
    order.par_sort_unstable();
    let groups: Vec<Vec<u32>> =
        order.chunks(settings.group_size.max(2)).map(|c| c.iter().map(|&(_, i)| i).collect()).collect();

    // Step 2: local trees in parallel. Each group's new nodes are numbered from a local base
    // and renumbered when concatenated.
    let locals: Vec<(Vec<Node>, u32)> = groups
        .par_iter()
        .map(|g| {
            // Local node array: the group's leaves first, then merged nodes.
            let mut local: Vec<Node> = g.iter().map(|&i| leaves[i as usize]).collect();
            let ids: Vec<u32> = (0..g.len() as u32).collect();
            let root = ploc(&mut local, ids, settings.radius, settings.seed);
            (local, root)
        })
        .collect();

    // Concatenate: global layout = all leaves (index = light index), then each group's merged
    // nodes. Local index k < group_len maps to the leaf g[k]; k >= group_len to offset + k - len.
    let mut nodes = leaves;
    let mut roots = Vec::with_capacity(locals.len());
    for (g, (local, root)) in groups.iter().zip(locals) {
        let offset = nodes.len() as u32;
        let len = g.len() as u32;
        let map = |k: u32| if k < len { g[k as usize] } else { offset + k - len };
        for node in &local[g.len()..] {
            let mut m = *node;
            m.left = map(m.left);
            m.right = map(m.right);
            nodes.push(m);
        }
        roots.push(map(root));
    }
    // Step 3: agglomerative merge of the groups' roots (in Morton order of their groups).
    let root = ploc(&mut nodes, roots, settings.radius, settings.seed ^ 0x70b);
    LightTree { nodes, root }
}

/// Baseline: top-down split at the median of the box centres along the widest axis.
pub fn build_median_split<L: TreeLight>(lights: &[L], seed: u64) -> LightTree {
    let n = lights.len();
    if n == 0 {
        return LightTree::default();
    }
    let mut nodes: Vec<Node> = lights.iter().enumerate().map(|(i, l)| leaf(i, l)).collect();
    let mut idx: Vec<u32> = (0..n as u32).collect();
    let root = split(&mut nodes, &mut idx, seed);
    LightTree { nodes, root }
}

fn split(nodes: &mut Vec<Node>, idx: &mut [u32], seed: u64) -> u32 {
    if idx.len() == 1 {
        return idx[0];
    }
    let b = idx.iter().fold(Aabb::EMPTY, |acc, &i| {
        let c = nodes[i as usize].bounds.center();
        acc.union(&Aabb::from_points(c, c))
    });
    let axis = (b.hi - b.lo).max_position();
    let mid = idx.len() / 2;
    idx.select_nth_unstable_by(mid, |&a, &c| {
        let (ka, kc) = (nodes[a as usize].bounds.center()[axis], nodes[c as usize].bounds.center()[axis]);
        ka.total_cmp(&kc).then(a.cmp(&c))
    });
    let (lo, hi) = idx.split_at_mut(mid);
    let l = split(nodes, lo, seed);
    let r = split(nodes, hi, seed);
    let m = merge(&nodes[l as usize], &nodes[r as usize], l, r, seed);
    nodes.push(m);
    nodes.len() as u32 - 1
}
