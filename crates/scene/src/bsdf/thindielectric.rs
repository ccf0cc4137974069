//! Mitsuba 3's `thindielectric`: a thin sheet of dielectric (a window pane, a soap film).
//! Light reflects specularly or goes straight through; the reflections inside the sheet are
//! summed in closed form, so reflection and transmission add up to 1.

use super::{reflect, BsdfSample};
use crate::bsdf::fresnel_dielectric;
use glam::Vec3;
use haze_core::Rgb;

/// Total reflectance of the sheet at incidence cosine `cos_i` (either side): with `R` the
/// Fresnel reflectance of one interface, `R' = R + T R T + T R^3 T + ... = 2R / (1 + R)`.
pub(super) fn reflectance(eta: f32, cos_i: f32) -> f32 {
    let (r, _, _) = fresnel_dielectric(cos_i.abs(), eta);
    r * 2.0 / (1.0 + r)
}

/// Reflection with probability `R'`, else straight transmission (Mitsuba's `Null`-typed
/// component: no bending, `eta` 1), each with weight 1.
pub(super) fn sample(eta: f32, wi: Vec3, u1: f32) -> BsdfSample {
    let r = reflectance(eta, wi.z);
    if u1 <= r {
        BsdfSample::specular(reflect(wi), Rgb::ONE, r, false)
    } else {
        BsdfSample { null: true, ..BsdfSample::specular(-wi, Rgb::ONE, 1.0 - r, true) }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::albedo;
    use super::super::Bsdf;
    use super::*;
    use glam::Vec2;

    /// White furnace: reflection and transmission sum to 1 from both sides, and the sampled
    /// lobe frequencies are `R'` and `1 - R'`.
    #[test]
    fn thindielectric_conserves_energy() {
        let b = Bsdf::ThinDielectric { eta: 1.333 / 1.000277 };
        for &cz in &[0.95f32, 0.4, 0.05, -0.3, -0.99] {
            let wi = Vec3::new((1.0 - cz * cz).sqrt(), 0.0, cz);
            let a = albedo(&b, wi, 5, 20_000);
            assert!((a - 1.0).abs() < 1e-6, "cos {cz}: {a}");
            let t = b.null_transmission(wi, Vec2::ZERO)[0];
            let n = 100_000;
            let mut s = haze_core::Sampler::from_seed(1);
            let through = (0..n)
                .filter(|_| b.sample(wi, s.next_1d(), s.next_2d(), Vec2::ZERO).unwrap().transmitted)
                .count() as f32
                / n as f32;
            assert!((through - t).abs() < 5e-3, "cos {cz}: sampled {through}, transmittance {t}");
        }
    }

    #[test]
    fn thin_sheet_at_normal_incidence() {
        // R = ((eta - 1) / (eta + 1))^2 = 0.04 for eta 1.5; R' = 0.08 / 1.04.
        let r = reflectance(1.5, 1.0);
        assert!((r - 0.08 / 1.04).abs() < 1e-5, "{r}");
        let s = sample(1.5, Vec3::Z, 0.99);
        assert!(s.null && s.transmitted && s.wo == -Vec3::Z && s.eta == 1.0);
    }
}
