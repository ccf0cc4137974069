//! The Disney ("principled") lobes that Mitsuba 3's `principled` and `principledthin` share:
//! Schlick's Fresnel weight, the diffuse with retro-reflection and Hanrahan-Krueger "fake
//! subsurface", the sheen, the GTR1 clearcoat distribution and the roughness-to-alpha map
//! (Burley 2012, "Physically Based Shading at Disney", Sections 5.3-5.6 and Appendix B; Burley 2015,
//! "Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering", Sections 3-4), with
//! Mitsuba 3's choices (`principledhelpers.h`) where they differ from the notes, so that scenes
//! render as in Mitsuba 3.
//!
//! Directions are local (`z` = shading normal) and point away from the surface.

use super::microfacet::{Microfacet, MicrofacetType};
use glam::{Vec2, Vec3};
use haze_core::{Rgb, INV_PI, PI};

/// Schlick's weight `(1 - cos)^5`, `cos` clamped to [0, 1] (Burley 2012, eq. 3's factor).
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Normal-incidence reflectance of a dielectric of relative index `eta`, `((eta - 1) / (eta + 1))^2`.
pub fn schlick_r0(eta: f32) -> f32 {
    ((eta - 1.0) / (eta + 1.0)).powi(2)
}

/// Schlick's approximation `R0 + (1 - R0) (1 - cos)^5` at the microfacet cosine `cos_i`
/// (negative from inside), seen through a relative index `eta`: from the denser side the
/// transmitted angle's cosine replaces `cos_i` (Mitsuba 3's `calc_schlick`; total internal
/// reflection gives cosine 0, so `F = 1`).
pub fn schlick_fresnel(r0: Rgb, cos_i: f32, eta: f32) -> Rgb {
    let (eta_it, eta_ti) = if cos_i >= 0.0 { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    r0 * (1.0 - w) + Rgb::splat(w)
}

/// `base_color` over its luminance (white where it is black): the hue that `spec_tint` and
/// `sheen_tint` blend towards (Burley 2012, Appendix B, `Ctint`).
pub fn tint(base_color: Rgb) -> Rgb {
    let lum = base_color.luminance();
    if lum > 0.0 {
        base_color / lum
    } else {
        Rgb::ONE
    }
}

/// `a (1 - t) + b t`.
pub fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// The GGX roughnesses `(alpha_x, alpha_y)` of a `roughness` and `anisotropic` (Burley 2012,
/// Appendix B: `alpha = roughness^2`, stretched by `aspect = sqrt(1 - 0.9 anisotropic)`), at
/// least 0.001 each as Mitsuba 3's `calc_dist_params`.
pub fn alphas(anisotropic: f32, roughness: f32) -> (f32, f32) {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

/// The main specular lobe's distribution: GGX with visible-normal sampling (Mitsuba 3's
/// default for `MicrofacetDistribution`).
pub fn ggx(anisotropic: f32, roughness: f32) -> Microfacet {
    let (ax, ay) = alphas(anisotropic, roughness);
    Microfacet::anisotropic(MicrofacetType::Ggx, ax, ay, true)
}

/// Mitsuba 3's `mac_mic_compatibility`: `wi` and `wo` on the sides of the microfacet `m`
/// (oriented to `wi`'s side of the macrosurface) that a reflection (same side) or a refraction
/// (opposite sides) needs.
pub fn compatible(m: Vec3, wi: Vec3, wo: Vec3, cos_i: f32, reflection: bool) -> bool {
    let m = if cos_i < 0.0 { -m } else { m };
    wi.dot(m) > 0.0 && if reflection { wo.dot(m) > 0.0 } else { wo.dot(m) < 0.0 }
}

/// `v` with the sign of `s` (Mitsuba's `mulsign`; `s = 0` counts as positive).
pub fn mulsign(v: Vec3, s: f32) -> Vec3 {
    if s < 0.0 {
        -v
    } else {
        v
    }
}

/// Mirror `wi` about the microfacet `m`.
pub fn reflect_about(wi: Vec3, m: Vec3) -> Vec3 {
    2.0 * wi.dot(m) * m - wi
}

/// The per-hit scalars of the diffuse base (the principled BSDF's `brdf` lobe): `roughness`,
/// `flatness`, `sheen`, `sheen_tint`, for [`diffuse_sheen`].
pub struct DiffuseParams {
    pub roughness: f32,
    pub flatness: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    /// Whether `flatness` was given (Mitsuba 3 evaluates the fake subsurface term only then;
    /// `lerp(x, f_ss, 0)` is `x` up to rounding).
    pub has_flatness: bool,
}

/// The diffuse base per unit `base_color / pi`, and the sheen, of a reflection `wi -> wo` with
/// half vector `wh`, both *without* the cosine and lobe weights: `(base term, sheen term)`.
/// Diffuse with retro-reflection: `(1 - Fi/2)(1 - Fo/2) + Rr (Fo + Fi + Fo Fi (Rr - 1))`,
/// `Rr = 2 roughness cos_d^2` (Burley 2015, eqs. 4-5); blended by `flatness` towards the
/// Hanrahan-Krueger approximation `1.25 (Fss (1/(cos_o + cos_i) - 1/2) + 1/2)`,
/// `Fss = (1 + (Fss90 - 1) Fo)(1 + (Fss90 - 1) Fi)`, `Fss90 = Rr / 2` (Burley 2012, Appendix B).
/// Sheen: `sheen Fd lerp(1, tint, sheen_tint)`, `Fd = schlick_weight(cos_d)` (Burley 2015, Section 3.1).
pub fn diffuse_sheen(p: &DiffuseParams, base_color: Rgb, cos_i: f32, cos_o: f32, cos_d: f32) -> (f32, Rgb) {
    let (fo, fi) = (schlick_weight(cos_o.abs()), schlick_weight(cos_i.abs()));
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * p.roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    let base = if p.has_flatness {
        let fss90 = rr / 2.0;
        let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
        let f_ss = 1.25 * (fss * (1.0 / (cos_o.abs() + cos_i.abs()) - 0.5) + 0.5);
        lerp(f_diff + f_retro, f_ss, p.flatness)
    } else {
        f_diff + f_retro
    };
    let sheen = if p.sheen > 0.0 {
        let fd = schlick_weight(cos_d.abs());
        let c = Rgb::ONE * (1.0 - p.sheen_tint) + tint(base_color) * p.sheen_tint;
        c * (p.sheen * fd)
    } else {
        Rgb::ZERO
    };
    (base * INV_PI, sheen)
}

/// Burley's GTR1 ("generalised Trowbridge-Reitz", gamma 1) distribution of the clearcoat's
/// normals, `D(m) = (a^2 - 1) / (pi ln(a^2) (1 + (a^2 - 1) cos^2))` (Burley 2012, Appendix B,
/// eq. 4), sampled by `D(m) cos(m)` (no visible-normal sampling, as Mitsuba 3's `GTR1Isotropic`).
#[derive(Clone, Copy, Debug)]
pub struct Gtr1 {
    pub alpha: f32,
}

impl Gtr1 {
    /// The clearcoat's roughness, `lerp(0.1, 0.001, clearcoat_gloss)` (Burley 2012, Appendix B).
    pub fn clearcoat(gloss: f32) -> Self {
        Gtr1 { alpha: lerp(0.1, 0.001, gloss) }
    }

    pub fn eval(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
        // Mitsuba's underflow guard, as in `Microfacet::eval`.
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Density of [`Self::sample`], `D(m) cos(m)` per solid angle of `m`.
    pub fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.eval(m)
        }
    }

    /// `cos^2 = (1 - a^2^(1 - u.y)) / (1 - a^2)`, the inverse of the marginal CDF of `D cos`.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin_theta = (1.0 - cos2).max(0.0).sqrt();
        Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos2.max(0.0).sqrt())
    }
}

/// Smith's GGX masking `G1` of the clearcoat at the fixed roughness `alpha` (Mitsuba 3 uses
/// 0.25, Burley 2012's clearcoat masking): `2 / (1 + sqrt(1 + alpha^2 tan^2))`, zero on the
/// back of the microfacet.
pub fn smith_ggx1(v: Vec3, wh: Vec3, alpha: f32) -> f32 {
    if v.dot(wh) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let cos2 = v.z * v.z;
    let tan2 = (1.0 - cos2) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;

    /// GTR1's `D cos` integrates to 1 over the hemisphere and its sampler inverts its CDF:
    /// the fraction of samples below a cosine matches the closed-form CDF.
    #[test]
    fn gtr1_is_normalised_and_sampled_by_its_pdf() {
        for alpha in [0.01f32, 0.03, 0.1] {
            let d = Gtr1 { alpha };
            // Integral of D cos over the hemisphere, in u = cos^2 (d omega = pi du per azimuth 2pi).
            let n = 200_000;
            let mut sum = 0.0f64;
            for i in 0..n {
                let u = (i as f64 + 0.5) / n as f64;
                let c = u.sqrt() as f32;
                let m = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                sum += (d.eval(m) * PI) as f64 / n as f64;
            }
            assert!((sum - 1.0).abs() < 2e-2, "alpha {alpha}: integral {sum}");
            let mut s = Sampler::from_seed(3);
            let t = 0.9f32;
            let frac = (0..100_000).filter(|_| d.sample(s.next_2d()).z > t).count() as f32 / 1e5;
            // CDF of cos^2 > t^2: 1 - ln(1 + (a^2 - 1) t^2) / ln(a^2).
            let a2 = alpha * alpha;
            let expect = 1.0 - (1.0 + (a2 - 1.0) * t * t).ln() / a2.ln();
            assert!((frac - expect).abs() < 0.01, "alpha {alpha}: {frac} vs {expect}");
        }
    }

    #[test]
    fn schlick_fresnel_limits() {
        let r0 = Rgb::splat(0.04);
        assert!((schlick_fresnel(r0, 1.0, 1.5)[0] - 0.04).abs() < 1e-6);
        assert!((schlick_fresnel(r0, 1e-6, 1.5)[0] - 1.0).abs() < 1e-4);
        // From inside beyond the critical angle the transmitted cosine is 0: F = 1.
        assert!((schlick_fresnel(r0, -0.3, 1.5)[0] - 1.0).abs() < 1e-6);
        assert_eq!(alphas(0.0, 0.5), (0.25, 0.25));
        let (ax, ay) = alphas(1.0, 0.5);
        assert!(ax > ay && (ax * ay - 0.0625).abs() < 1e-6);
    }
}
