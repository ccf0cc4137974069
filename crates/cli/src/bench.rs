//! `haze bench`: throughput of the shipped methods on scenes, as a table. The method and its
//! options go through the engine (`haze_engine::options`, `Method`) as `haze render`'s do; the
//! research tables (light-tree builders, cut sizes, the stochastic cut's scaling) are the
//! benchmarks of `crates/lab`.

use crate::render_cmd::{load_scene, set_threads};
use anyhow::Result;
use clap::Args;
use haze_engine::options::{self, MethodKind, Options, Spelling};
use haze_engine::Method;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to measure (default: the validation scenes shipped with haze,
    /// `tests/data/validation/scenes`, looked for in the current directory and beside the
    /// executable).
    pub scenes: Vec<PathBuf>,
    /// Samples per pixel per scene (default 64).
    #[arg(long)]
    pub spp: Option<String>,
    #[arg(long)]
    pub threads: Option<usize>,
    /// What to measure: `volpath` (samples/s against Mitsuba 3) or `vrl` (VRL evaluations/s).
    #[arg(long, default_value = "volpath")]
    pub integrator: String,
    /// vrl: VRLs per pass (default: haze render's).
    #[arg(long)]
    pub vrls: Option<String>,
    /// Override a scene `<default>` parameter: -D name=value.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
}

/// Mitsuba 3.9.1 `llvm_ad_rgb` volpath on the validation scenes on the same 2-core machine
/// (`tests/data/validation/README.md`): 128x96 pixels at 16384 spp in this many seconds.
const MITSUBA_SECONDS: &[(&str, f64)] = &[("hg-box.xml", 31.0), ("foggy-room.xml", 72.0)];

pub fn run(args: BenchArgs) -> Result<()> {
    set_threads(args.threads)?;
    let scenes = if args.scenes.is_empty() {
        vec![
            shipped("tests/data/validation/scenes/hg-box.xml")?,
            shipped("tests/data/validation/scenes/foggy-room.xml")?,
        ]
    } else {
        args.scenes.clone()
    };
    let kind = match args.integrator.as_str() {
        "volpath" => MethodKind::VolPath,
        "vrl" => MethodKind::Vrl,
        other => anyhow::bail!(
            "haze bench measures volpath or vrl, not '{other}' (light trees and cuts: cargo bench -p haze-lab)"
        ),
    };
    let mut given = vec![("spp", args.spp.as_deref().unwrap_or("64"))];
    if let Some(v) = args.vrls.as_deref() {
        given.push(("vrls", v));
    }
    let options = options::resolve(kind, &given, Spelling::Flag)?;
    match kind {
        MethodKind::Vrl => bench_vrl(&args, &options, &scenes),
        _ => bench_volpath(&args, &options, &scenes),
    }
}

/// A file shipped with haze (`rel` is its path in the repository), found in the current
/// directory, beside the executable, or in the directories above it (`target/release/haze` in
/// a clone), or in `share/haze` under one of those (an installed binary); never a path compiled
/// in from the source tree.
fn shipped(rel: &str) -> Result<PathBuf> {
    let mut roots = vec![PathBuf::from(".")];
    if let Ok(exe) = std::env::current_exe() {
        for dir in exe.ancestors().skip(1).take(4) {
            roots.push(dir.to_path_buf());
            roots.push(dir.join("share/haze"));
        }
    }
    if let Some(found) = roots.iter().map(|r| r.join(rel)).find(|p| p.is_file()) {
        return Ok(found);
    }
    let looked: Vec<String> = roots.iter().map(|r| r.display().to_string()).collect();
    anyhow::bail!(
        "haze bench: the default scene {rel} was not found (looked in {}); run it from a clone of \
         the haze repository or give the scene files as arguments",
        looked.join(", ")
    )
}

fn file_name(path: &std::path::Path) -> String {
    path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// VRL evaluations per second: one evaluation is one camera segment x one VRL, with its
/// visibility test. Light tracing, timed on a pass of its own, is taken out of the rate.
fn bench_vrl(args: &BenchArgs, options: &Options, scenes: &[PathBuf]) -> Result<()> {
    println!(
        "| scene | pixels | spp | VRLs/pass | light tracing s | total s | evaluations | M evaluations/s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &args.define)?;
        let method = Method::build(&scene, MethodKind::Vrl, &options.method, options.seed)?;
        let (paths, _) = method.vrl_evaluations().expect("a vrl method");
        let t0 = Instant::now();
        haze_engine::lights::trace_lights(&scene, paths, options.seed, 0)?;
        let trace_s = t0.elapsed().as_secs_f64();
        let settings = options.render_settings(MethodKind::Vrl, &scene);
        let out = method.render(&scene, &settings, &AtomicBool::new(false), |_| {});
        let secs = out.elapsed.as_secs_f64();
        let (_, evals) = method.vrl_evaluations().expect("a vrl method");
        println!(
            "| {} | {}x{} | {} | {} | {:.3} | {:.2} | {} | {:.2} |",
            file_name(path),
            scene.camera.width,
            scene.camera.height,
            out.film.samples,
            options::find("vrls").and_then(|o| o.value_in(options)).unwrap_or_default(),
            trace_s,
            secs,
            evals,
            evals as f64 / (secs - trace_s * out.passes as f64).max(1e-9) * 1e-6
        );
    }
    Ok(())
}

/// volpath's samples per second, against Mitsuba 3's on the validation scenes.
fn bench_volpath(args: &BenchArgs, options: &Options, scenes: &[PathBuf]) -> Result<()> {
    println!("| scene | pixels | spp | seconds | Msamples/s | Mitsuba 3 Msamples/s | ratio haze/Mitsuba |");
    println!("|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &args.define)?;
        let method = Method::build(&scene, MethodKind::VolPath, &options.method, options.seed)?;
        let settings = options.render_settings(MethodKind::VolPath, &scene);
        let out = method.render(&scene, &settings, &AtomicBool::new(false), |_| {});
        let px = scene.camera.width as u64 * scene.camera.height as u64;
        let rate = (px * out.film.samples) as f64 / out.elapsed.as_secs_f64() * 1e-6;
        let file = file_name(path);
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
