//! `haze render`.

use anyhow::{bail, Context, Result};
use clap::Args;
use haze_engine::methods::{Method, MethodOptions};
use haze_manylight::integrators::{Builder, LightBudget, LightcutSettings};
use haze_manylight::tree::bound::BoundKind;
use haze_manylight::tree::cut::CutSettings;
use haze_render::image_io::RgbImage;
use haze_render::progressive::{PassReport, RenderOutput, RenderSettings};
use haze_render::Component;
use haze_scene::{LoadOptions, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (Mitsuba 3 XML).
    pub scene: PathBuf,
    /// Output image: `.exr` (linear RGB, with a PNG preview written next to it) or `.png` (the
    /// preview only). Other extensions, and any file the scene reads, are refused.
    #[arg(short, long, default_value = "haze.exr")]
    pub output: PathBuf,
    /// Samples per pixel (default: the scene's sampler `sample_count`).
    #[arg(long, conflicts_with = "time")]
    pub spp: Option<u32>,
    /// Render for this many seconds instead of a fixed sample count.
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Seed of every random choice; the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Integrator, overriding the scene's `<integrator>`: volpath (volpathmis), vrl, vpl.
    #[arg(long)]
    pub integrator: Option<String>,
    /// Many-light integrators: trace about this many VRLs per pass (the light-path count is
    /// fixed from a pilot run). Default: 10000.
    #[arg(long, conflicts_with = "light_paths")]
    pub vrls: Option<u64>,
    /// Many-light integrators: trace exactly this many light paths per pass.
    #[arg(long)]
    pub light_paths: Option<u64>,
    /// vpl: clamp the geometry term 1/w^2 at this value (biased; off by default).
    #[arg(long)]
    pub vpl_clamp: Option<f32>,
    /// Lightcuts: refine a cut until every node's bound is at most epsilon times the cut's
    /// estimate (largest RGB channel of each).
    #[arg(long, default_value_t = 0.02)]
    pub epsilon: f32,
    /// Lightcuts: most nodes in a cut.
    #[arg(long, default_value_t = 1000)]
    pub max_cut: u32,
    /// Lightcuts: cluster bound, `paper` (Vibert et al. 2019), `conservative`, or `tight`
    /// (conservative, with the VRL integral bounded through the VRLs' directions: log(1/h)
    /// instead of 1/h near the camera line; docs/lightcuts.md).
    #[arg(long, default_value = "paper")]
    pub bound: String,
    /// Lightcuts: tree builder, `agglomerative` (the paper's 3-step parallel build) or `median`.
    #[arg(long, default_value = "agglomerative")]
    pub builder: String,
    /// Lightcuts: also write a PNG heat map of the mean cut size per pixel (one extra 1-spp
    /// pass with the same seed). Colour scale linear from 0 (black) to --max-cut (pale yellow,
    /// "inferno" colours); a legend strip below the map shows it, ticks at every quarter.
    #[arg(long, value_name = "PNG")]
    pub cut_image: Option<PathBuf>,
    /// Override a scene `<default>` parameter: -D name=value (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Also write OUT_emitted.exr, OUT_single.exr, OUT_multiple.exr, OUT_surface.exr (they sum to OUT.exr).
    #[arg(long)]
    pub components: bool,
    /// Write the per-pixel variance of one sample to this EXR.
    #[arg(long)]
    pub variance_out: Option<PathBuf>,
    /// Samples per pixel in each progressive pass.
    #[arg(long, default_value_t = 1)]
    pub spp_per_pass: u32,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn parse_defines(define: &[String]) -> Result<Vec<(String, String)>> {
    define
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
            _ => bail!("-D expects NAME=VALUE, got '{d}'"),
        })
        .collect()
}

pub fn load_scene(path: &Path, define: &[String]) -> Result<Scene> {
    let options = LoadOptions { defines: parse_defines(define)? };
    Ok(haze_scene::load_file(path, &options)?)
}

pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if t == 0 {
            bail!("--threads must be at least 1");
        }
        crate::limits::check_threads(t)?;
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting up the thread pool")?;
    }
    Ok(())
}

/// Ctrl-C once: finish the current pass and write the image; twice: exit at once.
fn install_interrupt_handler() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    let _ = ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            eprintln!("\ninterrupted twice: exiting without writing");
            std::process::exit(130);
        }
        eprintln!("\ninterrupt: finishing the current pass, then writing the image (Ctrl-C again to abort)");
    });
    flag
}

pub(crate) fn component_path(out: &Path, comp: Component) -> PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "haze".into());
    out.with_file_name(format!("{stem}_{}.exr", comp.name()))
}

pub fn lightcut_settings(args: &RenderArgs) -> Result<LightcutSettings> {
    if !(args.epsilon.is_finite() && args.epsilon >= 0.0) {
        bail!("--epsilon must be a number >= 0, got {}", args.epsilon);
    }
    if args.max_cut == 0 {
        bail!("--max-cut must be at least 1");
    }
    let bound: BoundKind = args.bound.parse().map_err(|e| anyhow::anyhow!("--bound: {e}"))?;
    let builder: Builder = args.builder.parse().map_err(|e| anyhow::anyhow!("--builder: {e}"))?;
    Ok(LightcutSettings {
        cut: CutSettings { epsilon: args.epsilon, max_cut: args.max_cut },
        bound,
        builder,
        ..Default::default()
    })
}

/// The many-light options of `args`, validated (lightcut options only for lightcut methods).
fn method_options(args: &RenderArgs, name: &str) -> Result<MethodOptions> {
    let budget = match (args.vrls, args.light_paths) {
        (Some(0), _) => bail!("--vrls must be at least 1"),
        (_, Some(0)) => bail!("--light-paths must be at least 1"),
        (_, Some(n)) => LightBudget::Paths(n),
        (Some(n), None) => LightBudget::Vrls(n),
        (None, None) => LightBudget::Vrls(10_000),
    };
    if let Some(c) = args.vpl_clamp {
        if !(c.is_finite() && c > 0.0) {
            bail!("--vpl-clamp must be a positive number, got {c}");
        }
    }
    let lightcuts =
        if name.ends_with("_lightcuts") { lightcut_settings(args)? } else { LightcutSettings::default() };
    Ok(MethodOptions { budget, vpl_clamp: args.vpl_clamp, lightcuts })
}

pub fn run(args: RenderArgs) -> Result<()> {
    set_threads(args.threads)?;
    if let Some(t) = args.time {
        if !(t.is_finite() && t > 0.0) {
            bail!("--time must be a positive number of seconds, got {t}");
        }
    }
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    if args.spp_per_pass == 0 {
        bail!("--spp-per-pass must be at least 1");
    }
    let (scene, inputs) = crate::output::load_with_sources(&args.scene, &args.define)?;
    let outputs = crate::output::check_render_outputs(&args, &inputs)?;
    crate::limits::check_render(&args, &scene)?;
    if let Some(w) = scene.integrator.path_cap_warning() {
        eprintln!("warning: {w}");
    }
    let name = args.integrator.clone().unwrap_or_else(|| scene.integrator.name.clone());
    if args.cut_image.is_some() && !name.ends_with("_lightcuts") {
        bail!("--cut-image needs a lightcut integrator (vrl_lightcuts or vpl_lightcuts), not '{name}'");
    }
    let settings = RenderSettings {
        spp: if args.time.is_some() { 0 } else { args.spp.unwrap_or(scene.spp) },
        time_limit: args.time.map(|t| crate::limits::seconds("--time", t)).transpose()?,
        seed: args.seed,
        spp_per_pass: args.spp_per_pass,
        components: args.components,
        first_pass: 0,
    };
    let cancel = install_interrupt_handler();
    let cam = &scene.camera;
    let pixels = cam.width as u64 * cam.height as u64;
    let bar = progress_bar(&settings, args.quiet);
    let on_pass = |r: &PassReport| {
        let rate = (r.spp_done * pixels) as f64 / r.elapsed.as_secs_f64().max(1e-9);
        bar.set_message(format!("{} spp, {:.2} Msamples/s", r.spp_done, rate * 1e-6));
        match settings.time_limit {
            Some(_) => bar.set_position(r.elapsed.as_millis() as u64),
            None => bar.set_position(r.spp_done),
        }
    };
    let options = method_options(&args, &name)?;
    let method = Method::build(&scene, &name, &options, args.seed)
        .with_context(|| format!("{}", args.scene.display()))?;
    let output = method.render(&scene, &settings, &cancel, on_pass);
    let summary = method.summary();
    bar.finish_and_clear();
    if let Some(s) = summary {
        eprintln!("{s}");
    }
    report_and_write(&args, &scene, &name, &output, &outputs)?;
    if let Some(path) = &args.cut_image {
        crate::cut_image::write(&method, &scene, args.seed, args.max_cut, path)?;
    }
    Ok(())
}

fn progress_bar(settings: &RenderSettings, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let (len, unit) = match settings.time_limit {
        Some(t) => (t.as_millis() as u64, "ms"),
        None => (settings.spp as u64, "spp"),
    };
    let bar = ProgressBar::new(len);
    let template =
        format!("{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {unit} ETA {{eta}} {{msg}}");
    bar.set_style(ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()));
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

fn report_and_write(
    args: &RenderArgs,
    scene: &Scene,
    name: &str,
    out: &RenderOutput,
    outputs: &crate::output::Outputs,
) -> Result<()> {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    if out.film.samples == 0 {
        if args.time.is_some() && !out.interrupted {
            bail!("the --time budget ended before the first pass did; nothing written (give more time)");
        }
        bail!("no samples were rendered (interrupted before the first pass ended); nothing written");
    }
    let secs = out.elapsed.as_secs_f64();
    let samples = out.film.samples * (w * h) as u64;
    eprintln!(
        "{name}: {}x{} at {} spp in {:.2} s ({} passes, {:.2} Msamples/s){}",
        w,
        h,
        out.film.samples,
        secs,
        out.passes,
        samples as f64 / secs.max(1e-9) * 1e-6,
        if out.interrupted { ", interrupted" } else { "" }
    );
    crate::limits::check_invalid_samples(name, out.invalid_samples, samples, &args.scene)?;
    if out.invalid_samples > 0 {
        eprintln!("warning: {} samples were NaN or infinite and were discarded", out.invalid_samples);
    }
    let write = |path: &Path, data: Vec<f32>| -> Result<()> {
        RgbImage::new(w, h, data).write_exr(path).with_context(|| format!("writing {}", path.display()))
    };
    let full = RgbImage::new(w, h, out.film.mean(None));
    let png = &outputs.png;
    if let Some(exr) = &outputs.exr {
        full.write_exr(exr).with_context(|| format!("writing {}", exr.display()))?;
    }
    full.write_png(png, args.exposure).with_context(|| format!("writing {}", png.display()))?;
    match &outputs.exr {
        Some(exr) => eprintln!("wrote {} and {}", exr.display(), png.display()),
        None => eprintln!("wrote {}", png.display()),
    }
    if args.components {
        for comp in Component::ALL {
            let p = component_path(&args.output, comp);
            write(&p, out.film.mean(Some(comp)))?;
            eprintln!("wrote {} ({})", p.display(), comp.name());
        }
    }
    if let Some(v) = &args.variance_out {
        write(v, out.film.sample_variance(None))?;
        eprintln!("wrote {} (per-pixel variance of one sample)", v.display());
    }
    Ok(())
}
