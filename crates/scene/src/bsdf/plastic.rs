//! Mitsuba 3's `plastic`: a diffuse base under a smooth dielectric coating. Specular
//! reflection off the coating with the Fresnel reflectance `F(wi)`; the rest enters, scatters
//! diffusely (with the internal reflections at the coating summed through `fdr_int`) and leaves
//! with `1 - F(wo)`, compressed by `1/eta^2`.

use super::{reflect, BsdfSample};
use crate::bsdf::fresnel_dielectric;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct Plastic {
    pub diffuse_reflectance: Texture,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Mitsuba's `nonlinear`: divide by `1 - R fdr_int` per channel instead of `1 - fdr_int`
    /// (the colour shift of light bouncing several times on the base).
    pub nonlinear: bool,
    /// Diffuse Fresnel reflectance seen from inside the coating, `fdr(1/eta)`.
    pub fdr_int: f32,
    /// Share of specular samples before the Fresnel weighting: `1 / (mean(diffuse) + 1)`
    /// (Mitsuba's `specular_sampling_weight` with a unit specular reflectance).
    pub specular_sampling_weight: f32,
}

/// Hemispherical average of the Fresnel reflectance of an interface of relative index `eta`
/// seen from the side of index 1 (`∫ F(cos) 2 cos dcos`), by the fits Mitsuba uses: Egan and
/// Hilgeman (1973) for `eta < 1`, d'Eon and Irving (2011) above.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let i = 1.0 / eta;
        let (i2, i3, i4, i5) = (i * i, i * i * i, i * i * i * i, i * i * i * i * i);
        0.919317 - 3.4793 * i + 6.75335 * i2 - 7.80989 * i3 + 4.98554 * i4 - 1.36881 * i5
    }
}

impl Plastic {
    pub fn new(diffuse_reflectance: Texture, eta: f32, nonlinear: bool) -> Self {
        let d_mean = diffuse_reflectance.mean().mean();
        Plastic {
            diffuse_reflectance,
            eta,
            nonlinear,
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
            specular_sampling_weight: 1.0 / (d_mean + 1.0),
        }
    }

    /// Probability of sampling the specular lobe given the Fresnel reflectance `f_i` at `wi`.
    fn prob_specular(&self, f_i: f32) -> f32 {
        let s = f_i * self.specular_sampling_weight;
        let d = (1.0 - f_i) * (1.0 - self.specular_sampling_weight);
        s / (s + d)
    }

    /// The diffuse albedo after the internal reflections at the coating.
    fn diffuse(&self, uv: TexPoint) -> Rgb {
        let r = self.diffuse_reflectance.eval(uv);
        if self.nonlinear {
            r.map(|c| c / (1.0 - c * self.fdr_int))
        } else {
            r / (1.0 - self.fdr_int)
        }
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let (f_i, _, _) = fresnel_dielectric(wi.z, self.eta);
        let p_spec = self.prob_specular(f_i);
        if u1 < p_spec {
            return Some(BsdfSample::specular(reflect(wi), Rgb::splat(f_i / p_spec), p_spec, false));
        }
        let wo = sample_cosine_hemisphere(u2);
        let pdf = cosine_hemisphere_pdf(wo.z) * (1.0 - p_spec);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let (f_o, _, _) = fresnel_dielectric(wo.z, self.eta);
        let weight = self.diffuse(uv) * ((1.0 - f_i) * (1.0 - f_o) / (self.eta * self.eta * (1.0 - p_spec)));
        Some(BsdfSample::glossy(wo, weight, pdf))
    }

    /// The diffuse lobe, `f |cos wo|` (the specular one is a delta).
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.eval_and::<false>(wi, wo, uv).0
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let (f_i, _, _) = fresnel_dielectric(wi.z, self.eta);
        cosine_hemisphere_pdf(wo.z) * (1.0 - self.prob_specular(f_i))
    }

    /// [`Self::eval`] and [`Self::pdf`] with the Fresnel reflectance at `wi` computed once.
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        self.eval_and::<true>(wi, wo, uv)
    }

    /// `(f |cos wo|, pdf)`, the pdf only `if PDF` (else 0: `eval` alone pays no division for it).
    #[inline(always)]
    fn eval_and<const PDF: bool>(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let (f_i, _, _) = fresnel_dielectric(wi.z, self.eta);
        let (f_o, _, _) = fresnel_dielectric(wo.z, self.eta);
        let cos_pdf = cosine_hemisphere_pdf(wo.z);
        let f = self.diffuse(uv) * (cos_pdf * (1.0 - f_i) * (1.0 - f_o) / (self.eta * self.eta));
        (f, if PDF { cos_pdf * (1.0 - self.prob_specular(f_i)) } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{albedo, check_sampling, dir, passed};
    use super::super::Bsdf;
    use super::*;

    #[test]
    fn diffuse_fresnel_fits() {
        // Reference values of the exact integral: 0.0918 for eta 1.5 from outside; from
        // inside 1 - (1 - 0.0918) / 1.5^2 = 0.5963.
        assert!((fresnel_diffuse_reflectance(1.5) - 0.0918).abs() < 2e-3);
        assert!((fresnel_diffuse_reflectance(1.0 / 1.5) - 0.5963).abs() < 3e-3);
    }

    #[test]
    fn plastic_sampling_matches_pdf() {
        let b = Bsdf::Plastic(Plastic::new(Rgb::new(0.5, 0.3, 0.2).into(), 1.49 / 1.000277, false));
        for cz in [0.9f32, 0.4, 0.1] {
            let r = check_sampling(&b, dir(cz, 2.0), 21, 200_000);
            assert!(passed(&r, 200_000), "cos {cz}: {r}");
        }
    }

    /// A white base under the coating: energy is conserved up to the approximation of the
    /// internal reflections (`fdr_int` is the fit, not the exact integral), and never above 1
    /// by more than that.
    #[test]
    fn plastic_white_furnace() {
        let b = Bsdf::Plastic(Plastic::new(Rgb::ONE.into(), 1.5, false));
        for cz in [0.95f32, 0.6, 0.2] {
            let a = albedo(&b, dir(cz, 0.0), 3, 200_000);
            assert!((a - 1.0).abs() < 0.03, "cos {cz}: {a}");
        }
    }

    #[test]
    fn plastic_diffuse_part_is_reciprocal() {
        let b = Plastic::new(Rgb::new(0.5, 0.3, 0.2).into(), 1.49, true);
        let mut s = haze_core::Sampler::from_seed(4);
        for _ in 0..200 {
            let wi = haze_core::sampling::sample_cosine_hemisphere(s.next_2d());
            let wo = haze_core::sampling::sample_cosine_hemisphere(s.next_2d());
            let a = b.eval(wi, wo, (Vec2::ZERO).into()) / wo.z;
            let c = b.eval(wo, wi, (Vec2::ZERO).into()) / wi.z;
            assert!((a - c).max_component().abs() < 1e-5 * a.max_component().max(1.0));
        }
    }
}
