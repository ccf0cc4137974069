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

use haze_render::image_io::RgbImage;
use haze_render::progressive::{render, RenderSettings};
use haze_render::VolPath;
use haze_scene::{load_file, LoadOptions};
use haze_testkit::data::peers_or_skip;
use haze_testkit::ztest::{pool_variance, sidak_threshold};
use std::io::Write;
use std::path::PathBuf;

mod load;
use std::sync::atomic::AtomicBool;

/// Mitsuba's linear sRGB -> CIE XYZ matrix (rows X, Y, Z).
const SRGB_TO_XYZ: [[f64; 3]; 3] =
    [[0.412453, 0.357580, 0.180423], [0.212671, 0.715160, 0.072169], [0.019334, 0.119193, 0.950227]];
const SAMPLE_BUDGET: usize = 2_000_000;
const VAR_FLOOR: f64 = 1e-4;
const ACCEPT_FRACTION: f64 = 0.9975;
const MEAN_Z_LIMIT: f64 = 5.0;

/// A file of the peer data, or `None` (with the skip line) when the data is absent.
fn peers(rel: &str) -> Option<PathBuf> {
    peers_or_skip().map(|dir| dir.join(rel))
}

fn to_xyz(rgb: &[f32]) -> Vec<f64> {
    rgb.chunks_exact(3)
        .flat_map(|c| SRGB_TO_XYZ.map(|m| m[0] * c[0] as f64 + m[1] * c[1] as f64 + m[2] * c[2] as f64))
        .collect()
}

/// Upper bound of the XYZ variance of a pixel from its per-channel RGB variance.
fn var_rgb_to_xyz_bound(var: &[f32]) -> Vec<f64> {
    var.chunks_exact(3)
        .flat_map(|v| {
            let s: [f64; 3] = std::array::from_fn(|j| (v[j].max(0.0) as f64).sqrt());
            SRGB_TO_XYZ.map(|m| (m[0] * s[0] + m[1] * s[1] + m[2] * s[2]).powi(2))
        })
        .collect()
}

struct Verdict {
    failing: usize,
    allowed: usize,
    max_z: f64,
    mean_z: [f64; 3],
}

impl Verdict {
    fn passed(&self) -> bool {
        self.failing <= self.allowed && self.mean_z.iter().all(|z| z.abs() <= MEAN_Z_LIMIT)
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} failing channel-pixels (PASS needs <= {}), max z {:.2}, image-mean z (X, Y, Z) \
             {:+.2}, {:+.2}, {:+.2}",
            self.failing, self.allowed, self.max_z, self.mean_z[0], self.mean_z[1], self.mean_z[2]
        )
    }
}

/// check.py's rule: `var_mean` is the variance of each test channel-pixel (XYZ).
fn rule(test: &[f64], reference: &[f64], var_mean: &[f64], pixels: usize) -> Verdict {
    let threshold = sidak_threshold(0.01, pixels);
    let (mut failing, mut max_z) = (0, 0.0f64);
    let (mut diff, mut var) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..test.len() {
        let z = (test[i] - reference[i]).abs() / var_mean[i].sqrt();
        // A NaN fails, as in the driver.
        if z.is_nan() || z > threshold {
            failing += 1;
        }
        if z.is_finite() {
            max_z = max_z.max(z);
        }
        diff[i % 3] += test[i] - reference[i];
        var[i % 3] += var_mean[i];
    }
    let allowed = test.len() - (3.0 * ACCEPT_FRACTION * pixels as f64).ceil() as usize;
    let mean_z = std::array::from_fn(|c| diff[c] / var[c].sqrt());
    Verdict { failing, allowed, max_z, mean_z }
}

/// Where the reference's variance comes from.
enum RefVariance {
    /// A per-sample variance image of the reference (XYZ stored as RGB, like Mitsuba's suite).
    Image(PathBuf),
    /// None: use haze's own variance, plus the reference's noise at this many spp.
    Own { ref_spp: f64 },
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
    let reference_img = RgbImage::read_exr(&reference).expect("reference EXR");
    assert_eq!((reference_img.width, reference_img.height), (w, h), "{name}: size");

    let test = to_xyz(&out.film.mean(None));
    let reference = to_xyz(&reference_img.data);
    let own_var = out.film.sample_variance(None);
    let test_var = var_rgb_to_xyz_bound(&own_var);
    let n = spp as f64;
    let (ref_var, ref_noise): (Vec<f64>, Vec<f64>) = match ref_var {
        RefVariance::Image(path) => {
            let v = to_xyz(&RgbImage::read_exr(&path).expect("variance EXR").data);
            (v.iter().map(|x| x.max(VAR_FLOOR)).collect(), vec![0.0; v.len()])
        }
        RefVariance::Own { ref_spp } => {
            let pooled = var_rgb_to_xyz_bound(&pool_variance(&own_var, w, h, 3));
            let floor: Vec<f64> = pooled.iter().map(|x| x.max(VAR_FLOOR)).collect();
            let noise = floor.iter().map(|x| x / ref_spp).collect();
            (floor, noise)
        }
    };
    let driver_var: Vec<f64> = ref_var.iter().zip(&ref_noise).map(|(v, r)| v / n + r).collect();
    let driver = rule(&test, &reference, &driver_var, w * h);
    let relaxed_var: Vec<f64> =
        ref_var.iter().zip(&test_var).zip(&ref_noise).map(|((v, t), r)| v.max(*t) / n + r).collect();
    let relaxed = rule(&test, &reference, &relaxed_var, w * h);
    println!("{name} ({w}x{h}, {spp} spp, {:.1} s):", out.elapsed.as_secs_f64());
    println!("  driver rule (reference variance): {driver}");
    println!("  check.py with haze's variance:    {relaxed}");
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
        let Some(h) = m.hetero.clone() else { continue };
        let VolumeData::Grid { grid, .. } = &h.sigma_t.data else { panic!("a grid") };
        let shift = glam::Affine3A::from_translation(glam::Vec3::new(0.5 / grid.res[0] as f32, 0.0, 0.0));
        let mut sigma_t = Volume::new(h.sigma_t.data.clone(), h.sigma_t.to_local.inverse() * shift);
        // Same box (the clipping is not what is perturbed), shifted lookups.
        sigma_t.bbox = h.sigma_t.bbox;
        let majorants = MajorantGrid::build(&sigma_t, h.scale, [MAJORANT_RES; 3]);
        m.hetero = Some(std::sync::Arc::new(Heterogeneous { sigma_t, majorants, ..(*h).clone() }));
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
