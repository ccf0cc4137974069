//! The light kinds the many-light integrator clusters: what differs between VRLs, VPLs and
//! surface VPLs is only which lights a pass makes, their tree summary, their bound and their
//! evaluation. [`LightKind`] is what every kind of light has (surface VPLs included);
//! [`ClusterKind`] is a kind of medium light an integrator is made for (`Vrls`, `Vpls`).

use super::Forest;
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::integrators::{
    connect, light_uniforms, medium_vpl_to_point, surface_vpl_to_point, surface_vpl_to_segment,
};
use crate::lighttrace::{LightSet, VplRecord, VrlRecord};
use crate::tree::bound::{BoundContext, BoundKind};
use crate::tree::cone::{node_cones, node_dir_cones};
use crate::tree::importance::{ImportanceContext, PointImportance};
use crate::tree::lights::LightSummary;
use crate::tree::stochastic::SampleNode;
use crate::tree::Aabb;
use crate::vpl::{sample_vpl_contribution, SurfaceVpl, Vpl};
use crate::vrl::estimator::{contributes, point_pair_estimate, sample_point_pair, PointPair};
use crate::vrl::surface::sample_vrl_to_point;
use crate::vrl::{sample_vrl_contribution, Vrl, VrlMedium};
use haze_core::Rgb;
use haze_scene::Scene;

/// A kind of virtual light that the many-light integrator sums over: through a cut of a tree of
/// them or every one of them (the exhaustive cut).
pub trait LightKind: Sized + Send + Sync + 'static {
    type Light: Send + Sync;
    /// What the tree knows of one light.
    fn summary(light: &Self::Light, media: &[VrlMedium]) -> LightSummary;
    /// The stochastic cut's importance of a leaf `node` holding `light` (by default the node
    /// formula; a kind may know its light's shape better).
    fn leaf_importance(ctx: &ImportanceContext, node: &SampleNode, _light: &Self::Light) -> f32 {
        ctx.importance(node)
    }
    /// The gathering points' importance of a leaf `node` holding `light`.
    fn leaf_point_importance(pi: &PointImportance, node: &SampleNode, _light: &Self::Light) -> f32 {
        pi.importance(node)
    }
    /// One sampled contribution of light `index` to camera segment `cs`, with random numbers
    /// of its own from `key` and `index` (`light_uniforms`): unbiased unless `clamps` clamps it.
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        light: &Self::Light,
        key: u64,
        index: u32,
        clamps: &Clamps,
    ) -> Rgb;
    /// The exhaustive cut of camera segment `cs`: `sum_i contribution(.., lights[i], key, i, ..)`
    /// in the order of `lights`. A kind may compute it faster, but must add the same values in
    /// the same order.
    fn contribution_sum(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        lights: &[Self::Light],
        key: u64,
        clamps: &Clamps,
    ) -> Rgb {
        sum_each(lights, |light, i| Self::contribution(scene, cs, media, light, key, i, clamps))
    }
    /// One sampled contribution of `light` to the gathering surface point `gp` (unbiased
    /// unless `clamps` clamps its `1/d^2`; `docs/theory.md` §5.1, §5.3).
    fn to_point(
        scene: &Scene,
        gp: &GatherPoint,
        media: &[VrlMedium],
        light: &Self::Light,
        u: f32,
        clamps: &Clamps,
    ) -> Rgb;
}

/// `sum_i f(lights[i], i)`, one light after the other from zero: the order in which
/// [`LightKind::contribution_sum`] defines the exhaustive cut's sum (a kind that hoists a
/// per-sum question out of `contribution` passes its own `f`).
#[inline]
fn sum_each<L>(lights: &[L], mut f: impl FnMut(&L, u32) -> Rgb) -> Rgb {
    let mut sum = Rgb::ZERO;
    for (i, light) in lights.iter().enumerate() {
        sum += f(light, i as u32);
    }
    sum
}

/// A kind of medium light that a many-light integrator is made for: with a tree's cut
/// (`vrl_lightcuts`, `vpl_lightcuts`) or the exhaustive cut (`vrl`, `vpl`). Its pass also has
/// surface VPLs ([`SurfaceVpls`]), whatever the kind.
pub trait ClusterKind: LightKind {
    /// The integrator's name with a tree's cut (`vrl_lightcuts`, ...).
    const NAME: &'static str;
    /// The integrator's name with the exhaustive cut, every light evaluated (`vrl`, ...).
    const EXHAUSTIVE_NAME: &'static str;
    /// What its lights are called in a summary line (`VRLs`, ...).
    const LIGHTS: &'static str;
    /// This kind's lights of a pass, in the two groups of `gather::Gather::segment`
    /// (medium-only, after a surface bounce).
    fn lights(set: &LightSet) -> [Vec<Self::Light>; 2];
    /// Per-node data the bound needs beyond the tree (the tight bound's cones).
    fn prepare(_forest: &mut Forest<Self>, _bound: BoundKind) {}
    /// Upper bound of node `index`'s contribution (the deterministic cut).
    fn bound(ctx: &BoundContext, forest: &Forest<Self>, index: u32) -> f32;
}

/// The clamps of the `1/d^2`-like terms: the biased ones of the exhaustive cut's options
/// (`vpl_clamp`, `clamp`; `None`, the default and always with a tree's cut, is unbiased) and
/// the compensated one (`compensated_clamp`, unbiased with its compensation walk).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clamps {
    /// The geometry term `1/w^2` of a medium VPL -> camera segment connection (VPLs only).
    pub vpl: Option<f32>,
    /// The `1/d^2` of the connections to gathering surface points and from surface VPLs.
    pub surface: Option<f32>,
    /// The `1/d^2` of surface VPL -> gathering point connections where `surface` is `None`,
    /// the clamped part recovered by the camera walk (`gather::Gather::compensated_clamp`).
    pub compensated: Option<f32>,
}

/// Virtual ray lights (`vrl_lightcuts`).
pub struct Vrls;

impl ClusterKind for Vrls {
    const NAME: &'static str = "vrl_lightcuts";
    const EXHAUSTIVE_NAME: &'static str = "vrl";
    const LIGHTS: &'static str = "VRLs";

    fn lights(set: &LightSet) -> [Vec<Vrl>; 2] {
        crate::integrators::split_groups(&set.vrls, |r| r.after_surface, VrlRecord::to_vrl)
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
}

impl LightKind for Vrls {
    type Light = Vrl;

    fn summary(v: &Vrl, media: &[VrlMedium]) -> LightSummary {
        LightSummary::vrl(v, &media[v.medium as usize])
    }
    fn leaf_importance(ctx: &ImportanceContext, node: &SampleNode, v: &Vrl) -> f32 {
        ctx.vrl_importance(v.seg.o, v.seg.d, v.seg.len, node.power)
    }
    fn leaf_point_importance(pi: &PointImportance, node: &SampleNode, v: &Vrl) -> f32 {
        pi.vrl_importance(v.seg.o, v.seg.d, v.seg.len, node.power)
    }
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        vrl: &Vrl,
        key: u64,
        index: u32,
        _clamps: &Clamps,
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
    /// In homogeneous media, a chunk of lights at a time: first the points of every light of the
    /// chunk (`sample_point_pair`), then their contributions (`point_pair_estimate`), which
    /// keeps the sampling's arithmetic apart from the connections' ray casts.
    fn contribution_sum(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        lights: &[Vrl],
        key: u64,
        clamps: &Clamps,
    ) -> Rgb {
        /// Lights sampled back to back before their contributions are evaluated.
        const CHUNK: usize = 16;
        if crate::hetero::any(scene) {
            return sum_each(lights, |vrl, i| Self::contribution(scene, cs, media, vrl, key, i, clamps));
        }
        let (cam, cam_medium) = (&cs.seg, &media[cs.medium as usize]);
        let mut sum = Rgb::ZERO;
        for (c, chunk) in lights.chunks(CHUNK).enumerate() {
            let mut pairs: [Option<PointPair>; CHUNK] = [None; CHUNK];
            for (k, vrl) in chunk.iter().enumerate() {
                if crate::depth::connects(scene, vrl.events, cs.events)
                    && contributes(cam, cam_medium, vrl, &media[vrl.medium as usize])
                {
                    pairs[k] = sample_point_pair(cam, &vrl.seg, light_uniforms(key, (c * CHUNK + k) as u32));
                }
            }
            for (vrl, pair) in chunk.iter().zip(&pairs) {
                if let Some(pair) = pair {
                    sum += point_pair_estimate(
                        cam,
                        cam_medium,
                        vrl,
                        &media[vrl.medium as usize],
                        pair,
                        |y, x| connect(scene, vrl.medium, y, x),
                    );
                }
            }
        }
        sum
    }
    fn to_point(
        scene: &Scene,
        gp: &GatherPoint,
        media: &[VrlMedium],
        vrl: &Vrl,
        u: f32,
        _clamps: &Clamps,
    ) -> Rgb {
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
    const NAME: &'static str = "vpl_lightcuts";
    const EXHAUSTIVE_NAME: &'static str = "vpl";
    const LIGHTS: &'static str = "VPLs";

    fn lights(set: &LightSet) -> [Vec<Vpl>; 2] {
        crate::integrators::split_groups(&set.vpls, |r| r.after_surface, VplRecord::to_vpl)
    }
    fn bound(ctx: &BoundContext, f: &Forest<Self>, index: u32) -> f32 {
        ctx.vpl_in_tree(&f.tree, &f.tree.nodes[index as usize], &f.lights)
    }
}

impl LightKind for Vpls {
    type Light = Vpl;

    fn summary(v: &Vpl, _media: &[VrlMedium]) -> LightSummary {
        LightSummary::vpl(v)
    }
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        vpl: &Vpl,
        key: u64,
        index: u32,
        clamps: &Clamps,
    ) -> Rgb {
        vpl_to_segment(scene, crate::hetero::any(scene), cs, media, vpl, key, index, clamps)
    }
    /// The scene's media asked once per sum, not once per light.
    fn contribution_sum(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        lights: &[Vpl],
        key: u64,
        clamps: &Clamps,
    ) -> Rgb {
        let hetero = crate::hetero::any(scene);
        sum_each(lights, |vpl, i| vpl_to_segment(scene, hetero, cs, media, vpl, key, i, clamps))
    }
    fn to_point(
        scene: &Scene,
        gp: &GatherPoint,
        media: &[VrlMedium],
        vpl: &Vpl,
        _u: f32,
        clamps: &Clamps,
    ) -> Rgb {
        medium_vpl_to_point(scene, vpl, gp, media, clamps.surface)
    }
}

/// [`Vpls`]' `contribution`, with `hetero = crate::hetero::any(scene)` given.
#[allow(clippy::too_many_arguments)]
#[inline]
fn vpl_to_segment(
    scene: &Scene,
    hetero: bool,
    cs: &CameraSegment,
    media: &[VrlMedium],
    vpl: &Vpl,
    key: u64,
    index: u32,
    clamps: &Clamps,
) -> Rgb {
    if !crate::depth::connects(scene, vpl.events, cs.events) {
        return Rgb::ZERO;
    }
    if hetero {
        let u = light_uniforms(key, index);
        return crate::hetero::vpl_to_segment(scene, cs, media, vpl, u, clamps.vpl);
    }
    sample_vpl_contribution(
        &cs.seg,
        &media[cs.medium as usize],
        vpl,
        &media[vpl.medium as usize].phase,
        light_uniforms(key, index).x,
        clamps.vpl,
        |y, x| connect(scene, vpl.medium, y, x),
    )
}

/// Surface VPLs (`docs/theory.md` §2.1, (T12c) and (T12d)), in every many-light method's pass.
/// **Ours:** with a tree's cut they get a tree of their own, built like the medium trees over
/// their points and fluxes, and cut stochastically for camera segments and gathering points
/// (docs/lightcuts.md, "The whole image").
pub struct SurfaceVpls;

impl LightKind for SurfaceVpls {
    type Light = SurfaceVpl;

    /// A point with its flux as power.
    fn summary(v: &SurfaceVpl, _media: &[VrlMedium]) -> LightSummary {
        LightSummary {
            bounds: Aabb::from_points(v.p, v.p),
            intensity: v.flux.max_component(),
            flux_bound: v.flux,
            length: 0.0,
            power: v.flux,
        }
    }
    fn contribution(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        vpl: &SurfaceVpl,
        key: u64,
        index: u32,
        clamps: &Clamps,
    ) -> Rgb {
        let (hetero, cam_medium) = (crate::hetero::any(scene), &media[cs.medium as usize]);
        surface_vpl_to_segment(scene, hetero, vpl, index as usize, cs, cam_medium, key, clamps.surface)
    }
    /// The scene's media asked once per sum, not once per light.
    fn contribution_sum(
        scene: &Scene,
        cs: &CameraSegment,
        media: &[VrlMedium],
        lights: &[SurfaceVpl],
        key: u64,
        clamps: &Clamps,
    ) -> Rgb {
        let (hetero, cam_medium) = (crate::hetero::any(scene), &media[cs.medium as usize]);
        sum_each(lights, |vpl, i| {
            surface_vpl_to_segment(scene, hetero, vpl, i as usize, cs, cam_medium, key, clamps.surface)
        })
    }
    fn to_point(
        scene: &Scene,
        gp: &GatherPoint,
        _media: &[VrlMedium],
        vpl: &SurfaceVpl,
        _u: f32,
        clamps: &Clamps,
    ) -> Rgb {
        surface_vpl_to_point(scene, vpl, gp, clamps.surface.or(clamps.compensated))
    }
}
