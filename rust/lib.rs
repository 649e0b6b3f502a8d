//! Native core of frenbrdf. The modules below are pure Rust; `py` holds the thin PyO3
//! wrappers that make them `frenbrdf._native`.

pub mod bsdf;
pub mod coords;
pub mod error;
pub mod knn;
pub mod merl;
pub mod parallel;
pub mod refine;
pub mod sht;

#[cfg(feature = "python")]
mod py;
