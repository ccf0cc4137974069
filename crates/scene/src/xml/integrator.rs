//! `<integrator>`: Mitsuba 3's `volpath`, `volpathmis` and `path`, the `moment` wrapper, and
//! haze's own `vrl`, `vpl`, `vrl_lightcuts` and `vpl_lightcuts`, with the parameters they share.
//!
//! An integrator type haze does not have (`direct`, `ptracer`, `aov`, `stokes`, ...) is not a
//! load error: a render that names its own integrator (`haze render --integrator`, the Python
//! `Scene.render(integrator=..)`) replaces it, and only a render with the scene's own
//! integrator fails, with the error kept in [`IntegratorSpec::unsupported`].

use super::context::Builder;
use super::document::Element;
use super::params::Params;
use super::{plugins, LoadError};
use crate::scene::IntegratorSpec;

/// The integrator of `<integrator>` element `el`.
pub(super) fn build<'a>(b: &Builder<'a>, el: &'a Element) -> Result<IntegratorSpec, LoadError> {
    let mut spec = match el.attr("type") {
        Some(ty) if plugins::parameters("integrator", ty).is_none() => unsupported(el, ty)?,
        _ => supported(b, &b.params(el)?)?,
    };
    spec.declared_at = Some(format!("{}:{}", el.source.file.display(), el.line));
    Ok(spec)
}

/// `max_depth` (Mitsuba 3 default -1 = unlimited; must be >= -1), `rr_depth` (5; must be > 0),
/// `hide_emitters` (false).
///
/// `moment` wraps one nested integrator and, in Mitsuba 3, adds the second moment of its
/// samples as AOVs; its mean image is the nested integrator's, so haze renders the nested
/// integrator (the per-pixel variance is available through `--variance-out`). Mitsuba accepts
/// several nested integrators; haze renders exactly one.
fn supported<'a>(b: &Builder<'a>, p: &Params<'a>) -> Result<IntegratorSpec, LoadError> {
    if p.ty() == "moment" {
        let nested = p.objects(&["integrator"]);
        let inner = match nested[..] {
            [one] => one,
            [] => return Err(p.element().error("'moment' needs one nested <integrator>")),
            [_, second, ..] => {
                return Err(second.site.error("haze's 'moment' renders one nested <integrator>, not several"))
            }
        };
        let spec = build(b, inner.target)?;
        p.finish()?;
        return Ok(spec);
    }
    let defaults = IntegratorSpec::default();
    let max_depth = p.int("max_depth", defaults.max_depth)?;
    check_max_depth(max_depth).map_err(|m| p.error_at("max_depth", m))?;
    let rr_depth = p.int("rr_depth", defaults.rr_depth as i32)?;
    check_rr_depth(rr_depth).map_err(|m| p.error_at("rr_depth", m))?;
    let hide_emitters = p.bool("hide_emitters", defaults.hide_emitters)?;
    p.finish()?;
    Ok(IntegratorSpec {
        name: p.ty().to_string(),
        max_depth,
        rr_depth: rr_depth as u32,
        hide_emitters,
        ..defaults
    })
}

fn check_max_depth(max_depth: i32) -> Result<(), String> {
    if max_depth < -1 {
        return Err(format!("'max_depth' must be -1 (unlimited) or >= 0, got {max_depth}"));
    }
    Ok(())
}

fn check_rr_depth(rr_depth: i32) -> Result<(), String> {
    if rr_depth <= 0 {
        return Err(format!("'rr_depth' must be > 0, got {rr_depth}"));
    }
    Ok(())
}

/// An integrator type haze does not have, kept for a render that replaces it. What an override
/// can honour is kept from it: a wrapper of exactly one nested `<integrator>` (Mitsuba's `aov`,
/// `stokes`) gives that one's settings; `direct` (emitted light plus direct illumination at the
/// first surface, Mitsuba 3's `direct` plugin) is `max_depth` 2; any other type gives the
/// `max_depth`, `rr_depth` and `hide_emitters` it sets, which Mitsuba's path-like integrators
/// (`ptracer`, `prb`, `prbvolpath`, ...) share. Its other parameters are not read.
fn unsupported(el: &Element, ty: &str) -> Result<IntegratorSpec, LoadError> {
    let nested: Vec<&Element> = el.children.iter().filter(|c| c.tag == "integrator").collect();
    let mut spec = match nested[..] {
        [inner] => match inner.attr("type") {
            Some(t) if plugins::parameters("integrator", t).is_none() => unsupported(inner, t)?,
            // A supported nested integrator: the parameters an override honours.
            _ => lenient(inner, IntegratorSpec::default())?,
        },
        _ => lenient(el, IntegratorSpec::default())?,
    };
    if ty == "direct" {
        spec.max_depth = 2;
    }
    spec.name = ty.to_string();
    spec.unsupported = Some(
        el.error(format!(
            "unsupported integrator type '{ty}' (supported: {}); --integrator replaces it",
            plugins::types_of("integrator")
        ))
        .to_string(),
    );
    Ok(spec)
}

/// `max_depth`, `rr_depth` and `hide_emitters` among the children of `el`, if given, checked as
/// for a supported integrator; other children are ignored.
fn lenient(el: &Element, mut spec: IntegratorSpec) -> Result<IntegratorSpec, LoadError> {
    for child in &el.children {
        let Some(name) = child.attr("name") else { continue };
        let value = || child.required_attr("value").map(str::trim);
        match (name, child.tag.as_str()) {
            ("max_depth", "integer") => {
                let v = value()?;
                let d: i32 =
                    v.parse().map_err(|_| child.error(format!("cannot parse '{v}' as an integer")))?;
                check_max_depth(d).map_err(|m| child.error(m))?;
                spec.max_depth = d;
            }
            ("rr_depth", "integer") => {
                let v = value()?;
                let d: i32 =
                    v.parse().map_err(|_| child.error(format!("cannot parse '{v}' as an integer")))?;
                check_rr_depth(d).map_err(|m| child.error(m))?;
                spec.rr_depth = d as u32;
            }
            ("hide_emitters", "boolean") => {
                spec.hide_emitters = match value()?.to_ascii_lowercase().as_str() {
                    "true" => true,
                    "false" => false,
                    v => return Err(child.error(format!("cannot parse '{v}' as a boolean (true or false)"))),
                };
            }
            _ => {}
        }
    }
    Ok(spec)
}
