//! BSDF plugins `null`, `diffuse`, `dielectric`, `thindielectric`, `roughdielectric`,
//! `plastic`, `roughplastic`, `twosided`, `conductor`, `roughconductor`, `mask`, `pplastic` and
//! `blendbsdf`, `normalmap` and `bumpmap`, `principled` and `principledthin`, and Mitsuba 3's table
//! of named indices of refraction.

use super::params::Params;
use super::{textures, LoadError};
use crate::bsdf::{
    conductor_ior, Blend, Bsdf, Conductor, Mask, Microfacet, MicrofacetType, PPlastic, Perturbation,
    Perturbed, Plastic, Principled, PrincipledThin, RoughDielectric, RoughPlastic, Roughness,
};
use crate::texture::Texture;
use haze_core::color::SpectrumKind;
use haze_core::Rgb;

/// Mitsuba 3's named indices of refraction (`int_ior="water"`), at 589 nm, as listed in its
/// `dielectric` documentation (`ior.h`).
pub const NAMED_IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.00004),
    ("hydrogen", 1.00013),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// The index of refraction called `name` (case-insensitive), from [`NAMED_IORS`].
pub fn ior_by_name(name: &str) -> Option<f32> {
    let name = name.trim().to_ascii_lowercase();
    NAMED_IORS.iter().find(|(n, _)| *n == name).map(|(_, ior)| *ior)
}

/// Builds a BSDF (Mitsuba 3 names and defaults).
/// - `null`: no parameters.
/// - `diffuse`: `reflectance` (default 0.5), a spectrum or texture in [0, 1].
/// - `dielectric`, `thindielectric`: `int_ior` (default `"bk7"` = 1.5046) and `ext_ior`
///   (`"air"` = 1.000277), numbers or names from [`NAMED_IORS`]; `eta = int_ior / ext_ior`.
/// - `roughdielectric`: the same plus `distribution` (`beckmann` (default) or `ggx`), `alpha`
///   (0.1, must be > 0) or `alpha_u` and `alpha_v` (numbers or textures), and `sample_visible`
///   (true).
/// - `plastic`: `diffuse_reflectance` (0.5, spectrum or texture), `int_ior`
///   (`"polypropylene"` = 1.49), `ext_ior` (`"air"`), `nonlinear` (false).
/// - `roughplastic`: the same plus `distribution`, `alpha` (a number only, as in Mitsuba 3)
///   and `sample_visible` as above.
/// - `twosided`: one nested or referenced BSDF, used on both sides.
///
/// Mitsuba's `specular_reflectance`/`specular_transmittance` scale factors are accepted only at
/// their default 1, because haze's BSDFs have no such factors.
pub(super) fn build(p: &Params) -> Result<Bsdf, LoadError> {
    let bsdf = match p.ty() {
        "diffuse" => {
            Bsdf::Diffuse { reflectance: textures::texture(p, "reflectance", Rgb::splat(0.5), (0.0, 1.0))? }
        }
        "dielectric" | "thindielectric" | "roughdielectric" => {
            let eta = eta(p, "bk7")?;
            unit_scale_factors(p, &["specular_reflectance", "specular_transmittance"])?;
            match p.ty() {
                "dielectric" => Bsdf::Dielectric { eta },
                "thindielectric" => Bsdf::ThinDielectric { eta },
                _ => Bsdf::RoughDielectric(RoughDielectric { distr: roughness(p)?, eta }),
            }
        }
        "plastic" | "roughplastic" => {
            let diffuse = textures::texture(p, "diffuse_reflectance", Rgb::splat(0.5), (0.0, 1.0))?;
            let eta = eta(p, "polypropylene")?;
            let nonlinear = p.bool("nonlinear", false)?;
            unit_scale_factors(p, &["specular_reflectance"])?;
            if p.ty() == "plastic" {
                Bsdf::Plastic(Plastic::new(diffuse, eta, nonlinear))
            } else {
                Bsdf::RoughPlastic(Box::new(RoughPlastic::new(microfacet(p)?, diffuse, eta, nonlinear)))
            }
        }
        "twosided" => {
            let nested = p.objects(&["bsdf"]);
            match nested.as_slice() {
                [o] => {
                    let inner = nested_bsdf(p, o)?;
                    if matches!(inner, Bsdf::TwoSided(_)) {
                        return Err(o.site.error("a twosided BSDF cannot wrap another twosided BSDF"));
                    }
                    Bsdf::TwoSided(Box::new(inner))
                }
                [] => return Err(p.element().error("a twosided BSDF needs one nested or referenced <bsdf>")),
                [_, o, ..] => {
                    return Err(o.site.error(
                        "unsupported: a twosided BSDF with a different BSDF on each side (give one <bsdf>)",
                    ))
                }
            }
        }
        "pplastic" => {
            let diffuse = textures::texture(p, "diffuse_reflectance", Rgb::splat(0.5), (0.0, 1.0))?;
            let specular = textures::texture(p, "specular_reflectance", Rgb::ONE, (0.0, 1.0))?;
            let eta = match p.float_opt("eta")? {
                Some(e) if p.raw("int_ior").is_some() || p.raw("ext_ior").is_some() => {
                    let _ = e;
                    return Err(p.error_at("eta", "give either 'eta' or 'int_ior'/'ext_ior', not both"));
                }
                Some(e) if !(MIN_IOR..=MAX_IOR).contains(&e) => {
                    return Err(
                        p.error_at("eta", format!("'eta' must lie in [{MIN_IOR}, {MAX_IOR}], got {e}"))
                    )
                }
                Some(e) => e,
                None => eta(p, "polypropylene")?,
            };
            Bsdf::PPlastic(Box::new(PPlastic::new(roughness(p)?, eta, diffuse, specular)))
        }
        "mask" => {
            // Mitsuba 3: `opacity` (0.5; a float, spectrum or texture in [0, 1]) over one
            // nested BSDF.
            let opacity = textures::texture(p, "opacity", Rgb::splat(0.5), (0.0, 1.0))?;
            let nested = match p.objects(&["bsdf"])[..] {
                [o] => nested_bsdf(p, o)?,
                [] => return Err(p.element().error("a mask needs one nested or referenced <bsdf>")),
                [_, o, ..] => return Err(o.site.error("a mask takes one <bsdf>")),
            };
            Bsdf::Mask(Box::new(Mask { opacity, nested: Box::new(nested) }))
        }
        "blendbsdf" => {
            // Mitsuba 3: `weight` (required, although its documentation says 0.5; a float or a
            // texture, read by luminance) and exactly two nested BSDFs, the first at weight 0.
            if p.raw("weight").is_none() && !p.objects(&["texture"]).iter().any(|o| o.name == Some("weight"))
            {
                return Err(p.element().error("a blendbsdf needs 'weight' (a float or a texture in [0, 1])"));
            }
            let weight = textures::texture(p, "weight", Rgb::splat(0.5), (0.0, 1.0))?;
            let nested = match p.objects(&["bsdf"])[..] {
                [a, b] => [nested_bsdf(p, a)?, nested_bsdf(p, b)?],
                [_, _, c, ..] => return Err(c.site.error("a blendbsdf takes two <bsdf>s, not more")),
                _ => return Err(p.element().error("a blendbsdf needs two nested or referenced <bsdf>s")),
            };
            Bsdf::Blend(Box::new(Blend { weight, nested }))
        }
        "normalmap" | "bumpmap" => {
            // Mitsuba 3: `normalmap` takes the texture `normalmap` (required); `bumpmap` one
            // nested texture of any name (the height) and `scale` (1); each one nested BSDF.
            let perturbation = if p.ty() == "normalmap" {
                if p.raw("normalmap").is_none()
                    && !p.objects(&["texture"]).iter().any(|o| o.name == Some("normalmap"))
                {
                    return Err(p
                        .element()
                        .error("a normalmap needs 'normalmap' (a texture, usually a raw bitmap)"));
                }
                Perturbation::NormalMap(textures::texture(p, "normalmap", Rgb::ZERO, (0.0, 1.0))?)
            } else {
                let height = match p.objects(&["texture"])[..] {
                    [o] => textures::build(&p.nested(o.target)?)?,
                    [] => {
                        return Err(p.element().error("a bumpmap needs one nested or referenced <texture>"))
                    }
                    [_, o, ..] => return Err(o.site.error("a bumpmap takes one <texture>")),
                };
                let scale = p.float("scale", 1.0)?;
                if !scale.is_finite() {
                    return Err(p.error_at("scale", format!("'scale' must be finite, got {scale}")));
                }
                Perturbation::BumpMap { height, scale }
            };
            let nested = match p.objects(&["bsdf"])[..] {
                [o] => nested_bsdf(p, o)?,
                [] => {
                    return Err(p
                        .element()
                        .error(format!("a {} needs one nested or referenced <bsdf>", p.ty())))
                }
                [_, o, ..] => return Err(o.site.error(format!("a {} takes one <bsdf>", p.ty()))),
            };
            Bsdf::Perturbed(Box::new(Perturbed { perturbation, nested }))
        }
        "conductor" | "roughconductor" => {
            let (eta, k) = complex_ior(p)?;
            let specular_reflectance = textures::texture(p, "specular_reflectance", Rgb::ONE, (0.0, 1.0))?;
            let distr = if p.ty() == "roughconductor" { Some(roughness(p)?) } else { None };
            Bsdf::Conductor(Box::new(Conductor { eta, k, specular_reflectance, distr }))
        }
        "principled" => Bsdf::Principled(Box::new(principled(p)?)),
        "principledthin" => Bsdf::PrincipledThin(Box::new(principled_thin(p)?)),
        _ => Bsdf::Null,
    };
    let texture_params: &[&str] = match p.ty() {
        "principled" => PRINCIPLED_TEXTURES,
        "principledthin" => PRINCIPLED_THIN_TEXTURES,
        "diffuse" => &["reflectance"],
        "plastic" | "roughplastic" => &["diffuse_reflectance"],
        "conductor" => &["specular_reflectance"],
        "roughconductor" => &["specular_reflectance", "alpha", "alpha_u", "alpha_v"],
        "roughdielectric" => &["alpha", "alpha_u", "alpha_v"],
        "mask" => &["opacity"],
        "blendbsdf" => &["weight"],
        "normalmap" => &["normalmap"],
        "pplastic" => &["diffuse_reflectance", "specular_reflectance", "alpha", "alpha_u", "alpha_v"],
        _ => &[],
    };
    // The bump map's one texture may have any name (Mitsuba 3 takes it by kind).
    if p.ty() != "bumpmap" {
        textures::reject_other_textures(p, texture_params)?;
    }
    p.finish()?;
    Ok(bsdf)
}

/// The parameters of `principled` that may be textures (all but `eta`, `specular` and the
/// sampling rates).
const PRINCIPLED_TEXTURES: &[&str] = &[
    "base_color",
    "roughness",
    "anisotropic",
    "metallic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "clearcoat",
    "clearcoat_gloss",
];

/// The parameters of `principledthin` that may be textures (`eta` too, unlike `principled`'s).
const PRINCIPLED_THIN_TEXTURES: &[&str] = &[
    "base_color",
    "roughness",
    "anisotropic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "eta",
    "diff_trans",
];

/// Mitsuba 3's `get_flag` of the principled BSDFs: the parameter is given and is not the
/// number 0 (a texture counts as given). The flags decide which lobes the BSDF has.
fn principled_flag(p: &Params, name: &str) -> Result<bool, LoadError> {
    if p.objects(&["texture"]).iter().any(|o| o.name == Some(name)) {
        return Ok(true);
    }
    match p.raw(name) {
        None => Ok(false),
        Some(el) if el.tag == "float" || el.tag == "integer" => Ok(p.float(name, 0.0)? != 0.0),
        Some(_) => Ok(true),
    }
}

/// A principled weight (`metallic`, `sheen`, ...): a float or texture in [0, 1].
fn unit_weight(p: &Params, name: &str, default: f32) -> Result<Texture, LoadError> {
    textures::texture(p, name, Rgb::splat(default), (0.0, 1.0))
}

/// A sampling rate of the principled BSDFs (default 1, finite and >= 0).
fn sampling_rate(p: &Params, name: &str) -> Result<f32, LoadError> {
    let v = p.float(name, 1.0)?;
    if v.is_nan() || v < 0.0 {
        return Err(p.error_at(name, format!("'{name}' must be >= 0, got {v}")));
    }
    Ok(v)
}

/// Mitsuba 3's `principled`: the weights of [`PRINCIPLED_TEXTURES`] (defaults: `base_color`
/// 0.5, `roughness` 0.5, the others 0), and `eta` or `specular` (0.5), not both:
/// `eta = 2 / (1 - sqrt(0.08 specular)) - 1` (Burley 2015, eq. 1 inverted). With transmission,
/// `eta` 1 becomes 1.001 and `specular` 0 becomes 0.001, as Mitsuba does (an index-matched
/// transmission lobe would be a delta).
fn principled(p: &Params) -> Result<Principled, LoadError> {
    let has_spec_trans = principled_flag(p, "spec_trans")?;
    let eta = match (p.float_opt("eta")?, p.raw("specular").is_some()) {
        (Some(_), true) => return Err(p.error_at("specular", "give either 'eta' or 'specular', not both")),
        (Some(eta), false) => {
            if !(MIN_IOR..=MAX_IOR).contains(&eta) {
                return Err(p.error_at("eta", format!("'eta' must lie in [{MIN_IOR}, {MAX_IOR}], got {eta}")));
            }
            if has_spec_trans && eta == 1.0 {
                1.001
            } else {
                eta
            }
        }
        (None, _) => {
            let mut specular = p.float("specular", 0.5)?;
            // specular 10 is eta 17.9; beyond 12.5 the formula has no solution.
            if !(0.0..=10.0).contains(&specular) {
                return Err(p.error_at("specular", format!("'specular' must lie in [0, 10], got {specular}")));
            }
            if has_spec_trans && specular == 0.0 {
                specular = 1e-3;
            }
            2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
        }
    };
    Ok(Principled {
        base_color: unit_weight(p, "base_color", 0.5)?,
        roughness: unit_weight(p, "roughness", 0.5)?,
        anisotropic: unit_weight(p, "anisotropic", 0.0)?,
        metallic: unit_weight(p, "metallic", 0.0)?,
        spec_trans: unit_weight(p, "spec_trans", 0.0)?,
        spec_tint: unit_weight(p, "spec_tint", 0.0)?,
        sheen: unit_weight(p, "sheen", 0.0)?,
        sheen_tint: unit_weight(p, "sheen_tint", 0.0)?,
        flatness: unit_weight(p, "flatness", 0.0)?,
        clearcoat: unit_weight(p, "clearcoat", 0.0)?,
        clearcoat_gloss: unit_weight(p, "clearcoat_gloss", 0.0)?,
        eta,
        has_spec_trans,
        has_anisotropic: principled_flag(p, "anisotropic")?,
        has_flatness: principled_flag(p, "flatness")?,
        spec_srate: sampling_rate(p, "main_specular_sampling_rate")?,
        clearcoat_srate: sampling_rate(p, "clearcoat_sampling_rate")?,
        diffuse_srate: sampling_rate(p, "diffuse_reflectance_sampling_rate")?,
    })
}

/// Mitsuba 3's `principledthin`: the weights of [`PRINCIPLED_THIN_TEXTURES`] (defaults as
/// `principled`'s; `eta` 1.5, a float or texture; `diff_trans` 0, in [0, 2]).
fn principled_thin(p: &Params) -> Result<PrincipledThin, LoadError> {
    Ok(PrincipledThin {
        base_color: unit_weight(p, "base_color", 0.5)?,
        roughness: unit_weight(p, "roughness", 0.5)?,
        anisotropic: unit_weight(p, "anisotropic", 0.0)?,
        spec_trans: unit_weight(p, "spec_trans", 0.0)?,
        spec_tint: unit_weight(p, "spec_tint", 0.0)?,
        sheen: unit_weight(p, "sheen", 0.0)?,
        sheen_tint: unit_weight(p, "sheen_tint", 0.0)?,
        flatness: unit_weight(p, "flatness", 0.0)?,
        eta: textures::texture(p, "eta", Rgb::splat(1.5), (MIN_IOR, MAX_IOR))?,
        diff_trans: textures::texture(p, "diff_trans", Rgb::ZERO, (0.0, 2.0))?,
        has_spec_trans: principled_flag(p, "spec_trans")?,
        has_diff_trans: principled_flag(p, "diff_trans")?,
        has_anisotropic: principled_flag(p, "anisotropic")?,
        has_flatness: principled_flag(p, "flatness")?,
        spec_refl_srate: sampling_rate(p, "specular_reflectance_sampling_rate")?,
        spec_trans_srate: sampling_rate(p, "specular_transmittance_sampling_rate")?,
        diff_refl_srate: sampling_rate(p, "diffuse_reflectance_sampling_rate")?,
        diff_trans_srate: sampling_rate(p, "diffuse_transmittance_sampling_rate")?,
    })
}

/// A BSDF nested in another (`twosided`, `mask`, `blendbsdf`, `normalmap`, `bumpmap`): any
/// but a normal or bump map, which haze applies only as a shape's own BSDF (the scene perturbs
/// the shape's shading normal).
fn nested_bsdf(p: &Params, o: &super::params::Object) -> Result<Bsdf, LoadError> {
    let bsdf = build(&p.nested(o.target)?)?;
    if matches!(bsdf, Bsdf::Perturbed(_)) {
        return Err(o.site.error(format!(
            "unsupported: a normalmap or bumpmap inside <bsdf type=\"{}\"> (haze applies them only as a shape's own BSDF)",
            p.ty()
        )));
    }
    Ok(bsdf)
}

/// `int_ior / ext_ior`, with the plugin's default `int_ior` and `ext_ior` air.
fn eta(p: &Params, default_int: &str) -> Result<f32, LoadError> {
    let int_ior = ior(p, "int_ior", default_int)?;
    let ext_ior = ior(p, "ext_ior", "air")?;
    Ok(int_ior / ext_ior)
}

/// Mitsuba's optional specular scale factors: only the default 1 is supported.
fn unit_scale_factors(p: &Params, names: &[&str]) -> Result<(), LoadError> {
    for &name in names {
        if let Some(v) = p.spectrum_opt(name)? {
            if v != Rgb::ONE {
                return Err(p.error_at(
                    name,
                    format!("unsupported: '{name}' other than 1 (haze's {} has no scale factors)", p.ty()),
                ));
            }
        }
    }
    Ok(())
}

/// A conductor's complex index of refraction `(eta, k)`, as Mitsuba 3 reads it: `eta` and `k`
/// (defaults 0 and 1: a perfect mirror) when `eta` is given or `material` is `none` (its
/// default), else the named `material`'s (`Au`, `Cu`, ...; [`crate::bsdf::CONDUCTOR_IORS`]).
fn complex_ior(p: &Params) -> Result<(Rgb, Rgb), LoadError> {
    let material = p.string_opt("material")?;
    // Indices of refraction, not reflectances: a wavelength list is not clamped to [0, 1].
    let unbounded = |name| p.spectrum_opt_as(name, SpectrumKind::Unbounded);
    let eta = unbounded("eta")?;
    let (eta, k) = match (material, eta) {
        (Some(m), Some(_)) if m != "none" => {
            return Err(p.error_at("eta", "give either 'eta' and 'k' or 'material', not both"))
        }
        (None | Some("none"), eta) | (_, eta @ Some(_)) => {
            (eta.unwrap_or(Rgb::ZERO), unbounded("k")?.unwrap_or(Rgb::ONE))
        }
        (Some(m), None) => conductor_ior(m).ok_or_else(|| {
            p.error_at(
                "material",
                format!("unknown conductor '{m}' (Mitsuba 3's names, case-sensitive: Au, Ag, Al, Cu, Cr, ...; or none)"),
            )
        })?,
    };
    for (name, v) in [("eta", eta), ("k", k)] {
        if v.min_component() < 0.0 || v.max_component() > MAX_IOR {
            return Err(p.error_at(name, format!("'{name}' must lie in [0, {MAX_IOR}] in every channel")));
        }
    }
    Ok((eta, k))
}

/// `distribution` (`beckmann` default, `ggx`), `alpha` (0.1, > 0) and `sample_visible` (true),
/// as Mitsuba 3's `roughplastic` reads them (one number: its tables are built per roughness).
fn microfacet(p: &Params) -> Result<Microfacet, LoadError> {
    let ty = distribution(p)?;
    let alpha = alpha_value(p, "alpha")?;
    Ok(Microfacet::new(ty, alpha, p.bool("sample_visible", true)?))
}

/// The roughness of `roughconductor`, `roughdielectric` and `pplastic`, as Mitsuba 3 reads it:
/// `distribution` and `sample_visible` as [`microfacet`], and `alpha` (0.1), or `alpha_u` and
/// `alpha_v` (both, and not with `alpha`), each a number (> 0) or a texture (read as one
/// number, values in [0, 100]; below 1e-4 they count as 1e-4, as Mitsuba clamps them).
fn roughness(p: &Params) -> Result<Roughness, LoadError> {
    let ty = distribution(p)?;
    let sample_visible = p.bool("sample_visible", true)?;
    let is_texture = |name: &str| p.objects(&["texture"]).iter().any(|o| o.name == Some(name));
    let given = |name: &str| p.raw(name).is_some() || is_texture(name);
    let value = |name: &str| -> Result<Texture, LoadError> {
        if is_texture(name) {
            textures::texture(p, name, Rgb::splat(0.1), (0.0, MAX_ALPHA))
        } else {
            Ok(Texture::Constant(Rgb::splat(alpha_value(p, name)?)))
        }
    };
    let (alpha_u, alpha_v) = match (given("alpha_u"), given("alpha_v")) {
        (false, false) => {
            let a = value("alpha")?;
            (a.clone(), a)
        }
        (true, true) => {
            if given("alpha") {
                return Err(p.error_at("alpha", "give either 'alpha' or 'alpha_u' and 'alpha_v', not both"));
            }
            (value("alpha_u")?, value("alpha_v")?)
        }
        (true, false) => return Err(p.error_at("alpha_u", "'alpha_u' needs 'alpha_v' too")),
        (false, true) => return Err(p.error_at("alpha_v", "'alpha_v' needs 'alpha_u' too")),
    };
    Ok(match (&alpha_u, &alpha_v) {
        (Texture::Constant(u), Texture::Constant(v)) => {
            Roughness::Fixed(Microfacet::anisotropic(ty, u[0], v[0], sample_visible))
        }
        _ => Roughness::Textured { base: Microfacet::new(ty, 0.1, sample_visible), alpha_u, alpha_v },
    })
}

/// `distribution`: `beckmann` (default) or `ggx`.
fn distribution(p: &Params) -> Result<MicrofacetType, LoadError> {
    match p.string_opt("distribution")? {
        None => Ok(MicrofacetType::Beckmann),
        Some(name) => MicrofacetType::from_name(name).ok_or_else(|| {
            p.error_at(
                "distribution",
                format!("unknown microfacet distribution '{name}' (supported: beckmann, ggx)"),
            )
        }),
    }
}

/// A roughness given as a number (default 0.1): in (0, [`MAX_ALPHA`]].
fn alpha_value(p: &Params, name: &str) -> Result<f32, LoadError> {
    let alpha = p.float(name, 0.1)?;
    if alpha.is_nan() || alpha <= 0.0 {
        return Err(p.error_at(name, format!("'{name}' must be > 0, got {alpha}")));
    }
    if alpha > MAX_ALPHA {
        return Err(p.error_at(name, format!("'{name}' must be at most {MAX_ALPHA}, got {alpha}")));
    }
    Ok(alpha)
}

/// An index of refraction given as a number (`<float>`) or a material name (`<string>`).
fn ior(p: &Params, name: &str, default: &str) -> Result<f32, LoadError> {
    let value = match p.raw(name) {
        None => ior_by_name(default).unwrap_or(1.0),
        Some(el) if el.tag == "string" => {
            let s = el.required_attr("value")?;
            ior_by_name(s).ok_or_else(|| {
                el.error(format!(
                    "unknown index of refraction '{s}' (known: vacuum, air, water, \
                     acrylic glass, bk7, diamond, ...; or give a number)"
                ))
            })?
        }
        Some(_) => p.float(name, 0.0)?,
    };
    if value <= 0.0 {
        return Err(p.error_at(name, format!("'{name}' must be > 0, got {value}")));
    }
    // Far outside this range the Fresnel terms overflow or cancel to NaN (int_ior 1e-30 made
    // every sample NaN); no real material comes near it.
    if !(MIN_IOR..=MAX_IOR).contains(&value) {
        return Err(p.error_at(
            name,
            format!("'{name}' must lie in [{MIN_IOR}, {MAX_IOR}] (haze's range for indices of refraction), got {value}"),
        ));
    }
    Ok(value)
}

/// The range of indices of refraction haze accepts.
const MIN_IOR: f32 = 0.01;
const MAX_IOR: f32 = 100.0;

/// Largest microfacet `alpha` haze accepts (beyond it the distributions overflow).
const MAX_ALPHA: f32 = 100.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ior_names() {
        assert_eq!(ior_by_name("bk7"), Some(1.5046));
        assert_eq!(ior_by_name("Water"), Some(1.3330));
        assert_eq!(ior_by_name("carbon dioxide"), Some(1.00045));
        assert_eq!(ior_by_name("unobtainium"), None);
        assert_eq!(NAMED_IORS.len(), 23);
        // Mitsuba's default dielectric: bk7 inside air.
        let eta = ior_by_name("bk7").unwrap() / ior_by_name("air").unwrap();
        assert!((eta - 1.504183).abs() < 1e-5);
    }
}
