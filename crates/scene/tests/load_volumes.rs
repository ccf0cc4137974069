//! The `heterogeneous` medium and its volumes (`gridvolume`, `constvolume`): what loads, with
//! Mitsuba 3's semantics, and every bad grid or parameter, message by message (file, line,
//! element and what is wrong).

use glam::Vec3;
use haze_core::Rgb;
use haze_scene::volume::Grid;
use haze_scene::{load_file, LoadOptions, Scene};
use std::path::{Path, PathBuf};

/// A fresh directory for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("haze-volumes-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A grid whose cell `(x, y, z)` channel `c` holds `f(x, y, z, c)`.
fn grid(res: [u32; 3], channels: u32, f: impl Fn(u32, u32, u32, u32) -> f32) -> Grid {
    Grid::from_fn(res, channels, (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 4.0, 3.0)), f)
}

/// A scene with a medium whose body is `medium` (line 4 onwards), written to `d/scene.xml`.
fn scene_file(d: &Path, medium: &str) -> PathBuf {
    let xml = format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film></sensor><emitter type=\"point\"><point name=\"position\" value=\"0, 5, 0\"/></emitter>\n\
         <medium id=\"smoke\" type=\"heterogeneous\">\n{medium}\n</medium>\n\
         <shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"smoke\"/></shape>\n</scene>\n"
    );
    let path = d.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

fn load(d: &Path, medium: &str) -> Result<Scene, String> {
    let path = scene_file(d, medium);
    load_file(&path, &LoadOptions::default()).map_err(|e| e.to_string())
}

/// The load fails with a one-line message that starts with the scene path and contains each
/// of `wants`.
fn fails(name: &str, vol: Option<&[u8]>, medium: &str, wants: &[&str]) {
    let d = dir(name);
    if let Some(bytes) = vol {
        std::fs::write(d.join("grid.vol"), bytes).unwrap();
    }
    let msg = match load(&d, medium) {
        Ok(_) => panic!("{name}: loaded without an error"),
        Err(m) => m,
    };
    assert!(msg.starts_with(&d.join("scene.xml").display().to_string()), "{name}: {msg}");
    assert!(!msg.contains('\n'), "{name}: {msg}");
    for w in wants {
        assert!(msg.contains(w), "{name}: `{msg}` lacks `{w}`");
    }
    std::fs::remove_dir_all(&d).ok();
}

const SIGMA_T_GRID: &str = "<volume name=\"sigma_t\" type=\"gridvolume\">\n<string name=\"filename\" value=\"grid.vol\"/>\n</volume>";

#[test]
fn grid_medium_loads_with_mitsuba_semantics() {
    let d = dir("loads");
    let g = grid([4, 2, 2], 1, |x, _, _, _| x as f32);
    std::fs::write(d.join("grid.vol"), g.to_vol_bytes()).unwrap();
    let rgb = grid([2, 2, 2], 3, |_, _, _, c| 0.2 + 0.3 * c as f32);
    std::fs::write(d.join("albedo.vol"), rgb.to_vol_bytes()).unwrap();
    let scene = load(
        &d,
        "<float name=\"scale\" value=\"2\"/>\n\
         <volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" value=\"grid.vol\"/>\n\
         <string name=\"filter_type\" value=\"nearest\"/><string name=\"wrap_mode\" value=\"repeat\"/>\n\
         <transform name=\"to_world\"><scale value=\"2\"/><translate x=\"-1\"/></transform></volume>\n\
         <volume name=\"albedo\" type=\"gridvolume\"><string name=\"filename\" value=\"albedo.vol\"/>\n\
         <boolean name=\"raw\" value=\"true\"/></volume>\n<phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase>",
    )
    .unwrap();
    let m = &scene.media[0];
    let h = m.as_grid().expect("heterogeneous");
    // to_world: scale 2 then translate x by -1: the unit cube -> [-1, 1] x [0, 2] x [0, 2].
    assert_eq!(h.sigma_t.bbox, (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 2.0)));
    // Nearest: world x = -1 + 2 (i + 0.5) / 4 is in cell i; times scale 2.
    for i in 0..4 {
        let p = Vec3::new(-1.0 + 2.0 * (i as f32 + 0.5) / 4.0, 1.0, 1.0);
        assert_eq!(h.sigma_t(p), Rgb::splat(2.0 * i as f32));
    }
    // Repeat: one grid width further along x is the same cell.
    assert_eq!(h.sigma_t(Vec3::new(1.0 + 2.0 * 1.5 / 4.0, 1.0, 1.0)), Rgb::splat(2.0));
    assert_eq!(h.albedo.eval(Vec3::splat(0.5)), Rgb::new(0.2, 0.5, 0.8));
    // Its bounds: the global majorant and the albedo's maximum.
    assert!(m.majorant()[0] >= 6.0 && m.majorant()[0] < 6.001, "{}", m.majorant());
    assert_eq!(m.albedo_bound(), Rgb::new(0.2, 0.5, 0.8));
    assert_eq!(m.phase, haze_core::Phase::HenyeyGreenstein { g: 0.5 });
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn grid_bbox_constvolume_and_plain_values() {
    let d = dir("bbox");
    std::fs::write(d.join("grid.vol"), grid([2, 2, 2], 1, |_, _, _, _| 1.0).to_vol_bytes()).unwrap();
    let scene = load(
        &d,
        "<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" value=\"grid.vol\"/>\n\
         <boolean name=\"use_grid_bbox\" value=\"true\"/></volume>",
    )
    .unwrap();
    // The file's box, (-1, 0, 2) - (1, 4, 3).
    let h = scene.media[0].as_grid().cloned().unwrap();
    assert_eq!(h.sigma_t.bbox, (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 4.0, 3.0)));
    // A constvolume's to_world only moves its box; a plain RGB is a constant over the unit cube.
    let scene = load(
        &d,
        "<volume name=\"sigma_t\" type=\"constvolume\"><rgb name=\"value\" value=\"0.5, 0.4, 0.3\"/>\n\
         <transform name=\"to_world\"><translate value=\"-0.5 -0.5 -0.5\"/></transform></volume>\n\
         <rgb name=\"albedo\" value=\"0, 0.5, 1\"/>",
    )
    .unwrap();
    let h = scene.media[0].as_grid().cloned().unwrap();
    assert_eq!(h.sigma_t.bbox, (Vec3::splat(-0.5), Vec3::splat(0.5)));
    assert_eq!(h.sigma_t(Vec3::splat(7.0)), Rgb::new(0.5, 0.4, 0.3));
    assert_eq!(h.albedo.bbox, (Vec3::ZERO, Vec3::ONE));
    // The grid file is one of the scene's files (what distributed renders ship to workers).
    let path = scene_file(
        &d,
        "<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" value=\"grid.vol\"/></volume>",
    );
    let (_, files) = haze_scene::load_file_with_sources(&path, &LoadOptions::default()).unwrap();
    assert!(files.iter().any(|f| f.ends_with("grid.vol")), "{files:?}");
    let scene = load(&d, "<float name=\"sigma_t\" value=\"3\"/>").unwrap();
    let h = scene.media[0].as_grid().cloned().unwrap();
    assert_eq!(h.sigma_t.bbox, (Vec3::ZERO, Vec3::ONE));
    assert_eq!(h.albedo.eval(Vec3::ZERO), Rgb::splat(0.75));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_grid_files() {
    let good = grid([3, 2, 2], 1, |x, y, z, _| (x + y + z) as f32).to_vol_bytes();
    let filename = "<string name=\"filename\">";
    fails(
        "truncated",
        Some(&good[..good.len() - 8]),
        SIGMA_T_GRID,
        &[":5:", filename, "grid.vol", "truncated .vol file", "3 x 2 x 2 cells x 1 channel(s)"],
    );
    fails(
        "short-header",
        Some(&good[..30]),
        SIGMA_T_GRID,
        &[":5:", filename, "truncated .vol header: 30 bytes"],
    );
    let mut b = good.clone();
    b[0..3].copy_from_slice(b"BOX");
    fails("magic", Some(&b), SIGMA_T_GRID, &[":5:", filename, "not a .vol file"]);
    let mut b = good.clone();
    b[3] = 4;
    fails("version", Some(&b), SIGMA_T_GRID, &[":5:", filename, "unsupported .vol version 4"]);
    let mut b = good.clone();
    b[4..8].copy_from_slice(&3i32.to_le_bytes());
    fails("encoding", Some(&b), SIGMA_T_GRID, &[":5:", filename, "unsupported .vol encoding 3"]);
    let mut b = good.clone();
    b[20..24].copy_from_slice(&6i32.to_le_bytes());
    fails("channels", Some(&b), SIGMA_T_GRID, &[":5:", filename, "channel count 6"]);
    let mut b = good.clone();
    b[12..16].copy_from_slice(&(-2i32).to_le_bytes());
    fails("resolution", Some(&b), SIGMA_T_GRID, &[":5:", filename, "invalid .vol resolution 3 x -2 x 2"]);
    let mut b = good.clone();
    b.extend_from_slice(&[0; 12]);
    fails("trailing", Some(&b), SIGMA_T_GRID, &[":5:", filename, "12 bytes after"]);
    let mut g = grid([3, 2, 2], 1, |x, y, z, _| (x + y + z) as f32);
    g.data[5] = -0.25;
    fails(
        "negative",
        Some(&g.to_vol_bytes()),
        SIGMA_T_GRID,
        &[":5:", filename, "cell (2, 1, 0) channel 0 holds -0.25", "'sigma_t' values must be finite"],
    );
    g.data[5] = f32::NAN;
    fails("nan", Some(&g.to_vol_bytes()), SIGMA_T_GRID, &[":5:", filename, "holds NaN"]);
    g.data[5] = f32::INFINITY;
    fails("inf", Some(&g.to_vol_bytes()), SIGMA_T_GRID, &[":5:", filename, "holds inf"]);
    let albedo = grid([2, 1, 1], 3, |x, _, _, c| if x == 1 && c == 2 { 1.5 } else { 0.5 });
    fails(
        "albedo-above-one",
        Some(&albedo.to_vol_bytes()),
        "<volume name=\"albedo\" type=\"gridvolume\">\n<string name=\"filename\" value=\"grid.vol\"/>\n</volume>",
        &[":5:", filename, "cell (1, 0, 0) channel 2 holds 1.5", "'albedo' values must be finite and lie in [0, 1]"],
    );
    fails("missing-file", None, SIGMA_T_GRID, &[":5:", filename, "grid.vol' not found"]);
    #[cfg(unix)]
    fails(
        "device",
        None,
        "<volume name=\"sigma_t\" type=\"gridvolume\">\n<string name=\"filename\" value=\"/dev/zero\"/>\n</volume>",
        &[":5:", filename, "'/dev/zero': not a regular file"],
    );
    let mut flat = grid([2, 2, 2], 1, |_, _, _, _| 1.0);
    flat.bbox = (Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0));
    fails(
        "empty-bbox",
        Some(&flat.to_vol_bytes()),
        "<volume name=\"sigma_t\" type=\"gridvolume\">\n<string name=\"filename\" value=\"grid.vol\"/>\n\
         <boolean name=\"use_grid_bbox\" value=\"true\"/>\n</volume>",
        &[":6:", "name=\"use_grid_bbox\"", "empty or invalid bounding box"],
    );
}

#[test]
fn bad_volume_and_medium_parameters() {
    let good = grid([2, 2, 2], 1, |_, _, _, _| 1.0).to_vol_bytes();
    let g = Some(good.as_slice());
    let vol = |extra: &str| {
        format!("<volume name=\"sigma_t\" type=\"gridvolume\">\n<string name=\"filename\" value=\"grid.vol\"/>\n{extra}\n</volume>")
    };
    fails(
        "no-filename",
        g,
        "<volume name=\"sigma_t\" type=\"gridvolume\">\n</volume>",
        &[":4:", "type=\"gridvolume\"", "missing parameter 'filename'"],
    );
    fails(
        "filter",
        g,
        &vol("<string name=\"filter_type\" value=\"cubic\"/>"),
        &[":6:", "name=\"filter_type\"", "invalid filter_type 'cubic'"],
    );
    fails(
        "wrap",
        g,
        &vol("<string name=\"wrap_mode\" value=\"border\"/>"),
        &[":6:", "name=\"wrap_mode\"", "invalid wrap_mode 'border'"],
    );
    fails(
        "unused",
        g,
        &vol("<float name=\"max_value\" value=\"3\"/>"),
        &[":6:", "unused parameter 'max_value'", "gridvolume"],
    );
    fails(
        "singular",
        g,
        &vol("<transform name=\"to_world\"><scale x=\"0\"/></transform>"),
        &[":6:", "name=\"to_world\"", "finite and invertible"],
    );
    fails(
        "other-name",
        g,
        "<volume name=\"density\" type=\"constvolume\"/>",
        &[":4:", "does not take a volume 'density'"],
    );
    fails(
        "twice",
        g,
        &format!("{}\n<float name=\"sigma_t\" value=\"2\"/>", SIGMA_T_GRID),
        &[":4:", "'sigma_t' is given more than once"],
    );
    fails(
        "negative-const",
        g,
        "<float name=\"sigma_t\" value=\"-1\"/>",
        &[":4:", "name=\"sigma_t\"", "must lie in [0"],
    );
    fails(
        "const-albedo",
        g,
        "<volume name=\"albedo\" type=\"constvolume\">\n<rgb name=\"value\" value=\"0.5, 1.2, 0\"/>\n</volume>",
        &[":5:", "name=\"value\"", "'value' of the 'albedo' volume must lie in [0, 1]"],
    );
    fails(
        "scale",
        g,
        "<float name=\"scale\" value=\"-2\"/>",
        &[":4:", "name=\"scale\"", "'scale' must not be negative"],
    );
    fails(
        "sample-emitters",
        g,
        "<boolean name=\"sample_emitters\" value=\"false\"/>",
        &[":4:", "unsupported: sample_emitters=false"],
    );
    fails(
        "volume-type",
        g,
        "<volume name=\"sigma_t\" type=\"openvdb\"/>",
        &[":4:", "unsupported volume type 'openvdb'", "gridvolume"],
    );
}
