//! Delta and ratio tracking in a heterogeneous medium against closed forms (`docs/theory.md`
//! §12.3-12.4): a grid whose density grows linearly along x (trilinear between cell centres, clamped
//! to the edge cells outside them), where the optical depth of any ray has a closed form.
//! Negative controls: a majorant below the maximum density must fail both tests.

use glam::{Affine3A, Vec3};
use haze_core::{Rgb, Sampler};
use haze_scene::hetero::{Heterogeneous, MajorantGrid, MAJORANT_RES};
use haze_scene::volume::{Filter, Grid, Volume, VolumeData, Wrap};
use haze_scene::Flight;
use haze_testkit::chi2::chi2_interval;
use std::sync::Arc;

const CELLS: u32 = 8;
/// Density slopes per channel (times `SCALE`); the grid spans `[0, 2]^3`.
const SLOPE: [f32; 3] = [1.0, 2.5, 0.4];
const SCALE: f32 = 1.5;
const ALBEDO: f32 = 0.6;

/// The medium; its majorants multiplied by `majorant_factor` (1 for the real ones).
fn medium(majorant_res: u32, majorant_factor: f32, albedo: f32) -> Heterogeneous {
    let mut data = Vec::new();
    for _z in 0..2 {
        for _y in 0..2 {
            for x in 0..CELLS {
                let u = (x as f32 + 0.5) / CELLS as f32;
                data.extend(SLOPE.map(|s| s * u));
            }
        }
    }
    let grid = Grid { res: [CELLS, 2, 2], channels: 3, data, bbox: (Vec3::ZERO, Vec3::ONE) };
    let sigma_t = Volume::new(
        VolumeData::Grid { grid: Arc::new(grid), filter: Filter::Trilinear, wrap: Wrap::Clamp },
        Affine3A::from_scale(Vec3::splat(2.0)),
    );
    let mut majorants = MajorantGrid::build(&sigma_t, SCALE, [majorant_res; 3]);
    for c in &mut majorants.cells {
        *c *= majorant_factor;
    }
    Heterogeneous { sigma_t, albedo: Volume::constant(Rgb::splat(albedo)), scale: SCALE, majorants }
}

/// `int_0^u clamp(s, lo, hi) ds` with `lo, hi` the first and last cell centres.
fn clamped_ramp_integral(u: f64) -> f64 {
    let (lo, hi) = (0.5 / CELLS as f64, 1.0 - 0.5 / CELLS as f64);
    if u <= lo {
        lo * u
    } else if u <= hi {
        lo * lo + (u * u - lo * lo) / 2.0
    } else {
        lo * lo + (hi * hi - lo * lo) / 2.0 + hi * (u - hi)
    }
}

/// The exact optical depth of `o + t d`, `t in [t0, t1]`, inside the box `[0, 2]^3`.
fn optical_depth(o: Vec3, d: Vec3, t0: f32, t1: f32) -> Rgb {
    let (mut a, mut b) = (t0 as f64, t1 as f64);
    for k in 0..3 {
        let (ok, dk) = (o[k] as f64, d[k] as f64);
        if dk == 0.0 {
            if !(0.0..=2.0).contains(&ok) {
                return Rgb::ZERO;
            }
        } else {
            let (p, q) = ((0.0 - ok) / dk, (2.0 - ok) / dk);
            a = a.max(p.min(q));
            b = b.min(p.max(q));
        }
    }
    if a >= b {
        return Rgb::ZERO;
    }
    let u = |t: f64| (o.x as f64 + t * d.x as f64) / 2.0;
    // sigma(x) = SCALE * slope * clamp(x / 2); int dt = int dx / |d_x| = 2 int du / |d_x|.
    let ramp = if d.x == 0.0 {
        (u(a).clamp(0.5 / CELLS as f64, 1.0 - 0.5 / CELLS as f64)) * (b - a)
    } else {
        2.0 * (clamped_ramp_integral(u(b)) - clamped_ramp_integral(u(a))).abs() / (d.x as f64).abs()
    };
    Rgb(SLOPE.map(|s| (SCALE as f64 * s as f64 * ramp) as f32))
}

/// Rays through, into, out of and past the box.
fn rays() -> Vec<(Vec3, Vec3, f32)> {
    let mut s = Sampler::from_seed(21);
    let mut out = vec![
        (Vec3::new(-1.0, 1.0, 1.0), Vec3::X, 10.0),
        (Vec3::new(3.0, 0.3, 1.7), -Vec3::X, 2.5),
        (Vec3::new(1.3, -1.0, 1.0), Vec3::Y, 10.0),
        (Vec3::new(-1.0, 3.0, 1.0), Vec3::X, 10.0),
    ];
    for _ in 0..8 {
        let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 4.0 - 1.0;
        let target = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 2.0;
        let d = (target - o).normalize();
        out.push((o, d, 1.0 + 4.0 * s.next_1d()));
    }
    out
}

/// Largest |z| of the ratio-tracking mean against `exp(-tau)` over the rays and channels.
fn ratio_tracking_worst_z(m: &Heterogeneous, n: usize) -> f64 {
    let mut s = Sampler::from_seed(5);
    let mut worst = 0.0f64;
    for (o, d, t1) in rays() {
        let exact = optical_depth(o, d, 0.0, t1).map(|x| (-x).exp());
        let (mut sum, mut sq) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let tr = m.transmittance(o, d, 0.0, t1, &mut s);
            for c in 0..3 {
                sum[c] += tr[c] as f64;
                sq[c] += (tr[c] as f64).powi(2);
            }
        }
        for c in 0..3 {
            let mean = sum[c] / n as f64;
            let var = (sq[c] / n as f64 - mean * mean).max(0.0);
            let diff = mean - exact[c] as f64;
            let z = if var > 0.0 {
                diff / (var / n as f64).sqrt()
            } else if diff.abs() < 1e-5 {
                0.0
            } else {
                1e9
            };
            worst = worst.max(z.abs());
        }
    }
    worst
}

#[test]
fn ratio_tracking_matches_the_analytic_transmittance() {
    // 12 rays x 3 channels: |z| < 4.5 holds with probability > 0.9998 for an unbiased estimator.
    for res in [MAJORANT_RES, 1] {
        let z = ratio_tracking_worst_z(&medium(res, 1.0, ALBEDO), 20_000);
        assert!(z < 4.5, "majorant grid {res}^3: worst |z| {z:.2}");
    }
    // Negative control: majorants at 60% let the density exceed them, and the clamped
    // ratio-tracking factors are biased.
    let z = ratio_tracking_worst_z(&medium(MAJORANT_RES, 0.6, ALBEDO), 20_000);
    assert!(z > 10.0, "majorant below the density went unnoticed: worst |z| {z:.2}");
}

/// Chi-square of the distances of real collisions along one ray (grey extinction: channel 0
/// in all three) against `sigma(t) exp(-tau(t))`, plus a binomial check of the passes.
fn delta_tracking_chi2(majorant_factor: f32) -> (f64, f64) {
    let m = medium(MAJORANT_RES, majorant_factor, ALBEDO);
    let (o, d) = (Vec3::new(-0.5, 0.2, 0.4), Vec3::new(1.0, 0.35, 0.3).normalize());
    let t_max = 3.5f32;
    let mut s = Sampler::from_seed(9);
    let mut bad_weight = 0usize;
    let n = 100_000;
    let r = chi2_interval(
        || match m.sample_free_flight(o, d, t_max, 0, &mut s) {
            Flight::Scatter { t, weight, .. } => {
                // f / p of the hero for a real collision is sigma_s / sigma_t = albedo.
                if (weight[0] - ALBEDO).abs() > 1e-3 * ALBEDO {
                    bad_weight += 1;
                }
                t as f64
            }
            Flight::Pass { weight, .. } => {
                if (weight[0] - 1.0).abs() > 1e-3 {
                    bad_weight += 1;
                }
                -1.0
            }
        },
        |t| {
            let tau = optical_depth(o, d, 0.0, t as f32)[0] as f64;
            // sigma at t: the derivative of the optical depth.
            let h = 1e-4;
            let sigma = (optical_depth(o, d, 0.0, (t + h) as f32)[0] as f64 - tau) / h;
            sigma.max(0.0) * (-tau).exp()
        },
        0.0,
        t_max as f64,
        50,
        n,
    );
    let pass = (-optical_depth(o, d, 0.0, t_max)[0] as f64).exp();
    let expected = pass * n as f64;
    let pass_z = (r.outside_support as f64 - expected) / (expected * (1.0 - pass)).sqrt();
    assert_eq!(bad_weight, 0, "throughput weights off");
    (r.p_value, pass_z)
}

#[test]
fn delta_tracking_distances_follow_the_free_flight_density() {
    let (p, pass_z) = delta_tracking_chi2(1.0);
    assert!(p > 0.001 && pass_z.abs() < 4.0, "p = {p:.4}, pass z = {pass_z:.2}");
    // Negative control: a majorant below the density samples too few collisions.
    let (p, pass_z) = delta_tracking_chi2(0.6);
    assert!(p < 1e-6 || pass_z.abs() > 6.0, "low majorant went unnoticed: p = {p:.4}, pass z = {pass_z:.2}");
}

/// Chromatic extinction, hero channel drawn per sample: the spectral-MIS estimates
/// `weight / mean(ratio)` of passing and of a real collision (albedo 1) reproduce `T_c` and
/// `1 - T_c` in every channel (`docs/theory.md` §12.3).
#[test]
fn spectral_mis_free_flight_estimates_each_channel() {
    let m = medium(MAJORANT_RES, 1.0, 1.0);
    let mut s = Sampler::from_seed(17);
    let n = 100_000;
    for (o, d, t1) in rays().into_iter().take(6) {
        let (mut pass, mut hit) = ([0.0f64; 3], [0.0f64; 3]);
        let (mut pass_sq, mut hit_sq) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let hero = haze_core::transmittance::hero_channel(s.next_1d());
            let (acc, sq, w, r) = match m.sample_free_flight(o, d, t1, hero, &mut s) {
                Flight::Pass { weight, ratio } => (&mut pass, &mut pass_sq, weight, ratio),
                Flight::Scatter { weight, ratio, .. } => (&mut hit, &mut hit_sq, weight, ratio),
            };
            for c in 0..3 {
                let v = (w[c] / r.mean()) as f64;
                acc[c] += v;
                sq[c] += v * v;
            }
        }
        let exact = optical_depth(o, d, 0.0, t1).map(|x| (-x).exp());
        for c in 0..3 {
            for (sum, sumsq, want) in [(pass[c], pass_sq[c], exact[c]), (hit[c], hit_sq[c], 1.0 - exact[c])] {
                let mean = sum / n as f64;
                let se = ((sumsq / n as f64 - mean * mean).max(1e-12) / n as f64).sqrt();
                let z = (mean - want as f64) / se;
                assert!(z.abs() < 4.5, "ray {o} {d}: channel {c}: {mean} vs {want} (z {z:.2})");
            }
        }
    }
}
