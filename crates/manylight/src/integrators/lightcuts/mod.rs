//! The many-light integrator, generic over the light kind ([`ClusterKind`]) and the cut
//! strategy ([`CutStrategy`]): `vrl_lightcuts` and `vpl_lightcuts` with a tree's cut, `vrl`
//! and `vpl` with the exhaustive cut. Each pass traces its light paths; a tree cut builds a
//! light tree over the VRLs (or VPLs) with the three-step parallel builder, and every camera
//! segment estimates the sum over its lights through a cut of the tree instead of one by one:
//! the stochastic, bound-free cut ([`StochasticCut`], `tree::stochastic`, the default), or the
//! paper's deterministic cut by bounds ([`BoundCut`], `tree::cut`, `--cut bound`). The
//! exhaustive cut ([`ExhaustiveCut`]) builds no tree and evaluates every light, with the same
//! per-light random numbers (`light_uniforms(key, index)`) as a tree's leaves.
//!
//! Lights that follow a surface bounce live in a group (and tree) of their own, so `multiple`
//! and `surface` stay separate. Every method's camera walk is the same (`gather.rs`, the whole
//! image). The surface VPLs ([`SurfaceVpls`]) get a tree of their own, cut stochastically for
//! camera segments; a gathering surface point picks one of the three trees and cuts it
//! stochastically with the point's importance, whatever the tree cut (docs/lightcuts.md "The
//! whole image").

mod bound;
#[cfg(test)]
mod bound_tests;
mod exhaustive;
mod forest;
mod kinds;
mod observer;
mod probe;
mod stochastic;
mod strategy;

pub use bound::BoundCut;
pub use exhaustive::ExhaustiveCut;
pub use forest::{Builder, Forest, TreeSettings};
pub use kinds::{Clamps, ClusterKind, LightKind, SurfaceVpls, Vpls, Vrls};
pub use observer::{CutObserver, Observed, SegmentCut};
pub use probe::CutSizeProbe;
pub use stochastic::StochasticCut;
pub use strategy::{CutStrategy, PassView};

use super::{caustic_tracer, media, paths_per_pass, surface_vpls, ManyLightSettings};
use crate::camera::CameraSegment;
use crate::gather::{whole_path_radiance, Gather, GatherPoint, PathTracedMedia};
use crate::lighttrace::trace_light_paths;
use crate::splat::{CameraSplats, CausticTracer};
use crate::tree::cut::CutStats;
use crate::vrl::VrlMedium;
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Counters reported after rendering.
#[derive(Default)]
struct Stats {
    lights: AtomicU64,
    passes: AtomicU64,
    trace_ns: AtomicU64,
    build_ns: AtomicU64,
    segments: AtomicU64,
    cut_total: AtomicU64,
    cut_max: AtomicU64,
    hit_max: AtomicU64,
    /// Camera segment x light evaluations of the exhaustive cut (`haze bench`'s unit of cost).
    evaluations: AtomicU64,
}

impl Stats {
    /// One tree's cut for one camera segment (none if the cut is empty).
    fn record(&self, s: &CutStats) {
        if s.size == 0 {
            return;
        }
        self.segments.fetch_add(1, Ordering::Relaxed);
        self.cut_total.fetch_add(s.size as u64, Ordering::Relaxed);
        self.cut_max.fetch_max(s.size as u64, Ordering::Relaxed);
        if s.hit_max {
            self.hit_max.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Changes of the estimate that only tests make (`crates/manylight/tests/integrators.rs`): the
/// negative controls, which must fail, and the unsplit walk the split is compared with.
/// `TestControls::default()` is the estimator; other values can be set only with the feature
/// `test-controls`, which only this crate's tests turn on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestControls {
    /// Scale of the virtual lights' light at gathering surface points: 1; off (0) must fail the
    /// whole-image z-test.
    pub gather_point_scale: f32,
    /// Scale of the caustic paths' splats (`crate::splat`): 1; 1.2 must fail the comparison
    /// with the camera continuation.
    pub caustic_scale: f32,
    /// `gather::Gather::split`: `Some(1)`; `None` is the unsplit walk.
    pub split: Option<f32>,
}

impl Default for TestControls {
    fn default() -> Self {
        TestControls { gather_point_scale: 1.0, caustic_scale: 1.0, split: Some(1.0) }
    }
}

/// `vrl_lightcuts` (`LightcutsIntegrator<Vrls>`) and `vpl_lightcuts`
/// (`LightcutsIntegrator<Vpls>`) with a tree cut ([`StochasticCut`], the default, or
/// [`BoundCut`]), and with the exhaustive cut `vrl` and `vpl` ([`LightcutsIntegrator::exhaustive`]):
/// one integrator, generic over the light kind and the cut strategy.
pub struct LightcutsIntegrator<K: ClusterKind, S: CutStrategy = StochasticCut> {
    ml: ManyLightSettings,
    /// The cut strategy and its settings.
    pub strategy: S,
    /// The clamps: the biased ones for `vrl` and `vpl` only (the option table refuses them
    /// elsewhere), the compensated one from [`ManyLightSettings::compensated_clamp`].
    pub clamps: Clamps,
    controls: TestControls,
    paths: u64,
    stats: Stats,
    kind: PhantomData<K>,
    caustics: Option<CausticTracer>,
}

/// What one pass shares between its camera samples: the forests and the media.
pub struct LightcutPass<K: ClusterKind, S: CutStrategy> {
    /// The medium lights' two groups (medium-only, after a surface bounce), with their trees
    /// if the strategy cuts trees.
    forests: [Forest<K>; 2],
    media: Vec<VrlMedium>,
    /// What the strategy computes once per pass (`CutStrategy::pass_data`).
    strategy: S::PassData,
    /// The surface VPLs, with a tree if the strategy cuts trees.
    surface: Forest<SurfaceVpls>,
    /// Mean extinction of the scene's media (the gathering points' importance).
    sigma_mean: f32,
    /// Light tracing's connections of the caustic vertices to the camera.
    splats: CameraSplats,
}

impl<K: ClusterKind, S: CutStrategy> LightcutsIntegrator<K, S> {
    pub fn new(scene: &Scene, ml: ManyLightSettings, strategy: S, seed: u64) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &ml, seed)?;
        let caustics = caustic_tracer(scene, &ml);
        let clamps = Clamps { compensated: ml.compensated_clamp, ..Clamps::default() };
        Ok(LightcutsIntegrator {
            ml,
            strategy,
            clamps,
            controls: TestControls::default(),
            paths,
            stats: Stats::default(),
            kind: PhantomData,
            caustics,
        })
    }

    /// This integrator with the estimate changed as `controls` says (this crate's tests only:
    /// feature `test-controls`).
    #[cfg(feature = "test-controls")]
    pub fn with_test_controls(mut self, controls: TestControls) -> Self {
        self.controls = controls;
        self
    }

    /// Light paths traced per pass.
    pub fn paths_per_pass(&self) -> u64 {
        self.paths
    }

    /// Camera segment x light evaluations of the exhaustive cut so far (each with its
    /// visibility test; 0 for the other cuts).
    pub fn evaluations(&self) -> u64 {
        self.stats.evaluations.load(Ordering::Relaxed)
    }

    /// Mean and largest cut size per camera segment, and the fraction of segments that hit
    /// `max_cut` (always 0 for the stochastic cut).
    pub fn cut_statistics(&self) -> (f64, u64, f64) {
        let segs = self.stats.segments.load(Ordering::Relaxed).max(1) as f64;
        (
            self.stats.cut_total.load(Ordering::Relaxed) as f64 / segs,
            self.stats.cut_max.load(Ordering::Relaxed),
            self.stats.hit_max.load(Ordering::Relaxed) as f64 / segs,
        )
    }

    /// Camera segments that had a cut (per tree with lights), so far.
    pub fn segments(&self) -> u64 {
        self.stats.segments.load(Ordering::Relaxed)
    }

    /// Lights per pass, averaged over the passes so far.
    pub fn lights_per_pass(&self) -> f64 {
        self.stats.lights.load(Ordering::Relaxed) as f64
            / self.stats.passes.load(Ordering::Relaxed).max(1) as f64
    }

    /// Seconds spent building trees, summed over passes.
    pub fn build_seconds(&self) -> f64 {
        self.stats.build_ns.load(Ordering::Relaxed) as f64 * 1e-9
    }

    /// Seconds spent tracing light paths, summed over passes.
    pub fn trace_seconds(&self) -> f64 {
        self.stats.trace_ns.load(Ordering::Relaxed) as f64 * 1e-9
    }
}

impl<K: ClusterKind> LightcutsIntegrator<K, ExhaustiveCut> {
    /// The brute-force integrator (`vrl`, `vpl`): the exhaustive cut, every light of a pass
    /// evaluated for every camera segment and gathering point.
    pub fn exhaustive(scene: &Scene, ml: ManyLightSettings, seed: u64) -> Result<Self, EmissionError> {
        Self::new(scene, ml, ExhaustiveCut, seed)
    }
}

impl<K: ClusterKind, S: CutStrategy> Integrator for LightcutsIntegrator<K, S> {
    type PassData = LightcutPass<K, S>;

    fn name(&self) -> &str {
        self.strategy.name::<K>()
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass<K, S> {
        let t0 = Instant::now();
        let set = trace_light_paths(scene, self.paths, seed, pass, &self.ml.trace)
            .expect("emitters were checked when the integrator was made");
        let media = media(scene);
        let t1 = Instant::now();
        let tree_seed = haze_core::rng::mix64(seed ^ ((pass as u64) << 32));
        let [a, b] = K::lights(&set);
        let surface_vpls = surface_vpls(&set);
        let splats = self.caustics.as_ref().map_or_else(CameraSplats::default, |c| {
            c.splats(scene, seed, pass).scaled(self.controls.caustic_scale)
        });
        let n = a.len() + b.len() + surface_vpls.len();
        let (forests, surface) = self.strategy.forests::<K>([a, b], surface_vpls, &media, tree_seed);
        let sigma_mean = if media.is_empty() {
            0.0
        } else {
            media.iter().map(|m| m.sigma_t.mean()).sum::<f32>() / media.len() as f32
        };
        self.stats.trace_ns.fetch_add((t1 - t0).as_nanos() as u64, Ordering::Relaxed);
        self.stats.build_ns.fetch_add(t1.elapsed().as_nanos() as u64, Ordering::Relaxed);
        self.stats.lights.fetch_add(n as u64, Ordering::Relaxed);
        self.stats.passes.fetch_add(1, Ordering::Relaxed);
        let strategy = self.strategy.pass_data(scene, &media);
        LightcutPass { forests, media, strategy, surface, sigma_mean, splats }
    }

    fn pixel_light(&self, pass: &LightcutPass<K, S>, pixel: u64) -> Rgb {
        pass.splats.get(pixel)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K, S>,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        whole_path_radiance(scene, ray, medium, sampler, &LightcutGather::new(self, scene, pass, &()))
    }

    fn summary(&self) -> Option<String> {
        let passes = self.stats.passes.load(Ordering::Relaxed).max(1) as f64;
        let (mean, max, hit) = self.cut_statistics();
        let Some(cut) = self.strategy.describe(mean, max, hit) else {
            return Some(format!(
                "{}: {} light paths and {:.0} {} and surface VPLs per pass on average ({passes} passes){}",
                self.name(),
                self.paths,
                self.lights_per_pass(),
                K::LIGHTS,
                if self.clamps == Clamps::default() { "" } else { "; clamped: the image is biased" },
            ));
        };
        Some(format!(
            "{}: {} light paths and {:.0} lights per pass ({} passes); per pass: light tracing {:.3} s, tree build {:.3} s; {cut}",
            self.name(),
            self.paths,
            self.lights_per_pass(),
            passes,
            self.trace_seconds() / passes,
            self.build_seconds() / passes,
        ))
    }
}

/// The lightcut integrator's side of the camera walk (`gather.rs`): its strategy's sums.
struct LightcutGather<'a, K: ClusterKind, S: CutStrategy, O> {
    integrator: &'a LightcutsIntegrator<K, S>,
    view: PassView<'a, K, S>,
    observer: &'a O,
}

impl<'a, K: ClusterKind, S: CutStrategy, O> LightcutGather<'a, K, S, O> {
    fn new(
        integrator: &'a LightcutsIntegrator<K, S>,
        scene: &'a Scene,
        pass: &'a LightcutPass<K, S>,
        observer: &'a O,
    ) -> Self {
        let view = PassView { scene, pass, clamps: &integrator.clamps, stats: &integrator.stats };
        LightcutGather { integrator, view, observer }
    }
}

impl<K: ClusterKind, S: CutStrategy, O: CutObserver<K>> Gather for LightcutGather<'_, K, S, O> {
    fn segment(&self, cs: &CameraSegment, key: u64) -> [Rgb; 2] {
        self.integrator.strategy.segment(&self.view, cs, key, self.observer)
    }

    fn splats_caustics(&self) -> bool {
        self.integrator.caustics.is_some()
    }

    fn split(&self) -> Option<f32> {
        self.integrator.controls.split
    }

    fn compensated_clamp(&self) -> Option<f32> {
        self.integrator.ml.compensated_clamp
    }

    fn path_traced_media(&self) -> PathTracedMedia {
        self.integrator.ml.path_traced_media
    }

    fn point(&self, gp: &GatherPoint, key: u64) -> Rgb {
        self.integrator.strategy.point(&self.view, gp, key) * self.integrator.controls.gather_point_scale
    }
}
