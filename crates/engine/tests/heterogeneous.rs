//! Heterogeneous media in every method (issue 15): `volpath`, `vrl`, `vpl`, `vrl_lightcuts`
//! and `vpl_lightcuts` (and light tracing for the Python binding) render such a scene (whether
//! correctly: `crates/manylight/tests/integrators.rs`, the smoke scenes against volpath); the
//! lightcut methods' bound cut refuses it.

use haze_engine::lights::trace_lights;
use haze_engine::options::{resolve, Spelling};
use haze_engine::{Method, MethodKind};
use haze_render::progressive::RenderSettings;
use haze_scene::{load_str, LoadOptions, Scene};
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn scene(medium_type: &str) -> Scene {
    let medium = if medium_type == "heterogeneous" {
        r#"<medium id="plume" type="heterogeneous"><volume name="sigma_t" type="constvolume">
             <float name="value" value="2"/></volume></medium>"#
    } else {
        r#"<medium id="plume" type="homogeneous"><float name="sigma_t" value="2"/></medium>"#
    };
    let xml = format!(
        r#"<scene version="3.0.0">
        <sensor type="perspective"><transform name="to_world"><lookat origin="0.5, 0.5, 4" target="0.5, 0.5, 0.5" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <emitter type="point"><point name="position" value="0.5, 3, 0.5"/><rgb name="intensity" value="5"/></emitter>
        {medium}
        <shape type="cube"><bsdf type="null"/><ref name="interior" id="plume"/>
          <transform name="to_world"><scale value="0.5"/><translate value="0.5 0.5 0.5"/></transform></shape>
        </scene>"#
    );
    load_str(&xml, Path::new("plume.xml"), Path::new("."), &LoadOptions::default()).unwrap()
}

#[test]
fn many_light_methods_render_heterogeneous_media() {
    let hetero = scene("heterogeneous");
    for kind in [MethodKind::Vrl, MethodKind::Vpl, MethodKind::VrlLightcuts, MethodKind::VplLightcuts] {
        let options = resolve(kind, &[], Spelling::Flag).unwrap();
        let method =
            Method::build(&hetero, kind, &options.method, 0).unwrap_or_else(|e| panic!("{kind}: {e}"));
        let settings = RenderSettings { spp: 4, ..Default::default() };
        let out = method.render(&hetero, &settings, &AtomicBool::new(false), |_| {});
        assert_eq!(out.invalid_samples, 0, "{kind}");
        let mean = out.film.mean(None);
        assert!(mean.iter().all(|v| v.is_finite()) && mean.iter().any(|v| *v > 0.0), "{kind}");
    }
    let lights = trace_lights(&hetero, 4000, 0, 0).expect("light tracing in a heterogeneous medium");
    assert!(!lights.vrls.is_empty() && !lights.vpls.is_empty());
}

/// The paper's bound cut renders heterogeneous media too (its bound with the medium's largest
/// `sigma_s` and the distance mixture's factor, `docs/theory.md` §12.5): finite, non-negative,
/// not black, for every bound kind.
#[test]
fn bound_cut_renders_heterogeneous_media() {
    let hetero = scene("heterogeneous");
    for kind in [MethodKind::VrlLightcuts, MethodKind::VplLightcuts] {
        for bound in ["paper", "conservative", "tight"] {
            let options = resolve(kind, &[("cut", "bound"), ("bound", bound)], Spelling::Flag).unwrap();
            let method =
                Method::build(&hetero, kind, &options.method, 0).unwrap_or_else(|e| panic!("{kind}: {e}"));
            let settings = RenderSettings { spp: 2, ..Default::default() };
            let out = method.render(&hetero, &settings, &AtomicBool::new(false), |_| {});
            assert_eq!(out.invalid_samples, 0, "{kind} {bound}");
            let mean = out.film.mean(None);
            assert!(mean.iter().all(|v| v.is_finite() && *v >= 0.0), "{kind} {bound}");
            assert!(mean.iter().any(|v| *v > 0.0), "{kind} {bound}");
        }
    }
}

#[test]
fn volpath_renders_heterogeneous_media() {
    let scene = scene("heterogeneous");
    let options = resolve(MethodKind::VolPath, &[], Spelling::Flag).unwrap();
    let method = Method::build(&scene, MethodKind::VolPath, &options.method, 0).unwrap();
    let settings = RenderSettings { spp: 16, ..Default::default() };
    let out = method.render(&scene, &settings, &AtomicBool::new(false), |_| {});
    assert_eq!(out.invalid_samples, 0);
    let mean = out.film.mean(None);
    assert!(mean.iter().all(|v| v.is_finite()) && mean.iter().any(|v| *v > 0.0));
}
