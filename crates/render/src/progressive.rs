//! The progressive render loop: passes of a few samples per pixel, run until a sample count or a
//! time budget is reached or the user interrupts.
//!
//! Reproducibility: the sampler of pixel `i` in pass `k` is `Sampler::new(seed, i, k)`, and each
//! pixel is accumulated by exactly one task in a fixed order, so the same seed and settings give
//! a bit-identical image for any thread count.

use crate::components::PathRadiance;
use crate::film::Film;
use crate::integrators::Integrator;
use haze_core::Sampler;
use haze_scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Samples per pixel to reach (the loop stops earlier if `time_limit` runs out).
    pub spp: u32,
    /// Wall-clock budget; passes stop once it is spent (a pass always completes).
    pub time_limit: Option<Duration>,
    pub seed: u64,
    /// Samples per pixel in one pass. Changing it changes the random streams (not the expected image).
    pub spp_per_pass: u32,
    /// Keep the component split (emitted, single, multiple, surface).
    pub components: bool,
    /// Index of the first pass. Passes are independent and keyed by their index, so renders of
    /// disjoint pass ranges (other processes, other machines) merge exactly with `Film::merge`.
    pub first_pass: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            spp: 16,
            time_limit: None,
            seed: 0,
            spp_per_pass: 1,
            components: false,
            first_pass: 0,
        }
    }
}

/// Progress after each pass.
#[derive(Clone, Debug)]
pub struct PassReport {
    pub passes: u32,
    pub spp_done: u64,
    pub elapsed: Duration,
}

pub struct RenderOutput {
    pub film: Film,
    pub passes: u32,
    pub elapsed: Duration,
    /// Samples that came out NaN or infinite and were replaced by zero (should stay 0; reported).
    pub invalid_samples: u64,
    /// True if the cancel flag stopped the render before its target.
    pub interrupted: bool,
}

/// Renders `scene` with `integrator`. `cancel` is polled between passes (Ctrl-C sets it);
/// `on_pass` is called after every pass.
pub fn render<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    settings: &RenderSettings,
    cancel: &AtomicBool,
    mut on_pass: impl FnMut(&PassReport),
) -> RenderOutput {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut film = Film::new(cam.width, cam.height, settings.components);
    let stride = film.stride();
    let invalid = AtomicU64::new(0);
    let start = Instant::now();
    let spp_per_pass = settings.spp_per_pass.max(1);
    let mut passes = 0u32;
    let mut interrupted = false;

    loop {
        let done = film.samples;
        let budget_left = settings.time_limit.is_none_or(|t| start.elapsed() < t);
        let target_left = settings.time_limit.is_some() && settings.spp == 0 || done < settings.spp as u64;
        if !budget_left || !target_left {
            break;
        }
        if cancel.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        let n_this = if settings.spp > 0 {
            (settings.spp as u64 - done).min(spp_per_pass as u64)
        } else {
            spp_per_pass as u64
        };
        let pass = settings.first_pass + passes;
        let data = integrator.begin_pass(scene, settings.seed, pass);
        film.data_mut().par_chunks_mut(stride * w).enumerate().for_each(|(y, row)| {
            for (x, slot) in row.chunks_mut(stride).enumerate() {
                let pixel = (y * w + x) as u64;
                let mut sampler = Sampler::new(settings.seed, pixel, pass as u64);
                for _ in 0..n_this {
                    // The reconstruction filter by importance sampling (see `PixelFilter`).
                    let pos = cam.sample_film_position(x as u32, y as u32, &mut sampler);
                    let ray = cam.generate_ray(pos);
                    let mut r = integrator.radiance(scene, &data, ray, cam.medium, &mut sampler);
                    if !r.total().is_finite() {
                        invalid.fetch_add(1, Ordering::Relaxed);
                        r = PathRadiance::default();
                    }
                    Film::add_sample(slot, &r);
                }
            }
        });
        debug_assert_eq!(h * w * stride, film.data_mut().len());
        film.samples += n_this;
        passes += 1;
        on_pass(&PassReport { passes, spp_done: film.samples, elapsed: start.elapsed() });
    }

    RenderOutput {
        film,
        passes,
        elapsed: start.elapsed(),
        invalid_samples: invalid.into_inner(),
        interrupted,
    }
}
