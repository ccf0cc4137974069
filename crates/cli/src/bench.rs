//! `haze bench`: throughput of volpath on scenes, as a table.

use crate::render_cmd::{load_scene, set_threads};
use anyhow::Result;
use clap::Args;
use haze_render::progressive::{render, RenderSettings};
use haze_render::VolPath;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to measure (default: the shared validation scenes).
    pub scenes: Vec<PathBuf>,
    /// Samples per pixel per scene.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    #[arg(long)]
    pub threads: Option<usize>,
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
    println!("| scene | pixels | spp | seconds | Msamples/s | Mitsuba 3 Msamples/s | ratio haze/Mitsuba |");
    println!("|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(&path, &[])?;
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
