use numpy::PyUntypedArrayMethods;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use super::{as_vec3s, to_numpy};
use crate::knn;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<KnnInterpolator>()?;
    Ok(())
}

/// Precomputed kNN Gaussian interpolation from `src` to `dst` points on the sphere.
#[pyclass(frozen, module = "frenbrdf._native")]
struct KnnInterpolator {
    inner: knn::KnnInterpolator,
}

#[pymethods]
impl KnnInterpolator {
    #[new]
    fn new(
        py: Python<'_>,
        src: PyReadonlyArray2<'_, f64>,
        dst: PyReadonlyArray2<'_, f64>,
        k: usize,
        sigma: f64,
    ) -> PyResult<Self> {
        let (src, dst) = (as_vec3s("src", &src)?, as_vec3s("dst", &dst)?);
        let inner = py.detach(|| knn::KnnInterpolator::new(src, dst, k, sigma))?;
        Ok(KnnInterpolator { inner })
    }

    /// `(n_src, channels)` values → `(n_dst, channels)`.
    fn apply<'py>(&self, py: Python<'py>, values: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let channels = values.shape()[1];
        let flat = values
            .as_slice()
            .map_err(|_| pyo3::exceptions::PyValueError::new_err("values must be C-contiguous"))?;
        let out = py.detach(|| self.inner.apply(flat, channels))?;
        Ok(to_numpy(py, (self.inner.n_targets(), channels), out))
    }

    #[getter]
    fn k(&self) -> usize {
        self.inner.k()
    }
    #[getter]
    fn n_src(&self) -> usize {
        self.inner.n_sources()
    }
    #[getter]
    fn n_dst(&self) -> usize {
        self.inner.n_targets()
    }
    /// Neighbour indices `(n_dst, k)`, nearest first.
    #[getter]
    fn indices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let indices = self.inner.indices().iter().map(|&i| i as i64).collect();
        to_numpy(py, (self.inner.n_targets(), self.inner.k()), indices)
    }
    /// Normalised weights `(n_dst, k)`; each row sums to 1.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_numpy(
            py,
            (self.inner.n_targets(), self.inner.k()),
            self.inner.weights().to_vec(),
        )
    }
}
