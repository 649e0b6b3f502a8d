//! Evaluating a measured BRDF at pairs of directions.
//!
//! For ω_i and ω_o in the local frame (z the normal) with half vector m:
//! 1. angles: θ by 2·asin(|ω − z|/2), accurate near the pole; φ by atan2;
//! 2. unit coordinates: u(θ) = √(2θ/π) and u(φ) = (φ + π)/2π, the azimuth of m taken
//!    relative to φ_i (modulo 2π) for isotropic materials;
//! 3. the VNDF warp's inverse, for the incident angles, takes m's coordinates to the
//!    "sample" point where the RGB table is interpolated (negative values → 0);
//! 4. with the `jacobian` flag, times D(m) / (4 σ(ω_i)).
//!
//! That product is f·cos θ_o, the quantity the reference implementations return (and
//! Mitsuba's `measured` plugin, whose `eval` includes the cosine); dividing by cos θ_o
//! gives the BRDF f in 1/sr.
//!
//! Anisotropic measurements that cover half or a quarter of the azimuths are first
//! mirrored into the measured range, as the reference implementations do.

use std::f64::consts::{FRAC_2_PI, PI, TAU};

use rayon::prelude::*;

use super::batch::Tables;
use super::simd::LANES;
use super::{MeasuredBsdf, Precision};
use crate::coords::{self, Vec3};
use crate::error::{invalid_argument, Result};
use crate::parallel;

/// A direction whose z (unit length) is at most this counts as at the horizon, where the BRDF is 0. The tabulated
/// f·cos θ_o does not vanish at the horizon, so f = (f·cos θ_o) / cos θ_o grows as 1/cos θ_o there; without the
/// tolerance a pair that lies on the horizon but for rounding (MERL bins with z = 1e-16) would be worth 1e14/sr.
pub const HORIZON: f64 = 1e-9;

/// Pairs per parallel task: a few hundred microseconds of work, a whole number of lanes.
pub(super) const CHUNK: usize = 256 * LANES;

/// Elevation of a unit vector, 2·asin(|v − z|/2): exact near the pole, unlike acos(v_z).
#[inline]
fn elevation(v: Vec3) -> f64 {
    let distance = (v[0] * v[0] + v[1] * v[1] + (v[2] - 1.0) * (v[2] - 1.0)).sqrt();
    2.0 * (0.5 * distance).min(1.0).asin()
}

#[inline]
fn theta_to_unit(theta: f64) -> f64 {
    (theta * FRAC_2_PI).sqrt()
}

#[inline]
fn phi_to_unit(phi: f64) -> f64 {
    (phi + PI) / TAU
}

impl MeasuredBsdf {
    /// The BRDF at one pair of directions (local frame, z the normal; normalised here):
    /// RGB reflectance in 1/sr, not multiplied by cos θ_o, 0 when either direction is at
    /// or below the horizon (z ≤ [`HORIZON`]).
    pub fn eval_pair(&self, wi: Vec3, wo: Vec3) -> [f64; 3] {
        let (mut wi, mut wo) = (coords::normalize(wi), coords::normalize(wo));
        if !(wi[2] > HORIZON && wo[2] > HORIZON) {
            return [0.0; 3];
        }
        if self.reduction >= 2 {
            // Mirror ω_i into the measured quarter (x, y ≤ 0) or half (y ≤ 0, by a
            // half turn), and ω_o with it.
            let (sy, sx) = (wi[1], if self.reduction == 4 { wi[0] } else { wi[1] });
            let flip = |v: f64, sign: f64| if sign.is_sign_positive() { -v } else { v };
            wi = [flip(wi[0], sx), flip(wi[1], sy), wi[2]];
            wo = [flip(wo[0], sx), flip(wo[1], sy), wo[2]];
        }
        let m = coords::normalize([wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]);
        let (theta_i, phi_i) = (elevation(wi), wi[1].atan2(wi[0]));
        let (theta_m, phi_m) = (elevation(m), m[1].atan2(m[0]));

        let u_wi = [theta_to_unit(theta_i), phi_to_unit(phi_i)];
        let azimuth = phi_to_unit(if self.isotropic { phi_m - phi_i } else { phi_m });
        let u_m = [theta_to_unit(theta_m), azimuth - azimuth.floor()];

        // The VNDF and the RGB table share their parameter axes (φ_i, θ_i).
        let blend = self.vndf.axes().blend(&[phi_i, theta_i]);
        let (sample, _) = self.vndf.invert_blended(&blend, u_m);
        let rgb: [f64; 3] = self.rgb.eval_channels(&blend, sample);
        let jacobian = if self.jacobian {
            self.ndf.eval(u_m, &[]) / (4.0 * self.sigma.eval(u_wi, &[]))
        } else {
            1.0
        };
        let scale = jacobian / wo[2];
        rgb.map(|value| value.max(0.0) * scale)
    }

    /// The BRDF at rows of direction pairs, in parallel, in either precision; see
    /// [`MeasuredBsdf::eval_pair`]. Rows must be finite and non-zero.
    pub fn eval(&self, wi: &[Vec3], wo: &[Vec3], precision: Precision) -> Result<Vec<[f64; 3]>> {
        let mut out = vec![[0.0; 3]; wi.len()];
        self.eval_into(wi, wo, &mut out, precision)?;
        Ok(out)
    }

    /// [`MeasuredBsdf::eval`] into `out`, one row per pair: the Python binding passes a
    /// NumPy array, which NumPy backs with huge pages (a `Vec` of 24 MB is faulted in or
    /// zeroed 4 KiB at a time). On an error, `out` may be partly written.
    pub fn eval_into(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]], precision: Precision) -> Result<()> {
        if wi.len() != wo.len() {
            return invalid_argument!("wi has {} rows but wo has {}", wi.len(), wo.len());
        }
        if out.len() != wi.len() {
            return invalid_argument!("out has {} rows for {} pairs", out.len(), wi.len());
        }
        let validate = || -> Result<()> {
            coords::validate_directions("wi", wi)?;
            coords::validate_directions("wo", wo)
        };
        if precision == Precision::Double {
            validate()?;
        }
        let valid = parallel::in_pool(|| {
            (wi.par_chunks(CHUNK).zip(wo.par_chunks(CHUNK)))
                .zip(out.par_chunks_mut(CHUNK))
                .all(|((wi, wo), out)| self.eval_chunk(wi, wo, out, precision))
        });
        // The float32 path checks the rows as it goes; the error names the first bad one.
        if !valid {
            validate()?;
        }
        Ok(())
    }

    /// [`MeasuredBsdf::eval`] on one task's rows; false where the float32 path finds a row
    /// that is not finite and non-zero (the float64 path is given checked rows).
    pub(super) fn eval_chunk(&self, wi: &[Vec3], wo: &[Vec3], out: &mut [[f64; 3]], precision: Precision) -> bool {
        match precision {
            Precision::Single => (self.batch.get_or_init(|| Tables::new(self))).eval_chunk(wi, wo, out),
            Precision::Double => {
                for ((&wi, &wo), out) in wi.iter().zip(wo).zip(out) {
                    *out = self.eval_pair(wi, wo);
                }
                true
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::f64::consts::FRAC_PI_2;
    use std::path::{Path, PathBuf};

    use super::*;
    use crate::bsdf::synthetic::{tabulate, MaterialArrays, TestRng as Rng};
    use crate::bsdf::tensor_file::{encode, f32_bytes, Dtype, FieldData, TensorFile};
    use crate::error::Error;

    fn build(arrays: &MaterialArrays) -> Result<MeasuredBsdf> {
        MeasuredBsdf::from_tensor_file(&TensorFile::parse(Path::new("synthetic.bsdf"), arrays.encode())?)
    }

    /// A material whose VNDF is constant (so its warp is the identity) and whose RGB
    /// table is `rgb`, with constant D = 2 and σ = 0.5: f = rgb(u_m) · D / (4σ) = rgb(u_m).
    fn flat(phi_i: Vec<f32>, rgb: impl Fn([usize; 5]) -> f32) -> MaterialArrays {
        let mut arrays = MaterialArrays::example(0.3, 1);
        let (n_phi, n_theta) = (phi_i.len(), arrays.theta_i.len());
        arrays.phi_i = phi_i;
        arrays.ndf = tabulate([2, 16], |_| 2.0);
        arrays.sigma = tabulate([2, 16], |_| 0.5);
        arrays.vndf = tabulate([n_phi, n_theta, 9, 17], |_| 1.0);
        arrays.rgb = tabulate([n_phi, n_theta, 3, 5, 33], rgb);
        arrays
    }

    /// f·cos θ_o, what the tables hold.
    fn projected(bsdf: &MeasuredBsdf, wi: Vec3, wo: Vec3) -> [f64; 3] {
        let cos = coords::normalize(wo)[2];
        bsdf.eval_pair(wi, wo).map(|f| f * cos)
    }

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance * b.abs().max(1.0)
    }

    #[test]
    fn constant_material() {
        let bsdf = build(&flat(vec![0.0], |[_, _, c, _, _]| [0.2, -0.1, 0.7][c])).unwrap();
        assert!(bsdf.isotropic() && bsdf.jacobian() && bsdf.reduction() == 1);
        let mut rng = Rng(1);
        for _ in 0..1000 {
            let (wi, wo) = (rng.upper(1e-6), rng.upper(1e-6));
            let value = projected(&bsdf, wi, wo);
            assert!(
                close(value[0], 0.2, 1e-7) && value[1] == 0.0 && close(value[2], 0.7, 1e-7),
                "{value:?}"
            );
            // Scale does not matter; below the horizon is black.
            let scaled = projected(&bsdf, wi.map(|x| 3.0 * x), wo);
            assert!((0..3).all(|c| close(scaled[c], value[c], 1e-12)));
            assert_eq!(bsdf.eval_pair([wi[0], wi[1], -wi[2]], wo), [0.0; 3]);
            assert_eq!(bsdf.eval_pair(wi, [wo[0], wo[1], -wo[2]]), [0.0; 3]);
        }
        assert_eq!(bsdf.eval_pair([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), [0.0; 3]);
        // On the horizon but for rounding: 0, not the table's value over 1e-16.
        let grazing = [(1.0f64 - 1e-32).sqrt(), 0.0, 1e-16];
        assert_eq!(bsdf.eval_pair([0.0, 0.0, 1.0], grazing), [0.0; 3]);
        assert_eq!(bsdf.eval_pair(grazing, [0.0, 0.0, 1.0]), [0.0; 3]);
        let above = bsdf.eval_pair([0.0, 0.0, 1.0], [(1.0f64 - 1e-12).sqrt(), 0.0, 1e-6]);
        assert!(above[0] > 0.0 && above[0].is_finite(), "{above:?}");
    }

    #[test]
    fn coordinates_of_the_half_vector() {
        // Channel 0 holds u(θ_m), channel 1 the relative azimuth u(φ_m − φ_i), channel 2
        // is 1 when the jacobian flag is off.
        let mut arrays = flat(vec![0.0], |[_, _, c, y, x]| match c {
            0 => x as f32 / 32.0,
            1 => y as f32 / 4.0,
            _ => 0.25,
        });
        let bsdf = build(&arrays).unwrap();
        let mut rng = Rng(2);
        for _ in 0..2000 {
            let (wi, wo) = (rng.upper(1e-3), rng.upper(1e-3));
            let m = coords::normalize([wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]);
            let theta_m = m[0].hypot(m[1]).atan2(m[2]);
            let relative = (m[1].atan2(m[0]) - wi[1].atan2(wi[0]) + PI).rem_euclid(TAU) / TAU;
            let [u_theta, u_phi, quarter] = projected(&bsdf, wi, wo);
            assert!(
                close(u_theta, (theta_m / FRAC_PI_2).sqrt(), 1e-6),
                "{u_theta} {theta_m}"
            );
            if (0.001..0.999).contains(&relative) {
                assert!(close(u_phi, relative, 1e-6), "{u_phi} {relative}");
            }
            assert!(close(quarter, 0.25, 1e-7));
        }
        // Without the Jacobian the table is returned as is.
        arrays.jacobian = false;
        arrays.sigma = tabulate([2, 16], |_| 1e-3);
        let bsdf = build(&arrays).unwrap();
        assert!(!bsdf.jacobian());
        assert!(close(projected(&bsdf, [0.0, 0.0, 1.0], [0.3, 0.0, 0.9])[2], 0.25, 1e-7));
    }

    #[test]
    fn incident_elevation_blends_slices() {
        // Each θ_i slice holds its own θ_i: linear blending returns θ_i itself.
        let theta = MaterialArrays::example(0.3, 1).theta_i;
        let bsdf = build(&flat(vec![0.0], |[_, t, _, _, _]| theta[t])).unwrap();
        let mut rng = Rng(3);
        for _ in 0..1000 {
            let (wi, wo) = (rng.upper(1e-3), rng.upper(1e-3));
            let theta_i = wi[0].hypot(wi[1]).atan2(wi[2]);
            let value = projected(&bsdf, wi, wo)[1];
            assert!(close(value, theta_i, 1e-6), "{value} vs {theta_i}");
        }
    }

    #[test]
    fn isotropic_materials_are_invariant_under_rotation() {
        let bsdf = build(&MaterialArrays::example(0.2, 1)).unwrap();
        let mut rng = Rng(4);
        for _ in 0..2000 {
            let (wi, wo) = (rng.upper(1e-3), rng.upper(1e-3));
            let (sin, cos) = (TAU * rng.next()).sin_cos();
            let rotate = |v: Vec3| [cos * v[0] - sin * v[1], sin * v[0] + cos * v[1], v[2]];
            let (a, b) = (bsdf.eval_pair(wi, wo), bsdf.eval_pair(rotate(wi), rotate(wo)));
            for c in 0..3 {
                assert!(close(a[c], b[c], 1e-6), "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn anisotropic_quarter_is_mirrored() {
        // φ_i measured over [−π, −π/2] (reduction 4); each slice holds 4 + its φ_i.
        let phi: Vec<f32> = (0..3).map(|k| (-PI + FRAC_PI_2 * k as f64 / 2.0) as f32).collect();
        let slice_phi = phi.clone();
        let bsdf = build(&flat(
            phi,
            move |[p, _, c, _, _]| if c == 0 { 4.0 + slice_phi[p] } else { 0.5 },
        ))
        .unwrap();
        assert!(!bsdf.isotropic());
        assert_eq!(bsdf.reduction(), 4);
        let mut rng = Rng(5);
        for _ in 0..1000 {
            let (wi, wo) = (rng.upper(1e-3), rng.upper(1e-3));
            let mirrored_phi = (-wi[1].abs()).atan2(-wi[0].abs());
            let value = projected(&bsdf, wi, wo)[0];
            assert!(close(value, 4.0 + mirrored_phi, 1e-6), "{value} vs {mirrored_phi}");
            let mirror_x = |v: Vec3| [-v[0], v[1], v[2]];
            assert_eq!(bsdf.eval_pair(mirror_x(wi), mirror_x(wo)), bsdf.eval_pair(wi, wo));
        }
        // A full circle of azimuths needs no mirroring; a third of one is refused.
        let full: Vec<f32> = (0..5).map(|k| (-PI + TAU * k as f64 / 4.0) as f32).collect();
        assert_eq!(build(&flat(full, |_| 1.0)).unwrap().reduction(), 1);
        let third: Vec<f32> = (0..3).map(|k| (-PI + TAU / 3.0 * k as f64 / 2.0) as f32).collect();
        let message = build(&flat(third, |_| 1.0)).unwrap_err().to_string();
        assert!(message.contains("only 2π, π and π/2"), "{message}");
    }

    #[test]
    fn batch_matches_pairs_and_checks_rows() {
        let bsdf = build(&MaterialArrays::example(0.15, 1)).unwrap();
        let mut rng = Rng(6);
        let wi: Vec<Vec3> = (0..10_000).map(|_| rng.upper(-0.2)).collect();
        let wo: Vec<Vec3> = (0..10_000).map(|_| rng.upper(-0.2)).collect();
        let batch = bsdf.eval(&wi, &wo, Precision::Double).unwrap();
        for k in 0..wi.len() {
            assert_eq!(batch[k], bsdf.eval_pair(wi[k], wo[k]));
        }
        assert!(bsdf
            .eval(&wi, &wo[1..], Precision::Double)
            .unwrap_err()
            .to_string()
            .contains("wo has 9999"));
        let mut short = vec![[0.0; 3]; wi.len() - 1];
        let message = bsdf
            .eval_into(&wi, &wo, &mut short, Precision::Single)
            .unwrap_err()
            .to_string();
        assert!(message.contains("out has 9999 rows for 10000 pairs"), "{message}");
        let mut bad = wo.clone();
        bad[17] = [0.0, f64::NAN, 1.0];
        assert!(bsdf
            .eval(&wi, &bad, Precision::Double)
            .unwrap_err()
            .to_string()
            .contains("wo row 17"));
        bad[17] = [0.0; 3];
        assert!(matches!(
            bsdf.eval(&bad, &wi, Precision::Single),
            Err(Error::InvalidArgument(_))
        ));
    }

    fn format_error(arrays: &MaterialArrays, edit: impl FnOnce(&mut Vec<u8>)) -> String {
        let mut bytes = arrays.encode();
        edit(&mut bytes);
        let result = TensorFile::parse(Path::new("bad.bsdf"), bytes).and_then(|f| MeasuredBsdf::from_tensor_file(&f));
        match result {
            Err(Error::BsdfFormat { message, .. }) => message,
            other => panic!("expected a BsdfFormat error, got {other:?}"),
        }
    }

    #[test]
    fn bad_material_files() {
        let good = MaterialArrays::example(0.3, 1);
        let expect = |arrays: &MaterialArrays, text: &str| {
            let message = format_error(arrays, |_| {});
            assert!(message.contains(text), "{message}");
        };
        let mut arrays = good.clone();
        arrays.rgb = tabulate([1, 8, 4, 32, 32], |_| 1.0);
        expect(
            &arrays,
            "field `rgb` has shape [1, 8, 4, 32, 32]; expected (phi_i, theta_i, 3, ny, nx)",
        );
        let mut arrays = good.clone();
        arrays.vndf = tabulate([1, 7, 128, 128], |_| 1.0);
        expect(&arrays, "field `vndf` has shape [1, 7, 128, 128]");
        let mut arrays = good.clone();
        arrays.vndf = tabulate([1, 8, 16, 16], |[_, t, _, _]| if t == 3 { 0.0 } else { 1.0 });
        expect(&arrays, "field `vndf`: slice 3 integrates to 0");
        let mut arrays = good.clone();
        arrays.sigma = tabulate([2, 16], |[_, x]| if x == 15 { 0.0 } else { 1.0 });
        expect(&arrays, "field `sigma` value 15 is 0");
        let mut arrays = good.clone();
        arrays.ndf = tabulate([2, 1], |_| 1.0);
        expect(&arrays, "field `ndf`: a 2 × 1 grid");
        let mut arrays = good.clone();
        arrays.theta_i[3] = arrays.theta_i[2];
        expect(&arrays, "not strictly increasing");

        // Wrong dtype: `rgb` relabelled float64 (code 11), and its size no longer fits.
        let bytes = good.encode();
        let rgb_header = bytes.windows(5).position(|w| w == b"\x03\x00rgb").unwrap();
        let message = format_error(&good, |b| b[rgb_header + 7] = 11);
        assert!(message.contains("field `rgb`"), "{message}");
        // Wrong dtype with a consistent size: `theta_i` as uint32.
        let theta_header = bytes.windows(9).position(|w| w == b"\x07\x00theta_i").unwrap();
        let message = format_error(&good, |b| b[theta_header + 11] = Dtype::UInt32 as u8);
        assert!(
            message.contains("field `theta_i` is uint32 with shape [8]; expected float32"),
            "{message}"
        );
        // No `rgb` at all.
        let message = format_error(&good, |b| b[rgb_header + 2..rgb_header + 5].copy_from_slice(b"spc"));
        assert!(message.contains("has no field `rgb`"), "{message}");
        // A spectral file: `spectra` over `wavelengths`, no `rgb`.
        let spectra = f32_bytes(&[0.5; 2 * 5 * 4 * 4]);
        let bytes = encode(&[FieldData {
            name: "spectra",
            dtype: Dtype::Float32,
            shape: &[1, 2, 5, 4, 4],
            data: &spectra,
        }]);
        let message =
            match TensorFile::parse(Path::new("s.bsdf"), bytes).and_then(|f| MeasuredBsdf::from_tensor_file(&f)) {
                Err(Error::BsdfFormat { message, .. }) => message,
                other => panic!("{other:?}"),
            };
        assert!(
            message.contains("spectral BSDF file") && message.contains("not supported"),
            "{message}"
        );
    }

    /// The RGL files beside the checkout, if present.
    pub(in crate::bsdf) fn real_files() -> Vec<PathBuf> {
        let data = std::env::var_os("FRENBRDF_SHARED_DATA")
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
        let folder = data.join("rgl-measured");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&folder)
            .map(|entries| {
                entries
                    .filter_map(|entry| Some(entry.ok()?.path()))
                    .filter(|path| path.extension().is_some_and(|e| e == "bsdf"))
                    .collect()
            })
            .unwrap_or_default();
        files.sort();
        if files.is_empty() {
            eprintln!(
                "skipped: no RGL .bsdf files in {} (set FRENBRDF_SHARED_DATA)",
                folder.display()
            );
        }
        files
    }

    #[test]
    fn real_files_read_and_evaluate_sanely() {
        for path in real_files() {
            let bsdf = MeasuredBsdf::read(&path).unwrap();
            let name = path.file_name().unwrap().to_string_lossy();
            assert!(
                !bsdf.description().is_empty() && bsdf.isotropic() && bsdf.jacobian(),
                "{name}"
            );
            assert_eq!(bsdf.theta_i().len(), 8);

            let mut rng = Rng(11);
            let n = 20_000;
            let wi: Vec<Vec3> = (0..n).map(|_| rng.upper(0.02)).collect();
            let wo: Vec<Vec3> = (0..n).map(|_| rng.upper(0.02)).collect();
            let forward = bsdf.eval(&wi, &wo, Precision::Double).unwrap();
            let backward = bsdf.eval(&wo, &wi, Precision::Double).unwrap();
            assert!(forward.iter().flatten().all(|v| v.is_finite() && *v >= 0.0), "{name}");
            assert!(forward.iter().any(|v| v.iter().all(|&c| c > 0.0)), "{name}");
            // Reciprocity holds approximately (the parameterisation is not symmetric):
            // the median relative difference of the luminance-ish sum is small.
            let mut differences: Vec<f64> = forward
                .iter()
                .zip(&backward)
                .map(|(f, b)| {
                    let (f, b) = (f.iter().sum::<f64>(), b.iter().sum::<f64>());
                    (f - b).abs() / (f + b).max(1e-12) * 2.0
                })
                .collect();
            differences.sort_by(f64::total_cmp);
            let median = differences[n / 2];
            eprintln!("{name}: median relative reciprocity difference {median:.4}");
            assert!(median < 0.3, "{name}: median reciprocity difference {median}");

            // Directional albedo ∫ f cos θ_o dω_o stays below 1 for a few incident angles
            // (stratified over the cosine-weighted hemisphere).
            for theta in [0.1f64, 0.6, 1.1] {
                let wi = [theta.sin(), 0.0, theta.cos()];
                let k = 200;
                let mut sum = [0.0; 3];
                for a in 0..k {
                    for b in 0..k {
                        let (r, phi) = (((a as f64 + 0.5) / k as f64).sqrt(), TAU * (b as f64 + 0.5) / k as f64);
                        let wo = [r * phi.cos(), r * phi.sin(), (1.0 - r * r).sqrt()];
                        let f = bsdf.eval_pair(wi, wo);
                        (0..3).for_each(|c| sum[c] += f[c] * PI / (k * k) as f64);
                    }
                }
                eprintln!("{name}: albedo at θ_i = {theta}: {sum:.3?}");
                assert!(
                    sum.iter().all(|&a| a > 0.0 && a < 1.05),
                    "{name}: albedo {sum:?} at θ_i = {theta}"
                );
            }
            // Below the horizon: black.
            let below = bsdf.eval_pair([0.3, 0.1, -0.5], [0.0, 0.0, 1.0]);
            assert_eq!(below, [0.0; 3]);
        }
    }
}
