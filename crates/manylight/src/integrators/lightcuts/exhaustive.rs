//! The exhaustive cut: every light of the pass evaluated at every camera segment and gathering
//! point, the brute-force sum of `vrl` and `vpl` (`docs/theory.md` §2.1) that the tree cuts
//! estimate.

use super::{ClusterKind, CutObserver, CutStrategy, Forest, LightKind, PassView, SurfaceVpls};
use crate::camera::CameraSegment;
use crate::gather::GatherPoint;
use crate::integrators::light_uniforms;
use crate::vpl::SurfaceVpl;
use crate::vrl::VrlMedium;
use haze_core::Rgb;
use haze_scene::Scene;
use std::sync::atomic::Ordering;

/// Every light evaluated; no tree is built. Light `i` of a group gets the numbers
/// `light_uniforms(key, i)` at a camera segment, as a tree's leaf does.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExhaustiveCut;

impl CutStrategy for ExhaustiveCut {
    type PassData = ();

    fn pass_data(&self, _scene: &Scene, _media: &[VrlMedium]) {}

    fn name<K: ClusterKind>(&self) -> &'static str {
        K::EXHAUSTIVE_NAME
    }

    fn forests<K: ClusterKind>(
        &self,
        [a, b]: [Vec<K::Light>; 2],
        surface: Vec<SurfaceVpl>,
        _media: &[VrlMedium],
        _seed: u64,
    ) -> ([Forest<K>; 2], Forest<SurfaceVpls>) {
        ([Forest::without_tree(a), Forest::without_tree(b)], Forest::without_tree(surface))
    }

    fn segment<K: ClusterKind, O: CutObserver<K>>(
        &self,
        view: &PassView<'_, K, Self>,
        cs: &CameraSegment,
        key: u64,
        _observer: &O,
    ) -> [Rgb; 2] {
        let (scene, pass, clamps) = (view.scene, view.pass, view.clamps);
        let media = &pass.media[..];
        let [a, b] = pass.forests.each_ref().map(|f| {
            if f.lights.is_empty() {
                Rgb::ZERO
            } else {
                K::contribution_sum(scene, cs, media, &f.lights, key, clamps)
            }
        });
        let surface_vpls = &pass.surface.lights;
        let n = pass.forests.iter().map(|f| f.lights.len()).sum::<usize>() + surface_vpls.len();
        view.stats.evaluations.fetch_add(n as u64, Ordering::Relaxed);
        let surface = SurfaceVpls::contribution_sum(scene, cs, media, surface_vpls, key, clamps);
        [a, b + surface]
    }

    /// The lights of both groups in order, each with the numbers of its index among them, then
    /// the surface VPLs.
    fn point<K: ClusterKind>(&self, view: &PassView<'_, K, Self>, gp: &GatherPoint, key: u64) -> Rgb {
        let (scene, pass, clamps) = (view.scene, view.pass, view.clamps);
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

    fn describe(&self, _mean: f64, _max: u64, _hit: f64) -> Option<String> {
        None
    }
}
