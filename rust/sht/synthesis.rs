//! Synthesis and the adjoint of analysis: coefficients gathered per order, the Legendre
//! step as a matrix product, and (for the adjoint on equiangular grids) the resampling
//! back to the grid's rings.

use rayon::prelude::*;

use super::linalg::{matmul_packed, MatMut, MatRef};
use super::real::Real;
use super::table::{LegendreTable, OrderPanels, Orientation};
use super::{order_scale, Chunks, Layout, Sht};
use crate::error::Result;

impl<T: Real> Sht<T> {
    /// Coefficients `(batch, (lmax+1)²)` → maps `(batch, nlat, nlon)`.
    pub fn synthesis(&self, coefficients: &[T], batch: usize) -> Result<Vec<T>> {
        let mut maps = vec![T::zero(); batch * self.nlat * self.nlon];
        self.synthesis_into(coefficients, batch, &mut maps)?;
        Ok(maps)
    }

    /// [`Sht::synthesis`] into `maps`, which it overwrites.
    pub fn synthesis_into(&self, coefficients: &[T], batch: usize, maps: &mut [T]) -> Result<()> {
        self.coefficients_to_maps(coefficients, batch, maps, false)
    }

    /// The adjoint (transpose) of [`Sht::analysis`]: coefficients → maps, so that
    /// ⟨analysis(x), c⟩ = ⟨x, analysis_adjoint(c)⟩. This is the backward pass of analysis.
    pub fn analysis_adjoint(&self, coefficients: &[T], batch: usize) -> Result<Vec<T>> {
        let mut maps = vec![T::zero(); batch * self.nlat * self.nlon];
        self.analysis_adjoint_into(coefficients, batch, &mut maps)?;
        Ok(maps)
    }

    /// [`Sht::analysis_adjoint`] into `maps`, which it overwrites.
    pub fn analysis_adjoint_into(&self, coefficients: &[T], batch: usize, maps: &mut [T]) -> Result<()> {
        self.coefficients_to_maps(coefficients, batch, maps, true)
    }

    fn coefficients_to_maps(&self, coefficients: &[T], batch: usize, maps: &mut [T], adjoint: bool) -> Result<()> {
        self.check_len("coefficients", coefficients.len(), batch, self.n_coefficients())?;
        self.check_len("maps", maps.len(), batch, self.nlat * self.nlon)?;
        self.for_each_chunk(
            Chunks::Parallel(self.chunk_items()),
            coefficients,
            self.n_coefficients(),
            maps,
            self.nlat * self.nlon,
            |coefficients, out| self.synthesis_chunk(coefficients, out, adjoint),
        );
        Ok(())
    }

    /// Synthesis, or with `adjoint` the adjoint of analysis, of one chunk.
    fn synthesis_chunk(&self, coefficients: &[T], maps: &mut [T], adjoint: bool) {
        let batch = coefficients.len() / self.n_coefficients();
        let point = 2.0 * std::f64::consts::PI / self.nlon as f64;
        let orders = self.gather(coefficients, batch);
        match (&self.gauss, adjoint) {
            (_, false) | (None, true) => {
                let (sym, anti) = self.legendre_synthesis(&self.at_grid, &orders, batch);
                let ring_factors: Vec<f64> = if adjoint {
                    self.weights.iter().map(|w| w * point).collect()
                } else {
                    vec![1.0; self.nlat]
                };
                self.unfold_rings(&sym, &anti, batch, &ring_factors, maps);
                self.pool.give([sym, anti]);
            }
            (Some((table, resampling)), true) => {
                let (gauss_sym, gauss_anti) = self.legendre_synthesis(table, &orders, batch);
                let gauss_layout = Layout {
                    ring_stride: 2 * batch,
                    order_stride: table.half_rings() * 2 * batch,
                };
                let (sym, anti) = self.map_rings(
                    [&gauss_sym, &gauss_anti],
                    gauss_layout,
                    &resampling.adjoint,
                    self.half_rings(),
                    batch,
                );
                self.unfold_rings(&sym, &anti, batch, &vec![point; self.nlat], maps);
                self.pool.give([gauss_sym, gauss_anti, sym, anti]);
            }
        }
        self.pool.give([orders]);
    }

    /// Per order m: folded spectrum `[m][half ring][part][batch]` = λ_mᵀ · coefficients
    /// `[m][l − m][part][batch]`.
    fn legendre_synthesis(&self, table: &LegendreTable<T>, orders: &[T], batch: usize) -> (Vec<T>, Vec<T>) {
        let (width, half) = (2 * batch, table.half_rings());
        let mut sym = self.pool.take((self.lmax + 1) * half * width);
        let mut anti = self.pool.take((self.lmax + 1) * half * width);
        let starts = self.order_starts(batch);
        sym.par_chunks_mut(half * width)
            .zip(anti.par_chunks_mut(half * width))
            .enumerate()
            .for_each_init(OrderPanels::default, |scratch, (m, (sym_m, anti_m))| {
                let panels = table.panels(m, scratch, Orientation::Synthesis);
                let degrees = self.degrees(m);
                for (parity, destination) in [(0, sym_m), (1, anti_m)] {
                    let rows = (degrees + 1 - parity) / 2;
                    // The quiet rings nearest the pole get nothing from this order.
                    let quiet = panels.quiet[parity];
                    destination[..quiet * width].fill(T::zero());
                    matmul_packed(
                        MatMut {
                            data: destination,
                            offset: quiet * width,
                            rows: half - quiet,
                            cols: width,
                            row_stride: width,
                        },
                        &panels.synthesis[parity],
                        MatRef {
                            data: orders,
                            offset: starts[m] + parity * width,
                            rows,
                            cols: width,
                            row_stride: 2 * width,
                            col_stride: 1,
                        },
                    );
                }
            });
        (sym, anti)
    }

    /// Inverse of [`Sht::scatter`]'s layout change (with the same √2 factors).
    fn gather(&self, coefficients: &[T], batch: usize) -> Vec<T> {
        let n = self.n_coefficients();
        let mut orders = self.pool.take((self.lmax + 1) * (self.lmax + 2) / 2 * 2 * batch);
        self.split_orders(&mut orders, batch)
            .into_par_iter()
            .enumerate()
            .for_each(|(m, block)| {
                let (degrees, scale) = (self.degrees(m), order_scale::<T>(m));
                for (i, row) in block.chunks_exact_mut(2 * batch).enumerate() {
                    for (b, item) in coefficients.chunks_exact(n).enumerate() {
                        row[b] = scale * item[self.offsets[m] + i];
                        row[batch + b] = if m == 0 {
                            T::zero()
                        } else {
                            scale * item[self.offsets[m] + degrees + i]
                        };
                    }
                }
            });
        orders
    }
}
