//! BSDF plugins `null`, `diffuse` and `dielectric`, and Mitsuba 3's table of named indices of
//! refraction.

use super::params::Params;
use super::LoadError;
use crate::bsdf::Bsdf;
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

/// Builds a BSDF.
/// - `null`: no parameters.
/// - `diffuse`: `reflectance` (Mitsuba 3 default 0.5), each channel in [0, 1].
/// - `dielectric`: `int_ior` (default `"bk7"` = 1.5046) and `ext_ior` (`"air"` = 1.000277),
///   numbers or names from [`NAMED_IORS`]; `eta = int_ior / ext_ior`. Mitsuba's
///   `specular_reflectance`/`specular_transmittance` scale factors are accepted only at their
///   default 1, because haze's dielectric has no such factors.
pub(super) fn build(p: &Params) -> Result<Bsdf, LoadError> {
    let bsdf = match p.ty() {
        "diffuse" => {
            let reflectance = p.spectrum("reflectance", Rgb::splat(0.5))?;
            if reflectance.min_component() < 0.0 || reflectance.max_component() > 1.0 {
                return Err(p.error_at("reflectance", "'reflectance' must lie in [0, 1] in every channel"));
            }
            Bsdf::Diffuse { reflectance }
        }
        "dielectric" => {
            let int_ior = ior(p, "int_ior", "bk7")?;
            let ext_ior = ior(p, "ext_ior", "air")?;
            for name in ["specular_reflectance", "specular_transmittance"] {
                if let Some(v) = p.spectrum_opt(name)? {
                    if v != Rgb::ONE {
                        return Err(p.error_at(
                            name,
                            format!(
                                "unsupported: '{name}' other than 1 (haze's dielectric has no scale factors)"
                            ),
                        ));
                    }
                }
            }
            Bsdf::Dielectric { eta: int_ior / ext_ior }
        }
        _ => Bsdf::Null,
    };
    p.finish()?;
    Ok(bsdf)
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
    Ok(value)
}

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
