//! Mitsuba 3's `roughdielectric`: a rough interface between two indices of refraction
//! (Walter et al. 2007, "Microfacet models for refraction through rough surfaces"), sampled by
//! picking a microfacet normal and then reflection or refraction with its Fresnel probability.

use super::microfacet::Microfacet;
use super::roughness::Roughness;
use super::BsdfSample;
use crate::bsdf::fresnel_dielectric;
use crate::mesh_attribute::TexPoint;
use glam::{Vec2, Vec3};
use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub struct RoughDielectric {
    pub distr: Roughness,
    /// `int_ior / ext_ior`.
    pub eta: f32,
}

/// `v` with the sign of its `z` flipped if `s < 0` (Mitsuba's `mulsign`).
fn mulsign(v: Vec3, s: f32) -> Vec3 {
    if s < 0.0 {
        -v
    } else {
        v
    }
}

impl RoughDielectric {
    /// The distribution used for sampling: Walter et al.'s widened one (`alpha` scaled by
    /// `1.2 - 0.2 sqrt|cos_i|`) when visible normals are not sampled, as Mitsuba does.
    fn sample_distr(d: Microfacet, cos_i: f32) -> Microfacet {
        if d.sample_visible {
            d
        } else {
            d.scaled(1.2 - 0.2 * cos_i.abs().sqrt())
        }
    }

    /// The generalised half vector of `(wi, wo)` on the side of the macrosurface normal, and
    /// the relative index `eta` seen from `wi` (`eta` or `1/eta`), and whether it is a reflection.
    fn half_vector(&self, wi: Vec3, wo: Vec3) -> (Vec3, f32, bool) {
        let reflect = wi.z * wo.z > 0.0;
        let eta = if wi.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = (wi + wo * if reflect { 1.0 } else { eta }).normalize();
        (mulsign(m, m.z), eta, reflect)
    }

    /// `with_pdf`: see [`super::Bsdf::sample_with`] (the pdf is skipped only with visible-normal
    /// sampling, whose weight does not need it).
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint, with_pdf: bool) -> Option<BsdfSample> {
        let cos_i = wi.z;
        if cos_i == 0.0 {
            return None;
        }
        let at_uv = self.distr.at(uv);
        let with_pdf = with_pdf || !at_uv.sample_visible;
        let distr = Self::sample_distr(at_uv, cos_i);
        let wi_s = mulsign(wi, cos_i);
        let m = distr.sample_normal(wi_s, u2);
        let m_pdf = if with_pdf { distr.pdf(wi_s, m) } else { 1.0 };
        if m_pdf.is_nan() || m_pdf <= 0.0 {
            return None;
        }
        let wi_m = wi.dot(m);
        let (f, cos_t, eta_ti) = fresnel_dielectric(wi_m, self.eta);
        let reflected = u1 <= f;
        let (wo, pdf_lobe, eta_it) = if reflected {
            (2.0 * wi_m * m - wi, f, 1.0)
        } else {
            // Refraction through the microfacet: wo = m (wi.m / eta_ti + cos_t) - wi / eta_ti,
            // with `eta_ti` the index ratio crossed into and `cos_t` signed.
            let inv = 1.0 / eta_ti;
            ((m * (wi_m * inv + cos_t) - wi * inv).normalize(), 1.0 - f, eta_ti)
        };
        // The side must agree with the lobe (a microfacet may send light through the macrosurface).
        if reflected != (wo.z * cos_i > 0.0) || wo.z == 0.0 {
            return None;
        }
        let wo_m = wo.dot(m);
        // Only from the widened non-visible distribution: a microfacet facing away from wi or wo.
        if wi_m * cos_i <= 0.0 || wo_m * wo.z <= 0.0 {
            return None;
        }
        let dwh_dwo = if reflected {
            1.0 / (4.0 * wo_m)
        } else {
            eta_it * eta_it * wo_m / (wi_m + eta_it * wo_m).powi(2)
        };
        let pdf = m_pdf * pdf_lobe * dwh_dwo.abs();
        let weight = if at_uv.sample_visible {
            // f |cos wo| / pdf = G1(wo, m) (times 1/eta^2 after refraction).
            let g1 = at_uv.smith_g1(wo, m);
            if reflected {
                g1
            } else {
                g1 / (eta_it * eta_it)
            }
        } else {
            // Sampled from the widened distribution: weight by the evaluated BSDF.
            self.eval_with(&at_uv, wi, wo) / pdf
        };
        if (pdf.is_nan() || pdf <= 0.0) || !weight.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wo,
            weight: Rgb::splat(weight),
            pdf: if with_pdf { pdf } else { 0.0 },
            specular: false,
            eta: eta_it,
            transmitted: !reflected,
            null: false,
        })
    }

    /// `f(wi, wo) |cos(wo)|` (the same for every channel).
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        self.eval_with(&self.distr.at(uv), wi, wo)
    }

    /// [`Self::eval`] with the distribution at the hit.
    fn eval_with(&self, distr: &Microfacet, wi: Vec3, wo: Vec3) -> f32 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i == 0.0 || cos_o == 0.0 {
            return 0.0;
        }
        let (m, eta, reflect) = self.half_vector(wi, wo);
        let d = distr.eval(m);
        let (f, _, _) = fresnel_dielectric(wi.dot(m), self.eta);
        let g = distr.g(wi, wo, m);
        if reflect {
            f * d * g / (4.0 * cos_i.abs())
        } else {
            let (wi_m, wo_m) = (wi.dot(m), wo.dot(m));
            let value = (1.0 - f) * d * g * eta * eta * wi_m * wo_m / (cos_i * (wi_m + eta * wo_m).powi(2));
            // Radiance scaling by (1/eta)^2, eta as seen from wi.
            (value / (eta * eta)).abs()
        }
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i == 0.0 || cos_o == 0.0 {
            return 0.0;
        }
        let (m, eta, reflect) = self.half_vector(wi, wo);
        let (wi_m, wo_m) = (wi.dot(m), wo.dot(m));
        if wi_m * cos_i <= 0.0 || wo_m * cos_o <= 0.0 {
            return 0.0;
        }
        let dwh_dwo =
            if reflect { 1.0 / (4.0 * wo_m) } else { eta * eta * wo_m / (wi_m + eta * wo_m).powi(2) };
        let (f, _, _) = fresnel_dielectric(wi_m, self.eta);
        let prob = Self::sample_distr(self.distr.at(uv), cos_i).pdf(mulsign(wi, cos_i), m)
            * if reflect { f } else { 1.0 - f };
        let p = prob * dwh_dwo.abs();
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::microfacet::MicrofacetType;
    use super::super::testing::{albedo, check_sampling, dir, passed};
    use super::super::Bsdf;
    use super::*;

    fn rough(ty: MicrofacetType, alpha: f32, eta: f32, vis: bool) -> Bsdf {
        rough_aniso(ty, alpha, alpha, eta, vis)
    }

    fn rough_aniso(ty: MicrofacetType, alpha_u: f32, alpha_v: f32, eta: f32, vis: bool) -> Bsdf {
        Bsdf::RoughDielectric(RoughDielectric {
            distr: Microfacet::anisotropic(ty, alpha_u, alpha_v, vis).into(),
            eta,
        })
    }

    /// White furnace: a rough interface loses energy only to the single-scattering
    /// approximation (light that would scatter again between microfacets), so its albedo
    /// (undoing the eta^2 radiance scaling) is at most 1, and close to 1 for small alpha.
    #[test]
    fn roughdielectric_energy() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (alpha, lo) in [(0.01f32, 0.995), (0.1, 0.95), (0.5, 0.6)] {
                for eta in [1.5f32, 1.0 / 1.5] {
                    let b = rough(ty, alpha, eta, true);
                    for cz in [0.9f32, 0.5, -0.7] {
                        let a = albedo(&b, dir(cz, 0.3), 4, 100_000);
                        assert!(a <= 1.0 + 3e-3 && a >= lo, "{ty:?} alpha {alpha} eta {eta} cos {cz}: {a}");
                    }
                }
            }
        }
    }

    #[test]
    fn roughdielectric_sampling_matches_pdf() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for alpha in [(0.1f32, 0.1f32), (0.5, 0.5), (0.05, 0.4)] {
                for vis in [true, false] {
                    for (eta, cz) in [(1.5f32, 0.8f32), (1.5, 0.3), (1.33, -0.6)] {
                        let b = rough_aniso(ty, alpha.0, alpha.1, eta, vis);
                        let r = check_sampling(&b, dir(cz, 1.0), 17, 200_000);
                        assert!(
                            passed(&r, 200_000),
                            "{ty:?} alpha {alpha:?} visible {vis} eta {eta} cos {cz}: {r}"
                        );
                    }
                }
            }
        }
    }

    /// Reflection is reciprocal: `f(wi, wo) = f(wo, wi)`, i.e. eval/|cos wo| symmetric.
    /// Refraction obeys the generalised rule `f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2`.
    #[test]
    fn roughdielectric_reciprocity() {
        let mut s = haze_core::Sampler::from_seed(8);
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            let eta = 1.5;
            let b = RoughDielectric { distr: Microfacet::anisotropic(ty, 0.3, 0.1, true).into(), eta };
            for _ in 0..1000 {
                let wi = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let wo = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let f_io = b.eval(wi, wo, (Vec2::ZERO).into()) / wo.z.abs();
                let f_oi = b.eval(wo, wi, (Vec2::ZERO).into()) / wi.z.abs();
                let (ratio, expect) = if wi.z * wo.z > 0.0 {
                    (f_io, f_oi)
                } else {
                    // Radiance BSDF: f(wi, wo) eta_i^2 = f(wo, wi) eta_o^2, with eta_i the index
                    // on wi's side.
                    let eta_i = if wi.z > 0.0 { 1.0 } else { eta };
                    let eta_o = if wo.z > 0.0 { 1.0 } else { eta };
                    (f_io * eta_o * eta_o, f_oi * eta_i * eta_i)
                };
                assert!(
                    (ratio - expect).abs() <= 2e-3 * ratio.abs().max(expect.abs()).max(1e-3),
                    "{ty:?} wi {wi} wo {wo}: {ratio} vs {expect}"
                );
            }
        }
    }
}
