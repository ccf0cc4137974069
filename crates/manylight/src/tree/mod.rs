//! The light tree over virtual lights (Walter et al. 2005 "Lightcuts"; Vibert et al. 2019 for
//! VRLs): a binary tree whose nodes bound a cluster of lights, built in parallel
//! ([`build`]), with the cluster bounds of the paper ([`bound`]) and the per-camera-segment
//! cut ([`cut`]).
//!
//! Nodes are stored flat; leaves hold one light each. Every node carries a *representative*
//! light chosen at build time with probability proportional to its scalar intensity, so that
//! `contribution(rep) * I_node / I_rep` is an unbiased estimate of the whole cluster.

pub mod bound;
pub mod build;
pub mod cone;
pub mod cut;
mod heap;
pub mod importance;
pub mod lights;
pub mod stochastic;

use glam::Vec3;
use haze_core::Rgb;

/// What the tree needs to know about a light (VRLs and VPLs share the tree code).
pub trait TreeLight: Sync {
    /// Bounding box of the light (a segment's endpoints, or a point).
    fn bounds(&self) -> Aabb;
    /// Scalar intensity for the clustering metric and the choice of representatives; must be
    /// positive for lights that carry energy.
    fn intensity(&self) -> f32;
    /// Upper bound of the light's flux anywhere on it, per channel (for cluster bounds).
    fn flux_bound(&self) -> Rgb;
    /// Length of the light (0 for points).
    fn length(&self) -> f32;
    /// The light's power for importance sampling, per channel: `Int_0^L Phi(v) dv` for a VRL
    /// (flux integrated along its length), the flux for a point light. Positive in every
    /// channel the light can contribute to.
    fn power(&self) -> Rgb;
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { lo: Vec3::splat(f32::INFINITY), hi: Vec3::splat(f32::NEG_INFINITY) };

    pub fn from_points(a: Vec3, b: Vec3) -> Self {
        Aabb { lo: a.min(b), hi: a.max(b) }
    }
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }
    pub fn diagonal(&self) -> f32 {
        (self.hi - self.lo).max(Vec3::ZERO).length()
    }
    pub fn center(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
    pub fn contains(&self, o: &Aabb) -> bool {
        self.lo.cmple(o.lo).all() && self.hi.cmpge(o.hi).all()
    }
}

/// Sentinel for "no child" (leaves).
pub const NONE: u32 = u32::MAX;

/// A node of the light tree. Leaves have `left == NONE` and `light` = their light's index.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub bounds: Aabb,
    /// Sum of the lights' scalar intensities.
    pub intensity: f32,
    /// Sum of the lights' flux bounds, per channel.
    pub flux_bound: Rgb,
    /// Longest light below (the paper's `L_max`).
    pub l_max: f32,
    /// Sum of the lights' [`TreeLight::power`], per channel (the stochastic cut's importance).
    pub power: Rgb,
    /// Representative light (index into the light array).
    pub rep: u32,
    pub left: u32,
    pub right: u32,
    /// Number of lights below.
    pub count: u32,
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.left == NONE
    }
}

/// A light tree: `nodes[root]` covers every light.
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    pub nodes: Vec<Node>,
    pub root: u32,
}

impl LightTree {
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Checks the invariants the cut relies on, returning the first violation: every light in
    /// exactly one leaf, children's boxes inside their parent's, intensities and flux bounds
    /// summing, `l_max` the longest light below, the representative a light of the subtree.
    pub fn check<L: TreeLight>(&self, lights: &[L]) -> Result<(), String> {
        if lights.is_empty() {
            return if self.nodes.is_empty() { Ok(()) } else { Err("nodes without lights".into()) };
        }
        let mut seen = vec![0u32; lights.len()];
        let mut stack = vec![self.root];
        let mut leaves_below = vec![Vec::<u32>::new(); self.nodes.len()];
        // Post-order via two passes: collect order, then verify bottom-up.
        let mut order = Vec::new();
        while let Some(n) = stack.pop() {
            order.push(n);
            let node = &self.nodes[n as usize];
            if !node.is_leaf() {
                stack.push(node.left);
                stack.push(node.right);
            }
        }
        for &n in order.iter().rev() {
            let node = &self.nodes[n as usize];
            let rel = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) + 1e-20;
            if node.is_leaf() {
                let l = node.rep as usize;
                seen[l] += 1;
                leaves_below[n as usize] = vec![node.rep];
                let lb = lights[l].bounds();
                if !node.bounds.contains(&lb) {
                    return Err(format!("leaf {n}: box does not contain its light"));
                }
                if !rel(node.intensity, lights[l].intensity())
                    || node.l_max != lights[l].length()
                    || node.power != lights[l].power()
                {
                    return Err(format!("leaf {n}: intensity, length or power differs from its light"));
                }
            } else {
                let (a, b) = (&self.nodes[node.left as usize], &self.nodes[node.right as usize]);
                if !node.bounds.contains(&a.bounds) || !node.bounds.contains(&b.bounds) {
                    return Err(format!("node {n}: a child's box is not inside its own"));
                }
                if !rel(node.intensity, a.intensity + b.intensity) {
                    return Err(format!(
                        "node {n}: intensity {} != {} + {}",
                        node.intensity, a.intensity, b.intensity
                    ));
                }
                for c in 0..3 {
                    if !rel(node.flux_bound[c], a.flux_bound[c] + b.flux_bound[c]) {
                        return Err(format!("node {n}: flux bound does not sum"));
                    }
                    if !rel(node.power[c], a.power[c] + b.power[c]) {
                        return Err(format!("node {n}: power does not sum"));
                    }
                }
                if node.l_max != a.l_max.max(b.l_max) || node.count != a.count + b.count {
                    return Err(format!("node {n}: l_max or count wrong"));
                }
                let mut below = std::mem::take(&mut leaves_below[node.left as usize]);
                below.extend(std::mem::take(&mut leaves_below[node.right as usize]));
                if !below.contains(&node.rep) {
                    return Err(format!("node {n}: representative {} is not in its subtree", node.rep));
                }
                leaves_below[n as usize] = below;
            }
        }
        if let Some(i) = seen.iter().position(|&k| k != 1) {
            return Err(format!("light {i} is in {} leaves", seen[i]));
        }
        Ok(())
    }
}
