//! `haze reference`, `haze compare` and its HTML report end to end on a tiny fog scene (16x12
//! pixels, a few hundred lights), in a few seconds.

use haze_render::image_io::RgbImage;
use std::path::PathBuf;

mod common;

use common::{assert_fails_with, assert_success as check, haze, stderr, tmp_dir};

/// A closed black box of isotropic fog lit by a small area light (the spirit of bench-smoke-room).
const TINY_SCENE: &str = r#"<scene version="3.0.0">
  <integrator type="volpath"><integer name="max_depth" value="20"/></integrator>
  <medium type="homogeneous" id="fog">
    <rgb name="albedo" value="0.9, 0.9, 0.9"/>
    <float name="sigma_t" value="0.8"/>
    <phase type="isotropic"/>
  </medium>
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 1, 1.8" target="0.2, 1.5, -1" up="0, 1, 0"/></transform>
    <ref id="fog"/>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film>
  </sensor>
  <shape type="cube">
    <transform name="to_world"><scale x="2" y="1.25" z="2"/><translate y="1.25"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <ref name="interior" id="fog"/>
  </shape>
  <shape type="rectangle">
    <transform name="to_world">
      <scale value="0.25"/><rotate x="1" angle="90"/><translate x="0.5" y="2.45" z="-0.5"/>
    </transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="40, 40, 40"/></emitter>
    <ref name="exterior" id="fog"/>
  </shape>
</scene>
"#;

/// A folder of its own for test `name` with [`TINY_SCENE`] in it; returns both.
fn tiny_scene(name: &str) -> (PathBuf, PathBuf) {
    let dir = tmp_dir(name);
    let scene = dir.join("tiny.xml");
    std::fs::write(&scene, TINY_SCENE).unwrap();
    (dir, scene)
}

#[test]
fn compare_writes_table_images_and_report() {
    let (dir, scene) = tiny_scene("report");
    let s = |p: &PathBuf| p.to_str().unwrap().to_string();
    let reference = dir.join("ref.exr");
    check(&haze(&["reference", &s(&scene), "-o", &s(&reference), "--time", "0.5"]), "haze reference");
    let r = RgbImage::read_exr(&reference).unwrap();
    assert_eq!((r.width, r.height), (16, 12));

    let (out, report) = (dir.join("img"), dir.join("report"));
    let methods = ["volpath", "vrl:200", "vrl_lightcuts:1k,cut_size=2", "vpl_lightcuts:2k"];
    let mut args = vec!["compare".to_string(), s(&scene), "--reference".into(), s(&reference)];
    args.extend(["--time", "0.3", "-o"].map(String::from));
    args.extend([s(&out), "--report".into(), s(&report), "--lights-plot".into(), s(&dir.join("lights.svg"))]);
    for m in methods {
        args.extend(["--method".to_string(), m.to_string()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = haze(&args);
    let table = check(&o, "haze compare");
    // Each method at its own auto spp per pass: the lightcut methods' rule gives 64 (its
    // clamp) at 16x12 pixels, the others 1.
    let err = stderr(&o);
    for (m, spp) in
        [("volpath", 1), ("vrl:200", 1), ("vrl_lightcuts:1000,cut_size=2", 64), ("vpl_lightcuts:2000", 64)]
    {
        let want = format!("{m}: rendering for 0.3 s, spp per pass {spp} (auto)");
        assert!(err.lines().any(|l| l == want), "`{want}` not in\n{err}");
    }

    assert!(table
        .starts_with("| method | lights | time (s) | passes | RMSE | SMAPE (%) | relMSE | mean cut size |"));
    assert_eq!(table.lines().count(), 2 + methods.len(), "{table}");
    let stems = ["volpath", "vrl-200", "vrl_lightcuts-1000_cut_size2", "vpl_lightcuts-2000"];
    for (m, stem) in methods.iter().zip(stems) {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| {} |", m.replace("1k", "1000").replace("2k", "2000"))));
        let row = row.unwrap_or_else(|| panic!("no row for {m} in\n{table}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let rmse: f64 = cells[5].parse().unwrap();
        assert!(rmse.is_finite() && rmse > 0.0, "{row}");
        assert_eq!(cells[8] != "-", m.contains("lightcuts"), "mean cut size only for lightcuts: {row}");
        let img = RgbImage::read_exr(&out.join(format!("{stem}.exr"))).unwrap();
        assert!(img.data.iter().all(|v| v.is_finite()));
        for suffix in [".png", "_error.png", "_crop.png"] {
            assert!(report.join(format!("{stem}{suffix}")).is_file(), "{stem}{suffix}");
        }
    }

    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    for needle in
        ["reference.png", "colorbar.png", "convergence_rmse.svg", "vrl_lightcuts-1000_cut_size2_error.png"]
    {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
    let svg = std::fs::read_to_string(report.join("convergence_rmse.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("vrl:200"), "the plot has a legend");
    // Axis labels: plotters writes tick labels as <text> elements; a log axis without a power of its
    // base in range would have none (see report::log_base).
    let labels = svg.matches("text-anchor=\"end\"").count();
    assert!(labels >= 2, "the RMSE axis has tick labels: {labels}");
    let lights = std::fs::read_to_string(dir.join("lights.svg")).unwrap();
    for family in ["vrl_lightcuts", "vpl_lightcuts", "lights per pass"] {
        assert!(lights.contains(family), "the RMSE-vs-lights plot names {family}");
    }
    assert!(!lights.contains(">volpath<"), "volpath has no light count");
    assert!(html.contains("document.body.dataset.images"), "the page marks whether its images loaded");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn compare_without_reference_renders_one_first() {
    let (dir, scene) = tiny_scene("auto-ref");
    let out = dir.join("out");
    let (scene, out_s) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let args =
        ["compare", scene, "--time", "0.2", "--reference-time", "0.4", "--method", "volpath", "-o", out_s];
    let o = haze(&args);
    let table = check(&o, "haze compare without --reference");
    let err = stderr(&o);
    assert!(err.contains("no --reference given: rendering one with volpath for 0.4 s"), "{err}");
    let reference = RgbImage::read_exr(&out.join("reference.exr")).expect("the reference is kept");
    assert_eq!((reference.width, reference.height), (16, 12));
    let volpath = RgbImage::read_exr(&out.join("volpath.exr")).unwrap();
    assert_ne!(reference.data, volpath.data, "the reference uses its own seed");
    assert_eq!(table.lines().count(), 3, "{table}");
    let o = haze(&[
        "compare",
        scene,
        "--reference",
        "r.exr",
        "--reference-time",
        "1",
        "--time",
        "1",
        "--method",
        "volpath",
    ]);
    assert_fails_with(&o, "--reference-time only applies");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_method_specs_and_missing_reference_are_clear_errors() {
    let (dir, scene) = tiny_scene("errors");
    let scene = scene.to_str().unwrap();
    let o = haze(&["compare", scene, "--reference", "nope.exr", "--time", "1", "--method", "vrl:ten"]);
    // A clap value parser's error: exit code 2, `error: invalid value ...`.
    let err = stderr(&o);
    assert!(o.status.code() == Some(2) && err.contains("got 'ten'") && !err.contains("panicked"), "{err}");
    let o = haze(&["compare", scene, "--reference", "nope.exr", "--time", "1", "--method", "volpath"]);
    assert_fails_with(&o, "nope.exr");
    std::fs::remove_dir_all(&dir).ok();
}
