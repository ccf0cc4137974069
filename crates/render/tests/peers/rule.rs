//! check.py's rule (`peers/mitsuba3-media-tests/check.py`; the module doc of `main.rs` states
//! it), shared by the peer tests of `volpath` (`main.rs`) and of the many-light integrators
//! (`crates/manylight/tests/peers_lightcuts.rs`, which includes this file by its path).
#![allow(dead_code)]

use haze_render::image_io::RgbImage;
use haze_render::Film;
use haze_testkit::ztest::{pool_variance, sidak_threshold};
use std::path::{Path, PathBuf};

/// Mitsuba's linear sRGB -> CIE XYZ matrix (rows X, Y, Z).
pub const SRGB_TO_XYZ: [[f64; 3]; 3] =
    [[0.412453, 0.357580, 0.180423], [0.212671, 0.715160, 0.072169], [0.019334, 0.119193, 0.950227]];
pub const VAR_FLOOR: f64 = 1e-4;
pub const ACCEPT_FRACTION: f64 = 0.9975;
pub const MEAN_Z_LIMIT: f64 = 5.0;

pub fn to_xyz(rgb: &[f32]) -> Vec<f64> {
    rgb.chunks_exact(3)
        .flat_map(|c| SRGB_TO_XYZ.map(|m| m[0] * c[0] as f64 + m[1] * c[1] as f64 + m[2] * c[2] as f64))
        .collect()
}

/// Upper bound of the XYZ variance of a pixel from its per-channel RGB variance.
pub fn var_rgb_to_xyz_bound(var: &[f32]) -> Vec<f64> {
    var.chunks_exact(3)
        .flat_map(|v| {
            let s: [f64; 3] = std::array::from_fn(|j| (v[j].max(0.0) as f64).sqrt());
            SRGB_TO_XYZ.map(|m| (m[0] * s[0] + m[1] * s[1] + m[2] * s[2]).powi(2))
        })
        .collect()
}

pub struct Verdict {
    pub failing: usize,
    pub allowed: usize,
    pub max_z: f64,
    pub mean_z: [f64; 3],
}

impl Verdict {
    pub fn passed(&self) -> bool {
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
pub fn rule(test: &[f64], reference: &[f64], var_mean: &[f64], pixels: usize) -> Verdict {
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
pub enum RefVariance {
    /// A per-sample variance image of the reference (XYZ stored as RGB, like Mitsuba's suite).
    Image(PathBuf),
    /// None: use haze's own variance, plus the reference's noise at this many spp.
    Own { ref_spp: f64 },
}

/// Applies the rule to `film`, a render of the scene whose Mitsuba 3 reference is `reference`
/// with per-pixel sample variances that are honest (independent samples), and prints both
/// verdicts under the heading `what`: the driver's (the reference's variance) and check.py's with
/// haze's own variance (returned second, the one the tests assert).
pub fn judge(what: &str, film: &Film, reference: &Path, ref_var: RefVariance) -> (Verdict, Verdict) {
    let (w, h) = (film.width as usize, film.height as usize);
    let reference_img = RgbImage::read_exr(reference).expect("reference EXR");
    assert_eq!((reference_img.width, reference_img.height), (w, h), "{what}: size");

    let test = to_xyz(&film.mean(None));
    let reference = to_xyz(&reference_img.data);
    let own_var = film.sample_variance(None);
    let test_var = var_rgb_to_xyz_bound(&own_var);
    // `samples` counts the samples of each pixel.
    let n = film.samples as f64;
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
    println!("{what}:");
    println!("  driver rule (reference variance): {driver}");
    println!("  check.py with haze's variance:    {relaxed}");
    (driver, relaxed)
}
