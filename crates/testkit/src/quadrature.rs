//! Adaptive Gauss-Kronrod quadrature in `f64`, for exact reference values in tests: that a pdf
//! integrates to one, the expected counts of a chi-square bin, the exact value of an estimator's
//! integral. Vector-valued (one integral per channel, e.g. RGB) so that one pass over the
//! integrand serves every channel.

/// Kronrod nodes of the 15-point rule on `[-1, 1]` (the positive half; `XK[7] = 0`).
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
/// Kronrod weights for `XK`.
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
/// Weights of the embedded 7-point Gauss rule (its nodes are `XK[1]`, `XK[3]`, `XK[5]`, `XK[7]`).
#[allow(clippy::excessive_precision)]
const WG: [f64; 4] = [0.129484966168869693, 0.279705391489276668, 0.381830050505118945, 0.417959183673469388];

/// Most interval bisections before giving up on the tolerance.
const MAX_SPLITS: usize = 20_000;

/// Gauss-Kronrod 7-15 rule on `[a, b]`: the Kronrod estimate and `|K - G|` (max over channels)
/// as its error estimate.
fn gk15<const N: usize>(f: &mut dyn FnMut(f64) -> [f64; N], a: f64, b: f64) -> ([f64; N], f64) {
    let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
    let fc = f(c);
    let mut k = fc.map(|x| WK[7] * x);
    let mut g = fc.map(|x| WG[3] * x);
    for i in 0..7 {
        let (f1, f2) = (f(c - r * XK[i]), f(c + r * XK[i]));
        for ch in 0..N {
            let s = f1[ch] + f2[ch];
            k[ch] += WK[i] * s;
            if i % 2 == 1 {
                g[ch] += WG[i / 2] * s;
            }
        }
    }
    let err = (0..N).map(|ch| ((k[ch] - g[ch]) * r).abs()).fold(0.0, f64::max);
    (k.map(|x| x * r), err)
}

/// Global adaptive quadrature (QUADPACK QAG style) of a vector-valued integrand over `[a, b]`,
/// first split at the `breaks` inside it (the peaks of the integrand), then bisecting the
/// interval with the largest error estimate until the summed estimate is below `rel_tol` times
/// the largest channel of the integral. An empty or NaN interval integrates to zero.
pub fn integrate_channels<const N: usize>(
    mut f: impl FnMut(f64) -> [f64; N],
    a: f64,
    b: f64,
    breaks: &[f64],
    rel_tol: f64,
) -> [f64; N] {
    if b.is_nan() || b <= a {
        return [0.0; N];
    }
    let mut pts = vec![a, b];
    pts.extend(breaks.iter().copied().filter(|&x| x > a && x < b));
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    let mut parts: Vec<(f64, f64, [f64; N], f64)> = pts
        .windows(2)
        .map(|w| {
            let (k, e) = gk15(&mut f, w[0], w[1]);
            (w[0], w[1], k, e)
        })
        .collect();
    let sum = |parts: &[(f64, f64, [f64; N], f64)]| -> [f64; N] {
        std::array::from_fn(|ch| parts.iter().map(|p| p.2[ch]).sum())
    };
    for _ in 0..MAX_SPLITS {
        let total = sum(&parts);
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
    sum(&parts)
}

/// [`integrate_channels`] of a scalar integrand.
pub fn integrate(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, breaks: &[f64], rel_tol: f64) -> f64 {
    integrate_channels(|x| [f(x)], a, b, breaks, rel_tol)[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomials_and_peaks() {
        // The 15-point Kronrod rule is exact for polynomials of degree 22.
        let p = integrate(|x| x.powi(10) - 3.0 * x * x, -1.0, 2.0, &[], 1e-14);
        let exact = (2f64.powi(11) + 1.0) / 11.0 - 9.0;
        assert!((p - exact).abs() < 1e-12 * exact.abs(), "{p} vs {exact}");
        // A narrow Cauchy peak, resolved thanks to its break point: integral of
        // e / (e^2 + (x - 0.3)^2) over [0, 1] = atan(0.7 / e) + atan(0.3 / e).
        let e = 1e-4;
        let peak = integrate(|x| e / (e * e + (x - 0.3) * (x - 0.3)), 0.0, 1.0, &[0.3], 1e-10);
        let exact = (0.7f64 / e).atan() + (0.3f64 / e).atan();
        assert!((peak - exact).abs() < 1e-8, "{peak} vs {exact}");
        let rgb = integrate_channels(|x| [1.0, x, x * x], 0.0, 3.0, &[], 1e-12);
        assert!((rgb[0] - 3.0).abs() < 1e-12 && (rgb[1] - 4.5).abs() < 1e-12 && (rgb[2] - 9.0).abs() < 1e-12);
        assert_eq!(integrate(|_| 1.0, 1.0, 1.0, &[], 1e-9), 0.0);
    }
}
