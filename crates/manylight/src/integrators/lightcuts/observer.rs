//! A hook on each camera segment's stochastic cut, for measurements that need the cut's inputs
//! (`haze-lab`'s selection-variance probe), rendered through [`Observed`]. Renders pass `()`,
//! whose empty method the compiler removes: the shipped integrator checks nothing per segment.

use super::{ClusterKind, CutStrategy, Forest, LightcutGather, LightcutPass, LightcutsIntegrator};
use crate::camera::CameraSegment;
use crate::gather::whole_path_radiance;
use crate::tree::stochastic::SampleNode;
use crate::vrl::VrlMedium;
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::{MediumId, Scene};

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

/// `integrator` with `observer` shown each stochastic cut of a camera segment: an integrator
/// whose image is `integrator`'s, bit for bit.
pub struct Observed<'a, K: ClusterKind, S: CutStrategy, O> {
    pub integrator: &'a LightcutsIntegrator<K, S>,
    pub observer: &'a O,
}

impl<K: ClusterKind, S: CutStrategy, O: CutObserver<K>> Integrator for Observed<'_, K, S, O> {
    type PassData = LightcutPass<K, S>;

    fn name(&self) -> &str {
        self.integrator.name()
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass<K, S> {
        self.integrator.begin_pass(scene, seed, pass)
    }

    fn pixel_light(&self, pass: &LightcutPass<K, S>, pixel: u64) -> Rgb {
        self.integrator.pixel_light(pass, pixel)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K, S>,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        let gather = LightcutGather::new(self.integrator, scene, pass, self.observer);
        whole_path_radiance(scene, ray, medium, sampler, &gather)
    }
}
