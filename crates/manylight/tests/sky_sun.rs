//! Sky and sun in the many-light integrators (issue 36): `vrl`, `vpl`, `vrl_lightcuts` and
//! `vpl_lightcuts` against `volpath`, every component by the per-pixel z-test and the image-mean
//! z from the per-pass spread (`compare_support`, as in `integrators.rs`), on small scenes lit
//! only by environment and directional emitters (`tests/data/sky-sun/`):
//! (a) `sky-fog.xml`, a fog box on a diffuse floor under a `constant` sky;
//! (b) `envmap-fog.xml`, the same under an `envmap` with a small, bright sun, and (b') with the
//! map turned so that the sun lies below the floor's horizon;
//! (c) `sun-window.xml`, a `directional` sun through the window of a closed room of fog;
//! (d) `cloud-sky.xml`, a heterogeneous cloud under a `directional` sun and a `constant` sky;
//! and the path-length rule on `sky-glass.xml` (the sky-lit fog with a glass ball before it) at
//! `max_depth` 2, 3, 6 and -1: each many-light method must estimate exactly volpath's sum. The
//! reference itself is checked too: `volpath` against Mitsuba 3 on (a)-(d)
//! (`tests/data/sky-sun/refs`, its README says how they were made).
//!
//! Each test first checks that `volpath` renders the scene (finite, not black, the expected
//! components present), then compares the many-light methods with it. The negative control of
//! the scene tests (a)-(c): `vrl_lightcuts`'s image scaled by 0.9 (what a light-tracing
//! normalisation, such as the disk's pdf, off by 10% does to the light-traced components) must
//! fail the same test on `multiple` or `surface`, so the test has the power to see such an
//! error. The budgets (16 x 16 pixels, 400 passes of 1 spp) are what that takes: at 48 passes
//! the image mean of `surface` in (c) had a standard error of 4% and a 10% error went unnoticed.
//! In the cloud (d) the many-light estimates are heavy-tailed (multiple scattering's per-pass
//! image mean has a standard error of 6-8% at 40k light paths, with a spot light standing in for
//! the sun), so there the control is printed, not asserted: (d) catches errors of about 30%.

mod compare_support;

use compare_support::*;
use haze_render::Component;
use haze_scene::{load_file, LoadOptions, Scene};
use haze_testkit::ztest::{pool_variance, z_test};

/// Scene `name` of `tests/data/sky-sun/` at `res x res` pixels with the `-D` overrides `defines`.
fn load(name: &str, res: u32, defines: &[(&str, &str)]) -> Scene {
    let path = haze_testkit::data::repo_root().join("tests/data/sky-sun").join(name);
    let mut all = vec![("res".to_string(), res.to_string())];
    all.extend(defines.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    load_file(&path, &LoadOptions { defines: all }).unwrap_or_else(|e| panic!("{e}"))
}

/// `volpath`'s reference of `scene`, checked: finite (`render_passes` asserts no invalid
/// sample), every component non-negative, the whole image not black and each component of
/// `present` contributing.
fn checked_reference(scene: &Scene, label: &str, present: &[Component]) -> Passes {
    let reference = volpath_reference(scene);
    for comp in Component::ALL {
        let mean = reference.film.mean(Some(comp));
        assert!(mean.iter().all(|v| v.is_finite() && *v >= 0.0), "{label}volpath {}", comp.name());
    }
    let total = reference.film.image_mean(None);
    println!("{label}volpath image mean {total:?}");
    assert!(total.iter().all(|v| *v > 0.0), "{label}volpath renders black: {total:?}");
    for &comp in present {
        let m = reference.film.image_mean(Some(comp));
        assert!(m.iter().all(|v| *v > 0.0), "{label}volpath has no {} light: {m:?}", comp.name());
    }
    reference
}

/// The negative control: `vrl_lightcuts` (`paths` light paths, `passes` passes) with its image
/// scaled by 0.9 must fail the comparison with `reference` on `multiple` or `surface` (asserted
/// when `assert`).
fn check_control(scene: &Scene, reference: &Passes, label: &str, paths: u64, passes: u32, assert: bool) {
    let (mut wrong, _) =
        lightcut_renders(scene, paths, passes, haze_manylight::integrators::StochasticCut::default(), [5, 6]);
    wrong.film.scale(0.9);
    for m in &mut wrong.pass_means {
        for v in m.iter_mut().flatten() {
            *v *= 0.9;
        }
    }
    let mut caught = Vec::new();
    for comp in [Component::Multiple, Component::Surface] {
        let (r, mean_z) = compare(&wrong, reference, comp);
        println!("{label}vrl_lightcuts x 0.9, {}: {r}; image-mean z = {mean_z:.2}", comp.name());
        if r.failed_fraction() > 0.01 || mean_z.abs() > 5.0 {
            caught.push(comp.name());
        }
    }
    if assert {
        assert!(!caught.is_empty(), "{label}: vrl_lightcuts 10% too dark went unnoticed");
    }
}

/// The whole check of one scene: the reference, the four many-light methods against it and the
/// negative control (asserted when `control`, else printed).
fn check_scene(scene: &Scene, label: &str, present: &[Component], paths: u64, passes: u32, control: bool) {
    let reference = checked_reference(scene, label, present);
    check_methods_against(scene, &reference, label, paths, passes, true);
    check_control(scene, &reference, label, paths, passes, control);
}

/// `volpath` on (a)-(d) at 16 x 16 pixels (4096 spp) against Mitsuba 3's 32768-spp
/// references: the per-pixel z-test with haze's pooled per-sample variance over its samples and,
/// for the reference's noise, over 32768 (plus a relative floor); at most 0.5% of the channel-pixels failing and the
/// image mean within 5 standard errors. `names` are the scenes' files.
fn check_volpath_against_mitsuba(names: &[&str]) {
    use haze_render::image_io::RgbImage;
    use haze_render::progressive::{render, RenderSettings};
    use haze_render::VolPath;
    let dir = haze_testkit::data::repo_root().join("tests/data/sky-sun");
    let mut failures = Vec::new();
    for name in names {
        let scene = load(&format!("{name}.xml"), 16, &[]);
        let reference = RgbImage::read_exr(&dir.join(format!("refs/{name}.exr"))).expect("reference EXR");
        let settings = RenderSettings { spp: 4096, seed: 7, spp_per_pass: 64, ..Default::default() };
        let out =
            render(&scene, &VolPath::from_spec(&scene.integrator), &settings, &Default::default(), |_| {});
        assert_eq!(out.invalid_samples, 0, "{name}: NaN/Inf samples");
        let var = pool_variance(&out.film.sample_variance(None), 16, 16, 3);
        let var_mean: Vec<f32> = var.iter().map(|v| v / 4096.0).collect();
        // Mitsuba's RGB variant returns the `constant` sky's radiance 0.6, 0.8, 1 as 0.5998,
        // 0.8002, 1 (its emitter spectra's round trip): a floor of 5e-4 relative on the
        // reference's error, so that the sky's noiseless pixels compare.
        let var_ref: Vec<f32> =
            var.iter().zip(&reference.data).map(|(v, r)| v / 32768.0 + (5e-4 * r).powi(2)).collect();
        let r = z_test(&out.film.mean(None), &var_mean, &reference.data, &var_ref, 0.01);
        println!("{name}: volpath vs Mitsuba 3: {r}");
        if r.failed_fraction() > 0.005 || r.mean_z.abs() > 5.0 {
            failures.push(format!("{name}: {r}"));
        }
    }
    assert!(failures.is_empty(), "volpath vs Mitsuba 3:\n{}", failures.join("\n"));
}

#[test]
fn volpath_matches_mitsuba_under_sky_and_envmap() {
    check_volpath_against_mitsuba(&["sky-fog", "envmap-fog"]);
}

/// Needs the `directional` emitter in the loader and in volpath.
#[test]
fn volpath_matches_mitsuba_under_the_sun() {
    check_volpath_against_mitsuba(&["sun-window", "cloud-sky"]);
}

/// (a) A constant sky only: light paths start on the disk covering the scene's bounding sphere,
/// in the fog (VRLs) and on the floor (surface VPLs, which light the fog from below).
#[test]
fn constant_sky_fog_matches_volpath() {
    let scene = load("sky-fog.xml", 16, &[]);
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    check_scene(&scene, "sky-fog ", &present, 100, 400, true);
}

/// (b) An environment map with a sun of one bright pixel: light directions from the map's
/// importance table, so most light paths carry the sun.
#[test]
fn envmap_sun_fog_matches_volpath() {
    let scene = load("envmap-fog.xml", 16, &[]);
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    check_scene(&scene, "envmap-fog ", &present, 100, 400, true);
}

/// (b') The same map turned upside down: the sun lies below the floor's horizon, so the floor
/// and the fog above it are lit by the dim part of the map only, which next-event estimation
/// (by the map's importance table, nearly all on the sun) seldom samples: direct light at the
/// gathering points comes mostly from the continuation's BSDF sample, weighted by MIS against
/// next-event estimation (docs/theory.md §2.1, "Direct light at `S` by MIS"). With those hits
/// not counted `surface` comes out 70% too dark and fails on 23-43% of its channel-pixels
/// (checked by hand). (Counted with weight 1 they go unnoticed here: for the dim directions the
/// BSDF's weight is nearly 1 anyway.)
#[test]
fn envmap_sun_below_horizon_matches_volpath() {
    let scene = load("envmap-fog.xml", 16, &[("env_rotation", "180")]);
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    let reference = checked_reference(&scene, "envmap-below ", &present);
    check_methods_against(&scene, &reference, "envmap-below ", 100, 400, true);
}

/// (c) A directional sun through a window into a closed room of fog: the only light enters by
/// the window (a few percent of the disk's paths), a shaft through the fog and a lit patch on
/// the floor.
#[test]
fn directional_sun_through_window_matches_volpath() {
    let scene = load("sun-window.xml", 16, &[]);
    let present = [Component::Single, Component::Multiple, Component::Surface];
    check_scene(&scene, "sun-window ", &present, 300, 400, true);
}

/// (d) A heterogeneous cloud under a directional sun and a constant sky (delta-tracked light
/// paths from both, VRLs carrying their transmittance).
#[test]
fn cloud_under_sun_and_sky_matches_volpath() {
    let scene = load("cloud-sky.xml", 16, &[]);
    let present = [Component::Emitted, Component::Single, Component::Multiple];
    check_scene(&scene, "cloud-sky ", &present, 100, 400, false);
}

/// The path-length rule: at `max_depth` (Mitsuba's: the longest path has `max_depth` segments;
/// 2 is single scattering and direct light only) every many-light method estimates the sum
/// `volpath` computes, on the sky-lit fog seen through a glass ball (camera-side delta events
/// count towards the depth as in volpath).
fn check_max_depth(max_depth: i32, present: &[Component]) {
    let depth = max_depth.to_string();
    let scene = load("sky-glass.xml", 16, &[("max_depth", &depth)]);
    assert_eq!(scene.integrator.max_depth, max_depth);
    let label = format!("sky-glass max_depth {max_depth} ");
    let reference = checked_reference(&scene, &label, present);
    check_methods_against(&scene, &reference, &label, 100, 200, true);
}

#[test]
fn max_depth_2_matches_volpath() {
    check_max_depth(2, &[Component::Emitted, Component::Single, Component::Surface]);
}

#[test]
fn max_depth_3_matches_volpath() {
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    check_max_depth(3, &present);
}

#[test]
fn max_depth_6_matches_volpath() {
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    check_max_depth(6, &present);
}

#[test]
fn max_depth_unlimited_matches_volpath() {
    let present = [Component::Emitted, Component::Single, Component::Multiple, Component::Surface];
    check_max_depth(-1, &present);
}

/// The path-length rule with an area light (no environment), so that a failure here is the
/// rule's and not the sky's: `tests/data/glass-ball-room.xml` (the hazy room with a glass ball
/// of `integrators.rs`, whose test covers `max_depth` -1) at 16 x 12 pixels and `max_depth` 2,
/// 3 and 6. Before issue 36's rule the many-light methods failed it at every one of them
/// (`vrl_lightcuts`, per-pass image-mean z): at 2 with multiple scattering volpath does not
/// count (0.0179 vs 0, z +43) and `surface` 3.2x too bright (z +24); at 3 `surface` 13% too
/// bright (z +5.0); at 6 `multiple` 10% (z -4.5) and `surface` 23% (z -15) too dark.
fn check_max_depth_area_light(max_depth: i32, present: &[Component]) {
    let path = haze_testkit::data::repo_root().join("tests/data/glass-ball-room.xml");
    let defines = [("res", "16"), ("res_y", "12")].map(|(k, v)| (k.to_string(), v.to_string()));
    let mut scene =
        load_file(&path, &LoadOptions { defines: defines.to_vec() }).unwrap_or_else(|e| panic!("{e}"));
    scene.integrator.max_depth = max_depth;
    let label = format!("glass-ball-room max_depth {max_depth} ");
    let reference = checked_reference(&scene, &label, present);
    check_methods_against(&scene, &reference, &label, 40, 200, true);
}

#[test]
fn area_light_max_depth_2_matches_volpath() {
    check_max_depth_area_light(2, &[Component::Single, Component::Surface]);
}

#[test]
fn area_light_max_depth_3_matches_volpath() {
    check_max_depth_area_light(3, &[Component::Single, Component::Multiple, Component::Surface]);
}

#[test]
fn area_light_max_depth_6_matches_volpath() {
    check_max_depth_area_light(6, &[Component::Single, Component::Multiple, Component::Surface]);
}
