//! Surface scattering models: Mitsuba 3's BSDF plugins `null`, `diffuse`, `dielectric`,
//! `thindielectric`, `roughdielectric`, `plastic`, `roughplastic`, `twosided`, `conductor` and
//! `roughconductor`, `mask`, `pplastic` (unpolarised), `blendbsdf`, `normalmap`/`bumpmap`
//! (`perturbed`), `principled` and `principledthin`, one file each,
//! with the microfacet distributions they share in [`microfacet`] and the Disney lobes of the
//! two principled BSDFs in `disney`.
//!
//! Local shading frame: `z` is the shading normal. `wi` points *away* from the surface towards
//! where the light (or the path) came from, `wo` away from it towards where it goes, as in
//! Mitsuba and pbrt. `uv` is the surface parameterisation of the hit, for textured parameters.
//! Values include the cosine factor only where said.

mod blend;
mod conductor;
mod dielectric;
mod disney;
mod mask;
pub mod microfacet;
mod perturbed;
mod plastic;
mod pplastic;
mod principled;
mod principledthin;
mod roughdielectric;
mod roughness;
mod roughplastic;
mod thindielectric;
mod twosided;

pub use blend::Blend;
pub use conductor::{conductor_ior, fresnel_conductor, Conductor, CONDUCTOR_IORS};
pub use dielectric::fresnel_dielectric;
pub use mask::Mask;
pub use microfacet::{Microfacet, MicrofacetType};
pub use perturbed::{Perturbation, Perturbed};
pub use plastic::{fresnel_diffuse_reflectance, Plastic};
pub use pplastic::PPlastic;
pub use principled::Principled;
pub use principledthin::PrincipledThin;
pub use roughdielectric::RoughDielectric;
pub use roughness::Roughness;
pub use roughplastic::RoughPlastic;

use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::{Rgb, INV_PI};

#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Index-matched boundary: light passes unchanged; only media change.
    Null,
    /// Lambertian reflector, `f = reflectance / pi`, front side only.
    Diffuse { reflectance: Texture },
    /// Smooth dielectric interface with relative index `eta = int_ior / ext_ior`.
    Dielectric { eta: f32 },
    /// Thin dielectric sheet (`int_ior / ext_ior = eta`): specular reflection and straight
    /// transmission, with the inter-reflections inside the sheet summed.
    ThinDielectric { eta: f32 },
    /// Rough dielectric interface (Walter et al. 2007).
    RoughDielectric(RoughDielectric),
    /// Smooth dielectric coating on a diffuse base.
    Plastic(Plastic),
    /// Rough dielectric coating on a diffuse base.
    RoughPlastic(Box<RoughPlastic>),
    /// The nested BSDF on both sides: back-facing `wi` see it mirrored through the surface.
    TwoSided(Box<Bsdf>),
    /// A smooth (`conductor`) or rough (`roughconductor`) metal, front side only.
    Conductor(Box<Conductor>),
    /// The nested BSDF with probability `opacity`, else straight through (`mask`).
    Mask(Box<Mask>),
    /// Mitsuba's `pplastic`, unpolarised: a specular lobe over a diffuse base, front side only.
    PPlastic(Box<PPlastic>),
    /// `(1 - w) f_0 + w f_1` of two nested BSDFs (`blendbsdf`).
    Blend(Box<Blend>),
    /// The nested BSDF in a shading frame a normal or bump map perturbs (`normalmap`,
    /// `bumpmap`); the scene perturbs the hit's shading normal, the BSDF is the nested one.
    Perturbed(Box<Perturbed>),
    /// Mitsuba 3's `principled` (the Disney BSDF, Burley 2012 and 2015).
    Principled(Box<Principled>),
    /// Mitsuba 3's `principledthin` (Burley 2015's thin-surface BSDF).
    PrincipledThin(Box<PrincipledThin>),
}

/// A sampled outgoing direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Outgoing direction in the local shading frame.
    pub wo: Vec3,
    /// `f(wi, wo) |cos(wo)| / pdf`, including the `1/eta^2` radiance scaling on refraction.
    pub weight: Rgb,
    /// Solid-angle pdf; for specular samples, the discrete probability of the chosen lobe.
    pub pdf: f32,
    pub specular: bool,
    /// Relative index of refraction along the sampled path (1 unless refracted), for Russian
    /// roulette on radiance (Mitsuba's `eta` tracking).
    pub eta: f32,
    /// True if `wo` is on the opposite side of the surface from `wi`.
    pub transmitted: bool,
    /// The path went straight on as if there were no surface (Mitsuba's sampled type
    /// `BSDFFlags::Null`: the `null` BSDF and the transmission of `thindielectric`). Mitsuba's
    /// volpath does not count such a sample as a scattering event (depth, MIS, specular chain).
    pub null: bool,
}

impl BsdfSample {
    fn specular(wo: Vec3, weight: Rgb, pdf: f32, transmitted: bool) -> Self {
        BsdfSample { wo, weight, pdf, specular: true, eta: 1.0, transmitted, null: false }
    }
    fn glossy(wo: Vec3, weight: Rgb, pdf: f32) -> Self {
        BsdfSample { wo, weight, pdf, specular: false, eta: 1.0, transmitted: false, null: false }
    }
}

impl Bsdf {
    #[inline]
    pub fn is_null(&self) -> bool {
        match self {
            Bsdf::Null => true,
            Bsdf::TwoSided(_) | Bsdf::Blend(_) | Bsdf::Perturbed(_) => self.nested_is_null(),
            _ => false,
        }
    }

    // Out of line: the nesting recurses, and the common BSDFs answer above without a call.
    fn nested_is_null(&self) -> bool {
        match self {
            Bsdf::Null => true,
            Bsdf::TwoSided(b) => b.is_null(),
            Bsdf::Blend(b) => b.nested.iter().all(Bsdf::is_null),
            Bsdf::Perturbed(p) => p.nested.is_null(),
            _ => false,
        }
    }

    /// True for BSDFs that can return a null-typed sample ([`BsdfSample::null`]: light passing
    /// straight through, which is not a scattering event and does not count towards a path's
    /// depth): `null` and `thindielectric`'s transmission.
    pub fn may_pass_through(&self) -> bool {
        match self {
            Bsdf::Null | Bsdf::ThinDielectric { .. } | Bsdf::Mask(_) => true,
            Bsdf::TwoSided(b) => b.may_pass_through(),
            Bsdf::Blend(b) => b.nested.iter().any(Bsdf::may_pass_through),
            Bsdf::Perturbed(p) => p.nested.may_pass_through(),
            _ => false,
        }
    }

    /// True for a rough interface that the many-light methods' camera walk passes through (next
    /// event estimation there, a BSDF sample, gathering beyond) instead of gathering at it
    /// (`docs/theory.md` §2.1, "Rough interfaces"): a connection from a virtual light to a point
    /// of rough glass goes through a refraction lobe on the receiver's side and, for surface
    /// VPLs on the glass, on the light's side too, so most camera samples get nothing from a
    /// pass's few lights in the lobes and a rare one gets much (Mitsuba 3's
    /// `test_homo_roughdielectric_spot`: 58% of the spheres' pixels had all samples equal).
    pub fn is_rough_interface(&self) -> bool {
        match self {
            Bsdf::RoughDielectric(_) => true,
            // A GGX transmission lobe: the same refraction lobes as a rough dielectric.
            Bsdf::Principled(p) => p.has_spec_trans,
            Bsdf::Perturbed(p) => p.nested.is_rough_interface(),
            _ => false,
        }
    }

    /// True when the BSDF has no effect on light at all besides absorbing it
    /// (a black diffuse surface): paths end there.
    #[inline]
    pub fn is_black(&self) -> bool {
        match self {
            Bsdf::Diffuse { reflectance: Texture::Constant(c) } => c.is_black(),
            Bsdf::Diffuse { .. } | Bsdf::TwoSided(_) | Bsdf::Blend(_) | Bsdf::Perturbed(_) => {
                self.nested_is_black()
            }
            _ => false,
        }
    }

    // Out of line, as `nested_is_null`: asked at every surface hit, answered above without a
    // call for a plain BSDF or a constant diffuse.
    fn nested_is_black(&self) -> bool {
        match self {
            Bsdf::Diffuse { reflectance } => reflectance.is_black(),
            Bsdf::TwoSided(b) => b.is_black(),
            Bsdf::Blend(b) => b.nested.iter().all(Bsdf::is_black),
            Bsdf::Perturbed(p) => p.nested.is_black(),
            _ => false,
        }
    }

    /// True if the BSDF's roughness differs along the surface's `dp/du` and `dp/dv` (an
    /// anisotropic or textured `alpha_u`/`alpha_v`): its shading frame must then follow `dp/du`
    /// ([`crate::Scene::shading_frame`]); every other BSDF is the same about the normal.
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Bsdf::RoughDielectric(b) => b.distr.is_anisotropic(),
            Bsdf::Conductor(c) => c.distr.as_ref().is_some_and(Roughness::is_anisotropic),
            Bsdf::PPlastic(b) => b.distr.is_anisotropic(),
            Bsdf::Principled(b) => b.has_anisotropic,
            Bsdf::PrincipledThin(b) => b.has_anisotropic,
            Bsdf::Mask(m) => m.nested.is_anisotropic(),
            Bsdf::TwoSided(b) => b.is_anisotropic(),
            Bsdf::Blend(b) => b.nested.iter().any(Bsdf::is_anisotropic),
            Bsdf::Perturbed(p) => p.nested.is_anisotropic(),
            _ => false,
        }
    }

    /// True for BSDFs whose every sample is specular (no NEE at their vertices).
    pub fn is_specular(&self) -> bool {
        match self {
            Bsdf::Null | Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. } => true,
            Bsdf::Conductor(c) => c.distr.is_none(),
            Bsdf::Mask(m) => m.nested.is_specular(),
            Bsdf::TwoSided(b) => b.is_specular(),
            Bsdf::Blend(b) => b.nested.iter().all(Bsdf::is_specular),
            Bsdf::Perturbed(p) => p.nested.is_specular(),
            _ => false,
        }
    }

    /// Samples `wo` given `wi` (both local, `z` = shading normal, `wi` pointing away from the
    /// surface towards the previous vertex) at surface coordinates `uv`. `u1` picks the lobe,
    /// `u2` the direction within it.
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, uv: impl Into<TexPoint>) -> Option<BsdfSample> {
        let uv: TexPoint = uv.into();
        self.sample_with(wi, u1, u2, uv, true)
    }

    /// [`Self::sample`]; with `with_pdf` false the caller promises not to read the sample's
    /// `pdf` (a path tracer whose emitters are all delta lights: no MIS weight ever uses it),
    /// and a rough dielectric sampling visible normals skips the microfacet density (an `exp`
    /// and a masking term) and reports `pdf` 0. Direction and weight are the same either way,
    /// except that a normal whose density underflows (`D(m) cos(m) <= 1e-20`) is rejected only
    /// when the pdf is computed.
    pub fn sample_with(
        &self,
        wi: Vec3,
        u1: f32,
        u2: Vec2,
        uv: impl Into<TexPoint>,
        with_pdf: bool,
    ) -> Option<BsdfSample> {
        let uv: TexPoint = uv.into();
        match self {
            Bsdf::Null => Some(BsdfSample { null: true, ..BsdfSample::specular(-wi, Rgb::ONE, 1.0, true) }),
            Bsdf::Diffuse { reflectance } => {
                if wi.z <= 0.0 {
                    return None;
                }
                let wo = sample_cosine_hemisphere(u2);
                let pdf = cosine_hemisphere_pdf(wo.z);
                (pdf > 0.0).then(|| BsdfSample::glossy(wo, reflectance.eval(uv), pdf))
            }
            Bsdf::Dielectric { eta } => Some(dielectric::sample(*eta, wi, u1)),
            Bsdf::ThinDielectric { eta } => Some(thindielectric::sample(*eta, wi, u1)),
            Bsdf::RoughDielectric(b) => b.sample(wi, u1, u2, uv, with_pdf),
            Bsdf::Plastic(b) => b.sample(wi, u1, u2, uv),
            Bsdf::RoughPlastic(b) => b.sample(wi, u1, u2, uv),
            Bsdf::TwoSided(b) => twosided::sample(b, wi, u1, u2, uv, with_pdf),
            Bsdf::Conductor(c) => c.sample(wi, u2, uv),
            Bsdf::Mask(m) => m.sample(wi, u1, u2, uv, with_pdf),
            Bsdf::PPlastic(b) => b.sample(wi, u1, u2, uv),
            Bsdf::Blend(b) => b.sample(wi, u1, u2, uv, with_pdf),
            Bsdf::Perturbed(p) => p.nested.sample_with(wi, u1, u2, uv, with_pdf),
            Bsdf::Principled(b) => b.sample(wi, u1, u2, uv),
            Bsdf::PrincipledThin(b) => b.sample(wi, u1, u2, uv),
        }
    }

    /// `f(wi, wo) |cos(wo)|` of the non-specular lobes (zero for specular ones).
    pub fn eval(&self, wi: Vec3, wo: Vec3, uv: impl Into<TexPoint>) -> Rgb {
        let uv: TexPoint = uv.into();
        match self {
            Bsdf::Diffuse { reflectance } if wi.z > 0.0 && wo.z > 0.0 => {
                reflectance.eval(uv) * (INV_PI * wo.z)
            }
            Bsdf::RoughDielectric(b) => Rgb::splat(b.eval(wi, wo, uv)),
            Bsdf::Plastic(b) => b.eval(wi, wo, uv),
            Bsdf::RoughPlastic(b) => b.eval(wi, wo, uv),
            Bsdf::TwoSided(b) => twosided::eval(b, wi, wo, uv),
            Bsdf::Conductor(c) => c.eval(wi, wo, uv),
            Bsdf::Mask(m) => m.eval(wi, wo, uv),
            Bsdf::PPlastic(b) => b.eval(wi, wo, uv),
            Bsdf::Blend(b) => b.eval(wi, wo, uv),
            Bsdf::Perturbed(p) => p.nested.eval(wi, wo, uv),
            Bsdf::Principled(b) => b.eval(wi, wo, uv),
            Bsdf::PrincipledThin(b) => b.eval(wi, wo, uv),
            _ => Rgb::ZERO,
        }
    }

    /// True if a sampled direction may leave on the other side of the surface than the one
    /// the path arrived from (a refraction or a straight pass): `null`, the dielectrics and
    /// `mask`.
    pub fn transmits(&self) -> bool {
        match self {
            Bsdf::Null | Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. } | Bsdf::RoughDielectric(_) => {
                true
            }
            Bsdf::Diffuse { .. }
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_)
            | Bsdf::Conductor(_)
            | Bsdf::PPlastic(_) => false,
            // A mask passes light straight through with probability `1 - opacity`.
            Bsdf::Mask(_) => true,
            Bsdf::Principled(b) => b.has_spec_trans,
            Bsdf::PrincipledThin(b) => b.has_spec_trans || b.has_diff_trans,
            Bsdf::TwoSided(b) => b.transmits(),
            Bsdf::Blend(b) => b.nested.iter().any(Bsdf::transmits),
            Bsdf::Perturbed(p) => p.nested.transmits(),
        }
    }

    /// True if [`Self::eval`] is zero unless `wi` and `wo` both lie on the front side
    /// (`z > 0`): `diffuse`, `plastic`, `roughplastic` and the conductors (each checks exactly
    /// that first).
    pub fn front_only(&self) -> bool {
        matches!(
            self,
            Bsdf::Diffuse { .. }
                | Bsdf::Plastic(_)
                | Bsdf::RoughPlastic(_)
                | Bsdf::Conductor(_)
                | Bsdf::PPlastic(_)
        ) || matches!(self, Bsdf::Principled(b) if !b.has_spec_trans)
            || matches!(self, Bsdf::Mask(m) if m.nested.front_only())
            || matches!(self, Bsdf::Blend(b) if b.nested.iter().all(Bsdf::front_only))
            || matches!(self, Bsdf::Perturbed(p) if p.nested.front_only())
    }

    /// Solid-angle pdf of [`Self::sample`] producing `wo` through a non-specular lobe (zero
    /// for specular BSDFs).
    pub fn pdf(&self, wi: Vec3, wo: Vec3, uv: impl Into<TexPoint>) -> f32 {
        let uv: TexPoint = uv.into();
        match self {
            Bsdf::Diffuse { .. } if wi.z > 0.0 && wo.z > 0.0 => cosine_hemisphere_pdf(wo.z),
            Bsdf::RoughDielectric(b) => b.pdf(wi, wo, uv),
            Bsdf::Plastic(b) => b.pdf(wi, wo),
            Bsdf::RoughPlastic(b) => b.pdf(wi, wo),
            Bsdf::TwoSided(b) => twosided::pdf(b, wi, wo, uv),
            Bsdf::Conductor(c) => c.pdf(wi, wo, uv),
            Bsdf::Mask(m) => m.pdf(wi, wo, uv),
            Bsdf::PPlastic(b) => b.pdf(wi, wo, uv),
            Bsdf::Blend(b) => b.pdf(wi, wo, uv),
            Bsdf::Perturbed(p) => p.nested.pdf(wi, wo, uv),
            Bsdf::Principled(b) => b.pdf(wi, wo, uv),
            Bsdf::PrincipledThin(b) => b.pdf(wi, wo, uv),
            _ => 0.0,
        }
    }

    /// `(`[`Self::eval`]`, `[`Self::pdf`]`)` of one direction, for next-event estimation
    /// with MIS, sharing what both compute (half vector, microfacet density, Fresnel terms)
    /// where the BSDF has such terms. The same values as the two calls.
    pub fn eval_pdf(&self, wi: Vec3, wo: Vec3, uv: impl Into<TexPoint>) -> (Rgb, f32) {
        let uv: TexPoint = uv.into();
        match self {
            Bsdf::Plastic(b) => b.eval_pdf(wi, wo, uv),
            Bsdf::RoughPlastic(b) => b.eval_pdf(wi, wo, uv),
            Bsdf::TwoSided(b) => twosided::eval_pdf(b, wi, wo, uv),
            Bsdf::Mask(m) => m.eval_pdf(wi, wo, uv),
            Bsdf::PPlastic(b) => b.eval_pdf(wi, wo, uv),
            Bsdf::Blend(b) => b.eval_pdf(wi, wo, uv),
            Bsdf::Perturbed(p) => p.nested.eval_pdf(wi, wo, uv),
            Bsdf::Principled(b) => b.eval_pdf(wi, wo, uv),
            Bsdf::PrincipledThin(b) => b.eval_pdf(wi, wo, uv),
            _ => (self.eval(wi, wo, uv), self.pdf(wi, wo, uv)),
        }
    }

    /// The fraction of light that goes straight through the surface along `-wi` (Mitsuba's
    /// `eval_null_transmission`), for shadow rays: 1 for `null`, the summed transmittance
    /// `1 - R'` for `thindielectric`, 0 for every surface that blocks.
    /// True if [`Self::null_transmission`] can be non-zero (shadow rays cross the surface).
    pub fn transmits_null(&self) -> bool {
        match self {
            Bsdf::Null | Bsdf::ThinDielectric { .. } | Bsdf::Mask(_) => true,
            Bsdf::TwoSided(b) => b.transmits_null(),
            Bsdf::Blend(b) => b.nested.iter().any(Bsdf::transmits_null),
            Bsdf::Perturbed(p) => p.nested.transmits_null(),
            _ => false,
        }
    }

    pub fn null_transmission(&self, wi: Vec3, uv: impl Into<TexPoint>) -> Rgb {
        let uv: TexPoint = uv.into();
        match self {
            Bsdf::Null => Rgb::ONE,
            Bsdf::ThinDielectric { eta } => Rgb::splat(1.0 - thindielectric::reflectance(*eta, wi.z)),
            Bsdf::TwoSided(b) => b.null_transmission(twosided::front(wi), uv),
            Bsdf::Mask(m) => Rgb::splat(1.0 - m.alpha(uv)),
            Bsdf::Blend(b) => b.null_transmission(wi, uv),
            Bsdf::Perturbed(p) => p.nested.null_transmission(wi, uv),
            _ => Rgb::ZERO,
        }
    }
}

/// Mirror reflection about the shading normal.
fn reflect(wi: Vec3) -> Vec3 {
    Vec3::new(-wi.x, -wi.y, wi.z)
}

#[cfg(test)]
pub(crate) mod testing {
    //! Checks shared by the BSDF tests.
    use super::*;
    use haze_core::Sampler;
    use haze_testkit::chi2::{chi2_sphere, Chi2Result};

    /// The chi-square test of `haze_testkit` on directions rotated by 90 degrees about `y`,
    /// so that lobes around the normal fall on the equator, where the test's equal-area bins
    /// are narrow in both angles.
    pub fn chi2_rotated(
        mut sample: impl FnMut() -> Option<Vec3>,
        pdf: impl Fn(Vec3) -> f32,
        n: usize,
    ) -> Chi2Result {
        let rot = |d: Vec3| Vec3::new(d.z, d.y, -d.x);
        let unrot = |d: Vec3| Vec3::new(-d.z, d.y, d.x);
        // A failed sample is a sample of the missing mass: put it where the pdf is zero
        // ("outside support") only if the pdf integrates to 1; callers pass conditional pdfs.
        chi2_sphere(
            || loop {
                if let Some(d) = sample() {
                    break rot(d);
                }
            },
            |d| pdf(unrot(d)),
            n,
        )
    }

    /// The chi-square verdict at level 0.01, tolerating a handful (1 in 20,000) of samples in
    /// bins where the test's 8x8 quadrature saw a zero pdf: a sharp edge of the support (the
    /// visibility cut-off `wi.m = 0` of the microfacets, the horizon) can leave a sliver of
    /// support in a bin whose quadrature points all miss it.
    pub fn passed(r: &Chi2Result, n: usize) -> bool {
        r.p_value >= 0.01 && r.outside_support * 20_000 <= n
    }

    /// The non-specular part of `b` as a sampler conditioned on producing a non-specular
    /// sample, and its pdf renormalised by the probability of that.
    pub fn check_sampling(b: &Bsdf, wi: Vec3, seed: u64, n: usize) -> Chi2Result {
        let uv = Vec2::new(0.3, 0.6);
        let mut s = Sampler::from_seed(seed);
        // Probability of a non-specular sample, estimated with a separate stream.
        let mut s2 = Sampler::from_seed(seed ^ 0x55);
        let m = 200_000;
        let mut ok = 0usize;
        for _ in 0..m {
            if let Some(smp) = b.sample(wi, s2.next_1d(), s2.next_2d(), uv) {
                if !smp.specular {
                    ok += 1;
                }
            }
        }
        let p_ns = ok as f32 / m as f32;
        chi2_rotated(
            || {
                let smp = b.sample(wi, s.next_1d(), s.next_2d(), uv)?;
                if smp.specular {
                    return None;
                }
                let pdf = b.pdf(wi, smp.wo, uv);
                assert!(
                    (pdf - smp.pdf).abs() <= 1e-3 * pdf.max(1e-2),
                    "{b:?}: sample pdf {} but pdf() {pdf} at {}",
                    smp.pdf,
                    smp.wo
                );
                let w = b.eval(wi, smp.wo, uv) / pdf;
                assert!(
                    (w - smp.weight).max_component().abs() <= 1e-3 * w.max_component().max(1.0),
                    "{b:?}: weight {} but eval/pdf {w}",
                    smp.weight
                );
                Some(smp.wo)
            },
            |d| b.pdf(wi, d, uv) / p_ns,
            n,
        )
    }

    /// Mean of `weight` (times `eta^2` after refraction, undoing the radiance scaling) over
    /// `n` samples: the directional albedo.
    pub fn albedo(b: &Bsdf, wi: Vec3, seed: u64, n: usize) -> f64 {
        let mut s = Sampler::from_seed(seed);
        let mut acc = 0.0f64;
        for _ in 0..n {
            if let Some(smp) = b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO) {
                acc += (smp.weight.mean() * smp.eta * smp.eta) as f64;
            }
        }
        acc / n as f64
    }

    pub fn dir(cos_theta: f32, phi: f32) -> Vec3 {
        let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;

    #[test]
    fn diffuse_sampling_weight_matches_eval_over_pdf() {
        let b = Bsdf::Diffuse { reflectance: Rgb::new(0.2, 0.5, 0.8).into() };
        let mut s = Sampler::from_seed(2);
        let wi = Vec3::new(0.0, 0.6, 0.8);
        for _ in 0..100 {
            let smp = b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO).unwrap();
            let w = b.eval(wi, smp.wo, Vec2::ZERO) / b.pdf(wi, smp.wo, Vec2::ZERO);
            assert!((w - smp.weight).max_component().abs() < 1e-4);
        }
    }

    /// `may_pass_through` says exactly which BSDFs sample null-typed directions (volpath stops
    /// a path at its depth limit only where none can be drawn).
    #[test]
    fn may_pass_through_matches_the_samples() {
        use self::microfacet::{Microfacet, MicrofacetType};
        let kinds = [
            Bsdf::Null,
            Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() },
            Bsdf::Dielectric { eta: 1.5 },
            Bsdf::ThinDielectric { eta: 1.5 },
            Bsdf::TwoSided(Box::new(Bsdf::ThinDielectric { eta: 1.5 })),
            Bsdf::TwoSided(Box::new(Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() })),
            Bsdf::RoughDielectric(roughdielectric::RoughDielectric {
                distr: Microfacet::new(MicrofacetType::Beckmann, 0.3, true).into(),
                eta: 1.5,
            }),
        ];
        let mut s = Sampler::from_seed(5);
        for b in &kinds {
            let mut null = false;
            for i in 0..2000 {
                let wi = if i % 2 == 0 {
                    Vec3::new(0.0, 0.6, 0.8)
                } else {
                    Vec3::new(0.3, 0.0, -0.95).normalize()
                };
                null |= b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO).is_some_and(|x| x.null);
            }
            assert_eq!(b.may_pass_through(), null, "{b:?}");
        }
    }

    /// `eval_pdf` shares terms between `eval` and `pdf` (plastic, roughplastic); it must give
    /// their values bit for bit, on both sides of the surface, for every kind.
    #[test]
    fn eval_pdf_is_eval_and_pdf() {
        use self::microfacet::{Microfacet, MicrofacetType};
        let tex = || Texture::from(Rgb::new(0.2, 0.7, 0.7));
        let mut kinds = vec![
            Bsdf::Null,
            Bsdf::Diffuse { reflectance: tex() },
            Bsdf::Dielectric { eta: 1.5 },
            Bsdf::Plastic(Plastic::new(tex(), 1.49, false)),
            Bsdf::Plastic(Plastic::new(tex(), 1.49, true)),
        ];
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for vis in [true, false] {
                let distr = Microfacet::new(ty, 0.3, vis);
                kinds.push(Bsdf::RoughPlastic(Box::new(RoughPlastic::new(distr, tex(), 1.49, vis))));
                kinds.push(Bsdf::RoughDielectric(RoughDielectric { distr: distr.into(), eta: 1.3 }));
            }
        }
        kinds.push(Bsdf::TwoSided(Box::new(kinds[6].clone())));
        let mut s = Sampler::from_seed(17);
        let mut dir = || haze_core::sampling::sample_uniform_sphere(s.next_2d());
        for b in &kinds {
            let mut nonzero = 0;
            for _ in 0..2000 {
                let (wi, wo, uv) = (dir(), dir(), Vec2::new(0.3, 0.6));
                let (f, pdf) = b.eval_pdf(wi, wo, uv);
                let (f2, pdf2) = (b.eval(wi, wo, uv), b.pdf(wi, wo, uv));
                assert_eq!(f.0.map(f32::to_bits), f2.0.map(f32::to_bits), "{b:?} at {wi}, {wo}");
                assert_eq!(pdf.to_bits(), pdf2.to_bits(), "{b:?} at {wi}, {wo}");
                nonzero += usize::from(pdf > 0.0);
            }
            let smooth = matches!(b, Bsdf::Null | Bsdf::Dielectric { .. });
            assert_eq!(nonzero == 0, smooth, "{b:?}: {nonzero} of 2000 pairs with a pdf");
        }
    }

    /// Without the pdf a sample keeps its direction, weight and flags (rough dielectrics with
    /// visible normals report pdf 0; every other kind computes it anyway).
    #[test]
    fn samples_without_pdf_keep_direction_and_weight() {
        use self::microfacet::{Microfacet, MicrofacetType};
        let mut kinds =
            vec![Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() }, Bsdf::Dielectric { eta: 1.5 }];
        for ty in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for vis in [true, false] {
                let rough = Bsdf::RoughDielectric(RoughDielectric {
                    distr: Microfacet::new(ty, 0.3, vis).into(),
                    eta: 1.3,
                });
                kinds.push(Bsdf::TwoSided(Box::new(rough.clone())));
                kinds.push(rough);
            }
        }
        let mut s = Sampler::from_seed(23);
        for b in &kinds {
            let skips = match b {
                Bsdf::RoughDielectric(r) => r.distr.sample_visible(),
                Bsdf::TwoSided(inner) => {
                    matches!(&**inner, Bsdf::RoughDielectric(r) if r.distr.sample_visible())
                }
                _ => false,
            };
            let mut n = 0;
            for _ in 0..3000 {
                let wi = haze_core::sampling::sample_uniform_sphere(s.next_2d());
                let (u1, u2) = (s.next_1d(), s.next_2d());
                let (a, b2) =
                    (b.sample(wi, u1, u2, Vec2::ZERO), b.sample_with(wi, u1, u2, Vec2::ZERO, false));
                let (Some(a), Some(c)) = (a, b2) else {
                    assert_eq!(a.is_some(), b2.is_some(), "{b:?} at {wi}");
                    continue;
                };
                n += 1;
                assert_eq!((a.wo, a.weight, a.specular, a.eta), (c.wo, c.weight, c.specular, c.eta), "{b:?}");
                assert_eq!((a.transmitted, a.null), (c.transmitted, c.null));
                assert_eq!(c.pdf, if skips { 0.0 } else { a.pdf }, "{b:?}");
            }
            assert!(n > 1000, "{b:?}: {n} samples");
        }
    }

    #[test]
    fn null_transmission_of_each_kind() {
        let wi = Vec3::new(0.0, 0.6, 0.8);
        assert_eq!(Bsdf::Null.null_transmission(wi, Vec2::ZERO), Rgb::ONE);
        assert_eq!(Bsdf::Dielectric { eta: 1.5 }.null_transmission(wi, Vec2::ZERO), Rgb::ZERO);
        let t = Bsdf::ThinDielectric { eta: 1.5 }.null_transmission(wi, Vec2::ZERO)[0];
        assert!(t > 0.8 && t < 1.0, "{t}");
        let back = Bsdf::ThinDielectric { eta: 1.5 }.null_transmission(-wi, Vec2::ZERO)[0];
        assert_eq!(t, back, "a thin sheet transmits the same from both sides");
    }
}
