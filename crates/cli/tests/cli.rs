//! The `haze` binary end to end: bad input gives a clear error and a non-zero exit (never a
//! panic), images are reproducible across thread counts, components sum to the full image, and
//! no output contains NaN or Inf.

use haze_render::image_io::RgbImage;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;

use common::{assert_clean_failure, assert_fails_with, data, haze, repo, s, stderr, tmp, HAZE};

#[test]
fn every_bad_scene_is_a_clear_error_not_a_panic() {
    let corpus = repo("tests/bad-scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&corpus)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 20, "corpus has {} scenes", scenes.len());
    let out = tmp("bad.exr");
    for scene in &scenes {
        let o =
            haze(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--spp", "1", "--quiet"]);
        let err = assert_clean_failure(&o, &scene.display().to_string());
        assert!(err.contains(&scene.display().to_string()), "error does not name the file: {err}");
        let expected = std::fs::read_to_string(scene.with_extension("expected")).unwrap();
        for want in expected.lines().filter(|l| !l.is_empty()) {
            assert!(err.contains(want), "{}: `{err}` lacks `{want}`", scene.display());
        }
    }
    assert!(!out.exists(), "a failed load must not write an image");
}

#[test]
fn bad_command_line_values_are_clear_errors() {
    let scene = data("validation/scenes/hg-box.xml");
    let s = scene.to_str().unwrap();
    let out = tmp("x.exr");
    let o = out.to_str().unwrap();
    for (args, want) in [
        (vec!["render", s, "-o", o, "--spp", "0"], "--spp must be a positive integer"),
        (vec!["render", s, "-o", o, "--time", "-2"], "--time must be a positive number"),
        (vec!["render", s, "-o", o, "--time", "NaN"], "--time must be a positive number"),
        (vec!["render", s, "-o", o, "--threads", "0", "--spp", "1"], "--threads must be at least 1"),
        (vec!["render", s, "-o", o, "--integrator", "bdpt", "--spp", "1"], "unknown integrator 'bdpt'"),
        (vec!["render", s, "-o", o, "-D", "novalue", "--spp", "1"], "-D expects NAME=VALUE"),
        (vec!["render", "/nonexistent/scene.xml", "-o", o], "/nonexistent/scene.xml"),
    ] {
        let e = assert_clean_failure(&haze(&args), &args.join(" "));
        assert!(e.contains(want), "{}: `{e}` lacks `{want}`", args.join(" "));
    }
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--quiet"];
    args.extend_from_slice(extra);
    let o = haze(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

#[test]
fn same_seed_gives_the_same_image_for_any_thread_count() {
    let scene = data("validation/scenes/foggy-room.xml");
    let (a, b, c) = (tmp("t1.exr"), tmp("t2.exr"), tmp("seed2.exr"));
    render(&scene, &a, &["--spp", "4", "--seed", "7", "--threads", "1"]);
    render(&scene, &b, &["--spp", "4", "--seed", "7", "--threads", "2"]);
    render(&scene, &c, &["--spp", "4", "--seed", "8", "--threads", "2"]);
    let (ia, ib, ic) =
        (RgbImage::read_exr(&a).unwrap(), RgbImage::read_exr(&b).unwrap(), RgbImage::read_exr(&c).unwrap());
    assert!(ia.data == ib.data, "thread count changed the image");
    assert!(ia.data != ic.data, "the seed had no effect");
    assert!(a.with_extension("png").exists());
}

#[test]
fn components_sum_to_the_full_image_and_are_finite() {
    for name in ["foggy-room", "hg-box"] {
        let scene = data(&format!("validation/scenes/{name}.xml"));
        let out = tmp(&format!("{name}.exr"));
        let var = tmp(&format!("{name}-var.exr"));
        render(&scene, &out, &["--spp", "4", "--components", "--variance-out", var.to_str().unwrap()]);
        let full = RgbImage::read_exr(&out).unwrap();
        let mut sum = vec![0.0f64; full.data.len()];
        for comp in ["emitted", "single", "multiple", "surface"] {
            let p = out.with_file_name(format!("{name}_{comp}.exr"));
            let img = RgbImage::read_exr(&p).unwrap_or_else(|e| panic!("{comp}: {e}"));
            assert!(
                img.data.iter().all(|v| v.is_finite() && *v >= 0.0),
                "{comp} has NaN, Inf or negative values"
            );
            for (s, v) in sum.iter_mut().zip(&img.data) {
                *s += *v as f64;
            }
        }
        assert!(full.data.iter().all(|v| v.is_finite()));
        for (i, (s, f)) in sum.iter().zip(&full.data).enumerate() {
            assert!(
                (s - *f as f64).abs() <= 1e-5 * (1.0 + f.abs() as f64),
                "{name} value {i}: components sum {s}, full {f}"
            );
        }
        // Both scenes have black surfaces only, so the multiple-scattering part must be non-zero
        // and the surface part zero.
        let multiple = RgbImage::read_exr(&out.with_file_name(format!("{name}_multiple.exr"))).unwrap();
        assert!(multiple.data.iter().any(|v| *v > 0.0));
        let surface = RgbImage::read_exr(&out.with_file_name(format!("{name}_surface.exr"))).unwrap();
        assert!(surface.data.iter().all(|v| *v == 0.0));
        let v = RgbImage::read_exr(&var).unwrap();
        assert!(v.data.iter().all(|x| x.is_finite() && *x >= 0.0));
    }
}

#[test]
fn time_budget_renders_progressively() {
    let scene = data("validation/scenes/hg-box.xml");
    let out = tmp("timed.exr");
    let o = render(&scene, &out, &["--time", "0.5"]);
    let err = stderr(&o);
    assert!(err.contains("passes"), "{err}");
    assert!(RgbImage::read_exr(&out).unwrap().data.iter().any(|v| *v > 0.0));
}

/// Ctrl-C (SIGINT) finishes the current pass and writes the image of the passes done so far.
#[test]
fn interrupt_writes_the_passes_finished_so_far() {
    let scene = data("validation/scenes/foggy-room.xml");
    let out = tmp("interrupted.exr");
    let child = Command::new(HAZE)
        .args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--time", "60", "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "exit {:?}: {err}", o.status.code());
    assert!(err.contains("interrupted"), "{err}");
    let img = RgbImage::read_exr(&out).unwrap();
    assert!(img.data.iter().all(|v| v.is_finite()) && img.data.iter().any(|v| *v > 0.0));
}

/// `--cut-image`: a heat map with the image's width, the map's rows plus the legend strip,
/// varying cut sizes; and a clear error for an integrator without cuts.
#[test]
fn cut_image_is_a_heat_map_of_the_image_size() {
    let scene = repo("scenes/bench-smoke-room.xml");
    // The bound cut maps its size (0 to --max-cut), the stochastic cut the largest cut node's
    // share of the importance (0 to 1).
    for (cut, scale) in
        [("bound", "colour scale 0 to 1000 linear"), ("stochastic", "colour scale 0 to 1 linear")]
    {
        let (out, map) = (tmp("cut.exr"), tmp(&format!("cut-map-{cut}.png")));
        let _ = std::fs::remove_file(&map);
        let o = render(
            &scene,
            &out,
            &[
                "-D",
                "res=24",
                "-D",
                "res_y=24",
                "--spp",
                "1",
                "--integrator",
                "vrl_lightcuts",
                "--cut",
                cut,
                if cut == "stochastic" { "--cut-size" } else { "--max-cut" },
                if cut == "stochastic" { "4" } else { "1000" },
                "--vrls",
                "3000",
                "--cut-image",
                map.to_str().unwrap(),
            ],
        );
        assert!(stderr(&o).contains(scale), "{}", stderr(&o));
        let img = image::open(&map).expect("cut image readable").to_rgb8();
        // 24 rows of map and a legend strip of max(24 / 8, 4) = 4 rows.
        assert_eq!((img.width(), img.height()), (24, 28));
        let map_pixels: Vec<[u8; 3]> =
            (0..24).flat_map(|y| (0..24).map(move |x| (x, y))).map(|(x, y)| img.get_pixel(x, y).0).collect();
        let distinct: std::collections::HashSet<[u8; 3]> = map_pixels.iter().copied().collect();
        assert!(distinct.len() > 3, "{cut}: the map does not vary: {distinct:?}");
        // The legend runs from the scale's bottom colour (left) to its top colour (right).
        assert_eq!(img.get_pixel(0, 27).0, [0, 0, 4]);
        assert_eq!(img.get_pixel(23, 27).0, [252, 255, 164]);
    }
    let (out, map) = (tmp("cut.exr"), tmp("cut-map.png"));
    let args =
        ["render", s(&scene), "-o", s(&out), "-D", "res=8", "--integrator", "vrl", "--cut-image", s(&map)];
    assert_fails_with(&haze(&args), "--cut-image does not apply to vrl");
}

/// `--integrator` replaces a scene integrator haze does not have (Mitsuba's `direct` here),
/// with one note on stderr naming it; without `--integrator` the scene is an error naming the
/// file and line of its `<integrator>`.
#[test]
fn integrator_flag_replaces_an_unsupported_scene_integrator() {
    let dir = common::tmp_dir("replaced-integrator");
    let scene = dir.join("direct.xml");
    std::fs::write(
        &scene,
        r#"<scene version="3.0.0">
  <integrator type="direct"><integer name="emitter_samples" value="2"/></integrator>
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <shape type="sphere"><emitter type="area"/></shape>
</scene>"#,
    )
    .unwrap();
    let out = dir.join("out.exr");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "render".to_string(),
            s(&scene).to_string(),
            "-o".into(),
            s(&out).to_string(),
            "-q".into(),
            "--spp".into(),
            "1".into(),
        ];
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let run = |extra: &[&'static str]| Command::new(HAZE).args(args(extra)).output().unwrap();
    let o = run(&[]);
    assert_fails_with(
        &o,
        &format!(
            "{}:2:3: <integrator type=\"direct\">: unsupported integrator type 'direct'",
            scene.display()
        ),
    );
    assert!(!out.exists());
    let o = run(&["--integrator", "volpath"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let notes: Vec<&str> = err.lines().filter(|l| l.starts_with("note: ")).collect();
    assert_eq!(notes.len(), 1, "{err}");
    assert!(
        notes[0].contains("'volpath' replaces the scene's <integrator type=\"direct\">")
            && notes[0].contains(":2)"),
        "{err}"
    );
    assert!(out.exists());
}
