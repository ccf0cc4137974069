//! Shared by the VRL and VPL estimator tests: adaptive Gauss-Kronrod quadrature (`f64`), an
//! independent `f64` evaluation of the phase function, the Monte Carlo loop with its standard
//! error, and the pass/fail check with its printed table row.
#![allow(dead_code)]

use glam::Quat;
use haze_core::{Phase, Rgb, Sampler, Vec3};

pub type Rgb64 = [f64; 3];

// -- Quadrature --------------------------------------------------------------------------------

#[allow(clippy::excessive_precision)]
const XK: [f64; 8] = [
    0.991455371120812639,
    0.949107912342758525,
    0.864864423359769073,
    0.741531185599394440,
    0.586087235467691130,
    0.405845151377397167,
    0.207784955007898468,
    0.0,
];
#[allow(clippy::excessive_precision)]
const WK: [f64; 8] = [
    0.022935322010529225,
    0.063092092629978553,
    0.104790010322250184,
    0.140653259715525919,
    0.169004726639267903,
    0.190350578064785410,
    0.204432940075298892,
    0.209482141084727828,
];
#[allow(clippy::excessive_precision)]
const WG: [f64; 4] = [0.129484966168869693, 0.279705391489276668, 0.381830050505118945, 0.417959183673469388];

/// Gauss-Kronrod 7-15 rule on `[a, b]`: the Kronrod estimate and `|K - G|` (max over channels).
fn gk15(f: &mut dyn FnMut(f64) -> Rgb64, a: f64, b: f64) -> (Rgb64, f64) {
    let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
    let fc = f(c);
    let mut k = fc.map(|x| WK[7] * x);
    let mut g = fc.map(|x| WG[3] * x);
    for i in 0..7 {
        let (f1, f2) = (f(c - r * XK[i]), f(c + r * XK[i]));
        for ch in 0..3 {
            let s = f1[ch] + f2[ch];
            k[ch] += WK[i] * s;
            if i % 2 == 1 {
                g[ch] += WG[i / 2] * s;
            }
        }
    }
    let err = (0..3).map(|ch| ((k[ch] - g[ch]) * r).abs()).fold(0.0, f64::max);
    (k.map(|x| x * r), err)
}

/// Global adaptive quadrature (QUADPACK QAG style) of an RGB integrand over `[a, b]`, first
/// split at the `breaks` inside it (the peaks of the integrand), until the summed error
/// estimate is below `rel_tol` times the largest channel of the integral.
pub fn integrate(mut f: impl FnMut(f64) -> Rgb64, a: f64, b: f64, breaks: &[f64], rel_tol: f64) -> Rgb64 {
    if b.is_nan() || b <= a {
        return [0.0; 3];
    }
    let mut pts = vec![a, b];
    pts.extend(breaks.iter().copied().filter(|&x| x > a && x < b));
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    let mut parts: Vec<(f64, f64, Rgb64, f64)> = pts
        .windows(2)
        .map(|w| {
            let (k, e) = gk15(&mut f, w[0], w[1]);
            (w[0], w[1], k, e)
        })
        .collect();
    for _ in 0..20_000 {
        let total = sum_parts(&parts);
        let err: f64 = parts.iter().map(|p| p.3).sum();
        if err <= rel_tol * total.iter().fold(0.0f64, |m, x| m.max(x.abs())) || err == 0.0 {
            break;
        }
        let i = (0..parts.len()).max_by(|&i, &j| parts[i].3.total_cmp(&parts[j].3)).unwrap();
        let (lo, hi, _, _) = parts.swap_remove(i);
        let mid = 0.5 * (lo + hi);
        for (x, y) in [(lo, mid), (mid, hi)] {
            let (k, e) = gk15(&mut f, x, y);
            parts.push((x, y, k, e));
        }
    }
    sum_parts(&parts)
}

fn sum_parts(parts: &[(f64, f64, Rgb64, f64)]) -> Rgb64 {
    std::array::from_fn(|ch| parts.iter().map(|p| p.2[ch]).sum())
}

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
