//! Analysis: the batch split into chunks, each chunk's Legendre step (a matrix product
//! with the kept table, or λ recomputed in registers), and the scatter of coefficients.

use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::linalg::{matmul_packed, MatMut, MatRef};
use super::real::Real;
use super::table::{LegendreTable, OrderPanels, Orientation};
use super::{order_scale, streamed, transpose, Chunks, Layout, Sht, MAP_BLOCK};
use crate::error::Result;

/// Chunks of at most this many maps are analysed with λ recomputed in registers
/// ([`streamed`]) even where the table is kept: a one-map product reuses each table value
/// only twice, so reading the table costs more than recomputing it (single maps of 90×180
/// and 128×256, one thread, f64 and f32: research/performance.md).
const STREAMED_MAX_BATCH: usize = 1;

/// Tables larger than this (about half the last-level cache) are read from memory for
/// every chunk of maps: beyond it every batch is analysed on the fly, a map at a time,
/// which beat both reading the table and chunks of maps on the fly at 256×512 (a 34 MB
/// table; research/performance.md).
const STREAMED_MIN_TABLE_BYTES_ANY_BATCH: usize = 16 << 20;

/// Bytes of gathered spectra a group of orders analysed on the fly may occupy (per
/// worker, in cache).
const STREAMED_GROUP_BYTES: usize = 256 << 10;

/// Maps larger than this (a core's L2 cache) are analysed one after another, each parallel
/// inside over orders ([`Chunks::OneAfterAnother`]), rather than one per worker: two at once evict each other's
/// intermediates. Below it one map per worker stays the faster (512×1024 against 256×512
/// on two threads: research/performance.md).
pub(super) const SHARED_MAP_BYTES: usize = 2 << 20;

impl<T: Real> Sht<T> {
    /// Maps `(batch, nlat, nlon)` → coefficients `(batch, (lmax+1)²)`.
    pub fn analysis(&self, maps: &[T], batch: usize) -> Result<Vec<T>> {
        let len = batch * self.n_coefficients();
        let mut coefficients = Vec::with_capacity(len);
        self.analysis_into(maps, batch, &mut coefficients.spare_capacity_mut()[..len])?;
        // SAFETY: `analysis_into` wrote every coefficient.
        unsafe { coefficients.set_len(len) };
        Ok(coefficients)
    }

    /// [`Sht::analysis`] into `coefficients`, which it fills. Not zero-filled first by the
    /// caller: every value is written once, and zeroing a large output cost a noticeable
    /// share of a transform (research/performance.md).
    pub fn analysis_into(&self, maps: &[T], batch: usize, coefficients: &mut [MaybeUninit<T>]) -> Result<()> {
        self.check_len("maps", maps.len(), batch, self.nlat * self.nlon)?;
        self.check_len("coefficients", coefficients.len(), batch, self.n_coefficients())?;
        // Maps one at a time where λ is recomputed anyway: a chunk's intermediates then
        // stay in cache.
        let map_bytes = self.nlat * self.nlon * std::mem::size_of::<T>();
        let chunks = if !Self::streams_every_map(self.analysis_table()) {
            Chunks::Parallel(self.chunk_items())
        } else if map_bytes > SHARED_MAP_BYTES {
            Chunks::OneAfterAnother
        } else {
            Chunks::Parallel(1)
        };
        self.for_each_chunk(
            chunks,
            maps,
            self.nlat * self.nlon,
            coefficients,
            self.n_coefficients(),
            |maps, out| self.analysis_chunk(maps, out),
        );
        Ok(())
    }

    /// The table analysis reads: the grid's own, or the Gauss–Legendre rings an
    /// equiangular grid is resampled to.
    fn analysis_table(&self) -> &LegendreTable<T> {
        match &self.gauss {
            Some((table, _)) => table,
            None => &self.at_grid,
        }
    }

    /// Whether analysis of chunks of `batch` maps recomputes λ in registers ([`streamed`])
    /// rather than reading `table`.
    fn streams(table: &LegendreTable<T>, batch: usize) -> bool {
        Self::streams_every_map(table) || batch <= STREAMED_MAX_BATCH
    }

    /// Whether analysis recomputes λ whatever the batch: the table is not kept, or too
    /// large to stay in cache.
    fn streams_every_map(table: &LegendreTable<T>) -> bool {
        table.cached.is_none() || table.bytes() > STREAMED_MIN_TABLE_BYTES_ANY_BATCH
    }

    fn analysis_chunk(&self, maps: &[T], coefficients: &mut [MaybeUninit<T>]) {
        let batch = maps.len() / (self.nlat * self.nlon);
        let point = 2.0 * std::f64::consts::PI / self.nlon as f64;
        let orders = match &self.gauss {
            // Single maps always take the on-the-fly path (`Sht::streams`).
            None if batch == 1 => {
                let ring_factors: Vec<f64> = self.weights.iter().map(|w| w * point).collect();
                let tiles = self.fold_ring_blocks(maps, &ring_factors);
                let orders = self.streamed_tiles_analysis(&tiles);
                self.pool.give(tiles);
                orders
            }
            None => {
                let ring_factors: Vec<f64> = self.weights.iter().map(|w| w * point).collect();
                let (sym, anti) = self.fold_rings(maps, batch, &ring_factors);
                let layout = Layout {
                    ring_stride: (self.lmax + 1) * 2 * batch,
                    order_stride: 2 * batch,
                };
                let orders = self.legendre_analysis(&self.at_grid, &sym, &anti, layout, batch);
                self.pool.give([sym, anti]);
                orders
            }
            Some((table, resampling)) => {
                let (sym, anti) = self.fold_rings(maps, batch, &vec![point; self.nlat]);
                let folded = Layout {
                    ring_stride: (self.lmax + 1) * 2 * batch,
                    order_stride: 2 * batch,
                };
                let (gauss_sym, gauss_anti) =
                    self.map_rings([&sym, &anti], folded, &resampling.forward, table.half_rings(), batch);
                let layout = Layout {
                    ring_stride: 2 * batch,
                    order_stride: table.half_rings() * 2 * batch,
                };
                let orders = self.legendre_analysis(table, &gauss_sym, &gauss_anti, layout, batch);
                self.pool.give([sym, anti, gauss_sym, gauss_anti]);
                orders
            }
        };
        self.scatter(&orders, batch, coefficients);
        self.pool.give([orders]);
    }

    /// The on-the-fly Legendre step of one map from [`Sht::fold_ring_blocks`]' tiles:
    /// coefficients `[m][l − m][part]`.
    fn streamed_tiles_analysis(&self, [sym, anti]: &[Vec<T>; 2]) -> Vec<T> {
        let table = &self.at_grid;
        let orders = self.lmax + 1;
        // The kernel reads f64: f32 tiles are widened first.
        let widened: [Vec<f64>; 2];
        let parts: [&[f64]; 2] = match [sym, anti].map(|tiles| (tiles as &dyn std::any::Any).downcast_ref::<Vec<f64>>())
        {
            [Some(sym), Some(anti)] => [sym, anti],
            _ => {
                widened = [sym, anti].map(|tiles| tiles.iter().map(|v| v.to_f64().unwrap_or(f64::NAN)).collect());
                [&widened[0], &widened[1]]
            }
        };
        let mut out = self.pool.take(orders * (orders + 1) / 2 * 2);
        self.split_orders(&mut out, 1)
            .into_par_iter()
            .enumerate()
            .for_each_init(streamed::Scratch::default, |scratch, (m, block)| {
                let rings = streamed::LANES;
                let spectra = streamed::Spectra {
                    parts: parts.map(|tiles| &tiles[m * 2 * rings..]),
                    column_stride: rings,
                    vector_stride: self.ring_block_tile(),
                    width: 2,
                };
                table.streamed_order(m, spectra, block, scratch);
            });
        out
    }

    /// Per order m: coefficients `[m][l − m][part][batch]` = λ_m · folded spectrum, the
    /// even-(l − m) degrees from the symmetric part and the odd ones from the antisymmetric.
    fn legendre_analysis(
        &self,
        table: &LegendreTable<T>,
        sym: &[T],
        anti: &[T],
        layout: Layout,
        batch: usize,
    ) -> Vec<T> {
        let (width, half) = (2 * batch, table.half_rings());
        let streamed = Self::streams(table, batch);
        let mut orders = self.pool.take((self.lmax + 1) * (self.lmax + 2) / 2 * width);
        if streamed {
            self.streamed_analysis(table, [sym, anti], layout, batch, &mut orders);
            return orders;
        }
        self.split_orders(&mut orders, batch)
            .into_par_iter()
            .enumerate()
            .for_each_init(OrderPanels::default, |scratch, (m, block)| {
                let panels = table.panels(m, scratch, Orientation::Analysis);
                let degrees = self.degrees(m);
                for parity in 0..2 {
                    let rows = (degrees + 1 - parity) / 2;
                    let quiet = panels.quiet[parity];
                    matmul_packed(
                        MatMut {
                            data: &mut *block,
                            offset: parity * width,
                            rows,
                            cols: width,
                            row_stride: 2 * width,
                        },
                        &panels.analysis[parity],
                        MatRef {
                            data: if parity == 0 { sym } else { anti },
                            offset: m * layout.order_stride + quiet * layout.ring_stride,
                            rows: half - quiet,
                            cols: width,
                            row_stride: layout.ring_stride,
                            col_stride: 1,
                        },
                    );
                }
            });
        orders
    }

    /// [`Sht::legendre_analysis`] with λ recomputed in registers ([`streamed`]), for groups
    /// of consecutive orders: each group's spectra are first gathered into columns of
    /// rings, reading for every ring the group's orders at once (whole cache lines, where
    /// one order at a time would read a few values from each line).
    fn streamed_analysis(
        &self,
        table: &LegendreTable<T>,
        parts: [&[T]; 2],
        layout: Layout,
        batch: usize,
        orders: &mut [T],
    ) {
        let (width, half) = (2 * batch, table.half_rings());
        let stride = streamed::padded_stride(half);
        let group = (STREAMED_GROUP_BYTES / (2 * width * stride * 8)).clamp(1, MAP_BLOCK);
        let mut blocks = self.split_orders(orders, batch);
        blocks.par_chunks_mut(group).enumerate().for_each_init(
            || (streamed::Scratch::default(), [Vec::new(), Vec::new()]),
            |(scratch, columns), (g, blocks)| {
                let first = g * group;
                // The group's folded spectra in f64: `columns[part][(k · width + c) · stride + p]`
                // for its k-th order, zero-padded to whole vectors.
                for (part, source) in parts.into_iter().enumerate() {
                    let columns = &mut columns[part];
                    columns.clear();
                    columns.resize(blocks.len() * width * stride, 0.0);
                    for p in 0..half {
                        for k in 0..blocks.len() {
                            let ring = &source[(first + k) * layout.order_stride + p * layout.ring_stride..][..width];
                            for (c, value) in ring.iter().enumerate() {
                                columns[(k * width + c) * stride + p] = value.to_f64().unwrap_or(f64::NAN);
                            }
                        }
                    }
                }
                for (k, block) in blocks.iter_mut().enumerate() {
                    let m = first + k;
                    let order_columns = [0, 1].map(|part| &columns[part][k * width * stride..][..width * stride]);
                    let spectra = streamed::Spectra {
                        parts: order_columns,
                        column_stride: stride,
                        vector_stride: streamed::LANES,
                        width,
                    };
                    table.streamed_order(m, spectra, block, scratch);
                }
            },
        );
    }

    /// Per-order blocks `[m][l − m][part][batch]` → `(batch, (lmax+1)²)`, applying the √2
    /// of m > 0.
    fn scatter(&self, orders: &[T], batch: usize, coefficients: &mut [MaybeUninit<T>]) {
        let n = self.n_coefficients();
        let starts = self.order_starts(batch);
        for m in 0..=self.lmax {
            let degrees = self.degrees(m);
            transpose::scatter_order(
                &transpose::OrderBlock {
                    block: &orders[starts[m]..][..degrees * 2 * batch],
                    batch,
                    degrees,
                    parts: if m == 0 { 1 } else { 2 },
                    scale: order_scale(m),
                    stride: n,
                    offset: self.offsets[m],
                },
                coefficients,
            );
        }
    }
}
