//! `haze._haze`: the Python binding of haze. A thin layer over `haze-engine`: it converts
//! arguments and results (numpy arrays, Python exceptions) and runs renders off the GIL; every
//! decision about rendering lives in the engine. The Python package `haze` (python/haze) wraps
//! this module with keyword defaults, structured arrays and the Ray backend.
//!
//! Errors: scene-loading errors become `haze.SceneError` (the loader's message, with `file`,
//! `line`, `column`, `element` attributes); bad arguments `ValueError`; a panic inside the
//! renderer is caught on its thread and becomes `RuntimeError` (never unwinds into Python).

mod film;
mod interrupt;
mod scene;

use haze_engine::render::image_io::RgbImage;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

pyo3::create_exception!(
    haze,
    SceneError,
    PyException,
    "A scene file could not be loaded. The message names the file, line, column and element; \
     the attributes `file`, `line`, `column` and `element` hold them."
);

/// anyhow errors of the engine (bad arguments, emitters that cannot emit) as `ValueError`.
pub(crate) fn value_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
}

/// Checks two images for the metrics: same shape, last axis of 3 channels; returns the flat
/// float32 slices.
fn image_pair<'a>(
    approx: &'a PyReadonlyArrayDyn<'_, f32>,
    reference: &'a PyReadonlyArrayDyn<'_, f32>,
) -> PyResult<(&'a [f32], &'a [f32])> {
    if approx.shape() != reference.shape() {
        return Err(PyValueError::new_err(format!(
            "the images differ in shape: {:?} and {:?}",
            approx.shape(),
            reference.shape()
        )));
    }
    if approx.shape().last() != Some(&3) {
        return Err(PyValueError::new_err(format!(
            "images must have RGB as their last axis (shape (H, W, 3)), got {:?}",
            approx.shape()
        )));
    }
    let flat = |a: &'a PyReadonlyArrayDyn<'_, f32>| {
        a.as_slice().map_err(|_| PyValueError::new_err("images must be C-contiguous float32 arrays"))
    };
    Ok((flat(approx)?, flat(reference)?))
}

/// Root mean squared error over all pixels and channels (`haze_render::metrics::rmse`).
#[pyfunction]
fn rmse(approx: PyReadonlyArrayDyn<'_, f32>, reference: PyReadonlyArrayDyn<'_, f32>) -> PyResult<f64> {
    let (a, r) = image_pair(&approx, &reference)?;
    Ok(haze_engine::render::metrics::rmse(a, r, None))
}

/// Symmetric mean absolute percentage error in percent (`haze_render::metrics::smape`).
#[pyfunction]
fn smape(approx: PyReadonlyArrayDyn<'_, f32>, reference: PyReadonlyArrayDyn<'_, f32>) -> PyResult<f64> {
    let (a, r) = image_pair(&approx, &reference)?;
    Ok(haze_engine::render::metrics::smape(a, r, None))
}

/// Relative mean squared error with the 1e-2 guard (`haze_render::metrics::rel_mse`).
#[pyfunction]
fn relmse(approx: PyReadonlyArrayDyn<'_, f32>, reference: PyReadonlyArrayDyn<'_, f32>) -> PyResult<f64> {
    let (a, r) = image_pair(&approx, &reference)?;
    Ok(haze_engine::render::metrics::rel_mse(a, r, None))
}

/// The virtual lights of pass `pass_` traced with `paths` light paths and `seed`, as a dict of
/// plain arrays (`vrl_start`, `vrl_direction`, `vrl_length`, `vrl_flux`, `vrl_ratio`,
/// `vrl_medium`, `vrl_after_surface`, `vpl_position`, `vpl_direction`, `vpl_flux`,
/// `vpl_medium`, `vpl_after_surface`, `paths`).
#[pyfunction]
#[pyo3(signature = (scene, paths, seed=0, pass_=0))]
fn trace_lights<'py>(
    py: Python<'py>,
    scene: &scene::Scene,
    paths: u64,
    seed: u64,
    pass_: u32,
) -> PyResult<Bound<'py, PyDict>> {
    let s = scene.inner.clone();
    let set = interrupt::run(py, move |_| haze_engine::lights::trace_lights(&s, paths, seed, pass_))?
        .map_err(value_error)?;
    let vec3 = |v: Vec<[f32; 3]>| -> PyResult<Bound<'py, PyAny>> {
        let n = v.len();
        let flat: Vec<f32> = v.into_iter().flatten().collect();
        Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
    };
    let d = PyDict::new(py);
    let vrls = &set.vrls;
    d.set_item("vrl_start", vec3(vrls.iter().map(|r| r.o.to_array()).collect())?)?;
    d.set_item("vrl_direction", vec3(vrls.iter().map(|r| r.d.to_array()).collect())?)?;
    d.set_item("vrl_length", PyArray1::from_iter(py, vrls.iter().map(|r| r.len)))?;
    d.set_item("vrl_flux", vec3(vrls.iter().map(|r| r.beta.0).collect())?)?;
    d.set_item("vrl_ratio", vec3(vrls.iter().map(|r| r.ratio.0).collect())?)?;
    d.set_item("vrl_medium", PyArray1::from_iter(py, vrls.iter().map(|r| r.medium)))?;
    d.set_item("vrl_after_surface", PyArray1::from_iter(py, vrls.iter().map(|r| r.after_surface)))?;
    let vpls = &set.vpls;
    d.set_item("vpl_position", vec3(vpls.iter().map(|r| r.p.to_array()).collect())?)?;
    d.set_item("vpl_direction", vec3(vpls.iter().map(|r| r.d_in.to_array()).collect())?)?;
    d.set_item("vpl_flux", vec3(vpls.iter().map(|r| r.flux.0).collect())?)?;
    d.set_item("vpl_medium", PyArray1::from_iter(py, vpls.iter().map(|r| r.medium)))?;
    d.set_item("vpl_after_surface", PyArray1::from_iter(py, vpls.iter().map(|r| r.after_surface)))?;
    d.set_item("paths", set.paths)?;
    Ok(d)
}

/// The engine's table of options (`haze_engine::options::OPTIONS`), one dict per option:
/// `name`, `flag` (`--max-cut`), `kind` (`count`, `integer`, `number`, `number or word`,
/// `choice`, `flag`), `choices` (the words a `choice` or `number or word` takes, or None), `default` (the default as text, or None when unset),
/// `default_doc` (what the default is, in words), `help` (with the methods and the default),
/// `methods` (the methods it applies to), `scope` (`render`, `pass` or `method`), `conflicts_with`,
/// `requires` (`None` or `(option, value)`: the option applies only with that value),
/// `example` (a valid non-default value) and `python_default`: the default a Python signature
/// shows, the value itself for options of every method that have one, else None (not given).
#[pyfunction]
fn method_options(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    use haze_engine::options::{Default, Kind, Scope, Value, OPTIONS};
    OPTIONS
        .iter()
        .map(|o| {
            let d = PyDict::new(py);
            d.set_item("name", o.name)?;
            d.set_item("flag", o.flag())?;
            d.set_item("kind", o.kind.label())?;
            let choices = match o.kind {
                Kind::Choice(c) | Kind::PositiveOr(c) => Some(c.to_vec()),
                _ => None,
            };
            d.set_item("choices", choices)?;
            let (default, doc) = match o.default {
                Default::Value(v) => (Some(v), v),
                Default::Unset(what) => (None, what),
            };
            d.set_item("default", default)?;
            d.set_item("default_doc", doc)?;
            d.set_item("help", o.help_text())?;
            d.set_item("methods", o.applies_to.iter().map(|m| m.name()).collect::<Vec<_>>())?;
            let scope = match o.scope {
                Scope::Render => "render",
                Scope::Pass => "pass",
                Scope::Method => "method",
            };
            d.set_item("scope", scope)?;
            d.set_item("conflicts_with", o.conflicts_with.to_vec())?;
            d.set_item("example", o.example)?;
            d.set_item("requires", o.requires)?;
            let python_default = match (o.applies_to_all(), default.map(|v| o.kind.parse(v))) {
                (true, Some(Ok(Value::Int(n)))) => n.into_pyobject(py)?.into_any(),
                (true, Some(Ok(Value::Float(x)))) => x.into_pyobject(py)?.into_any(),
                (true, Some(Ok(Value::Word(w)))) => w.into_pyobject(py)?.into_any(),
                (true, Some(Ok(Value::Flag(b)))) => pyo3::types::PyBool::new(py, b).to_owned().into_any(),
                _ => py.None().into_bound(py),
            };
            d.set_item("python_default", python_default)?;
            Ok(d)
        })
        .collect()
}

/// Reads a linear-RGB OpenEXR image as a float32 array of shape (H, W, 3).
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let img =
        RgbImage::read_exr(&path).map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))?;
    Ok(PyArray1::from_vec(py, img.data).reshape([img.height, img.width, 3])?.into_any())
}

/// The flat data of an (H, W, 3) float32 image.
fn rgb_image(image: &PyReadonlyArrayDyn<'_, f32>) -> PyResult<RgbImage> {
    let shape = image.shape();
    if shape.len() != 3 || shape[2] != 3 {
        return Err(PyValueError::new_err(format!("images must have shape (H, W, 3), got {shape:?}")));
    }
    let data =
        image.as_slice().map_err(|_| PyValueError::new_err("images must be C-contiguous float32 arrays"))?;
    Ok(RgbImage::new(shape[1], shape[0], data.to_vec()))
}

/// Writes an (H, W, 3) float32 linear-RGB image as a 32-bit float OpenEXR file (non-finite
/// pixels are refused).
#[pyfunction]
fn write_exr(path: std::path::PathBuf, image: PyReadonlyArrayDyn<'_, f32>) -> PyResult<()> {
    rgb_image(&image)?.write_exr(&path).map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))
}

/// Writes an (H, W, 3) float32 linear-RGB image as an sRGB PNG, `exposure` in stops.
#[pyfunction]
#[pyo3(signature = (path, image, exposure=0.0))]
fn write_png(path: std::path::PathBuf, image: PyReadonlyArrayDyn<'_, f32>, exposure: f32) -> PyResult<()> {
    rgb_image(&image)?
        .write_png(&path, exposure)
        .map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))
}

/// The x86-64 target features beyond the baseline (x86-64-v1: SSE2) that this extension was
/// compiled with, empty for a portable build (docs/performance.md §5.1): a wheel built for the
/// building CPU would name AVX2 or AVX-512 here and could die of SIGILL on another CPU. The AVX2
/// node test is chosen at run time and does not count (it is not compiled in globally).
#[pyfunction]
fn compiled_features() -> Vec<&'static str> {
    macro_rules! enabled {
        ($($f:tt),*) => { [$((cfg!(target_feature = $f), $f)),*] };
    }
    let all = enabled!(
        "sse3",
        "ssse3",
        "sse4.1",
        "sse4.2",
        "popcnt",
        "cmpxchg16b",
        "avx",
        "avx2",
        "fma",
        "bmi1",
        "bmi2",
        "lzcnt",
        "movbe",
        "f16c",
        "avx512f",
        "avx512vl",
        "avx512bw"
    );
    all.into_iter().filter(|(on, _)| *on).map(|(_, f)| f).collect()
}

#[pymodule]
fn _haze(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    let names: Vec<&str> = haze_engine::MethodKind::ALL.iter().map(|m| m.name()).collect();
    m.add("METHOD_NAMES", PyTuple::new(m.py(), names)?)?;
    m.add_function(wrap_pyfunction!(method_options, m)?)?;
    m.add_function(wrap_pyfunction!(compiled_features, m)?)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<film::Film>()?;
    m.add_function(wrap_pyfunction!(scene::load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(film::merge_films, m)?)?;
    m.add_function(wrap_pyfunction!(film::pass_blocks, m)?)?;
    m.add_function(wrap_pyfunction!(trace_lights, m)?)?;
    m.add_function(wrap_pyfunction!(rmse, m)?)?;
    m.add_function(wrap_pyfunction!(smape, m)?)?;
    m.add_function(wrap_pyfunction!(relmse, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    Ok(())
}
