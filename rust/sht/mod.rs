//! Spherical harmonic transform: analysis (grid → coefficients), synthesis (coefficients
//! → grid) and the exact adjoint of analysis, batched over maps.
//!
//! # Basis and layout
//! Real orthonormal harmonics without the Condon–Shortley phase:
//! Y_l0 = λ_l0(θ), and for m > 0 a cosine part √2 λ_lm(θ) cos mφ and a sine part
//! √2 λ_lm(θ) sin mφ (see [`legendre`]). Coefficients are stored in blocks by m: the m = 0
//! block holds l = 0..=lmax; each m > 0 is followed by its cosine block (l = m..=lmax) and
//! its sine block (same l). [`Sht::degrees_orders`] lists (l, m) per position, the sine
//! part labelled −m. There are (lmax + 1)² coefficients.
//!
//! # Grids
//! Rings at colatitudes θ_j, each with `nlon` equally spaced longitudes φ_k = 2πk/nlon.
//! Gauss–Legendre rings integrate exactly with nlat ≥ lmax + 1. Equiangular rings
//! (θ_j = πj/(nlat−1), poles included) are analysed by resampling each Fourier order
//! exactly onto Gauss–Legendre rings ([`grid::equiangular_to_gauss`]), exact for
//! nlat ≥ lmax + 2.
//!
//! # How it runs
//! An FFT along the rings, then per order m a Legendre step that is a matrix product
//! ([`linalg`]) over a chunk of maps. North and south rings are folded into
//! symmetric and antisymmetric parts, since λ_lm(−x) = (−1)^(l+m) λ_lm(x): each half of the
//! degrees meets only one of them, which halves the work. Analysis gets both parts of a
//! ring pair from one complex FFT (rustfft), split into the parts and transposed to the
//! product's layout (maps innermost) in vector registers ([`split`], [`transpose`]), while
//! later pairs' rings are prefetched; synthesis ends in a real inverse FFT per ring
//! (realfft). Chunks of maps, rings and orders run in parallel with rayon. Legendre
//! tables are built once per plan and kept while they fit in [`LEGENDRE_CACHE_BYTES`].
//! Analysis of single maps, and of every map where the table is not kept or exceeds
//! `STREAMED_MIN_TABLE_BYTES_ANY_BATCH` ([`analysis`]), recomputes λ in registers
//! instead, a map at a time ([`streamed`]); on Gauss–Legendre grids each map's FFTs are
//! then folded straight into tiles of ring blocks that the kernel reads as vectors.
//! Synthesis recomputes the tables it lacks per call.
//!
//! # Files, by stage
//! This file holds the plan type: its construction, accessors and the batching shared by
//! every stage. The stages are further `impl Sht` blocks: [`fold`], the FFT stage (rings ↔
//! folded spectra); [`analysis`] and [`synthesis`] (with the adjoint), the Legendre step
//! and the layout changes around it; [`resample`], equiangular rings to Gauss–Legendre
//! ones and back. What they use does not depend on them or on this file: the fixed
//! matrices a plan builds ([`table`]), the matrix kernel ([`linalg`]), the on-the-fly
//! kernel ([`streamed`]), the vector transpositions ([`split`], [`transpose`]), the
//! recurrence ([`legendre`]), the grids ([`grid`]) and the scalar type ([`Real`]).

// The docs above link the private stages for readers of `cargo doc --document-private-items`
// (the crate is not published; its public face is the Python package).
#![allow(rustdoc::private_intra_doc_links)]

mod analysis;
mod fold;
pub mod grid;
pub mod legendre;
mod linalg;
mod real;
mod resample;
mod split;
mod streamed;
mod synthesis;
mod table;
mod transpose;

use std::sync::{Arc, Mutex};

use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner};
use rustfft::{Fft, FftPlanner};

use crate::error::{invalid_argument, Result};
use crate::parallel;
use legendre::Recurrence;
pub use real::Real;
use table::{fold_resampling, LegendreTable, Resampling};

/// Largest Legendre table a plan keeps (per node set); larger ones are recomputed.
pub const LEGENDRE_CACHE_BYTES: usize = 256 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    GaussLegendre,
    Equiangular,
}

impl Grid {
    pub fn name(self) -> &'static str {
        match self {
            Grid::GaussLegendre => "Gauss–Legendre",
            Grid::Equiangular => "equiangular",
        }
    }
}

/// A transform plan: grid, FFTs and Legendre tables, built once and reused.
pub struct Sht<T: Real> {
    nlat: usize,
    nlon: usize,
    lmax: usize,
    grid: Grid,
    theta: Vec<f64>,
    weights: Vec<f64>,
    /// Complex FFT along a ring, for analysis (two real rings at once).
    fft: Arc<dyn Fft<T>>,
    inverse: Arc<dyn ComplexToReal<T>>,
    /// λ at the grid's own rings: synthesis, and analysis on Gauss–Legendre grids.
    at_grid: LegendreTable<T>,
    /// Equiangular grids only: λ and weights at lmax + 1 Gauss–Legendre rings, and the
    /// resampling onto them, `[m parity][symmetric, antisymmetric]`, row-major
    /// (Gauss half rings × grid half rings), Gauss weights folded in.
    gauss: Option<(LegendreTable<T>, Resampling<T>)>,
    /// Position of each order's first coefficient.
    offsets: Vec<usize>,
    /// Scratch buffers kept between calls, so repeated transforms do not pay for fresh
    /// pages every time.
    pool: BufferPool<T>,
}

/// Reusable zero-filled scratch buffers.
struct BufferPool<T> {
    free: Mutex<Vec<Vec<T>>>,
}

impl<T: Real> BufferPool<T> {
    /// A buffer of `len` values whose contents are unspecified (left from earlier
    /// calls): callers write every element before reading it.
    fn take(&self, len: usize) -> Vec<T> {
        let reused = self.free.lock().ok().and_then(|mut free| {
            // The smallest buffer that is large enough: no reallocation, no fresh pages.
            let best = (0..free.len())
                .filter(|&i| free[i].capacity() >= len)
                .min_by_key(|&i| free[i].capacity())?;
            Some(free.swap_remove(best))
        });
        let mut buffer = reused.unwrap_or_default();
        buffer.resize(len, T::zero());
        buffer
    }

    fn give(&self, buffers: impl IntoIterator<Item = Vec<T>>) {
        if let Ok(mut free) = self.free.lock() {
            free.extend(buffers);
            free.truncate(4 * rayon::current_num_threads() + 8);
        }
    }
}

/// Maps transposed together between per-ring and per-order layouts: one cache line of f64.
const MAP_BLOCK: usize = split::BLOCK;

/// Bytes of folded spectra a chunk of maps may occupy: small enough to stay in cache
/// while a chunk goes through every stage of a transform.
const CHUNK_BYTES: usize = 2 << 20;

/// How a batched transform splits its batch.
#[derive(Clone, Copy)]
enum Chunks {
    /// Chunks of this many items, run in parallel.
    Parallel(usize),
    /// One item after another, each parallel inside: items too large to share a cache.
    OneAfterAnother,
}

/// Where the (ring, order) blocks of a folded spectrum sit in its buffer.
#[derive(Clone, Copy)]
struct Layout {
    ring_stride: usize,
    order_stride: usize,
}

impl<T: Real> Sht<T> {
    pub fn new(nlat: usize, nlon: usize, lmax: usize, grid: Grid) -> Result<Self> {
        Self::with_cache_limit(nlat, nlon, lmax, grid, LEGENDRE_CACHE_BYTES)
    }

    /// A plan that keeps Legendre tables up to `cache_bytes` (tests use 0 to exercise the
    /// on-the-fly path on small grids).
    pub(super) fn with_cache_limit(
        nlat: usize,
        nlon: usize,
        lmax: usize,
        grid: Grid,
        cache_bytes: usize,
    ) -> Result<Self> {
        let min_rings = match grid {
            Grid::GaussLegendre => lmax + 1,
            Grid::Equiangular => (lmax + 2).max(2),
        };
        if nlat < min_rings {
            return invalid_argument!(
                "nlat = {nlat} rings are too few for exact quadrature at lmax = {lmax} on the {} grid: need nlat ≥ {min_rings}",
                grid.name()
            );
        }
        if nlon < 2 * lmax + 1 {
            return invalid_argument!(
                "nlon = {nlon} is too small for lmax = {lmax}: need nlon ≥ 2·lmax + 1 = {}",
                2 * lmax + 1
            );
        }
        let recurrence = Arc::new(Recurrence::new(lmax));
        let (theta, weights) = match grid {
            Grid::GaussLegendre => grid::gauss_legendre(nlat),
            Grid::Equiangular => (grid::equiangular(nlat), grid::clenshaw_curtis_weights(nlat)),
        };
        let gauss = (grid == Grid::Equiangular).then(|| {
            let (gauss_theta, gauss_weights) = grid::gauss_legendre(lmax + 1);
            let resampling = fold_resampling(&grid::equiangular_to_gauss(&theta, &gauss_theta), nlat, &gauss_weights);
            (
                LegendreTable::new(recurrence.clone(), &gauss_theta, cache_bytes),
                resampling,
            )
        });
        let mut planner = RealFftPlanner::<T>::new();
        let mut offsets = Vec::with_capacity(lmax + 1);
        let mut next = 0;
        for m in 0..=lmax {
            offsets.push(next);
            next += if m == 0 { lmax + 1 } else { 2 * (lmax + 1 - m) };
        }
        Ok(Sht {
            nlat,
            nlon,
            lmax,
            grid,
            at_grid: LegendreTable::new(recurrence, &theta, cache_bytes),
            theta,
            weights,
            fft: FftPlanner::new().plan_fft_forward(nlon),
            inverse: planner.plan_fft_inverse(nlon),
            gauss,
            offsets,
            pool: BufferPool {
                free: Mutex::new(Vec::new()),
            },
        })
    }

    pub fn nlat(&self) -> usize {
        self.nlat
    }
    pub fn nlon(&self) -> usize {
        self.nlon
    }
    pub fn lmax(&self) -> usize {
        self.lmax
    }
    pub fn grid(&self) -> Grid {
        self.grid
    }
    pub fn n_coefficients(&self) -> usize {
        (self.lmax + 1) * (self.lmax + 1)
    }
    /// Ring colatitudes θ_j.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }
    /// Ring quadrature weights (Gauss–Legendre, or Clenshaw–Curtis on equiangular rings),
    /// summing to 2; multiply by 2π/nlon for the weight of one grid point.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// (l, m) of every coefficient position, sine parts labelled −m.
    pub fn degrees_orders(&self) -> Vec<[i64; 2]> {
        let mut out = Vec::with_capacity(self.n_coefficients());
        for m in 0..=self.lmax as i64 {
            let degrees = m..=self.lmax as i64;
            out.extend(degrees.clone().map(|l| [l, m]));
            if m > 0 {
                out.extend(degrees.map(|l| [l, -m]));
            }
        }
        out
    }

    /// Runs `transform` on the batch split as `chunks` says (callers size chunks so that
    /// their intermediates stay in cache).
    fn for_each_chunk<Out: Send>(
        &self,
        chunks: Chunks,
        input: &[T],
        input_width: usize,
        output: &mut [Out],
        output_width: usize,
        transform: impl Fn(&[T], &mut [Out]) + Sync,
    ) {
        let transform = &transform;
        parallel::in_pool(|| match chunks {
            Chunks::OneAfterAnother => output
                .chunks_mut(output_width)
                .zip(input.chunks(input_width))
                .for_each(|(out, item)| transform(item, out)),
            Chunks::Parallel(items) => output
                .par_chunks_mut(items * output_width)
                .zip(input.par_chunks(items * input_width))
                .for_each(|(out, items)| transform(items, out)),
        })
    }

    /// Items per chunk of a batched transform.
    fn chunk_items(&self) -> usize {
        // At least a block of maps per chunk: narrower products waste the kernel's tiles,
        // and each order's slice of a chunk stays small however large the grid.
        let bytes_per_item = 4 * self.half_rings().max(self.lmax + 1) * (self.lmax + 1) * std::mem::size_of::<T>();
        (CHUNK_BYTES / bytes_per_item).max(MAP_BLOCK)
    }

    fn check_len(&self, name: &str, len: usize, batch: usize, per_item: usize) -> Result<()> {
        if len != batch * per_item {
            return invalid_argument!("{name} has {len} values; expected batch {batch} × {per_item}");
        }
        Ok(())
    }

    fn half_rings(&self) -> usize {
        self.nlat.div_ceil(2)
    }

    fn degrees(&self, m: usize) -> usize {
        self.lmax + 1 - m
    }

    /// Splits a buffer of per-order blocks (`[m][l − m][part][batch]`) into the blocks.
    fn split_orders<'a>(&self, buffer: &'a mut [T], batch: usize) -> Vec<&'a mut [T]> {
        let mut rest = buffer;
        let mut blocks = Vec::with_capacity(self.lmax + 1);
        for m in 0..=self.lmax {
            let (block, tail) = rest.split_at_mut(self.degrees(m) * 2 * batch);
            blocks.push(block);
            rest = tail;
        }
        blocks
    }

    /// Where each order's block starts in a `[m][l − m][part][batch]` buffer.
    fn order_starts(&self, batch: usize) -> Vec<usize> {
        (0..=self.lmax)
            .scan(0, |next, m| {
                let start = *next;
                *next += self.degrees(m) * 2 * batch;
                Some(start)
            })
            .collect()
    }
}

/// 1 for m = 0, √2 otherwise: the real basis' normalisation.
fn order_scale<T: Real>(m: usize) -> T {
    T::of(if m == 0 { 1.0 } else { std::f64::consts::SQRT_2 })
}

#[cfg(test)]
mod tests;
