//! The crate's one error type. Pure Rust: the mapping to Python exceptions lives in
//! `py/errors.rs`.

use std::path::{Path, PathBuf};

/// Everything that can go wrong in the native core.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused a file operation (missing file, permissions, …).
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A file or array does not follow the MERL binary format.
    #[error("{path}: {message}")]
    MerlFormat { path: PathBuf, message: String },

    /// A file does not follow the RGL `.bsdf` (`tensor_file`) format, or describes a
    /// material this crate cannot evaluate.
    #[error("{path}: {message}")]
    BsdfFormat { path: PathBuf, message: String },

    /// A caller passed an argument outside the function's domain.
    #[error("{0}")]
    InvalidArgument(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn merl_format(path: &Path, message: impl Into<String>) -> Self {
        Error::MerlFormat {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    pub(crate) fn bsdf_format(path: &Path, message: impl Into<String>) -> Self {
        Error::BsdfFormat {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Shorthand for `Err(Error::InvalidArgument(format!(...)))`.
macro_rules! invalid_argument {
    ($($arg:tt)*) => {
        Err($crate::error::Error::InvalidArgument(format!($($arg)*)))
    };
}
pub(crate) use invalid_argument;
