//! Rust errors → Python exceptions.

use std::io::ErrorKind;

use pyo3::exceptions::{PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyValueError};
use pyo3::PyErr;

use crate::error::Error;

// Defined in Python (frenbrdf/exceptions.py) so it has a docstring and a stable home.
pyo3::import_exception!(frenbrdf.exceptions, MerlFormatError);
pyo3::import_exception!(frenbrdf.exceptions, BsdfFormatError);

impl From<Error> for PyErr {
    fn from(error: Error) -> PyErr {
        let message = error.to_string();
        match error {
            Error::Io { path, source } => {
                // OSError(errno, strerror, filename) carries the path like Python's own errors.
                let arguments = (
                    source.raw_os_error().unwrap_or(0),
                    source.to_string(),
                    path.display().to_string(),
                );
                match source.kind() {
                    ErrorKind::NotFound => PyFileNotFoundError::new_err(arguments),
                    ErrorKind::PermissionDenied => PyPermissionError::new_err(arguments),
                    ErrorKind::IsADirectory => PyIsADirectoryError::new_err(arguments),
                    _ => PyOSError::new_err(arguments),
                }
            }
            Error::MerlFormat { .. } => MerlFormatError::new_err(message),
            Error::BsdfFormat { .. } => BsdfFormatError::new_err(message),
            Error::InvalidArgument(_) => PyValueError::new_err(message),
        }
    }
}
