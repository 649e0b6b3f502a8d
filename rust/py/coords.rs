use numpy::PyUntypedArrayMethods;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::{as_vec3s, to_numpy};
use crate::coords::{self, Rusinkiewicz, Vec3};
use crate::merl;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(directions_to_rusinkiewicz, m)?)?;
    m.add_function(wrap_pyfunction!(rusinkiewicz_to_directions, m)?)?;
    m.add_function(wrap_pyfunction!(half_diff_vectors, m)?)?;
    m.add_function(wrap_pyfunction!(rusinkiewicz_to_half_diff, m)?)?;
    m.add_function(wrap_pyfunction!(merl_bin_to_angles, m)?)?;
    m.add_function(wrap_pyfunction!(merl_angles_to_bin, m)?)?;
    Ok(())
}

type Pair<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

fn vec3_rows<'py>(py: Python<'py>, rows: Vec<Vec3>) -> Bound<'py, PyArray2<f64>> {
    to_numpy(py, (rows.len(), 3), rows.into_flattened())
}

fn as_angle_rows<'a>(array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [Rusinkiewicz]> {
    if array.shape()[1] != 4 {
        return Err(PyValueError::new_err(format!(
            "angles must have shape (n, 4) = (θ_h, φ_h, θ_d, φ_d), got {:?}",
            array.shape()
        )));
    }
    let flat = array
        .as_slice()
        .map_err(|_| PyValueError::new_err("angles must be C-contiguous"))?;
    Ok(bytemuck::cast_slice(flat))
}

#[pyfunction]
fn directions_to_rusinkiewicz<'py>(
    py: Python<'py>,
    wi: PyReadonlyArray2<'py, f64>,
    wo: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (wi, wo) = (as_vec3s("wi", &wi)?, as_vec3s("wo", &wo)?);
    let angles = py.detach(|| coords::batch_to_rusinkiewicz(wi, wo))?;
    Ok(to_numpy(py, (angles.len(), 4), angles.into_flattened()))
}

#[pyfunction]
fn rusinkiewicz_to_directions<'py>(py: Python<'py>, angles: PyReadonlyArray2<'py, f64>) -> PyResult<Pair<'py>> {
    let angles = as_angle_rows(&angles)?;
    let (wi, wo) = py.detach(|| coords::batch_from_rusinkiewicz(angles))?;
    Ok((vec3_rows(py, wi), vec3_rows(py, wo)))
}

#[pyfunction]
fn half_diff_vectors<'py>(
    py: Python<'py>,
    wi: PyReadonlyArray2<'py, f64>,
    wo: PyReadonlyArray2<'py, f64>,
) -> PyResult<Pair<'py>> {
    let (wi, wo) = (as_vec3s("wi", &wi)?, as_vec3s("wo", &wo)?);
    let (h, d) = py.detach(|| coords::batch_half_diff(wi, wo))?;
    Ok((vec3_rows(py, h), vec3_rows(py, d)))
}

#[pyfunction]
fn rusinkiewicz_to_half_diff<'py>(py: Python<'py>, angles: PyReadonlyArray2<'py, f64>) -> PyResult<Pair<'py>> {
    let angles = as_angle_rows(&angles)?;
    let (h, d) = py.detach(|| coords::batch_half_diff_of_angles(angles))?;
    Ok((vec3_rows(py, h), vec3_rows(py, d)))
}

/// `(n, 3)` bin indices (may be fractional) → `(n, 3)` angles (θ_h, θ_d, φ_d).
#[pyfunction]
fn merl_bin_to_angles<'py>(py: Python<'py>, bins: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let bins = as_vec3s("bins", &bins)?;
    let angles: Vec<[f64; 3]> = py.detach(|| {
        bins.iter()
            .map(|&[h, d, p]| [merl::theta_h_of_bin(h), merl::theta_d_of_bin(d), merl::phi_d_of_bin(p)])
            .collect()
    });
    Ok(to_numpy(py, (angles.len(), 3), angles.into_flattened()))
}

/// `(n, 3)` angles (θ_h, θ_d, φ_d) → `(n, 3)` MERL bin indices (int64).
#[pyfunction]
fn merl_angles_to_bin<'py>(py: Python<'py>, angles: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let angles = as_vec3s("angles", &angles)?;
    if let Some(row) = angles.iter().position(|a| a.iter().any(|x| !x.is_finite())) {
        return Err(PyValueError::new_err(format!(
            "angles row {row} is not finite: {:?}",
            angles[row]
        )));
    }
    let bins: Vec<[i64; 3]> = py.detach(|| {
        angles
            .iter()
            .map(|&[h, d, p]| merl::bin_of_angles(h, d, p).map(|i| i as i64))
            .collect()
    });
    Ok(to_numpy(py, (bins.len(), 3), bins.into_flattened()))
}
