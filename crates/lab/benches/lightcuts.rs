//! Light trees and the bound cut, as tables:
//!
//! ```text
//! cargo bench -p haze-lab --bench lightcuts -- [SCENES...] [--build-only] [--max-cut N] [--bound B]
//!     [--ploc-radius R] [--max-cut-vrls N] [-D NAME=VALUE] [--threads N]
//! ```
//!
//! Per scene (default: the validation scenes `hg-box.xml` and `foggy-room.xml`): light-tree
//! build times (3-step agglomerative against median split, 1 and all threads, for 10k, 100k
//! and 1M VRLs traced in the scene), the tree's cost, the bound cut's mean size at 1 spp, and the
//! frame time of `vrl_lightcuts` with 100k VRLs against `vrl` with 10k VRLs. Without scenes
//! also the mean cut size against the VRL count on a scene whose cuts converge (the smoke room).
//! Methods and options come from the engine (`--max-cut`, `--bound` as `haze render` reads
//! them); the builders are called directly, which is what is measured.

use anyhow::Result;
use clap::Parser;
use haze_engine::options::{find, MethodKind};
use haze_engine::Method;
use haze_lab::setup::{self, file_name, load_average, process_cpu_seconds};
use haze_manylight::lighttrace::{paths_for_vrl_count, trace_light_paths, LightTraceSettings};
use haze_manylight::tree::build::{build_agglomerative, build_median_split, BuildSettings};
use haze_manylight::tree::lights::LightSummary;
use haze_manylight::tree::{LightTree, Node};
use haze_manylight::vrl::{Segment, Vrl};
use haze_render::progressive::RenderSettings;
use haze_scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

#[derive(Parser, Debug)]
struct Args {
    /// Scenes to measure (default: the validation scenes shipped with haze).
    scenes: Vec<PathBuf>,
    /// Measure cut sizes up to this many VRLs (larger counts: build time only).
    #[arg(long, default_value_t = 1_000_000)]
    max_cut_vrls: u64,
    /// Most nodes per cut for the cut-size column (a large value shows the sizes the error
    /// criterion alone asks for; default: haze render's).
    #[arg(long)]
    max_cut: Option<String>,
    /// Cluster bound for the cut-size column: paper, conservative or tight (default: haze
    /// render's).
    #[arg(long)]
    bound: Option<String>,
    /// Override a scene `<default>` parameter: -D name=value (e.g. -D res=48 for cheaper cuts).
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Only the build times (no cut sizes, no frame times).
    #[arg(long)]
    build_only: bool,
    /// PLOC search radius of the agglomerative builder (default: the builder's).
    #[arg(long)]
    ploc_radius: Option<usize>,
    #[arg(long)]
    threads: Option<usize>,
    /// Passed by `cargo bench`.
    #[arg(long, hide = true)]
    bench: bool,
}

fn main() -> Result<()> {
    let args = Args::parse();
    setup::set_threads(args.threads)?;
    let scenes = setup::scenes_or_validation(&args.scenes);
    for path in &scenes {
        lightcuts_tables(&args, path)?;
    }
    if args.scenes.is_empty() && !args.build_only {
        cut_growth()?;
    }
    Ok(())
}

/// The VRLs of `n` traced in `scene` (pass 0, seed 0) as the tree sees them, and the light-path
/// count that traces them.
fn vrl_summaries(scene: &Scene, n: u64) -> Result<(u64, Vec<LightSummary>)> {
    let trace = LightTraceSettings::from_max_depth(scene.integrator.max_depth);
    let paths = paths_for_vrl_count(scene, n, 0, &trace)?;
    let set = trace_light_paths(scene, paths, 0, 0, &trace)?;
    let media = haze_manylight::integrators::media_of(scene);
    let lights = set
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
    Ok((paths, lights))
}

/// One scene's build table and frame times.
fn lightcuts_tables(args: &Args, path: &Path) -> Result<()> {
    let scene = setup::load_scene(path, &args.define)?;
    // The tables measure the paper's cut.
    let mut given = vec![("cut", "bound")];
    for (name, value) in [("max_cut", &args.max_cut), ("bound", &args.bound)] {
        if let Some(v) = value {
            given.push((name, v));
        }
    }
    let base = setup::options(MethodKind::VrlLightcuts, &given)?;
    let cut = base.method.lightcuts.bound.cut;
    let bound_name = find("bound").and_then(|b| b.value_in(&base)).unwrap_or_default();
    let defaults = BuildSettings::default();
    let build_settings = BuildSettings { radius: args.ploc_radius.unwrap_or(defaults.radius), ..defaults };
    println!(
        "\n### {} ({}x{}; PLOC radius {}, groups of {}; cuts: bound {}, epsilon {}, max cut {}; load average {})\n",
        file_name(path),
        scene.camera.width,
        scene.camera.height,
        build_settings.radius,
        build_settings.group_size,
        bound_name,
        cut.epsilon,
        cut.max_cut,
        load_average()
    );
    println!("| VRLs | builder | threads | build s | CPU s | ns per N log2 N | tree cost | mean cut (1 spp) | segments at max-cut | cut s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for n in [10_000u64, 100_000, 1_000_000] {
        let (paths, lights) = vrl_summaries(&scene, n)?;
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
                    let paths = paths.to_string();
                    let mut given = given.clone();
                    given.extend([("light_paths", paths.as_str()), ("builder", builder)]);
                    let mut options = setup::options(MethodKind::VrlLightcuts, &given)?;
                    options.method.lightcuts.bound.tree.build = build_settings;
                    let integ = setup::vrl_bound_cut(&scene, &options)?;
                    let settings = RenderSettings { spp: 1, ..Default::default() };
                    let out = haze_render::progressive::render(
                        &scene,
                        &integ,
                        &settings,
                        &AtomicBool::new(false),
                        |_| {},
                    );
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
    if !args.build_only {
        // Frame time: vrl_lightcuts 100k against vrl 10k, 1 spp, all threads.
        let lc_secs = frame_seconds(&scene, MethodKind::VrlLightcuts, "100000")?;
        let vrl_secs = frame_seconds(&scene, MethodKind::Vrl, "10000")?;
        println!(
            "\nframe at 1 spp: vrl_lightcuts (100k VRLs) {lc_secs:.2} s, vrl (10k VRLs) {vrl_secs:.2} s, ratio {:.2}",
            lc_secs / vrl_secs
        );
    }
    Ok(())
}

/// The quantity the agglomerative builder greedily minimises, summed over the tree:
/// `sum_internal I(node) diag(node)^2 / (I(root) diag(root)^2)` (lower is a tighter tree).
fn tree_cost(tree: &LightTree) -> f64 {
    let cost = |n: &Node| n.intensity as f64 * (n.bounds.diagonal() as f64).powi(2);
    let total: f64 = tree.nodes.iter().filter(|n| !n.is_leaf()).map(cost).sum();
    total / cost(&tree.nodes[tree.root as usize]).max(1e-300)
}

/// Seconds of one frame at 1 spp of method `kind` with `vrls` VRLs per pass (its defaults
/// otherwise): its per-pass light tracing and tree build included, its construction (the pilot
/// light-tracing run) not.
fn frame_seconds(scene: &Scene, kind: MethodKind, vrls: &str) -> Result<f64> {
    let options = setup::options(kind, &[("vrls", vrls)])?;
    let method = Method::build(scene, kind, &options.method, 0)?;
    let settings = RenderSettings { spp: 1, ..Default::default() };
    Ok(method.render(scene, &settings, &AtomicBool::new(false), |_| {}).elapsed.as_secs_f64())
}

/// Mean cut size against the number of VRLs (10k, 100k, 1M) on a scene whose cuts converge
/// below an unlimited cap (the smoke room, 32x32, 1 spp, epsilon 0.02), with the paper's and the
/// tight bound: the cut must grow sub-linearly. On the validation scenes every segment stops at
/// the default cap of 1000, which says nothing about growth.
fn cut_growth() -> Result<()> {
    let scene = setup::load_scene(&PathBuf::from("scenes/bench-smoke-room.xml"), &["res=32".to_string()])?;
    println!(
        "\n### mean cut size vs VRLs: bench-smoke-room.xml, 32x32, 1 spp, epsilon 0.02, no cut limit (load average {})\n",
        load_average()
    );
    println!("| VRLs | mean cut, paper | cut/N | render s | mean cut, tight | cut/N | render s |");
    println!("|---|---|---|---|---|---|---|");
    let no_limit = u32::MAX.to_string();
    for n in [10_000u64, 100_000, 1_000_000] {
        let mut row = String::new();
        let mut lights = 0.0;
        let vrls = n.to_string();
        for bound in ["paper", "tight"] {
            let given =
                [("cut", "bound"), ("bound", bound), ("max_cut", no_limit.as_str()), ("vrls", vrls.as_str())];
            let integ = setup::vrl_bound_cut(&scene, &setup::options(MethodKind::VrlLightcuts, &given)?)?;
            let settings = RenderSettings { spp: 1, ..Default::default() };
            let out =
                haze_render::progressive::render(&scene, &integ, &settings, &AtomicBool::new(false), |_| {});
            let (mean, _, _) = integ.cut_statistics();
            lights = integ.lights_per_pass();
            row +=
                &format!(" {mean:.0} | {:.4} | {:.2} |", mean / lights.max(1.0), out.elapsed.as_secs_f64());
        }
        println!("| {lights:.0} |{row}");
    }
    Ok(())
}
