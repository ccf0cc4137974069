//! `haze bench`: throughput of volpath on scenes, as a table.

use crate::render_cmd::{load_scene, set_threads};
use anyhow::Result;
use clap::Args;
use haze_engine::options::{self, MethodKind, Options, Spelling};
use haze_manylight::integrators::{LightBudget, ManyLightSettings, VrlIntegrator};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, render_volpath, RenderSettings};
use haze_render::Integrator;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to measure (default: the validation scenes shipped with haze,
    /// `tests/data/validation/scenes`, looked for in the current directory and beside the
    /// executable).
    pub scenes: Vec<PathBuf>,
    /// volpath, vrl: samples per pixel per scene (default 64).
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
    /// lightcuts: measure cut sizes up to this many VRLs (larger counts: build time only).
    #[arg(long, default_value_t = 1_000_000)]
    pub max_cut_vrls: u64,
    /// lightcuts: most nodes per cut for the cut-size column (a large value shows the sizes the
    /// error criterion alone asks for; default: haze render's).
    #[arg(long)]
    pub max_cut: Option<String>,
    /// lightcuts: cluster bound for the cut-size column: paper, conservative or tight (default:
    /// haze render's).
    #[arg(long)]
    pub bound: Option<String>,
    /// Override a scene `<default>` parameter: -D name=value (e.g. -D res=48 for cheaper cuts).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    pub define: Vec<String>,
    /// lightcuts: only the build times (no cut sizes, no frame times).
    #[arg(long)]
    pub build_only: bool,
    /// lightcuts: PLOC search radius of the agglomerative builder (default: the builder's).
    #[arg(long)]
    pub ploc_radius: Option<usize>,
    /// stochastic: the largest VRL count of the scaling table (10k, 100k, ... up to this).
    #[arg(long, default_value_t = 10_000_000)]
    pub max_vrls: u64,
    /// stochastic: nodes per cut (default: haze render's).
    #[arg(long)]
    pub cut_size: Option<String>,
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
    if args.integrator == "stochastic" {
        return bench_stochastic(&args, &scenes);
    }
    if args.cut_size.is_some() {
        anyhow::bail!("--cut-size applies only to haze bench --integrator stochastic");
    }
    // The options go through the engine's table, as haze render's do.
    let kind = match args.integrator.as_str() {
        "volpath" => MethodKind::VolPath,
        "vrl" => MethodKind::Vrl,
        "lightcuts" => MethodKind::VrlLightcuts,
        other => anyhow::bail!("haze bench measures volpath, vrl, lightcuts or stochastic, not '{other}'"),
    };
    if kind.is_lightcuts() {
        // Its frames are 1 spp and its light counts 10k, 100k and 1M.
        for (flag, given) in [("--spp", &args.spp), ("--vrls", &args.vrls)] {
            if given.is_some() {
                anyhow::bail!("{flag} does not apply to haze bench --integrator lightcuts (it measures 1-spp frames with 10k, 100k and 1M VRLs)");
            }
        }
    }
    // The lightcuts tables measure the paper's cut.
    let mut given = if kind.is_lightcuts() { vec![("cut", "bound")] } else { Vec::new() };
    let spp = args.spp.as_deref().unwrap_or(if kind.is_lightcuts() { "1" } else { "64" });
    for (name, value) in [
        ("spp", Some(spp)),
        ("vrls", args.vrls.as_deref()),
        ("max_cut", args.max_cut.as_deref()),
        ("bound", args.bound.as_deref()),
    ] {
        if let Some(v) = value {
            given.push((name, v));
        }
    }
    let options = options::resolve(kind, &given, Spelling::Flag)?;
    match kind {
        MethodKind::VolPath => bench_volpath(&options, &scenes),
        MethodKind::Vrl => bench_vrl(&options, &scenes),
        _ => {
            bench_lightcuts(&args, &options, &scenes)?;
            if args.scenes.is_empty() && !args.build_only {
                cut_growth()?;
            }
            Ok(())
        }
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

/// Light-tree build times (3-step agglomerative vs median split, 1 and all threads, for 10k,
/// 100k and 1M VRLs traced in the scene), mean cut size against the number of VRLs, and the
/// frame time of `vrl_lightcuts` with 100k VRLs against `vrl` with 10k VRLs at 1 spp.
fn bench_lightcuts(args: &BenchArgs, options: &Options, scenes: &[PathBuf]) -> Result<()> {
    use haze_manylight::integrators::{Builder, CutStrategy, LightcutSettings, LightcutsIntegrator, Vrls};
    use haze_manylight::lighttrace::{paths_for_vrl_count, trace_light_paths};
    use haze_manylight::tree::build::{build_agglomerative, build_median_split, BuildSettings};
    use haze_manylight::tree::lights::LightSummary;
    use haze_manylight::vrl::{Segment, Vrl};
    let bound = options.method.lightcuts.bound;
    let cut_settings = options.method.lightcuts.cut;
    let max_cut = cut_settings.max_cut;
    let bound_name = options::find("bound").and_then(|b| b.value_in(options)).unwrap_or_default();
    for path in scenes {
        let scene = load_scene(path, &args.define)?;
        let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let trace = LightTraceSettings::from_max_depth(scene.integrator.max_depth);
        let defaults = BuildSettings::default();
        let build_settings =
            BuildSettings { radius: args.ploc_radius.unwrap_or(defaults.radius), ..defaults };
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        println!(
            "\n### {file} ({}x{}; PLOC radius {}, groups of {}; cuts: bound {}, epsilon {}, max cut {}; load average {})\n",
            scene.camera.width,
            scene.camera.height,
            build_settings.radius,
            build_settings.group_size,
            bound_name,
            cut_settings.epsilon,
            max_cut,
            load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
        );
        println!("| VRLs | builder | threads | build s | CPU s | ns per N log2 N | tree cost | mean cut (1 spp) | segments at max-cut | cut s |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for n in [10_000u64, 100_000, 1_000_000] {
            let paths = paths_for_vrl_count(&scene, n, 0, &trace)?;
            let set = trace_light_paths(&scene, paths, 0, 0, &trace)?;
            let media = haze_manylight::integrators::media_of(&scene);
            let lights: Vec<LightSummary> = set
                .vrls
                .iter()
                .map(|r| {
                    let v = Vrl {
                        events: 0,
                        seg: Segment::new(r.o, r.d, r.len),
                        flux: r.beta,
                        ratio: r.ratio,
                        medium: r.medium,
                    };
                    LightSummary::vrl(&v, &media[r.medium as usize])
                })
                .collect();
            let nn = lights.len() as f64;
            for builder in ["agglomerative", "median"] {
                for threads in [1usize, rayon::current_num_threads()] {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
                    let (t0, cpu0) = (Instant::now(), process_cpu_seconds());
                    let tree = pool.install(|| match builder {
                        "agglomerative" => build_agglomerative(&lights, &build_settings),
                        _ => build_median_split(&lights, 0),
                    });
                    let secs = t0.elapsed().as_secs_f64();
                    let cpu =
                        cpu0.zip(process_cpu_seconds()).map_or("-".into(), |(a, b)| format!("{:.2}", b - a));
                    assert_eq!(tree.nodes.len(), 2 * lights.len() - 1);
                    // Cut sizes with this builder (1 spp frame), measured once per builder.
                    let cut = if threads == 1 && n <= args.max_cut_vrls && !args.build_only {
                        let lc = LightcutSettings {
                            builder: if builder == "median" {
                                Builder::MedianSplit
                            } else {
                                Builder::Agglomerative
                            },
                            build: build_settings,
                            bound,
                            cut: cut_settings,
                            strategy: CutStrategy::Bound,
                            ..Default::default()
                        };
                        let ml = ManyLightSettings {
                            budget: LightBudget::Paths(paths),
                            trace: trace.clone(),
                            caustic_paths: None,
                            compensated_clamp: None,
                        };
                        let integ = LightcutsIntegrator::<Vrls>::new(&scene, ml, lc, 0)?;
                        let settings = RenderSettings { spp: 1, ..Default::default() };
                        let out = render(&scene, &integ, &settings, &AtomicBool::new(false), |_| {});
                        let (mean, _, hit) = integ.cut_statistics();
                        (
                            format!("{mean:.1}"),
                            format!("{:.1}%", 100.0 * hit),
                            format!("{:.2}", out.elapsed.as_secs_f64()),
                        )
                    } else {
                        ("-".into(), "-".into(), "-".into())
                    };
                    println!(
                        "| {} | {builder} | {threads} | {secs:.3} | {cpu} | {:.1} | {:.2} | {} | {} | {} |",
                        lights.len(),
                        secs * 1e9 / (nn * nn.log2()),
                        tree_cost(&tree),
                        cut.0,
                        cut.1,
                        cut.2
                    );
                }
            }
        }
        if args.build_only {
            continue;
        }
        // Frame time: vrl_lightcuts 100k against vrl 10k, 1 spp, all threads.
        let ml = |vrls| ManyLightSettings {
            budget: LightBudget::Vrls(vrls),
            trace: trace.clone(),
            caustic_paths: None,
            compensated_clamp: None,
        };
        let lc = LightcutsIntegrator::<Vrls>::new(&scene, ml(100_000), LightcutSettings::default(), 0)?;
        let lc_secs = frame_seconds(&scene, &lc);
        let vrl_secs = frame_seconds(&scene, &VrlIntegrator::new(&scene, ml(10_000), 0)?);
        println!(
            "\nframe at 1 spp: vrl_lightcuts (100k VRLs) {lc_secs:.2} s, vrl (10k VRLs) {vrl_secs:.2} s, ratio {:.2}",
            lc_secs / vrl_secs
        );
    }
    Ok(())
}

/// The quantity the agglomerative builder greedily minimises, summed over the tree:
/// `sum_internal I(node) diag(node)^2 / (I(root) diag(root)^2)` (lower is a tighter tree).
fn tree_cost(tree: &haze_manylight::tree::LightTree) -> f64 {
    let cost = |n: &haze_manylight::tree::Node| n.intensity as f64 * (n.bounds.diagonal() as f64).powi(2);
    let total: f64 = tree.nodes.iter().filter(|n| !n.is_leaf()).map(cost).sum();
    total / cost(&tree.nodes[tree.root as usize]).max(1e-300)
}

/// Mean cut size against the number of VRLs (10k, 100k, 1M) on a scene whose cuts converge
/// below an unlimited cap (the smoke room, 32x32, 1 spp, epsilon 0.02), with the paper's and the
/// tight bound: the "must grow sub-linearly". On the validation scenes every segment
/// stops at the default cap of 1000, which says nothing about growth.
fn cut_growth() -> Result<()> {
    use haze_manylight::integrators::{CutStrategy, LightcutSettings, LightcutsIntegrator, Vrls};
    use haze_manylight::tree::bound::BoundKind;
    use haze_manylight::tree::cut::CutSettings;
    let path = shipped("scenes/bench-smoke-room.xml")?;
    let scene = load_scene(&path, &["res=32".to_string()])?;
    let trace = LightTraceSettings::from_max_depth(scene.integrator.max_depth);
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "\n### mean cut size vs VRLs: bench-smoke-room.xml, 32x32, 1 spp, epsilon 0.02, no cut limit (load average {})\n",
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    println!("| VRLs | mean cut, paper | cut/N | render s | mean cut, tight | cut/N | render s |");
    println!("|---|---|---|---|---|---|---|");
    for n in [10_000u64, 100_000, 1_000_000] {
        let mut row = String::new();
        let mut lights = 0.0;
        for bound in [BoundKind::Paper, BoundKind::Tight] {
            let ml = ManyLightSettings {
                budget: LightBudget::Vrls(n),
                trace: trace.clone(),
                caustic_paths: None,
                compensated_clamp: None,
            };
            let lc = LightcutSettings {
                bound,
                cut: CutSettings { max_cut: u32::MAX, ..Default::default() },
                strategy: CutStrategy::Bound,
                ..Default::default()
            };
            let integ = LightcutsIntegrator::<Vrls>::new(&scene, ml, lc, 0)?;
            let settings = RenderSettings { spp: 1, ..Default::default() };
            let out = render(&scene, &integ, &settings, &AtomicBool::new(false), |_| {});
            let (mean, _, _) = integ.cut_statistics();
            lights = integ.lights_per_pass();
            row +=
                &format!(" {mean:.0} | {:.4} | {:.2} |", mean / lights.max(1.0), out.elapsed.as_secs_f64());
        }
        println!("| {lights:.0} |{row}");
    }
    Ok(())
}

/// CPU time (user + system) of this process so far, from `/proc/self/stat` (Linux; 10 ms
/// ticks). Beside wall time it shows how much of a timing another load on the cores took.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// VRL evaluations per second: one evaluation is one camera segment x one VRL, with its
/// visibility test. Light tracing time is reported separately.
fn bench_vrl(options: &Options, scenes: &[PathBuf]) -> Result<()> {
    println!(
        "| scene | pixels | spp | VRLs/pass | light tracing s | total s | evaluations | M evaluations/s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &[])?;
        let ml = ManyLightSettings {
            budget: options.method.budget,
            trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
            caustic_paths: None,
            compensated_clamp: None,
        };
        let integrator = VrlIntegrator::new(&scene, ml, 0)?;
        let t0 = Instant::now();
        let _ = integrator.begin_pass(&scene, 0, 0);
        let trace_s = t0.elapsed().as_secs_f64();
        let settings = RenderSettings { spp: spp(options), spp_per_pass: 1, ..Default::default() };
        let out = render(&scene, &integrator, &settings, &AtomicBool::new(false), |_| {});
        let secs = out.elapsed.as_secs_f64();
        let evals = integrator.evaluations();
        let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        println!(
            "| {file} | {}x{} | {} | {} | {:.3} | {:.2} | {} | {:.2} |",
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

/// The `--spp` of `haze bench` (always given: it has a default of its own).
fn spp(options: &Options) -> u32 {
    options.spp.expect("bench passes --spp")
}

fn bench_volpath(options: &Options, scenes: &[PathBuf]) -> Result<()> {
    println!("| scene | pixels | spp | seconds | Msamples/s | Mitsuba 3 Msamples/s | ratio haze/Mitsuba |");
    println!("|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = load_scene(path, &[])?;
        let settings = RenderSettings { spp: spp(options), spp_per_pass: 4, ..Default::default() };
        let out = render_volpath(&scene, &settings);
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

/// Seconds of one frame at 1 spp with `integ`: its per-pass light tracing and tree build included,
/// its construction (the pilot light-tracing run) not.
/// The stochastic cut's cost per camera segment against the number of VRLs. One pass (light
/// set and trees) is prepared for each of 10k, 100k, ... `--max-vrls` VRLs; then, in rounds,
/// the gather of `--spp` samples per pixel (cuts, descents, light evaluations, and the camera
/// rays and single scattering they share: everything but light tracing and the build) is timed
/// on each pass in turn, so every round measures all light counts under the same machine load.
/// The table gives the median over rounds and the ratio to the first row per round (median,
/// and its spread): the "within 2x from 10k to 10M" is that ratio.
fn bench_stochastic(args: &BenchArgs, scenes: &[PathBuf]) -> Result<()> {
    use haze_manylight::integrators::{LightcutsIntegrator, Vrls};
    if args.vrls.is_some() || args.max_cut.is_some() || args.bound.is_some() {
        anyhow::bail!("haze bench --integrator stochastic takes --spp, --cut-size and --max-vrls (the VRL counts are 10k, 100k, ...)");
    }
    let mut given = vec![("spp", args.spp.as_deref().unwrap_or("16"))];
    if let Some(k) = args.cut_size.as_deref() {
        given.push(("cut_size", k));
    }
    let options = options::resolve(MethodKind::VrlLightcuts, &given, Spelling::Flag)?;
    let (spp, cut_size) = (options.spp.unwrap_or(16), options.method.lightcuts.stochastic.cut_size);
    const ROUNDS: usize = 5;
    for path in scenes {
        let scene = load_scene(path, &args.define)?;
        let file = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let trace = LightTraceSettings::from_max_depth(scene.integrator.max_depth);
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        println!(
            "\n### {file}: stochastic cut of {} nodes, {}x{} at {} spp sharing one pass, {ROUNDS} interleaved rounds (load average {})\n",
            cut_size,
            scene.camera.width,
            scene.camera.height,
            spp,
            load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
        );
        let mut prepared = Vec::new();
        let mut n = 10_000u64;
        while n <= args.max_vrls {
            let ml = ManyLightSettings {
                budget: LightBudget::Vrls(n),
                trace: trace.clone(),
                caustic_paths: None,
                compensated_clamp: None,
            };
            let integ = LightcutsIntegrator::<Vrls>::new(&scene, ml, options.method.lightcuts, 0)?;
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

/// Median, least and largest of `v`.
fn spread(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[0], s[s.len() - 1])
}

/// The gather of one pass: `spp` camera samples per pixel through `data`, rows in parallel as
/// `render` does (the sums are discarded).
fn gather<I: Integrator>(scene: &haze_scene::Scene, integ: &I, data: &I::PassData, spp: u32, round: u64) {
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

fn frame_seconds(scene: &haze_scene::Scene, integ: &impl Integrator) -> f64 {
    let settings = RenderSettings { spp: 1, ..Default::default() };
    render(scene, integ, &settings, &AtomicBool::new(false), |_| {}).elapsed.as_secs_f64()
}
