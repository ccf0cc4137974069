//! Isotropic microfacet distributions (Beckmann and GGX) with Smith shadowing-masking and
//! sampling of all normals or of the visible normals only, as in Mitsuba 3's
//! `MicrofacetDistribution` (`microfacet.h`).
//!
//! Directions are in the local shading frame (`z` = macrosurface normal) and point away from the
//! surface. Microfacet normals `m` have `m.z > 0`.

use glam::{Vec2, Vec3};
use haze_core::sampling::sample_uniform_disk_concentric;
use haze_core::PI;

/// `distribution` parameter of the rough BSDFs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MicrofacetType {
    /// `exp(-tan^2(theta) / alpha^2) / (pi alpha^2 cos^4(theta))` (Mitsuba's default).
    Beckmann,
    /// Trowbridge-Reitz: `1 / (pi alpha^2 cos^4(theta) (1 + tan^2(theta) / alpha^2)^2)`.
    Ggx,
}

impl MicrofacetType {
    /// The Mitsuba name (`beckmann`, `ggx`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "beckmann" => Some(MicrofacetType::Beckmann),
            "ggx" => Some(MicrofacetType::Ggx),
            _ => None,
        }
    }
}

/// An isotropic microfacet distribution of roughness `alpha` (RMS slope for Beckmann).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub ty: MicrofacetType,
    pub alpha: f32,
    /// Sample the distribution of normals visible from `wi` (Heitz and d'Eon 2014) instead of
    /// `D(m) cos(theta_m)`.
    pub sample_visible: bool,
}

impl Microfacet {
    /// `alpha` is clamped to at least 1e-4 as Mitsuba does (a smaller one is numerically a
    /// smooth surface).
    pub fn new(ty: MicrofacetType, alpha: f32, sample_visible: bool) -> Self {
        Microfacet { ty, alpha: alpha.max(1e-4), sample_visible }
    }

    /// The normal distribution `D(m)` (per unit projected... solid angle: `∫ D(m) m.z dm = 1`).
    pub fn eval(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let cos2 = m.z * m.z;
        let xy = (m.x * m.x + m.y * m.y) / a2;
        let d = match self.ty {
            MicrofacetType::Beckmann => (-xy / cos2).exp() / (PI * a2 * cos2 * cos2),
            MicrofacetType::Ggx => {
                let t = xy + cos2;
                1.0 / (PI * a2 * t * t)
            }
        };
        // Mitsuba's guard against underflow in later stages.
        if d * m.z > 1e-20 && d.is_finite() {
            d
        } else {
            0.0
        }
    }

    /// Smith's monodirectional shadowing-masking `G1(v, m)`; zero when `v` sees the back of
    /// the microfacet (`dot(v, m)` and `v.z` of different signs). The Beckmann one is
    /// Walter et al.'s (2007) rational fit.
    pub fn smith_g1(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy_alpha2 = self.alpha * self.alpha * (v.x * v.x + v.y * v.y);
        if xy_alpha2 == 0.0 {
            return 1.0;
        }
        let tan_alpha2 = xy_alpha2 / (v.z * v.z);
        match self.ty {
            MicrofacetType::Beckmann => {
                let a = 1.0 / tan_alpha2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
            MicrofacetType::Ggx => 2.0 / (1.0 + (1.0 + tan_alpha2).sqrt()),
        }
    }

    /// Separable Smith shadowing-masking `G1(wi, m) G1(wo, m)`.
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.smith_g1(wi, m) * self.smith_g1(wo, m)
    }

    /// Density of [`Self::sample`] producing `m`, per unit solid angle of `m`. `wi.z > 0`.
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        let d = self.eval(m);
        if self.sample_visible {
            d * self.smith_g1(wi, m) * wi.dot(m).abs() / wi.z
        } else {
            d * m.z
        }
    }

    /// Samples a microfacet normal seen from `wi` (`wi.z > 0`); returns it with its pdf
    /// ([`Self::pdf`]). With visible sampling, the slope-space method of Heitz and d'Eon (2014):
    /// stretch `wi` by `alpha`, sample the slopes of the unit-roughness distribution seen from
    /// it, rotate, unstretch.
    pub fn sample(&self, wi: Vec3, u: Vec2) -> (Vec3, f32) {
        let m = if self.sample_visible {
            let wi_p = Vec3::new(self.alpha * wi.x, self.alpha * wi.y, wi.z).normalize();
            let sin_theta = (1.0 - wi_p.z * wi_p.z).max(0.0).sqrt();
            let (sin_phi, cos_phi) = if sin_theta > 0.0 {
                ((wi_p.y / sin_theta).clamp(-1.0, 1.0), (wi_p.x / sin_theta).clamp(-1.0, 1.0))
            } else {
                (0.0, 1.0)
            };
            let s = self.sample_visible_11(wi_p.z, u);
            let slope = Vec2::new(cos_phi * s.x - sin_phi * s.y, sin_phi * s.x + cos_phi * s.y) * self.alpha;
            Vec3::new(-slope.x, -slope.y, 1.0).normalize()
        } else {
            let a2 = self.alpha * self.alpha;
            let tan2 = match self.ty {
                MicrofacetType::Beckmann => -a2 * (1.0 - u.x).ln(),
                MicrofacetType::Ggx => a2 * u.x / (1.0 - u.x),
            };
            let cos_theta = 1.0 / (1.0 + tan2).sqrt();
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
        };
        (m, self.pdf(wi, m))
    }

    /// Slopes of the visible normals of the unit-roughness distribution seen from a direction
    /// in the `xz` plane with cosine `cos_theta_i`.
    fn sample_visible_11(&self, cos_theta_i: f32, u: Vec2) -> Vec2 {
        match self.ty {
            MicrofacetType::Beckmann => {
                // Inverse of the marginal CDF in the slope x by safeguarded Newton iterations
                // (Jakob's improvement of Heitz and d'Eon 2014), then a Gaussian in y.
                if cos_theta_i > 0.99999 {
                    let r = (-(1.0 - u.x).max(1e-12).ln()).sqrt();
                    let phi = 2.0 * PI * u.y;
                    return Vec2::new(r * phi.cos(), r * phi.sin());
                }
                // In f32 with Mitsuba 3's stopping rule (|CDF error| < 1e-5, at most 9 Newton
                // steps; `MicrofacetDistribution::sample_visible_11`): f64 and 1e-7 cost twice
                // the time (f64 `exp`/`log` in every step) for slopes no f32 direction resolves.
                let ci = cos_theta_i;
                let sin_theta_i = (1.0 - ci * ci).max(0.0).sqrt();
                let tan_theta_i = sin_theta_i / ci;
                let cot_theta_i = 1.0 / tan_theta_i;
                let inv_sqrt_pi = std::f32::consts::FRAC_2_SQRT_PI * 0.5;
                let (mut a, mut c) = (-1.0f32, erf(cot_theta_i));
                let x = u.x.clamp(1e-6, 1.0 - 1e-7);
                let theta_i = ci.acos();
                let fit = 1.0 + theta_i * (-0.876 + theta_i * (0.4265 - 0.0594 * theta_i));
                let mut b = c - (1.0 + c) * (1.0 - x).powf(fit);
                let norm = 1.0 / (1.0 + c + inv_sqrt_pi * tan_theta_i * (-cot_theta_i * cot_theta_i).exp());
                // The slope `erfinv(b)` of the converged step, kept (one `erfinv` fewer).
                let mut slope = None;
                for _ in 0..9 {
                    if !(b >= a && b <= c) {
                        b = 0.5 * (a + c);
                    }
                    let inv = erfinv(b);
                    let value = norm * (1.0 + b + inv_sqrt_pi * tan_theta_i * (-inv * inv).exp()) - x;
                    let derivative = norm * (1.0 - inv * tan_theta_i);
                    if value.abs() < 1e-5 {
                        slope = Some(inv);
                        break;
                    }
                    if value > 0.0 {
                        c = b;
                    } else {
                        a = b;
                    }
                    b -= value / derivative;
                }
                let y = (2.0 * u.y - 1.0).clamp(-1.0 + 1e-7, 1.0 - 1e-7);
                Vec2::new(slope.unwrap_or_else(|| erfinv(b)), erfinv(y))
            }
            MicrofacetType::Ggx => {
                // Project a disk sample onto the visible half of the hemisphere (Heitz 2017,
                // "A simpler and exact sampling routine for the GGX distribution of visible
                // normals"), then convert the normal to a slope.
                let mut p = sample_uniform_disk_concentric(u);
                let s = 0.5 * (1.0 + cos_theta_i);
                p.y = (1.0 - p.x * p.x).max(0.0).sqrt() * (1.0 - s) + p.y * s;
                let z = (1.0 - p.length_squared()).max(0.0).sqrt();
                let sin_theta_i = (1.0 - cos_theta_i * cos_theta_i).max(0.0).sqrt();
                let norm = 1.0 / (sin_theta_i * p.y + cos_theta_i * z);
                Vec2::new(cos_theta_i * p.y - sin_theta_i * z, p.x) * norm
            }
        }
    }
}

/// Error function, as `1 - erfc` with the Chebyshev fit of `erfc` from Numerical Recipes
/// (`erfcc`: relative error of `erfc` below 1.2e-7 everywhere), evaluated in f32 like Mitsuba's
/// `erf` (absolute error ~1e-7, which is the resolution of the f32 CDF values it is used for).
// The published coefficients, as printed; the compiler rounds them to f32.
#[allow(clippy::excessive_precision)]
pub(crate) fn erf(x: f32) -> f32 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let mut p = 0.17087277;
    for c in
        [-0.82215223, 1.48851587, -1.13520398, 0.27886807, -0.18628806, 0.09678418, 0.37409196, 1.00002368]
    {
        p = c + t * p;
    }
    let erfc = t * (-z * z - 1.26551223 + t * p).exp();
    (1.0 - erfc).copysign(x)
}

/// Inverse error function on (-1, 1): Giles' (2010) single-precision approximation (relative
/// error below 4e-7).
// The published coefficients, as printed; the compiler rounds them to f32.
#[allow(clippy::excessive_precision)]
pub(crate) fn erfinv(y: f32) -> f32 {
    let w = -((1.0 - y) * (1.0 + y)).ln();
    if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_36e-8;
        for c in [
            3.432_739_39e-7,
            -3.523_387_7e-6,
            -4.391_506_54e-6,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ] {
            p = c + p * w;
        }
        p * y
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        for c in [
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ] {
            p = c + p * w;
        }
        p * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testing::{chi2_rotated, passed};
    use haze_core::Sampler;

    fn all() -> Vec<Microfacet> {
        let mut v = Vec::new();
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for alpha in [0.1, 0.5] {
                for vis in [true, false] {
                    v.push(Microfacet::new(ty, alpha, vis));
                }
            }
        }
        v
    }

    #[test]
    fn erf_and_inverse_agree() {
        // Against libm's erf / erfc (Python's math.erf): absolute error and, in the tail,
        // relative error of erfc.
        for (x, want) in
            [(0.5, 0.520_499_877_813_046_5), (2.9, 0.999_958_902_121_900_5), (3.1, 0.999_988_351_342_632_8)]
        {
            // f32: the approximation's 1.2e-7 plus rounding.
            assert!((erf(x as f32) as f64 - want).abs() < 3e-7, "{x}");
            assert!((erf(-x as f32) as f64 + want).abs() < 3e-7);
        }
        for &y in &[-0.999f32, -0.5, 0.0, 0.3, 0.9, 0.99999] {
            let x = erfinv(y);
            let d = std::f32::consts::FRAC_2_SQRT_PI * (-x * x).exp();
            // |x - erfinv(y)| = |erf(x) - y| / erf'(x) to first order; in the tail, where
            // erf' is tiny, the CDF error (what sampling sees) instead.
            let err = (erf(x) - y).abs();
            assert!(err / d <= 1e-5 * x.abs().max(1e-1) || err <= 3e-7, "{y}: {x}");
        }
    }

    /// The projected area of the microsurface is that of the macrosurface:
    /// `∫ D(m) m.z dm = 1`, and with visible normals `∫ G1(wi, m) max(0, wi.m) D(m) dm = wi.z`.
    #[test]
    fn normalisation() {
        let mut s = Sampler::from_seed(3);
        let wi = Vec3::new(0.6, 0.0, 0.8);
        for d in all() {
            let n = 400_000;
            let (mut a, mut b) = (0.0f64, 0.0f64);
            for _ in 0..n {
                // Uniform on the upper hemisphere, pdf 1/(2 pi).
                let m = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let m = Vec3::new(m.x, m.y, m.z.abs());
                a += (d.eval(m) * m.z) as f64;
                b += (d.eval(m) * d.smith_g1(wi, m) * wi.dot(m).max(0.0)) as f64;
            }
            let scale = 2.0 * std::f64::consts::PI / n as f64;
            let tol = if d.alpha < 0.2 { 0.05 } else { 0.01 };
            assert!((a * scale - 1.0).abs() < tol, "{d:?}: {}", a * scale);
            // Smith G1 of the Beckmann fit is approximate (Walter et al. report < 0.4 %).
            assert!((b * scale / 0.8 - 1.0).abs() < tol, "{d:?}: {}", b * scale / 0.8);
        }
    }

    #[test]
    fn sampling_matches_pdf() {
        for d in all() {
            for wi in
                [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.8, 0.0, 0.6), Vec3::new(-0.3, 0.9, 0.3).normalize()]
            {
                let mut s = Sampler::from_seed(11);
                let res = chi2_rotated(
                    || {
                        let (m, pdf) = d.sample(wi, s.next_2d());
                        assert!((pdf - d.pdf(wi, m)).abs() <= 1e-3 * pdf.max(1.0), "returned pdf");
                        Some(m)
                    },
                    |m| d.pdf(wi, m),
                    200_000,
                );
                assert!(passed(&res, 200_000), "{d:?} wi {wi}: {res}");
            }
        }
    }
}
