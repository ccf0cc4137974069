//! `atan2`, `acos` and `sin_cos` in f32 as short polynomials, inlined where they are used,
//! for the hot mappings between directions and angles (the environment map's lookup and
//! sampling, the concentric disk). glibc's `atan2f`, `acosf` and `sincosf` are calls of 40-120
//! instructions with branches for arguments these mappings never pass (huge, subnormal); the
//! polynomials here are within a few f32 ulps of the exact value on the ranges stated, which
//! the tests below check against f64 on dense grids (docs/performance.md §4.3).

use std::f32::consts::{FRAC_PI_2, PI};

/// `atan(a) / a` as a polynomial in `a^2` on `[0, 1]`: a weighted least-squares fit at
/// Chebyshev nodes, reweighted towards equal ripple; `a P(a^2)` is within 1.4e-7 of
/// `atan(a)` (about one f32 ulp of `pi / 4`).
const ATAN: [f32; 8] = [
    0.999_999_34,
    -0.333_298_6,
    0.199_465_66,
    -0.139_086_29,
    0.096_421_96,
    -0.055_912_29,
    0.021_862_924,
    -0.004_054_556,
];

/// `atan2(y, x)` in `[-pi, pi]`, within 3e-7 radians of the exact value for finite
/// arguments. `atan2(0, 0)` is 0, and a zero `y` gives `+0` or `pi` whatever its sign (std
/// gives `-0` or `-pi` for `-0.0`; a caller that wraps the angle to `[0, 2 pi)` sees no
/// difference).
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let a = if hi > 0.0 { lo / hi } else { 0.0 };
    let z = a * a;
    let mut p = ATAN[7];
    for &c in ATAN[..7].iter().rev() {
        p = p.mul_add(z, c);
    }
    let mut r = p * a;
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// `asin(s) = s + s z P(z)` with `z = s^2`, for `s` in `[0, 1/2]` (Cephes `asinf`, Moshier).
#[inline(always)]
fn asin_poly(s: f32, z: f32) -> f32 {
    let p = 4.216_32e-2_f32
        .mul_add(z, 2.418_131e-2)
        .mul_add(z, 4.547_002_6e-2)
        .mul_add(z, 7.495_300_3e-2)
        .mul_add(z, 1.666_675_2e-1);
    (p * z).mul_add(s, s)
}

/// `acos(x)` in `[0, pi]` for `x` in `[-1, 1]` (clamped), within 3e-7 radians. For `|x| > 1/2`
/// through `acos(|x|) = 2 asin(sqrt((1 - |x|) / 2))`, which keeps the precision near the poles.
#[inline(always)]
pub fn acos(x: f32) -> f32 {
    let a = x.abs().min(1.0);
    let r = if a > 0.5 {
        let z = 0.5 * (1.0 - a);
        2.0 * asin_poly(z.sqrt(), z)
    } else {
        FRAC_PI_2 - asin_poly(a, a * a)
    };
    if x < 0.0 {
        PI - r
    } else {
        r
    }
}

/// `(sin x, cos x)` for `|x| <= 4 pi`, within 2e-7 (absolute) of the exact values: `x`
/// reduced by the nearest multiple of `pi / 2` in two parts (Cody and Waite), then Cephes'
/// `sinf` and `cosf` polynomials on `[-pi / 4, pi / 4]`. Larger arguments lose precision with
/// the reduction; nothing in haze passes them.
#[inline(always)]
pub fn sin_cos(x: f32) -> (f32, f32) {
    const PIO2_HI: f32 = 1.570_796_4;
    const PIO2_LO: f32 = -4.371_139e-8;
    let q = (x * std::f32::consts::FRAC_2_PI).round();
    let r = q.mul_add(-PIO2_LO, q.mul_add(-PIO2_HI, x));
    let z = r * r;
    let s = (-1.951_529_6e-4_f32).mul_add(z, 8.332_161e-3).mul_add(z, -1.666_665_5e-1) * z;
    let s = s.mul_add(r, r);
    let c = 2.443_315_7e-5_f32.mul_add(z, -1.388_731_6e-3).mul_add(z, 4.166_664_6e-2) * z * z;
    let c = c + (-0.5f32).mul_add(z, 1.0);
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points evenly spread over `[lo, hi]`, both ends included.
    fn grid(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f32> {
        (0..=n).map(move |k| (lo + (hi - lo) * k as f64 / n as f64) as f32)
    }

    #[test]
    fn atan2_matches_f64() {
        let mut worst = 0.0f64;
        for y in grid(-3.0, 3.0, 601) {
            for x in grid(-3.0, 3.0, 601) {
                if x == 0.0 && y == 0.0 {
                    continue;
                }
                let exact = (y as f64).atan2(x as f64);
                let e = (atan2(y, x) as f64 - exact).abs();
                // `y = +-0` with `x < 0`: +pi here, where f64 gives -pi for -0.0.
                let e = e.min((e - 2.0 * std::f64::consts::PI).abs());
                worst = worst.max(e);
            }
        }
        // Unit directions near the axes and tiny or huge ratios.
        for t in grid(-20.0, 20.0, 4001) {
            let (y, x) = (t.exp2() * 0.37, 1.0f32);
            for (yy, xx) in [(y, x), (x, y), (-y, x), (y, -x), (-x, -y)] {
                let e = (atan2(yy, xx) as f64 - (yy as f64).atan2(xx as f64)).abs();
                worst = worst.max(e);
            }
        }
        assert!(worst < 3e-7, "atan2 error {worst}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(0.0, -1.0), PI);
        assert_eq!(atan2(1.0, 0.0), FRAC_PI_2);
    }

    #[test]
    fn acos_matches_f64() {
        let mut worst = 0.0f64;
        for x in grid(-1.0, 1.0, 2_000_000) {
            worst = worst.max((acos(x) as f64 - (x as f64).acos()).abs());
        }
        // Near the poles, where acos is steep.
        for k in 0..2000 {
            let x = 1.0 - k as f32 * f32::EPSILON * 0.5;
            for x in [x, -x] {
                worst = worst.max((acos(x) as f64 - (x as f64).acos()).abs());
            }
        }
        assert!(worst < 3e-7, "acos error {worst}");
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(1.5), 0.0, "clamped");
        assert!((acos(-1.0) - PI).abs() <= f32::EPSILON * PI);
    }

    #[test]
    fn sin_cos_match_f64() {
        let mut worst = 0.0f64;
        let lim = 4.0 * std::f64::consts::PI;
        for x in grid(-lim, lim, 4_000_000) {
            let (s, c) = sin_cos(x);
            let x = x as f64;
            worst = worst.max((s as f64 - x.sin()).abs()).max((c as f64 - x.cos()).abs());
        }
        assert!(worst < 2e-7, "sin_cos error {worst}");
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        // The sign of sin at the ends of [0, pi], which callers test for poles.
        assert!(sin_cos(PI).0.abs() < 1e-7 && sin_cos(1e-30).0 >= 0.0);
    }
}
