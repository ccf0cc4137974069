//! `<integrator>`: Mitsuba 3's `volpath`, `volpathmis` and `path`, the `moment` wrapper, and
//! haze's own `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts`, with the parameters they share.

use super::params::Params;
use super::LoadError;
use crate::scene::IntegratorSpec;

/// `max_depth` (Mitsuba 3 default -1 = unlimited; must be >= -1), `rr_depth` (5; must be > 0),
/// `hide_emitters` (false).
///
/// `moment` wraps one nested integrator and, in Mitsuba 3, adds the second moment of its
/// samples as AOVs; its mean image is the nested integrator's, so haze renders the nested
/// integrator (the per-pixel variance is available through `--variance-out`). Mitsuba accepts
/// several nested integrators; haze renders exactly one.
pub(super) fn build(p: &Params) -> Result<IntegratorSpec, LoadError> {
    if p.ty() == "moment" {
        let nested = p.objects(&["integrator"]);
        let inner = match nested[..] {
            [one] => one,
            [] => return Err(p.element().error("'moment' needs one nested <integrator>")),
            [_, second, ..] => {
                return Err(second.site.error("haze's 'moment' renders one nested <integrator>, not several"))
            }
        };
        let spec = build(&p.nested(inner.target)?)?;
        p.finish()?;
        return Ok(spec);
    }
    let defaults = IntegratorSpec::default();
    let max_depth = p.int("max_depth", defaults.max_depth)?;
    if max_depth < -1 {
        return Err(
            p.error_at("max_depth", format!("'max_depth' must be -1 (unlimited) or >= 0, got {max_depth}"))
        );
    }
    let rr_depth = p.int("rr_depth", defaults.rr_depth as i32)?;
    if rr_depth <= 0 {
        return Err(p.error_at("rr_depth", format!("'rr_depth' must be > 0, got {rr_depth}")));
    }
    let hide_emitters = p.bool("hide_emitters", defaults.hide_emitters)?;
    p.finish()?;
    Ok(IntegratorSpec { name: p.ty().to_string(), max_depth, rr_depth: rr_depth as u32, hide_emitters })
}
