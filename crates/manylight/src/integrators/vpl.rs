//! `vpl`: brute-force virtual point lights, every VPL of the pass evaluated for every camera
//! segment with equiangular sampling of the camera point.

use super::{connect, light_uniforms, media, paths_per_pass, ManyLightSettings, SEGMENTS};
use crate::camera::trace_camera_ray;
use crate::lighttrace::trace_light_paths;
use crate::single::single_scattering;
use crate::vpl::{sample_vpl_contribution, Vpl};
use crate::vrl::VrlMedium;
use haze_core::{Ray, Rgb, Sampler};
use haze_render::{Component, Integrator, PathRadiance};
use haze_scene::lights::EmissionError;
use haze_scene::{MediumId, Scene};
use std::sync::atomic::{AtomicU64, Ordering};

pub struct VplIntegrator {
    settings: ManyLightSettings,
    paths: u64,
    /// `Some(c)`: clamp the VPL geometry term `1/w^2` at `c` (biased; see the estimator).
    pub clamp: Option<f32>,
    made: AtomicU64,
    passes: AtomicU64,
}

pub struct VplPass {
    medium_only: Vec<Vpl>,
    after_surface: Vec<Vpl>,
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
        Ok(VplIntegrator { settings, paths, clamp, made: AtomicU64::new(0), passes: AtomicU64::new(0) })
    }
}

impl Integrator for VplIntegrator {
    type PassData = VplPass;

    fn name(&self) -> &str {
        "vpl"
    }

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> VplPass {
        let set = trace_light_paths(scene, self.paths, seed, pass, &self.settings.trace)
            .expect("emitters were checked when the integrator was made");
        self.made.fetch_add(set.vpls.len() as u64, Ordering::Relaxed);
        self.passes.fetch_add(1, Ordering::Relaxed);
        let (mut medium_only, mut after_surface) = (Vec::new(), Vec::new());
        for r in &set.vpls {
            let v = Vpl { p: r.p, d_in: r.d_in, flux: r.flux, medium: r.medium };
            if r.after_surface {
                after_surface.push(v);
            } else {
                medium_only.push(v);
            }
        }
        VplPass { medium_only, after_surface, media: media(scene) }
    }

    fn radiance(
        &self,
        scene: &Scene,
        pass: &VplPass,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance {
        SEGMENTS.with_borrow_mut(|segments| {
            let mut out = PathRadiance::default();
            let path = trace_camera_ray(scene, ray, medium, segments);
            out.add(Component::Emitted, path.emitted);
            for cs in segments.iter() {
                out.add(Component::Single, single_scattering(scene, cs, sampler));
                // Per-light random numbers from one key per segment (see `light_uniforms`).
                let key = ((sampler.next_u32() as u64) << 32) | sampler.next_u32() as u64;
                let cam_medium = &pass.media[cs.medium as usize];
                for (lights, comp) in
                    [(&pass.medium_only, Component::Multiple), (&pass.after_surface, Component::Surface)]
                {
                    let mut sum = Rgb::ZERO;
                    for (i, vpl) in lights.iter().enumerate() {
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
                    out.add(comp, cs.tr_before * sum);
                }
            }
            out
        })
    }

    fn summary(&self) -> Option<String> {
        let passes = self.passes.load(Ordering::Relaxed).max(1);
        Some(format!(
            "vpl: {} light paths and {:.0} VPLs per pass on average ({} passes){}",
            self.paths,
            self.made.load(Ordering::Relaxed) as f64 / passes as f64,
            passes,
            if self.clamp.is_some() { "; geometry term clamped: the image is biased" } else { "" }
        ))
    }
}
