//! `frenbrdf._native`: thin PyO3 wrappers around the pure-Rust core. Each wrapper
//! checks shapes, releases the GIL for the heavy work, and maps errors.

mod bsdf;
mod coords;
mod errors;
mod knn;
mod merl;
mod refine;
mod sht;

use numpy::ndarray::{Array, Dimension, ShapeBuilder};
use numpy::PyUntypedArrayMethods;
use numpy::{IntoPyArray, PyArray, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::coords::Vec3;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(num_threads, m)?)?;
    merl::register(m)?;
    coords::register(m)?;
    knn::register(m)?;
    sht::register(m)?;
    bsdf::register(m)?;
    refine::register(m)?;
    Ok(())
}

/// Threads the native core runs on (rayon's pool; set `RAYON_NUM_THREADS` to change).
#[pyfunction]
fn num_threads() -> usize {
    rayon::current_num_threads()
}

/// Moves `data` into a numpy array of `shape` without copying.
fn to_numpy<'py, T: numpy::Element, D: Dimension>(
    py: Python<'py>,
    shape: impl ShapeBuilder<Dim = D>,
    data: Vec<T>,
) -> Bound<'py, PyArray<T, D>> {
    Array::from_shape_vec(shape, data)
        .expect("the shape matches the data by construction")
        .into_pyarray(py)
}

/// Views an `(n, 3)` C-contiguous float64 array as rows of 3-vectors.
fn as_vec3s<'a>(name: &str, array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [Vec3]> {
    let shape = array.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (n, 3), got {shape:?}"
        )));
    }
    // `as_slice` also accepts Fortran order, which would be read transposed.
    let flat = (array.as_slice().ok())
        .filter(|_| array.is_c_contiguous())
        .ok_or_else(|| PyValueError::new_err(format!("{name} must be C-contiguous")))?;
    Ok(bytemuck::cast_slice(flat))
}
