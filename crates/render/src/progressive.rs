//! The progressive render loop: passes of a few samples per pixel, run until a sample count or a
//! time budget is reached or the user interrupts.
//!
//! Reproducibility: the sampler of pixel `i` in pass `k` is `Sampler::for_pixel(generator, seed,
//! i, k)` (for `independent`, `Sampler::new(seed, i, k)`), its `j`-th sample of the pass is the
//! pixel's sample `k * spp_per_pass + j` of the generator's pattern, and each pixel is
//! accumulated by exactly one task in a fixed order, so the same seed and settings give a
//! bit-identical image for any thread count.
//!
//! Passes run in rounds: one parallel sweep over the film renders several consecutive passes
//! (every pixel its samples of pass `k`, then of `k + 1`, ...), so the accumulation order of each
//! pixel, and the image, are those of one pass per sweep. Integrators without per-pass data
//! (`Integrator::passes_batchable`) grow their rounds to about 75 ms of wall time, which removes
//! the per-pass cost of `spp_per_pass = 1`; the number of passes still depends only on `spp` and
//! `spp_per_pass`, and cancellation and time budgets stop at a round's end (a pass boundary).

use crate::components::{Component, PathRadiance};
use crate::film::Film;
use crate::integrators::{Integrator, VolPath};
use haze_core::{Sampler, SamplerSpec};
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
    /// The sample generator; its `sample_count` is the size of its pattern (a time-budget
    /// render, or spp beyond it, starts fresh rounds of the pattern).
    pub sampler: SamplerSpec,
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
            sampler: SamplerSpec::default(),
        }
    }
}

/// Wall time a round of passes aims at: long enough that the per-round sweep costs nothing, short
/// enough that Ctrl-C and time budgets react quickly.
const ROUND_SECONDS: f64 = 0.075;

/// Passes in the next round, from the last round's `passes` taking `took`: aimed at
/// [`ROUND_SECONDS`], growing at most fourfold per round, never past a time budget's end.
fn next_round(round: u64, passes: u64, took: Duration, limit: Option<Duration>, elapsed: Duration) -> u64 {
    let per_pass = took.as_secs_f64() / passes.max(1) as f64;
    let mut aim = ROUND_SECONDS;
    if let Some(limit) = limit {
        aim = aim.min((limit.saturating_sub(elapsed)).as_secs_f64());
    }
    let want = if per_pass > 0.0 { (aim / per_pass).floor() } else { f64::INFINITY };
    (want.min((round * 4) as f64).max(1.0)) as u64
}

/// Progress after each round of passes.
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

/// Renders `scene` with volpath as the scene's `<integrator>` element sets it, to the end of
/// `settings`' budget, with no cancel flag and no progress report (benchmarks and tests).
pub fn render_volpath(scene: &Scene, settings: &RenderSettings) -> RenderOutput {
    render(scene, &VolPath::from_spec(&scene.integrator), settings, &AtomicBool::new(false), |_| {})
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

    // Passes per round: every pass keeps its own sampler key `(seed, pixel, pass)` and each pixel
    // accumulates its samples in pass order, so how passes are grouped into rounds changes no
    // bit of the image; rounds only amortise the per-pass cost (a parallel sweep over the film,
    // its tail where one thread waits for the other) for integrators without per-pass data.
    // Rounds grow until they take about `ROUND_SECONDS` of wall time.
    let batchable = integrator.passes_batchable();
    let rays = cam.ray_generator();
    // Camera rays' closest hits come from the scene's camera grid: built here on the pool,
    // rather than on one thread by the first camera ray.
    scene.prepare_camera_grid();
    let mut round = 1u64;
    loop {
        let done = film.samples;
        let elapsed = start.elapsed();
        let budget_left = settings.time_limit.is_none_or(|t| elapsed < t);
        let target_left = settings.time_limit.is_some() && settings.spp == 0 || done < settings.spp as u64;
        if !budget_left || !target_left {
            break;
        }
        if cancel.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        // The passes of this round: their sample counts depend only on `spp`, `spp_per_pass` and
        // the pass index, never on timing.
        let mut counts = Vec::new();
        let mut planned = done;
        while (counts.len() as u64) < round {
            if settings.spp > 0 && planned >= settings.spp as u64 {
                break;
            }
            let n = if settings.spp > 0 {
                (settings.spp as u64 - planned).min(spp_per_pass as u64)
            } else {
                spp_per_pass as u64
            };
            counts.push(n);
            planned += n;
        }
        let first = settings.first_pass + passes;
        let data: Vec<I::PassData> = (0..counts.len() as u32)
            .map(|k| integrator.begin_pass(scene, settings.seed, first + k))
            .collect();
        let t_round = Instant::now();
        let cam_boundary = scene.camera_boundary();
        film.data_mut().par_chunks_mut(stride * w).enumerate().for_each(|(y, row)| {
            for (x, slot) in row.chunks_mut(stride).enumerate() {
                let pixel = (y * w + x) as u64;
                for (k, (&n_this, data)) in counts.iter().zip(&data).enumerate() {
                    let pass = (first + k as u32) as u64;
                    let mut sampler = Sampler::for_pixel(&settings.sampler, settings.seed, pixel, pass);
                    for j in 0..n_this {
                        // Every pass but the last holds spp_per_pass samples.
                        sampler.start_sample(pass * spp_per_pass as u64 + j);
                        // The reconstruction filter by importance sampling (see `PixelFilter`).
                        let pos = cam.sample_film_position(x as u32, y as u32, &mut sampler);
                        let ray = rays.sample(pos, &mut sampler);
                        let medium = cam_boundary.medium_towards(ray.d, cam.medium);
                        let mut r = integrator.radiance(scene, data, ray, medium, &mut sampler);
                        r.add(Component::Surface, integrator.pixel_light(data, pixel));
                        if !r.total().is_finite() {
                            invalid.fetch_add(1, Ordering::Relaxed);
                            r = PathRadiance::default();
                        }
                        Film::add_sample(slot, &r);
                    }
                }
            }
        });
        debug_assert_eq!(h * w * stride, film.data_mut().len());
        film.samples = planned;
        passes += counts.len() as u32;
        on_pass(&PassReport { passes, spp_done: film.samples, elapsed: start.elapsed() });
        if batchable {
            round = next_round(
                round,
                counts.len() as u64,
                t_round.elapsed(),
                settings.time_limit,
                start.elapsed(),
            );
        }
    }

    RenderOutput {
        film,
        passes,
        elapsed: start.elapsed(),
        invalid_samples: invalid.into_inner(),
        interrupted,
    }
}
