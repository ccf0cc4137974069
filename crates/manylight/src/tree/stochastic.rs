//! The stochastic, bound-free lightcut (ours; in the spirit of Lin & Yuksel 2020's real-time
//! stochastic lightcuts and of the light-tree samplers of pbrt-v4 and Cycles; docs/lightcuts.md,
//! "Stochastic cut").
//!
//! Per camera segment:
//! 1. **Cut.** Start with the root and repeatedly replace the inner node of largest importance
//!    ([`super::importance`]) by its two children until the cut has `k` nodes (or only leaves).
//!    The cut is a deterministic function of the segment, so it does not bias anything.
//! 2. **Sample.** In each cut node, descend to one light, going left with probability
//!
//!    ```text
//!    p_left = (1 - a) I_l / (I_l + I_r) + a P_l / (P_l + P_r)
//!    ```
//!
//!    (`I` importance, `P` summed power, `a` the power share). The light's probability is the
//!    product of the choices on its way down; its sampled contribution divided by that
//!    probability is an unbiased estimate of the cut node's sum, because every light with
//!    non-zero power has a positive probability (the power share) and lights without power
//!    contribute nothing. Summing over the disjoint cut nodes estimates the sum over all lights.
//!
//! The random numbers of a descent come from a hash of the segment key and the cut node, so the
//! result does not depend on evaluation order or thread count.

use super::heap::Keyed;
use super::LightTree;
use glam::Vec3;
use haze_core::rng::mix64;
use haze_core::Rgb;
use std::collections::BinaryHeap;

/// Settings of the stochastic cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StochasticSettings {
    /// Nodes in the cut (`--cut-size`): lights sampled per camera segment and tree.
    pub cut_size: u32,
    /// Share `a` of the child probability given by power alone (module docs), in `(0, 1]`.
    pub power_share: f32,
    /// Joint samples of each sampled light (`--light-samples`), averaged (not used by the
    /// traversal itself; the integrator evaluates them).
    pub light_samples: u32,
}

impl Default for StochasticSettings {
    /// `cut_size` 1, power share 0.1: at equal time one light per camera segment and tree beat
    /// 2, 4 and 8 on the smoke room and the spot beam (docs/lightcuts.md, "Choosing the
    /// defaults"): more camera samples pay more than more lights per sample.
    fn default() -> Self {
        StochasticSettings { cut_size: 1, power_share: 0.1, light_samples: 1 }
    }
}

/// A node of [`SampleTree`]: what the importance needs (power centroid and equivalent radius,
/// [`power_moments`]; summed power) and where its children are, in 32 bytes.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct SampleNode {
    /// Power-weighted centroid of the lights below.
    pub center: Vec3,
    /// `sqrt(3)` times their power-weighted RMS distance from `center` (the half-diagonal for
    /// one segment or a uniform box).
    pub radius: f32,
    /// Summed [`super::TreeLight::power`] of the lights below.
    pub power: Rgb,
    /// Inner node: index of the left child, the right child is next to it (the two share one
    /// cache line). Leaf: the light's index with [`LEAF`] set.
    link: u32,
}

/// Marks a leaf's `link`.
const LEAF: u32 = 1 << 31;

impl SampleNode {
    /// A point light's node (no tree link): for importances of single lights.
    pub fn point(p: Vec3, power: Rgb) -> Self {
        SampleNode { center: p, radius: 0.0, power, link: LEAF }
    }
    pub fn is_leaf(&self) -> bool {
        self.link & LEAF != 0
    }
    /// The light of a leaf.
    pub fn light(&self) -> u32 {
        self.link & !LEAF
    }
    /// The children of an inner node.
    pub fn children(&self) -> [u32; 2] {
        [self.link, self.link + 1]
    }
}

/// Two sibling nodes in one 64-byte cache line: a descent step reads exactly one line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct NodePair([SampleNode; 2]);

/// Node pairs per block: a node's children, then the children of each (two levels, 192 bytes).
const BLOCK: usize = 3;
/// Block levels per treelet: `1 + 4 + 16 = 21` blocks, 4032 bytes, one 4 KiB page.
const TREELET_LEVELS: usize = 3;

/// A [`LightTree`] laid out for the descents (docs/lightcuts.md, "Cost per camera segment").
///
/// - 32-byte nodes, siblings side by side in one aligned 64-byte line ([`NodePair`]); node ids
///   are `2 * pair + side`, the root is node 0, alone in pair 0.
/// - **Blocks of two levels**: below an inner node `X` the three pairs `X`'s children,
///   `X.left`'s children and `X.right`'s children are stored consecutively (a leaf child's
///   pair is left empty). A descent prefetches the whole block as soon as it knows `X`, so it
///   waits for memory once per two levels instead of once per level.
/// - **Treelets**: three levels of blocks (six levels of the tree) below a node lie together,
///   breadth first, in one 4 KiB page, so a descent through `L` levels touches about `L / 6`
///   pages.
/// - On Linux the array asks for transparent huge pages (`crate::memory`).
///
/// Once the tree outgrows the caches a descent's cost is memory latency; these choices cut the
/// number of round trips it waits for. The tree is the same binary tree as before: only the
/// layout changed, so the probabilities do not.
#[derive(Clone, Debug, Default)]
pub struct SampleTree {
    pairs: Vec<NodePair>,
}

impl SampleTree {
    /// The layout of `tree` (at most `2^31` lights).
    pub fn new(tree: &LightTree) -> Self {
        if tree.is_empty() {
            return SampleTree::default();
        }
        let moments = power_moments(tree);
        let of = |i: u32| {
            let n = &tree.nodes[i as usize];
            let (center, radius) = moments[i as usize];
            SampleNode { center, radius, power: n.power, link: if n.is_leaf() { n.rep | LEAF } else { 0 } }
        };
        let inner = |i: u32| !tree.nodes[i as usize].is_leaf();
        let empty =
            NodePair([SampleNode { center: Vec3::ZERO, radius: 0.0, power: Rgb::ZERO, link: LEAF }; 2]);
        // A block per inner node whose parent's block does not hold its children: about
        // `leaves / 2` blocks of three pairs, plus pair 0.
        let leaves = tree.nodes.iter().filter(|n| n.is_leaf()).count();
        let mut pairs = crate::memory::huge_page_vec::<NodePair>(1 + BLOCK * (leaves / 2 + 1));
        let root = of(tree.root);
        pairs.push(NodePair([root, empty.0[0]]));
        // (source node, destination node id) of treelet roots still to lay out.
        let mut treelets = vec![(tree.root, 0u32)];
        let (mut level, mut next) = (Vec::new(), Vec::new());
        let set_link = |pairs: &mut Vec<NodePair>, id: u32, link: u32| {
            pairs[(id >> 1) as usize].0[(id & 1) as usize].link = link;
        };
        while let Some(top) = treelets.pop() {
            if !inner(top.0) {
                continue;
            }
            level.clear();
            level.push(top);
            for _ in 0..TREELET_LEVELS {
                next.clear();
                for &(src, dst) in &level {
                    // The block of `src`: its children, then each child's children.
                    let n = &tree.nodes[src as usize];
                    let b = pairs.len() as u32;
                    set_link(&mut pairs, dst, 2 * b);
                    pairs.push(NodePair([of(n.left), of(n.right)]));
                    for (side, child) in [n.left, n.right].into_iter().enumerate() {
                        if !inner(child) {
                            pairs.push(empty);
                            continue;
                        }
                        let c = &tree.nodes[child as usize];
                        let at = 2 * (b + 1 + side as u32);
                        set_link(&mut pairs, 2 * b + side as u32, at);
                        pairs.push(NodePair([of(c.left), of(c.right)]));
                        next.extend([(c.left, at), (c.right, at + 1)].into_iter().filter(|&(s, _)| inner(s)));
                    }
                }
                std::mem::swap(&mut level, &mut next);
                if level.is_empty() {
                    break;
                }
            }
            // Inner nodes below the treelet's last blocks root the next treelets (depth first,
            // so that a subtree's treelets stay near each other).
            treelets.extend(level.iter().rev().copied());
        }
        SampleTree { pairs }
    }

    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Node `id` (the root is 0; see [`SampleNode::children`]).
    #[inline(always)]
    pub fn node(&self, id: u32) -> &SampleNode {
        &self.pairs[(id >> 1) as usize].0[(id & 1) as usize]
    }

    /// Number of nodes (the unused slot beside the root included).
    pub fn len(&self) -> usize {
        2 * self.pairs.len()
    }

    /// The two children of an inner node.
    #[inline(always)]
    fn children_of(&self, node: &SampleNode) -> &[SampleNode; 2] {
        &self.pairs[(node.link >> 1) as usize].0
    }
}

/// Per node of `tree`, the power-weighted centroid of its lights and its *equivalent radius*
/// `sqrt(3) * rms`, with `rms^2` the power-weighted mean squared distance of the lights' points
/// from the centroid (a VRL counts as its segment, uniformly: second moment `L^2 / 12` about
/// its midpoint). For a uniform box or a single segment the equivalent radius is the box's
/// half-diagonal; for a cluster whose power sits in a few lights it is much smaller, and the
/// centroid sits where the power is, not where the box's far corners put it. Measured with the
/// selection probe (docs/lightcuts.md, "Choosing the importance"): 1.2-1.9x less selection
/// variance than the box's centre and half-diagonal on all five scenes.
pub fn power_moments(tree: &LightTree) -> Vec<(Vec3, f32)> {
    // (centroid, mean squared distance from it, weight); children precede parents.
    let mut m: Vec<(Vec3, f32, f32)> = Vec::with_capacity(tree.nodes.len());
    for n in &tree.nodes {
        let box_moment = {
            let r = 0.5 * n.bounds.diagonal();
            (n.bounds.center(), r * r / 3.0)
        };
        let w = n.power[0] + n.power[1] + n.power[2];
        let entry = if n.is_leaf() {
            (box_moment.0, box_moment.1, w)
        } else {
            let (a, b) = (m[n.left as usize], m[n.right as usize]);
            let total = a.2 + b.2;
            if total > 0.0 && total.is_finite() {
                let c = (a.0 * a.2 + b.0 * b.2) / total;
                let var = (a.2 * (a.1 + (a.0 - c).length_squared())
                    + b.2 * (b.1 + (b.0 - c).length_squared()))
                    / total;
                (c, var, total)
            } else {
                (box_moment.0, box_moment.1, total)
            }
        };
        m.push(entry);
    }
    m.into_iter().map(|(c, var, _)| (c, (3.0 * var).sqrt())).collect()
}

/// Scalar power of a node (sum of channels).
#[inline]
pub fn power(node: &SampleNode) -> f32 {
    node.power[0] + node.power[1] + node.power[2]
}

/// The probability of one choice among several (module docs): `(1 - a) I / sum_I + a
/// by_power`, with `by_power` the choice's share of the power; `by_power` alone where the
/// importances are all zero or not finite.
#[inline]
pub fn mixed_probability(i: f32, i_sum: f32, by_power: f32, share: f32) -> f32 {
    if i_sum > 0.0 && i_sum.is_finite() {
        (1.0 - share) * (i / i_sum) + share * by_power
    } else {
        by_power
    }
}

/// Probability of going to the left child ([`mixed_probability`]); 1/2 where the powers are
/// all zero or not finite too.
#[inline]
pub fn left_probability(left: &SampleNode, right: &SampleNode, i_left: f32, i_right: f32, share: f32) -> f32 {
    let (pl, pr) = (power(left), power(right));
    let by_power = if pl + pr > 0.0 && (pl + pr).is_finite() { pl / (pl + pr) } else { 0.5 };
    mixed_probability(i_left, i_left + i_right, by_power, share)
}

/// A frontier node keyed by its importance.
type Entry = Keyed;

/// Reusable buffers of [`stochastic_cut`] (one per thread: nothing is allocated per segment
/// once they have grown).
#[derive(Default)]
pub struct StochasticScratch {
    heap: BinaryHeap<Entry>,
    cut: Vec<u32>,
}

impl StochasticScratch {
    /// The cut of the last [`select_cut`] or [`stochastic_cut`].
    pub fn cut(&self) -> &[u32] {
        &self.cut
    }
}

/// The cut of step 1 (module docs) into `scratch`, returned as node indices.
pub fn select_cut<'s>(
    tree: &SampleTree,
    importance: &impl Fn(&SampleNode) -> f32,
    cut_size: u32,
    scratch: &'s mut StochasticScratch,
) -> &'s [u32] {
    let StochasticScratch { heap, cut } = scratch;
    heap.clear();
    cut.clear();
    if tree.is_empty() {
        return cut;
    }
    let root = tree.node(0);
    if root.is_leaf() {
        cut.push(0);
        return cut;
    }
    heap.push(Entry::new(importance(root), 0));
    // `cut` holds the leaves reached so far; the heap the inner nodes.
    while heap.len() + cut.len() < cut_size.max(1) as usize {
        let Some(top) = heap.pop() else { break };
        for child in tree.node(top.node).children() {
            let c = tree.node(child);
            if c.is_leaf() {
                cut.push(child);
            } else {
                heap.push(Entry::new(importance(c), child));
            }
        }
    }
    cut.extend(heap.drain().map(|e| e.node));
    cut
}

/// Descends from node `start` to one light (step 2, module docs) with the uniform numbers of
/// `rng`; returns the light and its probability given `start`.
pub fn sample_light(
    tree: &SampleTree,
    start: u32,
    importance: &impl Fn(&SampleNode) -> f32,
    share: f32,
    rng: &mut u64,
) -> (u32, f32) {
    let mut n = tree.node(start);
    let mut prob = 1.0f32;
    prefetch_block(tree, n);
    while !n.is_leaf() {
        let [l, r] = tree.children_of(n);
        // The children's blocks are fetched while their importances are computed; the pairs
        // of the level after them are in the block fetched one level earlier (type docs).
        prefetch_block(tree, l);
        prefetch_block(tree, r);
        let p = left_probability(l, r, importance(l), importance(r), share);
        *rng = rng.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let u = (mix64(*rng) >> 40) as f32 * (1.0 / (1u32 << 24) as f32);
        if u < p {
            prob *= p;
            n = l;
        } else {
            prob *= 1.0 - p;
            n = r;
        }
    }
    (n.light(), prob)
}

/// Asks the CPU to fetch the block below `node`: its children's pair and, where `node` heads a
/// block, the two pairs after it (a hint; nothing on other targets). Fetching lines of the
/// block that are already cached costs nothing measurable.
#[inline(always)]
fn prefetch_block(tree: &SampleTree, node: &SampleNode) {
    #[cfg(target_arch = "x86_64")]
    if !node.is_leaf() {
        let first = (node.link >> 1) as usize;
        if first + BLOCK <= tree.pairs.len() {
            for pair in &tree.pairs[first..first + BLOCK] {
                // SAFETY: prefetching is a hint; any address is allowed, and this one is in bounds.
                unsafe {
                    use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                    _mm_prefetch::<_MM_HINT_T0>((pair as *const NodePair).cast());
                }
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (tree, node);
}

/// The probability of every light below `start` under [`sample_light`] (for tests and
/// diagnostics; walks the whole subtree).
pub fn light_probabilities(
    tree: &SampleTree,
    start: u32,
    importance: &impl Fn(&SampleNode) -> f32,
    share: f32,
) -> Vec<(u32, f64)> {
    let mut out = Vec::new();
    let mut stack = vec![(start, 1.0f64)];
    while let Some((i, prob)) = stack.pop() {
        let n = tree.node(i);
        if n.is_leaf() {
            out.push((n.light(), prob));
            continue;
        }
        let [li, ri] = n.children();
        let (l, r) = (tree.node(li), tree.node(ri));
        let p = left_probability(l, r, importance(l), importance(r), share) as f64;
        stack.push((li, prob * p));
        stack.push((ri, prob * (1.0 - p)));
    }
    out
}

/// Estimates the sum of all lights' contributions to one camera segment: selects the cut, then
/// samples one light per cut node and calls `evaluate(light, probability)`, which adds that
/// light's sampled contribution divided by the probability to its own accumulator. `key` seeds
/// the descents. Returns the cut's size.
pub fn stochastic_cut(
    tree: &SampleTree,
    importance: &impl Fn(&SampleNode) -> f32,
    settings: &StochasticSettings,
    key: u64,
    scratch: &mut StochasticScratch,
    mut evaluate: impl FnMut(u32, f32),
) -> u32 {
    let cut = select_cut(tree, importance, settings.cut_size, scratch);
    for &start in cut.iter() {
        let mut rng = mix64(key ^ mix64(start as u64 ^ haze_core::streams::CUT_NODE_DESCENT));
        let (light, prob) = sample_light(tree, start, importance, settings.power_share, &mut rng);
        if prob > 0.0 {
            evaluate(light, prob);
        }
    }
    cut.len() as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree::build::{build_agglomerative, build_median_split, BuildSettings};
    use crate::tree::lights::LightSummary;
    use crate::tree::Aabb;
    use haze_core::Sampler;

    fn lights(n: usize, seed: u64) -> Vec<LightSummary> {
        let mut s = Sampler::from_seed(seed);
        (0..n)
            .map(|_| {
                let lo = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
                let p = s.next_1d() * s.next_1d();
                LightSummary {
                    bounds: Aabb { lo, hi: lo + Vec3::splat(s.next_1d()) },
                    intensity: p,
                    flux_bound: Rgb::splat(p),
                    length: 1.0,
                    power: Rgb::new(p, 0.5 * p, 0.0),
                }
            })
            .collect()
    }

    /// Walks the layout and the source tree together: the same nodes (box, power, light) under
    /// the same parents; every block holds its head's children and grandchildren pairs in
    /// order; every light appears once.
    /// Two points of power 1 and 3, 4 apart: centroid 1 from the heavy one, mean squared
    /// distance `(1 * 9 + 3 * 1) / 4 = 3`, equivalent radius 3; a segment alone keeps its
    /// midpoint and half-length.
    #[test]
    fn power_moments_of_two_points_and_a_segment() {
        let point = |x: f32, p: f32| LightSummary {
            bounds: Aabb::from_points(Vec3::new(x, 0.0, 0.0), Vec3::new(x, 0.0, 0.0)),
            intensity: p,
            flux_bound: Rgb::splat(p / 3.0),
            length: 0.0,
            power: Rgb::splat(p / 3.0),
        };
        let tree = build_median_split(&[point(0.0, 1.0), point(4.0, 3.0)], 0);
        let (c, r) = power_moments(&tree)[tree.root as usize];
        assert!((c - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-5 && (r - 3.0).abs() < 1e-5, "{c} {r}");
        let seg = LightSummary {
            bounds: Aabb::from_points(Vec3::ZERO, Vec3::new(2.0, 2.0, 1.0)),
            length: 3.0,
            ..point(0.0, 1.0)
        };
        let tree = build_median_split(&[seg], 0);
        let (c, r) = power_moments(&tree)[tree.root as usize];
        assert!((c - Vec3::new(1.0, 1.0, 0.5)).length() < 1e-6 && (r - 1.5).abs() < 1e-5, "{c} {r}");
    }

    fn check_layout(tree: &LightTree, sample: &SampleTree) {
        let mut seen = vec![false; tree.nodes.iter().filter(|n| n.is_leaf()).count()];
        // (source node, layout id, heads a block)
        let mut stack = vec![(tree.root, 0u32, true)];
        let mut blocks = 0;
        let moments = power_moments(tree);
        while let Some((src, id, head)) = stack.pop() {
            let (n, s) = (&tree.nodes[src as usize], sample.node(id));
            assert_eq!((s.center, s.radius), moments[src as usize]);
            assert_eq!(s.power, n.power);
            if n.is_leaf() {
                assert!(s.is_leaf());
                assert!(!std::mem::replace(&mut seen[s.light() as usize], true), "light twice");
                continue;
            }
            assert!(!s.is_leaf() && s.link % 2 == 0, "children start a pair");
            let [l, r] = s.children();
            if head {
                blocks += 1;
                for (side, (child, cid)) in [(n.left, l), (n.right, r)].into_iter().enumerate() {
                    if !tree.nodes[child as usize].is_leaf() {
                        assert_eq!(sample.node(cid).link, s.link + 2 * (1 + side as u32), "block order");
                    }
                }
            }
            stack.push((n.left, l, !head));
            stack.push((n.right, r, !head));
        }
        assert!(seen.iter().all(|&b| b), "every light in the layout");
        assert!(blocks > 0 || tree.nodes.len() == 1);
        assert!(sample.len() <= 2 * (1 + BLOCK * (seen.len() / 2 + 1)), "the reserved room suffices");
    }

    #[test]
    fn layout_keeps_the_tree() {
        for (n, seed) in [(1, 1), (2, 2), (3, 3), (17, 4), (1000, 5), (4096, 6)] {
            let ls = lights(n, seed);
            check_layout(&build_median_split(&ls, seed), &SampleTree::new(&build_median_split(&ls, seed)));
            let settings = BuildSettings { group_size: 64, seed, ..Default::default() };
            let agg = build_agglomerative(&ls, &settings);
            check_layout(&agg, &SampleTree::new(&agg));
        }
    }
}
