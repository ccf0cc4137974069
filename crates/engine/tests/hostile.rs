//! Front-end settings that used to panic (issue 16): a time budget too large for a `Duration`
//! (or too small for any pass) is an error of the engine's option table, for every front end.

use haze_engine::options::{resolve, Spelling};
use haze_engine::MethodKind;
use haze_scene::{load_str, LoadOptions};
use std::path::Path;

#[test]
fn huge_time_budget_is_an_error_not_a_panic() {
    let e =
        resolve(MethodKind::VolPath, &[("time", "1e20")], Spelling::Flag).expect_err("an error").to_string();
    assert!(e.contains("--time is more than a year"), "{e}");
    let e =
        resolve(MethodKind::Vrl, &[("time", "1e-300")], Spelling::Keyword).expect_err("an error").to_string();
    assert!(e.contains("time is too small a budget"), "{e}");
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"/></scene>"#;
    let scene = load_str(xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    let ok = resolve(MethodKind::VolPath, &[("time", "2")], Spelling::Flag).unwrap();
    assert_eq!(
        ok.render_settings(MethodKind::VolPath, &scene).time_limit,
        Some(std::time::Duration::from_secs(2))
    );
}

/// The many-light methods connect to the pinhole: a thin-lens or orthographic scene is an error
/// naming the sensor for them, and renders with volpath.
#[test]
fn many_light_methods_refuse_cameras_without_a_pinhole() {
    use haze_engine::methods::Method;
    for sensor in [
        r#"<sensor type="thinlens"><float name="aperture_radius" value="0.1"/>"#,
        r#"<sensor type="orthographic">"#,
    ] {
        let xml = format!(
            r#"<scene version="3.0.0">{sensor}<film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
            <emitter type="point"><point name="position" x="0" y="0" z="2"/></emitter></scene>"#
        );
        let scene = load_str(&xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
        let ty = scene.camera.plugin_name();
        for kind in [MethodKind::Vrl, MethodKind::Vpl, MethodKind::VrlLightcuts, MethodKind::VplLightcuts] {
            let options = resolve(kind, &[], Spelling::Flag).unwrap();
            let e = Method::build(&scene, kind, &options.method, 1).err().expect("an error").to_string();
            assert!(e.contains("needs a pinhole camera") && e.contains(ty), "{e}");
        }
        let options = resolve(MethodKind::VolPath, &[], Spelling::Flag).unwrap();
        assert!(Method::build(&scene, MethodKind::VolPath, &options.method, 1).is_ok());
    }
}

/// A spot light with a `texture` renders with volpath only: the many-light methods' light
/// estimators have no texture, so they refuse it by name.
#[test]
fn many_light_methods_refuse_textured_spots() {
    use haze_engine::methods::Method;
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
        <emitter type="spot"><rgb name="texture" value="0.5"/></emitter></scene>"#;
    let scene = load_str(xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    let options = resolve(MethodKind::Vrl, &[], Spelling::Flag).unwrap();
    let e = Method::build(&scene, MethodKind::Vrl, &options.method, 1).err().expect("an error").to_string();
    assert!(e.contains("spot lights with a 'texture'"), "{e}");
    let options = resolve(MethodKind::VolPath, &[], Spelling::Flag).unwrap();
    assert!(Method::build(&scene, MethodKind::VolPath, &options.method, 1).is_ok());
}

/// A `projector` renders with volpath only, like a textured spot: the many-light methods
/// refuse it by name, every one of them.
#[test]
fn many_light_methods_refuse_projectors() {
    use haze_engine::methods::Method;
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
        <emitter type="projector"><float name="fov" value="40"/></emitter></scene>"#;
    let scene = load_str(xml, Path::new("t.xml"), Path::new("."), &LoadOptions::default()).unwrap();
    for kind in [MethodKind::Vrl, MethodKind::Vpl, MethodKind::VrlLightcuts, MethodKind::VplLightcuts] {
        let options = resolve(kind, &[], Spelling::Flag).unwrap();
        let e = Method::build(&scene, kind, &options.method, 1).err().expect("an error").to_string();
        assert!(e.contains("does not support projector emitters (render with volpath)"), "{e}");
    }
    let options = resolve(MethodKind::VolPath, &[], Spelling::Flag).unwrap();
    assert!(Method::build(&scene, MethodKind::VolPath, &options.method, 1).is_ok());
}
