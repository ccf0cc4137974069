//! Medium plugin `homogeneous` and phase function plugins `isotropic` and `hg`.

use super::params::Params;
use super::LoadError;
use crate::medium::Medium;
use haze_core::{Phase, Rgb};

/// Builds a `homogeneous` medium named `name`. Parameters (Mitsuba 3 defaults): `sigma_t`
/// (1, per unit length, >= 0), `albedo` (0.75, in [0, 1]), `scale` (1, >= 0, multiplies
/// `sigma_t`), one nested `<phase>` (isotropic), `sample_emitters` (true; haze always samples
/// emitters, so `false` is unsupported). `sigma_t` and `albedo` are RGB, or a float for grey.
pub(super) fn build(p: &Params, name: String) -> Result<Medium, LoadError> {
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
    if !p.bool("sample_emitters", true)? {
        return Err(p.error_at(
            "sample_emitters",
            "unsupported: sample_emitters=false (haze always samples emitters in media)",
        ));
    }
    let phases = p.objects(&["phase"]);
    if let Some(second) = phases.get(1) {
        return Err(second
            .site
            .error(format!("a medium takes one <phase>; another is at line {}", phases[0].site.line)));
    }
    let phase = match phases.first() {
        Some(o) => phase(&p.nested(o.target)?)?,
        None => Phase::Isotropic,
    };
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
    Ok(Medium { name, sigma_t, albedo, phase })
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
