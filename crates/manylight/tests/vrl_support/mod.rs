//! Shared by the VRL and VPL estimator tests: RGB quadrature (from `haze-testkit`), an
//! independent `f64` evaluation of the phase function, the Monte Carlo loop with its standard
//! error, and the pass/fail check with its printed table row.
#![allow(dead_code)]

use glam::Quat;
use haze_core::{Phase, Rgb, Sampler, Vec3};
use haze_manylight::vrl::sampling::{equiangular_pdf, sample_equiangular};
use haze_manylight::vrl::Segment;

pub type Rgb64 = [f64; 3];

/// Adaptive Gauss-Kronrod quadrature of an RGB integrand.
pub use haze_testkit::quadrature::integrate_channels as integrate;

// -- Independent f64 physics ------------------------------------------------------------------

/// Henyey-Greenstein (isotropic for `g = 0`) in `f64`, of the cosine between propagation
/// directions.
pub fn hg64(cos: f64, g: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * std::f64::consts::PI * denom * denom.sqrt())
}

pub fn phase_of(g: f32) -> Phase {
    if g == 0.0 {
        Phase::Isotropic
    } else {
        Phase::HenyeyGreenstein { g }
    }
}

pub fn g_of(p: &Phase) -> f64 {
    match *p {
        Phase::Isotropic => 0.0,
        Phase::HenyeyGreenstein { g } => g as f64,
    }
}

pub fn d64(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

pub fn rgb64(c: Rgb) -> Rgb64 {
    [c[0] as f64, c[1] as f64, c[2] as f64]
}

pub fn random_rotation(s: &mut Sampler) -> Quat {
    Quat::from_axis_angle(haze_core::sampling::sample_uniform_sphere(s.next_2d()), 6.0 * s.next_1d())
}

pub fn random_rgb(s: &mut Sampler, lo: f32, hi: f32) -> Rgb {
    Rgb::new(lo + (hi - lo) * s.next_1d(), lo + (hi - lo) * s.next_1d(), lo + (hi - lo) * s.next_1d())
}

// -- Monte Carlo and the check ----------------------------------------------------------------

pub struct McResult {
    pub mean: Rgb64,
    /// Standard error of the mean, per channel.
    pub se: Rgb64,
    pub n: usize,
}

/// Averages `est` in batches of `batch` samples until the largest relative standard error is
/// below `target_rel_se` or `n_max` samples were taken.
pub fn monte_carlo(
    mut est: impl FnMut(&mut Sampler) -> Rgb,
    seed: u64,
    target_rel_se: f64,
    n_max: usize,
) -> McResult {
    let batch = 100_000;
    let mut s = Sampler::from_seed(seed);
    let (mut sum, mut sum2, mut n) = ([0.0f64; 3], [0.0f64; 3], 0usize);
    loop {
        for _ in 0..batch {
            let e = est(&mut s);
            for ch in 0..3 {
                let x = e[ch] as f64;
                sum[ch] += x;
                sum2[ch] += x * x;
            }
        }
        n += batch;
        let mean = sum.map(|x| x / n as f64);
        let se: Rgb64 = std::array::from_fn(|ch| {
            ((sum2[ch] / n as f64 - mean[ch] * mean[ch]).max(0.0) / n as f64).sqrt()
        });
        let rel = (0..3).map(|ch| se[ch] / mean[ch].abs()).fold(0.0, f64::max);
        if rel < target_rel_se || n >= n_max {
            return McResult { mean, se, n };
        }
    }
}

/// The acceptance rule: in every channel `|mean - reference| < 4 SE` and relative error < 0.5%.
/// Returns whether it passed and the table row.
pub fn check(name: &str, mc: &McResult, reference: Rgb64) -> (bool, String) {
    let mut ok = true;
    let (mut worst_rel, mut worst_z) = (0.0f64, 0.0f64);
    for ((mean, se), r) in mc.mean.iter().zip(mc.se).zip(reference) {
        let diff = (mean - r).abs();
        let rel = diff / r.abs();
        let z = diff / se;
        ok &= rel < 5e-3 && z < 4.0 && mean.is_finite();
        worst_rel = worst_rel.max(rel);
        worst_z = worst_z.max(z);
    }
    let row = format!(
        "{name:<34} {:>12.6e} {:>12.6e} {:>9.5}% {:>6.2} {:>8} {}",
        mc.mean[1],
        reference[1],
        100.0 * worst_rel,
        worst_z,
        mc.n,
        if ok { "ok" } else { "FAIL" }
    );
    (ok, row)
}

/// Runs `est` of every case (in parallel, case `i` seeded `seed + i`) until the relative
/// standard error is below 0.1% (or `n_max` samples), so that passing the 4-SE rule of
/// [`check`] also keeps the error within about 0.4%; returns the verdicts and table rows.
pub fn run_cases<C: Sync>(
    cases: &[C],
    name: impl Fn(&C) -> &str + Sync,
    reference: impl Fn(&C) -> Rgb64 + Sync,
    est: impl Fn(&C, &mut Sampler) -> Rgb + Sync,
    seed: u64,
    n_max: usize,
) -> Vec<(bool, String)> {
    use rayon::prelude::*;
    cases
        .par_iter()
        .enumerate()
        .map(|(i, case)| {
            let mc = monte_carlo(|s| est(case, s), seed + i as u64, 1e-3, n_max);
            check(name(case), &mc, reference(case))
        })
        .collect()
}

/// The library's `f32` integrand `f` agrees with the independent `f64` one `r` to 0.1% in
/// every channel.
pub fn assert_matches_f64(f: Rgb, r: Rgb64, name: &str) {
    for ch in 0..3 {
        assert!((f[ch] as f64 - r[ch]).abs() <= 1e-3 * r[ch], "{name}: {f} vs {r:?}");
    }
}

/// A camera distance `t` drawn equiangularly towards `point` from the segment `cam` with the
/// uniform number `u`, and its pdf (per unit length); `uniform_pdf` replaces the pdf by the
/// uniform `1/len` (a wrong pdf, for negative controls).
pub fn equiangular_towards(cam: &Segment, point: Vec3, u: f32, uniform_pdf: bool) -> (f32, f32) {
    let r = point - cam.o;
    let delta = r.dot(cam.d);
    let h = (r - delta * cam.d).length();
    let t = sample_equiangular(u, delta, h, 0.0, cam.len).expect("a camera segment of positive length");
    let pdf = if uniform_pdf { 1.0 / cam.len } else { equiangular_pdf(t, delta, h, 0.0, cam.len) };
    (t, pdf)
}

pub fn table_header() -> String {
    format!(
        "{:<34} {:>12} {:>12} {:>10} {:>6} {:>8}\n{}",
        "config",
        "estimate(G)",
        "integral(G)",
        "max rel",
        "max z",
        "samples",
        "-".repeat(92)
    )
}

// -- Shared test scaffolding ------------------------------------------------------------------

/// A random camera segment for the degenerate-configuration tests: origin in `[-2, 2]^3`,
/// uniform direction, length at a random scale (`1e-4`, 1 or 100), zero for every 11th `i`.
/// Returns the segment and its scale.
pub fn degenerate_camera_segment(s: &mut Sampler, i: u32) -> (haze_manylight::vrl::Segment, f32) {
    let c = haze_core::sampling::sample_uniform_sphere(s.next_2d());
    let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - Vec3::splat(2.0);
    let scale = [1e-4f32, 1.0, 100.0][(s.next_u32() % 3) as usize];
    let len = if i % 11 == 0 { 0.0 } else { scale * (0.01 + 2.0 * s.next_1d()) };
    (haze_manylight::vrl::Segment::new(o, c, len), scale)
}

/// Prints the rows of a negative-control run under `title` and checks that every `must_pass`
/// row passed and every `must_fail` group failed (named in its message).
pub fn report_controls(title: &str, must_pass: &[(bool, String)], must_fail: &[(&[(bool, String)], &str)]) {
    println!("\n{title}:\n{}", table_header());
    for (_, row) in must_pass.iter().chain(must_fail.iter().flat_map(|(rows, _)| rows.iter())) {
        println!("{row}");
    }
    assert!(must_pass.iter().all(|r| r.0), "the manual estimator with the right pdf must pass");
    for (rows, what) in must_fail {
        assert!(rows.iter().all(|r| !r.0), "the check failed to detect {what}");
    }
}

/// Prints `rows` as a table under `title` and checks that every row passed.
pub fn report_rows(title: &str, rows: &[(bool, String)], failure: &str) {
    println!("\n{title}\n{}", table_header());
    for (_, row) in rows {
        println!("{row}");
    }
    assert!(rows.iter().all(|r| r.0), "{failure}");
}
