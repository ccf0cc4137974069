//! Surface scattering models (Mitsuba 3 plugins `null`, `diffuse`, `dielectric`).
//!
//! Local shading frame: `z` is the shading normal. `wi` points *away* from the surface towards
//! where the light (or the path) came from, `wo` away from it towards where it goes, as in
//! Mitsuba and pbrt. Values include the cosine factor only where said.

use haze_core::Rgb;

#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Index-matched boundary: light passes unchanged; only media change.
    Null,
    /// Lambertian reflector, `f = reflectance / pi`.
    Diffuse { reflectance: Rgb },
    /// Smooth dielectric interface with relative index `eta = int_ior / ext_ior`.
    Dielectric { eta: f32 },
}

impl Bsdf {
    pub fn is_null(&self) -> bool {
        matches!(self, Bsdf::Null)
    }
    /// True when the BSDF has no effect on light at all besides absorbing it
    /// (a black diffuse surface): paths end there.
    pub fn is_black(&self) -> bool {
        matches!(self, Bsdf::Diffuse { reflectance } if reflectance.is_black())
    }
}

use glam::{Vec2, Vec3};
use haze_core::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use haze_core::INV_PI;

/// A sampled outgoing direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Outgoing direction in the local shading frame.
    pub wo: Vec3,
    /// `f(wi, wo) |cos(wo)| / pdf`, including the `1/eta^2` radiance scaling on refraction.
    pub weight: Rgb,
    /// Solid-angle pdf; meaningless for specular samples.
    pub pdf: f32,
    pub specular: bool,
    /// Relative index of refraction along the sampled path (1 unless refracted), for Russian
    /// roulette on radiance (Mitsuba's `eta` tracking).
    pub eta: f32,
    /// True if `wo` is on the opposite side of the surface from `wi`.
    pub transmitted: bool,
}

impl Bsdf {
    /// Samples `wo` given `wi` (both local, `z` = shading normal, `wi` pointing away from the
    /// surface towards the previous vertex).
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        match *self {
            Bsdf::Null => Some(BsdfSample {
                wo: -wi,
                weight: Rgb::ONE,
                pdf: 1.0,
                specular: true,
                eta: 1.0,
                transmitted: true,
            }),
            Bsdf::Diffuse { reflectance } => {
                if wi.z <= 0.0 {
                    return None;
                }
                let wo = sample_cosine_hemisphere(u2);
                let pdf = cosine_hemisphere_pdf(wo.z);
                (pdf > 0.0).then_some(BsdfSample {
                    wo,
                    weight: reflectance,
                    pdf,
                    specular: false,
                    eta: 1.0,
                    transmitted: false,
                })
            }
            Bsdf::Dielectric { eta } => {
                let cos_i = wi.z;
                let (f, cos_t, eta_ti) = fresnel_dielectric(cos_i, eta);
                if u1 < f {
                    Some(BsdfSample {
                        wo: Vec3::new(-wi.x, -wi.y, wi.z),
                        weight: Rgb::ONE,
                        pdf: f,
                        specular: true,
                        eta: 1.0,
                        transmitted: false,
                    })
                } else {
                    // Refraction: wo = -wi / eta_ti + n (cos_i / eta_ti + cos_t), with cos_t
                    // carrying the sign of the transmitted side.
                    let inv = 1.0 / eta_ti;
                    let wo = Vec3::new(-wi.x * inv, -wi.y * inv, cos_t).normalize();
                    // Radiance is compressed by eta^2 entering the denser side (Veach 1997, 5.2).
                    let scale = inv * inv;
                    Some(BsdfSample {
                        wo,
                        weight: Rgb::splat(scale),
                        pdf: 1.0 - f,
                        specular: true,
                        eta: eta_ti,
                        transmitted: true,
                    })
                }
            }
        }
    }

    /// `f(wi, wo) |cos(wo)|` for non-specular BSDFs (zero for specular ones).
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        match *self {
            Bsdf::Diffuse { reflectance } if wi.z > 0.0 && wo.z > 0.0 => reflectance * (INV_PI * wo.z),
            _ => Rgb::ZERO,
        }
    }

    /// Solid-angle pdf of [`Self::sample`] producing `wo` (zero for specular BSDFs).
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match *self {
            Bsdf::Diffuse { .. } if wi.z > 0.0 => cosine_hemisphere_pdf(wo.z),
            _ => 0.0,
        }
    }

    /// True for BSDFs whose every sample is specular (no NEE at their vertices).
    pub fn is_specular(&self) -> bool {
        matches!(self, Bsdf::Null | Bsdf::Dielectric { .. })
    }
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface with relative index `eta`
/// (inside over outside). `cos_i` is measured from the normal on the outside; negative means
/// the ray arrives from inside. Returns `(F, cos_t, eta_ti)` where `cos_t` is the signed cosine
/// of the transmitted direction (opposite sign to `cos_i`) and `eta_ti` the relative index
/// the ray crosses into (`eta` entering, `1/eta` leaving). Total internal reflection gives `F = 1`.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32, f32) {
    let eta_ti = if cos_i >= 0.0 { eta } else { 1.0 / eta };
    let ci = cos_i.abs();
    let sin2_t = (1.0 - ci * ci).max(0.0) / (eta_ti * eta_ti);
    if sin2_t >= 1.0 {
        return (1.0, 0.0, eta_ti);
    }
    let ct = (1.0 - sin2_t).sqrt();
    let rs = (ci - eta_ti * ct) / (ci + eta_ti * ct);
    let rp = (eta_ti * ci - ct) / (eta_ti * ci + ct);
    let f = 0.5 * (rs * rs + rp * rp);
    (f, if cos_i >= 0.0 { -ct } else { ct }, eta_ti)
}

#[cfg(test)]
mod tests {
    use super::*;
    use haze_core::Sampler;

    #[test]
    fn fresnel_limits() {
        let (f0, _, _) = fresnel_dielectric(1.0, 1.5);
        assert!((f0 - 0.04).abs() < 1e-4, "{f0}");
        let (tir, _, _) = fresnel_dielectric(-0.1, 1.5);
        assert_eq!(tir, 1.0);
        let (one, ct, _) = fresnel_dielectric(0.7, 1.0);
        assert!(one.abs() < 1e-6 && (ct + 0.7).abs() < 1e-6);
    }

    #[test]
    fn dielectric_refraction_obeys_snell() {
        let b = Bsdf::Dielectric { eta: 1.33 };
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let s = b.sample(wi, 0.99, Vec2::ZERO).unwrap();
        assert!(s.transmitted && s.wo.z < 0.0);
        let sin_i = (1.0 - wi.z * wi.z).sqrt();
        let sin_t = (1.0 - s.wo.z * s.wo.z).sqrt();
        assert!((sin_i - 1.33 * sin_t).abs() < 1e-5);
        assert!((s.wo.x + wi.x / 1.33).abs() < 1e-5, "refracted direction lies in the plane of incidence");
    }

    /// White furnace: a dielectric conserves energy (reflection + transmission weights average
    /// to 1, up to the eta^2 radiance scaling which we undo).
    #[test]
    fn dielectric_conserves_energy() {
        let b = Bsdf::Dielectric { eta: 1.5 };
        let mut s = Sampler::from_seed(9);
        for &cz in &[0.9f32, 0.3, -0.5, -0.95] {
            let wi = Vec3::new((1.0 - cz * cz).sqrt(), 0.0, cz);
            let n = 100_000;
            let mut acc = 0.0f64;
            for _ in 0..n {
                let smp = b.sample(wi, s.next_1d(), s.next_2d()).unwrap();
                acc += (smp.weight[0] * smp.eta * smp.eta) as f64;
            }
            assert!((acc / n as f64 - 1.0).abs() < 1e-3, "cos {cz}: {}", acc / n as f64);
        }
    }

    #[test]
    fn diffuse_sampling_weight_matches_eval_over_pdf() {
        let b = Bsdf::Diffuse { reflectance: Rgb::new(0.2, 0.5, 0.8) };
        let mut s = Sampler::from_seed(2);
        let wi = Vec3::new(0.0, 0.6, 0.8);
        for _ in 0..100 {
            let smp = b.sample(wi, s.next_1d(), s.next_2d()).unwrap();
            let w = b.eval(wi, smp.wo) / b.pdf(wi, smp.wo);
            assert!((w - smp.weight).max_component().abs() < 1e-4);
        }
    }
}
