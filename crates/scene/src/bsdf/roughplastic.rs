//! Mitsuba 3's `roughplastic`: a diffuse base under a rough dielectric coating. Glossy
//! reflection off the coating (Torrance-Sparrow with the microfacet distribution); the light
//! that enters scatters diffusely and leaves, weighted by the coating's transmittance at `wi`
//! and at `wo`, which is tabulated once per material over the incidence cosine.

use super::microfacet::{Microfacet, MicrofacetType};
use super::BsdfSample;
use crate::bsdf::fresnel_dielectric;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::{Rgb, INV_PI};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Entries of the transmittance table over `cos theta` in [0, 1] (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
const TABLE_RES: usize = 64;

#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlastic {
    pub distr: Microfacet,
    pub diffuse_reflectance: Texture,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    pub nonlinear: bool,
    /// `1 / (mean(diffuse) + 1)`, as in [`super::Plastic`].
    pub specular_sampling_weight: f32,
    /// `T(mu)`: the energy the rough coating transmits into the base, at `mu` = `i / 63`
    /// ([`rough_transmittance`]; less than `1 - R(mu)` by what the Smith masking loses).
    external_transmittance: Vec<f32>,
    /// Cosine-weighted hemispherical reflectance of the coating seen from inside.
    internal_reflectance: f32,
}

impl RoughPlastic {
    pub fn new(distr: Microfacet, diffuse_reflectance: Texture, eta: f32, nonlinear: bool) -> Self {
        let d_mean = diffuse_reflectance.mean().mean();
        let (external_transmittance, internal_reflectance) = tables(distr, eta);
        RoughPlastic {
            distr,
            diffuse_reflectance,
            eta,
            nonlinear,
            specular_sampling_weight: 1.0 / (d_mean + 1.0),
            external_transmittance,
            internal_reflectance,
        }
    }

    /// Linear interpolation in the transmittance table.
    fn transmittance(&self, cos_theta: f32) -> f32 {
        let x = cos_theta * (TABLE_RES - 1) as f32;
        let i = (x.max(0.0) as usize).min(TABLE_RES - 2);
        let w1 = x - i as f32;
        (1.0 - w1) * self.external_transmittance[i] + w1 * self.external_transmittance[i + 1]
    }

    fn prob_specular(&self, cos_i: f32) -> f32 {
        self.prob_specular_from(self.transmittance(cos_i))
    }

    /// [`Self::prob_specular`] given the transmittance `t_i` at `cos_i`.
    fn prob_specular_from(&self, t_i: f32) -> f32 {
        let s = (1.0 - t_i) * self.specular_sampling_weight;
        let d = t_i * (1.0 - self.specular_sampling_weight);
        s / (s + d)
    }

    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = if u1 < self.prob_specular(wi.z) {
            let (m, _) = self.distr.sample(wi, u2);
            2.0 * wi.dot(m) * m - wi
        } else {
            sample_cosine_hemisphere(u2)
        };
        let (f, pdf) = self.eval_pdf(wi, wo, uv);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample::glossy(wo, f / pdf, pdf))
    }

    /// `f |cos wo|`: glossy coating reflection plus the diffuse base seen through it.
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        self.eval_and::<false>(wi, wo, uv).0
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        // `G1(wi, h)` enters only the visible-normal pdf.
        let g1_i = if self.distr.sample_visible { self.distr.smith_g1(wi, h) } else { 0.0 };
        self.pdf_with(wi, wo, h, self.distr.eval(h), g1_i, self.transmittance(cos_i))
    }

    /// [`Self::eval`] and [`Self::pdf`] at once: the half vector, `D(h)`, the transmittance at
    /// `cos_i` and, with visible-normal sampling, `G1(wi, h)` computed once for both (the same
    /// arithmetic as apart, so the same bits).
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        self.eval_and::<true>(wi, wo, uv)
    }

    /// `(f |cos wo|, pdf)`, the pdf only `if PDF` (else 0).
    #[inline(always)]
    fn eval_and<const PDF: bool>(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let h = (wi + wo).normalize();
        let d = self.distr.eval(h);
        let t_i = self.transmittance(cos_i);
        let (f, _, _) = fresnel_dielectric(wi.dot(h), self.eta);
        let g1_i = self.distr.smith_g1(wi, h);
        let specular = f * d * (g1_i * self.distr.smith_g1(wo, h)) / (4.0 * cos_i);
        let r = self.diffuse_reflectance.eval(uv);
        let diff = if self.nonlinear {
            r.map(|c| c / (1.0 - c * self.internal_reflectance))
        } else {
            r / (1.0 - self.internal_reflectance)
        };
        let t = t_i * self.transmittance(cos_o);
        let value = diff * (INV_PI * cos_o * t / (self.eta * self.eta)) + Rgb::splat(specular);
        (value, if PDF { self.pdf_with(wi, wo, h, d, g1_i, t_i) } else { 0.0 })
    }

    /// The pdf given the half vector `h`, `D(h)`, `G1(wi, h)` and the transmittance `t_i` at
    /// `cos_i`.
    fn pdf_with(&self, wi: Vec3, wo: Vec3, h: Vec3, d: f32, g1_i: f32, t_i: f32) -> f32 {
        let p_spec = self.prob_specular_from(t_i);
        let p_glossy = if self.distr.sample_visible {
            d * g1_i / (4.0 * wi.z)
        } else {
            self.distr.pdf(wi, h) / (4.0 * wo.dot(h))
        };
        p_spec * p_glossy + (1.0 - p_spec) * cosine_hemisphere_pdf(wo.z)
    }
}

/// `(external_transmittance, internal_reflectance)` of a coating, cached per distribution and
/// `eta`: building them costs about a million microfacet samples, and scenes repeat materials.
fn tables(distr: Microfacet, eta: f32) -> (Vec<f32>, f32) {
    type Key = (MicrofacetType, u32, u32);
    /// Transmittance table and internal reflectance per (distribution, alpha, eta).
    type Tables = HashMap<Key, (Vec<f32>, f32)>;
    static CACHE: OnceLock<Mutex<Tables>> = OnceLock::new();
    // roughplastic is isotropic (Mitsuba 3 takes one scalar `alpha` there).
    let key = (distr.ty, distr.alpha_u.to_bits(), eta.to_bits());
    let cache = CACHE.get_or_init(Default::default);
    if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return t.clone();
    }
    // The tables always integrate with visible-normal sampling, as Mitsuba's do.
    let vis = Microfacet { sample_visible: true, ..distr };
    let mus: Vec<f32> = (0..TABLE_RES).map(|i| (i as f32 / (TABLE_RES - 1) as f32).max(1e-6)).collect();
    let external: Vec<f32> = mus.par_iter().map(|&mu| rough_transmittance(&vis, mu, eta)).collect();
    let internal: Vec<f32> = mus.par_iter().map(|&mu| rough_reflectance(&vis, mu, 1.0 / eta) * mu).collect();
    let t = (external, 2.0 * internal.iter().sum::<f32>() / TABLE_RES as f32);
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, t.clone());
    t
}

/// Directional albedo of a rough dielectric interface's reflection at incidence cosine `mu`
/// (Mitsuba's `eval_reflectance`): `∫ F(wi.m) G1(wo, m)` over the visible normals `m`.
fn rough_reflectance(distr: &Microfacet, mu: f32, eta: f32) -> f32 {
    visible_normal_integral(distr, mu, eta, |wi, m| {
        let wo = 2.0 * wi.dot(m) * m - wi;
        if wo.z <= 0.0 {
            return 0.0;
        }
        let (f, _, _) = fresnel_dielectric(wi.dot(m), eta);
        distr.smith_g1(wo, m) * f
    })
}

/// Directional albedo of a rough dielectric interface's transmission at incidence cosine `mu`
/// (Mitsuba's `eval_transmittance`, the table `roughplastic` weights its base by):
/// `∫ (1 - F(wi.m)) G1(wt, m)` over the visible normals `m`, `wt` the direction refracted
/// through `m`. Not `1 - R`: the masking of the refracted direction removes energy too, a few
/// percent at grazing incidence.
fn rough_transmittance(distr: &Microfacet, mu: f32, eta: f32) -> f32 {
    visible_normal_integral(distr, mu, eta, |wi, m| {
        let wi_m = wi.dot(m);
        let (f, cos_t, eta_ti) = fresnel_dielectric(wi_m, eta);
        let inv = 1.0 / eta_ti;
        let wt = (m * (wi_m * inv + cos_t) - wi * inv).normalize();
        if wt.z * wi.z >= 0.0 {
            return 0.0;
        }
        distr.smith_g1(wt, m) * (1.0 - f)
    })
}

/// `∫ g(wi, m)` over the visible normals `m` of `distr` seen from `wi` (incidence cosine `mu`),
/// by Gauss-Legendre quadrature over the sampling square: 32 points per axis for `eta > 1`,
/// 128 for `eta < 1`, where total internal reflection makes the integrand rougher.
fn visible_normal_integral(distr: &Microfacet, mu: f32, eta: f32, g: impl Fn(Vec3, Vec3) -> f32) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let (nodes, weights) = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let mut acc = 0.0f64;
    for (x, wx) in nodes.iter().zip(&weights) {
        for (y, wy) in nodes.iter().zip(&weights) {
            let u = Vec2::new((0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32);
            let (m, _) = distr.sample(wi, u);
            acc += g(wi, m) as f64 * wx * wy;
        }
    }
    (acc * 0.25) as f32
}

/// Nodes and weights of the `n`-point Gauss-Legendre rule on [-1, 1] (Newton's method on the
/// Legendre polynomial from Chebyshev starting points).
fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        let mut x = -(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            // P_n(x) and its derivative by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::super::testing::{albedo, check_sampling, dir, passed};
    use super::super::Bsdf;
    use super::*;

    fn material(ty: MicrofacetType, alpha: f32, r: Rgb) -> RoughPlastic {
        RoughPlastic::new(Microfacet::new(ty, alpha, true), r.into(), 1.49 / 1.000277, false)
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(8);
        let integral = |f: &dyn Fn(f64) -> f64| x.iter().zip(&w).map(|(x, w)| f(*x) * w).sum::<f64>();
        assert!((integral(&|_| 1.0) - 2.0).abs() < 1e-12);
        assert!((integral(&|x| x.powi(14)) - 2.0 / 15.0).abs() < 1e-12);
    }

    /// Against the smooth limit: a very smooth coating reflects the Fresnel reflectance.
    #[test]
    fn smooth_limit_of_the_table() {
        let d = Microfacet::new(MicrofacetType::Beckmann, 1e-3, true);
        for mu in [0.9f32, 0.5, 0.2] {
            let r = rough_reflectance(&d, mu, 1.5);
            let (f, _, _) = fresnel_dielectric(mu, 1.5);
            assert!((r - f).abs() < 1e-3, "mu {mu}: {r} vs {f}");
        }
    }

    /// The transmittance table in the smooth limit is `1 - F`, and at grazing incidence it sits
    /// below `1 - R` by the energy the masking of the refracted directions removes.
    #[test]
    fn transmittance_table() {
        let d = Microfacet::new(MicrofacetType::Beckmann, 1e-3, true);
        for mu in [0.9f32, 0.5, 0.2] {
            let t = rough_transmittance(&d, mu, 1.5);
            let (f, _, _) = fresnel_dielectric(mu, 1.5);
            assert!((t - (1.0 - f)).abs() < 1e-3, "mu {mu}: {t} vs {}", 1.0 - f);
        }
        let d = Microfacet::new(MicrofacetType::Beckmann, 0.1, true);
        let (t, r) = (rough_transmittance(&d, 0.2, 1.49), rough_reflectance(&d, 0.2, 1.49));
        assert!(t < 1.0 - r - 0.02, "T {t}, 1 - R {}", 1.0 - r);
    }

    /// `f |cos wo|` of Mitsuba 3.9.1's default `roughplastic` (Beckmann, alpha 0.1, sampled
    /// visible normals, polypropylene over air) with `diffuse_reflectance` (0.2, 0.7, 0.7), from
    /// `BSDF.eval` in `scalar_rgb`, `wi` in the xz plane and `wo` in the yz plane (away from the
    /// glossy lobe, so this is the diffuse base seen through the transmittance table). The old
    /// table (`1 - R`) was 4 % high at `cos wo` = 0.2.
    #[test]
    fn diffuse_part_matches_mitsuba() {
        let b = material(MicrofacetType::Beckmann, 0.1, Rgb::new(0.2, 0.7, 0.7));
        let cases = [
            (1.0f32, 0.34f32, [0.0182773f32, 0.0639707]),
            (0.34, 1.0, [0.0537569, 0.188149]),
            (0.9, 0.2, [0.0088265, 0.0308927]),
            (0.5, 0.5, [0.0279768, 0.097919]),
        ];
        for (ci, co, want) in cases {
            let wi = Vec3::new((1.0 - ci * ci).sqrt(), 0.0, ci);
            let wo = Vec3::new(0.0, (1.0 - co * co).sqrt(), co);
            let got = b.eval(wi, wo, (Vec2::ZERO).into());
            for (g, w) in [got[0], got[1]].into_iter().zip(want) {
                assert!((g / w - 1.0).abs() < 2e-3, "cos {ci}, {co}: {g} vs Mitsuba {w}");
            }
        }
    }

    #[test]
    fn roughplastic_sampling_matches_pdf() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for alpha in [0.1f32, 0.5] {
                let b = Bsdf::RoughPlastic(Box::new(material(ty, alpha, Rgb::new(0.2, 0.7, 0.7))));
                for cz in [0.9f32, 0.3] {
                    let r = check_sampling(&b, dir(cz, 0.5), 31, 200_000);
                    assert!(passed(&r, 200_000), "{ty:?} alpha {alpha} cos {cz}: {r}");
                }
            }
        }
    }

    #[test]
    fn roughplastic_is_reciprocal() {
        let b = material(MicrofacetType::Beckmann, 0.3, Rgb::new(0.2, 0.7, 0.7));
        let mut s = haze_core::Sampler::from_seed(6);
        for _ in 0..500 {
            let wi = sample_cosine_hemisphere(s.next_2d());
            let wo = sample_cosine_hemisphere(s.next_2d());
            let a = b.eval(wi, wo, (Vec2::ZERO).into()) / wo.z;
            let c = b.eval(wo, wi, (Vec2::ZERO).into()) / wi.z;
            assert!(
                (a - c).max_component().abs() <= 1e-4 * a.max_component().max(1.0),
                "{wi} {wo}: {a} vs {c}"
            );
        }
    }

    /// White base: energy at most 1 (up to the table's approximation) and close to it for a
    /// smooth coating. Mitsuba's model loses energy through the Smith masking inside its
    /// tabulated reflectances, more with GGX's long tails (about 8 % at alpha 0.1).
    #[test]
    fn roughplastic_white_furnace() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            let b = Bsdf::RoughPlastic(Box::new(material(ty, 0.1, Rgb::ONE)));
            for cz in [0.9f32, 0.5] {
                let a = albedo(&b, dir(cz, 0.0), 2, 200_000);
                let lo = if ty == MicrofacetType::Beckmann { 0.95 } else { 0.9 };
                assert!(a < 1.02 && a > lo, "{ty:?} cos {cz}: {a}");
            }
        }
    }
}
