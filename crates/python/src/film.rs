//! `haze._haze.Film`: per-pixel sums and squared sums of a render, as numpy arrays, and the
//! exact merging of pass blocks.

use crate::value_error;
use haze_engine::passes::{merge_blocks, pass_blocks as engine_pass_blocks};
use haze_engine::render::Component;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The accumulated samples of a render: per pixel, for the image and (optionally) each
/// component, 3 sums and 3 squared sums in float64. Picklable (Ray sends it between processes).
#[pyclass(frozen, module = "haze._haze")]
pub struct Film {
    pub inner: haze_engine::render::Film,
}

fn component(name: Option<&str>) -> PyResult<Option<Component>> {
    let Some(name) = name else { return Ok(None) };
    match Component::ALL.into_iter().find(|c| c.name() == name) {
        Some(c) => Ok(Some(c)),
        None => {
            let names: Vec<_> = Component::ALL.iter().map(|c| c.name()).collect();
            Err(PyValueError::new_err(format!(
                "unknown component '{name}' (available: {})",
                names.join(", ")
            )))
        }
    }
}

impl Film {
    fn image<'py>(&self, py: Python<'py>, data: Vec<f32>) -> PyResult<Bound<'py, PyAny>> {
        let (w, h) = (self.inner.width as usize, self.inner.height as usize);
        Ok(PyArray1::from_vec(py, data).reshape([h, w, 3])?.into_any())
    }

    fn check_components(&self, c: Option<Component>) -> PyResult<()> {
        if c.is_some() && !self.inner.has_components() {
            return Err(PyValueError::new_err("this film has no components (render with components=True)"));
        }
        Ok(())
    }
}

#[pymethods]
impl Film {
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }

    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }

    /// Samples per pixel accumulated.
    #[getter]
    fn samples(&self) -> u64 {
        self.inner.samples
    }

    /// True if the film keeps the components (emitted, single, multiple, surface).
    #[getter]
    fn has_components(&self) -> bool {
        self.inner.has_components()
    }

    /// The mean image (float32, shape (H, W, 3)) of the whole image or of a component.
    #[pyo3(signature = (component=None))]
    fn mean<'py>(&self, py: Python<'py>, component: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let c = self::component(component)?;
        self.check_components(c)?;
        self.image(py, self.inner.mean(c))
    }

    /// The variance of the per-pixel mean (float32, shape (H, W, 3)).
    #[pyo3(signature = (component=None))]
    fn variance_of_mean<'py>(&self, py: Python<'py>, component: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
        let c = self::component(component)?;
        self.check_components(c)?;
        self.image(py, self.inner.variance_of_mean(c))
    }

    /// The raw sums (float64, shape (H, W, 6 * layers)): per layer 3 sums then 3 squared sums;
    /// layers are the image, then emitted, single, multiple, surface if the film has components.
    fn sums<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (w, h) = (self.inner.width as usize, self.inner.height as usize);
        let stride = self.inner.stride();
        Ok(PyArray1::from_slice(py, self.inner.data()).reshape([h, w, stride])?.into_any())
    }

    /// The film of `sums` (as `Film.sums` returns them) holding `samples` samples per pixel.
    #[staticmethod]
    fn from_sums(sums: PyReadonlyArray3<'_, f64>, samples: u64) -> PyResult<Film> {
        let shape = sums.shape();
        let (h, w, stride) = (shape[0], shape[1], shape[2]);
        let components = match stride {
            6 => false,
            30 => true,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "sums must have 6 or 30 values per pixel, got {stride}"
                )))
            }
        };
        let data = sums.as_array().iter().copied().collect();
        let film = haze_engine::render::Film::from_raw(w as u32, h as u32, components, data, samples)
            .map_err(PyValueError::new_err)?;
        Ok(Film { inner: film })
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let from_sums = py.get_type::<Film>().getattr("from_sums")?;
        let args = PyTuple::new(py, [self.sums(py)?, self.inner.samples.into_pyobject(py)?.into_any()])?;
        PyTuple::new(py, [from_sums, args.into_any()])
    }

    fn __repr__(&self) -> String {
        format!(
            "<haze.Film {}x{}, {} spp{}>",
            self.inner.width,
            self.inner.height,
            self.inner.samples,
            if self.inner.has_components() { ", with components" } else { "" }
        )
    }
}

/// Aligned blocks of at most `max_block` passes (rounded down to a power of two) covering the
/// passes `first .. first + count`, as (start, end) pairs: each is a node of the pass tree.
#[pyfunction]
pub fn pass_blocks(first: u32, count: u32, max_block: u32) -> Vec<(u32, u32)> {
    engine_pass_blocks(first..first.saturating_add(count), max_block)
        .into_iter()
        .map(|r| (r.start, r.end))
        .collect()
}

/// Merges the films of pass blocks `(start, end, film)` (from `pass_blocks`, each rendered by
/// `Scene.render_passes`) into the film of the passes `first .. first + count`: bit for bit
/// what `Scene.render_passes` over the whole range gives. Blocks may come in any order.
#[pyfunction]
pub fn merge_films(first: u32, count: u32, blocks: Vec<(u32, u32, PyRef<'_, Film>)>) -> PyResult<Film> {
    let blocks = blocks.into_iter().map(|(a, b, f)| (a..b, f.inner.clone())).collect();
    let film = merge_blocks(first..first.saturating_add(count), blocks).map_err(value_error)?;
    Ok(Film { inner: film })
}
