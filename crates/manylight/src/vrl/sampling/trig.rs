//! The two trigonometric functions of equiangular sampling, on the only domains it uses: the
//! angle `(0, pi)` that a segment subtends, from the two legs of its tangent, and `tan` on
//! `[0, pi/2)`. They are a rational approximation each (Cephes, S. L. Moshier; the same
//! coefficients as Go's `math.Tan` and `math.Atan`) behind a reduction that these domains make
//! short. libm's general versions cost about twice as much in the VRL estimator's inner loop, where
//! each sample needs one of each. Both stay within 2 ulp of libm (tests below).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// `pi/2 - FRAC_PI_2`: with it, `(FRAC_PI_2 - x) + FRAC_PI_2_LO` keeps `x`'s precision.
const FRAC_PI_2_LO: f64 = 6.123_233_995_736_766e-17;

/// The angle in `(0, pi)` whose tangent is `y / x`, for `y > 0` and any `x` (`x = -0` counts as
/// negative): `atan2(y, x)`. Cephes' reduction of `atan(r)`, `r = y / |x|`, to `|r'| <= 0.66`
/// (`pi/2 - atan(1/r)` above `tan(3 pi/8)`, `pi/4 + atan((r - 1)/(r + 1))` above 0.66), with the
/// ratio formed after it so that each branch divides once, and with `pi - atan(r)` for negative
/// `x` folded into the constant: `c + s atan(r')` with `c` a multiple of `pi/4` in two parts.
#[inline]
pub(super) fn angle(y: f64, x: f64) -> f64 {
    let ax = x.abs();
    let neg = x.is_sign_negative();
    // The multiple of pi/4 in a double and its remainder (Cephes' MOREBITS), the sign of the
    // reduced atan, and the reduced argument.
    let (hi, lo, sign, r) = if y > 2.414_213_562_373_095 * ax {
        (FRAC_PI_2, FRAC_PI_2_LO, if neg { 1.0 } else { -1.0 }, ax / y)
    } else if y > 0.66 * ax {
        let r = (y - ax) / (y + ax);
        if neg {
            (3.0 * FRAC_PI_4, 1.5 * FRAC_PI_2_LO, -1.0, r)
        } else {
            (FRAC_PI_4, 0.5 * FRAC_PI_2_LO, 1.0, r)
        }
    } else if neg {
        (PI, 2.0 * FRAC_PI_2_LO, -1.0, y / ax)
    } else {
        (0.0, 0.0, 1.0, y / ax)
    };
    (hi + sign * atan_small(r)) + lo
}

/// `atan(x)` for `|x| <= 0.66` (Cephes `atan.c`): `x + x z P(z) / Q(z)`, `z = x^2`.
#[inline]
fn atan_small(x: f64) -> f64 {
    let z = x * x;
    x + x * (z * horner(z, &ATAN_P) / horner(z, &ATAN_Q))
}

/// Cephes `atan.c`, highest degree first; `ATAN_Q` is monic.
const ATAN_P: [f64; 5] = [
    -8.750_608_600_031_904e-1,
    -1.615_753_718_733_365e1,
    -7.500_855_792_314_705e1,
    -1.228_866_684_490_136_2e2,
    -6.485_021_904_942_025e1,
];
const ATAN_Q: [f64; 6] = [
    1.0,
    2.485_846_490_142_306_4e1,
    1.650_270_098_316_988_6e2,
    4.328_810_604_912_903e2,
    4.853_903_996_359_137e2,
    1.945_506_571_482_614e2,
];

/// `tan(t)` for `t` in `[0, pi/2)`: the rational approximation on `[0, pi/4]` (Cephes `tan.c`,
/// `tan(z) = z + z zz P(zz) / Q(zz)`), and `1 / tan(pi/2 - t) = Q / (z (Q + zz P))` above, with
/// `z = pi/2 - t` exact (Sterbenz) plus the low part of `pi/2`.
#[inline]
pub(super) fn tan(t: f64) -> f64 {
    let reflect = t > FRAC_PI_4;
    let z = if reflect { (FRAC_PI_2 - t) + FRAC_PI_2_LO } else { t };
    let zz = z * z;
    let (p, q) = (horner(zz, &TAN_P), horner(zz, &TAN_Q));
    if reflect {
        q / (z * (q + zz * p))
    } else {
        z + z * zz * p / q
    }
}

/// Cephes `tan.c`, highest degree first; `TAN_Q` is monic.
const TAN_P: [f64; 3] = [-1.309_369_391_813_837_9e4, 1.153_516_648_385_874_2e6, -1.795_652_519_764_848_9e7];
const TAN_Q: [f64; 5] = [
    1.0,
    1.368_129_634_706_929_6e4,
    -1.320_892_344_402_109_7e6,
    2.500_838_018_233_579e7,
    -5.386_957_559_294_546_5e7,
];

/// `sum c[i] z^(n-1-i)` by Horner's rule.
#[inline(always)]
fn horner(z: f64, c: &[f64]) -> f64 {
    c.iter().fold(0.0, |acc, &k| acc * z + k)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            0.0
        } else {
            ((got - want) / want).abs() / f64::EPSILON
        }
    }

    #[test]
    fn tan_matches_libm_on_its_domain() {
        let n = 1_000_000;
        let mut worst = (0.0, 0.0);
        let at = |t: f64, worst: &mut (f64, f64)| {
            let e = ulps(tan(t), t.tan());
            if e > worst.0 {
                *worst = (e, t);
            }
        };
        for i in 0..n {
            at(FRAC_PI_2 * i as f64 / n as f64, &mut worst);
        }
        // Near pi/2, where tan is large and the reduction matters, and near 0 and pi/4.
        for i in 1..n {
            at(FRAC_PI_2 - 1e-12 * i as f64, &mut worst);
            at(1e-300 * i as f64, &mut worst);
            at(FRAC_PI_4 + 1e-12 * (i as f64 - n as f64 / 2.0), &mut worst);
        }
        assert!(worst.0 <= 2.0, "tan: {} ulp at {}", worst.0, worst.1);
        assert_eq!(tan(0.0), 0.0);
        assert!(tan(FRAC_PI_2) > 1e16);
    }

    #[test]
    fn angle_matches_atan2_for_positive_y() {
        let mut s = haze_core::Sampler::from_seed(5);
        let mut worst = (0.0, 0.0, 0.0);
        for i in 0..2_000_000 {
            let y = (60.0 * s.next_1d() as f64 - 30.0).exp();
            let x = (60.0 * s.next_1d() as f64 - 30.0).exp() * if i % 2 == 0 { 1.0 } else { -1.0 };
            // Also the octant boundaries and the axes.
            let x = match i % 7 {
                0 => y / 2.414_213_562_373_095,
                1 => y / 0.66,
                2 => 0.0,
                3 => -0.0,
                4 => -y,
                _ => x,
            };
            let e = ulps(angle(y, x), y.atan2(x));
            if e > worst.0 {
                worst = (e, y, x);
            }
        }
        assert!(worst.0 <= 2.0, "angle: {} ulp at y {} x {}", worst.0, worst.1, worst.2);
        assert_eq!(angle(1.0, 0.0), FRAC_PI_2);
        assert_eq!(angle(1.0, -0.0), FRAC_PI_2);
        assert_eq!(angle(1e-300, -1.0), 1e-300f64.atan2(-1.0));
        assert_eq!(angle(1e-300, 1.0), 1e-300);
    }
}
