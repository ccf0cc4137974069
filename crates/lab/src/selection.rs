//! The selection-variance probe: how much variance the stochastic cut's choice of one light adds,
//! per camera segment (docs/lightcuts.md, "Choosing the importance"; `examples/selection_probe.rs`).
//!
//! For a probed segment and tree, with `c_i` each light's mean contribution (over
//! [`PROBE_SAMPLES`] joint samples) and `p_i` a selection probability, sampling one light and
//! dividing by its probability has relative variance
//!
//! ```text
//! V(p) = sum_i c_i^2 / p_i / (sum_i c_i)^2 - 1        (0 when p_i is proportional to c_i)
//! ```
//!
//! reported for the tree's descent from the root (`k = 1`), for probabilities proportional to
//! power alone, and for probabilities proportional to each leaf's own importance (the tree's
//! structure taken out). [`SelectionProbe`] watches the cuts of a render through
//! `haze_manylight::integrators::Observed`, so the shipped integrator has no check of its own
//! on the hot path.

use haze_core::rng::mix64;
use haze_manylight::integrators::{Clamps, ClusterKind, CutObserver, SegmentCut};
use haze_manylight::tree::stochastic::{light_probabilities, power as tree_power};
use std::sync::Mutex;

/// Joint samples averaged per light for its mean contribution.
pub const PROBE_SAMPLES: u64 = 16;

/// Separates the probe's choice of segments from every stream of the image.
const PROBE_STREAM: u64 = 0x7072_6f62_6570_726f;

/// One probed camera segment and tree.
#[derive(Clone, Copy, Debug)]
pub struct SelectionRecord {
    pub lights: usize,
    /// `sum_i c_i` (channels summed).
    pub sum: f64,
    /// `V` of the tree's descent from the root.
    pub tree: f64,
    /// `V` of `p_i` proportional to power.
    pub power: f64,
    /// `V` of `p_i` proportional to each leaf's importance.
    pub leaves: f64,
    /// The joint sampling's own variance through the tree's descent,
    /// `sum_i Var_i / p_i / (sum_i c_i)^2` (`Var_i` the variance of one sample of light `i`).
    pub joint_tree: f64,
    /// The same with every light evaluated (brute force): `sum_i Var_i / (sum_i c_i)^2`.
    pub joint_all: f64,
}

/// Records one camera segment in `every` (by a hash of its key) into
/// [`SelectionProbe::take_records`]; render with `Observed { integrator, observer: &probe }`.
pub struct SelectionProbe {
    every: u64,
    records: Mutex<Vec<SelectionRecord>>,
}

impl SelectionProbe {
    /// `every` is at least 1.
    pub fn new(every: u64) -> Self {
        SelectionProbe { every: every.max(1), records: Mutex::new(Vec::new()) }
    }

    /// The records so far, emptying the store.
    pub fn take_records(&self) -> Vec<SelectionRecord> {
        std::mem::take(&mut *self.records.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

impl<K: ClusterKind> CutObserver<K> for SelectionProbe {
    fn stochastic_cut(&self, cut: &SegmentCut<'_, K>) {
        if mix64(cut.key ^ PROBE_STREAM) % self.every == 0 {
            if let Some(r) = record(cut) {
                self.records.lock().unwrap_or_else(|e| e.into_inner()).push(r);
            }
        }
    }
}

/// `V(p)` of the module docs for unnormalised weights `w` (infinite if a contributing light
/// has weight 0).
fn relative_variance(c: &[f64], w: &[f64]) -> f64 {
    let (sum, norm) = (c.iter().sum::<f64>(), w.iter().sum::<f64>());
    let mut v = 0.0;
    for (&ci, &wi) in c.iter().zip(w) {
        if ci != 0.0 {
            if wi <= 0.0 {
                return f64::INFINITY;
            }
            v += ci * ci * norm / wi;
        }
    }
    v / (sum * sum) - 1.0
}

/// The record of one stochastic cut (`None` when its lights contribute nothing).
fn record<K: ClusterKind>(cut: &SegmentCut<'_, K>) -> Option<SelectionRecord> {
    let SegmentCut { scene, media, cs, key, forest, importance, power_share: share } = *cut;
    let n = forest.lights.len();
    // Mean and sample variance of each light's contribution over PROBE_SAMPLES joint samples.
    let (c, var): (Vec<f64>, Vec<f64>) = forest
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let (mut s1, mut s2) = (0.0, 0.0);
            for m in 0..PROBE_SAMPLES {
                let v =
                    K::contribution(scene, cs, media, l, mix64(key ^ (m + 1)), i as u32, &Clamps::default());
                let x = (v[0] + v[1] + v[2]) as f64;
                s1 += x;
                s2 += x * x;
            }
            let n = PROBE_SAMPLES as f64;
            let mean = s1 / n;
            (mean, ((s2 - n * mean * mean) / (n - 1.0)).max(0.0))
        })
        .unzip();
    let sum: f64 = c.iter().sum();
    if !(sum > 0.0 && sum.is_finite()) {
        return None;
    }
    let mut tree = vec![0.0; n];
    for (light, p) in light_probabilities(&forest.sample, 0, &importance, share) {
        tree[light as usize] = p;
    }
    let (mut leaves, mut power) = (vec![0.0; n], vec![0.0; n]);
    let mut stack = vec![0u32];
    while let Some(id) = stack.pop() {
        let node = forest.sample.node(id);
        if node.is_leaf() {
            leaves[node.light() as usize] = importance(node) as f64;
            power[node.light() as usize] = tree_power(node) as f64;
        } else {
            stack.extend(node.children());
        }
    }
    let joint_tree = var.iter().zip(&tree).map(|(&v, &p)| if v > 0.0 { v / p } else { 0.0 }).sum::<f64>();
    let joint_all = var.iter().sum::<f64>();
    Some(SelectionRecord {
        lights: n,
        sum,
        tree: relative_variance(&c, &tree),
        power: relative_variance(&c, &power),
        leaves: relative_variance(&c, &leaves),
        joint_tree: joint_tree / (sum * sum),
        joint_all: joint_all / (sum * sum),
    })
}

#[cfg(test)]
mod tests {
    use super::relative_variance;

    /// Proportional probabilities add nothing; uniform ones over two lights 1 and 3 add
    /// `(1/0.5 + 9/0.5) / 16 - 1 = 0.25`.
    #[test]
    fn relative_variance_of_simple_cases() {
        assert!(relative_variance(&[1.0, 3.0], &[2.0, 6.0]).abs() < 1e-12);
        assert!((relative_variance(&[1.0, 3.0], &[1.0, 1.0]) - 0.25).abs() < 1e-12);
        assert!(relative_variance(&[1.0, 3.0], &[0.0, 1.0]).is_infinite());
    }
}
