//! The bound cut (`--cut bound`): the paper's deterministic cut of each medium tree for a camera
//! segment (`tree::cut`), refined by upper bounds on the nodes' contributions
//! (`tree::bound`, `docs/theory.md` §7).

use super::probe::tally;
use super::stochastic::{point_cut, surface_cut};
use super::{
    Clamps, ClusterKind, CutObserver, CutStrategy, Forest, LightcutPass, PassView, SurfaceVpls, TreeSettings,
};
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::tree::bound::{BoundContext, BoundKind, ThetaBound};
use crate::tree::cut::{lightcut, ClusterOracle, CutScratch, CutSettings};
use crate::tree::stochastic::StochasticSettings;
use crate::tree::Node;
use crate::vpl::SurfaceVpl;
use crate::vrl::VrlMedium;
use haze_core::Rgb;
use haze_scene::{MediumId, Scene};
use std::cell::RefCell;

thread_local! {
    static CUT_SCRATCH: RefCell<CutScratch> = RefCell::new(CutScratch::default());
}

/// The deterministic cut by bounds: refine until every node's bound is at most `epsilon` times
/// the estimate or the cut has `max_cut` nodes, each node estimated by its representative
/// light's sampled contribution times `I_node / I_rep`. It cuts the medium trees at camera
/// segments; the surface VPLs and gathering points it cuts stochastically with `points`, as
/// [`super::StochasticCut`] does.
#[derive(Clone, Copy, Debug)]
pub struct BoundCut {
    pub tree: TreeSettings,
    pub cut: CutSettings,
    pub bound: BoundKind,
    pub theta: ThetaBound,
    /// The stochastic cuts of the surface VPLs and of gathering points.
    pub points: StochasticSettings,
}

impl Default for BoundCut {
    fn default() -> Self {
        BoundCut {
            tree: TreeSettings::default(),
            cut: CutSettings::default(),
            bound: BoundKind::Paper,
            theta: ThetaBound::Exact,
            points: StochasticSettings::default(),
        }
    }
}

/// What the bound cut computes once per pass from the pass's media (`docs/theory.md` §7, and
/// §12.5 for heterogeneous media).
pub struct BoundPass {
    /// Per medium, `sigma_s f_max` on the camera side (`crate::hetero::bound_factor`).
    pub(super) camera_factors: Vec<Rgb>,
    /// The largest of `camera_factors`: any medium may hold the light.
    light_factor: Rgb,
    /// The least extinction any connection may see: zero where one may cross vacuum (a camera
    /// or a light outside every medium) or a heterogeneous medium (its extinction may be zero
    /// anywhere in its box, and is outside it).
    sigma_t_min: Rgb,
    /// The phase every medium shares, if one (for the tight bound's light-side phase).
    light_phase: Option<haze_core::Phase>,
}

impl BoundPass {
    fn new(scene: &Scene, media: &[VrlMedium]) -> BoundPass {
        let vacuum = scene.camera.medium.is_none()
            || scene
                .shapes
                .iter()
                .any(|s| s.is_medium_transition() && (s.interior.is_none() || s.exterior.is_none()));
        let sigma_t_min = if vacuum || crate::hetero::any(scene) {
            Rgb::ZERO
        } else {
            media.iter().fold(Rgb::splat(f32::INFINITY), |acc, m| acc.min(m.sigma_t))
        };
        let camera_factors: Vec<Rgb> = (0..media.len())
            .map(|id| crate::hetero::bound_factor(scene, &media[id], id as MediumId))
            .collect();
        BoundPass {
            light_factor: camera_factors.iter().fold(Rgb::ZERO, |a, f| a.max(*f)),
            camera_factors,
            sigma_t_min,
            light_phase: media.first().map(|m| m.phase).filter(|p| media.iter().all(|m| m.phase == *p)),
        }
    }
}

impl CutStrategy for BoundCut {
    type PassData = BoundPass;

    fn pass_data(&self, scene: &Scene, media: &[VrlMedium]) -> BoundPass {
        BoundPass::new(scene, media)
    }

    fn name<K: ClusterKind>(&self) -> &'static str {
        K::NAME
    }

    fn forests<K: ClusterKind>(
        &self,
        lights: [Vec<K::Light>; 2],
        surface: Vec<SurfaceVpl>,
        media: &[VrlMedium],
        seed: u64,
    ) -> ([Forest<K>; 2], Forest<SurfaceVpls>) {
        self.tree.forests(lights, surface, media, seed, |f| K::prepare(f, self.bound))
    }

    fn segment<K: ClusterKind, O: CutObserver<K>>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        _observer: &O,
    ) -> [Rgb; 2] {
        let [a, b] = [0, 1].map(|g| self.medium_cut(view, cs, key, g));
        [a, b + surface_cut(view, cs, key, &self.points)]
    }

    fn point<K: ClusterKind>(&self, view: &PassView<'_, K, Self>, gp: &GatherPoint, key: u64) -> Rgb {
        point_cut(view, gp, key, &self.points)
    }

    fn describe(&self, mean: f64, max: u64, hit: f64) -> Option<String> {
        Some(format!(
            "bound cut: size mean {mean:.1}, max {max}; {:.2}% of segments hit max-cut {}",
            100.0 * hit,
            self.cut.max_cut
        ))
    }
}

impl BoundCut {
    /// What the cut bounds the contributions to camera segment `cs` with (`docs/theory.md` §7,
    /// and §12.5 for heterogeneous media).
    pub(super) fn context<K: ClusterKind>(
        &self,
        pass: &LightcutPass<K, Self>,
        cs: &CameraSegment,
    ) -> BoundContext {
        let b = &pass.strategy;
        BoundContext {
            seg: cs.seg,
            camera_factor: b.camera_factors[cs.medium as usize],
            light_factor: b.light_factor,
            sigma_t_min: b.sigma_t_min,
            kind: self.bound,
            theta: self.theta,
            camera_phase: pass.media[cs.medium as usize].phase,
            light_phase: b.light_phase,
        }
    }

    /// The cut of medium tree `group` for camera segment `cs`.
    fn medium_cut<K: ClusterKind>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        group: usize,
    ) -> Rgb {
        let (scene, pass) = (view.scene, view.pass);
        let forest = &pass.forests[group];
        if forest.lights.is_empty() {
            return Rgb::ZERO;
        }
        let (value, stats) = CUT_SCRATCH.with_borrow_mut(|scratch| {
            let bound = self.context(pass, cs);
            let mut o = Oracle { scene, forest, cs, media: &pass.media, bound, key };
            lightcut(&forest.tree, &mut o, &self.cut, scratch)
        });
        if stats.size > 0 {
            tally(stats.size as f64);
        }
        view.stats.record(&stats);
        value
    }
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
    /// Unclamped: the bound cut has no biased clamps.
    fn contribution(&mut self, light: u32) -> Rgb {
        let l = &self.forest.lights[light as usize];
        K::contribution(self.scene, self.cs, self.media, l, self.key, light, &Clamps::default())
    }
}
