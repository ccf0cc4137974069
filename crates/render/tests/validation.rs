//! volpath against Mitsuba 3 references on the validation scenes
//! (`tests/data/validation`, 16384 spp Mitsuba 3.9.1 `volpath` renders).
//!
//! Statistic: per channel-pixel `z = (haze - ref) / sqrt(var_haze/n + var_ref)`, with haze's own
//! per-pixel sample variance and, for the reference's noise, the same per-sample variance over
//! the reference's 16384 samples (both render the same estimator family, so haze's variance is a
//! fair stand-in). Pass: at most 0.5% of channel-pixels beyond the Sidak-corrected threshold at
//! alpha = 0.01, and the image-mean z-score within 5. Variances are pooled over 3x3
//! neighbourhoods (`pool_variance`) so that edge pixels whose few samples missed the medium do
//! not report a zero variance (the Mitsuba render-test rule, with the
//! failing fraction relaxed from 0.25% because 128 spp variance estimates are noisy in fog).
//! The mean z-score gate is what catches a small global error such as sigma_t off by 10%.

use haze_render::image_io::RgbImage;
use haze_render::progressive::{render_volpath, RenderSettings};
use haze_scene::{load_file, LoadOptions, Scene};
use haze_testkit::data::{validation, validation_scene};
use haze_testkit::ztest::{pool_variance, z_test, ZTestReport};

const REFERENCE_SPP: f32 = 16384.0;

fn load(name: &str) -> Scene {
    load_file(&validation_scene(name), &LoadOptions::default()).expect("validation scene loads")
}

fn compare(scene: &Scene, name: &str, spp: u32, seed: u64) -> ZTestReport {
    let settings = RenderSettings { spp, seed, spp_per_pass: 8, ..Default::default() };
    let out = render_volpath(scene, &settings);
    assert_eq!(out.invalid_samples, 0, "NaN/Inf samples");
    let reference = RgbImage::read_exr(&validation(&format!("refs/{name}.exr"))).expect("reference EXR");
    assert_eq!(
        (reference.width, reference.height),
        (scene.camera.width as usize, scene.camera.height as usize)
    );
    let mean = out.film.mean(None);
    let (w, h) = (reference.width, reference.height);
    let sample_var = pool_variance(&out.film.sample_variance(None), w, h, 3);
    let var_mean: Vec<f32> = sample_var.iter().map(|v| v / spp as f32).collect();
    let var_ref: Vec<f32> = sample_var.iter().map(|v| v / REFERENCE_SPP).collect();
    z_test(&mean, &var_mean, &reference.data, &var_ref, 0.01)
}

fn check(name: &str, spp: u32) {
    let scene = load(name);
    let r = compare(&scene, name, spp, 1);
    println!("{name}: {r}");
    assert!(r.passed(0.005, 5.0), "{name} does not match the Mitsuba 3 reference: {r}");
}

/// The same comparison must reject a medium whose extinction is 10% too high.
fn check_detects_sigma_t_scaled(name: &str, spp: u32) {
    let mut scene = load(name);
    for m in &mut scene.media {
        let haze_scene::MediumKind::Homogeneous(h) = &mut m.kind else {
            panic!("{name}: a homogeneous medium")
        };
        h.sigma_t *= 1.1;
    }
    let r = compare(&scene, name, spp, 1);
    println!("{name} with sigma_t x 1.1: {r}");
    assert!(!r.passed(0.005, 5.0), "{name}: a 10% error in sigma_t went unnoticed: {r}");
}

#[test]
fn hg_box_matches_mitsuba() {
    check("hg-box", 256);
}

#[test]
fn foggy_room_matches_mitsuba() {
    check("foggy-room", 128);
}

#[test]
fn hg_box_rejects_wrong_sigma_t() {
    check_detects_sigma_t_scaled("hg-box", 256);
}

#[test]
fn foggy_room_rejects_wrong_sigma_t() {
    check_detects_sigma_t_scaled("foggy-room", 128);
}
