//! `haze render`.

use anyhow::{bail, Context, Result};
use clap::{Arg, ArgAction, ArgMatches, Args, FromArgMatches};
use haze_engine::options::{not_applicable, Kind, OPTIONS};
use haze_engine::{method_names, prepare, replacement_note, Method, MethodKind, Options, Spelling};
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
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    #[arg(long, help = integrator_help())]
    pub integrator: Option<String>,
    /// The options of the engine's table (haze_engine::options::OPTIONS).
    #[command(flatten)]
    pub options: EngineOptions,
    /// [vrl_lightcuts, vpl_lightcuts] Also write a PNG heat map of the mean cut size per pixel
    /// (one extra 1-spp pass with the same seed). Colour scale linear from 0 (black) to
    /// --max-cut (pale yellow, "inferno" colours); a legend strip below the map shows it, ticks
    /// at every quarter.
    #[arg(long, value_name = "PNG")]
    pub cut_image: Option<PathBuf>,
    /// Override a scene `<default>` parameter: -D name=value (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Write the per-pixel variance of one sample to this EXR.
    #[arg(long)]
    pub variance_out: Option<PathBuf>,
    /// Exposure of the PNG preview in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The methods `--integrator` takes, from the engine's one list.
fn integrator_help() -> String {
    format!(
        "Integrator, overriding the scene's `<integrator>`: {} (volpathmis is volpath; path is volpath for scenes without media)",
        method_names()
    )
}

/// The options given on the command line, as (name, text) pairs for `options::resolve`: one
/// flag per entry of the engine's table, with its help text; none has a default here (the
/// engine's table has them), so a flag is only ever "given" when the user gave it.
#[derive(Clone, Debug, Default)]
pub struct EngineOptions {
    pub given: Vec<(&'static str, String)>,
}

impl EngineOptions {
    pub fn pairs(&self) -> Vec<(&str, &str)> {
        self.given.iter().map(|(n, v)| (*n, v.as_str())).collect()
    }
}

impl FromArgMatches for EngineOptions {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut options = EngineOptions::default();
        options.update_from_arg_matches(matches)?;
        Ok(options)
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        for spec in OPTIONS {
            let value = match spec.kind {
                Kind::Flag => matches.get_flag(spec.name).then(|| "true".to_string()),
                _ => matches.get_one::<String>(spec.name).cloned(),
            };
            if let Some(v) = value {
                self.given.retain(|(n, _)| *n != spec.name);
                self.given.push((spec.name, v));
            }
        }
        Ok(())
    }
}

impl clap::Args for EngineOptions {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        OPTIONS.iter().fold(cmd, |cmd, spec| {
            let arg = Arg::new(spec.name).long(spec.flag()[2..].to_string()).help(spec.help_text());
            cmd.arg(match spec.kind {
                Kind::Flag => arg.action(ArgAction::SetTrue),
                _ => arg.action(ArgAction::Set).value_name("VALUE").allow_negative_numbers(true),
            })
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

pub fn load_scene(path: &Path, define: &[String]) -> Result<Scene> {
    let options = LoadOptions { defines: crate::output::parse_defines(define)? };
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

pub fn run(args: RenderArgs) -> Result<()> {
    set_threads(args.threads)?;
    let (scene, inputs) = crate::output::load_with_sources(&args.scene, &args.define)?;
    let (kind, options) = prepare(&scene, args.integrator.as_deref(), &args.options.pairs(), Spelling::Flag)
        .with_context(|| format!("{}", args.scene.display()))?;
    if args.cut_image.is_some() && !kind.is_lightcuts() {
        return Err(not_applicable("--cut-image", kind, MethodKind::LIGHTCUTS));
    }
    let outputs = Outputs {
        output: &args.output,
        exposure: args.exposure,
        variance_out: args.variance_out.as_deref(),
        cut_image: args.cut_image.as_deref(),
        quiet: args.quiet,
        inputs: &inputs,
        note: replacement_note(&scene, args.integrator.as_deref()),
    };
    render_and_write(&args.scene, &scene, kind, &options, &outputs)
}

/// Where `render_and_write` writes.
pub struct Outputs<'a> {
    pub output: &'a Path,
    pub exposure: f32,
    pub variance_out: Option<&'a Path>,
    pub cut_image: Option<&'a Path>,
    pub quiet: bool,
    /// Every file the scene reads (none of them may be overwritten).
    pub inputs: &'a [PathBuf],
    /// A line for stderr once the render's inputs are checked (the scene's integrator replaced).
    pub note: Option<String>,
}

/// Renders `scene` (read from `path`) with `kind` and `options` (Ctrl-C finishes the current
/// pass) and writes the images: `haze render` and `haze reference`.
pub fn render_and_write(
    path: &Path,
    scene: &Scene,
    kind: MethodKind,
    options: &Options,
    outputs: &Outputs,
) -> Result<()> {
    let plan = crate::output::check_render_outputs(
        outputs.output,
        options.components,
        outputs.variance_out,
        outputs.cut_image,
        outputs.inputs,
    )?;
    crate::limits::check_render(options, scene)?;
    if let Some(note) = &outputs.note {
        eprintln!("{note}");
    }
    if let Some(w) = scene.integrator.path_cap_warning() {
        eprintln!("warning: {w}");
    }
    let settings = options.render_settings(kind, scene);
    let described = options.describe(kind);
    if !described.is_empty() {
        eprintln!("{kind}: {described}");
    }
    if options.spp_per_pass.is_none() {
        eprintln!("{kind}: spp per pass {} (auto; --spp-per-pass sets it)", settings.spp_per_pass);
    }
    let cancel = install_interrupt_handler();
    let cam = &scene.camera;
    let pixels = cam.width as u64 * cam.height as u64;
    let bar = progress_bar(&settings, outputs.quiet);
    let on_pass = |r: &PassReport| {
        let rate = (r.spp_done * pixels) as f64 / r.elapsed.as_secs_f64().max(1e-9);
        bar.set_message(format!("{} spp, {:.2} Msamples/s", r.spp_done, rate * 1e-6));
        match settings.time_limit {
            Some(_) => bar.set_position(r.elapsed.as_millis() as u64),
            None => bar.set_position(r.spp_done),
        }
    };
    let method = Method::build(scene, kind, &options.method, options.seed)
        .with_context(|| format!("{}", path.display()))?;
    let output = method.render(scene, &settings, &cancel, on_pass);
    let summary = method.summary();
    bar.finish_and_clear();
    if let Some(s) = summary {
        eprintln!("{s}");
    }
    if let (Some((trace, build)), Some(cut)) = (method.trace_and_build_seconds(), method.mean_cut_size()) {
        let total = output.elapsed.as_secs_f64();
        eprintln!(
            "{kind}: mean cut {cut:.1} nodes per camera segment and tree; time: light tracing {trace:.2} s, tree build {build:.2} s, gather {:.2} s (of {total:.2} s)",
            (total - trace - build).max(0.0)
        );
    }
    report_and_write(outputs, &plan, options.components, path, scene, kind.name(), &output)?;
    if let Some(path) = outputs.cut_image {
        crate::cut_image::write(&method, scene, options, path)?;
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
    args: &Outputs,
    plan: &crate::output::Outputs,
    components: bool,
    scene_path: &Path,
    scene: &Scene,
    name: &str,
    out: &RenderOutput,
) -> Result<()> {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    if out.film.samples == 0 {
        if !out.interrupted {
            bail!("the --time budget ended before the first pass did; nothing written (give more time)");
        }
        bail!("no samples were rendered (interrupted before the first pass ended); nothing written");
    }
    let secs = out.elapsed.as_secs_f64();
    let samples = out.film.samples * (w * h) as u64;
    eprintln!(
        "{name}: {}x{} at {} spp in {:.3} s ({} passes, {:.2} Msamples/s){}",
        w,
        h,
        out.film.samples,
        secs,
        out.passes,
        samples as f64 / secs.max(1e-9) * 1e-6,
        if out.interrupted { ", interrupted" } else { "" }
    );
    crate::limits::check_invalid_samples(name, out.invalid_samples, samples, scene_path)?;
    if out.invalid_samples > 0 {
        eprintln!("warning: {} samples were NaN or infinite and were discarded", out.invalid_samples);
    }
    let write = |path: &Path, data: Vec<f32>| -> Result<()> {
        RgbImage::new(w, h, data).write_exr(path).with_context(|| format!("writing {}", path.display()))
    };
    let full = RgbImage::new(w, h, out.film.mean(None));
    let png = &plan.png;
    if let Some(exr) = &plan.exr {
        full.write_exr(exr).with_context(|| format!("writing {}", exr.display()))?;
    }
    full.write_png(png, args.exposure).with_context(|| format!("writing {}", png.display()))?;
    match &plan.exr {
        Some(exr) => eprintln!("wrote {} and {}", exr.display(), png.display()),
        None => eprintln!("wrote {}", png.display()),
    }
    if components {
        for comp in Component::ALL {
            let p = crate::output::component_path(args.output, comp);
            write(&p, out.film.mean(Some(comp)))?;
            eprintln!("wrote {} ({})", p.display(), comp.name());
        }
    }
    if let Some(v) = args.variance_out {
        write(v, out.film.sample_variance(None))?;
        eprintln!("wrote {} (per-pixel variance of one sample)", v.display());
    }
    Ok(())
}
