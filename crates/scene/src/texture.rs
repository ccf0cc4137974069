//! Reflectance textures (Mitsuba 3 plugins: a constant spectrum, `checkerboard`, `bitmap`,
//! `mesh_attribute`).
//!
//! A texture maps a hit ([`TexPoint`]: its surface parameterisation `uv`, and its triangle and
//! barycentrics for `mesh_attribute`) to an RGB value. Only the reflectance-like parameters of
//! the BSDFs take one (`diffuse.reflectance`, `plastic.diffuse_reflectance`, ...).

use crate::bitmap::Bitmap;
use crate::mesh_attribute::MeshAttribute;
pub use crate::mesh_attribute::TexPoint;
use glam::{Affine2, Mat2, Vec2};
use haze_core::Rgb;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same value everywhere (a `<rgb>`, `<spectrum>` or `<float>` parameter).
    Constant(Rgb),
    /// Mitsuba 3's `checkerboard`: with `(s, t) = to_uv(uv)`, `color0` where the fractional
    /// parts of `s` and `t` are both above 1/2 or both at most 1/2, else `color1`. The squares
    /// have side 1/2 in the transformed coordinates.
    Checkerboard { color0: Rgb, color1: Rgb, to_uv: Affine2 },
    /// Mitsuba 3's `bitmap`: an image (shared by every BSDF that refers to it).
    Bitmap(Arc<Bitmap>),
    /// Mitsuba 3's `mesh_attribute`: a vertex or face attribute of the one mesh this texture
    /// is bound to, times its `scale`.
    MeshAttribute(Arc<MeshAttribute>),
}

impl From<Rgb> for Texture {
    fn from(c: Rgb) -> Self {
        Texture::Constant(c)
    }
}

impl Texture {
    /// The value at `at` (a [`TexPoint`], or the surface coordinates `uv` alone).
    #[inline]
    pub fn eval(&self, at: impl Into<TexPoint>) -> Rgb {
        let at = at.into();
        let uv = at.uv;
        match self {
            Texture::Constant(c) => *c,
            Texture::Checkerboard { color0, color1, to_uv } => {
                let p = to_uv.transform_point2(uv);
                let upper = |x: f32| x - x.floor() > 0.5;
                if upper(p.x) == upper(p.y) {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::Bitmap(b) => b.eval(uv),
            Texture::MeshAttribute(a) => a.eval(at),
        }
    }

    /// The value at `uv` as one number (Mitsuba's `Texture::eval_1`): the luminance of the
    /// RGB value ([`Rgb::luminance`], Mitsuba's weights), so a grey texture gives
    /// its grey level.
    ///
    /// A `checkerboard` gives the *other* square's colour here: Mitsuba 3.9.1's
    /// `checkerboard.cpp` picks `color0` where the fractional parts are on the same side of 1/2
    /// in `eval` but on different sides in `eval_1`, so every one-number use (a roughness, a
    /// mask's opacity, a blend weight) sees the pattern shifted by one square. haze does the
    /// same so that scenes render as in Mitsuba (a textured-roughness scene was 27% off before).
    ///
    /// A three-channel `mesh_attribute` gives 0 ([`MeshAttribute::eval_1`], as Mitsuba 3.9.1).
    #[inline]
    pub fn eval_1(&self, at: impl Into<TexPoint>) -> f32 {
        let at = at.into();
        let uv = at.uv;
        match self {
            Texture::Checkerboard { color0, color1, to_uv } => {
                let p = to_uv.transform_point2(uv);
                let upper = |x: f32| x - x.floor() > 0.5;
                if upper(p.x) != upper(p.y) {
                    color0.luminance()
                } else {
                    color1.luminance()
                }
            }
            Texture::MeshAttribute(a) => a.eval_1(at),
            _ => self.eval(at).luminance(),
        }
    }

    /// The gradient of [`Self::eval_1`] with respect to `uv` (Mitsuba's `eval_1_grad`): zero
    /// for a constant and for the piecewise constant `checkerboard` (as Mitsuba's), the
    /// bilinear interpolant's for a bitmap ([`Bitmap::eval_1_grad`]). Zero for a mesh
    /// attribute too (Mitsuba 3's `mesh_attribute` has no `eval_1_grad`: a bump map of one is
    /// an error there).
    pub fn eval_1_grad(&self, at: impl Into<TexPoint>) -> Vec2 {
        match self {
            Texture::Constant(_) | Texture::Checkerboard { .. } | Texture::MeshAttribute(_) => Vec2::ZERO,
            Texture::Bitmap(b) => b.eval_1_grad(at.into().uv),
        }
    }

    /// The average over the texture's domain (Mitsuba's `Texture::mean`), used for sampling
    /// weights that must not depend on the hit.
    pub fn mean(&self) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checkerboard { color0, color1, .. } => (*color0 + *color1) * 0.5,
            Texture::Bitmap(b) => b.mean(),
            Texture::MeshAttribute(a) => a.mean(),
        }
    }

    /// True if the texture is zero everywhere.
    pub fn is_black(&self) -> bool {
        match self {
            Texture::Constant(c) => c.is_black(),
            Texture::Checkerboard { color0, color1, .. } => color0.is_black() && color1.is_black(),
            Texture::Bitmap(b) => b.range() == (0.0, 0.0),
            Texture::MeshAttribute(a) => a.range() == (0.0, 0.0),
        }
    }

    /// Smallest and largest channel value the texture takes anywhere (for validation).
    pub fn range(&self) -> (f32, f32) {
        match self {
            Texture::Constant(c) => (c.min_component(), c.max_component()),
            Texture::Checkerboard { color0, color1, .. } => (
                color0.min_component().min(color1.min_component()),
                color0.max_component().max(color1.max_component()),
            ),
            Texture::Bitmap(b) => b.range(),
            Texture::MeshAttribute(a) => a.range(),
        }
    }
}

/// The 2D affine part of a Mitsuba `to_uv` 4x4 transform: the upper-left 2x2 block and the
/// first two translation entries (Mitsuba 3 `Transform4f::extract`).
pub fn affine2_from_mat4(m: glam::Mat4) -> Affine2 {
    Affine2::from_mat2_translation(
        Mat2::from_cols(m.x_axis.truncate().truncate(), m.y_axis.truncate().truncate()),
        m.w_axis.truncate().truncate(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_pattern_and_mean() {
        let t = Texture::Checkerboard {
            color0: Rgb::splat(0.4),
            color1: Rgb::splat(0.2),
            to_uv: Affine2::IDENTITY,
        };
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Rgb::splat(0.4));
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Rgb::splat(0.4));
        // Mitsuba 3.9.1's eval_1 reads the other colour (see `Texture::eval_1`).
        assert_eq!(t.eval_1(Vec2::new(0.25, 0.25)), Rgb::splat(0.2).luminance());
        assert_eq!(t.eval_1(Vec2::new(0.25, 0.75)), Rgb::splat(0.4).luminance());
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Rgb::splat(0.2));
        assert_eq!(t.eval(Vec2::new(-0.25, 0.25)), Rgb::splat(0.2), "periodic, also for negative uv");
        assert!((t.mean()[0] - 0.3).abs() < 1e-6);
        let scaled = Texture::Checkerboard {
            color0: Rgb::splat(0.4),
            color1: Rgb::splat(0.2),
            to_uv: affine2_from_mat4(glam::Mat4::from_scale(glam::Vec3::splat(16.0))),
        };
        assert_eq!(scaled.eval(Vec2::new(0.75 / 16.0, 0.25 / 16.0)), Rgb::splat(0.2));
        assert_eq!(scaled.eval(Vec2::new(0.75 / 16.0, 0.75 / 16.0)), Rgb::splat(0.4));
    }
}
