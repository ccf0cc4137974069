//! Emitter plugins `point`, `spot`, `constant`, `envmap`, `directional`, `projector`, and `area`
//! (inside a shape).

use super::document::Document;
use super::params::Params;
use super::LoadError;
use crate::emitter::Emitter;
use crate::envmap::EnvMap;
use crate::texture::Texture;
use glam::{Mat4, Vec3};
use haze_core::Rgb;
use std::sync::Arc;

/// Builds a `point`, `spot` or `constant` emitter (an `area` emitter is built by its shape
/// with [`area_radiance`]). Mitsuba 3 defaults:
/// - `point`: `position` (origin) or the translation of `to_world`; `intensity` 1 (W/sr).
/// - `spot`: `to_world` (shines down local +z); `intensity` 1; `cutoff_angle` 20 degrees;
///   `beam_width` 3/4 of the cutoff; both half-angles in degrees, stored in radians;
///   `texture` (none; a texture or spectrum multiplying the intensity, see
///   [`Emitter::spot_texture`]).
/// - `constant`: `radiance` 1.
/// - `projector`: `irradiance` 1 (a spectrum or texture), `scale` 1, `to_world`, `fov`,
///   `fov_axis`, `focal_length` (see [`crate::projector::Projector`]).
/// - `envmap`: `filename` (required; an OpenEXR or Radiance HDR latitude-longitude image,
///   found through the `<path>` folders like any file), `scale` 1, `to_world` (identity; a
///   rotation, without scaling).
/// - `directional`: `irradiance` 1 (W/m^2, on a surface facing the light); the direction of
///   travel from `direction`, or else local `+z` of `to_world` (either, not both; default
///   `+z`), normalised.
///
/// haze emitters take no medium: a `<medium>` or `<ref>` to one inside an emitter is an
/// "unsupported" error rather than silently ignored.
pub(super) fn build(p: &Params, doc: &Document) -> Result<Emitter, LoadError> {
    if let Some(m) = p.objects(&["medium"]).first() {
        return Err(m.site.error("unsupported: a medium inside <emitter> (haze emitters take no medium)"));
    }
    let emitter = match p.ty() {
        "point" => {
            let position = match (p.point_opt("position")?, p.transform_opt("to_world")?) {
                (Some(_), Some(_)) => {
                    return Err(p.error_at("to_world", "give either 'position' or 'to_world', not both"))
                }
                (Some(pos), None) => pos,
                (None, Some(m)) => m.transform_point3(Vec3::ZERO),
                (None, None) => Vec3::ZERO,
            };
            let intensity = non_negative(p, "intensity")?;
            Emitter::Point { position, intensity }
        }
        "spot" => {
            let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
            // The spot maps directions back to its local frame through the inverse.
            let linear = glam::Mat3::from_mat4(to_world);
            let scale = linear.x_axis.abs().max(linear.y_axis.abs()).max(linear.z_axis.abs()).max_element();
            let inverse_ok =
                linear.determinant().abs() > 1e-9 * scale * scale * scale && to_world.inverse().is_finite();
            if !inverse_ok {
                return Err(p.error_at("to_world", "the spot's to_world is singular (it has no inverse)"));
            }
            let intensity = non_negative(p, "intensity")?;
            let cutoff = p.float("cutoff_angle", 20.0)?;
            if !(cutoff > 0.0 && cutoff < 180.0) {
                return Err(p.error_at(
                    "cutoff_angle",
                    format!("'cutoff_angle' must be in (0, 180) degrees, got {cutoff}"),
                ));
            }
            let beam = p.float("beam_width", cutoff * 0.75)?;
            if beam < 0.0 || beam > cutoff {
                return Err(p.error_at(
                    "beam_width",
                    format!("'beam_width' ({beam}) must lie in [0, cutoff_angle = {cutoff}] degrees"),
                ));
            }
            // Mitsuba 3's `texture` (optional): a spectrum or texture projected through the cone.
            let textured = p.raw("texture").is_some()
                || p.objects(&["texture"]).iter().any(|o| o.name == Some("texture"));
            let texture = if textured {
                Some(super::textures::texture(p, "texture", Rgb::ONE, (0.0, super::MAX_MAGNITUDE))?)
            } else {
                None
            };
            Emitter::spot(to_world, intensity, cutoff.to_radians(), beam.to_radians(), texture)
        }
        "projector" => {
            // Mitsuba 3's `projector`: `irradiance` (1; a spectrum or texture, >= 0), `scale`
            // (1), `to_world`, and the perspective camera's `fov`/`fov_axis`/`focal_length`,
            // whose aspect ratio is the image's (1 for a constant irradiance).
            let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
            if !to_world.inverse().is_finite() || glam::Mat3::from_mat4(to_world).determinant().abs() < 1e-12
            {
                return Err(
                    p.error_at("to_world", "the projector's to_world is singular (it has no inverse)")
                );
            }
            let irradiance =
                super::textures::texture(p, "irradiance", Rgb::ONE, (0.0, super::MAX_MAGNITUDE))?;
            let scale = p.float("scale", 1.0)?;
            if scale < 0.0 {
                return Err(p.error_at("scale", format!("'scale' must be >= 0, got {scale}")));
            }
            let aspect = match &irradiance {
                crate::texture::Texture::Bitmap(b) => b.width as f32 / b.height as f32,
                _ => 1.0,
            };
            let fov_x = super::sensor::fov_x(p, aspect)?;
            Emitter::Projector(Box::new(crate::projector::Projector::new(
                to_world, irradiance, scale, fov_x, aspect,
            )))
        }
        "constant" => Emitter::Constant { radiance: non_negative(p, "radiance")? },
        "envmap" => {
            let filename =
                p.string_opt("filename")?.ok_or_else(|| p.element().error("missing parameter 'filename'"))?;
            let scale = p.float("scale", 1.0)?;
            if scale < 0.0 {
                return Err(p.error_at("scale", format!("'scale' must not be negative, got {scale}")));
            }
            let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
            if super::transform::uniform_scale(&to_world).is_none_or(|s| (s - 1.0).abs() > 1e-3) {
                return Err(p.error_at("to_world", "the envmap's to_world must be a rotation (no scaling)"));
            }
            let path = doc.resolve(filename, p.element());
            let map = EnvMap::load(&path, scale, to_world).map_err(|m| p.error_at("filename", m))?;
            Emitter::EnvMap(Arc::new(map))
        }
        "directional" => {
            let d = match (p.point_opt("direction")?, p.transform_opt("to_world")?) {
                (Some(_), Some(_)) => {
                    return Err(p.error_at("to_world", "give either 'direction' or 'to_world', not both"))
                }
                (Some(d), None) => d,
                (None, Some(m)) => m.transform_vector3(Vec3::Z),
                (None, None) => Vec3::Z,
            };
            let len = d.length();
            if !(len > 1e-20 && len.is_finite()) {
                let name = if p.raw("direction").is_some() { "direction" } else { "to_world" };
                return Err(p.error_at(
                    name,
                    format!("the directional emitter's direction must not be zero, got {d}"),
                ));
            }
            Emitter::Directional { d: d / len, irradiance: non_negative(p, "irradiance")? }
        }
        // Shapes build area emitters; the builder rejects them elsewhere.
        _ => return Err(p.element().error("an area emitter must be nested inside the <shape> that emits")),
    };
    p.finish()?;
    Ok(emitter)
}

/// The `radiance` of an `area` emitter (Mitsuba 3 default 1): a spectrum, or a texture
/// (nested or `<ref>`) looked up at the surface point's uv, every value in
/// `[0, MAX_MAGNITUDE]`.
pub(super) fn area_radiance(p: &Params) -> Result<Texture, LoadError> {
    if let Some(m) = p.objects(&["medium"]).first() {
        return Err(m.site.error("unsupported: a medium inside <emitter> (haze emitters take no medium)"));
    }
    super::textures::reject_other_textures(p, &["radiance"])?;
    let textured = p.objects(&["texture"]).iter().any(|o| o.name == Some("radiance"));
    let radiance = if textured {
        super::textures::texture(p, "radiance", Rgb::ONE, (0.0, super::MAX_MAGNITUDE))?
    } else {
        Texture::Constant(non_negative(p, "radiance")?)
    };
    p.finish()?;
    Ok(radiance)
}

/// A spectrum parameter defaulting to 1 that must not be negative (nor so large that the
/// estimates built on it overflow).
fn non_negative(p: &Params, name: &str) -> Result<Rgb, LoadError> {
    let v = p.spectrum(name, Rgb::ONE)?;
    if v.min_component() < 0.0 {
        return Err(p.error_at(name, format!("'{name}' must not be negative")));
    }
    if v.max_component() > super::MAX_MAGNITUDE {
        return Err(p.error_at(
            name,
            format!("'{name}' must be at most {:e}, got {:e}", super::MAX_MAGNITUDE, v.max_component()),
        ));
    }
    Ok(v)
}
