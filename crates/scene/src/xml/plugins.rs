//! The table of supported Mitsuba 3 plugins and the parameters each one reads.
//!
//! The loader's strictness check uses it (a parameter not listed is "unused"; a type not listed
//! is "unsupported"), and a test checks that `docs/mitsuba-compat.md` mentions every entry.

/// One supported plugin: `(kind, type, parameters)`, e.g. `("shape", "sphere", &["center",
/// ..])`. `kind` is the XML tag (`shape`, `bsdf`, `texture`, `medium`, `phase`, `emitter`, `sensor`,
/// `film`, `rfilter`, `sampler`, `integrator`); the parameters are the names of the typed
/// parameters (`<float name="..">`, ...) the plugin reads. Nested objects (a shape's `<bsdf>`,
/// a medium's `<phase>`, ...) are not listed here.
pub type PluginEntry = (&'static str, &'static str, &'static [&'static str]);

/// Parameters shared by every integrator (see [`crate::IntegratorSpec`]).
const INTEGRATOR_PARAMS: &[&str] = &["max_depth", "rr_depth", "hide_emitters"];
const MESH_FILE_PARAMS: &[&str] =
    &["filename", "to_world", "flip_normals", "face_normals", "flip_tex_coords"];
const SHAPE_PARAMS: &[&str] = &["to_world", "flip_normals"];

const PLUGINS: &[PluginEntry] = &[
    ("integrator", "volpath", INTEGRATOR_PARAMS),
    ("integrator", "volpathmis", INTEGRATOR_PARAMS),
    ("integrator", "path", INTEGRATOR_PARAMS),
    ("integrator", "moment", &[]),
    ("integrator", "vrl", INTEGRATOR_PARAMS),
    ("integrator", "vpl", INTEGRATOR_PARAMS),
    ("integrator", "vrl_lightcuts", INTEGRATOR_PARAMS),
    ("integrator", "vpl_lightcuts", INTEGRATOR_PARAMS),
    (
        "sensor",
        "perspective",
        &["fov", "fov_axis", "focal_length", "near_clip", "far_clip", "focus_distance", "to_world"],
    ),
    (
        "sensor",
        "thinlens",
        &[
            "fov",
            "fov_axis",
            "focal_length",
            "near_clip",
            "far_clip",
            "focus_distance",
            "aperture_radius",
            "to_world",
        ],
    ),
    ("sensor", "orthographic", &["near_clip", "far_clip", "focus_distance", "to_world"]),
    ("sampler", "independent", &["sample_count", "seed"]),
    ("sampler", "stratified", &["sample_count", "seed", "jitter"]),
    ("sampler", "multijitter", &["sample_count", "seed", "jitter"]),
    ("sampler", "orthogonal", &["sample_count", "seed", "jitter", "strength"]),
    ("sampler", "ldsampler", &["sample_count", "seed"]),
    ("film", "hdrfilm", &["width", "height", "pixel_format", "component_format", "file_format", "banner"]),
    ("rfilter", "box", &[]),
    ("rfilter", "tent", &["radius"]),
    ("rfilter", "gaussian", &["stddev"]),
    ("shape", "sphere", &["center", "radius", "to_world", "flip_normals"]),
    ("shape", "cube", SHAPE_PARAMS),
    ("shape", "rectangle", SHAPE_PARAMS),
    ("shape", "disk", SHAPE_PARAMS),
    ("shape", "obj", MESH_FILE_PARAMS),
    ("shape", "ply", MESH_FILE_PARAMS),
    ("shape", "cylinder", &["p0", "p1", "radius", "to_world", "flip_normals"]),
    ("shape", "shapegroup", &[]),
    ("shape", "instance", &["to_world"]),
    ("shape", "serialized", &["filename", "shape_index", "to_world", "flip_normals", "face_normals"]),
    ("bsdf", "null", &[]),
    ("bsdf", "diffuse", &["reflectance"]),
    ("bsdf", "dielectric", &["int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"]),
    ("bsdf", "thindielectric", &["int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"]),
    (
        "bsdf",
        "roughdielectric",
        &[
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
            "int_ior",
            "ext_ior",
            "specular_reflectance",
            "specular_transmittance",
        ],
    ),
    ("bsdf", "plastic", &["diffuse_reflectance", "int_ior", "ext_ior", "nonlinear", "specular_reflectance"]),
    (
        "bsdf",
        "roughplastic",
        &[
            "distribution",
            "alpha",
            "sample_visible",
            "diffuse_reflectance",
            "int_ior",
            "ext_ior",
            "nonlinear",
            "specular_reflectance",
        ],
    ),
    ("bsdf", "twosided", &[]),
    ("bsdf", "conductor", &["material", "eta", "k", "specular_reflectance"]),
    ("bsdf", "mask", &["opacity"]),
    ("bsdf", "blendbsdf", &["weight"]),
    ("bsdf", "normalmap", &["normalmap"]),
    ("bsdf", "bumpmap", &["scale"]),
    (
        "bsdf",
        "pplastic",
        &[
            "diffuse_reflectance",
            "specular_reflectance",
            "int_ior",
            "ext_ior",
            "eta",
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
        ],
    ),
    (
        "bsdf",
        "roughconductor",
        &[
            "distribution",
            "alpha",
            "alpha_u",
            "alpha_v",
            "sample_visible",
            "material",
            "eta",
            "k",
            "specular_reflectance",
        ],
    ),
    (
        "bsdf",
        "principled",
        &[
            "base_color",
            "roughness",
            "anisotropic",
            "metallic",
            "spec_trans",
            "eta",
            "specular",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "clearcoat",
            "clearcoat_gloss",
            "main_specular_sampling_rate",
            "clearcoat_sampling_rate",
            "diffuse_reflectance_sampling_rate",
        ],
    ),
    (
        "bsdf",
        "principledthin",
        &[
            "base_color",
            "roughness",
            "anisotropic",
            "spec_trans",
            "eta",
            "spec_tint",
            "sheen",
            "sheen_tint",
            "flatness",
            "diff_trans",
            "specular_reflectance_sampling_rate",
            "specular_transmittance_sampling_rate",
            "diffuse_reflectance_sampling_rate",
            "diffuse_transmittance_sampling_rate",
        ],
    ),
    ("texture", "rawconstant", &["value"]),
    ("texture", "checkerboard", &["color0", "color1", "to_uv"]),
    ("texture", "bitmap", &["filename", "filter_type", "wrap_mode", "raw", "to_uv", "format", "accel"]),
    ("texture", "mesh_attribute", &["name", "scale"]),
    ("medium", "homogeneous", &["sigma_t", "albedo", "scale", "sample_emitters"]),
    ("medium", "heterogeneous", &["sigma_t", "albedo", "scale", "sample_emitters"]),
    (
        "volume",
        "gridvolume",
        &["filename", "filter_type", "wrap_mode", "to_world", "use_grid_bbox", "raw", "grid"],
    ),
    ("volume", "constvolume", &["value", "to_world"]),
    ("phase", "isotropic", &[]),
    ("phase", "hg", &["g"]),
    ("emitter", "point", &["position", "intensity", "to_world"]),
    ("emitter", "spot", &["to_world", "intensity", "cutoff_angle", "beam_width", "texture"]),
    ("emitter", "projector", &["irradiance", "scale", "to_world", "fov", "fov_axis", "focal_length"]),
    ("emitter", "area", &["radiance"]),
    ("emitter", "constant", &["radiance"]),
    ("emitter", "envmap", &["filename", "scale", "to_world"]),
    ("emitter", "directional", &["direction", "irradiance", "to_world"]),
];

/// Every supported `(kind, type, parameters)`; see [`PluginEntry`].
pub fn supported_plugins() -> &'static [PluginEntry] {
    PLUGINS
}

/// The parameters of plugin `ty` of `kind`, or `None` if haze does not support it.
pub(super) fn parameters(kind: &str, ty: &str) -> Option<&'static [&'static str]> {
    PLUGINS.iter().find(|(k, t, _)| *k == kind && *t == ty).map(|(_, _, p)| *p)
}

/// The supported types of `kind`, comma-separated, for messages.
pub(super) fn types_of(kind: &str) -> String {
    let types: Vec<&str> = PLUGINS.iter().filter(|(k, _, _)| *k == kind).map(|(_, t, _)| *t).collect();
    types.join(", ")
}

/// True for the tags of plugin objects haze knows (it supports at least one type of each).
pub(super) fn is_supported_kind(tag: &str) -> bool {
    PLUGINS.iter().any(|(k, _, _)| *k == tag)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `docs/mitsuba-compat.md` must have, for every plugin, a table row naming its kind, its
    /// type and each of its parameters, so that the document cannot drift from the loader.
    #[test]
    fn compat_doc_mentions_every_plugin_and_parameter() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/mitsuba-compat.md");
        let doc = std::fs::read_to_string(path).expect("docs/mitsuba-compat.md is readable");
        for (kind, ty, params) in supported_plugins() {
            let row = doc.lines().find(|l| l.starts_with(&format!("| {kind} | `{ty}` |")));
            let Some(row) = row else {
                panic!("docs/mitsuba-compat.md has no row `| {kind} | `{ty}` | ...`");
            };
            for p in *params {
                assert!(row.contains(&format!("`{p}`")), "the row of {kind} `{ty}` does not mention `{p}`");
            }
        }
    }

    #[test]
    fn entries_are_unique() {
        for (i, (k, t, _)) in PLUGINS.iter().enumerate() {
            assert!(PLUGINS[..i].iter().all(|(k2, t2, _)| (k2, t2) != (k, t)), "{k} {t} listed twice");
        }
    }
}
