//! `haze._haze.Scene`: a loaded scene, and rendering it.

use crate::film::Film;
use crate::{interrupt, value_error, SceneError};
use haze_engine::passes::render_passes;
use haze_engine::scene::{load_file_with_sources, LoadError, LoadOptions};
use haze_engine::{prepare, Method, MethodKind, Options, Spelling};
use numpy::PyArrayMethods;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use std::path::PathBuf;
use std::sync::Arc;

/// A scene loaded from a Mitsuba 3 XML file (immutable; safe to share between threads).
#[pyclass(frozen, module = "haze._haze")]
pub struct Scene {
    pub inner: Arc<haze_engine::scene::Scene>,
    path: PathBuf,
    files: Vec<PathBuf>,
}

fn scene_error(py: Python<'_>, e: LoadError) -> PyErr {
    let err = SceneError::new_err(e.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception cannot fail in practice; the message has them all.
    let _ = value.setattr("file", e.file.display().to_string());
    let _ = value.setattr("line", e.line);
    let _ = value.setattr("column", e.column);
    let _ = value.setattr("element", e.element);
    err
}

/// Loads the scene file `path`; `defines` override its `<default>` parameters (`-D name=value`).
#[pyfunction]
#[pyo3(signature = (path, defines=Vec::new()))]
pub fn load_scene(py: Python<'_>, path: PathBuf, defines: Vec<(String, String)>) -> PyResult<Scene> {
    let options = LoadOptions { defines };
    let p = path.clone();
    let loaded = interrupt::run(py, move |_| load_file_with_sources(&p, &options))?;
    let (scene, files) = loaded.map_err(|e| scene_error(py, e))?;
    Ok(Scene { inner: Arc::new(scene), path, files })
}

/// The keyword options of a render (`**options` of the binding), as (name, text) pairs for
/// `haze_engine::options::resolve`: `None` values are left out (not given), `True`/`False` are
/// `true`/`false`, anything else its `str()`; the engine checks the text as it checks the
/// command line's.
fn given(options: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let mut out = Vec::new();
    if let Some(d) = options {
        for (k, v) in d.iter() {
            if v.is_none() {
                continue;
            }
            let text = if v.is_instance_of::<PyBool>() {
                if v.extract::<bool>()? { "true" } else { "false" }.to_string()
            } else {
                v.str()?.to_string()
            };
            out.push((k.extract::<String>()?, text));
        }
    }
    Ok(out)
}

/// The method `integrator` (default: the scene's own) with the `given` options.
fn method(
    scene: &haze_engine::scene::Scene,
    integrator: Option<&str>,
    given: &[(String, String)],
) -> anyhow::Result<(MethodKind, Method, Options)> {
    let pairs: Vec<(&str, &str)> = given.iter().map(|(n, v)| (n.as_str(), v.as_str())).collect();
    let (kind, options) = prepare(scene, integrator, &pairs, Spelling::Keyword)?;
    Ok((kind, Method::build(scene, kind, &options.method, options.seed)?, options))
}

#[pymethods]
impl Scene {
    /// The scene file this scene was loaded from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// Every file the scene read: the scene file first, then includes, meshes and images.
    #[getter]
    fn files(&self) -> Vec<PathBuf> {
        self.files.clone()
    }

    #[getter]
    fn width(&self) -> u32 {
        self.inner.camera.width
    }

    #[getter]
    fn height(&self) -> u32 {
        self.inner.camera.height
    }

    /// The scene's samples per pixel (its sampler's `sample_count`).
    #[getter]
    fn spp(&self) -> u32 {
        self.inner.spp
    }

    /// The scene's own integrator name.
    #[getter]
    fn integrator(&self) -> String {
        self.inner.integrator.name.clone()
    }

    /// Renders progressively (as `haze render` does) and returns the film. `options` are the
    /// engine's (`method_options()`), by name. Releases the GIL; Ctrl-C stops after the current
    /// pass and raises KeyboardInterrupt.
    #[pyo3(signature = (integrator=None, **options))]
    fn render(
        &self,
        py: Python<'_>,
        integrator: Option<String>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Film> {
        let given = given(options)?;
        let scene = self.inner.clone();
        // As `haze render`: one line on stderr when `integrator` replaces the scene's own.
        if let Some(note) = haze_engine::replacement_note(&scene, integrator.as_deref()) {
            eprintln!("{note}");
        }
        let out = interrupt::run(py, move |cancel| -> anyhow::Result<_> {
            let (kind, m, options) = method(&scene, integrator.as_deref(), &given)?;
            Ok(m.render(&scene, &options.render_settings(kind, &scene), cancel, |_| {}))
        })?
        .map_err(value_error)?;
        Ok(Film { inner: out.film })
    }

    /// Renders the passes `first .. first + count` (each of `spp_per_pass` samples) and sums
    /// them over the pass tree (`haze_engine::passes`): the film that merging any split of these
    /// passes rendered elsewhere gives, bit for bit. `options` as for `render`, without `spp` and
    /// `time` (the passes are the budget). Releases the GIL; Ctrl-C interrupts.
    #[pyo3(signature = (integrator=None, first=0, count=1, **options))]
    fn render_passes(
        &self,
        py: Python<'_>,
        integrator: Option<String>,
        first: u32,
        count: u32,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Film> {
        let given = given(options)?;
        if let Some((name, _)) = given.iter().find(|(n, _)| n == "spp" || n == "time") {
            return Err(PyValueError::new_err(format!(
                "render_passes renders `count` passes: {name} does not apply (use render)"
            )));
        }
        let scene = self.inner.clone();
        let out = interrupt::run(py, move |cancel| -> anyhow::Result<_> {
            let (kind, m, options) = method(&scene, integrator.as_deref(), &given)?;
            let end = first.checked_add(count).ok_or_else(|| anyhow::anyhow!("pass indices overflow"))?;
            render_passes(&m, &scene, &options.pass_settings(kind, &scene), first..end, cancel, |_| {})
        })?
        .map_err(value_error)?;
        Ok(Film { inner: out.film })
    }

    /// The mean cut size per pixel, float32 (H, W), of a lightcut method: one extra 1-spp pass
    /// (pass 0 with `seed`: the cuts of the image's first pass), as `haze render --cut-image`
    /// draws it. `options` as for `render`, without the sample budget (`spp`, `time`,
    /// `spp_per_pass`, `components`). Releases the GIL.
    #[pyo3(signature = (integrator=None, **options))]
    fn cut_sizes<'py>(
        &self,
        py: Python<'py>,
        integrator: Option<String>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let given = given(options)?;
        let budget = ["spp", "time", "spp_per_pass", "components"];
        if let Some((name, _)) = given.iter().find(|(n, _)| budget.contains(&n.as_str())) {
            return Err(PyValueError::new_err(format!(
                "cut_sizes renders one 1-spp pass: {name} does not apply"
            )));
        }
        let scene = self.inner.clone();
        let sizes = interrupt::run(py, move |_| -> anyhow::Result<_> {
            let (_, m, options) = method(&scene, integrator.as_deref(), &given)?;
            m.cut_sizes(&scene, options.seed, options.sampler_for(&scene))
        })?
        .map_err(value_error)?;
        let (w, h) = (self.inner.camera.width as usize, self.inner.camera.height as usize);
        Ok(numpy::PyArray1::from_vec(py, sizes).reshape([h, w])?.into_any())
    }

    /// Checks `options` for the method `integrator` as `render` would, without rendering, and
    /// returns the method's name (e.g. `volpath` for a scene whose integrator is `volpathmis`).
    #[pyo3(signature = (integrator=None, **options))]
    fn check_options(
        &self,
        integrator: Option<String>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<String> {
        let given = given(options)?;
        let pairs: Vec<(&str, &str)> = given.iter().map(|(n, v)| (n.as_str(), v.as_str())).collect();
        let (kind, _) =
            prepare(&self.inner, integrator.as_deref(), &pairs, Spelling::Keyword).map_err(value_error)?;
        Ok(kind.name().to_string())
    }

    /// The samples per pixel of each pass of a render with `integrator` (default: the scene's
    /// own) and `options` (checked as `render` checks them): `spp_per_pass` when given, else the
    /// engine's auto default for the method and this scene's image size
    /// (`haze_engine::options::auto_spp_per_pass`), as `haze render` would use.
    #[pyo3(signature = (integrator=None, **options))]
    fn spp_per_pass(&self, integrator: Option<String>, options: Option<&Bound<'_, PyDict>>) -> PyResult<u32> {
        let given = given(options)?;
        let pairs: Vec<(&str, &str)> = given.iter().map(|(n, v)| (n.as_str(), v.as_str())).collect();
        let (kind, options) =
            prepare(&self.inner, integrator.as_deref(), &pairs, Spelling::Keyword).map_err(value_error)?;
        Ok(options.spp_per_pass_for(kind, &self.inner))
    }

    fn __repr__(&self) -> String {
        format!(
            "<haze.Scene '{}' {}x{}, {} spp, integrator {}>",
            self.path.display(),
            self.inner.camera.width,
            self.inner.camera.height,
            self.inner.spp,
            self.inner.integrator.name
        )
    }
}
