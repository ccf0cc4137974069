//! Texture plugin `checkerboard`, and reading a reflectance parameter that may be a spectrum
//! or a `<texture>` (nested or referenced), as Mitsuba 3's `props.texture(name)` does.

use super::params::Params;
use super::LoadError;
use crate::texture::{affine2_from_mat4, Texture};
use glam::Mat4;
use haze_core::Rgb;

/// Builds a `<texture>`.
/// - `checkerboard`: `color0` (Mitsuba 3 default 0.4), `color1` (0.2), `to_uv` (identity),
///   applied to the surface `uv` before the pattern.
pub(super) fn build(p: &Params) -> Result<Texture, LoadError> {
    // `checkerboard` is the only texture type in the plugin table; `Params::new` rejects others.
    let color0 = p.spectrum("color0", Rgb::splat(0.4))?;
    let color1 = p.spectrum("color1", Rgb::splat(0.2))?;
    let to_uv = p.transform_opt("to_uv")?.unwrap_or(Mat4::IDENTITY);
    if !to_uv.is_finite() {
        return Err(p.error_at("to_uv", "'to_uv' must be finite"));
    }
    p.finish()?;
    Ok(Texture::Checkerboard { color0, color1, to_uv: affine2_from_mat4(to_uv) })
}

/// The parameter `name` of plugin `p`: a spectrum (`<rgb>`, `<spectrum>`, `<float>`), a
/// `<texture name="..">` nested in `p`, or a `<ref name=".." id=".."/>` to one; `default` if
/// none is given. Every value it can take must lie in `[lo, hi]`.
pub(super) fn texture(
    p: &Params,
    name: &str,
    default: Rgb,
    (lo, hi): (f32, f32),
) -> Result<Texture, LoadError> {
    let objects: Vec<_> = p.objects(&["texture"]).into_iter().filter(|o| o.name == Some(name)).collect();
    let spectrum = p.spectrum_opt(name)?;
    let tex = match (objects.as_slice(), spectrum) {
        ([], None) => Texture::Constant(default),
        ([], Some(c)) => Texture::Constant(c),
        ([o], None) => build(&p.nested(o.target)?)?,
        ([o, ..], _) => return Err(o.site.error(format!("'{name}' is given more than once"))),
    };
    let (min, max) = tex.range();
    if min < lo || max > hi {
        return Err(p.error_at(name, format!("'{name}' must lie in [{lo}, {hi}] in every channel")));
    }
    Ok(tex)
}

/// Fails on a `<texture>` of `p` whose `name` is not one of `accepted` (a texture parameter
/// the plugin does not have, or a texture without a name).
pub(super) fn reject_other_textures(p: &Params, accepted: &[&str]) -> Result<(), LoadError> {
    for o in p.objects(&["texture"]) {
        if !o.name.is_some_and(|n| accepted.contains(&n)) {
            let what =
                o.name.map_or("a <texture> without a name".to_string(), |n| format!("a texture '{n}'"));
            let takes = if accepted.is_empty() { "none".to_string() } else { accepted.join(", ") };
            return Err(o.site.error(format!(
                "{} does not take {what} (texture parameters: {takes})",
                p.element().describe()
            )));
        }
    }
    Ok(())
}
