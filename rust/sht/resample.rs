//! Equiangular grids: each order's folded spectra resampled exactly onto Gauss–Legendre
//! rings for analysis (and back, for the adjoint), with matrices built once per plan.

use rayon::prelude::*;

use super::linalg::{matmul_packed, MatMut, MatRef, Packed};
use super::real::Real;
use super::{Layout, Sht};

/// The equiangular → Gauss–Legendre resampling, `[m parity][symmetric, antisymmetric]`,
/// packed for both directions.
pub(super) struct Resampling<T> {
    pub(super) forward: [[Packed<T>; 2]; 2],
    pub(super) adjoint: [[Packed<T>; 2]; 2],
}

impl<T: Real> Sht<T> {
    /// Maps each order's folded spectra to other rings with a packed per-parity matrix
    /// (`matrices[m % 2][symmetric, antisymmetric]`): the equiangular → Gauss–Legendre
    /// resampling or its adjoint. Order m's input starts at `m · input.order_stride`, its
    /// rings `input.ring_stride` apart; the output is `[m][ring][part][batch]`.
    pub(super) fn map_rings(
        &self,
        [sym, anti]: [&[T]; 2],
        input: Layout,
        matrices: &[[Packed<T>; 2]; 2],
        rings_out: usize,
        batch: usize,
    ) -> (Vec<T>, Vec<T>) {
        let (width, orders) = (2 * batch, self.lmax + 1);
        let mut out = [
            self.pool.take(orders * rings_out * width),
            self.pool.take(orders * rings_out * width),
        ];
        let [out_sym, out_anti] = &mut out;
        out_sym
            .par_chunks_mut(rings_out * width)
            .zip(out_anti.par_chunks_mut(rings_out * width))
            .enumerate()
            .for_each(|(m, (sym_m, anti_m))| {
                for (part, (source, destination)) in [(sym, sym_m), (anti, anti_m)].into_iter().enumerate() {
                    let matrix = &matrices[m % 2][part];
                    matmul_packed(
                        MatMut {
                            data: destination,
                            offset: 0,
                            rows: rings_out,
                            cols: width,
                            row_stride: width,
                        },
                        matrix,
                        MatRef {
                            data: source,
                            offset: m * input.order_stride,
                            rows: matrix.depth(),
                            cols: width,
                            row_stride: input.ring_stride,
                            col_stride: 1,
                        },
                    );
                }
            });
        let [sym, anti] = out;
        (sym, anti)
    }
}

/// Restricts the full resampling matrices (Gauss rings × equiangular rings) to folded
/// symmetric/antisymmetric parts on half rings, with the Gauss weights folded in.
///
/// A folded symmetric part holds g_j + g_j' on paired rings and g_j on an equator ring
/// (antisymmetric: g_j − g_j', and 0 on the equator); the rows are built so that the
/// output holds the same quantities at the Gauss rings, times their weights.
pub(super) fn fold_resampling<T: Real>(full: &[Vec<f64>; 2], n_source: usize, gauss_weights: &[f64]) -> Resampling<T> {
    let n_target = gauss_weights.len();
    let (source_half, target_half) = (n_source.div_ceil(2), n_target.div_ceil(2));
    let folded: [[Vec<T>; 2]; 2] = full.each_ref().map(|matrix| {
        [1.0, -1.0].map(|sign: f64| {
            let mut folded = vec![T::zero(); target_half * source_half];
            for k in 0..target_half {
                let target_is_equator = n_target - 1 - k == k;
                let rows_per_part = match (target_is_equator, sign > 0.0) {
                    (true, true) => 1.0,
                    (true, false) => 0.0,
                    (false, _) => 2.0,
                };
                for j in 0..source_half {
                    let mirror = n_source - 1 - j;
                    let entry = &matrix[k * n_source..];
                    let value = if mirror == j {
                        if sign > 0.0 {
                            entry[j]
                        } else {
                            0.0
                        }
                    } else {
                        0.5 * (entry[j] + sign * entry[mirror])
                    };
                    folded[k * source_half + j] = T::of(rows_per_part * gauss_weights[k] * value);
                }
            }
            folded
        })
    });
    let pack = |transpose: bool| {
        folded.each_ref().map(|parts| {
            parts.each_ref().map(|matrix| {
                let (rows, cols, row_stride, col_stride) = if transpose {
                    (source_half, target_half, 1, source_half)
                } else {
                    (target_half, source_half, source_half, 1)
                };
                Packed::new(MatRef {
                    data: matrix,
                    offset: 0,
                    rows,
                    cols,
                    row_stride,
                    col_stride,
                })
            })
        })
    };
    Resampling {
        forward: pack(false),
        adjoint: pack(true),
    }
}
