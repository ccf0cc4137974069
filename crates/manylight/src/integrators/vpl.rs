//! `vpl`: brute-force virtual point lights, every medium and surface VPL of the pass evaluated
//! for every gathering segment (equiangular sampling of the camera point) and every gathering
//! surface point of the camera path (`docs/theory.md` §2.1).

use super::{
    caustic_tracer, connect, light_uniforms, media, medium_vpl_to_point, paths_per_pass, split_groups,
    surface_vpls, surface_vpls_to_point, surface_vpls_to_segment, ManyLightSettings, PassTracer,
};
use crate::camera::CameraSegment;
use crate::gather::{whole_path_radiance, Gather, GatherPoint, PathTracedMedia};
use crate::lighttrace::VplRecord;
use crate::splat::{CameraSplats, CausticTracer};
use crate::vpl::SurfaceVpl;
use crate::vpl::{sample_vpl_contribution, Vpl};
use crate::vrl::VrlMedium;
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};

pub struct VplIntegrator {
    settings: ManyLightSettings,
    /// `Some(c)`: clamp the VPL geometry term `1/w^2` at `c` (biased; see the estimator).
    pub clamp: Option<f32>,
    /// `Some(c)`: clamp the `1/d^2` of connections to gathering points and of surface VPLs at
    /// `c` (biased).
    pub surface_clamp: Option<f32>,
    tracer: PassTracer,
    caustics: Option<CausticTracer>,
}

/// The VPLs of one pass in the two groups of `gather::Gather::segment`.
pub struct VplPass {
    groups: [Vec<Vpl>; 2],
    surface_vpls: Vec<SurfaceVpl>,
    media: Vec<VrlMedium>,
    /// The scene has a heterogeneous medium: every light goes through `crate::hetero`.
    hetero: bool,
    splats: CameraSplats,
}

impl VplIntegrator {
    pub fn new(
        scene: &Scene,
        settings: ManyLightSettings,
        seed: u64,
        clamp: Option<f32>,
    ) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &settings, seed)?;
        let caustics = caustic_tracer(scene, &settings);
        Ok(VplIntegrator { settings, clamp, surface_clamp: None, tracer: PassTracer::new(paths), caustics })
    }
}

impl Integrator for VplIntegrator {
    type PassData = VplPass;

    fn name(&self) -> &str {
        "vpl"
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> VplPass {
        let set = self
            .tracer
            .trace(scene, seed, pass, &self.settings.trace, |s| s.vpls.len() + s.surface_vpls.len());
        let groups = split_groups(&set.vpls, |r| r.after_surface, VplRecord::to_vpl);
        let splats =
            self.caustics.as_ref().map_or_else(CameraSplats::default, |c| c.splats(scene, seed, pass));
        VplPass {
            groups,
            surface_vpls: surface_vpls(&set),
            media: media(scene),
            hetero: crate::hetero::any(scene),
            splats,
        }
    }

    fn pixel_light(&self, pass: &VplPass, pixel: u64) -> Rgb {
        pass.splats.get(pixel)
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &VplPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        whole_path_radiance(scene, ray, medium, sampler, &VplGather { integrator: self, scene, pass })
    }

    fn summary(&self) -> Option<String> {
        Some(format!(
            "vpl: {}{}",
            self.tracer.summary("VPLs and surface VPLs"),
            if self.clamp.is_some() { "; geometry term clamped: the image is biased" } else { "" }
        ))
    }
}

/// The VPL integrator's side of the camera walk.
struct VplGather<'a> {
    integrator: &'a VplIntegrator,
    scene: &'a Scene,
    pass: &'a VplPass,
}

impl Gather for VplGather<'_> {
    fn segment(&self, cs: &CameraSegment, key: u64) -> [Rgb; 2] {
        let (scene, pass) = (self.scene, self.pass);
        let cam_medium = &pass.media[cs.medium as usize];
        let sums = [0, 1].map(|g| {
            let mut sum = Rgb::ZERO;
            if pass.hetero {
                for (i, vpl) in pass.groups[g].iter().enumerate() {
                    if !crate::depth::connects(scene, vpl.events, cs.events) {
                        continue;
                    }
                    let u = light_uniforms(key, i as u32);
                    sum +=
                        crate::hetero::vpl_to_segment(scene, cs, &pass.media, vpl, u, self.integrator.clamp);
                }
                return sum;
            }
            for (i, vpl) in pass.groups[g].iter().enumerate() {
                if !crate::depth::connects(scene, vpl.events, cs.events) {
                    continue;
                }
                sum += sample_vpl_contribution(
                    &cs.seg,
                    cam_medium,
                    vpl,
                    &pass.media[vpl.medium as usize].phase,
                    light_uniforms(key, i as u32).x,
                    self.integrator.clamp,
                    |y, x| connect(scene, vpl.medium, y, x),
                );
            }
            sum
        });
        let surface = surface_vpls_to_segment(
            scene,
            &pass.surface_vpls,
            cs,
            cam_medium,
            key,
            self.integrator.surface_clamp,
        );
        [sums[0], sums[1] + surface]
    }

    fn splats_caustics(&self) -> bool {
        self.integrator.caustics.is_some()
    }

    fn compensated_clamp(&self) -> Option<f32> {
        self.integrator.settings.compensated_clamp
    }

    fn path_traced_media(&self) -> PathTracedMedia {
        self.integrator.settings.path_traced_media
    }

    fn point(&self, gp: &GatherPoint, _key: u64) -> Rgb {
        let (scene, pass) = (self.scene, self.pass);
        let clamp = self.integrator.surface_clamp;
        let mut sum =
            surface_vpls_to_point(scene, &pass.surface_vpls, gp, clamp.or(self.compensated_clamp()));
        for vpl in pass.groups.iter().flatten() {
            sum += medium_vpl_to_point(scene, vpl, gp, &pass.media, clamp);
        }
        sum
    }
}
