//! Mitsuba 3's `principled`: the Disney BSDF (Burley 2012; Burley 2015) as Mitsuba 3 writes it,
//! a diffuse base with retro-reflection, fake subsurface and sheen (`brdf` weight
//! `(1 - metallic)(1 - spec_trans)`), a GGX specular lobe whose Fresnel blends a dielectric's,
//! a tinted Schlick and a metal's (`principled_fresnel`), a GGX transmission lobe (`bsdf` weight
//! `(1 - metallic) spec_trans`) and a GTR1 clearcoat. Only the specular lobes act from inside
//! (a pure dielectric Fresnel there), so without `spec_trans` it is front-only.
//!
//! Mitsuba 3's formulas are kept where they depart from the papers, because scenes must render
//! as in Mitsuba: the clearcoat is `0.25 clearcoat F D G |cos_o|` with no `4 cos_i cos_o`
//! denominator, and the transmission is tinted by `sqrt(base_color)`.
//!
//! Sampling (Mitsuba's): a GGX visible normal `m` from `u2` fixes the dielectric Fresnel `F`;
//! the lobe is chosen by `u1` among diffuse `brdf`, clearcoat `clearcoat / 4`, transmission
//! `bsdf (1 - F)` and reflection `1 - bsdf (1 - F)` (each times its sampling rate; from inside
//! `F` and `1 - F`), and the weight is `eval / pdf` with the pdf of the mixture.

use super::dielectric::fresnel_dielectric;
use super::disney::{
    compatible, diffuse_sheen, ggx, mulsign, reflect_about, schlick_fresnel, schlick_r0, tint, DiffuseParams,
    Gtr1,
};
use super::BsdfSample;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct Principled {
    pub base_color: Texture,
    pub roughness: Texture,
    pub anisotropic: Texture,
    pub metallic: Texture,
    pub spec_trans: Texture,
    pub spec_tint: Texture,
    pub sheen: Texture,
    pub sheen_tint: Texture,
    pub flatness: Texture,
    pub clearcoat: Texture,
    pub clearcoat_gloss: Texture,
    /// Interior over exterior index (`eta`, or `2 / (1 - sqrt(0.08 specular)) - 1`).
    pub eta: f32,
    /// Mitsuba 3's `m_has_*` flags: the parameter was given and is not the number 0. Only
    /// these decide the lobes a scene has (a transmitting surface, an anisotropic frame).
    pub has_spec_trans: bool,
    pub has_anisotropic: bool,
    pub has_flatness: bool,
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate` (all 1 by default).
    pub spec_srate: f32,
    pub clearcoat_srate: f32,
    pub diffuse_srate: f32,
}

/// The parameters at one hit.
struct At {
    base_color: Rgb,
    roughness: f32,
    anisotropic: f32,
    metallic: f32,
    spec_trans: f32,
    spec_tint: f32,
    clearcoat: f32,
}

/// The lobes' selection probabilities, normalised: `[diffuse, clearcoat, transmission,
/// reflection]` (Mitsuba's order for `u1`).
fn lobe_probs(p: &Principled, front: bool, brdf: f32, bsdf: f32, clearcoat: f32, f: f32) -> [f32; 4] {
    let (reflect, trans, cc, diffuse) = if front {
        (
            p.spec_srate * (1.0 - bsdf * (1.0 - f)),
            p.spec_srate * bsdf * (1.0 - f),
            0.25 * clearcoat * p.clearcoat_srate,
            brdf * p.diffuse_srate,
        )
    } else {
        (f, if p.has_spec_trans { 1.0 - f } else { 0.0 }, 0.0, 0.0)
    };
    let trans = if p.has_spec_trans { trans } else { 0.0 };
    let inv = 1.0 / (reflect + trans + cc + diffuse);
    [diffuse * inv, cc * inv, trans * inv, reflect * inv]
}

impl Principled {
    fn at(&self, uv: TexPoint) -> At {
        At {
            base_color: self.base_color.eval(uv),
            roughness: self.roughness.eval_1(uv),
            anisotropic: self.anisotropic.eval_1(uv),
            metallic: self.metallic.eval_1(uv),
            spec_trans: if self.has_spec_trans { self.spec_trans.eval_1(uv) } else { 0.0 },
            spec_tint: self.spec_tint.eval_1(uv),
            clearcoat: self.clearcoat.eval_1(uv),
        }
    }

    /// `(1 - metallic)(1 - spec_trans)` and `(1 - metallic) spec_trans`.
    fn weights(a: &At) -> (f32, f32) {
        ((1.0 - a.metallic) * (1.0 - a.spec_trans), (1.0 - a.metallic) * a.spec_trans)
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return None;
        }
        let a = self.at(uv);
        let (brdf, bsdf) = Self::weights(&a);
        let front = cos_i > 0.0;
        if !front && bsdf <= 0.0 {
            return None;
        }
        let m = ggx(a.anisotropic, a.roughness).sample_normal(mulsign(wi, cos_i), u2);
        let (f, cos_t, eta_it) = fresnel_dielectric(wi.dot(m), self.eta);
        let [p_diffuse, p_cc, p_trans, _] = lobe_probs(self, front, brdf, bsdf, a.clearcoat, f);
        let (wo, refracted) = if u1 < p_diffuse {
            (sample_cosine_hemisphere(u2), false)
        } else if u1 < p_diffuse + p_cc {
            let m_cc = Gtr1::clearcoat(self.clearcoat_gloss.eval_1(uv)).sample(u2);
            let wo = reflect_about(wi, m_cc);
            if !compatible(m_cc, wi, wo, cos_i, true) {
                return None;
            }
            (wo, false)
        } else if u1 < p_diffuse + p_cc + p_trans {
            // Refraction through `m`: `wo = m (wi.m / eta_it + cos_t) - wi / eta_it`, `cos_t`
            // signed (Walter et al. 2007, eq. 40).
            let inv = 1.0 / eta_it;
            let wo = (m * (wi.dot(m) * inv + cos_t) - wi * inv).normalize();
            if !compatible(m, wi, wo, cos_i, false) {
                return None;
            }
            (wo, true)
        } else {
            let wo = reflect_about(wi, m);
            if !compatible(m, wi, wo, cos_i, true) {
                return None;
            }
            (wo, false)
        };
        // The side must agree with the lobe (a microfacet may send light through the macrosurface).
        if (cos_i * wo.z < 0.0) != refracted || wo.z == 0.0 {
            return None;
        }
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
            eta: if refracted { eta_it } else { 1.0 },
            transmitted: refracted,
            null: false,
        })
    }

    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.eval_pdf(wi, wo, uv).0
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.eval_pdf(wi, wo, uv).1
    }

    /// `(f(wi, wo) |cos_o|, pdf)`, Mitsuba 3's `eval` and `pdf` (radiance transport: the
    /// transmission carries the `1 / eta^2` scaling).
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i == 0.0 || cos_o == 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let a = self.at(uv);
        let (brdf, bsdf) = Self::weights(&a);
        let front = cos_i > 0.0;
        if !front && bsdf <= 0.0 {
            // Nothing acts from inside without transmission (and nothing samples there).
            return (Rgb::ZERO, 0.0);
        }
        let reflect = cos_i * cos_o > 0.0;
        let eta_path = if front { self.eta } else { 1.0 / self.eta };
        // The generalised half vector, on the macrosurface normal's side (Walter et al. 2007, eq. 16).
        let wh = (wi + wo * if reflect { 1.0 } else { eta_path }).normalize();
        let wh = mulsign(wh, wh.z);
        let (wi_h, wo_h) = (wi.dot(wh), wo.dot(wh));
        let (f, _, _) = fresnel_dielectric(wi_h, self.eta);
        let distr = ggx(a.anisotropic, a.roughness);
        let refl_ok = reflect && compatible(wh, wi, wo, cos_i, true);
        let refr_ok = !reflect && compatible(wh, wi, wo, cos_i, false);

        let mut value = Rgb::ZERO;
        if refl_ok && f > 0.0 {
            let fp = self.principled_fresnel(f, &a, wi_h, front, bsdf);
            value += fp * (distr.eval(wh) * distr.g(wi, wo, wh) / (4.0 * cos_i.abs()));
        }
        if self.has_spec_trans && bsdf > 0.0 && refr_ok && f < 1.0 {
            // Walter et al. 2007, eq. 21, with the radiance scaling `1 / eta_path^2`, which
            // cancels its `eta^2`.
            let t = (1.0 - f) * distr.eval(wh) * distr.g(wi, wo, wh) * wi_h * wo_h
                / (cos_i * (wi_h + eta_path * wo_h).powi(2));
            value += a.base_color.map(f32::sqrt) * (bsdf * t.abs());
        }
        if front && refl_ok && a.clearcoat > 0.0 {
            let fcc = schlick_fresnel(Rgb::splat(0.04), wi_h, self.eta)[0];
            let dcc = Gtr1::clearcoat(self.clearcoat_gloss.eval_1(uv)).eval(wh);
            let gcc = super::disney::smith_ggx1(wi, wh, 0.25) * super::disney::smith_ggx1(wo, wh, 0.25);
            value += Rgb::splat(0.25 * a.clearcoat * fcc * dcc * gcc * cos_o.abs());
        }
        if front && reflect && brdf > 0.0 {
            let params = DiffuseParams {
                roughness: a.roughness,
                flatness: if self.has_flatness { self.flatness.eval_1(uv) } else { 0.0 },
                sheen: self.sheen.eval_1(uv),
                sheen_tint: self.sheen_tint.eval_1(uv),
                has_flatness: self.has_flatness,
            };
            let (base, sheen) = diffuse_sheen(&params, a.base_color, cos_i, cos_o, wh.dot(wo));
            value += a.base_color * (brdf * cos_o.abs() * base);
            if a.metallic < 1.0 {
                value += sheen * ((1.0 - a.metallic) * cos_o.abs());
            }
        }

        // The pdf of the lobe mixture, with the lobe probabilities at the half vector's Fresnel
        // (the sampled normal's, for the specular lobes).
        let [p_diffuse, p_cc, p_trans, p_reflect] = lobe_probs(self, front, brdf, bsdf, a.clearcoat, f);
        let dwh_dwo = if reflect {
            1.0 / (4.0 * wo_h)
        } else {
            eta_path * eta_path * wo_h / (wi_h + eta_path * wo_h).powi(2)
        }
        .abs();
        let wi_s = mulsign(wi, cos_i);
        let mut pdf = 0.0;
        if refl_ok {
            pdf += p_reflect * distr.pdf(wi_s, wh) * dwh_dwo;
            if p_cc > 0.0 {
                pdf += p_cc * Gtr1::clearcoat(self.clearcoat_gloss.eval_1(uv)).pdf(wh) * dwh_dwo;
            }
        }
        if reflect && p_diffuse > 0.0 {
            pdf += p_diffuse * cosine_hemisphere_pdf(wo.z);
        }
        if refr_ok && p_trans > 0.0 {
            pdf += p_trans * distr.pdf(wi_s, wh) * dwh_dwo;
        }
        let pdf = if pdf.is_finite() { pdf } else { 0.0 };
        (if value.is_finite() { value } else { Rgb::ZERO }, pdf)
    }

    /// Mitsuba 3's `principled_fresnel`: on the front,
    /// `(1 - metallic)(1 - spec_tint) F + metallic Schlick(base_color) + (1 - metallic)
    /// spec_tint Schlick(tint R0(eta))`; from inside the dielectric's `bsdf F` alone.
    fn principled_fresnel(&self, f: f32, a: &At, cos: f32, front: bool, bsdf: f32) -> Rgb {
        if !front {
            return Rgb::splat(bsdf * f);
        }
        let eta_it = if cos >= 0.0 { self.eta } else { 1.0 / self.eta };
        let metal = schlick_fresnel(a.base_color, cos, self.eta) * a.metallic;
        let tinted = schlick_fresnel(tint(a.base_color) * schlick_r0(eta_it), cos, self.eta)
            * ((1.0 - a.metallic) * a.spec_tint);
        Rgb::splat((1.0 - a.metallic) * (1.0 - a.spec_tint) * f) + metal + tinted
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::bsdf::testing::{albedo, check_sampling, chi2_rotated, dir, passed};
    use crate::bsdf::Bsdf;
    use haze_core::Sampler;

    /// A principled BSDF with Mitsuba 3's defaults and the given weights.
    pub fn principled(set: &[(&str, f32)]) -> Principled {
        let c = |v: f32| Texture::Constant(Rgb::splat(v));
        let mut b = Principled {
            base_color: Texture::Constant(Rgb::new(0.8, 0.4, 0.2)),
            roughness: c(0.5),
            anisotropic: c(0.0),
            metallic: c(0.0),
            spec_trans: c(0.0),
            spec_tint: c(0.0),
            sheen: c(0.0),
            sheen_tint: c(0.0),
            flatness: c(0.0),
            clearcoat: c(0.0),
            clearcoat_gloss: c(0.0),
            eta: 1.5,
            has_spec_trans: false,
            has_anisotropic: false,
            has_flatness: false,
            spec_srate: 1.0,
            clearcoat_srate: 1.0,
            diffuse_srate: 1.0,
        };
        for &(name, v) in set {
            match name {
                "roughness" => b.roughness = c(v),
                "anisotropic" => (b.anisotropic, b.has_anisotropic) = (c(v), true),
                "metallic" => b.metallic = c(v),
                "spec_trans" => (b.spec_trans, b.has_spec_trans) = (c(v), true),
                "spec_tint" => b.spec_tint = c(v),
                "sheen" => b.sheen = c(v),
                "sheen_tint" => b.sheen_tint = c(v),
                "flatness" => (b.flatness, b.has_flatness) = (c(v), true),
                "clearcoat" => b.clearcoat = c(v),
                "clearcoat_gloss" => b.clearcoat_gloss = c(v),
                "eta" => b.eta = v,
                _ => panic!("no weight {name}"),
            }
        }
        b
    }

    /// The sampler draws directions with the density `pdf` reports (chi-square over the sphere,
    /// `check_sampling`, which also checks each sample's pdf and weight against `pdf` and
    /// `eval / pdf`), for each lobe alone and mixed, from outside and, with transmission, from
    /// inside.
    #[test]
    fn principled_sampling_matches_its_pdf() {
        let cases: &[(&[(&str, f32)], f32)] = &[
            (&[], 0.7),
            (&[("roughness", 0.2), ("metallic", 1.0)], 0.5),
            (&[("roughness", 0.3), ("anisotropic", 0.8), ("metallic", 0.5)], 0.8),
            (&[("clearcoat", 1.0), ("clearcoat_gloss", 0.3), ("roughness", 0.7)], 0.6),
            (&[("sheen", 1.0), ("sheen_tint", 0.5), ("flatness", 0.5), ("spec_tint", 0.7)], 0.4),
            (&[("spec_trans", 1.0), ("roughness", 0.3)], 0.7),
            (&[("spec_trans", 0.6), ("roughness", 0.4), ("metallic", 0.2), ("clearcoat", 0.5)], 0.3),
            (&[("spec_trans", 1.0), ("roughness", 0.3)], -0.7),
            (&[("spec_trans", 0.5), ("roughness", 0.5), ("anisotropic", 0.5)], -0.4),
        ];
        for (i, (set, cos)) in cases.iter().enumerate() {
            let b = Bsdf::Principled(Box::new(principled(set)));
            let n = 200_000;
            let r = check_sampling(&b, dir(*cos, 0.9), 30 + i as u64, n);
            assert!(passed(&r, n), "{set:?} cos {cos}: {r}");
        }
    }

    /// The chi-square test can fail: the samples of one roughness against the pdf of another.
    #[test]
    fn principled_chi2_control_fails() {
        let b = principled(&[("roughness", 0.3), ("metallic", 1.0)]);
        let other = principled(&[("roughness", 0.4), ("metallic", 1.0)]);
        let (wi, uv) = (dir(0.7, 0.9), Vec2::ZERO);
        let mut s = Sampler::from_seed(5);
        let n = 200_000;
        let r = chi2_rotated(
            || b.sample(wi, s.next_1d(), s.next_2d(), uv.into()).map(|x| x.wo),
            |d| other.pdf(wi, d, uv.into()),
            n,
        );
        assert!(!passed(&r, n), "a wrong roughness went unnoticed: {r}");
    }

    /// Transmission is a rough interface and transmits; without it the BSDF is front-only
    /// and returns nothing from inside. A white metal reflects at most what arrives, a
    /// transmitting one loses energy only to single scattering.
    #[test]
    fn principled_sides_and_energy() {
        let opaque = Bsdf::Principled(Box::new(principled(&[])));
        assert!(opaque.front_only() && !opaque.transmits() && !opaque.is_rough_interface());
        let mut s = Sampler::from_seed(2);
        let inside = dir(-0.6, 0.3);
        assert!((0..100).all(|_| opaque.sample(inside, s.next_1d(), s.next_2d(), Vec2::ZERO).is_none()));
        let glass = Bsdf::Principled(Box::new(principled(&[("spec_trans", 1.0), ("roughness", 0.2)])));
        assert!(!glass.front_only() && glass.transmits() && glass.is_rough_interface());
        let mut metal = principled(&[("metallic", 1.0), ("roughness", 0.2)]);
        metal.base_color = Texture::Constant(Rgb::ONE);
        for cos in [0.2, 0.6, 1.0] {
            let a = albedo(&Bsdf::Principled(Box::new(metal.clone())), dir(cos, 0.0), 3, 100_000);
            assert!(a > 0.85 && a < 1.003, "white metal at cos {cos}: {a}");
        }
        let mut clear = principled(&[("spec_trans", 1.0), ("roughness", 0.1)]);
        clear.base_color = Texture::Constant(Rgb::ONE);
        for cos in [0.3, 0.9, -0.9] {
            let a = albedo(&Bsdf::Principled(Box::new(clear.clone())), dir(cos, 0.0), 4, 100_000);
            assert!(a > 0.9 && a < 1.003, "clear glass at cos {cos}: {a}");
        }
    }
}
