//! Measured BRDFs of the RGL material database: the RGB `.bsdf` files of Dupuy & Jakob,
//! "An Adaptive Parameterization for Efficient Material Acquisition and Rendering",
//! ACM TOG 37(6), 2018.
//!
//! A file is a [`tensor_file`] with, for an incident direction at angles
//! (`phi_i`, `theta_i`):
//! - `vndf` `(n_phi_i, n_theta_i, ny, nx)`: the visible normal distribution over the
//!   half vector's (√(2θ_m/π), φ_m), φ_m relative to φ_i for isotropic materials;
//!   its warp ([`warp::Marginal2D`]) defines the "sample" space in which
//! - `rgb` `(n_phi_i, n_theta_i, 3, ny', nx')` stores the reflectance;
//! - `ndf` and `sigma` `(2, n)`: the microfacet normal distribution and the projected
//!   area, for the Jacobian factor D(m) / (4 σ(ω_i)) applied when `jacobian` is 1;
//! - `description`, and `luminance`/`spectra`/`wavelengths`/`valid`, not needed here.
//!
//! [`MeasuredBsdf::read`] reads and checks a file; [`MeasuredBsdf::eval`] evaluates it,
//! in float64 one pair at a time ([`eval`]) or in float32 across pairs ([`batch`]);
//! [`MeasuredBsdf::merl_table`] tabulates it at the bins of a MERL file.

mod batch;
#[cfg(test)]
mod batch_tests;
mod eval;
#[cfg(target_arch = "x86_64")]
mod gather;
mod merl_table;
mod simd;
pub mod synthetic;
pub mod tensor_file;
pub mod warp;

use std::f32::consts::FRAC_PI_2;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::error::Result;
pub use eval::HORIZON;
use tensor_file::{Dtype, Field, TensorFile};
use warp::{Interpolant, Marginal2D, ParamAxes};

/// The arithmetic of [`MeasuredBsdf::eval`] and [`MeasuredBsdf::merl_table`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// float32, vectorised across pairs: several times faster, and within about 1e-5
    /// (relative) of `Double` where the value is not tiny.
    Single,
    /// float64, one pair at a time ([`MeasuredBsdf::eval_pair`]): the reference.
    Double,
}

/// A measured RGB BRDF, ready to evaluate.
#[derive(Clone, Debug)]
pub struct MeasuredBsdf {
    path: PathBuf,
    description: String,
    fields: Vec<Field>,
    theta_i: Vec<f32>,
    phi_i: Vec<f32>,
    isotropic: bool,
    /// Symmetry of an anisotropic measurement: `phi_i` covers 2π / `reduction`.
    reduction: u32,
    jacobian: bool,
    ndf: Interpolant,
    sigma: Interpolant,
    vndf: Marginal2D,
    rgb: Interpolant,
    /// The tables rearranged for the float32 path, built on its first use.
    batch: OnceLock<batch::Tables>,
}

impl MeasuredBsdf {
    /// Reads an RGB `.bsdf` file.
    pub fn read(path: &Path) -> Result<MeasuredBsdf> {
        MeasuredBsdf::from_tensor_file(&TensorFile::read(path)?)
    }

    /// Checks the fields of a parsed file and builds the evaluator.
    pub fn from_tensor_file(file: &TensorFile) -> Result<MeasuredBsdf> {
        if file.field("rgb").is_none() && file.field("spectra").is_some() {
            return Err(file.error(
                "is a spectral BSDF file (`spectra` over `wavelengths`), which is not supported: \
                 only RGB files (with an `rgb` tensor, the `*_rgb.bsdf` files) can be read",
            ));
        }
        let (_, theta_i) = file.f32_values("theta_i", 1)?;
        let (_, phi_i) = file.f32_values("phi_i", 1)?;
        let (ndf_shape, ndf) = file.f32_values("ndf", 2)?;
        let (sigma_shape, sigma) = file.f32_values("sigma", 2)?;
        let (vndf_shape, vndf) = file.f32_values("vndf", 4)?;
        let (rgb_shape, rgb) = file.f32_values("rgb", 5)?;
        let jacobian = file.require("jacobian", Dtype::UInt8, 1)?;
        if jacobian.shape != [1] {
            return Err(file.error(format!("field `jacobian` has shape {:?}; expected [1]", jacobian.shape)));
        }
        let jacobian = match file.data(jacobian)[0] {
            0 => false,
            1 => true,
            flag => return Err(file.error(format!("field `jacobian` is {flag}; the flag is 0 or 1"))),
        };
        let description = match file.field("description") {
            Some(_) => String::from_utf8_lossy(file.data(file.require("description", Dtype::UInt8, 1)?)).into_owned(),
            None => String::new(),
        };

        let (n_phi, n_theta) = (phi_i.len(), theta_i.len());
        let expect_leading = |name: &str, shape: &[usize], leading: &[usize], layout: &str| {
            if shape[..leading.len()] == *leading {
                Ok(())
            } else {
                Err(file.error(format!(
                    "field `{name}` has shape {shape:?}; expected {layout} = ({}, …)",
                    leading.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
                )))
            }
        };
        expect_leading("vndf", &vndf_shape, &[n_phi, n_theta], "(phi_i, theta_i, ny, nx)")?;
        expect_leading("rgb", &rgb_shape, &[n_phi, n_theta, 3], "(phi_i, theta_i, 3, ny, nx)")?;
        if let Some(i) = sigma.iter().position(|&v| !v.is_finite() || v <= 0.0) {
            return Err(file.error(format!(
                "field `sigma` value {i} is {}; a projected area is finite and positive",
                sigma[i]
            )));
        }
        if let Some(i) = ndf.iter().position(|&v| !v.is_finite() || v < 0.0) {
            return Err(file.error(format!(
                "field `ndf` value {i} is {}; a distribution is finite and not negative",
                ndf[i]
            )));
        }

        // Incidence from above the surface: the RGL files' last angle is π/2 rounded up to float32.
        if let Some(i) = theta_i.iter().position(|&v| !(0.0..=FRAC_PI_2 + 1e-6).contains(&v)) {
            return Err(file.error(format!(
                "field `theta_i` value {i} is {} rad; an incidence angle lies in 0 … π/2",
                theta_i[i]
            )));
        }

        let field_error = |name: &'static str| move |message: String| file.error(format!("field `{name}`: {message}"));
        let axes = ParamAxes::new(&[&phi_i, &theta_i]).map_err(field_error("phi_i/theta_i"))?;
        let isotropic = n_phi <= 2;
        let reduction = if isotropic {
            1
        } else {
            let span = (phi_i[n_phi - 1] - phi_i[0]) as f64;
            let reduction = (TAU / span).round();
            if ![1.0, 2.0, 4.0].contains(&reduction) {
                return Err(file.error(format!(
                    "field `phi_i` spans {span} rad, 2π / {}: only 2π, π and π/2 are supported",
                    TAU / span
                )));
            }
            reduction as u32
        };

        Ok(MeasuredBsdf {
            path: file.path().to_path_buf(),
            description,
            fields: file.fields().to_vec(),
            ndf: Interpolant::new(ndf, ndf_shape[1], ndf_shape[0], 1, ParamAxes::none()).map_err(field_error("ndf"))?,
            sigma: Interpolant::new(sigma, sigma_shape[1], sigma_shape[0], 1, ParamAxes::none())
                .map_err(field_error("sigma"))?,
            vndf: Marginal2D::new(&vndf, vndf_shape[3], vndf_shape[2], axes.clone()).map_err(field_error("vndf"))?,
            rgb: Interpolant::new(rgb, rgb_shape[4], rgb_shape[3], 3, axes).map_err(field_error("rgb"))?,
            theta_i,
            phi_i,
            isotropic,
            reduction,
            jacobian,
            batch: OnceLock::new(),
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file's `description` (empty if it has none).
    pub fn description(&self) -> &str {
        &self.description
    }

    /// Every field of the file, needed here or not.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    /// Incident elevations (radians) at which the material was measured.
    pub fn theta_i(&self) -> &[f32] {
        &self.theta_i
    }

    /// Incident azimuths (radians) at which the material was measured.
    pub fn phi_i(&self) -> &[f32] {
        &self.phi_i
    }

    /// Whether the material is isotropic (at most two `phi_i` values).
    pub fn isotropic(&self) -> bool {
        self.isotropic
    }

    /// 1, 2 or 4: an anisotropic measurement covers 2π / `reduction` of azimuths and is
    /// extended by symmetry.
    pub fn reduction(&self) -> u32 {
        self.reduction
    }

    /// Whether the stored reflectance is multiplied by D(m) / (4 σ(ω_i)).
    pub fn jacobian(&self) -> bool {
        self.jacobian
    }

    /// The values of the `rgb` field as stored, `(phi_i, theta_i, 3, ny, nx)` flattened.
    pub fn rgb(&self) -> &[f32] {
        self.rgb.data()
    }
}
