//! The rendering methods of `haze render --integrator` and `haze compare --method`: one place
//! that turns a method and its options (`crate::options`) into an integrator and renders with it.

pub use crate::options::MethodOptions;
use crate::options::{method_names, resolve, MethodKind, Options, Spelling, TreeCut};
use anyhow::{anyhow, bail, Result};
use haze_core::SamplerSpec;
use haze_manylight::integrators::{
    BoundCut, Clamps, CutSizeProbe, LightcutsIntegrator, ManyLightSettings, StochasticCut, VplIntegrator,
    Vpls, VrlIntegrator, Vrls,
};
use haze_manylight::lighttrace::LightTraceSettings;
use haze_render::progressive::{render, PassReport, RenderOutput, RenderSettings};
use haze_render::{Integrator, VolPath};
use haze_scene::Scene;
use std::sync::atomic::AtomicBool;

/// The method `name` names for `scene` (`None`: the scene's own `<integrator>`). `path` is
/// volpath for scenes without media (Mitsuba 3's `path` ignores media).
///
/// This is the one place a render's integrator is chosen: a given `name` replaces the scene's
/// `<integrator>`, whatever its type (haze loads scenes whose integrator it does not have,
/// `IntegratorSpec::unsupported`); without one, such a scene is an error naming the file and
/// line of its `<integrator>`. [`replacement_note`] says what a given name replaced.
pub fn method_kind(scene: &Scene, name: Option<&str>) -> Result<MethodKind> {
    if let (None, Some(e)) = (name, &scene.integrator.unsupported) {
        bail!("{e}");
    }
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

/// The one-line note a front end prints when the method `name` it was given replaces the
/// `<integrator>` the scene declares (of another type): which one, where, and the settings
/// kept from it (`max_depth`, `rr_depth`, `hide_emitters` apply to every method). `None` when
/// nothing was replaced.
pub fn replacement_note(scene: &Scene, name: Option<&str>) -> Option<String> {
    let spec = &scene.integrator;
    let (name, at) = (name?, spec.declared_at.as_ref()?);
    if name == spec.name {
        return None;
    }
    let mut kept = Vec::new();
    if spec.max_depth != -1 {
        kept.push(format!("max_depth {}", spec.max_depth));
    }
    if spec.rr_depth != 5 {
        kept.push(format!("rr_depth {}", spec.rr_depth));
    }
    if spec.hide_emitters {
        kept.push("hide_emitters".to_string());
    }
    let kept = if kept.is_empty() { String::new() } else { format!(", keeping its {}", kept.join(", ")) };
    Some(format!(
        "note: integrator '{name}' replaces the scene's <integrator type=\"{}\"> ({at}){kept}",
        spec.name
    ))
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

/// A ready-to-render integrator of any kind: one variant per method and, for the lightcut
/// methods, per tree cut (the integrator is generic over its cut strategy).
pub enum Method {
    VolPath(VolPath),
    Vrl(VrlIntegrator),
    Vpl(VplIntegrator),
    /// `vrl_lightcuts` with `cut=stochastic`.
    VrlLightcuts(LightcutsIntegrator<Vrls, StochasticCut>),
    /// `vpl_lightcuts` with `cut=stochastic`.
    VplLightcuts(LightcutsIntegrator<Vpls, StochasticCut>),
    /// `vrl_lightcuts` with `cut=bound`.
    VrlBoundCut(LightcutsIntegrator<Vrls, BoundCut>),
    /// `vpl_lightcuts` with `cut=bound`.
    VplBoundCut(LightcutsIntegrator<Vpls, BoundCut>),
}

/// `$body` with `$i` bound to the integrator of whichever variant `$method` is.
macro_rules! each_integrator {
    ($method:expr, $i:ident => $body:expr) => {
        match $method {
            Method::VolPath($i) => $body,
            Method::Vrl($i) => $body,
            Method::Vpl($i) => $body,
            Method::VrlLightcuts($i) => $body,
            Method::VplLightcuts($i) => $body,
            Method::VrlBoundCut($i) => $body,
            Method::VplBoundCut($i) => $body,
        }
    };
}

/// `$body` with `$i` bound to the lightcut integrator of `$method`, or `$other` for methods
/// without a tree cut.
macro_rules! each_lightcuts {
    ($method:expr, $i:ident => $body:expr, _ => $other:expr) => {
        match $method {
            Method::VrlLightcuts($i) => $body,
            Method::VplLightcuts($i) => $body,
            Method::VrlBoundCut($i) => $body,
            Method::VplBoundCut($i) => $body,
            Method::VolPath(_) | Method::Vrl(_) | Method::Vpl(_) => $other,
        }
    };
}

impl Method {
    /// Builds the integrator `name` for `scene`. Many-light methods fix their light-path count
    /// here (a pilot light-tracing run for `LightBudget::Vrls`).
    pub fn build(scene: &Scene, kind: MethodKind, options: &MethodOptions, seed: u64) -> Result<Method> {
        let many_light = || ManyLightSettings {
            budget: options.budget,
            trace: LightTraceSettings::from_max_depth(scene.integrator.max_depth),
            caustic_paths: options.caustic_paths,
            compensated_clamp: options.compensated_clamp.for_scene(scene, options.clamp),
            path_traced_media: options.path_traced_media,
        };
        // Name the method in a refusal (e.g. an environment emitter): "integrator 'vrl': ...".
        let named = |e: haze_scene::lights::EmissionError| anyhow!("integrator '{kind}': {e}");
        // The many-light methods connect light paths to the pinhole (their caustic paths splat
        // through it), which a thin lens or an orthographic camera does not have.
        if kind != MethodKind::VolPath && !scene.camera.is_pinhole() {
            bail!(
                "integrator '{kind}' needs a pinhole camera (sensor type 'perspective'); this scene's \
                 sensor is '{}': render it with volpath",
                scene.camera.plugin_name()
            );
        }
        if kind != MethodKind::VolPath && scene.emitters.iter().any(|e| e.is_textured_spot()) {
            bail!("integrator '{kind}' does not support spot lights with a 'texture' (render with volpath)");
        }
        if kind != MethodKind::VolPath
            && scene.emitters.iter().any(|e| matches!(e, haze_scene::emitter::Emitter::Projector(_)))
        {
            bail!("integrator '{kind}' does not support projector emitters (render with volpath)");
        }
        Ok(match kind {
            MethodKind::VolPath => Method::VolPath(VolPath::from_spec(&scene.integrator)),
            MethodKind::Vrl => {
                let mut i = VrlIntegrator::exhaustive(scene, many_light(), seed).map_err(named)?;
                i.clamps.surface = options.clamp;
                Method::Vrl(i)
            }
            MethodKind::Vpl => {
                let mut i = VplIntegrator::exhaustive(scene, many_light(), seed).map_err(named)?;
                i.clamps = Clamps { vpl: options.vpl_clamp, surface: options.clamp, ..i.clamps };
                Method::Vpl(i)
            }
            MethodKind::VrlLightcuts | MethodKind::VplLightcuts => {
                let lc = &options.lightcuts;
                let vrls = kind == MethodKind::VrlLightcuts;
                match lc.cut {
                    TreeCut::Stochastic if vrls => Method::VrlLightcuts(
                        LightcutsIntegrator::new(scene, many_light(), lc.stochastic, seed).map_err(named)?,
                    ),
                    TreeCut::Stochastic => Method::VplLightcuts(
                        LightcutsIntegrator::new(scene, many_light(), lc.stochastic, seed).map_err(named)?,
                    ),
                    TreeCut::Bound if vrls => Method::VrlBoundCut(
                        LightcutsIntegrator::new(scene, many_light(), lc.bound, seed).map_err(named)?,
                    ),
                    TreeCut::Bound => Method::VplBoundCut(
                        LightcutsIntegrator::new(scene, many_light(), lc.bound, seed).map_err(named)?,
                    ),
                }
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
        each_integrator!(self, i => render(scene, i, settings, cancel, on_pass))
    }

    /// The integrator's line of statistics after rendering, if it has one.
    pub fn summary(&self) -> Option<String> {
        each_integrator!(self, i => i.summary())
    }

    /// Per pixel (row-major, 0 where the camera path meets no medium), from one extra 1-spp
    /// pass (pass 0 with `seed`: the lights and cuts of the image's first pass), the mean over
    /// the pixel's camera segments of the cut size (`--cut bound`) or of the largest cut node's
    /// share of the cut's importance (`--cut stochastic`), with the image's sample generator
    /// `sampler` (its first sample). Lightcut methods only.
    pub fn cut_sizes(&self, scene: &Scene, seed: u64, sampler: SamplerSpec) -> Result<Vec<f32>> {
        let settings = RenderSettings { spp: 1, seed, sampler, ..Default::default() };
        let cancel = AtomicBool::new(false);
        let out = each_lightcuts!(
            self,
            i => render(scene, &CutSizeProbe(i), &settings, &cancel, |_| {}),
            _ => bail!("cut sizes need a lightcut method ({})", crate::options::names(MethodKind::LIGHTCUTS))
        );
        Ok(out.film.mean(None).chunks(3).map(|p| p[0]).collect())
    }

    /// The lightcut method's tree cut (`None` for other methods).
    pub fn tree_cut(&self) -> Option<TreeCut> {
        match self {
            Method::VrlLightcuts(_) | Method::VplLightcuts(_) => Some(TreeCut::Stochastic),
            Method::VrlBoundCut(_) | Method::VplBoundCut(_) => Some(TreeCut::Bound),
            Method::VolPath(_) | Method::Vrl(_) | Method::Vpl(_) => None,
        }
    }

    /// Seconds spent tracing light paths and building light trees, summed over passes, for
    /// lightcut methods (the rest of a render is gathering: the cuts and their lights).
    pub fn trace_and_build_seconds(&self) -> Option<(f64, f64)> {
        each_lightcuts!(self, i => Some((i.trace_seconds(), i.build_seconds())), _ => None)
    }

    /// `vrl`'s light paths per pass and its camera segment x VRL evaluations so far (each with
    /// its visibility test: the brute-force sum's unit of cost, which `haze bench` rates).
    /// `None` for other methods.
    pub fn vrl_evaluations(&self) -> Option<(u64, u64)> {
        match self {
            Method::Vrl(i) => Some((i.paths_per_pass(), i.evaluations())),
            _ => None,
        }
    }

    /// Mean number of nodes per cut (per camera segment), for lightcut methods.
    pub fn mean_cut_size(&self) -> Option<f64> {
        each_lightcuts!(self, i => Some(i.cut_statistics().0), _ => None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(integrator: &str) -> Scene {
        let xml = format!(r#"<scene version="3.0.0"><sensor type="perspective"/>{integrator}</scene>"#);
        let p = std::path::Path::new("t.xml");
        haze_scene::load_str(&xml, p, std::path::Path::new("."), &haze_scene::LoadOptions::default()).unwrap()
    }

    /// A given method replaces any scene integrator, one haze does not have included, with one
    /// note; without one, an unsupported scene integrator is the loader's located error.
    #[test]
    fn a_given_method_replaces_the_scene_integrator() {
        let direct = scene(r#"<integrator type="direct"/>"#);
        let e = method_kind(&direct, None).unwrap_err().to_string();
        assert!(e.starts_with("t.xml:1:") && e.contains("unsupported integrator type 'direct'"), "{e}");
        assert_eq!(method_kind(&direct, Some("vrl")).unwrap(), MethodKind::Vrl);
        assert_eq!(
            replacement_note(&direct, Some("volpath")).as_deref(),
            Some("note: integrator 'volpath' replaces the scene's <integrator type=\"direct\"> (t.xml:1), keeping its max_depth 2")
        );
        assert_eq!(replacement_note(&direct, None), None, "nothing replaced");

        let volpath = scene(r#"<integrator type="volpath"/>"#);
        assert_eq!(replacement_note(&volpath, Some("volpath")), None, "the same type is no replacement");
        assert!(replacement_note(&volpath, Some("vpl")).is_some_and(|n| !n.contains("keeping")));
        assert_eq!(replacement_note(&scene(""), Some("vpl")), None, "no <integrator> to replace");
        assert_eq!(method_kind(&volpath, None).unwrap(), MethodKind::VolPath);
        // An unknown method name stays an error.
        assert!(method_kind(&direct, Some("bdpt"))
            .unwrap_err()
            .to_string()
            .contains("unknown integrator 'bdpt'"));
    }
}
