//! `<sensor>` (`perspective`, `thinlens`, `orthographic`) with its `<film type="hdrfilm">` (and `<rfilter>`),
//! `<sampler>` (Mitsuba 3's `independent`, `stratified`, `multijitter`, `orthogonal`, `ldsampler`)
//! and optional medium.

use super::context::Builder;
use super::document::Element;
use super::params::Params;
use super::transform::uniform_scale;
use super::values::parse_float;
use super::LoadError;
use crate::camera::{Camera, PixelFilter, Projection};
use glam::Mat4;
use haze_core::{SamplerKind, SamplerSpec};

/// Mitsuba 3's `hdrfilm` default resolution.
const DEFAULT_WIDTH: u32 = 768;
const DEFAULT_HEIGHT: u32 = 576;
/// Larger films are surely a typo (and would exhaust memory).
const MAX_RESOLUTION: i32 = 1 << 16;

/// The camera and the sampler of `<sensor>` element `el` (no `<sampler>`: `independent` with
/// Mitsuba 3's 4 samples).
///
/// Every sensor (Mitsuba 3 defaults): `near_clip` (0.01), `far_clip` (10000), `focus_distance`
/// (`far_clip`), `to_world` (identity).
/// - `perspective`: `fov` in degrees with `fov_axis` (`x`), or `focal_length` (`"50mm"`, on a
///   36x24 mm film, measured along the diagonal) when no `fov` is given; `to_world` must not
///   scale; `focus_distance` has no effect on a pinhole.
/// - `thinlens`: the same plus `aperture_radius` (required, as in Mitsuba 3; >= 0), in focus at
///   camera-space depth `focus_distance` (> 0).
/// - `orthographic`: no field of view: the film is the rectangle `[-1, 1] x [-1/aspect,
///   1/aspect]` of the camera's near plane, sized by `to_world`'s scale (which must keep it
///   non-degenerate); `focus_distance` is accepted and has no effect (as in Mitsuba 3).
pub(super) fn build<'a>(b: &mut Builder<'a>, el: &'a Element) -> Result<(Camera, SamplerSpec), LoadError> {
    let p = b.params(el)?;
    let (width, height, filter) = match single(&p, "film")? {
        Some(film_el) => film(&p.nested(film_el)?)?,
        None => (DEFAULT_WIDTH, DEFAULT_HEIGHT, PixelFilter::MITSUBA_DEFAULT),
    };
    let sampler = match single(&p, "sampler")? {
        Some(sampler_el) => sampler(&p.nested(sampler_el)?)?,
        None => SamplerSpec::default(),
    };
    let medium = match single(&p, "medium")? {
        Some(medium_el) => Some(b.medium(medium_el)?),
        None => None,
    };
    let orthographic = p.ty() == "orthographic";
    let fov_x_deg = if orthographic { 0.0 } else { fov_x(&p, width as f32 / height as f32)? };
    let near_clip = p.float("near_clip", Camera::DEFAULT_NEAR_CLIP)?;
    if near_clip <= 0.0 {
        return Err(p.error_at("near_clip", format!("'near_clip' must be > 0, got {near_clip}")));
    }
    let far_clip = p.float("far_clip", Camera::DEFAULT_FAR_CLIP)?;
    if far_clip <= near_clip {
        return Err(p.error_at(
            "far_clip",
            format!("'far_clip' ({far_clip}) must be larger than 'near_clip' ({near_clip})"),
        ));
    }
    // Mitsuba 3 reads `focus_distance` (default `far_clip`) in every projective camera and
    // uses it only in `thinlens`: a pinhole is in focus everywhere.
    let focus_distance = p.float("focus_distance", far_clip)?;
    let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
    let projection = match p.ty() {
        "perspective" => Projection::Pinhole,
        "thinlens" => {
            let aperture_radius = p.float_opt("aperture_radius")?.ok_or_else(|| {
                p.element().error("a thinlens sensor needs 'aperture_radius' (Mitsuba 3 has no default)")
            })?;
            if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
                return Err(p.error_at(
                    "aperture_radius",
                    format!("'aperture_radius' must be >= 0, got {aperture_radius}"),
                ));
            }
            if !(focus_distance > 0.0 && focus_distance.is_finite()) {
                return Err(p.error_at(
                    "focus_distance",
                    format!("'focus_distance' must be > 0, got {focus_distance}"),
                ));
            }
            Projection::ThinLens { aperture_radius, focus_distance }
        }
        "orthographic" => Projection::Orthographic,
        other => return Err(p.element().error(format!("unsupported sensor type '{other}'"))),
    };
    if orthographic {
        // Scale sizes the film; a singular transform would give every ray the same origin or a
        // zero direction.
        let det = to_world.determinant();
        if !(det.abs() > 1e-12 && det.is_finite()) {
            return Err(p.error_at("to_world", "the orthographic sensor's to_world must be invertible"));
        }
    } else if uniform_scale(&to_world).is_none_or(|s| (s - 1.0).abs() > 1e-3) {
        // As Mitsuba 3: rays would be mis-scaled (and the clip distances wrong).
        return Err(p.error_at(
            "to_world",
            format!(
                "the {} sensor's to_world must not scale (rotations, mirroring and translations only)",
                p.ty()
            ),
        ));
    }
    p.finish()?;
    let camera =
        Camera { to_world, projection, fov_x_deg, near_clip, far_clip, medium, width, height, filter };
    Ok((camera, sampler))
}

/// The one nested object of `tag`, if any.
fn single<'a>(p: &Params<'a>, tag: &str) -> Result<Option<&'a Element>, LoadError> {
    let objects = p.objects(&[tag]);
    if let Some(second) = objects.get(1) {
        return Err(second.site.error(format!(
            "{} takes one <{tag}>; another is at line {}",
            p.element().describe(),
            objects[0].site.line
        )));
    }
    Ok(objects.first().map(|o| o.target))
}

/// Which extent of the film `fov` spans (Mitsuba 3's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum FovAxis {
    X,
    Y,
    Diagonal,
    /// The smaller of the two image sides.
    Smaller,
    /// The larger of the two image sides.
    Larger,
}

impl FovAxis {
    fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "x" => Some(FovAxis::X),
            "y" => Some(FovAxis::Y),
            "diagonal" => Some(FovAxis::Diagonal),
            "smaller" => Some(FovAxis::Smaller),
            "larger" => Some(FovAxis::Larger),
            _ => None,
        }
    }
}

/// Converts a full field of view `fov_deg` along `axis` into the horizontal one, for a film of
/// `aspect = width / height`; Mitsuba 3's `perspective` does the same. With `t = tan(fov/2)`:
/// `y`: `tan(x/2) = t * aspect`; `diagonal`: `tan(x/2) = t / sqrt(1 + 1/aspect^2)`.
pub(super) fn fov_x_from(fov_deg: f32, axis: FovAxis, aspect: f32) -> f32 {
    let t = (0.5 * fov_deg.to_radians()).tan();
    let from_y = || 2.0 * (t * aspect).atan().to_degrees();
    match axis {
        FovAxis::X => fov_deg,
        FovAxis::Y => from_y(),
        FovAxis::Diagonal => 2.0 * (t / (1.0 + 1.0 / (aspect * aspect)).sqrt()).atan().to_degrees(),
        FovAxis::Smaller if aspect > 1.0 => from_y(),
        FovAxis::Larger if aspect <= 1.0 => from_y(),
        FovAxis::Smaller | FovAxis::Larger => fov_deg,
    }
}

/// The diagonal field of view of a lens of focal length `f_mm` on a 36x24 mm film:
/// `2 atan(sqrt(36^2 + 24^2) / (2 f))`.
pub(super) fn diagonal_fov_of_focal_length(f_mm: f32) -> f32 {
    2.0 * ((36.0f32 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * f_mm)).atan().to_degrees()
}

/// The horizontal field of view in degrees from `fov` (with `fov_axis`) or `focal_length`
/// (`"50mm"` by default), for an image of the given aspect ratio (width over height): the
/// perspective camera's and the projector's (Mitsuba 3's `parse_fov`).
pub(super) fn fov_x(p: &Params, aspect: f32) -> Result<f32, LoadError> {
    let fov = p.float_opt("fov")?;
    let focal = p.string_opt("focal_length")?;
    if fov.is_some() && focal.is_some() {
        return Err(p.error_at("focal_length", "give either 'fov' or 'focal_length', not both"));
    }
    if let Some(fov) = fov {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(p.error_at("fov", format!("'fov' must be in (0, 180) degrees, got {fov}")));
        }
        let axis = match p.string_opt("fov_axis")? {
            None => FovAxis::X,
            Some(s) => FovAxis::parse(s).ok_or_else(|| {
                p.error_at("fov_axis", format!("unknown fov_axis '{s}' (x, y, diagonal, smaller or larger)"))
            })?,
        };
        return Ok(fov_x_from(fov, axis, aspect));
    }
    let text = focal.unwrap_or("50mm");
    let number = text.strip_suffix("mm").unwrap_or(text);
    let f_mm = parse_float(number).ok().filter(|f| *f > 0.0 && f.is_finite());
    let Some(f_mm) = f_mm else {
        return Err(p.error_at(
            "focal_length",
            format!("cannot parse focal length '{text}' (expected e.g. \"50mm\")"),
        ));
    };
    Ok(fov_x_from(diagonal_fov_of_focal_length(f_mm), FovAxis::Diagonal, aspect))
}

/// `hdrfilm`: `width` and `height` (768x576), `pixel_format` `rgb`/`rgba`,
/// `component_format` `float16`/`float32`, `file_format` `openexr`; haze writes what its
/// command line asks for, so the last three are only checked. `banner` (a boolean) is a
/// Mitsuba 0.x parameter that Mitsuba 3's `hdrfilm` marks as read and ignores ("no banner in
/// Mitsuba 3"); haze does the same. The nested `<rfilter>` (default `gaussian`, as Mitsuba 3)
/// is read by [`rfilter`].
fn film(p: &Params) -> Result<(u32, u32, PixelFilter), LoadError> {
    let side = |name: &str, default: u32| -> Result<u32, LoadError> {
        let v = p.int(name, default as i32)?;
        if !(1..=MAX_RESOLUTION).contains(&v) {
            return Err(p.error_at(name, format!("'{name}' must be in 1..={MAX_RESOLUTION}, got {v}")));
        }
        Ok(v as u32)
    };
    let width = side("width", DEFAULT_WIDTH)?;
    let height = side("height", DEFAULT_HEIGHT)?;
    for (name, accepted) in [
        ("pixel_format", &["rgb", "rgba"][..]),
        ("component_format", &["float16", "float32"][..]),
        ("file_format", &["openexr", "exr"][..]),
    ] {
        if let Some(v) = p.string_opt(name)? {
            if !accepted.contains(&v.to_ascii_lowercase().as_str()) {
                return Err(p.error_at(
                    name,
                    format!("unsupported {name} '{v}' (supported: {})", accepted.join(", ")),
                ));
            }
        }
    }
    // Checked to be a boolean, then ignored, as Mitsuba 3 does.
    p.bool("banner", false)?;
    let filter = match single(p, "rfilter")? {
        Some(el) => rfilter(&p.nested(el)?)?,
        None => PixelFilter::MITSUBA_DEFAULT,
    };
    p.finish()?;
    Ok((width, height, filter))
}

/// `box`; `tent` with `radius` (Mitsuba 3 default 1 pixel); `gaussian` with `stddev` (0.5
/// pixels; the support is 4 standard deviations). See [`PixelFilter`] for how haze applies them.
fn rfilter(p: &Params) -> Result<PixelFilter, LoadError> {
    let positive = |name: &str, default: f32| -> Result<f32, LoadError> {
        let v = p.float(name, default)?;
        if v <= 0.0 || v > 16.0 {
            return Err(p.error_at(name, format!("'{name}' must be in (0, 16] pixels, got {v}")));
        }
        Ok(v)
    };
    let filter = match p.ty() {
        "box" => PixelFilter::Box,
        "tent" => PixelFilter::Tent { radius: positive("radius", 1.0)? },
        "gaussian" => PixelFilter::Gaussian { stddev: positive("stddev", 0.5)? },
        other => return Err(p.element().error(format!("unsupported rfilter type '{other}'"))),
    };
    p.finish()?;
    Ok(filter)
}

/// Every sampler: `sample_count` (4, > 0; rounded as Mitsuba 3 rounds it for the type, e.g. up to
/// a square for `stratified`, and rendered so), `seed` (accepted and ignored: haze seeds per
/// pixel from the render's seed); `stratified`, `multijitter` and `orthogonal` also `jitter`
/// (true), `orthogonal` `strength` (2; the only strength haze renders).
fn sampler(p: &Params) -> Result<SamplerSpec, LoadError> {
    let kind = SamplerKind::from_name(p.ty())
        .ok_or_else(|| p.element().error(format!("unsupported sampler type '{}'", p.ty())))?;
    let spp = p.int("sample_count", haze_core::sampler::DEFAULT_SAMPLE_COUNT as i32)?;
    if spp <= 0 {
        return Err(p.error_at("sample_count", format!("'sample_count' must be > 0, got {spp}")));
    }
    p.int("seed", 0)?;
    let mut spec = SamplerSpec::new(kind, spp as u32);
    if matches!(kind, SamplerKind::Stratified | SamplerKind::Multijitter | SamplerKind::Orthogonal) {
        spec.jitter = p.bool("jitter", true)?;
    }
    if kind == SamplerKind::Orthogonal {
        // Mitsuba 3 builds strength-t arrays by Bush's construction but still draws p^2 of their
        // p^t rows, which are not stratified in any projection; its docs advise against it.
        let strength = p.int("strength", 2)?;
        if strength != 2 {
            return Err(p.error_at(
                "strength",
                format!("orthogonal 'strength' {strength} is not supported (haze renders strength 2)"),
            ));
        }
    }
    p.finish()?;
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-3
    }

    #[test]
    fn default_focal_length_on_a_square_film() {
        // 50mm on the 36x24 diagonal, converted as fov_axis=diagonal for a 48x48 film.
        let x = fov_x_from(diagonal_fov_of_focal_length(50.0), FovAxis::Diagonal, 1.0);
        assert!(close(x, 34.0221), "{x}");
    }

    #[test]
    fn fov_axis_conversions() {
        let aspect = 2.0;
        assert_eq!(fov_x_from(40.0, FovAxis::X, aspect), 40.0);
        // y: tan(x/2) = tan(20 deg) * 2.
        let y = fov_x_from(40.0, FovAxis::Y, aspect);
        assert!(close(y, 2.0 * (20f32.to_radians().tan() * 2.0).atan().to_degrees()));
        assert!(close(fov_x_from(40.0, FovAxis::Smaller, aspect), y));
        assert_eq!(fov_x_from(40.0, FovAxis::Larger, aspect), 40.0);
        // A portrait film: the smaller side is x.
        assert_eq!(fov_x_from(40.0, FovAxis::Smaller, 0.5), 40.0);
        // Diagonal of a square film: tan(x/2) = tan(d/2) / sqrt(2).
        let d = fov_x_from(90.0, FovAxis::Diagonal, 1.0);
        assert!(close(d, 2.0 * (1.0 / 2f32.sqrt()).atan().to_degrees()));
        // y then back: the vertical fov of the result is the input.
        let back = 2.0 * ((0.5 * y.to_radians()).tan() / aspect).atan().to_degrees();
        assert!(close(back, 40.0));
    }

    #[test]
    fn focal_length_50mm_diagonal() {
        assert!(close(diagonal_fov_of_focal_length(50.0), 46.7930));
    }
}
