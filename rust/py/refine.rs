use numpy::{
    PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::to_numpy;
use crate::refine::{self, Loss};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<WeightFit>()?;
    Ok(())
}

/// Adam on one NBRDF's weights against a material's samples (the weight stage of
/// `frenbrdf.models.reconstruct`), forward, backward and update in one native loop.
#[pyclass(module = "frenbrdf._native")]
struct WeightFit {
    inner: refine::WeightFit,
}

/// A C-contiguous array's values.
fn contiguous<'a, T: numpy::Element, D: numpy::ndarray::Dimension>(
    name: &str,
    array: &'a numpy::PyReadonlyArray<'_, T, D>,
) -> PyResult<&'a [T]> {
    array
        .as_slice()
        .ok()
        .filter(|_| array.is_c_contiguous())
        .ok_or_else(|| PyValueError::new_err(format!("{name} must be C-contiguous")))
}

/// Sample indices as the fit takes them.
fn row_indices(indices: &[i64]) -> PyResult<Vec<u32>> {
    let converted: Option<Vec<u32>> = indices.iter().map(|&i| u32::try_from(i).ok()).collect();
    converted.ok_or_else(|| PyValueError::new_err("rows must lie in 0 to 2³² − 1"))
}

#[pymethods]
impl WeightFit {
    /// `tensors`: float32 weights `(out, in)` and biases `(out,)` of each layer in order,
    /// from 6 inputs to 3 outputs; `decays`: Adam's weight decay per tensor; samples:
    /// float32 `coords` `(N, 6)`, mapped `values` `(N, 3)`, `cos_in` `(N,)`; `loss`: 'l1'
    /// or 'mse'. Raises ValueError naming what does not fit.
    #[new]
    fn new(
        tensors: Vec<PyReadonlyArrayDyn<'_, f32>>,
        decays: Vec<f32>,
        coords: PyReadonlyArray2<'_, f32>,
        values: PyReadonlyArray2<'_, f32>,
        cos_in: PyReadonlyArray1<'_, f32>,
        loss: &str,
    ) -> PyResult<Self> {
        let loss = match loss {
            "l1" => Loss::L1,
            "mse" => Loss::Mse,
            other => {
                return Err(PyValueError::new_err(format!(
                    "loss must be 'l1' or 'mse', got {other:?}"
                )))
            }
        };
        let mut owned = Vec::with_capacity(tensors.len());
        for (index, tensor) in tensors.iter().enumerate() {
            owned.push((
                contiguous(&format!("tensor {index}"), tensor)?.to_vec(),
                tensor.shape().to_vec(),
            ));
        }
        for (name, array, width) in [
            ("coords", &coords, refine::N_INPUTS),
            ("values", &values, refine::N_OUTPUTS),
        ] {
            if array.shape()[1] != width {
                return Err(PyValueError::new_err(format!(
                    "{name} must have shape (N, {width}), got {:?}",
                    array.shape()
                )));
            }
        }
        let inner = refine::WeightFit::new(
            owned,
            &decays,
            contiguous("coords", &coords)?,
            contiguous("values", &values)?,
            contiguous("cos_in", &cos_in)?,
            loss,
        )?;
        Ok(WeightFit { inner })
    }

    /// One Adam step per learning rate (float32 `(steps,)`); `rows`: `(steps, batch)` sample
    /// indices, each step's batch, or None for every sample each step. Returns each step's
    /// loss before its update (float64; with the tie's term, if `tie` set one), stopping after
    /// the first that is not finite.
    #[pyo3(signature = (learning_rates, rows=None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        learning_rates: PyReadonlyArray1<'py, f32>,
        rows: Option<PyReadonlyArray2<'py, i64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let rates = contiguous("learning_rates", &learning_rates)?;
        let (rows, batch) = match &rows {
            None => (None, 0),
            Some(array) => (Some(row_indices(contiguous("rows", array)?)?), array.shape()[1]),
        };
        let inner = &mut self.inner;
        let losses = py.detach(|| inner.run(rates, rows.as_deref(), batch))?;
        Ok(to_numpy(py, losses.len(), losses))
    }

    /// The loss on `rows` (int64 `(batch,)` sample indices, or None for every sample; with the
    /// tie's term, if any) and its gradient (float32, flat), at the flat float32 `weights`
    /// (each tensor in the order given, flattened), which become the fit's weights; Adam's
    /// state is untouched.
    #[pyo3(signature = (weights, rows=None))]
    fn gradient<'py>(
        &mut self,
        py: Python<'py>,
        weights: PyReadonlyArray1<'py, f32>,
        rows: Option<PyReadonlyArray1<'py, i64>>,
    ) -> PyResult<(f64, Bound<'py, PyArray1<f32>>)> {
        let weights = contiguous("weights", &weights)?;
        let rows = match &rows {
            None => None,
            Some(array) => Some(row_indices(contiguous("rows", array)?)?),
        };
        let inner = &mut self.inner;
        let (loss, gradient) = py.detach(|| inner.gradient_at(weights, rows.as_deref()))?;
        Ok((loss, to_numpy(py, gradient.len(), gradient)))
    }

    /// Ties `pairs` (float32 `(P, 2, 6)`: pairs of NBRDF inputs) with `weight`: every step's
    /// loss adds `weight` times the mean over pairs and channels of |N(a) − N(b)| (its square
    /// for 'mse'), pulling each pair's two outputs together. A weight of 0 unties them.
    fn tie(&mut self, pairs: PyReadonlyArray3<'_, f32>, weight: f32) -> PyResult<()> {
        if pairs.shape()[1..] != [2, refine::N_INPUTS] {
            return Err(PyValueError::new_err(format!(
                "pairs must have shape (P, 2, {}), got {:?}",
                refine::N_INPUTS,
                pairs.shape()
            )));
        }
        Ok(self.inner.tie(contiguous("pairs", &pairs)?, weight)?)
    }

    /// Each tensor's values, flat (float32), in the order given.
    fn tensors<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray1<f32>>> {
        self.inner
            .tensors()
            .into_iter()
            .map(|t| to_numpy(py, t.len(), t))
            .collect()
    }
}
