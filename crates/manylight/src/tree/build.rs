//! Building the light tree. The paper's three parallel steps (Vibert et al. 2019, "Light tree"):
//!
//! 1. **Partition by sorting**: Morton codes of the lights' box centres, sorted in parallel, cut
//!    into groups of at most `group_size` consecutive lights.
//! 2. **Local agglomerative trees**, one per group in parallel, repeatedly merging the pair with
//!    the smallest metric `d(A, B) = I(A ∪ B) diag(box(A ∪ B))^2` (`docs/theory.md` §9). Pairs are found by
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
        power: l.power(),
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
        power: a.power + b.power,
        rep,
        left: ia,
        right: ib,
        count: a.count + b.count,
    }
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

/// What the PLOC search reads of a cluster, packed (28 bytes) and stored in Morton order so the
/// neighbour scan walks contiguous memory instead of chasing node indices. `node == NONE` marks a
/// slot whose cluster was merged into its left partner's slot. (SIMD `Vec3A` corners were
/// measured no faster.)
#[derive(Clone, Copy, Debug)]
struct Cluster {
    lo: glam::Vec3,
    hi: glam::Vec3,
    intensity: f32,
    node: u32,
}

impl Cluster {
    fn of(node: &Node, id: u32) -> Self {
        Cluster { lo: node.bounds.lo, hi: node.bounds.hi, intensity: node.intensity, node: id }
    }
    fn alive(&self) -> bool {
        self.node != NONE
    }
}

/// `d(A, B) = I(A ∪ B) diag(box(A ∪ B))^2` (`docs/theory.md` §9; Walter et al. 2008's metric with the
/// paper's intensity), on packed clusters. It only grows when `B` grows (intensity and box both
/// grow), which is what lets [`ploc`] keep a cluster's best neighbour across iterations.
#[inline(always)]
fn cluster_metric(a: &Cluster, b: &Cluster) -> f32 {
    let e = a.hi.max(b.hi) - a.lo.min(b.lo);
    (a.intensity + b.intensity) * e.length_squared()
}

/// Reusable buffers of [`ploc`] (one per rayon worker: the loop allocates nothing once grown).
#[derive(Default)]
struct PlocScratch {
    clusters: Vec<Cluster>,
    best: Vec<u32>,
    best_d: Vec<f32>,
    /// Slots whose best neighbour must be searched again, and their flags.
    dirty: Vec<u32>,
    flagged: Vec<bool>,
    /// Pairs merged in the current iteration (left slot, right slot).
    pairs: Vec<(u32, u32)>,
}

/// Slots are compacted (merged-away slots removed, every best neighbour searched afresh) once
/// the live clusters fall below this fraction of the slots, so that a search window of
/// `radius` slots on each side still holds about `radius` live clusters.
const COMPACT_BELOW: f32 = 0.5;

/// Best partner of every cluster (all alive) among `radius` neighbours on each side (ties to
/// the lower index, so mutual pairs are found consistently, as in [`rescan`]). Every pair inside the window is
/// evaluated once and offered to both ends; candidates reach each cluster in increasing index
/// order, as in [`rescan`].
fn nearest_neighbours(c: &[Cluster], radius: usize, best: &mut [u32], best_d: &mut [f32]) {
    let n = c.len();
    best.fill(NONE);
    best_d.fill(f32::INFINITY);
    for i in 0..n {
        let a = c[i];
        let (mut bi, mut bdi) = (best[i], best_d[i]);
        for j in i + 1..(i + radius + 1).min(n) {
            let d = cluster_metric(&a, &c[j]);
            // Strict `<` with candidates in increasing index: ties go to the lower index.
            let better = d < bdi;
            bdi = if better { d } else { bdi };
            bi = if better { j as u32 } else { bi };
            // Candidate `i` reaches `j` after every smaller index and before any larger one.
            if d < best_d[j] {
                best_d[j] = d;
                best[j] = i as u32;
            }
        }
        best[i] = bi;
        best_d[i] = bdi;
    }
}

/// Best live partner of slot `i` within `radius` slots on each side. Candidates are scanned in
/// increasing index with a strict `<`, so ties go to the lower index; dead slots have an
/// infinite intensity, so their metric (`inf` or NaN) never wins, and the loop has no branch
/// but the selects (the comparisons are unpredictable; branches cost more than the metric).
fn rescan(c: &[Cluster], i: usize, radius: usize) -> (u32, f32) {
    let a = &c[i];
    let (mut b, mut bd) = (NONE, f32::INFINITY);
    let (lo, hi) = (i.saturating_sub(radius), (i + radius + 1).min(c.len()));
    for (j, cj) in c[lo..i].iter().enumerate() {
        let d = cluster_metric(a, cj);
        let better = d < bd;
        bd = if better { d } else { bd };
        b = if better { (lo + j) as u32 } else { b };
    }
    for (j, cj) in c[i + 1..hi].iter().enumerate() {
        let d = cluster_metric(a, cj);
        let better = d < bd;
        bd = if better { d } else { bd };
        b = if better { (i + 1 + j) as u32 } else { b };
    }
    (b, bd)
}

/// PLOC (Meister & Bittner 2018) over `scratch.clusters` (in spatial order), appending merged
/// nodes to `nodes`; returns the root's index. Each iteration merges the mutual best pairs
/// among neighbours within `radius` slots; the merged cluster takes the left slot.
///
/// Best neighbours are kept across iterations: after `A` and `B` merge, a cluster `K` whose best
/// was some other `M` keeps it, because `d(K, A ∪ B) >= d(K, A) >= d(K, M)` (the metric grows
/// with either argument) and no other slot in its window changed. Only the merged clusters and
/// those whose best was `A` or `B` search again. With the VRLs' widely spread intensities only
/// ~5% of the clusters merge per iteration (dim clusters are everybody's best, few pairs are
/// mutual) and each merged cluster was the best of several others, so caching saves only ~20%
/// of the searches (measured on 1M VRLs); evaluating each pair once in the full searches saves
/// another half.
fn ploc(nodes: &mut Vec<Node>, scratch: &mut PlocScratch, radius: usize, seed: u64) -> u32 {
    ploc_with(nodes, scratch, radius, seed, true)
}

/// [`ploc`]; with `cache == false` every live slot searches again in every iteration (the
/// reference the cached search is tested against).
fn ploc_with(nodes: &mut Vec<Node>, scratch: &mut PlocScratch, radius: usize, seed: u64, cache: bool) -> u32 {
    let PlocScratch { clusters, best, best_d, dirty, flagged, pairs } = scratch;
    let mut live = clusters.len();
    let mut full_search = true;
    while live > 1 {
        let n = clusters.len();
        if full_search {
            best.resize(n, NONE);
            best_d.resize(n, f32::INFINITY);
            flagged.clear();
            flagged.resize(n, false);
            nearest_neighbours(clusters, radius, best, best_d);
            full_search = false;
        } else {
            for &i in dirty.iter() {
                let (b, d) = rescan(clusters, i as usize, radius);
                best[i as usize] = b;
                best_d[i as usize] = d;
            }
        }
        // Merge mutual pairs. A dead slot's best is NONE, so it never looks mutual.
        pairs.clear();
        for i in 0..n {
            let j = best[i];
            if j != NONE && (j as usize) > i && best[j as usize] == i as u32 {
                pairs.push((i as u32, j));
            }
        }
        if pairs.is_empty() {
            if live < n {
                compact(clusters);
                full_search = true;
                continue;
            }
            // No mutual pair among all-live slots (possible only with exact ties): merge the
            // first two to progress.
            pairs.push((0, 1));
        }
        for &(i, j) in pairs.iter() {
            let (ia, ib) = (clusters[i as usize].node, clusters[j as usize].node);
            let m = merge(&nodes[ia as usize], &nodes[ib as usize], ia, ib, seed);
            clusters[i as usize] = Cluster::of(&m, nodes.len() as u32);
            clusters[j as usize].node = NONE;
            clusters[j as usize].intensity = f32::INFINITY;
            nodes.push(m);
        }
        live -= pairs.len();
        if (live as f32) < COMPACT_BELOW * n as f32 {
            compact(clusters);
            full_search = true;
            continue;
        }
        // Slots to search again: the merged ones and those whose best was merged (they lie
        // within `radius` of it, as every best does).
        dirty.clear();
        for &(i, j) in pairs.iter() {
            best[j as usize] = NONE;
            for k in (i as usize).saturating_sub(radius)..(j as usize + radius + 1).min(n) {
                if !flagged[k] && clusters[k].alive() && (k as u32 == i || best[k] == i || best[k] == j) {
                    flagged[k] = true;
                    dirty.push(k as u32);
                }
            }
        }
        for &k in dirty.iter() {
            flagged[k as usize] = false;
        }
        if !cache {
            dirty.clear();
            dirty.extend((0..n as u32).filter(|&k| clusters[k as usize].alive()));
        }
    }
    clusters.iter().find(|c| c.alive()).map_or(NONE, |c| c.node)
}

/// Removes merged-away slots, keeping the spatial order.
fn compact(clusters: &mut Vec<Cluster>) {
    clusters.retain(Cluster::alive);
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
    let sorted: Vec<u32> = order.iter().map(|&(_, i)| i).collect();
    let groups: Vec<&[u32]> = sorted.chunks(settings.group_size.max(2)).collect();

    // Step 2: local trees in parallel. Each group's new nodes are numbered from a local base
    // and renumbered when concatenated.
    let locals: Vec<(Vec<Node>, u32)> = groups
        .par_iter()
        .map_init(PlocScratch::default, |scratch, g| {
            // Local node array: the group's leaves first, then merged nodes.
            let mut local: Vec<Node> = Vec::with_capacity(2 * g.len());
            local.extend(g.iter().map(|&i| leaves[i as usize]));
            scratch.clusters.clear();
            scratch.clusters.extend(local.iter().enumerate().map(|(k, l)| Cluster::of(l, k as u32)));
            let root = ploc(&mut local, scratch, settings.radius, settings.seed);
            (local, root)
        })
        .collect();

    // Concatenate: global layout = all leaves (index = light index), then each group's merged
    // nodes (a group of `len` leaves adds `len - 1`). Local index k < len maps to the leaf g[k];
    // k >= len to base + k - len.
    let mut nodes = leaves;
    let mut offset = nodes.len() as u32;
    let mut bases = Vec::with_capacity(groups.len());
    for g in &groups {
        bases.push(offset);
        offset += g.len() as u32 - 1;
    }
    let renumber = |g: &[u32], base: u32, k: u32| {
        let len = g.len() as u32;
        if k < len {
            g[k as usize]
        } else {
            base + k - len
        }
    };
    let merged: Vec<Node> = groups
        .par_iter()
        .zip(&locals)
        .zip(&bases)
        .flat_map_iter(|((g, (local, _)), &base)| {
            local[g.len()..].iter().map(move |node| Node {
                left: renumber(g, base, node.left),
                right: renumber(g, base, node.right),
                ..*node
            })
        })
        .collect();
    nodes.extend(merged);
    let roots: Vec<u32> = groups
        .iter()
        .zip(&locals)
        .zip(&bases)
        .map(|((g, (_, root)), &base)| renumber(g, base, *root))
        .collect();
    // Step 3: agglomerative merge of the groups' roots (in Morton order of their groups).
    let mut scratch = PlocScratch::default();
    scratch.clusters.extend(roots.iter().map(|&r| Cluster::of(&nodes[r as usize], r)));
    let root =
        ploc(&mut nodes, &mut scratch, settings.radius, settings.seed ^ haze_core::streams::PLOC_ROOTS);
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

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::{Rgb, Sampler};

    /// Keeping best neighbours across iterations gives the same tree as searching every
    /// cluster's neighbours again in every iteration (the metric's monotonicity argument).
    #[test]
    fn cached_neighbour_search_matches_full_search() {
        let mut s = Sampler::from_seed(11);
        for (n, radius) in [(300usize, 16usize), (1000, 8), (777, 3), (64, 1)] {
            let leaves: Vec<Node> = (0..n)
                .map(|i| {
                    let p = glam::Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
                    let q = p + glam::Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5;
                    // Intensities over four decades, as VRL fluxes spread.
                    let w = 10f32.powf(4.0 * s.next_1d());
                    Node {
                        bounds: Aabb::from_points(p, q),
                        intensity: w,
                        flux_bound: Rgb::splat(w),
                        l_max: (q - p).length(),
                        power: Rgb::splat(w),
                        rep: i as u32,
                        left: NONE,
                        right: NONE,
                        count: 1,
                    }
                })
                .collect();
            let scene = leaves.iter().fold(Aabb::EMPTY, |acc, l| acc.union(&l.bounds));
            let mut order: Vec<(u32, u32)> = leaves
                .iter()
                .enumerate()
                .map(|(i, l)| (morton(l.bounds.center(), &scene), i as u32))
                .collect();
            order.sort_unstable();
            let run = |cache: bool| {
                let mut nodes = leaves.clone();
                let mut scratch = PlocScratch::default();
                scratch.clusters.extend(order.iter().map(|&(_, i)| Cluster::of(&nodes[i as usize], i)));
                let root = ploc_with(&mut nodes, &mut scratch, radius, 7, cache);
                (nodes, root)
            };
            let (a, ra) = run(true);
            let (b, rb) = run(false);
            assert_eq!(ra, rb, "n = {n}, radius = {radius}");
            assert_eq!(a.len(), 2 * n - 1);
            for (x, y) in a.iter().zip(&b) {
                assert_eq!((x.left, x.right, x.rep), (y.left, y.right, y.rep), "n = {n}, radius = {radius}");
            }
        }
    }
}
