//! `.vdb` and `.vol` files holding the same grid render the same image (issue 15): the scenes
//! `tests/data/vdb/smoke-vdb.xml` and `smoke-vol.xml` differ only in the grid file
//! (`smoke.vdb`, written by pyopenvdb, and `smoke.vol`, by `scripts/gen-vdb-testdata.py`'s
//! struct packing; `crates/scene/tests/load_vdb.rs` checks the lookups). Same seed, same
//! samples: the volpath images must be equal pixel for pixel; the negative control, a `.vdb`
//! with one voxel changed, must not be. The same grid saved as half floats (`half.vdb`) renders
//! nearly the same image.

use haze_engine::options::{resolve, Spelling};
use haze_engine::{Method, MethodKind};
use haze_render::progressive::RenderSettings;
use haze_scene::{load_file, load_str, LoadOptions, Scene};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// `smoke-vdb.xml` with its grid file replaced by `file` (a name in `tests/data/vdb`).
fn vdb_scene(file: &str) -> Scene {
    let xml = std::fs::read_to_string(data("smoke-vdb.xml"))
        .unwrap()
        .replace("\"smoke.vdb\"", &format!("\"{file}\""));
    load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap()
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/vdb").join(name)
}

fn render(scene: &Scene) -> Vec<f32> {
    let options = resolve(MethodKind::VolPath, &[], Spelling::Flag).unwrap();
    let method = Method::build(scene, MethodKind::VolPath, &options.method, 0).unwrap();
    let settings = RenderSettings { spp: 4, seed: 7, ..Default::default() };
    let out = method.render(scene, &settings, &AtomicBool::new(false), |_| {});
    assert_eq!(out.invalid_samples, 0);
    out.film.mean(None)
}

/// Pixels that differ by more than 1e-6 relative.
fn differing(a: &[f32], b: &[f32]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).filter(|(x, y)| (*x - *y).abs() > 1e-6 * x.abs().max(y.abs()).max(1e-3)).count()
}

#[test]
fn vdb_and_vol_render_the_same_image() {
    let vdb = render(&load_file(&data("smoke-vdb.xml"), &LoadOptions::default()).unwrap());
    let vol = render(&load_file(&data("smoke-vol.xml"), &LoadOptions::default()).unwrap());
    // The image is not trivially empty: the smoke scatters light into most pixels.
    let lit = vdb.iter().filter(|v| **v > 1e-4).count();
    assert!(lit > vdb.len() / 3, "{lit} of {} values lit", vdb.len());
    // Bit for bit: after loading, both scenes hold the same grid, box and transform (the
    // numbers are dyadic), so every random decision is the same.
    assert_eq!(differing(&vdb, &vol), 0, "the .vdb and .vol renders differ");
    assert!(vdb == vol, "the .vdb and .vol renders are close but not bit-identical");
    // Negative control: one voxel of 240 changed by 0.25 changes the image.
    let changed = render(&vdb_scene("smoke-changed.vdb"));
    let n = differing(&vdb, &changed);
    assert!(n > 10, "a changed voxel changed only {n} values");
}

/// The mean absolute difference of two images over the mean of the first.
fn relative_difference(a: &[f32], b: &[f32]) -> f64 {
    let mean = a.iter().map(|v| *v as f64).sum::<f64>();
    a.iter().zip(b).map(|(x, y)| (*x as f64 - *y as f64).abs()).sum::<f64>() / mean
}

/// The grid of `smoke.vdb` saved as half floats (`half.vdb`, read through the patched vdb-rs:
/// `vendor/vdb-rs/PATCHES.md`) renders nearly the same image: its densities are the float
/// grid's rounded to 2^-11 relative (`crates/scene/tests/load_vdb.rs`), so with the same seed the
/// images differ by little (0.16% of the image mean on average per value when written), far less
/// than the negative control's, one voxel changed by 0.25 (3.1%).
#[test]
fn half_float_vdb_renders_nearly_the_same_image() {
    let float = render(&load_file(&data("smoke-vdb.xml"), &LoadOptions::default()).unwrap());
    let half = render(&vdb_scene("half.vdb"));
    let changed = render(&vdb_scene("smoke-changed.vdb"));
    let (d_half, d_changed) = (relative_difference(&float, &half), relative_difference(&float, &changed));
    assert!(d_half > 0.0, "the half-float image equals the float one: not the half grid?");
    assert!(d_half < 0.005, "half floats: mean difference {d_half} of the image mean");
    // The gate can fail: the changed voxel fails it.
    assert!(d_changed > 0.005, "the changed voxel passes the gate: {d_changed}");
}
