//! The many-light integrator, generic over the light kind ([`ClusterKind`]) and the cut
//! ([`CutStrategy`]): `vrl_lightcuts` and `vpl_lightcuts` with a tree's cut, `vrl` and `vpl`
//! with the exhaustive cut. Each pass traces its light paths, builds a light tree over the VRLs
//! (or VPLs) with the three-step parallel builder, and every camera segment estimates the sum
//! over its lights through a cut of the tree instead of one by one: by default the
//! stochastic, bound-free cut (`tree::stochastic`), or the paper's deterministic cut by bounds
//! (`tree::cut`, `--cut bound`). The exhaustive cut builds no tree and evaluates every light,
//! with the same per-light random numbers (`light_uniforms(key, index)`) as a tree's leaves.
//!
//! Lights that follow a surface bounce live in a group (and tree) of their own, so `multiple`
//! and `surface` stay separate. Every method's camera walk is the same (`gather.rs`, the whole
//! image). The surface VPLs ([`SurfaceVpls`]) get a tree of their own, cut stochastically for
//! camera segments; a gathering surface point picks one of the three trees and cuts it
//! stochastically with the point's importance, whatever `--cut` says (docs/lightcuts.md "The
//! whole image").

#[cfg(test)]
mod bound_tests;
mod kinds;
mod observer;

pub use kinds::{Clamps, ClusterKind, LightKind, SurfaceVpls, Vpls, Vrls};
pub use observer::{CutObserver, Observed, SegmentCut};

use super::{caustic_tracer, light_uniforms, media, paths_per_pass, surface_vpls, ManyLightSettings};
use crate::camera::CameraSegment;
use crate::gather::{whole_path_radiance, Gather, GatherPoint, PathTracedMedia};
use crate::lighttrace::trace_light_paths;
use crate::splat::{CameraSplats, CausticTracer};
use crate::tree::bound::{BoundContext, BoundKind, ThetaBound};
use crate::tree::build::{build_agglomerative, build_median_split, BuildSettings};
use crate::tree::cone::{DirCone, LineCone};
use crate::tree::cut::{lightcut, ClusterOracle, CutScratch, CutSettings, CutStats};
use crate::tree::importance::{ImportanceContext, PointImportance};
use crate::tree::lights::LightSummary;
use crate::tree::stochastic::{
    mixed_probability, power, stochastic_cut, SampleNode, SampleTree, StochasticScratch, StochasticSettings,
};
use crate::tree::{LightTree, Node};
use crate::vrl::VrlMedium;
use haze_core::streams::{LIGHT_SAMPLES, POINT_CUT, SEGMENT_CUT, SURFACE_VPL_CUT, TREE_SEEDS};
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};
use std::cell::RefCell;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Which tree builder to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// The paper's three-step parallel agglomerative build.
    Agglomerative,
    /// Top-down median split (baseline).
    MedianSplit,
}

/// How a camera segment's cut is chosen (`--cut`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CutStrategy {
    /// Bound-free: a cut of `cut_size` nodes by importance, one light sampled per node
    /// (`tree::stochastic`). Unbiased; a fixed cost per camera segment.
    Stochastic,
    /// The paper's deterministic cut: refine by upper bounds until `epsilon` or `max_cut`
    /// (`tree::cut`), each node estimated by its representative.
    Bound,
    /// Every light evaluated, for camera segments and gathering points alike: the brute-force
    /// sum of `vrl` and `vpl` (`docs/theory.md` §2.1), the reference the cuts estimate. No tree
    /// is built.
    Exhaustive,
}

#[derive(Clone, Copy, Debug)]
pub struct LightcutSettings {
    pub strategy: CutStrategy,
    /// `CutStrategy::Stochastic` only.
    pub stochastic: StochasticSettings,
    /// `CutStrategy::Bound` only (with `bound` and `theta`).
    pub cut: CutSettings,
    pub bound: BoundKind,
    pub theta: ThetaBound,
    pub builder: Builder,
    pub build: BuildSettings,
}

impl Default for LightcutSettings {
    fn default() -> Self {
        LightcutSettings {
            strategy: CutStrategy::Stochastic,
            stochastic: StochasticSettings::default(),
            cut: CutSettings::default(),
            bound: BoundKind::Paper,
            theta: ThetaBound::Exact,
            builder: Builder::Agglomerative,
            build: BuildSettings::default(),
        }
    }
}

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
/// (`LightcutsIntegrator<Vpls>`), and with the exhaustive cut `vrl` and `vpl`
/// ([`LightcutsIntegrator::exhaustive`]): one integrator, generic over the light kind.
pub struct LightcutsIntegrator<K: ClusterKind> {
    ml: ManyLightSettings,
    pub settings: LightcutSettings,
    /// The clamps: the biased ones for `vrl` and `vpl` only (the option table refuses them
    /// elsewhere), the compensated one from [`ManyLightSettings::compensated_clamp`].
    pub clamps: Clamps,
    controls: TestControls,
    paths: u64,
    stats: Stats,
    kind: PhantomData<K>,
    caustics: Option<CausticTracer>,
}

/// One tree of lights (medium-only or after a surface bounce).
pub struct Forest<K: LightKind> {
    pub lights: Vec<K::Light>,
    pub tree: LightTree,
    /// Cones of the VRLs' directions per node (`--bound tight` only; empty otherwise).
    pub cones: Vec<LineCone>,
    pub dir_cones: Vec<DirCone>,
    /// The tree laid out for the stochastic cut's descents (`--cut stochastic` only).
    pub sample: SampleTree,
}

impl<K: LightKind> Forest<K> {
    /// The lights without a tree (the exhaustive cut needs none).
    fn without_tree(lights: Vec<K::Light>) -> Self {
        Forest {
            lights,
            tree: LightTree::default(),
            cones: Vec::new(),
            dir_cones: Vec::new(),
            sample: SampleTree::default(),
        }
    }
}

/// What one pass shares between its camera samples: the two trees and the media.
pub struct LightcutPass<K: ClusterKind> {
    forests: [Forest<K>; 2],
    media: Vec<VrlMedium>,
    /// Per medium, the bound cut's `sigma_s f_max` factor (`crate::hetero::bound_factor`).
    bound_factors: Vec<Rgb>,
    light_factor: Rgb,
    sigma_t_min: Rgb,
    /// The phase every medium shares, if one (for the tight bound's light-side phase).
    light_phase: Option<haze_core::Phase>,
    /// The surface VPLs, with a tree cut stochastically for camera segments and gathering
    /// points (none with the exhaustive cut).
    surface: Forest<SurfaceVpls>,
    /// Mean extinction of the scene's media (the gathering points' importance).
    sigma_mean: f32,
    /// Light tracing's connections of the caustic vertices to the camera.
    splats: CameraSplats,
}

impl<K: ClusterKind> LightcutsIntegrator<K> {
    pub fn new(
        scene: &Scene,
        ml: ManyLightSettings,
        settings: LightcutSettings,
        seed: u64,
    ) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &ml, seed)?;
        let caustics = caustic_tracer(scene, &ml);
        let clamps = Clamps { compensated: ml.compensated_clamp, ..Clamps::default() };
        Ok(LightcutsIntegrator {
            ml,
            settings,
            clamps,
            controls: TestControls::default(),
            paths,
            stats: Stats::default(),
            kind: PhantomData,
            caustics,
        })
    }

    /// The brute-force integrator (`vrl`, `vpl`): the exhaustive cut, every light of a pass
    /// evaluated for every camera segment and gathering point.
    pub fn exhaustive(scene: &Scene, ml: ManyLightSettings, seed: u64) -> Result<Self, EmissionError> {
        let settings = LightcutSettings { strategy: CutStrategy::Exhaustive, ..LightcutSettings::default() };
        Self::new(scene, ml, settings, seed)
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

    /// The light tree over `summaries` with the configured builder.
    fn build_tree(&self, summaries: &[LightSummary], seed: u64) -> LightTree {
        match self.settings.builder {
            Builder::Agglomerative => {
                build_agglomerative(summaries, &BuildSettings { seed, ..self.settings.build })
            }
            Builder::MedianSplit => build_median_split(summaries, seed),
        }
    }

    fn build(&self, lights: Vec<K::Light>, media: &[VrlMedium], seed: u64) -> Forest<K> {
        let summaries: Vec<LightSummary> = {
            use rayon::prelude::*;
            lights.par_iter().map(|l| K::summary(l, media)).collect()
        };
        let tree = self.build_tree(&summaries, seed);
        let mut forest =
            Forest { lights, tree, cones: Vec::new(), dir_cones: Vec::new(), sample: SampleTree::default() };
        if self.settings.strategy == CutStrategy::Bound {
            K::prepare(&mut forest, self.settings.bound);
        }
        // Gathering points cut every tree stochastically, whatever the camera segments use.
        forest.sample = SampleTree::new(&forest.tree);
        forest
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

thread_local! {
    static CUT_SCRATCH: RefCell<CutScratch> = RefCell::new(CutScratch::default());
    static STOCHASTIC_SCRATCH: RefCell<StochasticScratch> = RefCell::new(StochasticScratch::default());
    /// What [`CutSizeProbe`] maps, summed, and camera segments counted on this thread since
    /// it last reset them: the cut size (bound cut) or the largest cut node's share of the
    /// cut's importance (stochastic cut).
    static CUT_TALLY: std::cell::Cell<(f64, u64)> = const { std::cell::Cell::new((0.0, 0)) };
    /// Set while [`CutSizeProbe`] renders: the stochastic cut then also computes its share.
    static PROBING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The deterministic cut's view of one forest and camera segment.
struct Oracle<'a, K: ClusterKind> {
    scene: &'a Scene,
    forest: &'a Forest<K>,
    cs: &'a CameraSegment,
    media: &'a [VrlMedium],
    bound: BoundContext,
    key: u64,
}

impl<K: ClusterKind> ClusterOracle for Oracle<'_, K> {
    fn bound(&self, index: u32, _node: &Node) -> f32 {
        K::bound(&self.bound, self.forest, index)
    }
    fn contribution(&mut self, light: u32) -> Rgb {
        let l = &self.forest.lights[light as usize];
        K::contribution(self.scene, self.cs, self.media, l, self.key, light, &Clamps::default())
    }
}

impl<K: ClusterKind> Integrator for LightcutsIntegrator<K> {
    type PassData = LightcutPass<K>;

    fn name(&self) -> &str {
        match self.settings.strategy {
            CutStrategy::Exhaustive => K::EXHAUSTIVE_NAME,
            CutStrategy::Stochastic | CutStrategy::Bound => K::NAME,
        }
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass<K> {
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
        let (forests, surface) = if self.settings.strategy == CutStrategy::Exhaustive {
            ([a, b].map(Forest::without_tree), Forest::without_tree(surface_vpls))
        } else {
            let forests =
                [self.build(a, &media, tree_seed), self.build(b, &media, tree_seed ^ TREE_SEEDS[0])];
            let summaries: Vec<LightSummary> =
                surface_vpls.iter().map(|v| SurfaceVpls::summary(v, &media)).collect();
            let tree = self.build_tree(&summaries, tree_seed ^ TREE_SEEDS[1]);
            let sample = SampleTree::new(&tree);
            (forests, Forest { lights: surface_vpls, tree, cones: Vec::new(), dir_cones: Vec::new(), sample })
        };
        let sigma_mean = if media.is_empty() {
            0.0
        } else {
            media.iter().map(|m| m.sigma_t.mean()).sum::<f32>() / media.len() as f32
        };
        self.stats.trace_ns.fetch_add((t1 - t0).as_nanos() as u64, Ordering::Relaxed);
        self.stats.build_ns.fetch_add(t1.elapsed().as_nanos() as u64, Ordering::Relaxed);
        self.stats.lights.fetch_add(n as u64, Ordering::Relaxed);
        self.stats.passes.fetch_add(1, Ordering::Relaxed);
        // Bounds on transmittance use the least extinction any connection may see; vacuum
        // anywhere (a camera or light outside every medium) makes it zero.
        let vacuum = scene.camera.medium.is_none()
            || scene
                .shapes
                .iter()
                .any(|s| s.is_medium_transition() && (s.interior.is_none() || s.exterior.is_none()));
        // A heterogeneous medium's extinction may be 0 anywhere in its box (and is outside it).
        let sigma_t_min = if vacuum || crate::hetero::any(scene) {
            Rgb::ZERO
        } else {
            media.iter().fold(Rgb::splat(f32::INFINITY), |acc, m| {
                Rgb(std::array::from_fn(|c| acc[c].min(m.sigma_t[c])))
            })
        };
        let light_phase = media.first().map(|m| m.phase).filter(|p| media.iter().all(|m| m.phase == *p));
        let bound_factors: Vec<Rgb> = (0..media.len())
            .map(|id| crate::hetero::bound_factor(scene, &media[id], id as MediumId))
            .collect();
        LightcutPass {
            light_factor: bound_factors.iter().fold(Rgb::ZERO, |a, f| a.max(*f)),
            bound_factors,
            forests,
            media,
            sigma_t_min,
            light_phase,
            surface,
            sigma_mean,
            splats,
        }
    }

    fn pixel_light(&self, pass: &LightcutPass<K>, pixel: u64) -> Rgb {
        pass.splats.get(pixel)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K>,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        let gather = LightcutGather { integrator: self, scene, pass, observer: &() };
        whole_path_radiance(scene, ray, medium, sampler, &gather)
    }

    fn summary(&self) -> Option<String> {
        let passes = self.stats.passes.load(Ordering::Relaxed).max(1) as f64;
        let (mean, max, hit) = self.cut_statistics();
        if self.settings.strategy == CutStrategy::Exhaustive {
            return Some(format!(
                "{}: {} light paths and {:.0} {} and surface VPLs per pass on average ({passes} passes){}",
                self.name(),
                self.paths,
                self.lights_per_pass(),
                K::LIGHTS,
                if self.clamps == Clamps::default() { "" } else { "; clamped: the image is biased" },
            ));
        }
        let cut = match self.settings.strategy {
            CutStrategy::Stochastic => format!(
                "stochastic cut of {} nodes: mean {mean:.1} per camera segment and tree",
                self.settings.stochastic.cut_size
            ),
            CutStrategy::Bound => format!(
                "bound cut: size mean {mean:.1}, max {max}; {:.2}% of segments hit max-cut {}",
                100.0 * hit,
                self.settings.cut.max_cut
            ),
            CutStrategy::Exhaustive => unreachable!("returned above"),
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

impl<K: ClusterKind> LightcutsIntegrator<K> {
    fn record(&self, s: &CutStats) {
        if s.size == 0 {
            return;
        }
        if self.settings.strategy == CutStrategy::Bound {
            CUT_TALLY.with(|t| {
                let (size, n) = t.get();
                t.set((size + s.size as f64, n + 1));
            });
        }
        self.stats.segments.fetch_add(1, Ordering::Relaxed);
        self.stats.cut_total.fetch_add(s.size as u64, Ordering::Relaxed);
        self.stats.cut_max.fetch_max(s.size as u64, Ordering::Relaxed);
        if s.hit_max {
            self.stats.hit_max.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Renders, instead of a camera path's radiance, the mean over its segments of the cut size
/// (bound cut) or of the largest cut node's share of the cut's importance (stochastic cut: 1
/// where one cluster dominates, `1/k` where the importance spreads evenly), in every channel of
/// the `emitted` component (0 where the path meets no medium). Runs the wrapped
/// integrator unchanged, so the cuts are those of the image with the same seed and pass.
pub struct CutSizeProbe<'a, K: ClusterKind>(pub &'a LightcutsIntegrator<K>);

impl<K: ClusterKind> Integrator for CutSizeProbe<'_, K> {
    type PassData = LightcutPass<K>;

    fn name(&self) -> &str {
        self.0.name()
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass<K> {
        self.0.begin_pass(scene, seed, pass)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K>,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        CUT_TALLY.with(|t| t.set((0.0, 0)));
        PROBING.set(true);
        let _ = self.0.radiance(scene, pass, ray, medium, sampler);
        PROBING.set(false);
        let (size, n) = CUT_TALLY.with(|t| t.get());
        let mut r = PathRadiance::default();
        if n > 0 {
            r.add(haze_render::Component::Emitted, Rgb::splat(size as f32 / n as f32));
        }
        r
    }
}

impl<K: ClusterKind> LightcutsIntegrator<K> {
    /// What the bound cut bounds the contributions to camera segment `cs` with (`docs/theory.md`
    /// §7, and §12.5 for heterogeneous media).
    fn bound_context(&self, pass: &LightcutPass<K>, cs: &CameraSegment) -> BoundContext {
        BoundContext {
            seg: cs.seg,
            camera_factor: pass.bound_factors[cs.medium as usize],
            light_factor: pass.light_factor,
            sigma_t_min: pass.sigma_t_min,
            kind: self.settings.bound,
            theta: self.settings.theta,
            camera_phase: pass.media[cs.medium as usize].phase,
            light_phase: pass.light_phase,
        }
    }

    /// The cut of tree `group` for the camera segment `cs` (`gather::Gather::segment`'s per-group
    /// sum, estimated through the tree).
    fn segment_cut(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K>,
        cs: &CameraSegment,
        key: u64,
        group: usize,
        observer: &impl CutObserver<K>,
    ) -> Rgb {
        let forest = &pass.forests[group];
        if forest.lights.is_empty() {
            return Rgb::ZERO;
        }
        let cam_medium = &pass.media[cs.medium as usize];
        let (value, stats) = match self.settings.strategy {
            CutStrategy::Exhaustive => {
                return K::contribution_sum(scene, cs, &pass.media, &forest.lights, key, &self.clamps)
            }
            CutStrategy::Stochastic => STOCHASTIC_SCRATCH.with_borrow_mut(|scratch| {
                let ctx = ImportanceContext::new(cs.seg, cam_medium);
                // A leaf's importance from its light's own shape (`ClusterKind::leaf_importance`).
                let importance = |n: &SampleNode| {
                    if n.is_leaf() {
                        K::leaf_importance(&ctx, n, &forest.lights[n.light() as usize])
                    } else {
                        ctx.importance(n)
                    }
                };
                let mut sum = Rgb::ZERO;
                let light_samples = self.settings.stochastic.light_samples;
                let descent_key = key ^ SEGMENT_CUT.wrapping_mul(group as u64 + 1);
                let size = stochastic_cut(
                    &forest.sample,
                    &importance,
                    &self.settings.stochastic,
                    descent_key,
                    scratch,
                    |light, prob| {
                        // `light_samples` joint samples of the chosen light, averaged: the
                        // descent divides each light's joint-sampling variance by its
                        // probability (docs/lightcuts.md, "Choosing the importance").
                        let l = &forest.lights[light as usize];
                        let m = light_samples.max(1);
                        let weight = 1.0 / (prob * m as f32);
                        for j in 0..m as u64 {
                            let kj = if j == 0 {
                                key
                            } else {
                                haze_core::rng::mix64(key ^ j.wrapping_mul(LIGHT_SAMPLES))
                            };
                            let c = K::contribution(scene, cs, &pass.media, l, kj, light, &self.clamps);
                            sum += c * weight;
                        }
                    },
                );
                observer.stochastic_cut(&SegmentCut {
                    scene,
                    media: &pass.media,
                    cs,
                    key,
                    forest,
                    importance: &importance,
                    power_share: self.settings.stochastic.power_share,
                });
                if PROBING.get() {
                    let (mut total, mut largest) = (0.0f64, 0.0f64);
                    for &n in scratch.cut() {
                        let i = importance(forest.sample.node(n)) as f64;
                        total += i;
                        largest = largest.max(i);
                    }
                    let share = if total > 0.0 { largest / total } else { 1.0 };
                    CUT_TALLY.with(|t| {
                        let (v, n) = t.get();
                        t.set((v + share, n + 1));
                    });
                }
                (sum, CutStats { size, hit_max: false })
            }),
            CutStrategy::Bound => CUT_SCRATCH.with_borrow_mut(|scratch| {
                let bound = self.bound_context(pass, cs);
                let mut o = Oracle { scene, forest, cs, media: &pass.media, bound, key };
                lightcut(&forest.tree, &mut o, &self.settings.cut, scratch)
            }),
        };
        self.record(&stats);
        value
    }
}

/// The lightcut integrator's side of the camera walk (`gather.rs`).
struct LightcutGather<'a, K: ClusterKind, O> {
    integrator: &'a LightcutsIntegrator<K>,
    scene: &'a Scene,
    pass: &'a LightcutPass<K>,
    observer: &'a O,
}

impl<K: ClusterKind, O: CutObserver<K>> Gather for LightcutGather<'_, K, O> {
    fn segment(&self, cs: &CameraSegment, key: u64) -> [Rgb; 2] {
        let (scene, pass, integrator) = (self.scene, self.pass, self.integrator);
        let cuts = [0, 1].map(|g| integrator.segment_cut(scene, pass, cs, key, g, self.observer));
        let cam_medium = &pass.media[cs.medium as usize];
        let (media, clamps) = (&pass.media[..], &integrator.clamps);
        let surface_vpls = &pass.surface.lights;
        if integrator.settings.strategy == CutStrategy::Exhaustive {
            let n = pass.forests.iter().map(|f| f.lights.len()).sum::<usize>() + surface_vpls.len();
            integrator.stats.evaluations.fetch_add(n as u64, Ordering::Relaxed);
            let surface = SurfaceVpls::contribution_sum(scene, cs, media, surface_vpls, key, clamps);
            return [cuts[0], cuts[1] + surface];
        }
        let ctx = ImportanceContext::new(cs.seg, cam_medium);
        let surface =
            self.cut_sum(&pass.surface.sample, &|n| ctx.importance(n), key ^ SURFACE_VPL_CUT, |i| {
                SurfaceVpls::contribution(scene, cs, media, &surface_vpls[i as usize], key, i, clamps)
            });
        [cuts[0], cuts[1] + surface]
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
        let scale = self.integrator.controls.gather_point_scale;
        if self.integrator.settings.strategy == CutStrategy::Exhaustive {
            return self.point_exhaustive(gp, key) * scale;
        }
        self.point_cut(gp, key) * scale
    }
}

impl<K: ClusterKind, O> LightcutGather<'_, K, O> {
    /// Every light's contribution to the gathering point `gp`: the lights of both groups in
    /// order, each with the numbers of its index among them, then the surface VPLs.
    fn point_exhaustive(&self, gp: &GatherPoint, key: u64) -> Rgb {
        let (scene, pass, clamps) = (self.scene, self.pass, &self.integrator.clamps);
        let mut sum = Rgb::ZERO;
        for (i, light) in pass.forests.iter().flat_map(|f| &f.lights).enumerate() {
            sum += K::to_point(scene, gp, &pass.media, light, light_uniforms(key, i as u32).x, clamps);
        }
        // Surface VPLs sample nothing at a point: no random number.
        let mut surface = Rgb::ZERO;
        for vpl in &pass.surface.lights {
            surface += SurfaceVpls::to_point(scene, gp, &pass.media, vpl, 0.0, clamps);
        }
        sum + surface
    }

    /// The gathering point's cut: one tree chosen, then cut stochastically.
    fn point_cut(&self, gp: &GatherPoint, key: u64) -> Rgb {
        let (scene, pass) = (self.scene, self.pass);
        let pi = PointImportance::new(gp.p, gp.n, pass.sigma_mean);
        // One tree per gathering point, picked like a descent's first step over the three
        // roots (importance mixed with the power share), then cut: one light evaluation per
        // point, as many as a segment's single tree.
        let roots = [&pass.forests[0].sample, &pass.forests[1].sample, &pass.surface.sample];
        let share = self.integrator.settings.stochastic.power_share;
        let (mut imp, mut pow) = ([0.0f32; 3], [0.0f32; 3]);
        for (g, tree) in roots.iter().enumerate() {
            if !tree.is_empty() {
                let root = tree.node(0);
                imp[g] = pi.importance(root);
                pow[g] = power(root);
            }
        }
        let (imp_sum, pow_sum) = (imp.iter().sum::<f32>(), pow.iter().sum::<f32>());
        if !(pow_sum > 0.0 && pow_sum.is_finite()) {
            return Rgb::ZERO;
        }
        let prob = |g: usize| mixed_probability(imp[g], imp_sum, pow[g] / pow_sum, share);
        let u = light_uniforms(key ^ POINT_CUT, 0).x;
        // Falls back to the last tree with power if rounding leaves `u` above the sum.
        let mut g = pow.iter().rposition(|&p| p > 0.0).unwrap_or(2);
        let mut acc = 0.0;
        for (j, &power) in pow.iter().enumerate() {
            acc += prob(j);
            if u < acc && power > 0.0 {
                g = j;
                break;
            }
        }
        let p_tree = prob(g);
        if p_tree <= 0.0 {
            return Rgb::ZERO;
        }
        let stream = POINT_CUT.wrapping_mul(g as u64 + 2);
        let sum = if g < 2 {
            let forest = &pass.forests[g];
            let importance = |n: &SampleNode| {
                if n.is_leaf() {
                    K::leaf_point_importance(&pi, n, &forest.lights[n.light() as usize])
                } else {
                    pi.importance(n)
                }
            };
            self.cut_sum(&forest.sample, &importance, key ^ stream, |i| {
                let u = light_uniforms(key ^ stream, i).x;
                K::to_point(scene, gp, &pass.media, &forest.lights[i as usize], u, &self.integrator.clamps)
            })
        } else {
            let surface = &pass.surface.lights;
            self.cut_sum(&pass.surface.sample, &|n| pi.importance(n), key ^ stream, |i| {
                SurfaceVpls::to_point(
                    scene,
                    gp,
                    &pass.media,
                    &surface[i as usize],
                    0.0,
                    &self.integrator.clamps,
                )
            })
        };
        sum * (1.0 / p_tree)
    }

    /// The stochastic cut's estimate (`cut_size` nodes, one light each) of the sum of `eval`
    /// over the lights of `tree`, descending with `importance` and the numbers of `key`.
    fn cut_sum(
        &self,
        tree: &SampleTree,
        importance: &impl Fn(&SampleNode) -> f32,
        key: u64,
        mut eval: impl FnMut(u32) -> Rgb,
    ) -> Rgb {
        if tree.is_empty() {
            return Rgb::ZERO;
        }
        let settings = &self.integrator.settings.stochastic;
        STOCHASTIC_SCRATCH.with_borrow_mut(|scratch| {
            let mut sum = Rgb::ZERO;
            stochastic_cut(tree, importance, settings, key, scratch, |light, prob| {
                sum += eval(light) * (1.0 / prob);
            });
            sum
        })
    }
}
