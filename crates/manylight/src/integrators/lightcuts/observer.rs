//! A hook on each camera segment's stochastic cut, for measurements that need the cut's inputs
//! (`haze-lab`'s selection-variance probe). Renders pass `()`, whose empty method the compiler
//! removes: the shipped integrator checks nothing per segment.

use super::{ClusterKind, Forest};
use crate::camera::CameraSegment;
use crate::tree::stochastic::SampleNode;
use crate::vrl::VrlMedium;
use haze_scene::Scene;

/// What one stochastic cut of one tree for one camera segment saw.
pub struct SegmentCut<'a, K: ClusterKind> {
    pub scene: &'a Scene,
    /// The pass's media table (`ClusterKind::contribution`'s `media`).
    pub media: &'a [VrlMedium],
    pub cs: &'a CameraSegment,
    /// The segment's key: `ClusterKind::contribution(.., key, i)` is light `i`'s sample in the
    /// image.
    pub key: u64,
    pub forest: &'a Forest<K>,
    /// The importance the descent used (leaves by `ClusterKind::leaf_importance`).
    pub importance: &'a dyn Fn(&SampleNode) -> f32,
    /// The descent's power share `a` (`StochasticSettings::power_share`).
    pub power_share: f32,
}

/// Sees every stochastic cut of a camera segment, after its estimate; it cannot change the
/// estimate, so an observed render is the image's render.
pub trait CutObserver<K: ClusterKind>: Sync {
    fn stochastic_cut(&self, cut: &SegmentCut<'_, K>);
}

/// No observer: what renders use.
impl<K: ClusterKind> CutObserver<K> for () {
    #[inline(always)]
    fn stochastic_cut(&self, _: &SegmentCut<'_, K>) {}
}
