//! `haze compare` (equal-time comparison of methods against a reference) and `haze reference`.

use crate::render_cmd::{load_scene, render_and_write, set_threads, Outputs};
use crate::results::{CurvePoint, MethodLabel, MethodResult};
use anyhow::{bail, Context, Result};
use clap::Args;
use haze_engine::options::{self, Scope, OPTIONS};
use haze_engine::{method_names, prepare, Method, MethodKind, MethodOptions, Spelling};
use haze_manylight::integrators::LightBudget;
use haze_render::image_io::RgbImage;
use haze_render::metrics::Metrics;
use haze_render::progressive::RenderSettings;
use haze_render::Film;
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// One method of a comparison: `NAME[:LIGHTS][,KEY=VALUE]...`, e.g. `volpath`, `vrl:10000`,
/// `vrl_lightcuts:100k,cut_size=2`, `vpl_lightcuts:1M,cut=bound,bound=tight`. `LIGHTS` is `vrls`, the
/// number of virtual lights traced per pass (about; the light-path count is fixed from a pilot
/// run); it accepts the suffixes `k` (x1000) and `M` (x1000000). The keys are the method options
/// of the engine's table (`haze_engine::options`, scope `Method`) and `spp_per_pass` (scope
/// `Pass`), checked by the engine.
#[derive(Clone, Debug)]
pub struct MethodSpec {
    pub kind: MethodKind,
    /// The options as given (`LIGHTS` as `vrls`), in order, values trimmed.
    pub given: Vec<(&'static str, String)>,
    /// The resolved options.
    pub options: MethodOptions,
    /// `spp_per_pass=N` of the spec (`None`: `--spp-per-pass`, else the engine's auto default).
    pub spp_per_pass: Option<u32>,
}

/// The options a `--method` spec takes as `KEY=VALUE`: the method options and how its samples
/// are grouped into passes (not the render's budget or seed, which `haze compare` sets for
/// every method alike).
fn spec_key(spec: &options::OptionSpec) -> bool {
    spec.scope != Scope::Render
}

impl MethodSpec {
    /// Virtual lights per pass requested (`vrls`, the default for many-light methods); `None`
    /// for volpath or a budget in light paths.
    pub fn light_count(&self) -> Option<u64> {
        match (self.kind, self.options.budget) {
            (MethodKind::VolPath, _) | (_, LightBudget::Paths(_)) => None,
            (_, LightBudget::Vrls(n)) => Some(n),
        }
    }

    /// A file-name-safe form of the spec, e.g. `vrl_lightcuts-100000_epsilon0.01`.
    pub fn file_stem(&self) -> String {
        self.to_string().replace(':', "-").replace(',', "_").replace('=', "")
    }
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
        let kind = MethodKind::from_name(name)
            .ok_or_else(|| format!("unknown method '{name}' in '{s}' (available: {})", method_names()))?;
        let mut given: Vec<(&'static str, String)> = Vec::new();
        if let Some(l) = lights {
            // `LIGHTS` is `vrls=LIGHTS`, checked by the engine, kept as a plain number.
            let vrls = options::find("vrls").expect("the engine's vrls option");
            let count = match vrls.parse(l, Spelling::Keyword).map_err(|e| format!("'{s}': {e}"))? {
                options::Value::Int(n) => n,
                other => unreachable!("vrls is a count, got {other:?}"),
            };
            given.push(("vrls", count.to_string()));
        }
        for opt in parts {
            let Some((key, value)) = opt.split_once('=') else {
                return Err(format!("'{s}': options are KEY=VALUE, got '{opt}'"));
            };
            let key = key.trim();
            match options::find(key) {
                Some(spec) if spec_key(spec) => given.push((spec.name, value.trim().to_string())),
                _ => {
                    let known: Vec<&str> = OPTIONS.iter().filter(|o| spec_key(o)).map(|o| o.name).collect();
                    return Err(format!("'{s}': unknown option '{key}' (available: {})", known.join(", ")));
                }
            }
        }
        let pairs: Vec<(&str, &str)> = given.iter().map(|(n, v)| (*n, v.as_str())).collect();
        let resolved =
            options::resolve(kind, &pairs, Spelling::Keyword).map_err(|e| format!("'{s}': {e}"))?;
        Ok(MethodSpec { kind, given, options: resolved.method, spp_per_pass: resolved.spp_per_pass })
    }
}

impl fmt::Display for MethodSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.kind)?;
        for (i, (name, value)) in self.given.iter().enumerate() {
            if i == 0 && *name == "vrls" {
                write!(f, ":{value}")?;
            } else {
                write!(f, ",{name}={value}")?;
            }
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
    #[arg(long = "method", required = true, value_parser = clap::value_parser!(MethodSpec), help = method_help())]
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
    /// Camera samples per pixel of every method's passes (many-light methods share a pass's
    /// lights between them). Default: per method, `spp_per_pass=N` of its `--method` spec, else
    /// haze render's auto default for the method and image size (`haze render --help`).
    #[arg(long)]
    pub spp_per_pass: Option<String>,
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
    spp_per_pass: u32,
) -> Result<MethodResult> {
    let start = Instant::now();
    let method = Method::build(scene, spec.kind, &spec.options, seed)?;
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
            spp: chunk * spp_per_pass,
            time_limit: (passes > 0).then_some(remaining),
            seed,
            spp_per_pass,
            components: false,
            first_pass: passes,
            sampler: spec.options.sampler_for(scene, None),
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
        spec: MethodLabel { text: spec.to_string(), file_stem: spec.file_stem(), lights: spec.light_count() },
        seconds,
        passes,
        metrics,
        mean_cut: method.mean_cut_size(),
        image,
        curve,
    })
}

/// The spp per pass of `spec` on `scene`, and where it comes from: `every` (`--spp-per-pass`),
/// the spec's `spp_per_pass=N`, or the engine's auto default (`Options::spp_per_pass_for`).
/// Both given is an error: neither silently wins.
fn spp_per_pass(
    spec: &MethodSpec,
    every: Option<u32>,
    time: f64,
    scene: &haze_scene::Scene,
) -> Result<(u32, &'static str)> {
    let (given, how) = match (every, spec.spp_per_pass) {
        (Some(_), Some(_)) => {
            bail!("{spec}: give either --spp-per-pass or spp_per_pass in --method, not both")
        }
        (Some(n), None) => (Some(n), "--spp-per-pass"),
        (None, Some(n)) => (Some(n), "given"),
        (None, None) => (None, "auto"),
    };
    // Compare's budget is time, not a sample count.
    let options = options::Options { spp_per_pass: given, time: Some(time), ..options::Options::defaults() };
    Ok((options.spp_per_pass_for(spec.kind, scene), how))
}

/// Checks a number of seconds as the engine checks `time`.
fn seconds(flag: &str, t: f64) -> Result<()> {
    let spec = options::find("time").expect("the engine's time option");
    spec.kind.parse(&t.to_string()).map_err(|what| anyhow::anyhow!("{flag} {what} of seconds, got {t}"))?;
    Ok(())
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
    seconds("--time", args.time)?;
    if args.reference.is_some() && args.reference_time.is_some() {
        bail!("--reference-time only applies when no --reference is given");
    }
    let scene = load_scene(&args.scene, &args.define)?;
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("creating {}", args.out_dir.display()))?;
    let reference_path = match &args.reference {
        Some(path) => path.clone(),
        None => {
            let time = args.reference_time.unwrap_or(10.0 * args.time);
            seconds("--reference-time", time)?;
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
    let every = match &args.spp_per_pass {
        Some(text) => {
            let spec = options::find("spp_per_pass").expect("the table has spp_per_pass");
            options::resolve(MethodKind::VolPath, &[(spec.name, text)], Spelling::Flag)?.spp_per_pass
        }
        None => None,
    };
    let mut results = Vec::new();
    for spec in &args.methods {
        let (spp_per_pass, how) = spp_per_pass(spec, every, args.time, &scene)?;
        eprintln!("{spec}: rendering for {:.1} s, spp per pass {spp_per_pass} ({how})", args.time);
        let r = run_method(&scene, spec, &reference.data, budget, args.seed, spp_per_pass)
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

/// `haze reference`: `haze render --integrator volpath --time T`, through the engine.
pub fn reference(args: ReferenceArgs) -> Result<()> {
    set_threads(args.threads)?;
    let (scene, inputs) = crate::output::load_with_sources(&args.scene, &args.define)?;
    let (time, seed) = (args.time.to_string(), args.seed.to_string());
    let (kind, options) =
        prepare(&scene, Some("volpath"), &[("time", &time), ("seed", &seed)], Spelling::Flag)?;
    let outputs = Outputs {
        output: &args.output,
        exposure: 0.0,
        variance_out: None,
        cut_image: None,
        quiet: false,
        inputs: &inputs,
        note: None,
    };
    render_and_write(&args.scene, &scene, kind, &options, &outputs)
}

/// The help of `--method`, with the engine's method names and method options.
fn method_help() -> String {
    let keys: Vec<&str> = OPTIONS.iter().filter(|o| spec_key(o)).map(|o| o.name).collect();
    format!(
        "A method to compare (repeatable): NAME[:LIGHTS][,KEY=VALUE]..., NAME one of {}, LIGHTS the \
         virtual lights per pass (vrls; e.g. 10000, 100k, 1M), KEY one of {} (as `haze render \
         --help` describes them; e.g. vrl_lightcuts:100k,cut=bound,epsilon=0.01,bound=tight)",
        method_names(),
        keys.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_manylight::integrators::Builder;
    use haze_manylight::tree::bound::BoundKind;

    fn spec(s: &str) -> MethodSpec {
        s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn parses_the_paper_methods() {
        let v = spec("volpath");
        assert_eq!((v.kind, v.given.len(), v.light_count()), (MethodKind::VolPath, 0, None));
        assert_eq!(spec("vrl:10000").light_count(), Some(10_000));
        assert_eq!(spec("vrl_lightcuts:100k").light_count(), Some(100_000));
        assert_eq!(spec("vpl_lightcuts:1M").light_count(), Some(1_000_000));
        assert_eq!(spec("vpl_lightcuts:1_000_000").light_count(), Some(1_000_000));
        let s = spec("vrl_lightcuts:100000,cut=bound,epsilon=0.01,max_cut=500");
        assert_eq!(
            (s.options.lightcuts.bound.cut.epsilon, s.options.lightcuts.bound.cut.max_cut),
            (0.01, 500)
        );
        let o = spec("vrl_lightcuts:10k,cut=bound,bound=tight,builder=median").options;
        assert_eq!(
            (o.lightcuts.bound.bound, o.lightcuts.bound.tree.builder),
            (BoundKind::Tight, Builder::MedianSplit)
        );
        // The defaults are the engine's.
        let defaults = options::Options::defaults().method;
        assert_eq!(spec("vrl").options.budget, defaults.budget);
        assert_eq!(spec("vrl").light_count(), Some(10_000));
        assert_eq!(spec("vpl,light_paths=40").light_count(), None);
        assert_eq!(spec("vpl,vpl_clamp=3").options.vpl_clamp, Some(3.0));
    }

    #[test]
    fn display_round_trips_and_names_files() {
        for s in [
            "volpath",
            "vrl:10000",
            "vrl_lightcuts:100000,cut=bound,epsilon=0.01",
            "vpl_lightcuts:5,cut=bound,max_cut=7",
            "vrl_lightcuts:100,cut=bound,bound=conservative,builder=median",
            "vpl,light_paths=40,vpl_clamp=2",
        ] {
            assert_eq!(spec(s).to_string(), s);
        }
        assert_eq!(spec("vrl_lightcuts:100000,cut_size=2").file_stem(), "vrl_lightcuts-100000_cut_size2");
    }

    #[test]
    fn bad_specs_are_clear_errors() {
        for (s, expected) in [
            ("bdpt", "unknown method 'bdpt'"),
            ("volpath:10", "vrls does not apply to volpath"),
            ("vrl:0", "positive integer"),
            ("vrl:ten", "got 'ten'"),
            ("vrl:10,epsilon=0.1", "epsilon does not apply to vrl (only to vrl_lightcuts, vpl_lightcuts)"),
            ("vpl_lightcuts,vpl_clamp=1", "vpl_clamp does not apply to vpl_lightcuts"),
            ("vrl_lightcuts:10,epsilon=-1", "epsilon must be a number >= 0"),
            ("vrl_lightcuts:10,epsilon=nan", "epsilon must be a number >= 0"),
            ("vrl_lightcuts:10,epsilon", "KEY=VALUE"),
            ("vrl_lightcuts:10,bound=loose", "bound must be 'paper', 'conservative' or 'tight', got 'loose'"),
            ("vrl_lightcuts:10,builder=sah", "builder must be 'agglomerative' or 'median', got 'sah'"),
            ("vrl_lightcuts:10,alpha=2", "unknown option 'alpha'"),
            ("vrl_lightcuts:10,seed=2", "unknown option 'seed'"),
            ("vpl_lightcuts,cut=bound,max_cut=0", "max_cut must be a positive integer"),
            ("vrl:10,light_paths=3", "give either vrls or light_paths, not both"),
        ] {
            let e = s.parse::<MethodSpec>().expect_err(s);
            assert!(e.contains(expected), "{s}: {e}");
        }
    }

    #[test]
    fn every_method_option_with_every_method_is_used_or_rejected_naming_both() {
        for o in OPTIONS.iter().filter(|o| spec_key(o)) {
            for m in MethodKind::ALL {
                // An option that needs another's value (`epsilon` needs `cut=bound`) gets it.
                let requirement = match o.requires.filter(|_| o.applies_to.contains(&m)) {
                    Some((name, value)) => format!(",{name}={value}"),
                    None => String::new(),
                };
                let s = format!("{m}{requirement},{}={}", o.name, o.example);
                match s.parse::<MethodSpec>() {
                    Ok(spec) => {
                        assert!(o.applies_to.contains(&m), "{s} accepted");
                        let resolved = options::Options {
                            method: spec.options,
                            spp_per_pass: spec.spp_per_pass,
                            ..options::Options::defaults()
                        };
                        assert_eq!(o.value_in(&resolved).as_deref(), Some(o.example), "{s}");
                    }
                    Err(e) => {
                        assert!(!o.applies_to.contains(&m), "{s}: {e}");
                        assert!(e.contains(&format!("{} does not apply to {m}", o.name)), "{s}: {e}");
                    }
                }
            }
        }
    }

    /// Each method gets its own auto spp per pass (16 for the lightcut methods at 128x128, 1
    /// for the others), its spec's `spp_per_pass=N`, or `--spp-per-pass` for all.
    #[test]
    fn spp_per_pass_is_per_method() {
        let xml = r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
            <integer name="width" value="128"/><integer name="height" value="128"/></film></sensor></scene>"#;
        let path = std::path::Path::new("t.xml");
        let scene = haze_scene::load_str(xml, path, std::path::Path::new("."), &Default::default()).unwrap();
        let of = |s: &str, every| spp_per_pass(&spec(s), every, 1.0, &scene).map_err(|e| e.to_string());
        assert_eq!(of("vrl_lightcuts:1000", None), Ok((16, "auto")));
        assert_eq!(of("vpl_lightcuts", None), Ok((16, "auto")));
        for s in ["vrl:1000", "vpl", "volpath"] {
            assert_eq!(of(s, None), Ok((1, "auto")), "{s}");
        }
        assert_eq!(of("vrl_lightcuts:1000,spp_per_pass=4", None), Ok((4, "given")));
        assert_eq!(of("volpath,spp_per_pass=8", None), Ok((8, "given")));
        assert_eq!(of("vrl_lightcuts", Some(2)), Ok((2, "--spp-per-pass")));
        assert!(of("vrl,spp_per_pass=4", Some(2)).unwrap_err().contains("give either --spp-per-pass"));
        assert_eq!(spec("vrl:10,spp_per_pass=3").to_string(), "vrl:10,spp_per_pass=3");
        let e = "vrl,spp_per_pass=0".parse::<MethodSpec>().unwrap_err();
        assert!(e.contains("spp_per_pass must be a positive integer"), "{e}");
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
