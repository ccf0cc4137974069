//! `vrl_lightcuts` and `vpl_lightcuts`: the paper's scalable estimators. Each pass traces its
//! light paths, builds a light tree over the VRLs (or VPLs) with the three-step parallel
//! builder, and every camera segment sums its lights through a lightcut instead of one by one.
//! Both share the cut loop (`tree::cut::lightcut`) and differ only in bound and evaluation.
//!
//! Component split as in `vrl`/`vpl`: lights that follow a surface bounce live in a tree of
//! their own, so `multiple` and `surface` stay separate.

use super::{
    connect, light_uniforms, many_light_radiance, media, paths_per_pass, split_groups, ManyLightSettings,
};
use crate::camera::CameraSegment;
use crate::lighttrace::{trace_light_paths, VplRecord, VrlRecord};
use crate::tree::bound::{light_factor, BoundContext, BoundKind, ThetaBound};
use crate::tree::build::{build_agglomerative, build_median_split, BuildSettings};
use crate::tree::cone::{node_cones, node_dir_cones, DirCone, LineCone};
use crate::tree::cut::{lightcut, ClusterOracle, CutScratch, CutSettings, CutStats};
use crate::tree::lights::LightSummary;
use crate::tree::{LightTree, Node};
use crate::vpl::{sample_vpl_contribution, Vpl};
use crate::vrl::{sample_vrl_contribution, Vrl, VrlMedium};
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};
use std::cell::RefCell;
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

impl std::str::FromStr for Builder {
    type Err = String;

    /// The names of `--builder`: `agglomerative`, `median`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "agglomerative" => Ok(Builder::Agglomerative),
            "median" => Ok(Builder::MedianSplit),
            other => Err(format!("the builder must be 'agglomerative' or 'median', got '{other}'")),
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct LightcutSettings {
    pub cut: CutSettings,
    pub bound: BoundKind,
    pub theta: ThetaBound,
    pub builder: Builder,
    pub build: BuildSettings,
}

impl Default for LightcutSettings {
    fn default() -> Self {
        LightcutSettings {
            cut: CutSettings::default(),
            bound: BoundKind::Paper,
            theta: ThetaBound::Exact,
            builder: Builder::Agglomerative,
            build: BuildSettings::default(),
        }
    }
}

/// The two kinds of virtual light the lightcut integrators handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    Vrl,
    Vpl,
}

/// Counters reported after rendering.
#[derive(Default)]
struct Stats {
    lights: AtomicU64,
    passes: AtomicU64,
    build_ns: AtomicU64,
    segments: AtomicU64,
    cut_total: AtomicU64,
    cut_max: AtomicU64,
    hit_max: AtomicU64,
}

pub struct LightcutsIntegrator {
    kind: LightKind,
    ml: ManyLightSettings,
    pub settings: LightcutSettings,
    paths: u64,
    stats: Stats,
}

/// One tree of lights (medium-only or after a surface bounce).
pub struct Forest<L> {
    lights: Vec<L>,
    tree: LightTree,
    /// Cones of the VRLs' directions per node (`--bound tight` only; empty otherwise).
    cones: Vec<LineCone>,
    dir_cones: Vec<DirCone>,
}

pub struct LightcutPass {
    vrls: [Forest<Vrl>; 2],
    vpls: [Forest<Vpl>; 2],
    media: Vec<VrlMedium>,
    light_factor: Rgb,
    sigma_t_min: Rgb,
    /// The phase every medium shares, if one (for the tight bound's light-side phase).
    light_phase: Option<haze_core::Phase>,
}

impl LightcutsIntegrator {
    pub fn new(
        scene: &Scene,
        kind: LightKind,
        ml: ManyLightSettings,
        settings: LightcutSettings,
        seed: u64,
    ) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &ml, seed)?;
        Ok(LightcutsIntegrator { kind, ml, settings, paths, stats: Stats::default() })
    }

    fn build<L>(&self, lights: Vec<L>, summary: impl Fn(&L) -> LightSummary + Sync, seed: u64) -> Forest<L>
    where
        L: Sync,
    {
        let summaries: Vec<LightSummary> = {
            use rayon::prelude::*;
            lights.par_iter().map(&summary).collect()
        };
        let build = BuildSettings { seed, ..self.settings.build };
        let tree = match self.settings.builder {
            Builder::Agglomerative => build_agglomerative(&summaries, &build),
            Builder::MedianSplit => build_median_split(&summaries, seed),
        };
        Forest { lights, tree, cones: Vec::new(), dir_cones: Vec::new() }
    }

    /// Mean and largest cut size per camera segment, and the fraction of segments that hit
    /// `max_cut`.
    pub fn cut_statistics(&self) -> (f64, u64, f64) {
        let segs = self.stats.segments.load(Ordering::Relaxed).max(1) as f64;
        (
            self.stats.cut_total.load(Ordering::Relaxed) as f64 / segs,
            self.stats.cut_max.load(Ordering::Relaxed),
            self.stats.hit_max.load(Ordering::Relaxed) as f64 / segs,
        )
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
}

thread_local! {
    static CUT_SCRATCH: RefCell<CutScratch> = RefCell::new(CutScratch::default());
    /// Cut sizes summed and camera segments counted on this thread since [`CutSizeProbe`]
    /// last reset them.
    static CUT_TALLY: std::cell::Cell<(u64, u64)> = const { std::cell::Cell::new((0, 0)) };
}

/// What both oracles know of the camera segment being cut for.
#[derive(Clone, Copy)]
struct SegmentContext<'a> {
    scene: &'a Scene,
    cs: &'a CameraSegment,
    cam_medium: &'a VrlMedium,
    media: &'a [VrlMedium],
    bound: BoundContext,
    key: u64,
}

struct VrlOracle<'a> {
    ctx: SegmentContext<'a>,
    tree: &'a LightTree,
    cones: &'a [LineCone],
    dir_cones: &'a [DirCone],
    lights: &'a [Vrl],
}

impl ClusterOracle for VrlOracle<'_> {
    fn bound(&self, index: u32, _node: &Node) -> f32 {
        self.ctx.bound.vrl_node(self.tree, index, self.lights, self.cones, self.dir_cones)
    }
    fn contribution(&mut self, light: u32) -> Rgb {
        let vrl = &self.lights[light as usize];
        let SegmentContext { scene, cs, cam_medium, media, key, .. } = self.ctx;
        sample_vrl_contribution(
            &cs.seg,
            cam_medium,
            vrl,
            &media[vrl.medium as usize],
            light_uniforms(key, light),
            |y, x| connect(scene, vrl.medium, y, x),
        )
    }
}

struct VplOracle<'a> {
    ctx: SegmentContext<'a>,
    tree: &'a LightTree,
    lights: &'a [Vpl],
}

impl ClusterOracle for VplOracle<'_> {
    fn bound(&self, _index: u32, node: &Node) -> f32 {
        self.ctx.bound.vpl_in_tree(self.tree, node, self.lights)
    }
    fn contribution(&mut self, light: u32) -> Rgb {
        let vpl = &self.lights[light as usize];
        let SegmentContext { scene, cs, cam_medium, media, key, .. } = self.ctx;
        sample_vpl_contribution(
            &cs.seg,
            cam_medium,
            vpl,
            &media[vpl.medium as usize].phase,
            light_uniforms(key, light).x,
            None,
            |y, x| connect(scene, vpl.medium, y, x),
        )
    }
}

impl Integrator for LightcutsIntegrator {
    type PassData = LightcutPass;

    fn name(&self) -> &str {
        match self.kind {
            LightKind::Vrl => "vrl_lightcuts",
            LightKind::Vpl => "vpl_lightcuts",
        }
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass {
        let set = trace_light_paths(scene, self.paths, seed, pass, &self.ml.trace)
            .expect("emitters were checked when the integrator was made");
        let media = media(scene);
        let t0 = Instant::now();
        let tree_seed = haze_core::rng::mix64(seed ^ ((pass as u64) << 32));
        fn empty<L>() -> [Forest<L>; 2] {
            [
                Forest {
                    lights: Vec::new(),
                    tree: LightTree::default(),
                    cones: Vec::new(),
                    dir_cones: Vec::new(),
                },
                Forest {
                    lights: Vec::new(),
                    tree: LightTree::default(),
                    cones: Vec::new(),
                    dir_cones: Vec::new(),
                },
            ]
        }
        let (vrls, vpls) = match self.kind {
            LightKind::Vrl => {
                let [a, b] = split_groups(&set.vrls, |r| r.after_surface, VrlRecord::to_vrl);
                let s = |v: &Vrl| LightSummary::vrl(v, &media[v.medium as usize]);
                let mut forests = [self.build(a, s, tree_seed), self.build(b, s, tree_seed ^ 1)];
                if self.settings.bound == BoundKind::Tight {
                    for f in &mut forests {
                        f.cones = node_cones(&f.tree, |i| f.lights[i as usize].seg.d);
                        f.dir_cones = node_dir_cones(&f.tree, |i| f.lights[i as usize].seg.d);
                    }
                }
                (forests, empty())
            }
            LightKind::Vpl => {
                let [a, b] = split_groups(&set.vpls, |r| r.after_surface, VplRecord::to_vpl);
                (
                    empty(),
                    [
                        self.build(a, LightSummary::vpl, tree_seed),
                        self.build(b, LightSummary::vpl, tree_seed ^ 1),
                    ],
                )
            }
        };
        self.stats.build_ns.fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
        let n = match self.kind {
            LightKind::Vrl => set.vrls.len(),
            LightKind::Vpl => set.vpls.len(),
        };
        self.stats.lights.fetch_add(n as u64, Ordering::Relaxed);
        self.stats.passes.fetch_add(1, Ordering::Relaxed);
        // Bounds on transmittance use the least extinction any connection may see; vacuum
        // anywhere (a camera or light outside every medium) makes it zero.
        let vacuum = scene.camera.medium.is_none()
            || scene
                .shapes
                .iter()
                .any(|s| s.is_medium_transition() && (s.interior.is_none() || s.exterior.is_none()));
        let sigma_t_min = if vacuum {
            Rgb::ZERO
        } else {
            media.iter().fold(Rgb::splat(f32::INFINITY), |acc, m| {
                Rgb(std::array::from_fn(|c| acc[c].min(m.sigma_t[c])))
            })
        };
        let light_phase = media.first().map(|m| m.phase).filter(|p| media.iter().all(|m| m.phase == *p));
        LightcutPass { light_factor: light_factor(&media), vrls, vpls, media, sigma_t_min, light_phase }
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        CUT_SCRATCH.with_borrow_mut(|scratch| {
            many_light_radiance(scene, ray, medium, sampler, |cs, key, group| {
                let cam_medium = &pass.media[cs.medium as usize];
                let bound = BoundContext {
                    seg: cs.seg,
                    camera_factor: cam_medium.sigma_s * cam_medium.phase.max_value(),
                    light_factor: pass.light_factor,
                    sigma_t_min: pass.sigma_t_min,
                    kind: self.settings.bound,
                    theta: self.settings.theta,
                    camera_phase: cam_medium.phase,
                    light_phase: pass.light_phase,
                };
                let ctx = SegmentContext { scene, cs, cam_medium, media: &pass.media, bound, key };
                let (value, stats) = match self.kind {
                    LightKind::Vrl => {
                        let f = &pass.vrls[group];
                        let mut o = VrlOracle {
                            ctx,
                            tree: &f.tree,
                            cones: &f.cones,
                            dir_cones: &f.dir_cones,
                            lights: &f.lights,
                        };
                        lightcut(&f.tree, &mut o, &self.settings.cut, scratch)
                    }
                    LightKind::Vpl => {
                        let f = &pass.vpls[group];
                        let mut o = VplOracle { ctx, tree: &f.tree, lights: &f.lights };
                        lightcut(&f.tree, &mut o, &self.settings.cut, scratch)
                    }
                };
                self.record(&stats);
                value
            })
        })
    }

    fn summary(&self) -> Option<String> {
        let passes = self.stats.passes.load(Ordering::Relaxed).max(1);
        let (mean, max, hit) = self.cut_statistics();
        Some(format!(
            "{}: {} light paths and {:.0} lights per pass ({} passes); tree build {:.3} s per pass; cut size mean {:.1}, max {}; {:.2}% of segments hit max-cut {}",
            self.name(),
            self.paths,
            self.stats.lights.load(Ordering::Relaxed) as f64 / passes as f64,
            passes,
            self.build_seconds() / passes as f64,
            mean,
            max,
            100.0 * hit,
            self.settings.cut.max_cut
        ))
    }
}

impl LightcutsIntegrator {
    fn record(&self, s: &CutStats) {
        if s.size == 0 {
            return;
        }
        CUT_TALLY.with(|t| {
            let (size, n) = t.get();
            t.set((size + s.size as u64, n + 1));
        });
        self.stats.segments.fetch_add(1, Ordering::Relaxed);
        self.stats.cut_total.fetch_add(s.size as u64, Ordering::Relaxed);
        self.stats.cut_max.fetch_max(s.size as u64, Ordering::Relaxed);
        if s.hit_max {
            self.stats.hit_max.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Renders the mean cut size over a camera path's segments instead of its radiance, in every
/// channel of the `emitted` component (0 where the path meets no medium). Runs the wrapped
/// integrator unchanged, so the cuts are those of the image with the same seed and pass.
pub struct CutSizeProbe<'a>(pub &'a LightcutsIntegrator);

impl Integrator for CutSizeProbe<'_> {
    type PassData = LightcutPass;

    fn name(&self) -> &str {
        self.0.name()
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass {
        self.0.begin_pass(scene, seed, pass)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        CUT_TALLY.with(|t| t.set((0, 0)));
        let _ = self.0.radiance(scene, pass, ray, medium, sampler);
        let (size, n) = CUT_TALLY.with(|t| t.get());
        let mut r = PathRadiance::default();
        if n > 0 {
            r.add(haze_render::Component::Emitted, Rgb::splat(size as f32 / n as f32));
        }
        r
    }
}
