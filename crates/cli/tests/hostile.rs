//! `haze render` on hostile command lines (issue 16): no panic, no abort, no clobbered file.
//! Each case is a clear `error:` and exit code 1, before anything large is allocated.

use std::path::PathBuf;

mod common;

use common::{assert_fails_with as failure, haze, s, tmp};

/// A small valid scene in the temporary folder.
fn scene(name: &str, film: u32) -> PathBuf {
    let path = tmp(name);
    std::fs::write(
        &path,
        format!(
            r#"<scene version="3.0.0">
            <sensor type="perspective"><film type="hdrfilm">
                <integer name="width" value="{film}"/><integer name="height" value="{film}"/>
            </film></sensor>
            <shape type="sphere"/><emitter type="constant"/>
        </scene>"#
        ),
    )
    .unwrap();
    path
}

#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let sc = scene("out.xml", 4);
    let before = std::fs::read(&sc).unwrap();
    failure(&haze(&["render", s(&sc), "-o", s(&sc), "--spp", "1", "-q"]), "give one of those extensions");
    assert_eq!(std::fs::read(&sc).unwrap(), before, "the scene file changed");
    for bad in ["x.jpg", "x.txt"] {
        failure(
            &haze(&["render", s(&sc), "-o", s(&tmp(bad)), "--spp", "1", "-q"]),
            "give one of those extensions",
        );
        assert!(!tmp(bad).exists());
    }
    let exr = tmp("same.exr");
    failure(
        &haze(&["render", s(&sc), "-o", s(&exr), "--variance-out", s(&exr), "--spp", "1", "-q"]),
        "--variance-out",
    );
    // An input with an image extension: an environment map the scene reads.
    let env = tmp("env.exr");
    assert!(haze(&["render", s(&sc), "-o", s(&env), "--spp", "1", "-q"]).status.success());
    let env_scene = tmp("env.xml");
    std::fs::write(
        &env_scene,
        r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
            <integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
            <emitter type="envmap"><string name="filename" value="env.exr"/></emitter></scene>"#,
    )
    .unwrap();
    let env_before = std::fs::read(&env).unwrap();
    failure(&haze(&["render", s(&env_scene), "-o", s(&env), "--spp", "1", "-q"]), "would overwrite an input");
    assert_eq!(std::fs::read(&env).unwrap(), env_before);
}

/// `-o x.png` writes the PNG preview only (the EXR used to be written under that name, then
/// overwritten by the preview).
#[test]
fn png_output_writes_only_the_png() {
    let sc = scene("png.xml", 4);
    let png = tmp("only.png");
    let o = haze(&["render", s(&sc), "-o", s(&png), "--spp", "1", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(!png.with_extension("exr").exists());
}

#[test]
fn budgets_threads_films_and_lights_are_bounded() {
    let sc = scene("limits.xml", 4);
    let out = tmp("limits.exr");
    let o = s(&out);
    failure(&haze(&["render", s(&sc), "-o", o, "--time", "1e20", "-q"]), "more than a year");
    failure(&haze(&["render", s(&sc), "-o", o, "--time", "1e-300", "-q"]), "too small a budget");
    failure(&haze(&["reference", s(&sc), "-o", o, "--time", "1e20"]), "more than a year");
    failure(
        &haze(&["render", s(&sc), "-o", o, "--spp", "1", "--threads", "100000", "-q"]),
        "--threads 100000",
    );
    let big = scene("big.xml", 65536);
    failure(&haze(&["render", s(&big), "-o", o, "--spp", "1", "-q"]), "too large for memory");
    for option in ["--vrls", "--light-paths"] {
        let args =
            ["render", s(&sc), "-o", o, "--spp", "1", "--integrator", "vrl", option, "10000000000", "-q"];
        failure(&haze(&args), &format!("{option} 10000000000"));
    }
}
