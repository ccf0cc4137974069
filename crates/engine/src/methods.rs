//! The rendering methods of `haze render --integrator` and `haze compare --method`: one place
//! that turns a method and its options (`crate::options`) into an integrator and renders with it.

use crate::options::{method_names, resolve, MethodKind, Options, Spelling};
use anyhow::{anyhow, bail, Result};
use haze_manylight::integrators::{
    surface_warning, CutSizeProbe, LightBudget, LightKind, LightcutSettings, LightcutsIntegrator,
    ManyLightSettings, VplIntegrator, VrlIntegrator,
};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, PassReport, RenderOutput, RenderSettings};
use haze_render::{Integrator, VolPath};
use haze_scene::Scene;
use std::sync::atomic::AtomicBool;

/// Options of the many-light methods (volpath has none). Front ends make them with
/// [`crate::options::resolve`], which owns their defaults and checks.
#[derive(Clone, Debug)]
pub struct MethodOptions {
    pub budget: LightBudget,
    /// vpl only: clamp of the geometry term (biased).
    pub vpl_clamp: Option<f32>,
    pub lightcuts: LightcutSettings,
}

/// The method `name` names for `scene` (`None`: the scene's own `<integrator>`). `path` is
/// volpath for scenes without media (Mitsuba 3's `path` ignores media).
pub fn method_kind(scene: &Scene, name: Option<&str>) -> Result<MethodKind> {
    let name = name.unwrap_or(&scene.integrator.name);
    if name == "path" {
        if !scene.media.is_empty() {
            bail!("integrator 'path' ignores participating media in Mitsuba 3; this scene has media: use volpath");
        }
        return Ok(MethodKind::VolPath);
    }
    MethodKind::from_name(name)
        .ok_or_else(|| anyhow!("unknown integrator '{name}' (available: {})", method_names()))
}

/// What every front end does first: the method (`integrator`, default the scene's) and its
/// options from the `given` (name, text) pairs (see [`crate::options::resolve`]).
pub fn prepare(
    scene: &Scene,
    integrator: Option<&str>,
    given: &[(&str, &str)],
    spelling: Spelling,
) -> Result<(MethodKind, Options)> {
    let kind = method_kind(scene, integrator)?;
    Ok((kind, resolve(kind, given, spelling)?))
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
    pub fn build(scene: &Scene, kind: MethodKind, options: &MethodOptions, seed: u64) -> Result<Method> {
        let many_light = || {
            if let Some(w) = surface_warning(scene) {
                eprintln!("warning: {w}");
            }
            ManyLightSettings {
                budget: options.budget,
                trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
            }
        };
        Ok(match kind {
            MethodKind::VolPath => Method::VolPath(VolPath::from_spec(&scene.integrator)),
            MethodKind::Vrl => Method::Vrl(VrlIntegrator::new(scene, many_light(), seed)?),
            MethodKind::Vpl => Method::Vpl(VplIntegrator::new(scene, many_light(), seed, options.vpl_clamp)?),
            MethodKind::VrlLightcuts | MethodKind::VplLightcuts => {
                let light = if kind == MethodKind::VrlLightcuts { LightKind::Vrl } else { LightKind::Vpl };
                let lc = options.lightcuts;
                Method::Lightcuts(LightcutsIntegrator::new(scene, light, many_light(), lc, seed)?)
            }
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

    /// The mean cut size over each pixel's camera segments (row-major, 0 where the camera path
    /// meets no medium), from one extra 1-spp pass: pass 0 with `seed`, i.e. the lights and
    /// cuts of the image's first pass. Lightcut methods only.
    pub fn cut_sizes(&self, scene: &Scene, seed: u64) -> Result<Vec<f32>> {
        let Method::Lightcuts(integrator) = self else {
            bail!("cut sizes need a lightcut method ({})", crate::options::names(MethodKind::LIGHTCUTS));
        };
        let settings = RenderSettings { spp: 1, seed, ..Default::default() };
        let out = render(scene, &CutSizeProbe(integrator), &settings, &AtomicBool::new(false), |_| {});
        Ok(out.film.mean(None).chunks(3).map(|p| p[0]).collect())
    }

    /// Mean number of nodes per cut (per camera segment), for lightcut methods.
    pub fn mean_cut_size(&self) -> Option<f64> {
        match self {
            Method::Lightcuts(i) => Some(i.cut_statistics().0),
            _ => None,
        }
    }
}
