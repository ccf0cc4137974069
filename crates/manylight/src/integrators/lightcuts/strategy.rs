//! The cut strategy: how [`super::LightcutsIntegrator`] sums a pass's lights at a camera segment
//! and at a gathering point. One type per strategy, each owning its settings:
//! [`super::ExhaustiveCut`] (every light, no tree: `vrl`, `vpl`), [`super::StochasticCut`]
//! (bound-free, `--cut stochastic`) and [`super::BoundCut`] (the paper's cut by bounds,
//! `--cut bound`). The integrator is generic over the strategy, so a render dispatches on it
//! once, at compile time, never per light.

use super::{Clamps, ClusterKind, CutObserver, Forest, LightcutPass, Stats, SurfaceVpls};
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::vpl::SurfaceVpl;
use crate::vrl::VrlMedium;
use haze_core::Rgb;
use haze_scene::Scene;

/// How a pass's lights are summed.
///
/// Invariant: every strategy estimates the same sum, over the pass's lights (medium lights of
/// both groups and surface VPLs), of each light's sampled contribution
/// (`LightKind::contribution` at a camera segment, `LightKind::to_point` at a gathering
/// point): the exhaustive cut adds all of them; a tree cut evaluates some, each weighted by the
/// inverse of its probability (stochastic) or by its node's intensity over its own (the bound
/// cut's representatives, `tree::cut`). At a camera segment, light `i` of a group draws
/// `light_uniforms(key, i)` whatever the strategy, so a bound cut refined to every leaf equals
/// the exhaustive cut up to the order of the sum.
pub trait CutStrategy: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// What the strategy computes once per pass besides the forests, from the pass's media
    /// (the bound cut's per-medium factors, `super::bound::BoundPass`; `()` for the others).
    type PassData: Send + Sync;

    /// The integrator's name for light kind `K` (`vrl`, `vrl_lightcuts`, ...).
    fn name<K: ClusterKind>(&self) -> &'static str;

    /// The pass's [`CutStrategy::PassData`]; called once per pass.
    fn pass_data(&self, scene: &Scene, media: &[VrlMedium]) -> Self::PassData;

    /// The pass's forests from its lights: the medium lights' two groups (medium-only, after a
    /// surface bounce) and the surface VPLs, with trees built from `seed` if the strategy cuts
    /// trees. Called once per pass, before any [`CutStrategy::segment`] or
    /// [`CutStrategy::point`].
    fn forests<K: ClusterKind>(
        &self,
        lights: [Vec<K::Light>; 2],
        surface: Vec<SurfaceVpl>,
        media: &[VrlMedium],
        seed: u64,
    ) -> ([Forest<K>; 2], Forest<SurfaceVpls>);

    /// The estimate of `gather::Gather::segment`'s two sums for camera segment `cs`: the
    /// medium-only lights, then the lights after a surface bounce plus the surface VPLs.
    /// `observer` sees every stochastic cut of a medium tree.
    fn segment<K: ClusterKind, O: CutObserver<K>>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        observer: &O,
    ) -> [Rgb; 2];

    /// The estimate of the sum over every light of the pass of its light at the gathering
    /// surface point `gp` (`gather::Gather::point`).
    fn point<K: ClusterKind>(&self, view: &PassView<'_, K, Self>, gp: &GatherPoint, key: u64) -> Rgb;

    /// The summary line's account of the cuts, from the mean and largest cut size per camera
    /// segment and tree and the fraction of segments that hit a size limit; `None` for a
    /// strategy that cuts no tree.
    fn describe(&self, mean: f64, max: u64, hit: f64) -> Option<String>;
}

/// What a strategy reads while it sums lights: the scene, the pass, the integrator's clamps
/// and its counters.
pub struct PassView<'a, K: ClusterKind, S: CutStrategy> {
    pub(super) scene: &'a Scene,
    pub(super) pass: &'a LightcutPass<K, S>,
    pub(super) clamps: &'a Clamps,
    pub(super) stats: &'a Stats,
}
