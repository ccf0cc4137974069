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
