//! Mitsuba 3's `blendbsdf`: the linear combination `f = (1 - w) f_0 + w f_1` of two nested BSDFs,
//! `w = clamp(weight(uv), 0, 1)` a float or a texture read as one number (its luminance,
//! Mitsuba's `eval_1`), `f_0` the first nested BSDF in document order.
//!
//! Sampling picks `f_1` with probability `w` (else `f_0`) and samples it, as Mitsuba does. A
//! specular (or null) sample keeps its weight (the choice probability cancels the blend weight)
//! and its discrete pdf times the choice probability. A non-specular direction can come from
//! either lobe, so its pdf is the mixture's `(1 - w) p_0 + w p_1` and its weight `f / pdf` of the
//! whole blend (one-sample mixture sampling, Veach's thesis, section 9.2.4): the same pdf next-event
//! estimation's MIS weight uses. Mitsuba reports the chosen lobe's own pdf and weight instead,
//! which is the same estimator when the lobes do not overlap and makes its MIS weights not sum
//! to one where they do.

use super::{Bsdf, BsdfSample};
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct Blend {
    /// In `[0, 1]` after clamping; an RGB texture counts by its luminance.
    pub weight: Texture,
    /// `[f_0, f_1]`: `f_0` at weight 0, `f_1` at weight 1.
    pub nested: [Bsdf; 2],
}

impl Blend {
    /// `w` at `uv`.
    pub fn weight(&self, uv: TexPoint) -> f32 {
        self.weight.eval_1(uv).clamp(0.0, 1.0)
    }

    /// The nested BSDFs with their blend weights `(1 - w, w)`.
    fn lobes(&self, uv: TexPoint) -> [(&Bsdf, f32); 2] {
        let w = self.weight(uv);
        [(&self.nested[0], 1.0 - w), (&self.nested[1], w)]
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint, with_pdf: bool) -> Option<BsdfSample> {
        let w = self.weight(uv);
        // Mitsuba's split of `u1`: `f_1` on `u1 <= w`, each part rescaled to [0, 1).
        let (chosen, p, u) = if u1 <= w && w > 0.0 {
            (&self.nested[1], w, u1 / w)
        } else {
            (&self.nested[0], 1.0 - w, ((u1 - w) / (1.0 - w)).min(1.0 - f32::EPSILON))
        };
        let s = chosen.sample_with(wi, u, u2, uv, with_pdf)?;
        if s.specular {
            return Some(BsdfSample { pdf: s.pdf * p, ..s });
        }
        let (f, pdf) = self.eval_pdf(wi, s.wo, uv);
        (pdf > 0.0).then(|| BsdfSample { weight: f / pdf, pdf, ..s })
    }

    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.lobes(uv).iter().map(|(b, w)| b.eval(wi, wo, uv) * *w).fold(Rgb::ZERO, |a, b| a + b)
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.lobes(uv).iter().map(|(b, w)| b.pdf(wi, wo, uv) * *w).sum()
    }

    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        self.lobes(uv).iter().fold((Rgb::ZERO, 0.0), |(f, pdf), (b, w)| {
            let (fb, pb) = b.eval_pdf(wi, wo, uv);
            (f + fb * *w, pdf + pb * *w)
        })
    }

    /// `(1 - w) t_0 + w t_1` of the nested BSDFs' straight-through transmissions.
    pub fn null_transmission(&self, wi: Vec3, uv: TexPoint) -> Rgb {
        self.lobes(uv).iter().map(|(b, w)| b.null_transmission(wi, uv) * *w).fold(Rgb::ZERO, |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::{Microfacet, MicrofacetType};
    use crate::bsdf::testing::{albedo, check_sampling, dir, passed};
    use crate::bsdf::{Conductor, RoughPlastic};

    fn blend(w: f32, a: Bsdf, b: Bsdf) -> Bsdf {
        Bsdf::Blend(Box::new(Blend { weight: Rgb::splat(w).into(), nested: [a, b] }))
    }

    fn diffuse(r: f32) -> Bsdf {
        Bsdf::Diffuse { reflectance: Rgb::splat(r).into() }
    }

    fn rough_plastic() -> Bsdf {
        let distr = Microfacet::new(MicrofacetType::Ggx, 0.2, true);
        Bsdf::RoughPlastic(Box::new(RoughPlastic::new(distr, Rgb::splat(0.4).into(), 1.5, false)))
    }

    fn mirror() -> Bsdf {
        Bsdf::Conductor(Box::new(Conductor {
            eta: Rgb::ZERO,
            k: Rgb::ONE,
            specular_reflectance: Rgb::ONE.into(),
            distr: None,
        }))
    }

    /// Two diffuse lobes blend to the diffuse of the blended albedo: `(1 - w) 0.2 + w 0.8`
    /// (analytic), in `eval`, and in the mean sample weight.
    #[test]
    fn two_diffuse_lobes_blend_linearly() {
        let b = blend(0.25, diffuse(0.2), diffuse(0.8));
        let (wi, wo) = (dir(0.7, 0.3), dir(0.4, 2.0));
        let expected = 0.75 * 0.2 + 0.25 * 0.8;
        assert!((b.eval(wi, wo, Vec2::ZERO)[0] - expected * haze_core::INV_PI * wo.z).abs() < 1e-6);
        assert!((albedo(&b, wi, 1, 100_000) - expected as f64).abs() < 1e-4);
        // Weights 0 and 1 are the nested BSDFs alone.
        assert_eq!(
            blend(0.0, diffuse(0.2), diffuse(0.8)).eval(wi, wo, Vec2::ZERO),
            diffuse(0.2).eval(wi, wo, Vec2::ZERO)
        );
        assert_eq!(
            blend(1.0, diffuse(0.2), diffuse(0.8)).eval(wi, wo, Vec2::ZERO),
            diffuse(0.8).eval(wi, wo, Vec2::ZERO)
        );
    }

    /// A glossy and a diffuse lobe: samples follow the mixture pdf (chi-square), their weights
    /// are `eval / pdf`, and the albedo is the blend of the nested albedos.
    #[test]
    fn overlapping_lobes_sample_the_mixture() {
        let b = blend(0.6, rough_plastic(), diffuse(0.9));
        for wi in [dir(0.9, 0.1), dir(0.3, 1.0)] {
            let r = check_sampling(&b, wi, 7, 200_000);
            assert!(passed(&r, 200_000), "{r:?}");
            let expected =
                0.4 * albedo(&rough_plastic(), wi, 8, 400_000) + 0.6 * albedo(&diffuse(0.9), wi, 9, 400_000);
            let got = albedo(&b, wi, 10, 400_000);
            assert!((got - expected).abs() < 4e-3, "{got} vs {expected}");
        }
    }

    /// A mirror blended with a diffuse lobe: the specular samples come with probability
    /// `1 - w`, and the albedo is `(1 - w) 1 + w 0.5`.
    #[test]
    fn specular_and_diffuse_lobes() {
        let b = blend(0.3, mirror(), diffuse(0.5));
        let wi = dir(0.8, 0.5);
        assert!((albedo(&b, wi, 3, 200_000) - (0.7 + 0.3 * 0.5)).abs() < 2e-3);
        let mut s = haze_core::Sampler::from_seed(4);
        let n = 100_000;
        let specular =
            (0..n).filter(|_| b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO).unwrap().specular).count();
        assert!((specular as f64 / n as f64 - 0.7).abs() < 0.005, "{specular}");
        assert!(!b.is_specular() && b.front_only());
        assert!(blend(0.3, mirror(), mirror()).is_specular());
    }
}
