//! Mitsuba 3's `pplastic` in its unpolarised (RGB) form: a rough dielectric coating's specular
//! lobe `s F(wi.m) D(m) G / (4 cos_i)` plus a diffuse base seen through the coating twice,
//! `(1 - F(cos_i)) (1 - F(cos_o)) rho / pi` (no inter-reflections, unlike `roughplastic`).
//! Sampled as Mitsuba: the specular lobe with probability `s_mean / (rho_mean + s_mean)`
//! (visible normals or `D(m) cos`), else a cosine-weighted direction; the pdf is the mixture's.

use super::fresnel_dielectric;
use super::microfacet::Microfacet;
use super::roughness::Roughness;
use super::BsdfSample;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::{Rgb, INV_PI};

#[derive(Clone, Debug, PartialEq)]
pub struct PPlastic {
    pub distr: Roughness,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    pub diffuse_reflectance: Texture,
    pub specular_reflectance: Texture,
    /// Probability of sampling the specular lobe.
    specular_weight: f32,
}

impl PPlastic {
    pub fn new(
        distr: Roughness,
        eta: f32,
        diffuse_reflectance: Texture,
        specular_reflectance: Texture,
    ) -> Self {
        let (d, s) = (diffuse_reflectance.mean().mean(), specular_reflectance.mean().mean());
        let specular_weight = if d + s > 0.0 { s / (d + s) } else { 0.5 };
        PPlastic { distr, eta, diffuse_reflectance, specular_reflectance, specular_weight }
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = if u1 < self.specular_weight {
            let m = self.distr.at(uv).sample_normal(wi, u2);
            2.0 * wi.dot(m) * m - wi
        } else {
            sample_cosine_hemisphere(u2)
        };
        let (f, pdf) = self.eval_pdf(wi, wo, uv);
        (pdf > 0.0 && pdf.is_finite()).then(|| BsdfSample::glossy(wo, f / pdf, pdf))
    }

    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.eval_pdf(wi, wo, uv).0
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.pdf_with(&self.distr.at(uv), wi, wo)
    }

    /// [`Self::pdf`] with the distribution at the hit.
    fn pdf_with(&self, distr: &Microfacet, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let m = (wi + wo).normalize();
        let p_spec =
            if wi.dot(m) <= 0.0 || wo.dot(m) <= 0.0 { 0.0 } else { distr.pdf(wi, m) / (4.0 * wo.dot(m)) };
        self.specular_weight * p_spec + (1.0 - self.specular_weight) * cosine_hemisphere_pdf(wo.z)
    }

    /// `(f cos_o, pdf)` of `wo`.
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let distr = self.distr.at(uv);
        let m = (wi + wo).normalize();
        let (f_m, _, _) = fresnel_dielectric(wi.dot(m), self.eta);
        let specular = distr.eval(m) * distr.g(wi, wo, m) / (4.0 * wi.z);
        let (f_i, _, _) = fresnel_dielectric(wi.z, self.eta);
        let (f_o, _, _) = fresnel_dielectric(wo.z, self.eta);
        let diffuse = self.diffuse_reflectance.eval(uv) * ((1.0 - f_i) * (1.0 - f_o) * INV_PI * wo.z);
        let f = self.specular_reflectance.eval(uv) * (f_m * specular) + diffuse;
        (f, self.pdf_with(&distr, wi, wo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::MicrofacetType;
    use crate::bsdf::testing::{albedo, check_sampling, dir, passed};
    use crate::bsdf::Bsdf;

    fn pplastic(ty: MicrofacetType, alpha: f32, visible: bool, rho: f32) -> Bsdf {
        Bsdf::PPlastic(Box::new(PPlastic::new(
            Microfacet::new(ty, alpha, visible).into(),
            1.49,
            Rgb::splat(rho).into(),
            Rgb::ONE.into(),
        )))
    }

    #[test]
    fn pplastic_sampling_matches_its_pdf_and_conserves_energy() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (alpha, cos, visible) in [(0.06, 0.8, true), (0.3, 0.3, false), (0.5, 0.9, true)] {
                let b = pplastic(ty, alpha, visible, 0.5);
                let r = check_sampling(&b, dir(cos, 0.7), 1, 200_000);
                assert!(passed(&r, 200_000), "{ty:?} {alpha} {cos} {visible}: {r:?}");
            }
            // A white base: reflection below 1 (the two crossings of the coating lose energy).
            for cos in [0.1, 0.5, 1.0] {
                let a = albedo(&pplastic(ty, 0.2, true, 1.0), dir(cos, 0.0), 7, 100_000);
                assert!(a < 1.0 && a > 0.5, "{ty:?} cos {cos}: {a}");
            }
        }
        // Reciprocity of f = eval / cos_o.
        let b = pplastic(MicrofacetType::Ggx, 0.3, true, 0.4);
        let (wi, wo) = (dir(0.3, 0.2), dir(0.8, 2.5));
        let (f1, f2) = (b.eval(wi, wo, Vec2::ZERO) / wo.z, b.eval(wo, wi, Vec2::ZERO) / wi.z);
        assert!((f1 - f2).max_component().abs() < 1e-5 * f1.max_component(), "{f1:?} {f2:?}");
    }
}
