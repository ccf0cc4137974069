//! `.vdb` and `.vol` files holding the same grid render the same image (issue 15): the scenes
//! `tests/data/vdb/smoke-vdb.xml` and `smoke-vol.xml` differ only in the grid file
//! (`smoke.vdb`, written by pyopenvdb, and `smoke.vol`, by `scripts/gen-vdb-testdata.py`'s
//! struct packing; `crates/scene/tests/load_vdb.rs` checks the lookups). Same seed, same
//! samples: the volpath images must be equal pixel for pixel; the negative control, a `.vdb`
//! with one voxel changed, must not be.

use haze_engine::options::{resolve, Spelling};
use haze_engine::{Method, MethodKind};
use haze_render::progressive::RenderSettings;
use haze_scene::{load_file, load_str, LoadOptions, Scene};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

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
    let xml = std::fs::read_to_string(data("smoke-vdb.xml"))
        .unwrap()
        .replace("\"smoke.vdb\"", "\"smoke-changed.vdb\"");
    let changed =
        render(&load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap());
    let n = differing(&vdb, &changed);
    assert!(n > 10, "a changed voxel changed only {n} values");
}
