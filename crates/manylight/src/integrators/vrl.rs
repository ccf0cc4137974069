//! `vrl`: brute-force virtual ray lights, every VRL and surface VPL of the pass evaluated for
//! every gathering segment (the joint importance sampling of Novak et al. 2012 for VRLs) and
//! every gathering surface point of the camera path (`docs/theory.md` §2.1).

use super::{
    caustic_tracer, connect, light_uniforms, media, paths_per_pass, split_groups, surface_vpls,
    surface_vpls_to_point, surface_vpls_to_segment, ManyLightSettings, PassTracer,
};
use crate::camera::CameraSegment;
use crate::gather::{whole_path_radiance, Gather, GatherPoint, PathTracedMedia};
use crate::lighttrace::VrlRecord;
use crate::splat::{CameraSplats, CausticTracer};
use crate::vpl::SurfaceVpl;
use crate::vrl::estimator::{contributes, point_pair_estimate, sample_point_pair, PointPair};
use crate::vrl::surface::sample_vrl_to_point;
use crate::vrl::{Vrl, VrlMedium};
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};
use std::sync::atomic::{AtomicU64, Ordering};

pub struct VrlIntegrator {
    settings: ManyLightSettings,
    /// `Some(c)`: clamp the `1/d^2` of surface-VPL connections at `c` (biased).
    pub clamp: Option<f32>,
    controls: TestControls,
    caustics: Option<CausticTracer>,
    tracer: PassTracer,
    /// Camera segment x VRL evaluations so far (for `haze bench`).
    evaluations: AtomicU64,
}

/// Changes of `vrl`'s estimate that only tests make (`crates/manylight/tests/integrators.rs`):
/// the negative controls, which must fail, and the unsplit walk the split is compared with.
/// `TestControls::default()` is the estimator, what [`VrlIntegrator::new`] renders with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestControls {
    /// Scale of the virtual lights' light at gathering surface points (VRL -> surface point and
    /// surface VPL -> surface point): 1; off (0) must fail the whole-image z-test.
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

/// The VRLs of one pass in the two groups of `gather::Gather::segment` (medium-only, after a
/// surface bounce), so that the hot loop does not branch per light.
pub struct VrlPass {
    groups: [Vec<Vrl>; 2],
    surface_vpls: Vec<SurfaceVpl>,
    media: Vec<VrlMedium>,
    /// The scene has a heterogeneous medium: every light goes through `crate::hetero`.
    hetero: bool,
    splats: CameraSplats,
}

impl VrlIntegrator {
    /// Fails if an emitter cannot start light paths (`constant`).
    pub fn new(scene: &Scene, settings: ManyLightSettings, seed: u64) -> Result<Self, EmissionError> {
        Self::with_test_controls(scene, settings, seed, TestControls::default())
    }

    /// [`VrlIntegrator::new`] with the estimate changed as `controls` says (tests only).
    pub fn with_test_controls(
        scene: &Scene,
        settings: ManyLightSettings,
        seed: u64,
        controls: TestControls,
    ) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &settings, seed)?;
        let caustics = caustic_tracer(scene, &settings);
        Ok(VrlIntegrator {
            settings,
            clamp: None,
            controls,
            caustics,
            tracer: PassTracer::new(paths),
            evaluations: AtomicU64::new(0),
        })
    }

    pub fn paths_per_pass(&self) -> u64 {
        self.tracer.paths()
    }

    /// Camera segment x VRL evaluations made so far (one evaluation includes its visibility test).
    pub fn evaluations(&self) -> u64 {
        self.evaluations.load(Ordering::Relaxed)
    }
}

impl Integrator for VrlIntegrator {
    type PassData = VrlPass;

    fn name(&self) -> &str {
        "vrl"
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> VrlPass {
        let set = self
            .tracer
            .trace(scene, seed, pass, &self.settings.trace, |s| s.vrls.len() + s.surface_vpls.len());
        let groups = split_groups(&set.vrls, |r| r.after_surface, VrlRecord::to_vrl);
        let splats = self.caustics.as_ref().map_or_else(CameraSplats::default, |c| {
            c.splats(scene, seed, pass).scaled(self.controls.caustic_scale)
        });
        VrlPass {
            groups,
            surface_vpls: surface_vpls(&set),
            media: media(scene),
            hetero: crate::hetero::any(scene),
            splats,
        }
    }

    fn pixel_light(&self, pass: &VrlPass, pixel: u64) -> Rgb {
        pass.splats.get(pixel)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &VrlPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        whole_path_radiance(scene, ray, medium, sampler, &VrlGather { integrator: self, scene, pass })
    }

    fn summary(&self) -> Option<String> {
        Some(format!("vrl: {}", self.tracer.summary("VRLs and surface VPLs")))
    }
}

/// The VRL integrator's side of the camera walk.
struct VrlGather<'a> {
    integrator: &'a VrlIntegrator,
    scene: &'a Scene,
    pass: &'a VrlPass,
}

impl Gather for VrlGather<'_> {
    fn segment(&self, cs: &CameraSegment, key: u64) -> [Rgb; 2] {
        let (scene, pass) = (self.scene, self.pass);
        let cam_medium = &pass.media[cs.medium as usize];
        let n = pass.groups[0].len() + pass.groups[1].len() + pass.surface_vpls.len();
        self.integrator.evaluations.fetch_add(n as u64, Ordering::Relaxed);
        let sums = [0, 1].map(|g| {
            if pass.hetero {
                let mut sum = Rgb::ZERO;
                for (i, vrl) in pass.groups[g].iter().enumerate() {
                    if !crate::depth::connects(scene, vrl.events, cs.events) {
                        continue;
                    }
                    sum += crate::hetero::vrl_to_segment(
                        scene,
                        cs,
                        &pass.media,
                        vrl,
                        light_uniforms(key, i as u32),
                    );
                }
                sum
            } else {
                sum_contributions(scene, cs, cam_medium, &pass.groups[g], &pass.media, key)
            }
        });
        let surface =
            surface_vpls_to_segment(scene, &pass.surface_vpls, cs, cam_medium, key, self.integrator.clamp);
        [sums[0], sums[1] + surface]
    }

    fn splats_caustics(&self) -> bool {
        self.integrator.caustics.is_some()
    }

    fn split(&self) -> Option<f32> {
        self.integrator.controls.split
    }

    fn compensated_clamp(&self) -> Option<f32> {
        self.integrator.settings.compensated_clamp
    }

    fn path_traced_media(&self) -> PathTracedMedia {
        self.integrator.settings.path_traced_media
    }

    fn point(&self, gp: &GatherPoint, key: u64) -> Rgb {
        let (scene, pass) = (self.scene, self.pass);
        let mut sum = Rgb::ZERO;
        let lights = pass.groups.iter().flatten().enumerate();
        if pass.hetero {
            for (i, vrl) in lights.filter(|(_, v)| crate::depth::connects(scene, v.events, gp.events)) {
                let u = light_uniforms(key, i as u32).x;
                sum += crate::hetero::vrl_to_point(scene, gp.p, |d| gp.reflectance(d), &pass.media, vrl, u);
            }
        } else {
            for (i, vrl) in lights.filter(|(_, v)| crate::depth::connects(scene, v.events, gp.events)) {
                sum += sample_vrl_to_point(
                    gp.p,
                    |d| gp.reflectance(d),
                    vrl,
                    &pass.media[vrl.medium as usize],
                    light_uniforms(key, i as u32).x,
                    |y, x| connect(scene, vrl.medium, y, x),
                );
            }
        }
        (sum + surface_vpls_to_point(
            scene,
            &pass.surface_vpls,
            gp,
            self.integrator.clamp.or(self.compensated_clamp()),
        )) * self.integrator.controls.gather_point_scale
    }
}

/// VRLs sampled back to back before their contributions are evaluated (see
/// [`sample_point_pair`]).
const CHUNK: usize = 16;

/// `sum_i sample_vrl_contribution(cam, .., lights[i], .., light_uniforms(key, i), ..)`, the same
/// values added in the same order, computed a chunk of lights at a time: first the points of
/// every light of the chunk, then their contributions.
fn sum_contributions(
    scene: &Scene,
    cs: &CameraSegment,
    cam_medium: &VrlMedium,
    lights: &[Vrl],
    media: &[VrlMedium],
    key: u64,
) -> Rgb {
    let cam = &cs.seg;
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
                let vrl_medium = &media[vrl.medium as usize];
                sum += point_pair_estimate(cam, cam_medium, vrl, vrl_medium, pair, |y, x| {
                    connect(scene, vrl.medium, y, x)
                });
            }
        }
    }
    sum
}
