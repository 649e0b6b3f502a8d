//! Equiangular grids: each order's folded spectra resampled exactly onto Gauss–Legendre
//! rings for analysis, and back for the adjoint, with the matrices a plan built once
//! ([`Resampling`](super::table::Resampling)).

use rayon::prelude::*;

use super::linalg::{matmul_packed, MatMut, MatRef, Packed};
use super::real::Real;
use super::{Layout, Sht};

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
