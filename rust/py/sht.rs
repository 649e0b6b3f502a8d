use std::mem::MaybeUninit;

use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
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

/// One of the plan's transforms into a given output: (plan, values, batch, out).
type Transform<T, Out> = fn(&Sht<T>, &[T], usize, &mut [Out]) -> Result<()>;

/// A value a transform writes, which decides how its output array is made. NumPy
/// allocates it either way, backing a large one with huge pages (a `Vec` faulted in page by
/// page cost a large share of a batched 256 × 512 analysis: research/performance.md).
trait OutputValue<T: numpy::Element>: Send + Sized {
    fn new_array(py: Python<'_>, dims: [usize; 2]) -> Bound<'_, PyArray2<T>>;
}

/// A transform that writes every value once: the array is left uninitialised.
impl<T: numpy::Element> OutputValue<T> for MaybeUninit<T> {
    fn new_array(py: Python<'_>, dims: [usize; 2]) -> Bound<'_, PyArray2<T>> {
        // SAFETY: only `MaybeUninit<T>` views of the values exist until the transform has
        // written them all.
        unsafe { PyArray2::<T>::new(py, dims, false) }
    }
}

/// A transform that takes initialised values: the array is zeroed.
impl<T: numpy::Element + Send> OutputValue<T> for T {
    fn new_array(py: Python<'_>, dims: [usize; 2]) -> Bound<'_, PyArray2<T>> {
        PyArray2::<T>::zeros(py, dims, false)
    }
}

/// Runs `transform` on a `(batch, n_in)` array of the plan's dtype into a new
/// `(batch, n_out)` array.
fn apply<'py, T: Real + numpy::Element, Out: OutputValue<T>>(
    py: Python<'py>,
    plan: &Sht<T>,
    array: &Bound<'py, PyAny>,
    [n_in, n_out]: [usize; 2],
    transform: Transform<T, Out>,
) -> PyResult<Bound<'py, PyAny>> {
    const { assert!(std::mem::size_of::<Out>() == std::mem::size_of::<T>()) };
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
    let out = Out::new_array(py, [batch, n_out]);
    // SAFETY: the new array is C-contiguous, `batch × n_out` values of T's layout (`Out`
    // is T or MaybeUninit<T>), and no one else holds it.
    let out_values = unsafe { std::slice::from_raw_parts_mut(out.data().cast::<Out>(), batch * n_out) };
    py.detach(|| transform(plan, values, batch, out_values))?;
    Ok(out.into_any())
}

macro_rules! dispatch {
    ($self:ident, $py:ident, $array:ident, $n_in:expr, $n_out:expr, $method:ident) => {
        match &$self.plan {
            Plan::F64(plan) => apply($py, plan, $array, [$n_in(plan), $n_out(plan)], Sht::<f64>::$method),
            Plan::F32(plan) => apply($py, plan, $array, [$n_in(plan), $n_out(plan)], Sht::<f32>::$method),
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
        dispatch!(self, py, maps, grid_points, coefficients, analysis_into)
    }

    fn synthesis<'py>(&self, py: Python<'py>, coeffs: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        dispatch!(self, py, coeffs, coefficients, grid_points, synthesis_into)
    }

    fn analysis_adjoint<'py>(&self, py: Python<'py>, coeffs: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        dispatch!(self, py, coeffs, coefficients, grid_points, analysis_adjoint_into)
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
