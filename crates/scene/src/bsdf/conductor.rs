//! Mitsuba 3's `conductor` and `roughconductor`: mirror reflection off a metal of complex index
//! of refraction `eta + i k` (smooth), or the Cook-Torrance microfacet model over such facets
//! (rough; Walter et al. 2007 with Mitsuba's distributions and sampling), both front side only.
//! The named materials' RGB indices are in `conductor_iors.rs`.

use super::microfacet::Microfacet;
use super::roughness::Roughness;
use super::{reflect, BsdfSample};
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::Rgb;

#[path = "conductor_iors.rs"]
mod iors;
pub use iors::CONDUCTOR_IORS;

#[derive(Clone, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the index of refraction, per channel.
    pub eta: Rgb,
    /// Imaginary part (absorption).
    pub k: Rgb,
    /// Mitsuba's `specular_reflectance` factor (1).
    pub specular_reflectance: Texture,
    /// `None`: a smooth mirror (`conductor`); else the facets' distribution (`roughconductor`).
    pub distr: Option<Roughness>,
}

/// `(eta, k)` of Mitsuba 3's named conductor `name` (`"Au"`, `"Cu_palik"`, ...; `"none"` is
/// the perfect mirror `eta = 0, k = 1`), case-sensitive as in Mitsuba.
pub fn conductor_ior(name: &str) -> Option<(Rgb, Rgb)> {
    if name == "none" {
        return Some((Rgb::ZERO, Rgb::ONE));
    }
    CONDUCTOR_IORS.iter().find(|(n, _, _)| *n == name).map(|(_, e, k)| (Rgb(*e), Rgb(*k)))
}

/// Unpolarised Fresnel reflectance of a conductor of complex relative index `eta + i k` at
/// incidence cosine `cos_i` (>= 0). Mitsuba 3's `fresnel_conductor`, after K. D. Moeller,
/// "Optics" (1988): with `s2 = 1 - cos_i^2`, `t = eta^2 - k^2 - s2`, `a2b2 = sqrt(t^2 + 4 eta^2
/// k^2)`, `a = sqrt((a2b2 + t) / 2)`: `r_s = (a2b2 + cos_i^2 - 2 a cos_i) / (a2b2 + cos_i^2 + 2 a
/// cos_i)`, `r_p = r_s (a2b2 cos_i^2 + s2^2 - 2 a cos_i s2) / (a2b2 cos_i^2 + s2^2 + 2 a cos_i
/// s2)`, `F = (r_s + r_p) / 2`.
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = cos_i * cos_i;
    let s2 = (1.0 - c2).max(0.0);
    let s4 = s2 * s2;
    let t = eta * eta - k * k - s2;
    let a2b2 = (t * t + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t)).max(0.0).sqrt();
    let term1 = a2b2 + c2;
    let term2 = 2.0 * cos_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

impl Conductor {
    /// The Fresnel reflectance per channel at `cos_i`, times `specular_reflectance` at `uv`.
    fn fresnel(&self, cos_i: f32, uv: TexPoint) -> Rgb {
        let f = Rgb::new(
            fresnel_conductor(cos_i, self.eta[0], self.k[0]),
            fresnel_conductor(cos_i, self.eta[1], self.k[1]),
            fresnel_conductor(cos_i, self.eta[2], self.k[2]),
        );
        f * self.specular_reflectance.eval(uv)
    }

    pub fn sample(&self, wi: Vec3, u2: Vec2, uv: TexPoint) -> Option<BsdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let Some(distr) = &self.distr else {
            return Some(BsdfSample::specular(reflect(wi), self.fresnel(wi.z, uv), 1.0, false));
        };
        let distr = distr.at(uv);
        let m = distr.sample_normal(wi, u2);
        let wi_m = wi.dot(m);
        let wo = 2.0 * wi_m * m - wi;
        if wo.z <= 0.0 || wi_m <= 0.0 {
            return None;
        }
        let pdf = distr.pdf(wi, m) / (4.0 * wo.dot(m));
        if pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        // eval / pdf: F D G / (4 cos_i) over D pdf_m / (4 wo.m).
        let f = self.eval_with(&distr, wi, wo, uv);
        let weight = f / pdf;
        Some(BsdfSample::glossy(wo, weight, pdf))
    }

    /// `f(wi, wo) cos(wo) = F(wi.m) D(m) G(wi, wo, m) / (4 cos_i)` with `m` the half vector
    /// (zero for the smooth conductor and below the surface).
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        let Some(distr) = &self.distr else { return Rgb::ZERO };
        self.eval_with(&distr.at(uv), wi, wo, uv)
    }

    /// [`Self::eval`] of the rough conductor with the distribution at the hit.
    fn eval_with(&self, distr: &Microfacet, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let m = (wi + wo).normalize();
        let d = distr.eval(m);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = distr.g(wi, wo, m);
        self.fresnel(wi.dot(m), uv) * (d * g / (4.0 * wi.z))
    }

    /// Solid-angle density of [`Self::sample`] producing `wo`.
    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
        let Some(distr) = &self.distr else { return 0.0 };
        let distr = distr.at(uv);
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let m = (wi + wo).normalize();
        let wo_m = wo.dot(m);
        if wo_m <= 0.0 {
            return 0.0;
        }
        distr.pdf(wi, m) / (4.0 * wo_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::MicrofacetType;
    use crate::bsdf::testing::{albedo, check_sampling, dir, passed};
    use crate::bsdf::Bsdf;
    use haze_core::Sampler;

    fn rough(ty: MicrofacetType, alpha: f32, visible: bool, material: &str) -> Bsdf {
        rough_with(Microfacet::new(ty, alpha, visible).into(), material)
    }

    fn rough_with(distr: Roughness, material: &str) -> Bsdf {
        let (eta, k) = conductor_ior(material).unwrap();
        Bsdf::Conductor(Box::new(Conductor {
            eta,
            k,
            specular_reflectance: Rgb::ONE.into(),
            distr: Some(distr),
        }))
    }

    /// At normal incidence `F = ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2)`; at grazing
    /// incidence 1; `none` (eta 0, k 1) is a perfect mirror at every angle; a dielectric
    /// (`k = 0`) gives the dielectric Fresnel term.
    #[test]
    fn fresnel_conductor_limits() {
        for (eta, k) in [(0.2f32, 3.0f32), (1.5, 0.0), (2.7, 1.1)] {
            let f0 = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
            assert!((fresnel_conductor(1.0, eta, k) - f0).abs() < 1e-6, "{eta} {k}");
            assert!((fresnel_conductor(0.0, eta, k) - 1.0).abs() < 1e-6);
        }
        for c in [0.0, 0.3, 0.7, 1.0] {
            assert!((fresnel_conductor(c, 0.0, 1.0) - 1.0).abs() < 1e-6);
            let (fd, _, _) = crate::bsdf::fresnel_dielectric(c, 1.5);
            assert!((fresnel_conductor(c, 1.5, 0.0) - fd).abs() < 1e-5, "cos {c}: {fd}");
        }
    }

    /// Gold from Mitsuba 3's table: the RGB indices of its RGB variants, and the normal-incidence
    /// reflectance they give (gold's familiar yellow: red and green high, blue low).
    #[test]
    fn named_gold_matches_mitsuba() {
        let (eta, k) = conductor_ior("Au").unwrap();
        // Mitsuba 3.9.1 (scalar_rgb): mi.load_dict({'type': 'conductor', 'material': 'Au'}), its
        // traversed `eta` and `k` (see the table's generator for how they are converted).
        let want_eta = Rgb::new(0.143_036, 0.375_307, 1.442_05);
        let want_k = Rgb::new(3.983, 2.385_56, 1.603_36);
        for c in 0..3 {
            assert!((eta[c] - want_eta[c]).abs() < 2e-3 * want_eta[c], "eta {eta:?}");
            assert!((k[c] - want_k[c]).abs() < 2e-3 * want_k[c], "k {k:?}");
        }
        let f0: Vec<f32> = (0..3).map(|c| fresnel_conductor(1.0, eta[c], k[c])).collect();
        assert!(f0[0] > 0.9 && f0[1] > 0.6 && f0[2] < 0.45, "{f0:?}");
        assert_eq!(conductor_ior("none"), Some((Rgb::ZERO, Rgb::ONE)));
        assert_eq!(conductor_ior("unobtainium"), None);
        assert!(CONDUCTOR_IORS.len() >= 70, "{}", CONDUCTOR_IORS.len());
    }

    #[test]
    fn smooth_conductor_reflects_with_its_fresnel_weight() {
        let (eta, k) = conductor_ior("Cu").unwrap();
        let b = Bsdf::Conductor(Box::new(Conductor {
            eta,
            k,
            specular_reflectance: Rgb::new(0.5, 1.0, 1.0).into(),
            distr: None,
        }));
        assert!(b.is_specular());
        let wi = dir(0.6, 0.3);
        let s = b.sample(wi, 0.5, Vec2::new(0.2, 0.7), Vec2::ZERO).unwrap();
        assert!(s.specular && !s.transmitted);
        assert!((s.wo - Vec3::new(-wi.x, -wi.y, wi.z)).length() < 1e-6);
        for c in 0..3 {
            let want = fresnel_conductor(0.6, eta[c], k[c]) * [0.5, 1.0, 1.0][c];
            assert!((s.weight[c] - want).abs() < 1e-6);
        }
        assert!(b.sample(-wi, 0.5, Vec2::new(0.2, 0.7), Vec2::ZERO).is_none(), "front side only");
        assert_eq!(b.eval(wi, dir(0.5, 1.0), Vec2::ZERO), Rgb::ZERO);
    }

    /// The sampled directions follow `pdf` (chi-square), and the weights are `eval / pdf`.
    #[test]
    fn rough_conductor_sampling_matches_its_pdf() {
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for visible in [true, false] {
                for (alpha, cos) in [(0.1, 0.8), (0.4, 0.3), (0.8, 0.95)] {
                    let b = rough(ty, alpha, visible, "Al");
                    let wi = dir(cos, 0.4);
                    let n = 200_000;
                    let r = check_sampling(&b, wi, 1, n);
                    assert!(passed(&r, n), "{ty:?} alpha {alpha} visible {visible} cos {cos}: {r:?}");
                }
                // Anisotropic (`alpha_u != alpha_v`), wi at azimuths along, across and
                // between the axes.
                for (au, av, cos, phi) in [(0.05, 0.3, 0.7, 0.0), (0.4, 0.1, 0.4, 1.2), (0.6, 0.15, 0.9, 2.0)]
                {
                    let b = rough_with(Microfacet::anisotropic(ty, au, av, visible).into(), "Al");
                    let n = 200_000;
                    let r = check_sampling(&b, dir(cos, phi), 1, n);
                    assert!(passed(&r, n), "{ty:?} alpha {au}/{av} visible {visible} cos {cos}: {r:?}");
                }
            }
        }
    }

    /// Textured roughness: at each `uv` the BSDF is the fixed-roughness one with the textures'
    /// values there (a checkerboard of two anisotropic roughnesses, as Mitsuba 3's carbon-fibre
    /// example), in `eval`, `pdf` and `sample`; and an anisotropic lobe is not the same when
    /// turned by 90 degrees about the normal (the control: the frame's axes matter).
    #[test]
    fn textured_roughness_is_the_fixed_one_at_each_uv() {
        use crate::texture::Texture;
        let checker = |a, b| Texture::Checkerboard {
            color0: Rgb::splat(a),
            color1: Rgb::splat(b),
            to_uv: glam::Affine2::from_scale(Vec2::splat(25.0)),
        };
        let base = Microfacet::new(MicrofacetType::Beckmann, 0.1, true);
        let textured = rough_with(
            Roughness::Textured { base, alpha_u: checker(0.05, 0.3), alpha_v: checker(0.3, 0.05) },
            "Cu",
        );
        let mut s = Sampler::from_seed(9);
        let (mut across, mut n) = (0usize, 0usize);
        for _ in 0..500 {
            let uv = s.next_2d();
            let t = uv * 25.0;
            let upper = |x: f32| x - x.floor() > 0.5;
            // `eval_1` of a checkerboard reads `color0` where the two sides differ (Mitsuba 3.9.1).
            let (au, av) = if upper(t.x) != upper(t.y) { (0.05, 0.3) } else { (0.3, 0.05) };
            let fixed =
                rough_with(Microfacet::anisotropic(MicrofacetType::Beckmann, au, av, true).into(), "Cu");
            let (wi, wo) =
                (dir(0.3 + 0.7 * s.next_1d(), 6.0 * s.next_1d()), dir(s.next_1d(), 6.0 * s.next_1d()));
            assert_eq!(textured.eval(wi, wo, uv), fixed.eval(wi, wo, uv));
            assert_eq!(textured.pdf(wi, wo, uv), fixed.pdf(wi, wo, uv));
            let (u1, u2) = (s.next_1d(), s.next_2d());
            let (a, b) = (textured.sample(wi, u1, u2, uv), fixed.sample(wi, u1, u2, uv));
            assert_eq!(a.map(|x| (x.wo, x.pdf)), b.map(|x| (x.wo, x.pdf)));
            // The same lobe turned by 90 degrees about the normal.
            let turn = |v: Vec3| Vec3::new(-v.y, v.x, v.z);
            let (turned, f) = (fixed.eval(turn(wi), turn(wo), uv)[0], fixed.eval(wi, wo, uv)[0]);
            if turned.max(f) > 1e-6 {
                n += 1;
                across += usize::from((turned - f).abs() > 0.1 * turned.max(f));
            }
        }
        assert!(n > 100 && across * 2 > n, "only {across} of {n} pairs changed by 10% when turned");
    }

    /// Energy: with a perfect mirror material (`none`) the albedo is at most 1 and close to
    /// it for smooth facets (the microfacet model loses only what the masking removes);
    /// reciprocity: `f(wi, wo) = f(wo, wi)`.
    #[test]
    fn energy_and_reciprocity() {
        let mut s = Sampler::from_seed(3);
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for alpha in [0.05, 0.3, 0.9] {
                let b = rough(ty, alpha, true, "none");
                for cos in [0.2, 0.6, 1.0] {
                    let a = albedo(&b, dir(cos, 0.1), 5, 100_000);
                    assert!(a <= 1.0 + 5e-3, "{ty:?} {alpha} {cos}: albedo {a}");
                    if alpha <= 0.05 && cos >= 0.6 {
                        assert!(a > 0.97, "{ty:?} {alpha} {cos}: albedo {a}");
                    }
                }
                let gold = rough(ty, alpha, true, "Au");
                for _ in 0..200 {
                    let (wi, wo) = (dir(s.next_1d(), 6.0 * s.next_1d()), dir(s.next_1d(), 6.0 * s.next_1d()));
                    // f = eval / cos(wo).
                    let f1 = gold.eval(wi, wo, Vec2::ZERO) / wo.z.max(1e-6);
                    let f2 = gold.eval(wo, wi, Vec2::ZERO) / wi.z.max(1e-6);
                    assert!(
                        (f1 - f2).max_component().abs() <= 1e-3 * f1.max_component().max(1e-3),
                        "{f1:?} {f2:?}"
                    );
                }
            }
        }
    }
}
