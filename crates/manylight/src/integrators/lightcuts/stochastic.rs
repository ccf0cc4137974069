//! The stochastic cut (`--cut stochastic`, `tree::stochastic`): a cut of `cut_size` nodes by
//! importance, one light sampled per node, weighted by the inverse of its probability. Also the
//! stochastic cuts every tree cut makes of the surface VPLs at camera segments and of all three
//! trees at gathering points ([`surface_cut`], [`point_cut`]; docs/lightcuts.md "The whole
//! image").

use super::probe::{probing, tally};
use super::{
    ClusterKind, CutObserver, CutStrategy, Forest, LightKind, PassView, SegmentCut, SurfaceVpls, TreeSettings,
};
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::integrators::light_uniforms;
use crate::tree::cut::CutStats;
use crate::tree::importance::{ImportanceContext, PointImportance};
use crate::tree::stochastic::{
    mixed_probability, power, stochastic_cut, SampleNode, SampleTree, StochasticScratch, StochasticSettings,
};
use crate::vpl::SurfaceVpl;
use crate::vrl::VrlMedium;
use haze_core::streams::{LIGHT_SAMPLES, POINT_CUT, SEGMENT_CUT, SURFACE_VPL_CUT};
use haze_core::Rgb;
use haze_scene::Scene;
use std::cell::RefCell;

thread_local! {
    static STOCHASTIC_SCRATCH: RefCell<StochasticScratch> = RefCell::new(StochasticScratch::default());
}

/// The bound-free cut: unbiased, a fixed cost per camera segment and tree.
#[derive(Clone, Copy, Debug, Default)]
pub struct StochasticCut {
    pub tree: TreeSettings,
    /// The cut of every tree, at camera segments and gathering points.
    pub settings: StochasticSettings,
}

impl CutStrategy for StochasticCut {
    type PassData = ();

    fn pass_data(&self, _scene: &Scene, _media: &[VrlMedium]) {}

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
        self.tree.forests(lights, surface, media, seed, |_| {})
    }

    fn segment<K: ClusterKind, O: CutObserver<K>>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        observer: &O,
    ) -> [Rgb; 2] {
        let [a, b] = [0, 1].map(|g| self.medium_cut(view, cs, key, g, observer));
        [a, b + surface_cut(view, cs, key, &self.settings)]
    }

    fn point<K: ClusterKind>(&self, view: &PassView<'_, K, Self>, gp: &GatherPoint, key: u64) -> Rgb {
        point_cut(view, gp, key, &self.settings)
    }

    fn describe(&self, mean: f64, _max: u64, _hit: f64) -> Option<String> {
        Some(format!(
            "stochastic cut of {} nodes: mean {mean:.1} per camera segment and tree",
            self.settings.cut_size
        ))
    }
}

impl StochasticCut {
    /// The cut of medium tree `group` for camera segment `cs`: each sampled light's
    /// `light_samples` joint samples averaged, weighted by `1 / probability`.
    fn medium_cut<K: ClusterKind, O: CutObserver<K>>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        group: usize,
        observer: &O,
    ) -> Rgb {
        let (scene, pass, clamps) = (view.scene, view.pass, view.clamps);
        let forest = &pass.forests[group];
        if forest.lights.is_empty() {
            return Rgb::ZERO;
        }
        let cam_medium = &pass.media[cs.medium as usize];
        let (sum, size) = STOCHASTIC_SCRATCH.with_borrow_mut(|scratch| {
            let ctx = ImportanceContext::new(cs.seg, cam_medium);
            // A leaf's importance from its light's own shape (`LightKind::leaf_importance`).
            let importance = |n: &SampleNode| {
                if n.is_leaf() {
                    K::leaf_importance(&ctx, n, &forest.lights[n.light() as usize])
                } else {
                    ctx.importance(n)
                }
            };
            let mut sum = Rgb::ZERO;
            let light_samples = self.settings.light_samples;
            let descent_key = key ^ SEGMENT_CUT.wrapping_mul(group as u64 + 1);
            let size = stochastic_cut(
                &forest.sample,
                &importance,
                &self.settings,
                descent_key,
                scratch,
                |light, prob| {
                    // `light_samples` joint samples of the chosen light, averaged: the descent divides
                    // each light's joint-sampling variance by its probability (docs/lightcuts.md,
                    // "Choosing the importance").
                    let l = &forest.lights[light as usize];
                    let m = light_samples.max(1);
                    let weight = 1.0 / (prob * m as f32);
                    for j in 0..m as u64 {
                        let kj = if j == 0 {
                            key
                        } else {
                            haze_core::rng::mix64(key ^ j.wrapping_mul(LIGHT_SAMPLES))
                        };
                        let c = K::contribution(scene, cs, &pass.media, l, kj, light, clamps);
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
                power_share: self.settings.power_share,
            });
            if probing() {
                let (mut total, mut largest) = (0.0f64, 0.0f64);
                for &n in scratch.cut() {
                    let i = importance(forest.sample.node(n)) as f64;
                    total += i;
                    largest = largest.max(i);
                }
                tally(if total > 0.0 { largest / total } else { 1.0 });
            }
            (sum, size)
        });
        view.stats.record(&CutStats { size, hit_max: false });
        sum
    }
}

/// The surface VPLs' light at camera segment `cs`, cut stochastically with the segment's
/// importance.
pub(super) fn surface_cut<K: ClusterKind, S: CutStrategy>(
    view: &PassView<'_, K, S>,
    cs: &CameraSegment,
    key: u64,
    settings: &StochasticSettings,
) -> Rgb {
    let (scene, pass, clamps) = (view.scene, view.pass, view.clamps);
    let (media, surface_vpls) = (&pass.media[..], &pass.surface.lights);
    let ctx = ImportanceContext::new(cs.seg, &pass.media[cs.medium as usize]);
    cut_sum(&pass.surface.sample, &|n| ctx.importance(n), key ^ SURFACE_VPL_CUT, settings, |i| {
        SurfaceVpls::contribution(scene, cs, media, &surface_vpls[i as usize], key, i, clamps)
    })
}

/// The gathering point's cut: one of the three trees chosen, then cut stochastically.
pub(super) fn point_cut<K: ClusterKind, S: CutStrategy>(
    view: &PassView<'_, K, S>,
    gp: &GatherPoint,
    key: u64,
    settings: &StochasticSettings,
) -> Rgb {
    let (scene, pass, clamps) = (view.scene, view.pass, view.clamps);
    let pi = PointImportance::new(gp.p, gp.n, pass.sigma_mean);
    // One tree per gathering point, picked like a descent's first step over the three roots
    // (importance mixed with the power share), then cut: one light evaluation per point, as
    // many as a segment's single tree.
    let roots = [&pass.forests[0].sample, &pass.forests[1].sample, &pass.surface.sample];
    let share = settings.power_share;
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
        cut_sum(&forest.sample, &importance, key ^ stream, settings, |i| {
            let u = light_uniforms(key ^ stream, i).x;
            K::to_point(scene, gp, &pass.media, &forest.lights[i as usize], u, clamps)
        })
    } else {
        let surface = &pass.surface.lights;
        cut_sum(&pass.surface.sample, &|n| pi.importance(n), key ^ stream, settings, |i| {
            SurfaceVpls::to_point(scene, gp, &pass.media, &surface[i as usize], 0.0, clamps)
        })
    };
    sum * (1.0 / p_tree)
}

/// The stochastic cut's estimate (`cut_size` nodes, one light each) of the sum of `eval` over
/// the lights of `tree`, descending with `importance` and the numbers of `key`.
fn cut_sum(
    tree: &SampleTree,
    importance: &impl Fn(&SampleNode) -> f32,
    key: u64,
    settings: &StochasticSettings,
    mut eval: impl FnMut(u32) -> Rgb,
) -> Rgb {
    if tree.is_empty() {
        return Rgb::ZERO;
    }
    STOCHASTIC_SCRATCH.with_borrow_mut(|scratch| {
        let mut sum = Rgb::ZERO;
        stochastic_cut(tree, importance, settings, key, scratch, |light, prob| {
            sum += eval(light) * (1.0 / prob);
        });
        sum
    })
}
