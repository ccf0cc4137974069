//! The cut-size image (`haze render --cut-image`): [`CutSizeProbe`] renders, per pixel, what the
//! tree cuts report through [`tally`] while it runs the wrapped integrator.

use super::{ClusterKind, CutStrategy, LightcutPass, LightcutsIntegrator};
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::{MediumId, Scene};
use std::cell::Cell;

thread_local! {
    /// What the cuts reported, summed, and camera segments counted on this thread since
    /// [`CutSizeProbe`] last reset them: the cut size (bound cut) or the largest cut node's
    /// share of the cut's importance (stochastic cut).
    static CUT_TALLY: Cell<(f64, u64)> = const { Cell::new((0.0, 0)) };
    /// Set while [`CutSizeProbe`] renders: the stochastic cut then also computes its share.
    static PROBING: Cell<bool> = const { Cell::new(false) };
}

/// Whether a [`CutSizeProbe`] is rendering on this thread (a cut then reports with [`tally`]
/// what costs extra to compute).
pub(super) fn probing() -> bool {
    PROBING.get()
}

/// One camera segment's cut reports `value`.
pub(super) fn tally(value: f64) {
    CUT_TALLY.with(|t| {
        let (v, n) = t.get();
        t.set((v + value, n + 1));
    });
}

/// Renders, instead of a camera path's radiance, the mean over its segments of the cut size
/// (bound cut) or of the largest cut node's share of the cut's importance (stochastic cut: 1
/// where one cluster dominates, `1/k` where the importance spreads evenly), in every channel of
/// the `emitted` component (0 where the path meets no medium). Runs the wrapped
/// integrator unchanged, so the cuts are those of the image with the same seed and pass.
pub struct CutSizeProbe<'a, K: ClusterKind, S: CutStrategy>(pub &'a LightcutsIntegrator<K, S>);

impl<K: ClusterKind, S: CutStrategy> Integrator for CutSizeProbe<'_, K, S> {
    type PassData = LightcutPass<K, S>;

    fn name(&self) -> &str {
        self.0.name()
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> LightcutPass<K, S> {
        self.0.begin_pass(scene, seed, pass)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &LightcutPass<K, S>,
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
