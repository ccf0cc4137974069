//! OpenVDB `.vdb` grids in `gridvolume` (issue 15, haze's extension of Mitsuba 3): the grid of
//! `tests/data/vdb/smoke.vdb` (written by pyopenvdb, `scripts/gen-vdb-testdata.py`) is the
//! medium of `smoke.vol` (written by the same script's own struct packing) wherever it is looked
//! up, a changed voxel is seen, and every bad file or parameter is an error naming the scene
//! file, the line and the element.

use glam::Vec3;
use haze_core::{Rgb, Sampler};
use haze_scene::hetero::Heterogeneous;
use haze_scene::volume::VolumeData;
use haze_scene::{load_file, load_str, LoadOptions, Scene};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    haze_testkit::data::repo_root().join("tests/data/vdb").join(name)
}

fn medium(scene: &Scene) -> Heterogeneous {
    scene.media[0].as_grid().cloned().expect("a heterogeneous medium")
}

/// `smoke-vdb.xml` with its grid file replaced by `file` (a name in `tests/data/vdb`).
fn vdb_scene(file: &str) -> Scene {
    let xml = std::fs::read_to_string(data("smoke-vdb.xml")).unwrap();
    assert!(xml.contains("\"smoke.vdb\""));
    let xml = xml.replace("\"smoke.vdb\"", &format!("\"{file}\""));
    load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap()
}

/// The grid generator's density of voxel `(i, j, k)` (index space), as float32.
fn generated(i: i32, j: i32, k: i32) -> f32 {
    let (a, b, c) = ((i + 3) as f64, (j - 2) as f64, (k - 1) as f64);
    if a < 3.0 && b < 2.0 {
        return 0.0;
    }
    (0.7 + 0.4 * (0.9 * a + 0.3).sin() * (0.7 * b).cos() + 0.1 * c) as f32
}

/// World centre of voxel `(i, j, k)` in `smoke-vdb.xml`: OpenVDB's `translation + voxel * ijk`
/// (translation (-1, 0.5, -0.75), voxel 1/4), then the element's translation by 0.5 along x.
fn centre(i: i32, j: i32, k: i32) -> Vec3 {
    Vec3::new(-1.0 + 0.5, 0.5, -0.75) + 0.25 * Vec3::new(i as f32, j as f32, k as f32)
}

#[test]
fn vdb_and_vol_files_hold_the_same_medium() {
    let from_vdb = medium(&vdb_scene("smoke.vdb"));
    let from_vol = medium(&load_file(&data("smoke-vol.xml"), &LoadOptions::default()).unwrap());
    // The same box, grid and map (the numbers are dyadic, so both routes are exact).
    assert_eq!(from_vdb.sigma_t.bbox, from_vol.sigma_t.bbox);
    assert_eq!(from_vdb.sigma_t.bbox, (Vec3::new(-1.625, 0.625, -0.875), Vec3::new(0.875, 2.625, 0.875)));
    let (VolumeData::Grid { grid: a, .. }, VolumeData::Grid { grid: b, .. }) =
        (&from_vdb.sigma_t.data, &from_vol.sigma_t.data)
    else {
        panic!("grid volumes expected");
    };
    assert_eq!((a.res, &a.data), (b.res, &b.data));
    // Lookups at random points in and around the box agree to float32 precision.
    let (lo, hi) = from_vdb.sigma_t.bbox;
    let mut s = Sampler::from_seed(15);
    for _ in 0..5000 {
        let t = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 1.2 - 0.1;
        let p = lo + (hi - lo) * t;
        let (x, y) = (from_vdb.sigma_t(p)[0], from_vol.sigma_t(p)[0]);
        assert!((x - y).abs() <= 1e-6 * x.abs().max(1.0), "at {p}: {x} (.vdb) vs {y} (.vol)");
    }
    // OpenVDB's placement: a voxel's value at its centre (times the medium's scale, 2), fading
    // to 0 one voxel beyond the active ones.
    for (i, j, k) in [(-3, 7, 1), (4, 2, 5), (2, 5, 3), (0, 3, 2), (-3, 2, 1)] {
        let want = 2.0 * generated(i, j, k);
        let got = from_vdb.sigma_t(centre(i, j, k))[0];
        assert!((got - want).abs() < 1e-5, "voxel ({i}, {j}, {k}): {got}, want {want}");
    }
    assert_eq!(from_vdb.sigma_t(centre(5, 4, 3)), Rgb::splat(0.0));
    assert_eq!(from_vdb.sigma_t(centre(1, 4, 0)), Rgb::splat(0.0));
    let half = from_vdb.sigma_t(centre(4, 4, 3) + Vec3::new(0.125, 0.0, 0.0))[0];
    assert!((half - generated(4, 4, 3)).abs() < 1e-5, "halfway to the background: {half}");
}

/// The negative control: one voxel changed by 0.25 in `smoke-changed.vdb` (voxel (2, 5, 3))
/// changes the lookups around it, and only there.
#[test]
fn a_changed_voxel_is_seen() {
    let good = medium(&vdb_scene("smoke.vdb"));
    let changed = medium(&vdb_scene("smoke-changed.vdb"));
    let d = changed.sigma_t(centre(2, 5, 3))[0] - good.sigma_t(centre(2, 5, 3))[0];
    assert!((d - 0.5).abs() < 1e-5, "{d}");
    assert_eq!(changed.sigma_t(centre(0, 5, 3)), good.sigma_t(centre(0, 5, 3)));
}

/// Filter types apply to `.vdb` grids: nearest reads the voxel whose centre is nearest.
#[test]
fn nearest_filter() {
    let xml = std::fs::read_to_string(data("smoke-vdb.xml")).unwrap().replace(
        "<string name=\"filename\" value=\"smoke.vdb\"/>",
        "<string name=\"filename\" value=\"smoke.vdb\"/><string name=\"filter_type\" value=\"nearest\"/>",
    );
    let h = medium(&load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap());
    let p = centre(2, 5, 3) + Vec3::new(0.12, -0.12, 0.1);
    assert!((h.sigma_t(p)[0] - 2.0 * generated(2, 5, 3)).abs() < 1e-5);
}

/// Active tiles hold their value over all their voxels (`tiles.vdb`: a 16^3 block stored as
/// eight 8^3 tiles, voxel size 1, no translation, and one voxel at (20, 3, 3)).
#[test]
fn tiles_fill_their_voxels() {
    let xml = std::fs::read_to_string(data("smoke-vdb.xml"))
        .unwrap()
        .replace("\"smoke.vdb\"", "\"tiles.vdb\"")
        .replace("<translate x=\"0.5\"/>", "");
    let h = medium(&load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap());
    // The active box (0, 0, 0) - (20, 15, 15), padded by one voxel, in world units.
    assert_eq!(h.sigma_t.bbox, (Vec3::splat(-1.5), Vec3::new(21.5, 16.5, 16.5)));
    let at = |i: f32, j: f32, k: f32| h.sigma_t(Vec3::new(i, j, k))[0] / 2.0;
    // (To float precision: world -> cell goes through the inverse of a scale by 23.)
    let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
    for p in [(0.0, 0.0, 0.0), (7.0, 8.0, 15.0), (15.0, 15.0, 15.0), (3.5, 12.25, 9.0)] {
        assert!(near(at(p.0, p.1, p.2), 0.5), "{p:?}: {}", at(p.0, p.1, p.2));
    }
    assert!(near(at(20.0, 3.0, 3.0), 1.0));
    assert!(near(at(18.0, 3.0, 3.0), 0.0));
    assert!(near(at(16.0, 3.0, 3.0), 0.0));
    assert!(near(at(15.5, 3.0, 3.0), 0.25));
}

/// Non-uniform voxels (1/4, 1/2, 1/8) and translation (1, 2, 3) (`scaled.vdb`, a
/// `ScaleTranslateMap`): each voxel centre holds its value.
#[test]
fn non_uniform_voxels() {
    let xml = std::fs::read_to_string(data("smoke-vdb.xml"))
        .unwrap()
        .replace("\"smoke.vdb\"", "\"scaled.vdb\"")
        .replace("<translate x=\"0.5\"/>", "");
    let h = medium(&load_str(&xml, &data("smoke-vdb.xml"), &data(""), &LoadOptions::default()).unwrap());
    let voxel = Vec3::new(0.25, 0.5, 0.125);
    let world =
        |i: i32, j: i32, k: i32| Vec3::new(1.0, 2.0, 3.0) + voxel * Vec3::new(i as f32, j as f32, k as f32);
    let lo = world(-3, 2, 1) - 1.5 * voxel;
    let hi = world(4, 7, 5) + 1.5 * voxel;
    assert!((h.sigma_t.bbox.0 - lo).abs().max_element() < 1e-6, "{:?}", h.sigma_t.bbox);
    assert!((h.sigma_t.bbox.1 - hi).abs().max_element() < 1e-6, "{:?}", h.sigma_t.bbox);
    for (i, j, k) in [(-3, 7, 1), (4, 2, 5), (2, 5, 3), (0, 3, 2), (1, 2, 4)] {
        let (got, want) = (h.sigma_t(world(i, j, k))[0] / 2.0, generated(i, j, k));
        assert!((got - want).abs() <= 1e-5, "voxel ({i}, {j}, {k}): {got}, want {want}");
    }
}

/// `x` rounded to the nearest half float (IEEE 754 binary16: 11 significant bits, ties to
/// even), for normal half values (magnitudes in [2^-14, 65504]) and zero: the low 13 of float32's
/// 24 significant bits rounded away. Independent of the `half` crate vdb-rs converts with.
fn round_to_half(x: f32) -> f32 {
    let b = x.to_bits();
    f32::from_bits((b + 0xfff + ((b >> 13) & 1)) & !0x1fff)
}

/// Half floats (`half.vdb`: the grid of `smoke.vdb` saved by OpenVDB as 16-bit half floats, with
/// a leaf of inactive background whose empty array of values OpenVDB stores as nothing, not even
/// a length, the case vdb-rs 0.6.0 misread: `vendor/vdb-rs/PATCHES.md`): the dense grid is the
/// float grid's rounded to half precision, cell for cell, and the lookups agree within it.
#[test]
fn half_floats_are_the_float_grid_rounded() {
    assert_eq!(round_to_half(1.0 + 1.0 / 4096.0), 1.0);
    assert_eq!(round_to_half(1.0 + 3.0 / 4096.0), 1.0 + 1.0 / 1024.0);
    assert_eq!(round_to_half(0.1), 0.099975586);
    let float = medium(&vdb_scene("smoke.vdb"));
    let half = medium(&vdb_scene("half.vdb"));
    assert_eq!(half.sigma_t.bbox, float.sigma_t.bbox);
    let (VolumeData::Grid { grid: f, .. }, VolumeData::Grid { grid: h, .. }) =
        (&float.sigma_t.data, &half.sigma_t.data)
    else {
        panic!("grid volumes expected");
    };
    assert_eq!(h.res, f.res);
    let (mut rounded, mut nonzero) = (0, 0);
    for (i, (x, y)) in f.data.iter().zip(&h.data).enumerate() {
        assert_eq!(*y, round_to_half(*x), "cell {i}: {y} (half.vdb), {x} (smoke.vdb)");
        rounded += (x != y) as usize;
        nonzero += (*x != 0.0) as usize;
    }
    // Not the float grid itself: most values lose bits.
    assert!(nonzero == 210 && rounded > nonzero / 2, "{rounded} of {nonzero} values rounded");
    // Lookups (scale 2, densities below 1.3) agree within half precision: 2^-11 relative.
    let (lo, hi) = float.sigma_t.bbox;
    let mut s = Sampler::from_seed(16);
    for _ in 0..2000 {
        let p = lo + (hi - lo) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let (x, y) = (float.sigma_t(p)[0], half.sigma_t(p)[0]);
        assert!((x - y).abs() <= 2.6 / 2048.0, "at {p}: {y} (half) vs {x} (float)");
    }
}

/// A fresh directory for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("haze-vdb-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The volume element of the error tests: starts on line 5 of the scene, its parameters one
/// per line after it (`filename` on line 6).
fn volume(name: &str, file: &str, extra: &str) -> String {
    format!(
        "<volume name=\"{name}\" type=\"gridvolume\">\n<string name=\"filename\" value=\"{file}\"/>\n{extra}\n</volume>"
    )
}

/// Loading a scene whose medium body is `medium` (from line 5) fails with a one-line message
/// that starts with the scene path and contains each of `wants`; `file` is written to
/// `grid.vdb` beside it.
fn fails(name: &str, file: Option<&[u8]>, medium: &str, wants: &[&str]) {
    let d = dir(name);
    if let Some(bytes) = file {
        std::fs::write(d.join("grid.vdb"), bytes).unwrap();
    }
    let xml = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/>\
         <integer name=\"height\" value=\"4\"/></film></sensor>\n<emitter type=\"point\"><point name=\"position\" value=\"0, 5, 0\"/></emitter>\n\
         <medium id=\"smoke\" type=\"heterogeneous\">\n{medium}\n</medium>\n\
         <shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"smoke\"/></shape>\n</scene>\n"
    );
    let path = d.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let msg = match load_file(&path, &LoadOptions::default()) {
        Ok(_) => panic!("{name}: loaded without an error"),
        Err(e) => e.to_string(),
    };
    assert!(msg.starts_with(&path.display().to_string()), "{name}: {msg}");
    assert!(!msg.contains('\n'), "{name}: {msg}");
    for w in wants {
        assert!(msg.contains(w), "{name}: `{msg}` lacks `{w}`");
    }
    std::fs::remove_dir_all(&d).ok();
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

const FILENAME: &str = "<string name=\"filename\">";
const GRID: &str = "<string name=\"grid\">";

#[test]
fn bad_vdb_files() {
    let good = bytes("smoke.vdb");
    let sigma_t = volume("sigma_t", "grid.vdb", "");
    // Truncated anywhere: in the header, in the grid descriptors, in the grid's data.
    for (i, cut) in [10, 40, 200, good.len() / 2, good.len() - 100, good.len() - 1].into_iter().enumerate() {
        fails(
            &format!("truncated-{i}"),
            Some(&good[..cut]),
            &sigma_t,
            &[":6:", FILENAME, "grid.vdb", "truncated .vdb"],
        );
    }
    let mut b = good.clone();
    b[0] = b'X';
    fails("magic", Some(&b), &sigma_t, &[":6:", FILENAME, "not an OpenVDB file"]);
    fails("vol-as-vdb", Some(&bytes("smoke.vol")), &sigma_t, &[":6:", FILENAME, "not an OpenVDB file"]);
    let mut b = good.clone();
    b[8..12].copy_from_slice(&220u32.to_le_bytes());
    fails("old-version", Some(&b), &sigma_t, &[":6:", FILENAME, "file format 220 is older"]);
    fails(
        "no-such-grid",
        Some(&good),
        &volume("sigma_t", "grid.vdb", "<string name=\"grid\" value=\"smoke\"/>"),
        &[":7:", GRID, "no grid named 'smoke': the file has 'density' (float), 'velocity' (vec3s)"],
    );
    fails(
        "default-name-missing",
        Some(&bytes("levelset.vdb")),
        &volume("sigma_t", "grid.vdb", "<string name=\"grid\" value=\"fog\"/>"),
        &[":7:", GRID, "no grid named 'fog': the file has 'density' (float)"],
    );
    fails(
        "vector-grid",
        Some(&good),
        &volume("sigma_t", "grid.vdb", "<string name=\"grid\" value=\"velocity\"/>"),
        &[":7:", GRID, "grid 'velocity' holds vec3s values (Tree_vec3s_5_4_3); haze reads float grids"],
    );
    fails(
        "negative",
        Some(&bytes("negative.vdb")),
        &sigma_t,
        &[":6:", FILENAME, "grid 'density' holds -0.5 at voxel (1, 4, 4)", "'sigma_t' values must be finite"],
    );
    fails("nan", Some(&bytes("nan.vdb")), &sigma_t, &[":6:", FILENAME, "holds NaN at voxel (3, 3, 1)"]);
    fails(
        "albedo-above-one",
        Some(&good),
        &volume("albedo", "grid.vdb", ""),
        &[":6:", FILENAME, "grid 'density' holds 1.", "'albedo' values must be finite and lie in [0, 1]"],
    );
    fails(
        "rotated",
        Some(&bytes("rotated.vdb")),
        &sigma_t,
        &[":6:", FILENAME, "unsupported or corrupt .vdb file (grid 'density')", "AffineMap"],
    );
    fails(
        "level-set",
        Some(&bytes("levelset.vdb")),
        &sigma_t,
        &[":6:", FILENAME, "grid 'density' is a level set"],
    );
    fails(
        "level-set-named",
        Some(&bytes("levelset.vdb")),
        &volume("sigma_t", "grid.vdb", "<string name=\"grid\" value=\"density\"/>"),
        &[":7:", GRID, "grid 'density' is a level set"],
    );
    // A corrupt root node origin (tiles.vdb: one root node, at (0, 0, 0); after the map's name
    // and five vectors, the buffer count, background, tile count and root count): near
    // i32::MAX, its voxel coordinates would overflow.
    let mut b = bytes("tiles.vdb");
    let at = b.windows(15).position(|w| w == b"UniformScaleMap").unwrap() + 15 + 5 * 24 + 16;
    assert_eq!(b[at..at + 12], [0; 12]);
    b[at..at + 4].copy_from_slice(&(i32::MAX - 100).to_le_bytes());
    fails(
        "root-origin",
        Some(&b),
        &sigma_t,
        &[":6:", FILENAME, "corrupt .vdb file (grid 'density'): a root node's origin [2147483547, 0, 0]"],
    );
    // Half floats are read like float grids, and checked like them.
    let mut b = bytes("half.vdb");
    let at = b.windows(6).position(|w| w == b"_HalfF").expect("a half-float grid");
    b[at + 1] = b'X';
    fails(
        "half-type-renamed",
        Some(&b),
        &sigma_t,
        &[":6:", FILENAME, "grid 'density' is a float grid of tree type Tree_float_5_4_3_XalfFloat"],
    );
    fails(
        "too-sparse",
        Some(&bytes("sparse.vdb")),
        &sigma_t,
        &[
            ":6:",
            FILENAME,
            "its active voxels span 4003 x 4003 x 4003 cells with the padding, more than the 536870912",
        ],
    );
    fails(
        "inactive-value",
        Some(&bytes("inactive.vdb")),
        &sigma_t,
        &[":6:", FILENAME, "inactive value 0.3 at voxel (-2, 2, 3)", "fog volumes"],
    );
    fails("missing-file", None, &sigma_t, &[":6:", FILENAME, "grid.vdb' not found"]);
    // A device behind a .vdb name is refused before anything is read.
    #[cfg(unix)]
    {
        let d = dir("device");
        std::os::unix::fs::symlink("/dev/zero", d.join("zero.vdb")).unwrap();
        let xml = format!(
            "<scene version=\"3.0.0\">\n<medium id=\"smoke\" type=\"heterogeneous\">\n{}\n</medium>\n</scene>\n",
            volume("sigma_t", "zero.vdb", "")
        );
        let e = load_str(&xml, Path::new("s.xml"), &d, &LoadOptions::default())
            .err()
            .expect("an error")
            .to_string();
        assert!(e.contains("s.xml:4:") && e.contains(FILENAME) && e.contains("not a regular file"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }
}

#[test]
fn options_that_do_not_apply() {
    let good = bytes("smoke.vdb");
    fails(
        "wrap",
        Some(&good),
        &volume("sigma_t", "grid.vdb", "<string name=\"wrap_mode\" value=\"clamp\"/>"),
        &[":7:", "name=\"wrap_mode\"", "'wrap_mode' does not apply to a .vdb grid"],
    );
    fails(
        "grid-bbox",
        Some(&good),
        &volume("sigma_t", "grid.vdb", "<boolean name=\"use_grid_bbox\" value=\"false\"/>"),
        &[":7:", "name=\"use_grid_bbox\"", "'use_grid_bbox' does not apply to a .vdb grid"],
    );
    // `grid` on a .vol file.
    let d = dir("vol-grid");
    std::fs::copy(data("smoke.vol"), d.join("grid.vol")).unwrap();
    let xml = format!(
        "<scene version=\"3.0.0\">\n<medium id=\"smoke\" type=\"heterogeneous\">\n{}\n</medium>\n</scene>\n",
        volume("sigma_t", "grid.vol", "<string name=\"grid\" value=\"density\"/>")
    );
    let e =
        load_str(&xml, Path::new("s.xml"), &d, &LoadOptions::default()).err().expect("an error").to_string();
    for want in ["s.xml:5:", GRID, "'grid' applies only to OpenVDB (.vdb) files"] {
        assert!(e.contains(want), "`{e}` lacks `{want}`");
    }
    std::fs::remove_dir_all(&d).ok();
}
