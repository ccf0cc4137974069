//! Mitsuba 3's `mask`: a nested BSDF seen with probability `opacity`, else nothing (light
//! passes straight through, a null-typed event like `null`). `f = opacity f_nested`; shadow
//! rays cross with `1 - opacity` (Mitsuba's `eval_null_transmission`).

use super::{Bsdf, BsdfSample};
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    /// In `[0, 1]`; an RGB texture counts by its luminance (Mitsuba's `eval_1`).
    pub opacity: Texture,
    pub nested: Box<Bsdf>,
}

impl Mask {
    /// The opacity at `uv`: the luminance of the texture's value ([`Texture::eval_1`]).
    pub fn alpha(&self, uv: TexPoint) -> f32 {
        self.opacity.eval_1(uv).clamp(0.0, 1.0)
    }

    /// The nested BSDF with probability `alpha` (its sample, pdf times `alpha`, weight
    /// unchanged: `alpha` cancels), else straight through with weight 1 and probability
    /// `1 - alpha`.
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint, with_pdf: bool) -> Option<BsdfSample> {
        let a = self.alpha(uv);
        if u1 < a {
            let s = self.nested.sample_with(wi, u1 / a, u2, uv, with_pdf)?;
            return Some(BsdfSample { pdf: s.pdf * a, ..s });
        }
        Some(BsdfSample { null: true, ..BsdfSample::specular(-wi, Rgb::ONE, 1.0 - a, true) })
    }

    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.nested.eval(wi, wo, uv) * self.alpha(uv)
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.nested.pdf(wi, wo, uv) * self.alpha(uv)
    }

    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        let (f, pdf) = self.nested.eval_pdf(wi, wo, uv);
        let a = self.alpha(uv);
        (f * a, pdf * a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testing::{albedo, check_sampling, dir, passed};

    fn mask(opacity: f32, nested: Bsdf) -> Bsdf {
        Bsdf::Mask(Box::new(Mask { opacity: Rgb::splat(opacity).into(), nested: Box::new(nested) }))
    }

    /// A mask of opacity `a` over a white diffuse surface reflects `a` and lets `1 - a` through:
    /// the albedo of its samples (null ones included) is 1, the non-null share `a`, and shadow
    /// rays see `1 - a`.
    #[test]
    fn mask_splits_between_its_bsdf_and_straight_through() {
        let white = Bsdf::Diffuse { reflectance: Rgb::ONE.into() };
        let b = mask(0.3, white.clone());
        let wi = dir(0.7, 0.2);
        assert!((albedo(&b, wi, 3, 100_000) - 1.0).abs() < 1e-3);
        let mut s = haze_core::Sampler::from_seed(9);
        let n = 100_000;
        let through =
            (0..n).filter(|_| b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO).unwrap().null).count();
        assert!((through as f64 / n as f64 - 0.7).abs() < 0.005, "{through}");
        assert_eq!(b.null_transmission(wi, Vec2::ZERO), Rgb::splat(0.7));
        assert!(b.transmits_null() && b.may_pass_through() && !b.is_specular());
        let wo = dir(0.5, 2.0);
        assert_eq!(b.eval(wi, wo, Vec2::ZERO), white.eval(wi, wo, Vec2::ZERO) * 0.3);
        let r = check_sampling(&b, wi, 4, 100_000);
        assert!(passed(&r, 100_000), "{r:?}");
        // Fully opaque is the nested BSDF; fully transparent is `null`.
        assert_eq!(mask(1.0, white.clone()).null_transmission(wi, Vec2::ZERO), Rgb::ZERO);
        assert!(mask(0.0, white).sample(wi, 0.0, Vec2::splat(0.5), Vec2::ZERO).unwrap().null);
    }
}
