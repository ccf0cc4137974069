//! The roughness of a microfacet BSDF as Mitsuba 3's `roughconductor`, `roughdielectric` and
//! `pplastic` take it: `alpha`, or `alpha_u` and `alpha_v`, each a number or a texture read as
//! one number (`Texture::eval_1`) at the hit's `uv`.

use super::microfacet::Microfacet;
use crate::mesh_attribute::TexPoint;
use crate::texture::Texture;

#[derive(Clone, Debug, PartialEq)]
pub enum Roughness {
    /// The same distribution everywhere (the common case: no texture lookups).
    Fixed(Microfacet),
    /// `alpha_u` and `alpha_v` looked up per hit; `base` carries the distribution type and the
    /// sampling method (its `alpha`s are unused).
    Textured { base: Microfacet, alpha_u: Texture, alpha_v: Texture },
}

impl From<Microfacet> for Roughness {
    fn from(d: Microfacet) -> Self {
        Roughness::Fixed(d)
    }
}

impl Roughness {
    /// The distribution at surface coordinates `uv` (alphas below 1e-4 clamped, as
    /// [`Microfacet::anisotropic`]; Mitsuba 3 clamps the same way, so a texture value of 0 is a
    /// nearly smooth surface).
    #[inline]
    pub fn at(&self, uv: TexPoint) -> Microfacet {
        match self {
            Roughness::Fixed(d) => *d,
            Roughness::Textured { base, alpha_u, alpha_v } => {
                Microfacet::anisotropic(base.ty, alpha_u.eval_1(uv), alpha_v.eval_1(uv), base.sample_visible)
            }
        }
    }

    /// The distribution if it is the same everywhere.
    pub fn fixed(&self) -> Option<&Microfacet> {
        match self {
            Roughness::Fixed(d) => Some(d),
            Roughness::Textured { .. } => None,
        }
    }

    /// Whether visible normals are sampled.
    pub fn sample_visible(&self) -> bool {
        match self {
            Roughness::Fixed(d) | Roughness::Textured { base: d, .. } => d.sample_visible,
        }
    }

    /// True if the distribution may differ along `dp/du` and `dp/dv` somewhere, so that the
    /// shading frame must follow the surface's `dp/du` (as Mitsuba 3's always does).
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Roughness::Fixed(d) => !d.is_isotropic(),
            Roughness::Textured { alpha_u, alpha_v, .. } => alpha_u != alpha_v,
        }
    }
}
