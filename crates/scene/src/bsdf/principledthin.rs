//! Mitsuba 3's `principledthin`: the thin-surface Disney BSDF (Burley 2015, Section 4: a sheet with no
//! inside, the same from both sides). Four lobes: a GGX reflection and a GGX "transmission"
//! (the reflection's mirror image through the sheet, with the roughness scaled by
//! `0.65 eta - 0.35`, Burley 2015, Figure 15), both weighted by `spec_trans`; and a diffuse
//! base with retro-reflection, fake subsurface and sheen, and a Lambertian transmission, weighted
//! by `(1 - spec_trans)` and split by `diff_trans / 2` (the parameter runs over [0, 2]).
//! As in Mitsuba 3, the GGX reflection exists only through `spec_trans`: without it the sheet is
//! diffuse.
//!
//! Sampling (Mitsuba's): the lobe by `u1` with probabilities `spec_trans / 2`, `spec_trans / 2`,
//! `(1 - spec_trans)(1 - diff_trans)` and `(1 - spec_trans) diff_trans` (times the sampling
//! rates), the direction by `u2`; the weight is `eval / pdf` with the mixture's pdf. A sample
//! never bends: `eta` is 1.

use super::dielectric::fresnel_dielectric;
use super::disney::{
    compatible, diffuse_sheen, ggx, mulsign, reflect_about, schlick_fresnel, schlick_r0, tint, DiffuseParams,
};
use super::microfacet::Microfacet;
use super::BsdfSample;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledThin {
    pub base_color: Texture,
    pub roughness: Texture,
    pub anisotropic: Texture,
    pub spec_trans: Texture,
    pub spec_tint: Texture,
    pub sheen: Texture,
    pub sheen_tint: Texture,
    pub flatness: Texture,
    /// The sheet's relative index (a texture in Mitsuba 3, read as one number).
    pub eta: Texture,
    /// In [0, 2], as Mitsuba 3 takes it (halved where used).
    pub diff_trans: Texture,
    /// Mitsuba 3's `m_has_*` flags: the parameter was given and is not the number 0.
    pub has_spec_trans: bool,
    pub has_diff_trans: bool,
    pub has_anisotropic: bool,
    pub has_flatness: bool,
    /// `specular_reflectance_sampling_rate`, `specular_transmittance_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`, `diffuse_transmittance_sampling_rate` (1 each).
    pub spec_refl_srate: f32,
    pub spec_trans_srate: f32,
    pub diff_refl_srate: f32,
    pub diff_trans_srate: f32,
}

/// The parameters at one hit.
struct At {
    roughness: f32,
    anisotropic: f32,
    spec_trans: f32,
    /// Halved: in [0, 1].
    diff_trans: f32,
}

impl PrincipledThin {
    fn at(&self, uv: TexPoint) -> At {
        At {
            roughness: self.roughness.eval_1(uv),
            anisotropic: self.anisotropic.eval_1(uv),
            spec_trans: if self.has_spec_trans { self.spec_trans.eval_1(uv) } else { 0.0 },
            diff_trans: if self.has_diff_trans { self.diff_trans.eval_1(uv) / 2.0 } else { 0.0 },
        }
    }

    /// Normalised `[specular reflection, specular transmission, diffuse reflection, diffuse
    /// transmission]` (Mitsuba's order for `u1`).
    fn lobe_probs(&self, a: &At) -> [f32; 4] {
        let st = a.spec_trans;
        let p = [
            st * self.spec_refl_srate / 2.0,
            st * self.spec_trans_srate / 2.0,
            self.diff_refl_srate * (1.0 - st) * (1.0 - a.diff_trans),
            if self.has_diff_trans { self.diff_trans_srate * (1.0 - st) * a.diff_trans } else { 0.0 },
        ];
        let inv = 1.0 / (p[0] + p[1] + p[2] + p[3]);
        p.map(|x| x * inv)
    }

    /// The transmission lobe's GGX: the roughness scaled by `0.65 eta - 0.35` (Burley 2015,
    /// Figure 15's fit for a thin sheet).
    fn trans_distr(a: &At, eta: f32) -> Microfacet {
        ggx(a.anisotropic, (0.65 * eta - 0.35) * a.roughness)
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return None;
        }
        let a = self.at(uv);
        // The sheet is the same from both sides: sample on the front, then mirror back.
        let wi_f = mulsign(wi, cos_i);
        let [p_sr, p_st, p_dr, _] = self.lobe_probs(&a);
        let wo = if u1 < p_sr {
            let m = ggx(a.anisotropic, a.roughness).sample_normal(wi_f, u2);
            let wo = reflect_about(wi_f, m);
            if wo.z <= 0.0 || !compatible(m, wi_f, wo, wi_f.z, true) {
                return None;
            }
            wo
        } else if u1 < p_sr + p_st {
            let m = Self::trans_distr(&a, self.eta.eval_1(uv)).sample_normal(wi_f, u2);
            // Reflected about `m`, then through the sheet: no bending.
            let r = reflect_about(wi_f, m);
            let wo = Vec3::new(r.x, r.y, -r.z);
            if wo.z >= 0.0 || !compatible(m, wi_f, wo, wi_f.z, false) {
                return None;
            }
            wo
        } else if u1 < p_sr + p_st + p_dr {
            sample_cosine_hemisphere(u2)
        } else {
            -sample_cosine_hemisphere(u2)
        };
        let wo = mulsign(wo, cos_i);
        let (value, pdf) = self.eval_pdf(wi, wo, uv);
        if pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        let weight = value / pdf;
        weight.is_finite().then_some(BsdfSample {
            wo,
            weight,
            pdf,
            specular: false,
            eta: 1.0,
            transmitted: wo.z * cos_i < 0.0,
            null: false,
        })
    }

    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.eval_pdf(wi, wo, uv).0
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.eval_pdf(wi, wo, uv).1
    }

    /// `(f(wi, wo) |cos_o|, pdf)`, Mitsuba 3's `eval` and `pdf`.
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        let cos_i = wi.z;
        if cos_i == 0.0 || wo.z == 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let a = self.at(uv);
        let base_color = self.base_color.eval(uv);
        let (wi_f, wo_t) = (mulsign(wi, cos_i), mulsign(wo, cos_i));
        let (ci, co) = (wi_f.z, wo_t.z);
        let reflect = co > 0.0;
        // The half vector of the reflection that the transmission mirrors through the sheet.
        let wo_r = Vec3::new(wo_t.x, wo_t.y, co.abs());
        let wh = (wi_f + wo_r).normalize();
        let st = a.spec_trans;
        let spec_refl = st > 0.0 && reflect && compatible(wh, wi_f, wo_t, ci, true);
        let spec_trans = st > 0.0 && !reflect && compatible(wh, wi_f, wo_t, ci, false);
        let eta = self.eta.eval_1(uv);

        let mut value = Rgb::ZERO;
        if self.has_spec_trans && (spec_refl || spec_trans) {
            let (f, _, _) = fresnel_dielectric(wi_f.dot(wh), eta);
            if spec_refl {
                let d = ggx(a.anisotropic, a.roughness);
                // Mitsuba 3's `thin_fresnel`: the dielectric's F blended by `spec_tint` towards
                // a Schlick term of the tinted `R0(eta)`.
                let spec_tint = self.spec_tint.eval_1(uv);
                let schlick = schlick_fresnel(tint(base_color) * schlick_r0(eta), wi_f.dot(wh), eta);
                let f_thin = Rgb::splat(f * (1.0 - spec_tint)) + schlick * spec_tint;
                value += f_thin * (st * d.eval(wh) * d.g(wi_f, wo_t, wh) / (4.0 * ci));
            }
            if spec_trans {
                let d = Self::trans_distr(&a, eta);
                value += base_color * (st * (1.0 - f) * d.eval(wh) * d.g(wi_f, wo_t, wh) / (4.0 * ci));
            }
        }
        if reflect && st < 1.0 && a.diff_trans < 1.0 {
            let params = DiffuseParams {
                roughness: a.roughness,
                flatness: if self.has_flatness { self.flatness.eval_1(uv) } else { 0.0 },
                sheen: self.sheen.eval_1(uv),
                sheen_tint: self.sheen_tint.eval_1(uv),
                has_flatness: self.has_flatness,
            };
            let (base, sheen) = diffuse_sheen(&params, base_color, ci, co, wh.dot(wo_t));
            let w = (1.0 - st) * (1.0 - a.diff_trans) * co;
            value += base_color * (w * base) + sheen * w;
        }
        if !reflect && st < 1.0 && a.diff_trans > 0.0 {
            value += base_color * ((1.0 - st) * a.diff_trans * haze_core::INV_PI * co.abs());
        }

        let [p_sr, p_st, p_dr, p_dt] = self.lobe_probs(&a);
        let mut pdf = 0.0;
        if self.has_spec_trans {
            // d wh / d wo of the mirrored reflection (Walter et al. 2007, eq. 14).
            let dwh_dwo = (1.0 / (4.0 * wo_r.dot(wh))).abs();
            if reflect && compatible(wh, wi_f, wo_t, ci, true) {
                pdf += p_sr * ggx(a.anisotropic, a.roughness).pdf(wi_f, wh) * dwh_dwo;
            } else if !reflect && compatible(wh, wi_f, wo_t, ci, false) {
                pdf += p_st * Self::trans_distr(&a, eta).pdf(wi_f, wh) * dwh_dwo;
            }
        }
        if reflect {
            pdf += p_dr * cosine_hemisphere_pdf(co);
        } else if self.has_diff_trans {
            pdf += p_dt * cosine_hemisphere_pdf(-co);
        }
        let pdf = if pdf.is_finite() { pdf } else { 0.0 };
        (if value.is_finite() { value } else { Rgb::ZERO }, pdf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::testing::{check_sampling, dir, passed};
    use crate::bsdf::Bsdf;

    fn thin(set: &[(&str, f32)]) -> Bsdf {
        let c = |v: f32| Texture::Constant(Rgb::splat(v));
        let mut b = PrincipledThin {
            base_color: Texture::Constant(Rgb::new(0.8, 0.4, 0.2)),
            roughness: c(0.5),
            anisotropic: c(0.0),
            spec_trans: c(0.0),
            spec_tint: c(0.0),
            sheen: c(0.0),
            sheen_tint: c(0.0),
            flatness: c(0.0),
            eta: c(1.5),
            diff_trans: c(0.0),
            has_spec_trans: false,
            has_diff_trans: false,
            has_anisotropic: false,
            has_flatness: false,
            spec_refl_srate: 1.0,
            spec_trans_srate: 1.0,
            diff_refl_srate: 1.0,
            diff_trans_srate: 1.0,
        };
        for &(name, v) in set {
            match name {
                "roughness" => b.roughness = c(v),
                "anisotropic" => (b.anisotropic, b.has_anisotropic) = (c(v), true),
                "spec_trans" => (b.spec_trans, b.has_spec_trans) = (c(v), true),
                "diff_trans" => (b.diff_trans, b.has_diff_trans) = (c(v), true),
                "spec_tint" => b.spec_tint = c(v),
                "sheen" => b.sheen = c(v),
                "sheen_tint" => b.sheen_tint = c(v),
                "flatness" => (b.flatness, b.has_flatness) = (c(v), true),
                "eta" => b.eta = c(v),
                _ => panic!("no weight {name}"),
            }
        }
        Bsdf::PrincipledThin(Box::new(b))
    }

    /// Sampling against the pdf (chi-square, and each sample's pdf and weight), from both
    /// sides of the sheet.
    #[test]
    fn principledthin_sampling_matches_its_pdf() {
        let cases: &[(&[(&str, f32)], f32)] = &[
            (&[], 0.7),
            (&[("diff_trans", 1.2), ("sheen", 0.8), ("flatness", 0.4)], 0.5),
            (&[("spec_trans", 1.0), ("roughness", 0.3)], 0.8),
            (&[("spec_trans", 0.5), ("roughness", 0.5), ("eta", 1.33), ("spec_tint", 0.5)], 0.4),
            (&[("spec_trans", 0.7), ("anisotropic", 0.7), ("roughness", 0.4), ("diff_trans", 0.5)], -0.6),
            (&[("spec_trans", 0.3), ("diff_trans", 2.0)], -0.3),
        ];
        for (i, (set, cos)) in cases.iter().enumerate() {
            let b = thin(set);
            let n = 200_000;
            let r = check_sampling(&b, dir(*cos, 0.9), 50 + i as u64, n);
            assert!(passed(&r, n), "{set:?} cos {cos}: {r}");
        }
    }

    /// The sheet is the same from both sides: `f(wi, wo) = f(-wi, -wo)`.
    #[test]
    fn principledthin_is_symmetric() {
        let b = thin(&[("spec_trans", 0.5), ("diff_trans", 0.8), ("roughness", 0.3)]);
        let mut s = haze_core::Sampler::from_seed(9);
        for _ in 0..1000 {
            let wi = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let wo = haze_core::sampling::sample_uniform_sphere(s.next_2d());
            let (a, c) = (b.eval_pdf(wi, wo, Vec2::ZERO), b.eval_pdf(-wi, -wo, Vec2::ZERO));
            assert_eq!(a.0, c.0);
            assert_eq!(a.1, c.1);
        }
        assert!(b.transmits() && !b.front_only());
    }
}
