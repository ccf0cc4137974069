//! Mitsuba 3's `dielectric`: a smooth interface between two indices of refraction, sampled by
//! choosing reflection with the Fresnel probability.

use super::{reflect, BsdfSample};
use glam::Vec3;
use haze_core::Rgb;

/// Samples reflection with probability `F(wi)`, else refraction (weight `1/eta^2` in radiance,
/// Veach 1997, 5.2). `eta = int_ior / ext_ior`; `wi.z < 0` means `wi` is inside.
pub(super) fn sample(eta: f32, wi: Vec3, u1: f32) -> BsdfSample {
    let (f, cos_t, eta_ti) = fresnel_dielectric(wi.z, eta);
    if u1 < f {
        return BsdfSample::specular(reflect(wi), Rgb::ONE, f, false);
    }
    // wo = -wi / eta_ti + n (cos_i / eta_ti + cos_t), with cos_t carrying the sign of the
    // transmitted side.
    let inv = 1.0 / eta_ti;
    let wo = Vec3::new(-wi.x * inv, -wi.y * inv, cos_t).normalize();
    BsdfSample { eta: eta_ti, ..BsdfSample::specular(wo, Rgb::splat(inv * inv), 1.0 - f, true) }
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
    use super::super::testing::albedo;
    use super::super::Bsdf;
    use super::*;
    use glam::Vec2;

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
        let s = b.sample(wi, 0.99, Vec2::ZERO, Vec2::ZERO).unwrap();
        assert!(s.transmitted && s.wo.z < 0.0);
        let sin_i = (1.0 - wi.z * wi.z).sqrt();
        let sin_t = (1.0 - s.wo.z * s.wo.z).sqrt();
        assert!((sin_i - 1.33 * sin_t).abs() < 1e-5);
        assert!((s.wo.x + wi.x / 1.33).abs() < 1e-5, "refracted direction lies in the plane of incidence");
    }

    /// White furnace: a dielectric conserves energy from both sides (reflection and
    /// transmission weights average to 1, up to the eta^2 radiance scaling which we undo).
    #[test]
    fn dielectric_conserves_energy() {
        for eta in [1.5, 1.0 / 1.33] {
            let b = Bsdf::Dielectric { eta };
            for &cz in &[0.9f32, 0.3, -0.5, -0.95] {
                let wi = Vec3::new((1.0 - cz * cz).sqrt(), 0.0, cz);
                let a = albedo(&b, wi, 9, 100_000);
                assert!((a - 1.0).abs() < 1e-3, "eta {eta} cos {cz}: {a}");
            }
        }
    }
}
