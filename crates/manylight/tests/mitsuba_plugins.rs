//! The many-light methods against Mitsuba 3.9.1 renders of haze's own small scenes
//! (`tests/data/mitsuba-plugins`, 32x32 references at 16384 spp; the README says how they were
//! made), for plugins whose lookups the light and camera walks must get right, as volpath's are
//! checked in `haze-render/tests/mitsuba_plugins.rs`.
//!
//! Statistic as there: per channel-pixel z-scores with haze's pooled per-pixel sample variance
//! standing in for the reference's too, at most 0.5% of the channel-pixels beyond the
//! Sidak-corrected threshold at alpha = 0.01, and the image mean within 5 standard errors.
//! Renders are one sample per pixel per pass, each pass with its own independently seeded
//! light paths, so the per-pixel sample variance is honest; the image mean's standard error
//! comes from the spread of the per-pass image means (the pixels of one pass share its lights;
//! the reference's, from independent pixels at 64x the samples, is neglected).

mod compare_support;

use compare_support::{lightcut_renders, render_passes, settings, Passes};
use haze_manylight::integrators::{VplIntegrator, VrlIntegrator};
use haze_render::image_io::RgbImage;
use haze_scene::bsdf::Bsdf;
use haze_scene::texture::Texture;
use haze_scene::{load_file, LoadOptions, Scene};
use haze_testkit::data::repo_root;
use haze_testkit::ztest::{pool_variance, z_test, ZTestReport};

const REFERENCE_SPP: f32 = 16384.0;
/// Passes of one sample per pixel, and light paths per pass.
const PASSES: u32 = 256;
const PATHS: u64 = 400;

fn load(name: &str) -> Scene {
    let path = repo_root().join(format!("tests/data/mitsuba-plugins/scenes/{name}.xml"));
    load_file(&path, &LoadOptions::default()).expect("scene loads")
}

/// The per-pixel z-test of `passes` against the reference `refs/{name}.exr`, and the image
/// mean's z-score (module docs).
fn against_reference(passes: &Passes, name: &str) -> (ZTestReport, f64) {
    let path = repo_root().join(format!("tests/data/mitsuba-plugins/refs/{name}.exr"));
    let reference = RgbImage::read_exr(&path).expect("reference EXR");
    let film = &passes.film;
    let (w, h) = (reference.width, reference.height);
    assert_eq!((w, h), (film.width as usize, film.height as usize));
    let sample_var = pool_variance(&film.sample_variance(None), w, h, 3);
    let var_mean: Vec<f32> = sample_var.iter().map(|v| v / film.samples as f32).collect();
    let var_ref: Vec<f32> = sample_var.iter().map(|v| v / REFERENCE_SPP).collect();
    let r = z_test(&film.mean(None), &var_mean, &reference.data, &var_ref, 0.01);
    let (mean, var) = passes.mean_and_variance(None);
    let ref_mean = reference.data.iter().map(|&v| v as f64).sum::<f64>() / reference.data.len() as f64;
    (r, (mean - ref_mean) / var.sqrt())
}

fn passed(r: &ZTestReport, mean_z: f64) -> bool {
    r.failed_fraction() <= 0.005 && mean_z.abs() <= 5.0
}

/// `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts` renders of `scene`, named.
fn renders(scene: &Scene) -> Vec<(&'static str, Passes)> {
    let ml = settings(scene, PATHS);
    let vrl = render_passes(scene, &VrlIntegrator::exhaustive(scene, ml.clone(), 1).unwrap(), PASSES, 1, 1);
    let vpl = render_passes(scene, &VplIntegrator::exhaustive(scene, ml, 2).unwrap(), PASSES, 1, 2);
    let (vrl_lc, vpl_lc) =
        lightcut_renders(scene, PATHS, PASSES, haze_manylight::integrators::StochasticCut::default(), [5, 6]);
    vec![("vrl", vrl), ("vpl", vpl), ("vrl_lightcuts", vrl_lc), ("vpl_lightcuts", vpl_lc)]
}

/// Renders `scene` with every many-light method ([`renders`]) and asserts that each passes the
/// rule (module docs) against `refs/{name}.exr`.
fn assert_every_method_matches(scene: &Scene, name: &str) {
    let mut failures = Vec::new();
    for (method, passes) in renders(scene) {
        let (r, mean_z) = against_reference(&passes, name);
        println!("{name}, {method}: {r}; per-pass image-mean z = {mean_z:.2}");
        if !passed(&r, mean_z) {
            failures.push(format!("{method}: {r}; image-mean z = {mean_z:.2}"));
        }
    }
    assert!(failures.is_empty(), "{name} does not match Mitsuba 3:\n{}", failures.join("\n"));
}

/// Mitsuba 3's `mesh_attribute` (per-vertex colours as a diffuse reflectance, per-face weights
/// as a `blendbsdf` weight) looked up at the hit's triangle and barycentrics by every lookup of
/// the many-light methods: gathering points, surface VPLs, light-path and camera-path BSDF
/// samples. Control, which must fail: the vertex colours replaced by their mean.
#[test]
fn mesh_attribute_matches_mitsuba() {
    let scene = load("mesh-attribute");
    assert_every_method_matches(&scene, "mesh-attribute");

    let mut flat = scene;
    let Bsdf::Diffuse { reflectance } = &flat.shapes[0].bsdf else { panic!("a diffuse") };
    assert!(matches!(reflectance, Texture::MeshAttribute(_)), "the vertex colours");
    flat.shapes[0].bsdf = Bsdf::Diffuse { reflectance: Texture::Constant(reflectance.mean()) };
    let vrl = VrlIntegrator::exhaustive(&flat, settings(&flat, PATHS), 1).unwrap();
    let (r, mean_z) = against_reference(&render_passes(&flat, &vrl, PASSES, 1, 1), "mesh-attribute");
    println!("mesh-attribute, colours flattened, vrl: {r}; image-mean z = {mean_z:.2}");
    assert!(!passed(&r, mean_z), "vertex colours replaced by their mean went unnoticed: {r}");
}

/// Mitsuba 3's `area` emitter with a textured `radiance` (a 3x2 bitmap on a quad in a thin fog):
/// light paths start with `L(uv) pi A / p_select` at a point uniform by area, emitters hit by the
/// camera walks are looked up at the hit's uv, next-event estimation at the sampled point's.
/// Control, which must fail: the texture replaced by its mean.
#[test]
fn textured_area_emitter_matches_mitsuba() {
    let scene = load("textured-area");
    assert_every_method_matches(&scene, "textured-area");

    let mut flat = scene;
    let haze_scene::Emitter::Area { radiance, .. } = &mut flat.emitters[0] else { panic!("an area emitter") };
    assert!(matches!(radiance, Texture::Bitmap(_)), "the bitmap");
    *radiance = Texture::Constant(radiance.mean());
    let vrl = VrlIntegrator::exhaustive(&flat, settings(&flat, PATHS), 1).unwrap();
    let (r, mean_z) = against_reference(&render_passes(&flat, &vrl, PASSES, 1, 1), "textured-area");
    println!("textured-area, texture flattened, vrl: {r}; image-mean z = {mean_z:.2}");
    assert!(!passed(&r, mean_z), "the texture replaced by its mean went unnoticed: {r}");
}
