//! `haze bench`: throughput of volpath on scenes, as a table.

use crate::render_cmd::{load_scene, set_threads};
use anyhow::Result;
use clap::Args;
use haze_manylight::integrators::{LightBudget, ManyLightSettings, VrlIntegrator};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, RenderSettings};
use haze_render::Integrator;
use haze_render::VolPath;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to measure (default: the shared validation scenes).
    pub scenes: Vec<PathBuf>,
    /// Samples per pixel per scene.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    #[arg(long)]
    pub threads: Option<usize>,
    /// What to measure: `volpath` (samples/s against Mitsuba 3) or `vrl` (VRL evaluations/s).
    #[arg(long, default_value = "volpath")]
    pub integrator: String,
    /// vrl: VRLs per pass.
    #[arg(long, default_value_t = 10_000)]
    pub vrls: u64,
}

/// Mitsuba 3.9.1 `llvm_ad_rgb` volpath on the validation scenes on the same 2-core machine
/// (`../shared/validation/README.md`): 128x96 pixels at 16384 spp in this many seconds.
const MITSUBA_SECONDS: &[(&str, f64)] = &[("hg-box.xml", 31.0), ("foggy-room.xml", 72.0)];

pub fn run(args: BenchArgs) -> Result<()> {
    set_threads(args.threads)?;
    let scenes = if args.scenes.is_empty() {
        let base = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/validation/scenes");
        vec![base.join("hg-box.xml"), base.join("foggy-room.xml")]
    } else {
        args.scenes.clone()
    };
    match args.integrator.as_str() {
        "volpath" => bench_volpath(&args, &scenes),
        "vrl" => bench_vrl(&args, &scenes),
        other => anyhow::bail!("haze bench measures volpath or vrl, not '{other}'"),
    }
}

/// VRL evaluations per second: one evaluation is one camera segment x one VRL, with its
/// visibility test. Light tracing time is reported separately.
fn bench_vrl(args: &BenchArgs, scenes: &[PathBuf]) -> Result<()> {
    println!(
        "| scene | pixels | spp | VRLs/pass | light tracing s | total s | evaluations | M evaluations/s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &[])?;
        let ml = ManyLightSettings {
            budget: LightBudget::Vrls(args.vrls),
            trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
        };
        let integrator = VrlIntegrator::new(&scene, ml, 0)?;
        let t0 = Instant::now();
        let _ = integrator.begin_pass(&scene, 0, 0);
        let trace_s = t0.elapsed().as_secs_f64();
        let settings = RenderSettings { spp: args.spp, spp_per_pass: 1, ..Default::default() };
        let out = render(&scene, &integrator, &settings, &AtomicBool::new(false), |_| {});
        let secs = out.elapsed.as_secs_f64();
        let evals = integrator.evaluations();
        let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        println!(
            "| {file} | {}x{} | {} | {} | {:.3} | {:.2} | {} | {:.2} |",
            scene.camera.width,
            scene.camera.height,
            out.film.samples,
            args.vrls,
            trace_s,
            secs,
            evals,
            evals as f64 / (secs - trace_s * out.passes as f64).max(1e-9) * 1e-6
        );
    }
    Ok(())
}

fn bench_volpath(args: &BenchArgs, scenes: &[PathBuf]) -> Result<()> {
    println!("| scene | pixels | spp | seconds | Msamples/s | Mitsuba 3 Msamples/s | ratio haze/Mitsuba |");
    println!("|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &[])?;
        let settings = RenderSettings { spp: args.spp, spp_per_pass: 4, ..Default::default() };
        let out = render(
            &scene,
            &VolPath::from_spec(&scene.integrator),
            &settings,
            &AtomicBool::new(false),
            |_| {},
        );
        let px = scene.camera.width as u64 * scene.camera.height as u64;
        let rate = (px * out.film.samples) as f64 / out.elapsed.as_secs_f64() * 1e-6;
        let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mi =
            MITSUBA_SECONDS.iter().find(|(n, _)| *n == file).map(|(_, s)| 128.0 * 96.0 * 16384.0 / s * 1e-6);
        println!(
            "| {file} | {}x{} | {} | {:.2} | {:.3} | {} | {} |",
            scene.camera.width,
            scene.camera.height,
            out.film.samples,
            out.elapsed.as_secs_f64(),
            rate,
            mi.map_or("-".into(), |m| format!("{m:.3}")),
            mi.map_or("-".into(), |m| format!("{:.2}", rate / m)),
        );
    }
    Ok(())
}
