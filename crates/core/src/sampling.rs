//! Sampling routines, each with its pdf beside it (pbrt-v4's `util/sampling.h` families).
//! Tests check every pair: the pdf integrates to one and histograms of samples match it.

use crate::{INV_4PI, INV_PI, PI};
use glam::{Vec2, Vec3};

/// Uniform direction on the unit sphere. pdf `1/(4 pi)` per steradian.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin_p, cos_p) = crate::fastmath::sin_cos(2.0 * PI * u.y);
    Vec3::new(r * cos_p, r * sin_p, z)
}

pub const fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Cosine-weighted direction on the `+z` hemisphere. pdf `cos(theta)/pi` per steradian.
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Shirley-Chiu concentric map from the unit square to the unit disk (area-preserving).
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, PI / 4.0 * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - PI / 4.0 * (o.x / o.y))
    };
    let (sin_t, cos_t) = crate::fastmath::sin_cos(theta);
    Vec2::new(r * cos_t, r * sin_t)
}

/// Uniform direction inside the cone around `+z` with `cos(theta) >= cos_max`.
/// pdf `1 / (2 pi (1 - cos_max))` per steradian.
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (sin_p, cos_p) = crate::fastmath::sin_cos(2.0 * PI * u.y);
    Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
}

pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform point on a triangle as barycentrics `(b1, b2)` (the weights of vertices 1 and 2);
/// Heitz 2019 "A low-distortion map between triangle and square". pdf `1/area`.
pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    let (mut b0, mut b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    b0 = b0.clamp(0.0, 1.0);
    b1 = b1.clamp(0.0, 1.0);
    Vec2::new(b1, 1.0 - b0 - b1)
}

/// Exponential distance `x >= 0` with rate `a`: `x = -ln(1-u)/a`, pdf `a exp(-a x)` per unit length.
pub fn sample_exponential(u: f32, a: f32) -> f32 {
    -(1.0 - u).ln() / a
}

pub fn exponential_pdf(x: f32, a: f32) -> f32 {
    a * (-a * x).exp()
}

/// Inverse of [`sample_exponential`]: the uniform number that produces `x`.
pub fn invert_exponential_sample(x: f32, a: f32) -> f32 {
    1.0 - (-a * x).exp()
}

/// Power heuristic with exponent 2 (Veach 1997), for one sample from each of two strategies.
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a == 0.0 {
        0.0
    } else if a.is_infinite() {
        1.0
    } else {
        a / (a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Sampler;
    use haze_testkit::chi2::{chi2_sphere, Chi2Result};

    fn assert_chi2(r: Chi2Result) {
        assert!(r.passed(0.01), "{r}");
    }

    #[test]
    fn uniform_sphere_matches_pdf() {
        let mut s = Sampler::from_seed(1);
        assert_chi2(chi2_sphere(|| sample_uniform_sphere(s.next_2d()), |_| uniform_sphere_pdf(), 200_000));
    }

    #[test]
    fn cosine_hemisphere_matches_pdf() {
        let mut s = Sampler::from_seed(2);
        assert_chi2(chi2_sphere(
            || sample_cosine_hemisphere(s.next_2d()),
            |d| cosine_hemisphere_pdf(d.z),
            200_000,
        ));
    }

    #[test]
    fn cone_matches_pdf() {
        let mut s = Sampler::from_seed(3);
        let cos_max = 0.6f32;
        assert_chi2(chi2_sphere(
            || sample_uniform_cone(s.next_2d(), cos_max),
            |d| {
                if d.z >= cos_max {
                    uniform_cone_pdf(cos_max)
                } else {
                    0.0
                }
            },
            200_000,
        ));
    }

    #[test]
    fn triangle_samples_are_uniform() {
        // Compare the fraction of samples in the sub-triangle b1 + b2 < 1/2 (area 1/4) and the
        // mean barycentric (1/3 each).
        let mut s = Sampler::from_seed(4);
        let n = 100_000;
        let (mut inside, mut m1, mut m2) = (0, 0.0f64, 0.0f64);
        for _ in 0..n {
            let b = sample_uniform_triangle(s.next_2d());
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            inside += (b.x + b.y < 0.5) as u32;
            m1 += b.x as f64;
            m2 += b.y as f64;
        }
        let f = inside as f64 / n as f64;
        assert!((f - 0.25).abs() < 0.006, "{f}");
        assert!((m1 / n as f64 - 1.0 / 3.0).abs() < 0.004);
        assert!((m2 / n as f64 - 1.0 / 3.0).abs() < 0.004);
    }

    #[test]
    fn exponential_family_is_consistent() {
        let a = 1.7;
        for &u in &[0.0, 0.1, 0.5, 0.9, 0.999] {
            let x = sample_exponential(u, a);
            assert!((invert_exponential_sample(x, a) - u).abs() < 1e-5);
        }
        let h = 1e-3;
        let integral: f32 = (0..20_000).map(|i| exponential_pdf((i as f32 + 0.5) * h, a) * h).sum();
        assert!((integral - 1.0).abs() < 1e-3);
    }
}
