use numpy::PyUntypedArrayMethods;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::to_numpy;
use crate::error::Result;
use crate::sht::{Grid, Real, Sht};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ShtPlan>()?;
    Ok(())
}

enum Plan {
    F64(Sht<f64>),
    F32(Sht<f32>),
}

/// A spherical harmonic transform plan. Arrays are 2-D: `(batch, nlat·nlon)` maps,
/// `(batch, (lmax+1)²)` coefficients, in the plan's dtype.
#[pyclass(frozen, module = "frenbrdf._native")]
struct ShtPlan {
    plan: Plan,
}

/// One of the plan's transforms: (plan, values, batch) → values.
type Transform<T> = fn(&Sht<T>, &[T], usize) -> Result<Vec<T>>;

/// Runs `transform` on a `(batch, n_in)` array of the plan's dtype.
fn apply<'py, T: Real + numpy::Element>(
    py: Python<'py>,
    plan: &Sht<T>,
    array: &Bound<'py, PyAny>,
    n_in: usize,
    n_out: usize,
    transform: Transform<T>,
) -> PyResult<Bound<'py, PyAny>> {
    let array: PyReadonlyArray2<'py, T> = array.extract()?;
    let (batch, width) = (array.shape()[0], array.shape()[1]);
    if width != n_in {
        return Err(PyValueError::new_err(format!(
            "expected (batch, {n_in}) values, got {:?}",
            array.shape()
        )));
    }
    let values = array
        .as_slice()
        .map_err(|_| PyValueError::new_err("array must be C-contiguous"))?;
    let out = py.detach(|| transform(plan, values, batch))?;
    Ok(to_numpy(py, (batch, n_out), out).into_any())
}

macro_rules! dispatch {
    ($self:ident, $py:ident, $array:ident, $n_in:expr, $n_out:expr, $method:ident) => {
        match &$self.plan {
            Plan::F64(plan) => apply($py, plan, $array, $n_in(plan), $n_out(plan), Sht::<f64>::$method),
            Plan::F32(plan) => apply($py, plan, $array, $n_in(plan), $n_out(plan), Sht::<f32>::$method),
        }
    };
}

fn grid_points<T: Real>(plan: &Sht<T>) -> usize {
    plan.nlat() * plan.nlon()
}
fn coefficients<T: Real>(plan: &Sht<T>) -> usize {
    plan.n_coefficients()
}

#[pymethods]
impl ShtPlan {
    #[new]
    fn new(py: Python<'_>, nlat: usize, nlon: usize, lmax: usize, grid: &str, dtype: &str) -> PyResult<Self> {
        let grid = match grid {
            "gauss" => Grid::GaussLegendre,
            "equiangular" => Grid::Equiangular,
            other => {
                return Err(PyValueError::new_err(format!(
                    "grid must be 'gauss' or 'equiangular', got {other:?}"
                )))
            }
        };
        let plan = match dtype {
            "float64" => Plan::F64(py.detach(|| Sht::new(nlat, nlon, lmax, grid))?),
            "float32" => Plan::F32(py.detach(|| Sht::new(nlat, nlon, lmax, grid))?),
            other => {
                return Err(PyValueError::new_err(format!(
                    "dtype must be 'float64' or 'float32', got {other:?}"
                )))
            }
        };
        Ok(ShtPlan { plan })
    }

    fn analysis<'py>(&self, py: Python<'py>, maps: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        dispatch!(self, py, maps, grid_points, coefficients, analysis)
    }

    fn synthesis<'py>(&self, py: Python<'py>, coeffs: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        dispatch!(self, py, coeffs, coefficients, grid_points, synthesis)
    }

    fn analysis_adjoint<'py>(&self, py: Python<'py>, coeffs: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        dispatch!(self, py, coeffs, coefficients, grid_points, analysis_adjoint)
    }

    /// `((lmax+1)², 2)` int64: (l, m) per coefficient, sine parts as −m.
    fn degrees_orders<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let pairs = match &self.plan {
            Plan::F64(plan) => plan.degrees_orders(),
            Plan::F32(plan) => plan.degrees_orders(),
        };
        to_numpy(py, (pairs.len(), 2), pairs.into_flattened())
    }

    /// Ring colatitudes θ_j and quadrature weights (Σ = 2).
    fn rings<'py>(&self, py: Python<'py>) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>) {
        let (theta, weights) = match &self.plan {
            Plan::F64(plan) => (plan.theta().to_vec(), plan.weights().to_vec()),
            Plan::F32(plan) => (plan.theta().to_vec(), plan.weights().to_vec()),
        };
        (PyArray1::from_vec(py, theta), PyArray1::from_vec(py, weights))
    }
}
