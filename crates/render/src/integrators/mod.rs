//! Integrators: estimators of the radiance arriving along a camera ray.

mod nee;
mod volpath;

pub use nee::{area_hit_weight, environment_hits, surface_nee, transmittance_to, transmittance_to_sampled};
pub use volpath::{HandOff, PathState, VolPath};

use crate::components::PathRadiance;
use haze_core::{Ray, Rgb, Sampler};
use haze_scene::{MediumId, Scene};

/// An estimator of radiance along camera rays, run in progressive passes.
pub trait Integrator: Sync {
    /// Data shared by every pixel of one pass (e.g. the virtual lights traced for it). Built from
    /// the pass's own seed so that passes are independent and reproducible.
    type PassData: Sync;

    fn name(&self) -> &str;

    fn begin_pass(&self, scene: &Scene, seed: u64, pass: u32) -> Self::PassData;

    /// True if several passes may run in one parallel sweep over the film (a "round", see
    /// `progressive::render`), each with its own `begin_pass` data held at the same time. The
    /// image is the same either way; rounds only save per-pass overhead. Integrators whose pass
    /// data is large or costly (traced light sets) keep one pass per round.
    fn passes_batchable(&self) -> bool {
        false
    }

    /// A line of statistics for the user after rendering (e.g. how many lights were made).
    fn summary(&self) -> Option<String> {
        None
    }

    /// Light the pass itself brings to pixel `pixel` (`y * width + x`), in the `surface`
    /// component: light tracing's connections to the camera (the many-light integrators'
    /// caustics seen directly). The render loop adds it to every sample of the pixel in the
    /// pass, so the pass's mean for the pixel gains it once.
    fn pixel_light(&self, _pass: &Self::PassData, _pixel: u64) -> Rgb {
        Rgb::ZERO
    }

    /// One sample of the radiance arriving at the camera along `-ray.d`, split by component.
    /// `medium` is the medium the ray starts in.
    fn radiance(
        &self,
        scene: &Scene,
        pass: &Self::PassData,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut Sampler,
    ) -> PathRadiance;
}
