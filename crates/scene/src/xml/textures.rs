//! Texture plugins `rawconstant`, `checkerboard`, `bitmap` and `mesh_attribute`, and reading a
//! reflectance parameter that may be a spectrum or a `<texture>` (nested or referenced), as
//! Mitsuba 3's `props.texture(name)` does.

use super::document::MeshScope;
use super::params::Params;
use super::LoadError;
use crate::bitmap::{Bitmap, FilterType, WrapMode};
use crate::mesh_attribute::MeshAttribute;
use crate::texture::{affine2_from_mat4, Texture};
use glam::Mat4;
use haze_core::Rgb;
use std::sync::Arc;

/// Builds a `<texture>`.
/// - `checkerboard`: `color0` (Mitsuba 3 default 0.4), `color1` (0.2), `to_uv` (identity),
///   applied to the surface `uv` before the pattern.
/// - `bitmap`: `filename` (required: PNG, JPEG, OpenEXR or Radiance HDR), `filter_type`
///   (`bilinear`; or `nearest`), `wrap_mode` (`repeat`; or `mirror`, `clamp`), `raw` (false:
///   8- and 16-bit images are sRGB-decoded), `to_uv` (identity); `format` and `accel` are
///   storage and GPU choices of Mitsuba 3's, checked and ignored. See [`crate::bitmap`].
/// - `rawconstant`: `value` (required), a `<float>` or a `<vector>`, returned as it is (no
///   spectral conversion, no clamping: Mitsuba 3 uses it for normal maps and other non-colours).
/// - `mesh_attribute`: `name` (required, `vertex_...` or `face_...`), `scale` (1): see
///   [`mesh_attribute`].
pub(super) fn build(p: &Params) -> Result<Texture, LoadError> {
    if p.ty() == "mesh_attribute" {
        return mesh_attribute(p);
    }
    if p.ty() == "rawconstant" {
        let value = match p.raw("value").map(|el| el.tag.as_str()) {
            None => return Err(p.element().error("a rawconstant needs 'value' (a <float> or a <vector>)")),
            Some("float" | "integer") => Rgb::splat(p.float("value", 0.0)?),
            Some("vector" | "point") => {
                let v = p.point_opt("value")?.unwrap_or_default();
                Rgb::new(v.x, v.y, v.z)
            }
            Some(tag) => {
                return Err(p.error_at(
                    "value",
                    format!("a rawconstant's 'value' is a <float> or a <vector> (3 numbers), not a <{tag}>"),
                ))
            }
        };
        p.finish()?;
        return Ok(Texture::Constant(value));
    }
    let to_uv = p.transform_opt("to_uv")?.unwrap_or(Mat4::IDENTITY);
    if !to_uv.is_finite() {
        return Err(p.error_at("to_uv", "'to_uv' must be finite"));
    }
    let to_uv = affine2_from_mat4(to_uv);
    if p.ty() == "bitmap" {
        return bitmap(p, to_uv);
    }
    let color0 = p.spectrum("color0", Rgb::splat(0.4))?;
    let color1 = p.spectrum("color1", Rgb::splat(0.2))?;
    p.finish()?;
    Ok(Texture::Checkerboard { color0, color1, to_uv })
}

fn bitmap(p: &Params, to_uv: glam::Affine2) -> Result<Texture, LoadError> {
    let filename =
        p.string_opt("filename")?.ok_or_else(|| p.element().error("missing parameter 'filename'"))?;
    let choice = |name: &str, default: &str, known: &str| -> Result<String, LoadError> {
        let v = p.string_opt(name)?.unwrap_or(default);
        if !known.split(", ").any(|k| k == v) {
            return Err(p.error_at(name, format!("unknown {name} '{v}' (supported: {known})")));
        }
        Ok(v.to_string())
    };
    let filter = FilterType::from_name(&choice("filter_type", "bilinear", "bilinear, nearest")?);
    let wrap = WrapMode::from_name(&choice("wrap_mode", "repeat", "repeat, mirror, clamp")?);
    choice("format", "auto", "auto, variant, float16, uint8")?;
    p.bool("accel", true)?;
    let raw = p.bool("raw", false)?;
    p.finish()?;
    let (Some(filter), Some(wrap)) = (filter, wrap) else {
        return Err(p.element().error("internal: filter or wrap mode without a name"));
    };
    if let Some(b) = p.doc().bitmaps.borrow().get(&p.element().uid) {
        return Ok(Texture::Bitmap(b.clone()));
    }
    let path = p.doc().resolve(filename, p.element());
    let b = Bitmap::load(&path, raw, filter, wrap, to_uv).map_err(|m| p.error_at("filename", m))?;
    let b = Arc::new(b);
    p.doc().bitmaps.borrow_mut().insert(p.element().uid, b.clone());
    Ok(Texture::Bitmap(b))
}

/// `mesh_attribute`: the attribute `name` of the mesh whose BSDF holds the texture, times
/// `scale` (Mitsuba 3's `eval_attribute`). Errors name the texture: not in a shape's BSDF, a
/// shape that is not a mesh, a name the mesh lacks (listing those it has), an attribute of other
/// than 1 or 3 channels.
fn mesh_attribute(p: &Params) -> Result<Texture, LoadError> {
    let name = p.string_opt("name")?.ok_or_else(|| p.element().error("a mesh_attribute needs 'name'"))?;
    if !(name.starts_with("vertex_") || name.starts_with("face_")) {
        return Err(p.error_at(
            "name",
            format!("a mesh attribute's name starts with \"vertex_\" or \"face_\", not '{name}'"),
        ));
    }
    let scale = p.float("scale", 1.0)?;
    if !scale.is_finite() {
        return Err(p.error_at("scale", "'scale' must be finite"));
    }
    p.finish()?;
    let scope = p.doc().mesh_scope.borrow();
    let (shape, mesh) = match &*scope {
        MeshScope::Declaration => return Ok(Texture::Constant(Rgb::ZERO)),
        MeshScope::Outside => {
            return Err(p.element().error(format!(
                "mesh_attribute '{name}' reads the mesh whose BSDF holds it; here it is not in a shape's BSDF"
            )))
        }
        MeshScope::Shape { shape, mesh } => (shape, mesh),
    };
    let Some(mesh) = mesh else {
        return Err(p.element().error(format!(
            "mesh_attribute '{name}' reads an attribute of a mesh, and {shape} is not a mesh (a ply file)"
        )));
    };
    let Some(attr) = mesh.attributes.iter().find(|a| a.name == name) else {
        let has = if mesh.kind != "ply" {
            format!("haze reads attributes from PLY files only, and this is a '{}' mesh", mesh.kind)
        } else if mesh.attributes.is_empty() {
            "its file has no other vertex or face properties".to_string()
        } else {
            let names: Vec<&str> = mesh.attributes.iter().map(|a| a.name.as_str()).collect();
            format!("it has {}", names.join(", "))
        };
        return Err(p.element().error(format!("{shape} has no mesh attribute '{name}' ({has})")));
    };
    let bound = MeshAttribute::bind(attr, scale, &mesh.indices, mesh.vertex_count).ok_or_else(|| {
        p.element().error(format!(
            "mesh attribute '{name}' of {shape} has {} channels; mesh_attribute reads 1 or 3 \
             (Mitsuba 3 evaluates others to 0)",
            attr.dim
        ))
    })?;
    Ok(Texture::MeshAttribute(Arc::new(bound)))
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
