//! Mitsuba 3 conformance on scenes we did not write (issue 8): the 8 homogeneous-media scenes and
//! the 4 heterogeneous-media scenes (issue 15) of Mitsuba 3's render-test suite and two public
//! Mitsuba 3 scenes, read from `$HAZE_PEERS_DIR` or
//! `../shared/peers/` (never copied into the repository; `scripts/fetch-peers.sh` downloads
//! them), rendered with haze's `volpath` and judged by `check.py`'s rule, reimplemented here;
//! `load.rs` checks that they load as their READMEs describe. Every test that reads peer data
//! is in this one test binary, so that a clone without the data prints the skip line once.
//!
//! The rule (`peers/mitsuba3-media-tests/check.py`, after Mitsuba 3's
//! `test_renders.py`), per pixel and per CIE XYZ channel (linear sRGB converted with Mitsuba's
//! matrix):
//! `z = |test - ref| / sqrt(var / spp)`, two-sided, at level 0.01 Sidak-corrected over the
//! `W * H` pixels; PASS iff at most 0.25% of the channel-pixels fail (17 of 6912 at 48x48), and
//! (check.py's `--mean-z-limit 5`) every channel's image-mean z-score is within 5.
//! `var` is the reference's per-sample variance floored at 1e-4 (the driver's rule). haze's
//! estimator is not Mitsuba's (filter importance sampling, hero-channel spectral MIS), so as
//! check.py does when given the tested renderer's variance (`TEST_VAR --test-var-rgb`), the
//! verdict uses `max(ref_var, test_var)`, where `test_var` is haze's per-sample RGB variance
//! turned into an upper bound of the XYZ variance, `(sum_j M_ij sqrt(v_j))^2`. The driver-rule
//! verdict (reference variance alone) is printed as well.
//!
//! Sample count: the driver's `2_000_000 / (W * H)`, i.e. 868 spp at 48x48, exactly the spp the
//! rule is calibrated for; the same budget gives 78 spp for the 160x160 Cornell box and 1953
//! spp for the 32x32 teapot. Each render is ~2M camera samples, a few seconds in release.
//!
//! The two other peer scenes have no variance image; there the reference variance is haze's own
//! per-sample variance (pooled over 3x3 pixels so that a pixel whose few samples missed a rare
//! path does not report zero), the reference's own noise `var / ref_spp` is added (check.py's
//! `--ref-spp`), and the rule is otherwise the same.

use haze_render::progressive::{render, RenderSettings};
use haze_render::VolPath;
use haze_scene::{load_file, LoadOptions};
use haze_testkit::data::peers_or_skip;
use rule::{judge, RefVariance, Verdict};
use std::io::Write;
use std::path::PathBuf;

mod load;
mod rule;
use std::sync::atomic::AtomicBool;

const SAMPLE_BUDGET: usize = 2_000_000;

/// A file of the peer data, or `None` (with the skip line) when the data is absent.
fn peers(rel: &str) -> Option<PathBuf> {
    peers_or_skip().map(|dir| dir.join(rel))
}

fn check(scene_path: PathBuf, reference: PathBuf, ref_var: RefVariance) {
    let name = scene_path.file_name().unwrap().to_string_lossy().to_string();
    let scene = load_file(&scene_path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let relaxed = verdict(&name, &scene, reference, ref_var);
    assert!(relaxed.passed(), "{name} fails check.py's rule: {relaxed}");
}

/// Renders `scene` and applies the rule; prints both verdicts, returns the relaxed one.
fn verdict(name: &str, scene: &haze_scene::Scene, reference: PathBuf, ref_var: RefVariance) -> Verdict {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let spp = (SAMPLE_BUDGET / (w * h)) as u32;
    let settings = RenderSettings { spp, seed: 0, spp_per_pass: 32, ..Default::default() };
    let integrator = VolPath::from_spec(&scene.integrator);
    let out = render(scene, &integrator, &settings, &AtomicBool::new(false), |_| {});
    assert_eq!(out.invalid_samples, 0, "{name}: NaN/Inf samples");
    let (_, relaxed) = judge(
        &format!("{name} ({w}x{h}, {spp} spp, {:.1} s)", out.elapsed.as_secs_f64()),
        &out.film,
        &reference,
        ref_var,
    );
    relaxed
}

fn suite(scene: &str) {
    let Some(dir) = peers(SUITE_DIR) else { return };
    let stem = scene.rsplit_once('_').map(|(s, _)| s).unwrap();
    check(
        dir.join(format!("{scene}.xml")),
        dir.join(format!("refs/{stem}_ref_rgb.exr")),
        RefVariance::Image(dir.join(format!("refs/{stem}_ref_rgb_var.exr"))),
    );
}

const SUITE_DIR: &str = "mitsuba3-media-tests/tests/scenes/participating_media";

/// One of the two public scenes: `small.xml` and its Mitsuba 3 reference `ref.exr` (not
/// upstream: `scripts/fetch-peers.sh` renders it when Mitsuba 3 is installed).
fn public_scene(name: &str, ref_spp: f64) {
    let Some(dir) = peers(name) else { return };
    let reference = dir.join("ref.exr");
    if !reference.exists() {
        // Straight to stderr: the harness captures `eprintln!` of passing tests.
        let _ = writeln!(
            std::io::stderr(),
            "skipped: {} is missing (scripts/fetch-peers.sh renders it with Mitsuba 3)",
            reference.display()
        );
        return;
    }
    check(dir.join("small.xml"), reference, RefVariance::Own { ref_spp });
}

#[test]
fn homo_area_light() {
    suite("test_homo_area_light_volpath");
}

#[test]
fn homo_dielectric_envmap() {
    suite("test_homo_dielectric_envmap_volpath");
}

#[test]
fn homo_emitter_inside_medium() {
    suite("test_homo_emitter_inside_medium_volpath");
}

#[test]
fn homo_null_envmap() {
    suite("test_homo_null_envmap_volpath");
}

#[test]
fn homo_obj_inside_medium() {
    suite("test_homo_obj_inside_medium_volpath");
}

#[test]
fn homo_roughdielectric_spot() {
    suite("test_homo_roughdielectric_spot_volpath");
}

#[test]
fn homo_spectral_sigmat() {
    suite("test_homo_spectral_sigmat_volpathmis");
}

#[test]
fn hetero_sigmat() {
    suite("test_hetero_sigmat_volpath");
}

#[test]
fn hetero_sigmat_albedo() {
    suite("test_hetero_sigmat_albedo_volpath");
}

#[test]
fn hetero_spectral_sigmat_no_scattering() {
    suite("test_hetero_spectral_sigmat_no_scattering_volpath");
}

#[test]
fn hetero_spectral_sigmat() {
    suite("test_hetero_spectral_sigmat_volpathmis");
}

/// Negative control of the heterogeneous scenes: the same render with every density lookup
/// moved by half a grid cell along x (cell values at cell corners instead of centres, a
/// plausible misreading of Mitsuba's grid) must fail the rule.
#[test]
fn hetero_sigmat_half_cell_offset_fails() {
    use haze_scene::hetero::{Heterogeneous, MajorantGrid, MAJORANT_RES};
    use haze_scene::volume::{Volume, VolumeData};
    let Some(dir) = peers(SUITE_DIR) else { return };
    let path = dir.join("test_hetero_sigmat_volpath.xml");
    let mut scene = load_file(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    for m in &mut scene.media {
        let Some(h) = m.as_grid().cloned() else { continue };
        let VolumeData::Grid { grid, .. } = &h.sigma_t.data else { panic!("a grid") };
        let shift = glam::Affine3A::from_translation(glam::Vec3::new(0.5 / grid.res[0] as f32, 0.0, 0.0));
        let mut sigma_t = Volume::new(h.sigma_t.data.clone(), h.sigma_t.to_local.inverse() * shift);
        // Same box (the clipping is not what is perturbed), shifted lookups.
        sigma_t.bbox = h.sigma_t.bbox;
        let majorants = MajorantGrid::build(&sigma_t, h.scale, [MAJORANT_RES; 3]);
        m.kind = haze_scene::MediumKind::Grid(std::sync::Arc::new(Heterogeneous { sigma_t, majorants, ..h }));
    }
    let relaxed = verdict(
        "test_hetero_sigmat_volpath.xml with a half-cell offset",
        &scene,
        dir.join("refs/test_hetero_sigmat_ref_rgb.exr"),
        RefVariance::Image(dir.join("refs/test_hetero_sigmat_ref_rgb_var.exr")),
    );
    assert!(!relaxed.passed(), "a half-cell offset of the density went unnoticed: {relaxed}");
}

#[test]
fn surf_area_light() {
    suite("test_surf_area_light_volpath");
}

#[test]
fn tof_cbox_volumetric() {
    public_scene("tof-cbox-volumetric", 8192.0);
}

#[test]
fn mi3_phase_trampoline_teapot() {
    public_scene("mi3-phase-trampoline-teapot", 262_144.0);
}
