//! Mitsuba 3's `normalmap` and `bumpmap`: a nested BSDF seen in a shading frame perturbed by a
//! texture. The BSDF itself is the nested one; the scene replaces the hit's shading normal by
//! [`Perturbed::shading_normal`] when it completes the interaction (`Scene::resolve_hit`), so
//! every integrator shades in the perturbed frame.
//!
//! With `ns` the shading normal and `dp/du`, `dp/dv` the surface's uv tangents
//! ([`crate::shape::tangents`]):
//! - `normalmap` (Mitsuba's `normalmap.cpp`): the texture's RGB value `c` is the tangent-space
//!   normal `2 c - 1` in the frame `s = normalize(dp/du - ns (ns . dp/du))`, `t = ns x s`, `ns`:
//!   `n' = normalize(s (2 c.r - 1) + t (2 c.g - 1) + ns (2 c.b - 1))`.
//! - `bumpmap` (Mitsuba's `bumpmap.cpp`): the height `h = scale * texture` (luminance) displaces
//!   the surface along `ns`: `dp/du' = dp/du + ns (dh/du - ns . dp/du)`, likewise for `v`, and
//!   `n' = normalize(dp/du' x dp/dv')`, turned to the geometric normal's side.
//!
//! Mitsuba also zeroes the BSDF where `wo` lies on different sides of the unperturbed and the
//! perturbed shading planes; haze does not (see docs/mitsuba-compat.md): such directions point
//! into the surface, where the geometry usually blocks them anyway.

use super::Bsdf;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;
use glam::Vec3;

#[derive(Clone, Debug, PartialEq)]
pub enum Perturbation {
    /// `normalmap`: tangent-space normals, `2 c - 1`.
    NormalMap(Texture),
    /// `bumpmap`: a height field `scale * texture`.
    BumpMap { height: Texture, scale: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Perturbed {
    pub perturbation: Perturbation,
    pub nested: Bsdf,
}

impl Perturbed {
    /// The perturbed shading normal at `uv` (see the module's formulas); `ns` unchanged where
    /// the result is degenerate (zero or not finite).
    pub fn shading_normal(&self, uv: TexPoint, n: Vec3, ns: Vec3, dp_du: Vec3, dp_dv: Vec3) -> Vec3 {
        let perturbed = match &self.perturbation {
            Perturbation::NormalMap(texture) => {
                let c = texture.eval(uv);
                let local = Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0);
                let s = (dp_du - ns * ns.dot(dp_du)).normalize_or_zero();
                let t = ns.cross(s);
                (s * local.x + t * local.y + ns * local.z).normalize_or_zero()
            }
            Perturbation::BumpMap { height, scale } => {
                let grad = height.eval_1_grad(uv) * *scale;
                let du = dp_du + ns * (grad.x - ns.dot(dp_du));
                let dv = dp_dv + ns * (grad.y - ns.dot(dp_dv));
                let m = du.cross(dv).normalize_or_zero();
                if m.dot(n) < 0.0 {
                    -m
                } else {
                    m
                }
            }
        };
        if perturbed == Vec3::ZERO || !perturbed.is_finite() {
            ns
        } else {
            perturbed
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bitmap::{Bitmap, FilterType, WrapMode};
    use glam::Affine2;
    use glam::Vec2;
    use haze_core::Rgb;
    use std::sync::Arc;

    fn perturbed(perturbation: Perturbation) -> Perturbed {
        Perturbed { perturbation, nested: Bsdf::Null }
    }

    /// The flat normal-map colour (0.5, 0.5, 1) keeps the normal; a tilted one turns it
    /// towards `dp/du` by the analytic angle; a constant height keeps it.
    #[test]
    fn normal_map_turns_the_normal_in_tangent_space() {
        let (n, du, dv) = (Vec3::Z, Vec3::new(2.0, 0.0, 0.3), Vec3::new(0.0, 3.0, 0.0));
        let flat = perturbed(Perturbation::NormalMap(Rgb::new(0.5, 0.5, 1.0).into()));
        assert!((flat.shading_normal((Vec2::ZERO).into(), n, n, du, dv) - n).length() < 1e-6);
        // (2c - 1) = (0.6, 0, 0.8): 36.87 degrees towards s = +x (dp/du without its normal part).
        let tilted = perturbed(Perturbation::NormalMap(Rgb::new(0.8, 0.5, 0.9).into()));
        let m = tilted.shading_normal((Vec2::ZERO).into(), n, n, du, dv);
        assert!((m - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6, "{m}");
        // Green along t = n x s = +y.
        let green = perturbed(Perturbation::NormalMap(Rgb::new(0.5, 0.8, 0.9).into()));
        assert!(
            (green.shading_normal((Vec2::ZERO).into(), n, n, du, dv) - Vec3::new(0.0, 0.6, 0.8)).length()
                < 1e-6
        );
        let constant = perturbed(Perturbation::BumpMap { height: Rgb::splat(0.7).into(), scale: 5.0 });
        assert!((constant.shading_normal((Vec2::ZERO).into(), n, n, du, dv) - n).length() < 1e-6);
    }

    /// A height ramp `h = a u` over the plane `p = (u, v, 0)` is the surface `z = scale a u`,
    /// whose normal is `(-scale a, 0, 1)` normalised; the bilinear gradient of a 2x2 bitmap is
    /// Mitsuba 3.9's `eval_1_grad` (numbers from `scalar_rgb`).
    #[test]
    fn bump_map_of_a_ramp_and_mitsuba_gradients() {
        let texels = vec![Rgb::splat(0.0), Rgb::splat(1.0), Rgb::splat(0.0), Rgb::splat(3.0)];
        let bitmap =
            |to_uv| Bitmap::new(2, 2, texels.clone(), FilterType::Bilinear, WrapMode::Repeat, to_uv).unwrap();
        let b = bitmap(Affine2::IDENTITY);
        for (uv, want) in [((0.5, 0.5), (4.0, 2.0)), ((0.3, 0.6), (4.8, 0.4)), ((0.9, 0.1), (-3.2, -2.8))] {
            let g = b.eval_1_grad(Vec2::new(uv.0, uv.1));
            assert!((g - Vec2::new(want.0, want.1)).length() < 1e-4, "{uv:?}: {g}");
        }
        let scaled = bitmap(Affine2::from_scale(Vec2::new(2.0, 3.0)));
        assert!((scaled.eval_1_grad(Vec2::new(0.3, 0.6)) - Vec2::new(11.2, -8.4)).length() < 1e-4);
        // At (0.5, 0.5), dh/du = 4 (times scale 0.1): normal (-0.4, -0.2, 1) normalised.
        let bump = perturbed(Perturbation::BumpMap { height: Texture::Bitmap(Arc::new(b)), scale: 0.1 });
        let m = bump.shading_normal((Vec2::new(0.5, 0.5)).into(), Vec3::Z, Vec3::Z, Vec3::X, Vec3::Y);
        assert!((m - Vec3::new(-0.4, -0.2, 1.0).normalize()).length() < 1e-5, "{m}");
        // Seen from a geometric normal on the other side, it turns to that side.
        let m = bump.shading_normal((Vec2::new(0.5, 0.5)).into(), -Vec3::Z, Vec3::Z, Vec3::X, Vec3::Y);
        assert!(m.z < 0.0);
    }
}
