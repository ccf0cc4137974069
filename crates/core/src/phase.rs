//! Phase functions (Mitsuba 3 plugin names `isotropic` and `hg`).
//!
//! Directions are *propagation* directions: `d_in` is the direction the light travelled before
//! scattering, `d_out` after it, `cos_theta = dot(d_in, d_out)`. Values are per steradian and
//! every phase function here is sampled exactly, so `pdf == value`.

use crate::frame::Frame;
use crate::sampling::{sample_uniform_sphere, uniform_sphere_pdf};
use crate::INV_4PI;
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    Isotropic,
    /// Henyey-Greenstein with asymmetry `g` in `(-1, 1)`; `g > 0` scatters forward.
    HenyeyGreenstein {
        g: f32,
    },
}

impl Phase {
    /// `p(cos_theta)`, normalised over the sphere.
    pub fn eval(&self, d_in: Vec3, d_out: Vec3) -> f32 {
        match *self {
            Phase::Isotropic => INV_4PI,
            Phase::HenyeyGreenstein { g } => hg(d_in.dot(d_out), g),
        }
    }

    /// Samples `d_out` given `d_in`; returns the direction and its pdf (= value).
    pub fn sample(&self, d_in: Vec3, u: Vec2) -> (Vec3, f32) {
        match *self {
            Phase::Isotropic => (sample_uniform_sphere(u), uniform_sphere_pdf()),
            Phase::HenyeyGreenstein { g } => {
                let cos_t = sample_hg_cos(u.x, g);
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let phi = 2.0 * crate::PI * u.y;
                let local = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                (Frame::from_normal(d_in).to_world(local), hg(cos_t, g))
            }
        }
    }

    /// Largest value over all angle pairs (used by light-cluster bounds): `1/(4 pi)` for the
    /// isotropic phase, `(1+|g|)/(4 pi (1-|g|)^2)` for HG (at `cos_theta = sign(g)`).
    pub fn max_value(&self) -> f32 {
        match *self {
            Phase::Isotropic => INV_4PI,
            Phase::HenyeyGreenstein { g } => {
                let a = g.abs();
                INV_4PI * (1.0 + a) / ((1.0 - a) * (1.0 - a))
            }
        }
    }
}

/// Henyey-Greenstein 1941: `p(cos) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2))`.
pub fn hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    INV_4PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// Inverts the HG CDF in `cos_theta`: `cos = (1 + g^2 - ((1 - g^2)/(1 - g + 2 g u))^2) / (2 g)`;
/// `u = 0` gives `cos = -1`, `u = 1` gives `cos = 1`. Near `g = 0` the formula cancels
/// catastrophically, so fall back to the isotropic inverse.
pub fn sample_hg_cos(u: f32, g: f32) -> f32 {
    if g.abs() < 1e-3 {
        return (2.0 * u - 1.0).clamp(-1.0, 1.0);
    }
    let sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - sq * sq) / (2.0 * g)).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Sampler;
    use haze_testkit::chi2::chi2_sphere;

    #[test]
    fn hg_sampling_matches_pdf_chi2() {
        for &g in &[-0.7f32, 0.0, 0.3, 0.5, 0.9] {
            let phase = Phase::HenyeyGreenstein { g };
            let d_in = Vec3::new(0.3, -0.5, 0.81).normalize();
            let mut s = Sampler::from_seed(11);
            let r = chi2_sphere(|| phase.sample(d_in, s.next_2d()).0, |d| phase.eval(d_in, d), 300_000);
            assert!(r.passed(0.01), "g = {g}: {r}");
        }
    }

    #[test]
    fn hg_chi2_rejects_wrong_sign() {
        // The test must be able to fail: samples drawn with g = 0.5 against the pdf for g = -0.5.
        let d_in = Vec3::Z;
        let mut s = Sampler::from_seed(12);
        let samp = Phase::HenyeyGreenstein { g: 0.5 };
        let wrong = Phase::HenyeyGreenstein { g: -0.5 };
        let r = chi2_sphere(|| samp.sample(d_in, s.next_2d()).0, |d| wrong.eval(d_in, d), 50_000);
        assert!(!r.passed(0.01), "{r}");
    }

    #[test]
    fn hg_pdf_integrates_to_one_and_returned_pdf_matches_eval() {
        for &g in &[-0.9f32, -0.3, 0.0, 0.5, 0.95] {
            // Integrate over cos_theta with a fine midpoint rule (2 pi from phi).
            let m = 200_000;
            let h = 2.0 / m as f64;
            let integral: f64 =
                (0..m).map(|i| hg((-1.0 + (i as f64 + 0.5) * h) as f32, g) as f64 * h).sum::<f64>()
                    * 2.0
                    * std::f64::consts::PI;
            assert!((integral - 1.0).abs() < 2e-3, "g = {g}: {integral}");
            let phase = Phase::HenyeyGreenstein { g };
            let mut s = Sampler::from_seed(3);
            for _ in 0..100 {
                let d_in = crate::sampling::sample_uniform_sphere(s.next_2d());
                let (d, pdf) = phase.sample(d_in, s.next_2d());
                assert!((pdf - phase.eval(d_in, d)).abs() <= 1e-3 * pdf.max(1.0));
                assert!(phase.eval(d_in, d) <= phase.max_value() * 1.0001);
            }
        }
    }
}
