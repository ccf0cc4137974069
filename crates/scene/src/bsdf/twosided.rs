//! Mitsuba 3's `twosided`: the nested BSDF on both sides of the surface. A `wi` below the
//! surface sees the BSDF mirrored through it (`z` flipped for `wi` and `wo`).

use super::{Bsdf, BsdfSample};
use crate::mesh_attribute::TexPoint;
use glam::{Vec2, Vec3};
use haze_core::Rgb;

/// `v` mirrored through the surface if it is below it.
pub(super) fn front(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, v.z.abs())
}

fn flip_z(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

pub(super) fn sample(
    b: &Bsdf,
    wi: Vec3,
    u1: f32,
    u2: Vec2,
    uv: TexPoint,
    with_pdf: bool,
) -> Option<BsdfSample> {
    if wi.z >= 0.0 {
        return b.sample_with(wi, u1, u2, uv, with_pdf);
    }
    let s = b.sample_with(flip_z(wi), u1, u2, uv, with_pdf)?;
    Some(BsdfSample { wo: flip_z(s.wo), ..s })
}

pub(super) fn eval(b: &Bsdf, wi: Vec3, wo: Vec3, uv: TexPoint) -> Rgb {
    if wi.z >= 0.0 {
        b.eval(wi, wo, uv)
    } else {
        b.eval(flip_z(wi), flip_z(wo), uv)
    }
}

pub(super) fn eval_pdf(b: &Bsdf, wi: Vec3, wo: Vec3, uv: TexPoint) -> (Rgb, f32) {
    if wi.z >= 0.0 {
        b.eval_pdf(wi, wo, uv)
    } else {
        b.eval_pdf(flip_z(wi), flip_z(wo), uv)
    }
}

pub(super) fn pdf(b: &Bsdf, wi: Vec3, wo: Vec3, uv: TexPoint) -> f32 {
    if wi.z >= 0.0 {
        b.pdf(wi, wo, uv)
    } else {
        b.pdf(flip_z(wi), flip_z(wo), uv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twosided_diffuse_reflects_on_both_sides() {
        let one = Bsdf::Diffuse { reflectance: Rgb::splat(0.5).into() };
        let two = Bsdf::TwoSided(Box::new(one.clone()));
        let wi = Vec3::new(0.0, 0.6, -0.8);
        let wo = Vec3::new(0.6, 0.0, -0.8);
        assert_eq!(one.eval(wi, wo, Vec2::ZERO), Rgb::ZERO);
        assert!(one.sample(wi, 0.5, Vec2::splat(0.5), Vec2::ZERO).is_none());
        let f = two.eval(wi, wo, Vec2::ZERO);
        assert!((f[0] - 0.5 * haze_core::INV_PI * 0.8).abs() < 1e-6);
        assert!(two.eval(wi, -wo, Vec2::ZERO).is_black(), "no transmission");
        let s = two.sample(wi, 0.5, Vec2::new(0.3, 0.7), Vec2::ZERO).unwrap();
        assert!(s.wo.z < 0.0 && !s.transmitted);
        assert!((two.pdf(wi, s.wo, Vec2::ZERO) - s.pdf).abs() < 1e-5);
    }
}
