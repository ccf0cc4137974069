//! `vpl`: brute-force virtual point lights, every VPL of the pass evaluated for every camera
//! segment with equiangular sampling of the camera point.

use super::{
    connect, light_uniforms, many_light_radiance, media, paths_per_pass, split_groups, ManyLightSettings,
    PassTracer,
};
use crate::lighttrace::VplRecord;
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
    tracer: PassTracer,
}

/// The VPLs of one pass in the two groups of `many_light_radiance`.
pub struct VplPass {
    groups: [Vec<Vpl>; 2],
    media: Vec<VrlMedium>,
}

impl VplIntegrator {
    pub fn new(
        scene: &Scene,
        settings: ManyLightSettings,
        seed: u64,
        clamp: Option<f32>,
    ) -> Result<Self, EmissionError> {
        let paths = paths_per_pass(scene, &settings, seed)?;
        Ok(VplIntegrator { settings, clamp, tracer: PassTracer::new(paths) })
    }
}

impl Integrator for VplIntegrator {
    type PassData = VplPass;

    fn name(&self) -> &str {
        "vpl"
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> VplPass {
        let set = self.tracer.trace(scene, seed, pass, &self.settings.trace, |s| s.vpls.len());
        let groups = split_groups(&set.vpls, |r| r.after_surface, VplRecord::to_vpl);
        VplPass { groups, media: media(scene) }
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &VplPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        many_light_radiance(scene, ray, medium, sampler, |cs, key, group| {
            let cam_medium = &pass.media[cs.medium as usize];
            let mut sum = Rgb::ZERO;
            for (i, vpl) in pass.groups[group].iter().enumerate() {
                sum += sample_vpl_contribution(
                    &cs.seg,
                    cam_medium,
                    vpl,
                    &pass.media[vpl.medium as usize].phase,
                    light_uniforms(key, i as u32).x,
                    self.clamp,
                    |y, x| connect(scene, vpl.medium, y, x),
                );
            }
            sum
        })
    }

    fn summary(&self) -> Option<String> {
        Some(format!(
            "vpl: {}{}",
            self.tracer.summary("VPLs"),
            if self.clamp.is_some() { "; geometry term clamped: the image is biased" } else { "" }
        ))
    }
}
