//! Medium plugins `homogeneous` and `heterogeneous`, volume plugins `gridvolume` and
//! `constvolume`, and phase function plugins `isotropic` and `hg`.

use super::document::Document;
use super::params::Params;
use super::LoadError;
use crate::hetero::{Heterogeneous, MajorantGrid, MAJORANT_RES};
use crate::medium::Medium;
use crate::vdb::{read_vdb, VdbError};
use crate::volume::{Filter, Grid, Volume, VolumeData, Wrap};
use glam::{Affine3A, Mat4};
use haze_core::{Phase, Rgb};
use std::path::Path;
use std::sync::Arc;

/// Builds a `<medium>` named `name`.
pub(super) fn build(p: &Params, name: String, doc: &Document) -> Result<Medium, LoadError> {
    match p.ty() {
        "heterogeneous" => heterogeneous(p, name, doc),
        _ => homogeneous(p, name),
    }
}

/// Builds a `homogeneous` medium named `name`. Parameters (Mitsuba 3 defaults): `sigma_t`
/// (1, per unit length, >= 0), `albedo` (0.75, in [0, 1]), `scale` (1, >= 0, multiplies
/// `sigma_t`), one nested `<phase>` (isotropic), `sample_emitters` (true; haze always samples
/// emitters, so `false` is unsupported). `sigma_t` and `albedo` are RGB, or a float for grey.
fn homogeneous(p: &Params, name: String) -> Result<Medium, LoadError> {
    let sigma_t = p.spectrum("sigma_t", Rgb::ONE)?;
    if sigma_t.min_component() < 0.0 {
        return Err(p.error_at("sigma_t", "'sigma_t' must not be negative"));
    }
    let albedo = p.spectrum("albedo", Rgb::splat(0.75))?;
    if albedo.min_component() < 0.0 || albedo.max_component() > 1.0 {
        return Err(p.error_at("albedo", "'albedo' must lie in [0, 1] in every channel"));
    }
    let scale = p.float("scale", 1.0)?;
    if scale < 0.0 {
        return Err(p.error_at("scale", format!("'scale' must not be negative, got {scale}")));
    }
    sample_emitters(p)?;
    let phase = nested_phase(p)?;
    p.finish()?;
    let sigma_t = sigma_t.map(|s| s * scale);
    if sigma_t.max_component() > super::MAX_MAGNITUDE {
        return Err(p.error_at(
            "sigma_t",
            format!(
                "'sigma_t' (times 'scale') must be at most {:e}, got {:e}: distances times it overflow",
                super::MAX_MAGNITUDE,
                sigma_t.max_component()
            ),
        ));
    }
    Ok(Medium::homogeneous(name, sigma_t, albedo, phase))
}

fn sample_emitters(p: &Params) -> Result<(), LoadError> {
    if !p.bool("sample_emitters", true)? {
        return Err(p.error_at(
            "sample_emitters",
            "unsupported: sample_emitters=false (haze always samples emitters in media)",
        ));
    }
    Ok(())
}

/// The medium's one nested `<phase>` (or a `<ref>` to one); isotropic if none.
fn nested_phase(p: &Params) -> Result<Phase, LoadError> {
    let phases = p.objects(&["phase"]);
    if let Some(second) = phases.get(1) {
        return Err(second
            .site
            .error(format!("a medium takes one <phase>; another is at line {}", phases[0].site.line)));
    }
    match phases.first() {
        Some(o) => phase(&p.nested(o.target)?),
        None => Ok(Phase::Isotropic),
    }
}

/// Builds a `heterogeneous` medium named `name` (Mitsuba 3's `src/media/heterogeneous.cpp`):
/// `sigma_t` (1) and `albedo` (0.75), each a float, an RGB or a nested `<volume>` (or a
/// `<ref>` to one); `scale` (1, >= 0, multiplies `sigma_t`); one `<phase>`;
/// `sample_emitters` (true only). A float or RGB is, as in Mitsuba 3, a `constvolume` over the
/// unit cube, and the medium is clipped to the `sigma_t` volume's bounding box.
fn heterogeneous(p: &Params, name: String, doc: &Document) -> Result<Medium, LoadError> {
    for o in p.objects(&["volume"]) {
        if !o.name.is_some_and(|n| n == "sigma_t" || n == "albedo") {
            let what = o.name.map_or("a <volume> without a name".to_string(), |n| format!("a volume '{n}'"));
            return Err(o.site.error(format!(
                "{} does not take {what} (volume parameters: sigma_t, albedo)",
                p.element().describe()
            )));
        }
    }
    let sigma_t = volume_param(p, "sigma_t", Rgb::ONE, (0.0, super::MAX_MAGNITUDE), doc)?;
    let albedo = volume_param(p, "albedo", Rgb::splat(0.75), (0.0, 1.0), doc)?;
    let scale = p.float("scale", 1.0)?;
    if scale < 0.0 {
        return Err(p.error_at("scale", format!("'scale' must not be negative, got {scale}")));
    }
    sample_emitters(p)?;
    let phase = nested_phase(p)?;
    p.finish()?;
    let max = sigma_t.max() * scale;
    if max.max_component() > super::MAX_MAGNITUDE {
        return Err(p.error_at(
            "scale",
            format!(
                "'sigma_t' times 'scale' must be at most {:e}, got {:e}: distances times it overflow",
                super::MAX_MAGNITUDE,
                max.max_component()
            ),
        ));
    }
    // A constant needs one majorant cell; a grid gets pbrt-v4's 16^3.
    let res = match sigma_t.data {
        VolumeData::Const(_) => [1; 3],
        VolumeData::Grid { .. } => [MAJORANT_RES; 3],
    };
    let majorants = MajorantGrid::build(&sigma_t, scale, res);
    let hetero = Heterogeneous { sigma_t, albedo, scale, majorants };
    Ok(Medium::grid(name, Arc::new(hetero), phase))
}

/// The volume-valued parameter `name` of a medium: a float or RGB (a constant over the unit
/// cube, as Mitsuba 3's `props.get_volume` makes it), a nested `<volume name="..">` or a
/// `<ref name=".." id=".."/>` to one; `default` if none is given. Every value must lie in
/// `[lo, hi]`.
fn volume_param(
    p: &Params,
    name: &str,
    default: Rgb,
    range: (f32, f32),
    doc: &Document,
) -> Result<Volume, LoadError> {
    let objects: Vec<_> = p.objects(&["volume"]).into_iter().filter(|o| o.name == Some(name)).collect();
    let spectrum = p.spectrum_opt(name)?;
    match (objects.as_slice(), spectrum) {
        ([], None) => Ok(Volume::constant(default)),
        ([], Some(c)) => {
            check_range(c, range).map_err(|m| p.error_at(name, format!("'{name}' {m}")))?;
            Ok(Volume::constant(c))
        }
        ([o], None) => volume(&p.nested(o.target)?, name, range, doc),
        ([o, ..], _) => Err(o.site.error(format!("'{name}' is given more than once"))),
    }
}

fn check_range(c: Rgb, (lo, hi): (f32, f32)) -> Result<(), String> {
    if c.0.iter().all(|v| *v >= lo && *v <= hi) {
        Ok(())
    } else {
        Err(format!("must lie in [{lo}, {hi}] in every channel, got {c}"))
    }
}

/// Builds a `<volume>` used as the medium parameter `what`, whose values must lie in `range`.
/// - `constvolume`: `value` (1; float or RGB), `to_world` (identity; only sets the bounding
///   box);
/// - `gridvolume`: `filename` (a `.vol` file, required), `filter_type` (`trilinear`; or
///   `nearest`), `wrap_mode` (`clamp`; or `repeat`, `mirror`), `to_world` (identity),
///   `use_grid_bbox` (false: the grid spans the unit cube; true: the box in the file), `raw`
///   (false; no effect in RGB rendering, as in Mitsuba's RGB variants);
/// - haze's extension: a `gridvolume` whose `filename` ends in `.vdb` reads the OpenVDB float
///   grid named by `grid` (`density`), placed by the file's own transform then `to_world`;
///   `filter_type` and `raw` apply, `wrap_mode` and `use_grid_bbox` are errors (see
///   `crate::vdb`), and `grid` is an error on a `.vol` file.
pub(super) fn volume(p: &Params, what: &str, range: (f32, f32), doc: &Document) -> Result<Volume, LoadError> {
    let to_world = p.transform_opt("to_world")?.unwrap_or(Mat4::IDENTITY);
    let to_world = affine(p, &to_world)?;
    if p.ty() == "constvolume" {
        let value = p.spectrum("value", Rgb::ONE)?;
        check_range(value, range)
            .map_err(|m| p.error_at("value", format!("'value' of the '{what}' volume {m}")))?;
        p.finish()?;
        return Ok(Volume::new(VolumeData::Const(value), to_world));
    }
    let filename =
        p.string_opt("filename")?.ok_or_else(|| p.element().error("missing parameter 'filename'"))?;
    let filter = match p.string_opt("filter_type")?.unwrap_or("trilinear") {
        "trilinear" => Filter::Trilinear,
        "nearest" => Filter::Nearest,
        other => {
            return Err(p.error_at(
                "filter_type",
                format!("invalid filter_type '{other}' (must be 'trilinear' or 'nearest')"),
            ))
        }
    };
    let is_vdb = Path::new(filename).extension().is_some_and(|e| e.eq_ignore_ascii_case("vdb"));
    if is_vdb && p.raw("wrap_mode").is_some() {
        return Err(p.error_at(
            "wrap_mode",
            "'wrap_mode' does not apply to a .vdb grid: outside its active voxels a .vdb grid is its background, 0 \
             (docs/openvdb.md)",
        ));
    }
    let wrap = match p.string_opt("wrap_mode")?.unwrap_or("clamp") {
        "clamp" => Wrap::Clamp,
        "repeat" => Wrap::Repeat,
        "mirror" => Wrap::Mirror,
        other => {
            return Err(p.error_at(
                "wrap_mode",
                format!("invalid wrap_mode '{other}' (must be 'clamp', 'repeat' or 'mirror')"),
            ))
        }
    };
    let use_grid_bbox = p.bool("use_grid_bbox", false)?;
    if is_vdb && p.raw("use_grid_bbox").is_some() {
        return Err(p.error_at(
            "use_grid_bbox",
            "'use_grid_bbox' does not apply to a .vdb grid: the file's own transform places it (docs/openvdb.md)",
        ));
    }
    let grid_name = p.string_opt("grid")?;
    if !is_vdb && grid_name.is_some() {
        return Err(p.error_at(
            "grid",
            format!("'grid' applies only to OpenVDB (.vdb) files; '{filename}' is read as a .vol grid"),
        ));
    }
    p.bool("raw", false)?;
    p.finish()?;
    let path = doc.resolve(filename, p.element());
    if !path.exists() {
        return Err(p.error_at("filename", format!("volume file '{}' not found", path.display())));
    }
    if is_vdb {
        return vdb_volume(p, &path, grid_name.unwrap_or("density"), what, range, filter, to_world);
    }
    let grid =
        Grid::read_vol(&path).map_err(|m| p.error_at("filename", format!("'{}': {m}", path.display())))?;
    if let Some((cell, c, v)) = grid.first_outside(range.0, range.1) {
        return Err(p.error_at(
            "filename",
            format!(
                "'{}': cell ({}, {}, {}) channel {c} holds {v}: '{what}' values must be finite and lie in [{}, {}]",
                path.display(),
                cell[0],
                cell[1],
                cell[2],
                range.0,
                range.1
            ),
        ));
    }
    let to_world = if use_grid_bbox {
        let (lo, hi) = grid.bbox;
        if !(lo.is_finite() && hi.is_finite() && hi.cmpgt(lo).all()) {
            return Err(p.error_at(
                "use_grid_bbox",
                format!("'{}' has an empty or invalid bounding box {lo} - {hi}", path.display()),
            ));
        }
        // Mitsuba's `bbox_transform`: the file's box maps to the unit cube.
        to_world * Affine3A::from_translation(lo) * Affine3A::from_scale(hi - lo)
    } else {
        to_world
    };
    Ok(Volume::new(VolumeData::Grid { grid: Arc::new(grid), filter, wrap }, to_world))
}

/// The float grid `grid_name` of the OpenVDB file `path` as a volume (`crate::vdb` has the
/// mapping): the VDB's world, then the element's `to_world`.
fn vdb_volume(
    p: &Params,
    path: &Path,
    grid_name: &str,
    what: &str,
    range: (f32, f32),
    filter: Filter,
    to_world: Affine3A,
) -> Result<Volume, LoadError> {
    let shown = path.display();
    // Errors about the grid point at `grid` if it is given, else at `filename`.
    let at_grid = if p.raw("grid").is_some() { "grid" } else { "filename" };
    let vdb = read_vdb(path, grid_name).map_err(|e| match e {
        VdbError::Grid(m) => p.error_at(at_grid, format!("'{shown}': {m}")),
        VdbError::File(m) => p.error_at("filename", format!("'{shown}': {m}")),
    })?;
    if let Some((cell, _, v)) = vdb.grid.first_outside(range.0, range.1) {
        let [i, j, k] = vdb.voxel(cell);
        return Err(p.error_at(
            at_grid,
            format!(
                "'{shown}': grid '{grid_name}' holds {v} at voxel ({i}, {j}, {k}): '{what}' values must be finite \
                 and lie in [{}, {}]",
                range.0, range.1
            ),
        ));
    }
    let to_world = to_world * vdb.to_world;
    // Clamp: the padding ring is background, so every wrap mode reads the same (crate::vdb).
    Ok(Volume::new(VolumeData::Grid { grid: Arc::new(vdb.grid), filter, wrap: Wrap::Clamp }, to_world))
}

/// A volume's `to_world` as an affine map; it must be invertible and finite.
fn affine(p: &Params, m: &Mat4) -> Result<Affine3A, LoadError> {
    let a = Affine3A::from_mat4(*m);
    let det = a.matrix3.determinant();
    if !(det.is_finite() && det.abs() > 1e-12 && a.translation.is_finite()) {
        return Err(p.error_at("to_world", "'to_world' of a volume must be finite and invertible"));
    }
    Ok(a)
}

/// `isotropic`, or `hg` with asymmetry `g` (Mitsuba 3 default 0.8) in (-1, 1).
pub(super) fn phase(p: &Params) -> Result<Phase, LoadError> {
    let phase = match p.ty() {
        "hg" => {
            let g = p.float("g", 0.8)?;
            if !(g > -1.0 && g < 1.0) {
                return Err(p.error_at("g", format!("'g' must lie in (-1, 1), got {g}")));
            }
            Phase::HenyeyGreenstein { g }
        }
        _ => Phase::Isotropic,
    };
    p.finish()?;
    Ok(phase)
}
