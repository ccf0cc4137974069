//! The light kinds the lightcut integrator clusters: what differs between VRLs and VPLs is
//! only which lights a pass makes, their tree summary, their bound and their evaluation.

use super::Forest;
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::integrators::{connect, light_uniforms, medium_vpl_to_point};
use crate::lighttrace::{LightSet, VplRecord, VrlRecord};
use crate::tree::bound::{BoundContext, BoundKind};
use crate::tree::cone::{node_cones, node_dir_cones};
use crate::tree::importance::{ImportanceContext, PointImportance};
use crate::tree::lights::LightSummary;
use crate::tree::stochastic::SampleNode;
use crate::vpl::{sample_vpl_contribution, Vpl};
use crate::vrl::surface::sample_vrl_to_point;
use crate::vrl::{sample_vrl_contribution, Vrl, VrlMedium};
use haze_core::Rgb;
use haze_scene::Scene;

/// A kind of virtual light that the lightcut integrator builds trees over and cuts.
pub trait ClusterKind: Sized + Send + Sync + 'static {
    type Light: Send + Sync;
    /// The integrator's name (`vrl_lightcuts`, ...).
    const NAME: &'static str;
    /// This kind's lights of a pass, in the two groups of `gather::Gather::segment`
    /// (medium-only, after a surface bounce).
    fn lights(set: &LightSet) -> [Vec<Self::Light>; 2];
    /// What the tree knows of one light.
    fn summary(light: &Self::Light, media: &[VrlMedium]) -> LightSummary;
    /// Per-node data the bound needs beyond the tree (the tight bound's cones).
    fn prepare(_forest: &mut Forest<Self>, _bound: BoundKind) {}
    /// The stochastic cut's importance of a leaf `node` holding `light` (by default the node
    /// formula; a kind may know its light's shape better).
    fn leaf_importance(ctx: &ImportanceContext, node: &SampleNode, _light: &Self::Light) -> f32 {
        ctx.importance(node)
    }
    /// The gathering points' importance of a leaf `node` holding `light`.
    fn leaf_point_importance(pi: &PointImportance, node: &SampleNode, _light: &Self::Light) -> f32 {
        pi.importance(node)
    }
    /// Upper bound of node `index`'s contribution (the deterministic cut).
    fn bound(ctx: &BoundContext, forest: &Forest<Self>, index: u32) -> f32;
    /// One sampled contribution of light `index` to camera segment `cs` (unbiased).
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        light: &Self::Light,
        key: u64,
        index: u32,
    ) -> Rgb;
    /// One sampled contribution of `light` to the gathering surface point `gp` (unbiased;
    /// `docs/theory.md` §5.1, §5.3).
    fn to_point(scene: &Scene, gp: &GatherPoint, media: &[VrlMedium], light: &Self::Light, u: f32) -> Rgb;
}

/// Virtual ray lights (`vrl_lightcuts`).
pub struct Vrls;

impl ClusterKind for Vrls {
    type Light = Vrl;
    const NAME: &'static str = "vrl_lightcuts";

    fn lights(set: &LightSet) -> [Vec<Vrl>; 2] {
        crate::integrators::split_groups(&set.vrls, |r| r.after_surface, VrlRecord::to_vrl)
    }
    fn summary(v: &Vrl, media: &[VrlMedium]) -> LightSummary {
        LightSummary::vrl(v, &media[v.medium as usize])
    }
    fn leaf_importance(ctx: &ImportanceContext, node: &SampleNode, v: &Vrl) -> f32 {
        ctx.vrl_importance(v.seg.o, v.seg.d, v.seg.len, node.power)
    }
    fn leaf_point_importance(pi: &PointImportance, node: &SampleNode, v: &Vrl) -> f32 {
        pi.vrl_importance(v.seg.o, v.seg.d, v.seg.len, node.power)
    }
    fn prepare(f: &mut Forest<Self>, bound: BoundKind) {
        if bound == BoundKind::Tight {
            f.cones = node_cones(&f.tree, |i| f.lights[i as usize].seg.d);
            f.dir_cones = node_dir_cones(&f.tree, |i| f.lights[i as usize].seg.d);
        }
    }
    fn bound(ctx: &BoundContext, f: &Forest<Self>, index: u32) -> f32 {
        ctx.vrl_node(&f.tree, index, &f.lights, &f.cones, &f.dir_cones)
    }
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        vrl: &Vrl,
        key: u64,
        index: u32,
    ) -> Rgb {
        if !crate::depth::connects(scene, vrl.events, cs.events) {
            return Rgb::ZERO;
        }
        if crate::hetero::any(scene) {
            return crate::hetero::vrl_to_segment(scene, cs, media, vrl, light_uniforms(key, index));
        }
        sample_vrl_contribution(
            &cs.seg,
            &media[cs.medium as usize],
            vrl,
            &media[vrl.medium as usize],
            light_uniforms(key, index),
            |y, x| connect(scene, vrl.medium, y, x),
        )
    }
    fn to_point(scene: &Scene, gp: &GatherPoint, media: &[VrlMedium], vrl: &Vrl, u: f32) -> Rgb {
        if !crate::depth::connects(scene, vrl.events, gp.events) {
            return Rgb::ZERO;
        }
        if crate::hetero::any(scene) {
            return crate::hetero::vrl_to_point(scene, gp.p, |d| gp.reflectance(d), media, vrl, u);
        }
        sample_vrl_to_point(
            gp.p,
            |d| gp.reflectance(d),
            vrl,
            &media[vrl.medium as usize],
            u,
            |y, x| connect(scene, vrl.medium, y, x),
        )
    }
}

/// Virtual point lights (`vpl_lightcuts`).
pub struct Vpls;

impl ClusterKind for Vpls {
    type Light = Vpl;
    const NAME: &'static str = "vpl_lightcuts";

    fn lights(set: &LightSet) -> [Vec<Vpl>; 2] {
        crate::integrators::split_groups(&set.vpls, |r| r.after_surface, VplRecord::to_vpl)
    }
    fn summary(v: &Vpl, _media: &[VrlMedium]) -> LightSummary {
        LightSummary::vpl(v)
    }
    fn bound(ctx: &BoundContext, f: &Forest<Self>, index: u32) -> f32 {
        ctx.vpl_in_tree(&f.tree, &f.tree.nodes[index as usize], &f.lights)
    }
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        vpl: &Vpl,
        key: u64,
        index: u32,
    ) -> Rgb {
        if !crate::depth::connects(scene, vpl.events, cs.events) {
            return Rgb::ZERO;
        }
        if crate::hetero::any(scene) {
            return crate::hetero::vpl_to_segment(scene, cs, media, vpl, light_uniforms(key, index), None);
        }
        sample_vpl_contribution(
            &cs.seg,
            &media[cs.medium as usize],
            vpl,
            &media[vpl.medium as usize].phase,
            light_uniforms(key, index).x,
            None,
            |y, x| connect(scene, vpl.medium, y, x),
        )
    }
    fn to_point(scene: &Scene, gp: &GatherPoint, media: &[VrlMedium], vpl: &Vpl, _u: f32) -> Rgb {
        medium_vpl_to_point(scene, vpl, gp, media, None)
    }
}
