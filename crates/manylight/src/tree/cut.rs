//! Choosing a cut of the light tree for one camera segment (Walter et al. 2005, applied per
//! camera segment as in Vibert et al. 2019; `docs/theory.md` §8).
//!
//! Start with the root, estimated by its representative's sampled contribution times
//! `I_node / I_rep`. Repeatedly replace the node with the largest bound by its two children
//! until that bound is at most `epsilon` times the current total estimate (both compared by
//! their largest channel) or the cut has `max_cut` nodes. A child that shares its parent's
//! representative reuses its sample; leaves are their own light's sampled contribution.
//! With `epsilon = 0` and no size limit every leaf is evaluated: the brute-force sum.

use super::heap::Keyed;
use super::{LightTree, Node};
use haze_core::Rgb;
use std::collections::BinaryHeap;

/// What the cut needs from a light kind: bounds of nodes and sampled contributions of lights.
pub trait ClusterOracle {
    /// Upper bound of the contribution of any light of node `index` (`node` is
    /// `tree.nodes[index]`), largest channel.
    fn bound(&self, index: u32, node: &Node) -> f32;
    /// One sampled contribution of light `light` to the current camera segment.
    fn contribution(&mut self, light: u32) -> Rgb;
}

#[derive(Clone, Copy, Debug)]
pub struct CutSettings {
    pub epsilon: f32,
    pub max_cut: u32,
}

impl Default for CutSettings {
    fn default() -> Self {
        CutSettings { epsilon: 0.02, max_cut: 1000 }
    }
}

/// Statistics of one cut.
#[derive(Clone, Copy, Debug, Default)]
pub struct CutStats {
    /// Nodes in the final cut.
    pub size: u32,
    /// The cut stopped at `max_cut` before meeting the error criterion.
    pub hit_max: bool,
}

/// What the paper's cut keeps beside a node of its frontier (keyed by the node's bound).
#[derive(Clone, Copy, Debug)]
struct Sampled {
    /// The representative's sampled contribution (unscaled), reused by a child that shares it.
    contribution: Rgb,
    estimate: Rgb,
}

type Entry = Keyed<Sampled>;

/// Reusable heap for [`lightcut`] (one per thread: the per-segment loop allocates nothing once
/// it has grown).
#[derive(Default)]
pub struct CutScratch {
    heap: BinaryHeap<Entry>,
}

/// Estimates the sum of all lights' contributions with a lightcut. Returns the estimate and the
/// cut's statistics.
pub fn lightcut(
    tree: &LightTree,
    oracle: &mut impl ClusterOracle,
    settings: &CutSettings,
    scratch: &mut CutScratch,
) -> (Rgb, CutStats) {
    if tree.is_empty() {
        return (Rgb::ZERO, CutStats::default());
    }
    let nodes = &tree.nodes;
    // Leaves come first in `nodes`, indexed by light: a light's intensity is its leaf's.
    let scaled = |node: &Node, c: Rgb| {
        if node.is_leaf() {
            c
        } else {
            let i_rep = nodes[node.rep as usize].intensity;
            if i_rep > 0.0 {
                c * (node.intensity / i_rep)
            } else {
                Rgb::ZERO
            }
        }
    };
    let root = &nodes[tree.root as usize];
    let c = oracle.contribution(root.rep);
    if root.is_leaf() {
        return (c, CutStats { size: 1, hit_max: false });
    }
    let heap = &mut scratch.heap;
    heap.clear();
    let est = scaled(root, c);
    heap.push(Entry {
        key: oracle.bound(tree.root, root),
        node: tree.root,
        data: Sampled { contribution: c, estimate: est },
    });
    let mut total = est;
    let mut leaf_sum = Rgb::ZERO;
    let mut leaves = 0u32;
    let mut hit_max = false;
    while let Some(top) = heap.peek() {
        if top.key <= settings.epsilon * total.max_component() {
            break;
        }
        if heap.len() as u32 + leaves >= settings.max_cut {
            hit_max = true;
            break;
        }
        let top = heap.pop().expect("peeked");
        total = total - top.data.estimate;
        let node = &nodes[top.node as usize];
        for child in [node.left, node.right] {
            let cn = &nodes[child as usize];
            let cc = if cn.rep == node.rep { top.data.contribution } else { oracle.contribution(cn.rep) };
            let ce = scaled(cn, cc);
            total += ce;
            if cn.is_leaf() {
                leaf_sum += ce;
                leaves += 1;
            } else {
                heap.push(Entry {
                    key: oracle.bound(child, cn),
                    node: child,
                    data: Sampled { contribution: cc, estimate: ce },
                });
            }
        }
    }
    // Sum the final cut afresh rather than trusting the running total's rounding.
    let sum = heap.iter().fold(leaf_sum, |acc, e| acc + e.data.estimate);
    (sum, CutStats { size: heap.len() as u32 + leaves, hit_max })
}
