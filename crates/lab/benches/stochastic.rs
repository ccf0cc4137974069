//! The stochastic cut's cost per camera segment against the number of VRLs, as a table:
//!
//! ```text
//! cargo bench -p haze-lab --bench stochastic -- [SCENES...] [--spp N] [--cut-size K]
//!     [--max-vrls N] [-D NAME=VALUE] [--threads N]
//! ```
//!
//! One pass (light set and trees) of `vrl_lightcuts` is prepared for each of 10k, 100k, ...
//! `--max-vrls` VRLs; then, in rounds, the gather of `--spp` samples per pixel (cuts, descents,
//! light evaluations, and the camera rays and single scattering they share: everything but
//! light tracing and the build) is timed on each pass in turn, so every round measures all light
//! counts under the same machine load. The table gives the median over rounds and the ratio to
//! the first row per round (median, and its spread): the target "within 2x from 10k to 10M" is
//! that ratio (docs/lightcuts.md). The method and its options (`--spp`, `--cut-size`) come
//! from the engine, as `haze render` resolves them.

use anyhow::Result;
use clap::Parser;
use haze_engine::options::MethodKind;
use haze_lab::setup::{self, file_name, load_average, spread};
use haze_render::Integrator;
use haze_scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser, Debug)]
struct Args {
    /// Scenes to measure (default: the validation scenes shipped with haze).
    scenes: Vec<PathBuf>,
    /// Samples per pixel of each timed gather (default 16).
    #[arg(long)]
    spp: Option<String>,
    /// Nodes per cut (default: haze render's).
    #[arg(long)]
    cut_size: Option<String>,
    /// The largest VRL count of the table (10k, 100k, ... up to this).
    #[arg(long, default_value_t = 10_000_000)]
    max_vrls: u64,
    /// Override a scene `<default>` parameter: -D name=value.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    #[arg(long)]
    threads: Option<usize>,
    /// Passed by `cargo bench`.
    #[arg(long, hide = true)]
    bench: bool,
}

/// Interleaved rounds per table.
const ROUNDS: usize = 5;

fn main() -> Result<()> {
    let args = Args::parse();
    setup::set_threads(args.threads)?;
    let scenes = setup::scenes_or_validation(&args.scenes);
    let mut given = vec![("spp", args.spp.as_deref().unwrap_or("16"))];
    if let Some(k) = args.cut_size.as_deref() {
        given.push(("cut_size", k));
    }
    let base = setup::options(MethodKind::VrlLightcuts, &given)?;
    let (spp, cut_size) = (base.spp.unwrap_or(16), base.method.lightcuts.stochastic.settings.cut_size);
    for path in &scenes {
        let scene = setup::load_scene(path, &args.define)?;
        println!(
            "\n### {}: stochastic cut of {cut_size} nodes, {}x{} at {spp} spp sharing one pass, {ROUNDS} interleaved rounds (load average {})\n",
            file_name(path),
            scene.camera.width,
            scene.camera.height,
            load_average()
        );
        let mut prepared = Vec::new();
        let mut n = 10_000u64;
        while n <= args.max_vrls {
            let vrls = n.to_string();
            let mut given = given.clone();
            given.push(("vrls", &vrls));
            let integ = setup::vrl_lightcuts(&scene, &setup::options(MethodKind::VrlLightcuts, &given)?)?;
            let data = integ.begin_pass(&scene, 0, 0);
            prepared.push((integ, data));
            n *= 10;
        }
        // times[row][round]: gather seconds per camera segment.
        let mut times = vec![Vec::new(); prepared.len()];
        for round in 0..ROUNDS {
            for (row, (integ, data)) in prepared.iter().enumerate() {
                let before = integ.segments();
                let t = Instant::now();
                gather(&scene, integ, data, spp, round as u64);
                let secs = t.elapsed().as_secs_f64();
                times[row].push(secs / (integ.segments() - before).max(1) as f64);
            }
        }
        println!("| VRLs | trace s | build s | gather ns per segment (median; min-max) | vs first row (median; min-max over rounds) |");
        println!("|---|---|---|---|---|");
        for (row, (integ, _)) in prepared.iter().enumerate() {
            let ns: Vec<f64> = times[row].iter().map(|t| t * 1e9).collect();
            let ratios: Vec<f64> = (0..ROUNDS).map(|r| times[row][r] / times[0][r]).collect();
            let (m, lo, hi) = spread(&ns);
            let (rm, rlo, rhi) = spread(&ratios);
            println!(
                "| {:.0} | {:.2} | {:.2} | {m:.0} ({lo:.0}-{hi:.0}) | {rm:.2} ({rlo:.2}-{rhi:.2}) |",
                integ.lights_per_pass(),
                integ.trace_seconds(),
                integ.build_seconds(),
            );
        }
    }
    Ok(())
}

/// The gather of one pass: `spp` camera samples per pixel through `data`, rows in parallel as
/// `render` does (the sums are discarded).
fn gather<I: Integrator>(scene: &Scene, integ: &I, data: &I::PassData, spp: u32, round: u64) {
    use haze_core::Sampler;
    use rayon::prelude::*;
    let cam = &scene.camera;
    let rays = cam.ray_generator();
    let total: f64 = (0..cam.height)
        .into_par_iter()
        .map(|y| {
            let mut sum = 0.0f64;
            for x in 0..cam.width {
                let mut sampler = Sampler::new(round, (y * cam.width + x) as u64, 0);
                for _ in 0..spp {
                    let pos = cam.sample_film_position(x, y, &mut sampler);
                    let ray = rays.sample(pos, &mut sampler);
                    sum += integ.radiance(scene, data, ray, cam.medium, &mut sampler).total().mean() as f64;
                }
            }
            sum
        })
        .sum();
    std::hint::black_box(total);
}
