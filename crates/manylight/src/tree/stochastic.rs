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
}

impl Default for StochasticSettings {
    /// `cut_size` 1, power share 0.1: at equal time one light per camera segment and tree beat
    /// 2, 4 and 8 on the smoke room and the spot beam (docs/lightcuts.md, "Choosing the
    /// defaults"): more camera samples pay more than more lights per sample.
    fn default() -> Self {
        StochasticSettings { cut_size: 1, power_share: 0.1 }
    }
}

/// A node of [`SampleTree`]: what the importance needs (box centre and half-diagonal, summed
/// power) and where its children are, in 32 bytes.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct SampleNode {
    pub center: Vec3,
    /// Half the box's diagonal.
    pub radius: f32,
    /// Summed [`super::TreeLight::power`] of the lights below.
    pub power: Rgb,
    /// Inner node: index of the left child, the right child is next to it. Leaf: the light's
    /// index with [`LEAF`] set.
    link: u32,
}

/// Marks a leaf's `link`.
const LEAF: u32 = 1 << 31;

impl SampleNode {
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

/// A [`LightTree`] laid out for the descents: 32-byte nodes in depth-first order, the root at
/// 0 and both children of a node side by side, so one descent step reads one or two cache
/// lines instead of two 72-byte nodes anywhere in memory (the cost per level then hardly
/// depends on the tree's size: docs/lightcuts.md, scaling table).
#[derive(Clone, Debug, Default)]
pub struct SampleTree {
    pub nodes: Vec<SampleNode>,
}

impl SampleTree {
    /// The layout of `tree` (at most `2^31` lights).
    pub fn new(tree: &LightTree) -> Self {
        if tree.is_empty() {
            return SampleTree::default();
        }
        let of = |i: u32| {
            let n = &tree.nodes[i as usize];
            SampleNode {
                center: n.bounds.center(),
                radius: 0.5 * n.bounds.diagonal(),
                power: n.power,
                link: if n.is_leaf() { n.rep | LEAF } else { 0 },
            }
        };
        let mut nodes = Vec::with_capacity(tree.nodes.len());
        nodes.push(of(tree.root));
        let mut stack = vec![(tree.root, 0u32)];
        while let Some((src, dst)) = stack.pop() {
            let n = &tree.nodes[src as usize];
            if n.is_leaf() {
                continue;
            }
            let k = nodes.len() as u32;
            nodes[dst as usize].link = k;
            nodes.push(of(n.left));
            nodes.push(of(n.right));
            stack.push((n.right, k + 1));
            stack.push((n.left, k));
        }
        SampleTree { nodes }
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// Scalar power of a node (sum of channels).
#[inline]
fn power(node: &SampleNode) -> f32 {
    node.power[0] + node.power[1] + node.power[2]
}

/// Probability of going to the left child (module docs). Falls back to the power share where
/// the importances are all zero or not finite, and to 1/2 where the powers are too.
#[inline]
pub fn left_probability(left: &SampleNode, right: &SampleNode, i_left: f32, i_right: f32, share: f32) -> f32 {
    let (pl, pr) = (power(left), power(right));
    let by_power = if pl + pr > 0.0 && (pl + pr).is_finite() { pl / (pl + pr) } else { 0.5 };
    let sum = i_left + i_right;
    if sum > 0.0 && sum.is_finite() {
        (1.0 - share) * (i_left / sum) + share * by_power
    } else {
        by_power
    }
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
    let nodes = &tree.nodes;
    if nodes[0].is_leaf() {
        cut.push(0);
        return cut;
    }
    heap.push(Entry::new(importance(&nodes[0]), 0));
    // `cut` holds the leaves reached so far; the heap the inner nodes.
    while heap.len() + cut.len() < cut_size.max(1) as usize {
        let Some(top) = heap.pop() else { break };
        for child in nodes[top.node as usize].children() {
            let c = &nodes[child as usize];
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
    let nodes = &tree.nodes;
    let mut n = &nodes[start as usize];
    let mut prob = 1.0f32;
    while !n.is_leaf() {
        let [li, ri] = n.children();
        let (l, r) = (&nodes[li as usize], &nodes[ri as usize]);
        // Both grandchildren pairs are fetched while the children's importances are computed:
        // the descent's cost is memory latency once the tree outgrows the caches.
        prefetch(nodes, l);
        prefetch(nodes, r);
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

/// Asks the CPU to fetch the children pair of `node` (a hint; nothing on other targets).
#[inline(always)]
fn prefetch(nodes: &[SampleNode], node: &SampleNode) {
    #[cfg(target_arch = "x86_64")]
    if !node.is_leaf() {
        if let Some(pair) = nodes.get(node.link as usize) {
            // SAFETY: prefetching is a hint; any address is allowed, and this one is in bounds.
            unsafe {
                use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                _mm_prefetch::<_MM_HINT_T0>((pair as *const SampleNode).cast());
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (nodes, node);
}

/// The probability of every light below `start` under [`sample_light`] (for tests and
/// diagnostics; walks the whole subtree).
pub fn light_probabilities(
    tree: &SampleTree,
    start: u32,
    importance: &impl Fn(&SampleNode) -> f32,
    share: f32,
) -> Vec<(u32, f64)> {
    let nodes = &tree.nodes;
    let mut out = Vec::new();
    let mut stack = vec![(start, 1.0f64)];
    while let Some((i, prob)) = stack.pop() {
        let n = &nodes[i as usize];
        if n.is_leaf() {
            out.push((n.light(), prob));
            continue;
        }
        let [li, ri] = n.children();
        let (l, r) = (&nodes[li as usize], &nodes[ri as usize]);
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
        let mut rng = mix64(key ^ mix64(start as u64 ^ 0x5eed_c0de_d1ce_f00d));
        let (light, prob) = sample_light(tree, start, importance, settings.power_share, &mut rng);
        if prob > 0.0 {
            evaluate(light, prob);
        }
    }
    cut.len() as u32
}
