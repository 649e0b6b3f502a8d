use std::path::PathBuf;

use numpy::PyUntypedArrayMethods;
use numpy::{PyArray2, PyArray4, PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::{as_vec3s, to_numpy};
use crate::error::Error;
use crate::merl::{self, Lookup, N_PHI_D, N_THETA_D, N_THETA_H};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_merl, m)?)?;
    m.add_function(wrap_pyfunction!(write_merl, m)?)?;
    m.add_function(wrap_pyfunction!(merl_lookup, m)?)?;
    m.add_function(wrap_pyfunction!(merl_lookup_directions, m)?)?;
    m.add("CHANNEL_SCALES", merl::CHANNEL_SCALES)?;
    m.add("FILE_BYTES", merl::FILE_BYTES)?;
    Ok(())
}

/// Reads a MERL file into a float64 array `(3, 90, 90, 180)`.
#[pyfunction]
#[pyo3(signature = (path, physical_units = true))]
fn read_merl(py: Python<'_>, path: PathBuf, physical_units: bool) -> PyResult<Bound<'_, PyArray4<f64>>> {
    let values = py.detach(|| merl::read_merl(&path, physical_units))?;
    Ok(to_numpy(py, (3, N_THETA_H, N_THETA_D, N_PHI_D), values))
}

/// Writes a float64 array `(3, 90, 90, 180)` as a MERL file, atomically.
#[pyfunction]
#[pyo3(signature = (path, table, physical_units = true))]
fn write_merl(py: Python<'_>, path: PathBuf, table: PyReadonlyArrayDyn<'_, f64>, physical_units: bool) -> PyResult<()> {
    let shape = table.shape();
    if shape != [3, N_THETA_H, N_THETA_D, N_PHI_D] {
        return Err(Error::merl_format(
            &path,
            format!("cannot write an array of shape {shape:?}; a MERL table is (3, 90, 90, 180)"),
        )
        .into());
    }
    let values = table
        .as_slice()
        .map_err(|_| PyValueError::new_err("table must be C-contiguous"))?;
    py.detach(|| merl::write_merl(&path, values, physical_units))?;
    Ok(())
}

fn parse_method(method: &str) -> PyResult<Lookup> {
    match method {
        "nearest" => Ok(Lookup::Nearest),
        "trilinear" => Ok(Lookup::Trilinear),
        other => Err(PyValueError::new_err(format!(
            "method must be 'nearest' or 'trilinear', got {other:?}"
        ))),
    }
}

fn table_slice<'a>(table: &'a PyReadonlyArrayDyn<'_, f64>) -> PyResult<&'a [f64]> {
    if table.shape() != [3, N_THETA_H, N_THETA_D, N_PHI_D] {
        return Err(PyValueError::new_err(format!(
            "table must have shape (3, 90, 90, 180), got {:?}",
            table.shape()
        )));
    }
    table
        .as_slice()
        .map_err(|_| PyValueError::new_err("table must be C-contiguous"))
}

/// Looks up a table at `(n, 3)` angles (θ_h, θ_d, φ_d); returns `(n, 3)` RGB.
#[pyfunction]
fn merl_lookup<'py>(
    py: Python<'py>,
    table: PyReadonlyArrayDyn<'py, f64>,
    angles: PyReadonlyArray2<'py, f64>,
    method: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (table, angles, method) = (
        table_slice(&table)?,
        as_vec3s("angles", &angles)?,
        parse_method(method)?,
    );
    let rgb = py.detach(|| merl::lookup(table, angles, method))?;
    Ok(to_numpy(py, (rgb.len(), 3), rgb.into_flattened()))
}

/// Looks up a table at `(n, 3)` direction pairs; returns `(n, 3)` RGB.
#[pyfunction]
fn merl_lookup_directions<'py>(
    py: Python<'py>,
    table: PyReadonlyArrayDyn<'py, f64>,
    wi: PyReadonlyArray2<'py, f64>,
    wo: PyReadonlyArray2<'py, f64>,
    method: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let table = table_slice(&table)?;
    let (wi, wo, method) = (as_vec3s("wi", &wi)?, as_vec3s("wo", &wo)?, parse_method(method)?);
    let rgb = py.detach(|| merl::lookup_directions(table, wi, wo, method))?;
    Ok(to_numpy(py, (rgb.len(), 3), rgb.into_flattened()))
}
