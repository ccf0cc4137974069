//! `haze compare` (equal-time comparison of methods against a reference) and `haze reference`.

use crate::render_cmd::{load_scene, set_threads, RenderArgs};
use anyhow::{bail, Context, Result};
use clap::{Args, Parser};
use haze_engine::methods::{Method, MethodOptions};
use haze_manylight::integrators::{Builder, LightBudget};
use haze_manylight::tree::bound::BoundKind;
use haze_render::image_io::RgbImage;
use haze_render::metrics::Metrics;
use haze_render::progressive::RenderSettings;
use haze_render::Film;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Light count of a many-light method when the spec gives none (as `haze render`).
const DEFAULT_LIGHTS: u64 = 10_000;

/// One method of a comparison: `NAME[:LIGHTS][,epsilon=E][,max_cut=N][,bound=B][,builder=T]`,
/// e.g. `volpath`,
/// `vrl:10000`, `vrl_lightcuts:100k,epsilon=0.01`, `vpl_lightcuts:1M`. `LIGHTS` is the number of
/// virtual lights traced per pass (about; the light-path count is fixed from a pilot run); it
/// accepts the suffixes `k` (x1000) and `M` (x1000000).
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSpec {
    pub name: String,
    pub lights: Option<u64>,
    pub epsilon: Option<f32>,
    pub max_cut: Option<u32>,
    /// Lightcut bound name (`paper`, `conservative`, `tight`), kept as given for display.
    pub bound: Option<String>,
    /// Tree builder name (`agglomerative`, `median`).
    pub builder: Option<String>,
}

impl MethodSpec {
    fn is_lightcuts(&self) -> bool {
        self.name.ends_with("_lightcuts")
    }

    /// Lights per pass requested (the default for many-light methods), `None` for volpath.
    pub fn light_count(&self) -> Option<u64> {
        (self.name != "volpath").then(|| self.lights.unwrap_or(DEFAULT_LIGHTS))
    }

    /// A file-name-safe form of the spec, e.g. `vrl_lightcuts-100000_epsilon0.01`.
    pub fn file_stem(&self) -> String {
        self.to_string().replace(':', "-").replace(',', "_").replace('=', "")
    }

    fn options(&self) -> MethodOptions {
        let mut o = MethodOptions {
            budget: LightBudget::Vrls(self.light_count().unwrap_or(DEFAULT_LIGHTS)),
            ..Default::default()
        };
        if let Some(e) = self.epsilon {
            o.lightcuts.cut.epsilon = e;
        }
        if let Some(m) = self.max_cut {
            o.lightcuts.cut.max_cut = m;
        }
        // Validated when parsed (`FromStr for MethodSpec`).
        if let Some(b) = self.bound.as_deref().and_then(|b| b.parse().ok()) {
            o.lightcuts.bound = b;
        }
        if let Some(b) = self.builder.as_deref().and_then(|b| b.parse().ok()) {
            o.lightcuts.builder = b;
        }
        o
    }
}

fn parse_count(s: &str) -> Option<u64> {
    let s = s.replace('_', "");
    let (digits, scale) = match s.as_bytes().last()? {
        b'k' => (&s[..s.len() - 1], 1_000),
        b'M' => (&s[..s.len() - 1], 1_000_000),
        _ => (&s[..], 1),
    };
    digits.parse::<u64>().ok()?.checked_mul(scale)
}

impl FromStr for MethodSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut parts = s.split(',');
        let head = parts.next().unwrap_or_default().trim();
        let (name, lights) = match head.split_once(':') {
            Some((n, l)) => (n, Some(l)),
            None => (head, None),
        };
        const NAMES: [&str; 5] = ["volpath", "vrl", "vpl", "vrl_lightcuts", "vpl_lightcuts"];
        if !NAMES.contains(&name) {
            return Err(format!("unknown method '{name}' in '{s}' (available: {})", NAMES.join(", ")));
        }
        let mut spec = MethodSpec {
            name: name.to_string(),
            lights: None,
            epsilon: None,
            max_cut: None,
            bound: None,
            builder: None,
        };
        if let Some(l) = lights {
            if name == "volpath" {
                return Err(format!("'{s}': volpath takes no light count"));
            }
            match parse_count(l) {
                Some(n) if n > 0 => spec.lights = Some(n),
                _ => {
                    return Err(format!(
                        "'{s}': the light count must be a positive integer (e.g. 10000, 100k, 1M), got '{l}'"
                    ))
                }
            }
        }
        for opt in parts {
            let Some((key, value)) = opt.split_once('=') else {
                return Err(format!("'{s}': options are KEY=VALUE, got '{opt}'"));
            };
            if !spec.is_lightcuts() {
                return Err(format!("'{s}': option '{key}' applies only to vrl_lightcuts and vpl_lightcuts"));
            }
            match key.trim() {
                "epsilon" => match value.trim().parse::<f32>() {
                    Ok(e) if e.is_finite() && e >= 0.0 => spec.epsilon = Some(e),
                    _ => return Err(format!("'{s}': epsilon must be a number >= 0, got '{value}'")),
                },
                "max_cut" => match value.trim().parse::<u32>() {
                    Ok(m) if m > 0 => spec.max_cut = Some(m),
                    _ => return Err(format!("'{s}': max_cut must be a positive integer, got '{value}'")),
                },
                "bound" => match value.trim().parse::<BoundKind>() {
                    Ok(_) => spec.bound = Some(value.trim().to_string()),
                    Err(e) => return Err(format!("'{s}': {e}")),
                },
                "builder" => match value.trim().parse::<Builder>() {
                    Ok(_) => spec.builder = Some(value.trim().to_string()),
                    Err(e) => return Err(format!("'{s}': {e}")),
                },
                other => {
                    return Err(format!(
                        "'{s}': unknown option '{other}' (available: epsilon, max_cut, bound, builder)"
                    ))
                }
            }
        }
        Ok(spec)
    }
}

impl fmt::Display for MethodSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.name)?;
        if let Some(l) = self.lights {
            write!(f, ":{l}")?;
        }
        if let Some(e) = self.epsilon {
            write!(f, ",epsilon={e}")?;
        }
        if let Some(m) = self.max_cut {
            write!(f, ",max_cut={m}")?;
        }
        if let Some(b) = &self.bound {
            write!(f, ",bound={b}")?;
        }
        if let Some(b) = &self.builder {
            write!(f, ",builder={b}")?;
        }
        Ok(())
    }
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Scene file (Mitsuba 3 XML).
    pub scene: PathBuf,
    /// Reference image (EXR), e.g. from `haze reference SCENE.xml --time 600 -o REF.exr`.
    /// Without it, a volpath reference is rendered first for `--reference-time` seconds and
    /// written to OUT_DIR/reference.exr.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Seconds of volpath for the reference made when `--reference` is not given
    /// (default: 10 x `--time`). Its noise adds to every method's error (MSE_measured ~
    /// MSE_true + MSE_reference, seeds differ), so give it much more time than the methods.
    #[arg(long)]
    pub reference_time: Option<f64>,
    /// Wall-clock budget of each method in seconds, light tracing and tree builds included.
    #[arg(long)]
    pub time: f64,
    /// A method to compare (repeatable): volpath, vrl:N, vpl:N, vrl_lightcuts:N, vpl_lightcuts:N,
    /// with N lights per pass (e.g. 10000, 100k, 1M) and lightcut options `,epsilon=E,max_cut=M`.
    #[arg(long = "method", required = true, value_parser = clap::value_parser!(MethodSpec))]
    pub methods: Vec<MethodSpec>,
    /// Folder for each method's image (METHOD.exr and METHOD.png).
    #[arg(short, long, default_value = "compare")]
    pub out_dir: PathBuf,
    /// Also write a static HTML report (index.html and its images) to this folder.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Also plot RMSE against the number of lights per pass (SVG), one line per method family;
    /// for runs of one method at several light counts, e.g. `--method vrl:1k --method vrl:10k ...`.
    #[arg(long, value_name = "FILE.svg")]
    pub lights_plot: Option<PathBuf>,
    /// Seed of every method.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Override a scene `<default>` parameter: -D name=value (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// Exposure of the PNG images in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

/// The error of a method's image at one moment of its run.
#[derive(Clone, Copy, Debug)]
pub struct CurvePoint {
    pub seconds: f64,
    pub metrics: Metrics,
}

/// What one method produced in its time budget.
pub struct MethodResult {
    pub spec: MethodSpec,
    pub seconds: f64,
    pub passes: u32,
    pub metrics: Metrics,
    pub mean_cut: Option<f64>,
    /// Row-major linear RGB.
    pub image: Vec<f32>,
    /// Error at the end of passes (geometrically spaced), for the convergence plot.
    pub curve: Vec<CurvePoint>,
}

/// Passes to render before the next error sample: every pass at first, then about 25% more
/// passes each time, so a run has O(log passes) samples, evenly spread on a log time axis.
fn next_chunk(passes_done: u32) -> u32 {
    (passes_done / 4).max(1)
}

/// Runs `spec` on `scene` for `budget` (build included) and measures it against `reference`.
/// At least one pass is rendered even if the build alone exceeds the budget.
pub fn run_method(
    scene: &haze_scene::Scene,
    spec: &MethodSpec,
    reference: &[f32],
    budget: Duration,
    seed: u64,
) -> Result<MethodResult> {
    let start = Instant::now();
    let method = Method::build(scene, &spec.name, &spec.options(), seed)?;
    let cam = &scene.camera;
    let mut film = Film::new(cam.width, cam.height, false);
    let cancel = AtomicBool::new(false);
    let mut passes = 0u32;
    let mut curve = Vec::new();
    loop {
        let remaining = budget.saturating_sub(start.elapsed());
        if remaining.is_zero() && passes > 0 {
            break;
        }
        let chunk = next_chunk(passes);
        let settings = RenderSettings {
            spp: chunk,
            time_limit: (passes > 0).then_some(remaining),
            seed,
            spp_per_pass: 1,
            components: false,
            first_pass: passes,
        };
        let out = method.render(scene, &settings, &cancel, |_| {});
        if out.passes == 0 {
            break;
        }
        passes += out.passes;
        film.merge(&out.film);
        let metrics = Metrics::compute(&film.mean(None), reference, None);
        curve.push(CurvePoint { seconds: start.elapsed().as_secs_f64(), metrics });
    }
    let seconds = start.elapsed().as_secs_f64();
    if let Some(summary) = method.summary() {
        eprintln!("{summary}");
    }
    let image = film.mean(None);
    let metrics = Metrics::compute(&image, reference, None);
    Ok(MethodResult {
        spec: spec.clone(),
        seconds,
        passes,
        metrics,
        mean_cut: method.mean_cut_size(),
        image,
        curve,
    })
}

/// The results as a markdown table.
pub fn markdown_table(results: &[MethodResult]) -> String {
    let mut s = String::from(
        "| method | lights | time (s) | passes | RMSE | SMAPE (%) | relMSE | mean cut size |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in results {
        let lights = r.spec.light_count().map_or("-".to_string(), |n| n.to_string());
        let cut = r.mean_cut.map_or("-".to_string(), |c| format!("{c:.1}"));
        s += &format!(
            "| {} | {} | {:.2} | {} | {:.4} | {:.2} | {:.4} | {} |\n",
            r.spec, lights, r.seconds, r.passes, r.metrics.rmse, r.metrics.smape, r.metrics.rel_mse, cut
        );
    }
    s
}

pub fn run(args: CompareArgs) -> Result<()> {
    set_threads(args.threads)?;
    if !(args.time.is_finite() && args.time > 0.0) {
        bail!("--time must be a positive number of seconds, got {}", args.time);
    }
    if args.reference.is_some() && args.reference_time.is_some() {
        bail!("--reference-time only applies when no --reference is given");
    }
    let scene = load_scene(&args.scene, &args.define)?;
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("creating {}", args.out_dir.display()))?;
    let reference_path = match &args.reference {
        Some(path) => path.clone(),
        None => {
            let time = args.reference_time.unwrap_or(10.0 * args.time);
            if !(time.is_finite() && time > 0.0) {
                bail!("--reference-time must be a positive number of seconds, got {time}");
            }
            let output = args.out_dir.join("reference.exr");
            eprintln!(
                "no --reference given: rendering one with volpath for {time:.1} s into {}",
                output.display()
            );
            reference(ReferenceArgs {
                scene: args.scene.clone(),
                output: output.clone(),
                time,
                seed: REFERENCE_SEED,
                threads: None,
                define: args.define.clone(),
            })
            .context("making the reference")?;
            output
        }
    };
    let reference = RgbImage::read_exr(&reference_path)
        .with_context(|| format!("reading the reference {}", reference_path.display()))?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    if (reference.width, reference.height) != (w, h) {
        bail!(
            "the reference {} is {}x{} but the scene renders {}x{}",
            reference_path.display(),
            reference.width,
            reference.height,
            w,
            h
        );
    }
    let budget = crate::limits::seconds("--time", args.time)?;
    let mut results = Vec::new();
    for spec in &args.methods {
        eprintln!("{spec}: rendering for {:.1} s", args.time);
        let r = run_method(&scene, spec, &reference.data, budget, args.seed)
            .with_context(|| format!("{}: method {spec}", args.scene.display()))?;
        let img = RgbImage::new(w, h, r.image.clone());
        let exr = args.out_dir.join(format!("{}.exr", spec.file_stem()));
        img.write_exr(&exr).with_context(|| format!("writing {}", exr.display()))?;
        let png = exr.with_extension("png");
        img.write_png(&png, args.exposure).with_context(|| format!("writing {}", png.display()))?;
        eprintln!(
            "{spec}: {} passes in {:.2} s, wrote {} and {}",
            r.passes,
            r.seconds,
            exr.display(),
            png.display()
        );
        if r.seconds > 1.5 * args.time {
            eprintln!(
                "warning: {spec} took {:.1} s for a budget of {} s: its light tracing and first pass alone exceed the budget (at least one pass is always rendered)",
                r.seconds, args.time
            );
        }
        results.push(r);
    }
    print!("{}", markdown_table(&results));
    if let Some(path) = &args.lights_plot {
        crate::report::lights_plot(path, &results, args.time)?;
        eprintln!("wrote the plot {}", path.display());
    }
    if let Some(dir) = &args.report {
        let page = crate::report::Report {
            scene: &args.scene,
            width: w,
            height: h,
            budget: args.time,
            reference: &reference.data,
            results: &results,
            exposure: args.exposure,
        };
        let index = page.write(dir)?;
        eprintln!("wrote the report {}", index.display());
    }
    Ok(())
}

/// Default seed of references: far from the methods' default seed 0, so the reference's noise
/// is independent of theirs.
pub const REFERENCE_SEED: u64 = 1_000_003;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    /// Scene file (Mitsuba 3 XML).
    pub scene: PathBuf,
    /// Output EXR path; a PNG preview is written next to it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Seconds of volpath rendering.
    #[arg(long)]
    pub time: f64,
    /// Seed (use another seed than the compared methods').
    #[arg(long, default_value_t = REFERENCE_SEED)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Override a scene `<default>` parameter: -D name=value (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
}

#[derive(Parser)]
struct RenderCommandLine {
    #[command(flatten)]
    render: RenderArgs,
}

/// `haze reference`: `haze render --integrator volpath --time T` under another name.
pub fn reference(args: ReferenceArgs) -> Result<()> {
    let mut argv: Vec<String> =
        vec!["haze".into(), path_arg(&args.scene), "-o".into(), path_arg(&args.output)];
    argv.extend(["--integrator".into(), "volpath".into(), "--time".into(), args.time.to_string()]);
    argv.extend(["--seed".into(), args.seed.to_string()]);
    if let Some(t) = args.threads {
        argv.extend(["--threads".into(), t.to_string()]);
    }
    for d in &args.define {
        argv.extend(["-D".into(), d.clone()]);
    }
    let parsed = RenderCommandLine::try_parse_from(argv).context("haze reference")?;
    crate::render_cmd::run(parsed.render)
}

fn path_arg(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(s: &str) -> MethodSpec {
        s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn parses_the_paper_methods() {
        assert_eq!(
            spec("volpath"),
            MethodSpec {
                name: "volpath".into(),
                lights: None,
                epsilon: None,
                max_cut: None,
                bound: None,
                builder: None
            }
        );
        assert_eq!(spec("vrl:10000").lights, Some(10_000));
        assert_eq!(spec("vrl_lightcuts:100k").lights, Some(100_000));
        assert_eq!(spec("vpl_lightcuts:1M").lights, Some(1_000_000));
        assert_eq!(spec("vpl_lightcuts:1_000_000").lights, Some(1_000_000));
        let s = spec("vrl_lightcuts:100000,epsilon=0.01,max_cut=500");
        assert_eq!((s.epsilon, s.max_cut), (Some(0.01), Some(500)));
        let s = spec("vrl_lightcuts:10k,bound=tight,builder=median");
        let o = s.options();
        assert_eq!((o.lightcuts.bound, o.lightcuts.builder), (BoundKind::Tight, Builder::MedianSplit));
        assert_eq!(spec("vrl").light_count(), Some(DEFAULT_LIGHTS));
        assert_eq!(spec("volpath").light_count(), None);
    }

    #[test]
    fn display_round_trips_and_names_files() {
        for s in [
            "volpath",
            "vrl:10000",
            "vrl_lightcuts:100000,epsilon=0.01",
            "vpl_lightcuts:5,max_cut=7",
            "vrl_lightcuts:100,bound=conservative,builder=median",
        ] {
            assert_eq!(spec(s).to_string(), s);
        }
        assert_eq!(spec("vrl_lightcuts:100000,epsilon=0.01").file_stem(), "vrl_lightcuts-100000_epsilon0.01");
    }

    #[test]
    fn bad_specs_are_clear_errors() {
        for (s, expected) in [
            ("bdpt", "unknown method 'bdpt'"),
            ("volpath:10", "volpath takes no light count"),
            ("vrl:0", "positive integer"),
            ("vrl:ten", "got 'ten'"),
            ("vrl:10,epsilon=0.1", "only to vrl_lightcuts"),
            ("vrl_lightcuts:10,epsilon=-1", "epsilon must be a number >= 0"),
            ("vrl_lightcuts:10,epsilon", "KEY=VALUE"),
            (
                "vrl_lightcuts:10,bound=loose",
                "the bound must be 'paper', 'conservative' or 'tight', got 'loose'",
            ),
            ("vrl_lightcuts:10,builder=sah", "the builder must be 'agglomerative' or 'median', got 'sah'"),
            ("vrl_lightcuts:10,alpha=2", "unknown option 'alpha'"),
            ("vpl_lightcuts,max_cut=0", "max_cut must be a positive integer"),
        ] {
            let e = s.parse::<MethodSpec>().expect_err(s);
            assert!(e.contains(expected), "{s}: {e}");
        }
    }

    #[test]
    fn chunks_grow_geometrically() {
        let mut done = 0;
        let mut samples = 0;
        while done < 10_000 {
            done += next_chunk(done);
            samples += 1;
        }
        assert!(samples < 60, "{samples} error samples for 10000 passes");
    }
}
