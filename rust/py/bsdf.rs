use std::path::PathBuf;

use numpy::{PyArray1, PyArray2, PyArray4, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use super::{as_vec3s, to_numpy};
use crate::bsdf::{MeasuredBsdf, Precision};
use crate::merl::{N_PHI_D, N_THETA_D, N_THETA_H};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<BsdfMeasurement>()?;
    m.add("BSDF_HORIZON", crate::bsdf::HORIZON)?;
    Ok(())
}

fn precision(double: bool) -> Precision {
    if double {
        Precision::Double
    } else {
        Precision::Single
    }
}

/// A measured RGB BRDF of the RGL material database (an `*_rgb.bsdf` file: Dupuy &
/// Jakob 2018's adaptive parameterisation in a `tensor_file`), ready to evaluate.
#[pyclass(frozen, module = "frenbrdf._native")]
struct BsdfMeasurement {
    inner: MeasuredBsdf,
}

#[pymethods]
impl BsdfMeasurement {
    /// Reads and checks a `.bsdf` file. Raises `FileNotFoundError` (and other `OSError`s)
    /// for the file system, `BsdfFormatError` for a malformed or spectral file.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py.detach(|| MeasuredBsdf::read(&path))?;
        Ok(BsdfMeasurement { inner })
    }

    /// The BRDF at `(n, 3)` direction pairs `wi`, `wo` (float64, C-contiguous, local
    /// frame with z the normal; normalised here): `(n, 3)` RGB reflectance in 1/sr, not
    /// multiplied by cos θ_o, negative measurements clamped to 0, and 0 where either
    /// direction is at or below the horizon. Computed in float32, vectorised across pairs,
    /// or with `double`, in float64 (several times slower, the reference).
    #[pyo3(signature = (wi, wo, double = false))]
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wi: PyReadonlyArray2<'py, f64>,
        wo: PyReadonlyArray2<'py, f64>,
        double: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (wi, wo) = (as_vec3s("wi", &wi)?, as_vec3s("wo", &wo)?);
        // NumPy's array, filled in place: NumPy backs it with huge pages. Not zeroed first
        // (0.93× the time of a call without it): `eval_into` writes every row or fails, and
        // on failure the array is dropped unseen.
        // SAFETY: f64 is trivially copyable, and no value is read before it is written.
        let rgb = unsafe { PyArray2::<f64>::new(py, [wi.len(), 3], false) };
        let mut values = rgb.readwrite();
        let rows = values.as_slice_mut()?.as_chunks_mut::<3>().0;
        py.detach(|| self.inner.eval_into(wi, wo, rows, precision(double)))?;
        Ok(rgb)
    }

    /// The BRDF at every MERL bin, as `eval` gives it: `(3, 90, 90, 180)` in 1/sr, with
    /// MERL's missing marker -1 where a bin's directions do not both lie strictly above
    /// the surface.
    #[pyo3(signature = (double = false))]
    fn merl_table<'py>(&self, py: Python<'py>, double: bool) -> PyResult<Bound<'py, PyArray4<f64>>> {
        // Not zeroed first, as in `eval`: `merl_table_into` writes every value.
        // SAFETY: f64 is trivially copyable, and no value is read before it is written.
        let table = unsafe { PyArray4::<f64>::new(py, [3, N_THETA_H, N_THETA_D, N_PHI_D], false) };
        let mut values = table.readwrite();
        let values = values.as_slice_mut()?;
        py.detach(|| self.inner.merl_table_into(values, precision(double)));
        Ok(table)
    }

    /// The file the measurement was read from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path().to_path_buf()
    }
    /// The file's `description` tensor, decoded as UTF-8 ('' if it has none).
    #[getter]
    fn description(&self) -> &str {
        self.inner.description()
    }
    /// Whether the material is isotropic (at most two incident azimuths measured).
    #[getter]
    fn isotropic(&self) -> bool {
        self.inner.isotropic()
    }
    /// 1, 2 or 4: an anisotropic measurement covers 2π / `reduction` of incident
    /// azimuths and is extended by mirror symmetry.
    #[getter]
    fn reduction(&self) -> u32 {
        self.inner.reduction()
    }
    /// Whether the stored RGB values are multiplied by D(m) / (4 σ(ω_i)).
    #[getter]
    fn jacobian(&self) -> bool {
        self.inner.jacobian()
    }
    /// Incident elevations (radians, float64) at which the material was measured.
    #[getter]
    fn theta_i<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let values: Vec<f64> = self.inner.theta_i().iter().map(|&v| v as f64).collect();
        to_numpy(py, values.len(), values)
    }
    /// Incident azimuths (radians, float64) at which the material was measured.
    #[getter]
    fn phi_i<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let values: Vec<f64> = self.inner.phi_i().iter().map(|&v| v as f64).collect();
        to_numpy(py, values.len(), values)
    }
    /// The values of the `rgb` field as stored (float32, flattened; its shape is in `fields`).
    #[getter]
    fn rgb<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        let values = self.inner.rgb().to_vec();
        to_numpy(py, values.len(), values)
    }
    /// Every tensor of the file: `{name: (dtype, shape)}`, dtype named as numpy names it.
    #[getter]
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let fields = PyDict::new(py);
        for field in self.inner.fields() {
            fields.set_item(&field.name, (field.dtype.name(), PyTuple::new(py, &field.shape)?))?;
        }
        Ok(fields)
    }

    fn __repr__(&self) -> String {
        format!(
            "BsdfMeasurement({:?}, description={:?}, isotropic={})",
            self.inner.path().display().to_string(),
            self.inner.description(),
            if self.inner.isotropic() { "True" } else { "False" }
        )
    }
}
