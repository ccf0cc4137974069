//! The rendering methods of `haze render --integrator` and `haze compare --method`: one place
//! that turns a method name and its options into an integrator and renders with it.

use anyhow::{bail, Result};
use haze_manylight::integrators::{
    surface_warning, LightBudget, LightKind, LightcutSettings, LightcutsIntegrator, ManyLightSettings,
    VplIntegrator, VrlIntegrator,
};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, PassReport, RenderOutput, RenderSettings};
use haze_render::{Integrator, VolPath};
use haze_scene::Scene;
use std::sync::atomic::AtomicBool;

/// Every method name accepted, for error messages.
pub const METHOD_NAMES: &str = "volpath, volpathmis, vrl, vpl, vrl_lightcuts, vpl_lightcuts";

/// Options of the many-light methods (ignored by volpath).
#[derive(Clone, Debug)]
pub struct MethodOptions {
    pub budget: LightBudget,
    /// vpl only: clamp of the geometry term (biased).
    pub vpl_clamp: Option<f32>,
    pub lightcuts: LightcutSettings,
}

impl Default for MethodOptions {
    fn default() -> Self {
        MethodOptions { budget: LightBudget::Vrls(10_000), vpl_clamp: None, lightcuts: Default::default() }
    }
}

impl MethodOptions {
    /// The options every front end offers, validated: about `vrls` VRLs per pass or exactly
    /// `light_paths` light paths (not both; default 10000 VRLs), and the lightcut `epsilon`
    /// (default 0.02). The rest keep their defaults.
    pub fn new(vrls: Option<u64>, light_paths: Option<u64>, epsilon: Option<f32>) -> Result<Self> {
        let budget = match (vrls, light_paths) {
            (Some(_), Some(_)) => bail!("give either vrls or light_paths, not both"),
            (Some(0), _) => bail!("vrls must be at least 1"),
            (_, Some(0)) => bail!("light_paths must be at least 1"),
            (Some(n), None) => LightBudget::Vrls(n),
            (None, Some(n)) => LightBudget::Paths(n),
            (None, None) => LightBudget::Vrls(10_000),
        };
        let mut options = MethodOptions { budget, ..Default::default() };
        if let Some(e) = epsilon {
            if !(e.is_finite() && e >= 0.0) {
                bail!("epsilon must be a number >= 0, got {e}");
            }
            options.lightcuts.cut.epsilon = e;
        }
        Ok(options)
    }
}

/// Render settings from a front end's arguments, validated: `spp` samples per pixel (default:
/// the scene's `sample_count`) or `time` seconds (not both).
pub fn render_settings(
    scene: &Scene,
    spp: Option<u32>,
    time: Option<f64>,
    seed: u64,
    spp_per_pass: u32,
    components: bool,
) -> Result<RenderSettings> {
    if spp.is_some() && time.is_some() {
        bail!("give either spp or time, not both");
    }
    if spp == Some(0) {
        bail!("spp must be at least 1");
    }
    if let Some(t) = time {
        if !(t.is_finite() && t > 0.0) {
            bail!("time must be a positive number of seconds, got {t}");
        }
    }
    if spp_per_pass == 0 {
        bail!("spp_per_pass must be at least 1");
    }
    Ok(RenderSettings {
        spp: if time.is_some() { 0 } else { spp.unwrap_or(scene.spp) },
        // `from_secs_f64` panics on overflow (`time=1e20`).
        time_limit: time
            .map(std::time::Duration::try_from_secs_f64)
            .transpose()
            .map_err(|_| anyhow::anyhow!("time {:e} s is too large", time.unwrap_or(0.0)))?,
        seed,
        spp_per_pass,
        components,
        first_pass: 0,
    })
}

/// A ready-to-render integrator of any kind.
pub enum Method {
    VolPath(VolPath),
    Vrl(VrlIntegrator),
    Vpl(VplIntegrator),
    Lightcuts(LightcutsIntegrator),
}

impl Method {
    /// Builds the integrator `name` for `scene`. Many-light methods fix their light-path count
    /// here (a pilot light-tracing run for `LightBudget::Vrls`) and print the surface warning
    /// of `surface_warning` to stderr.
    pub fn build(scene: &Scene, name: &str, options: &MethodOptions, seed: u64) -> Result<Method> {
        let many_light = || {
            if let Some(w) = surface_warning(scene) {
                eprintln!("warning: {w}");
            }
            ManyLightSettings {
                budget: options.budget,
                trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
            }
        };
        Ok(match name {
            "volpath" | "volpathmis" => Method::VolPath(VolPath::from_spec(&scene.integrator)),
            "path" if scene.media.is_empty() => Method::VolPath(VolPath::from_spec(&scene.integrator)),
            "path" => bail!(
                "integrator 'path' ignores participating media in Mitsuba 3; this scene has media: use volpath"
            ),
            "vrl" => Method::Vrl(VrlIntegrator::new(scene, many_light(), seed)?),
            "vpl" => Method::Vpl(VplIntegrator::new(scene, many_light(), seed, options.vpl_clamp)?),
            "vrl_lightcuts" | "vpl_lightcuts" => {
                let kind = if name == "vrl_lightcuts" { LightKind::Vrl } else { LightKind::Vpl };
                let lc = options.lightcuts;
                Method::Lightcuts(LightcutsIntegrator::new(scene, kind, many_light(), lc, seed)?)
            }
            other => bail!("unknown integrator '{other}' (available: {METHOD_NAMES})"),
        })
    }

    /// `progressive::render` with this integrator.
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        cancel: &AtomicBool,
        on_pass: impl FnMut(&PassReport),
    ) -> RenderOutput {
        match self {
            Method::VolPath(i) => render(scene, i, settings, cancel, on_pass),
            Method::Vrl(i) => render(scene, i, settings, cancel, on_pass),
            Method::Vpl(i) => render(scene, i, settings, cancel, on_pass),
            Method::Lightcuts(i) => render(scene, i, settings, cancel, on_pass),
        }
    }

    /// The integrator's line of statistics after rendering, if it has one.
    pub fn summary(&self) -> Option<String> {
        match self {
            Method::VolPath(i) => i.summary(),
            Method::Vrl(i) => i.summary(),
            Method::Vpl(i) => i.summary(),
            Method::Lightcuts(i) => i.summary(),
        }
    }

    /// Mean number of nodes per cut (per camera segment), for lightcut methods.
    pub fn mean_cut_size(&self) -> Option<f64> {
        match self {
            Method::Lightcuts(i) => Some(i.cut_statistics().0),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_validated() {
        assert_eq!(MethodOptions::new(None, None, None).unwrap().budget, LightBudget::Vrls(10_000));
        assert_eq!(MethodOptions::new(None, Some(7), None).unwrap().budget, LightBudget::Paths(7));
        assert_eq!(MethodOptions::new(None, None, Some(0.1)).unwrap().lightcuts.cut.epsilon, 0.1);
        assert!(MethodOptions::new(Some(1), Some(1), None).is_err());
        assert!(MethodOptions::new(Some(0), None, None).is_err());
        assert!(MethodOptions::new(None, None, Some(f32::NAN)).is_err());
    }
}
