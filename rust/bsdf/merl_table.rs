//! A measurement tabulated at the bins of a MERL file.

use std::sync::OnceLock;

use rayon::prelude::*;

use super::eval::CHUNK;
use super::{MeasuredBsdf, Precision};
use crate::coords::{from_rusinkiewicz, Vec3};
use crate::merl::{phi_d_of_bin, theta_d_of_bin, theta_h_of_bin, MISSING, N_BINS, N_PHI_D, N_THETA_D};
use crate::parallel;

/// (ω_i, ω_o) at every MERL bin, θ_h slowest and φ_d fastest, φ_h = 0: the values of
/// `frenbrdf.merl_bin_directions`. Computing them takes longer than evaluating a
/// measurement there, so they are computed once (70 MB) and kept.
pub(super) fn bin_directions() -> &'static (Vec<Vec3>, Vec<Vec3>) {
    static DIRECTIONS: OnceLock<(Vec<Vec3>, Vec<Vec3>)> = OnceLock::new();
    DIRECTIONS.get_or_init(|| {
        parallel::in_pool(|| {
            (0..N_BINS)
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|bin| {
                    let (h, rest) = (bin / (N_THETA_D * N_PHI_D), bin % (N_THETA_D * N_PHI_D));
                    let (d, p) = (rest / N_PHI_D, rest % N_PHI_D);
                    let angles = [
                        theta_h_of_bin(h as f64),
                        0.0,
                        theta_d_of_bin(d as f64),
                        phi_d_of_bin(p as f64),
                    ];
                    from_rusinkiewicz(angles)
                })
                .unzip()
        })
    })
}

impl MeasuredBsdf {
    /// The BRDF at every bin of a MERL table, as [`MeasuredBsdf::eval`] gives it, laid out
    /// as a MERL file's values in 1/sr: channel, θ_h, θ_d, φ_d (`3 × 90 × 90 × 180`), with
    /// [`MISSING`] where a bin's directions do not both lie strictly above the surface.
    pub fn merl_table(&self, precision: Precision) -> Vec<f64> {
        let mut table = vec![0.0; 3 * N_BINS];
        self.merl_table_into(&mut table, precision);
        table
    }

    /// [`MeasuredBsdf::merl_table`] into `table`, see [`MeasuredBsdf::eval_into`].
    ///
    /// # Panics
    /// If `table` does not hold `3 × N_BINS` values.
    pub fn merl_table_into(&self, table: &mut [f64], precision: Precision) {
        assert_eq!(table.len(), 3 * N_BINS, "a MERL table holds 3 × {N_BINS} values");
        let (wi, wo) = bin_directions();
        let (red, rest) = table.split_at_mut(N_BINS);
        let (green, blue) = rest.split_at_mut(N_BINS);
        parallel::in_pool(|| {
            let planes = red
                .par_chunks_mut(CHUNK)
                .zip(green.par_chunks_mut(CHUNK))
                .zip(blue.par_chunks_mut(CHUNK));
            planes.enumerate().for_each(|(chunk, ((red, green), blue))| {
                let bins = chunk * CHUNK..chunk * CHUNK + red.len();
                let (wi, wo) = (&wi[bins.clone()], &wo[bins]);
                let mut values = vec![[0.0; 3]; wi.len()];
                let valid = self.eval_chunk(wi, wo, &mut values, precision);
                debug_assert!(valid, "bin directions are unit vectors");
                for (k, ((wi, wo), rgb)) in wi.iter().zip(wo).zip(values).enumerate() {
                    let rgb = if wi[2] > 0.0 && wo[2] > 0.0 { rgb } else { [MISSING; 3] };
                    (red[k], green[k], blue[k]) = (rgb[0], rgb[1], rgb[2]);
                }
            })
        });
    }
}
