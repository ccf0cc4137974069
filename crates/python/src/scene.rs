//! `haze._haze.Scene`: a loaded scene, and rendering it.

use crate::film::Film;
use crate::{interrupt, value_error, SceneError};
use haze_engine::methods::{render_settings, Method, MethodOptions};
use haze_engine::passes::{render_passes, PassSettings};
use haze_engine::scene::{load_file_with_sources, LoadError, LoadOptions};
use pyo3::prelude::*;
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

/// The method `integrator` (default: the scene's own) with its options.
fn method(
    scene: &haze_engine::scene::Scene,
    integrator: Option<String>,
    options: &MethodOptions,
    seed: u64,
) -> anyhow::Result<Method> {
    let name = integrator.unwrap_or_else(|| scene.integrator.name.clone());
    Method::build(scene, &name, options, seed)
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

    /// Renders progressively (as `haze render` does) and returns the film. Releases the GIL;
    /// Ctrl-C stops after the current pass and raises KeyboardInterrupt.
    #[pyo3(signature = (integrator=None, spp=None, time=None, seed=0, vrls=None, light_paths=None,
                        epsilon=None, components=false, spp_per_pass=1))]
    #[allow(clippy::too_many_arguments)]
    fn render(
        &self,
        py: Python<'_>,
        integrator: Option<String>,
        spp: Option<u32>,
        time: Option<f64>,
        seed: u64,
        vrls: Option<u64>,
        light_paths: Option<u64>,
        epsilon: Option<f32>,
        components: bool,
        spp_per_pass: u32,
    ) -> PyResult<Film> {
        let scene = self.inner.clone();
        let out = interrupt::run(py, move |cancel| -> anyhow::Result<_> {
            let settings = render_settings(&scene, spp, time, seed, spp_per_pass, components)?;
            let options = MethodOptions::new(vrls, light_paths, epsilon)?;
            let m = method(&scene, integrator, &options, seed)?;
            Ok(m.render(&scene, &settings, cancel, |_| {}))
        })?
        .map_err(value_error)?;
        Ok(Film { inner: out.film })
    }

    /// Renders the passes `first .. first + count` (each of `spp_per_pass` samples) and sums
    /// them over the pass tree (`haze_engine::passes`): the film that merging any split of these
    /// passes rendered elsewhere gives, bit for bit. Releases the GIL; Ctrl-C interrupts.
    #[pyo3(signature = (integrator=None, first=0, count=1, spp_per_pass=1, seed=0, vrls=None,
                        light_paths=None, epsilon=None, components=false))]
    #[allow(clippy::too_many_arguments)]
    fn render_passes(
        &self,
        py: Python<'_>,
        integrator: Option<String>,
        first: u32,
        count: u32,
        spp_per_pass: u32,
        seed: u64,
        vrls: Option<u64>,
        light_paths: Option<u64>,
        epsilon: Option<f32>,
        components: bool,
    ) -> PyResult<Film> {
        let scene = self.inner.clone();
        let out = interrupt::run(py, move |cancel| -> anyhow::Result<_> {
            let options = MethodOptions::new(vrls, light_paths, epsilon)?;
            let m = method(&scene, integrator, &options, seed)?;
            let settings = PassSettings { seed, spp_per_pass, components };
            let end = first.checked_add(count).ok_or_else(|| anyhow::anyhow!("pass indices overflow"))?;
            render_passes(&m, &scene, &settings, first..end, cancel, |_| {})
        })?
        .map_err(value_error)?;
        Ok(Film { inner: out.film })
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
