//! What the lab's benchmarks and examples share: scenes by path, integrators built by method
//! name and options through `haze-engine`, and the state of the machine a table was measured on.

use anyhow::{anyhow, bail, Context, Result};
use haze_engine::options::{resolve, MethodKind, Options, Spelling};
use haze_engine::Method;
use haze_manylight::integrators::{BoundCut, LightcutsIntegrator, StochasticCut, Vrls};
use haze_scene::{LoadOptions, Scene};
use std::path::{Path, PathBuf};

/// The repository's root (this crate is `crates/lab` in it). `cargo bench` runs a benchmark in
/// the crate's directory; scene paths given relative to the root are found there too.
pub fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `path` as given, or relative to the repository's root when it names no file as given.
pub fn scene_path(path: &Path) -> PathBuf {
    if path.is_relative() && !path.exists() {
        repository_root().join(path)
    } else {
        path.to_path_buf()
    }
}

/// `scenes`, or without any the validation scenes `hg-box.xml` and `foggy-room.xml`.
pub fn scenes_or_validation(scenes: &[PathBuf]) -> Vec<PathBuf> {
    if scenes.is_empty() {
        ["hg-box.xml", "foggy-room.xml"]
            .map(|s| PathBuf::from("tests/data/validation/scenes").join(s))
            .to_vec()
    } else {
        scenes.to_vec()
    }
}

/// Loads the scene at `path` (see [`scene_path`]) with `NAME=VALUE` overrides of its
/// `<default>` parameters.
pub fn load_scene(path: &Path, defines: &[String]) -> Result<Scene> {
    let defines = defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
            _ => bail!("-D expects NAME=VALUE, got '{d}'"),
        })
        .collect::<Result<Vec<_>>>()?;
    let path = scene_path(path);
    haze_scene::load_file(&path, &LoadOptions { defines }).with_context(|| path.display().to_string())
}

/// The options of method `kind` from `given` (name, text) pairs, as `haze render` resolves them.
pub fn options(kind: MethodKind, given: &[(&str, &str)]) -> Result<Options> {
    resolve(kind, given, Spelling::Flag)
}

/// `vrl_lightcuts` with the stochastic cut for `scene` with `options` (seed 0), built by the
/// engine.
pub fn vrl_lightcuts(scene: &Scene, options: &Options) -> Result<LightcutsIntegrator<Vrls, StochasticCut>> {
    match Method::build(scene, MethodKind::VrlLightcuts, &options.method, 0)? {
        Method::VrlLightcuts(i) => Ok(i),
        _ => Err(anyhow!("vrl_lightcuts with cut=stochastic expected (options give another cut)")),
    }
}

/// `vrl_lightcuts` with the bound cut (`cut=bound` in `options`) for `scene` (seed 0), built by
/// the engine.
pub fn vrl_bound_cut(scene: &Scene, options: &Options) -> Result<LightcutsIntegrator<Vrls, BoundCut>> {
    match Method::build(scene, MethodKind::VrlLightcuts, &options.method, 0)? {
        Method::VrlBoundCut(i) => Ok(i),
        _ => Err(anyhow!("vrl_lightcuts with cut=bound expected (options give another cut)")),
    }
}

/// The file name of `path`, for table rows.
pub fn file_name(path: &Path) -> String {
    path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The 1, 5 and 15 minute load averages (`/proc/loadavg`), for a table's heading: another load
/// on the cores shows there.
pub fn load_average() -> String {
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
}

/// CPU time (user + system) of this process so far, from `/proc/self/stat` (Linux; 10 ms
/// ticks). Beside wall time it shows how much of a timing another load on the cores took.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Median, least and largest of `v` (not empty).
pub fn spread(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[0], s[s.len() - 1])
}

/// Sets the global thread pool's size (`None`: rayon's default, one thread per core).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new().num_threads(t.max(1)).build_global()?;
    }
    Ok(())
}
