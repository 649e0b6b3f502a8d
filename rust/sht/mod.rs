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
//! the next pair's rings are prefetched; synthesis ends in a real inverse FFT per ring
//! (realfft). Chunks of maps, rings and orders run in parallel with rayon. Legendre
//! tables are built once per plan and kept while they fit in [`LEGENDRE_CACHE_BYTES`].
//! Analysis of single maps, and of every map where the table is not kept or exceeds
//! [`STREAMED_MIN_TABLE_BYTES_ANY_BATCH`], recomputes λ in registers instead, a map at a
//! time ([`streamed`]); on Gauss–Legendre grids each map's FFTs are then folded straight
//! into tiles of ring blocks that the kernel reads as vectors. Synthesis recomputes the
//! tables it lacks per call.

pub mod grid;
pub mod legendre;
mod linalg;
mod real;
mod split;
mod streamed;
mod transpose;

use std::mem::MaybeUninit;
use std::sync::{Arc, Mutex};

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner};
use rustfft::{Fft, FftPlanner};

use crate::error::{invalid_argument, Result};
use crate::parallel;
use legendre::{Paired, Recurrence, Scaled};
use linalg::{matmul_packed, MatMut, MatRef, Packed};
pub use real::Real;

/// Largest Legendre table a plan keeps (per node set); larger ones are recomputed.
pub const LEGENDRE_CACHE_BYTES: usize = 256 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    GaussLegendre,
    Equiangular,
}

/// λ_lm at one set of rings, folded to the northern half (equator included).
struct LegendreTable<T> {
    lmax: usize,
    half_rings: usize,
    recurrence: Arc<Recurrence>,
    /// cos θ and λ_mm per half ring, zero-padded to whole vectors of [`streamed::LANES`]
    /// rings (`padded` of them) for the on-the-fly kernel to load directly; λ_mm by
    /// order, as mantissas `sectoral.0[m * padded + p]` and scales `sectoral.1[..]`.
    cos_theta: Vec<f64>,
    sectoral: (Vec<f64>, Vec<i32>),
    padded: usize,
    /// Per order, the vectors of rings from the pole whose λ stay negligible to lmax
    /// ([`streamed::silent_vectors`]), which the on-the-fly kernel skips.
    silent: Vec<usize>,
    /// Per m, when within the cache budget.
    cached: Option<Vec<OrderPanels<T>>>,
}

/// One order's λ_lm, split by the parity of l − m and packed for the kernel both ways:
/// degrees × half rings (analysis) and half rings × degrees (synthesis).
#[derive(Default)]
struct OrderPanels<T> {
    analysis: [Packed<T>; 2],
    synthesis: [Packed<T>; 2],
}

impl<T: Real> LegendreTable<T> {
    fn new(recurrence: Arc<Recurrence>, theta: &[f64], cache_bytes: usize) -> Self {
        let lmax = recurrence.lmax();
        let half = &theta[..theta.len().div_ceil(2)];
        let padded = half.len().next_multiple_of(streamed::LANES);
        let mut by_ring = vec![Scaled::ZERO; half.len() * (lmax + 1)];
        by_ring
            .par_chunks_mut(lmax + 1)
            .zip(half)
            .for_each(|(row, t)| recurrence.sectoral(t.sin(), row));
        let (mut mantissas, mut scales) = (vec![0.0; (lmax + 1) * padded], vec![0; (lmax + 1) * padded]);
        for (p, row) in by_ring.chunks_exact(lmax + 1).enumerate() {
            for (m, value) in row.iter().enumerate() {
                mantissas[m * padded + p] = value.mantissa;
                scales[m * padded + p] = value.scale;
            }
        }
        let mut cos_theta: Vec<f64> = half.iter().map(|t| t.cos()).collect();
        cos_theta.resize(padded, 0.0);
        let mut table = LegendreTable {
            lmax,
            half_rings: half.len(),
            recurrence,
            cos_theta,
            sectoral: (mantissas, scales),
            padded,
            silent: Vec::new(),
            cached: None,
        };
        table.silent = (0..=lmax)
            .into_par_iter()
            .map_init(Paired::default, |paired, m| {
                streamed::silent_vectors(&table.recurrence, m, table.rings(m), paired)
            })
            .collect();
        // Two packed copies of every value.
        if 2 * table.bytes() <= cache_bytes {
            let panels = (0..=lmax)
                .into_par_iter()
                .map(|m| {
                    let mut panels = OrderPanels::default();
                    table.compute(m, &mut panels, Orientation::Both);
                    panels
                })
                .collect();
            table.cached = Some(panels);
        }
        table
    }

    fn half_rings(&self) -> usize {
        self.half_rings
    }

    /// Size of one packed copy of the table (analysis or synthesis).
    fn bytes(&self) -> usize {
        (self.lmax + 1) * (self.lmax + 2) / 2 * self.half_rings() * std::mem::size_of::<T>()
    }

    /// Computes order m's λ and packs the panels `orientation` asks for.
    fn compute(&self, m: usize, panels: &mut OrderPanels<T>, orientation: Orientation) {
        let (degrees, half) = (self.lmax + 1 - m, self.half_rings());
        let rings = self.rings(m);
        let start: Vec<Scaled> = (rings.mantissa.iter().zip(rings.scale))
            .take(half)
            .map(|(&mantissa, &scale)| Scaled { mantissa, scale })
            .collect();
        let mut values = vec![0f64; degrees * half];
        self.recurrence.rows(m, &self.cos_theta[..half], &start, &mut values);
        let lambda: Vec<T> = values.into_iter().map(T::of).collect();
        for parity in 0..2 {
            let rows = (degrees + 1 - parity) / 2;
            if orientation != Orientation::Synthesis {
                panels.analysis[parity].pack(MatRef {
                    data: &lambda,
                    offset: parity * half,
                    rows,
                    cols: half,
                    row_stride: 2 * half,
                    col_stride: 1,
                });
            }
            if orientation != Orientation::Analysis {
                panels.synthesis[parity].pack(MatRef {
                    data: &lambda,
                    offset: parity * half,
                    rows: half,
                    cols: rows,
                    row_stride: 1,
                    col_stride: 2 * half,
                });
            }
        }
    }

    /// Order m's analysis with λ recomputed in registers ([`streamed`]): `spectra` at
    /// this table's rings → `out[(l − m) · width + c]`.
    fn streamed_order(&self, m: usize, spectra: streamed::Spectra<'_>, out: &mut [T], scratch: &mut streamed::Scratch) {
        streamed::analysis_order(
            streamed::Job {
                recurrence: &self.recurrence,
                m,
                rings: streamed::Rings {
                    silent: self.silent[m],
                    ..self.rings(m)
                },
                spectra,
            },
            out,
            scratch,
        );
    }

    /// The half rings' cos θ and order m's λ_mm there, padded to whole vectors (none
    /// counted silent).
    fn rings(&self, m: usize) -> streamed::Rings<'_> {
        streamed::Rings {
            cos_theta: &self.cos_theta,
            mantissa: &self.sectoral.0[m * self.padded..][..self.padded],
            scale: &self.sectoral.1[m * self.padded..][..self.padded],
            silent: 0,
        }
    }

    /// Order m's panels: from the cache, or computed into `scratch` (only the
    /// `orientation` asked for).
    fn panels<'a>(&'a self, m: usize, scratch: &'a mut OrderPanels<T>, orientation: Orientation) -> &'a OrderPanels<T> {
        match &self.cached {
            Some(panels) => &panels[m],
            None => {
                self.compute(m, scratch, orientation);
                scratch
            }
        }
    }
}

/// Which packed copies of λ a caller needs.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Orientation {
    Analysis,
    Synthesis,
    Both,
}

/// The equiangular → Gauss–Legendre resampling, `[m parity][symmetric, antisymmetric]`,
/// packed for both directions.
struct Resampling<T> {
    forward: [[Packed<T>; 2]; 2],
    adjoint: [[Packed<T>; 2]; 2],
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

/// Chunks of at most this many maps are analysed with λ recomputed in registers
/// ([`streamed`]) even where the table is kept: a one-map product reuses each table value
/// only twice, so reading the table costs more than recomputing it. Measured on one
/// thread, f64 (f32), one map: 90×180 0.13 (0.12) ms with the table, 0.10 (0.10) on the
/// fly; 128×256 0.20 (0.25) and 0.18 (0.175).
const STREAMED_MAX_BATCH: usize = 1;

/// Tables larger than this (about half the last-level cache) are read from memory for
/// every chunk of maps: beyond it every batch is analysed on the fly, a map at a time.
/// Measured on one thread, f64, 256×512 (34 MB table), batches of 8 (192): 1.15 (1.32)
/// ms a map with the table, 1.20 on the fly in chunks of 8 maps, 0.90 (1.13) a map at a
/// time.
const STREAMED_MIN_TABLE_BYTES_ANY_BATCH: usize = 16 << 20;

/// Bytes of gathered spectra a group of orders analysed on the fly may occupy (per
/// worker, in cache).
const STREAMED_GROUP_BYTES: usize = 256 << 10;

/// Maps transposed together between per-ring and per-order layouts: one cache line of f64.
const MAP_BLOCK: usize = split::BLOCK;

/// Bytes of folded spectra a chunk of maps may occupy: small enough to stay in cache
/// while a chunk goes through every stage of a transform.
const CHUNK_BYTES: usize = 2 << 20;

/// Maps larger than this (a core's L2 cache) are analysed one after another, each parallel
/// inside over orders ([`Chunks::OneAfterAnother`]), rather than one per worker: two at once evict each other's
/// intermediates. Measured on two threads, f64 512×1024 (4 MB a map), batch of 8: 2.40 ms
/// a map one per worker, 2.26 one after another; 256×512 (1 MB), batch of 192: 0.53 one
/// per worker, 0.66 one after another.
const SHARED_MAP_BYTES: usize = 2 << 20;

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
    pub(crate) fn with_cache_limit(
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
    /// caller: every value is written once, and zeroing a large output cost up to a tenth
    /// of a transform.
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

    /// FFT of every ring, north and south rings folded into symmetric and antisymmetric
    /// parts scaled by `ring_factors`. Layout `[half ring][m][part][batch]`, part 0 the
    /// cosine sums Σ_k x_k cos mφ_k and part 1 the sine sums Σ_k x_k sin mφ_k.
    ///
    /// One complex FFT per ring pair gives both parts: with z = (n + s) + i(n − s) for the
    /// north and south rings n and s, Z = SYM + i·ANTI, and since both are spectra of real
    /// rings, SYM_m = (Z_m + conj Z_−m)/2 and ANTI_m = (Z_m − conj Z_−m)/2i. Measured, this
    /// halves the FFT time of two real FFTs (realfft) at 180 points in f64, and more in f32.
    fn fold_rings(&self, maps: &[T], batch: usize, ring_factors: &[f64]) -> (Vec<T>, Vec<T>) {
        let (nlat, nlon, orders, width) = (self.nlat, self.nlon, self.lmax + 1, 2 * batch);
        let ring = |b: usize, j: usize| &maps[(b * nlat + j) * nlon..][..nlon];
        let slab = orders * width;
        let mut sym = self.pool.take(self.half_rings() * slab);
        let mut anti = self.pool.take(self.half_rings() * slab);
        let zero = Complex::new(T::zero(), T::zero());
        sym.par_chunks_mut(slab)
            .zip(anti.par_chunks_mut(slab))
            .enumerate()
            .for_each_init(
                || {
                    (
                        vec![zero; MAP_BLOCK * nlon],
                        vec![zero; self.fft.get_inplace_scratch_len()],
                    )
                },
                |(spectra, scratch), (p, (sym_p, anti_p))| {
                    let mirror = nlat - 1 - p;
                    // Half of the scale: SYM and ANTI are halves of sums of Z values.
                    let factor = T::of(0.5 * ring_factors[p]);
                    // The equator ring has no mirror: symmetric part only.
                    let anti_factor = if mirror == p { T::zero() } else { factor };
                    // Maps in blocks, so that each (m, part) run written below is a whole line.
                    for b0 in (0..batch).step_by(MAP_BLOCK) {
                        let block = MAP_BLOCK.min(batch - b0);
                        // The next pair's rings, fetched one at a time while this pair is
                        // transformed: they lie a whole map apart, beyond the hardware
                        // prefetcher, and fetching them all at once stalled on the cache's
                        // queue of misses (twice the time of the whole fold at 192 maps).
                        let next_maps = if p + 1 < mirror { block } else { 0 };
                        let mut next = (0..next_maps).flat_map(|i| [ring(b0 + i, p + 1), ring(b0 + i, mirror - 1)]);
                        let spectra = &mut spectra[..block * nlon];
                        for (i, z) in spectra.chunks_exact_mut(nlon).enumerate() {
                            let south = (mirror != p).then(|| ring(b0 + i, mirror));
                            pack_ring_pair(z, ring(b0 + i, p), south, T::one());
                            self.fft.process_with_scratch(z, scratch);
                            if let Some(ring) = next.next() {
                                prefetch(ring);
                            }
                        }
                        let spacing = orders.div_ceil(next_maps.max(1));
                        let mut due = 0;
                        split::split_pair(
                            &split::PairSpectra {
                                spectra,
                                nlon,
                                sym_factor: factor,
                                anti_factor,
                            },
                            &mut split::PairParts {
                                sym: sym_p,
                                anti: anti_p,
                                width,
                                half_width: batch,
                                first: b0,
                            },
                            orders,
                            &mut |m| {
                                if m >= due {
                                    if let Some(ring) = next.next() {
                                        prefetch(ring);
                                    }
                                    due += spacing;
                                }
                            },
                        );
                    }
                },
            );
        (sym, anti)
    }

    /// One map's FFTs folded as [`Sht::fold_rings`] does, for the on-the-fly analysis:
    /// ring pairs in blocks of [`streamed::LANES`], each block a tile `[m][part][ring]`
    /// (cosine and sine sums, the block's rings innermost), so that every order's values
    /// at a block's rings are one vector for the kernel, with no gathering between.
    /// Returns the symmetric and antisymmetric tiles, `[block][m][part][ring]`.
    fn fold_ring_blocks(&self, map: &[T], ring_factors: &[f64]) -> [Vec<T>; 2] {
        const RINGS: usize = streamed::LANES;
        let (nlat, nlon, orders, half) = (self.nlat, self.nlon, self.lmax + 1, self.half_rings());
        let tile = self.ring_block_tile();
        let blocks = half.div_ceil(RINGS);
        let [mut sym, mut anti] = [0, 1].map(|_| self.pool.take(blocks * tile));
        let zero = Complex::new(T::zero(), T::zero());
        let ring = |j: usize| &map[j * nlon..][..nlon];
        sym.par_chunks_mut(tile)
            .zip(anti.par_chunks_mut(tile))
            .enumerate()
            .for_each_init(
                || (vec![zero; RINGS * nlon], vec![zero; self.fft.get_inplace_scratch_len()]),
                |(spectra, scratch), (block, (sym, anti))| {
                    for (k, z) in spectra.chunks_exact_mut(nlon).enumerate() {
                        let p = block * RINGS + k;
                        if p >= half {
                            // Past the last ring pair: zeros, which the kernel pads with.
                            z.fill(zero);
                            continue;
                        }
                        // Each ring's factor applied here: the split takes one for the block.
                        let mirror = nlat - 1 - p;
                        let south = (mirror != p).then(|| ring(mirror));
                        pack_ring_pair(z, ring(p), south, T::of(ring_factors[p]));
                        self.fft.process_with_scratch(z, scratch);
                    }
                    // The block's rings take the place of a block of maps.
                    split::split_pair(
                        &split::PairSpectra {
                            spectra,
                            nlon,
                            sym_factor: T::of(0.5),
                            anti_factor: T::of(0.5),
                        },
                        &mut split::PairParts {
                            sym,
                            anti,
                            width: 2 * RINGS,
                            half_width: RINGS,
                            first: 0,
                        },
                        orders,
                        &mut |_| {},
                    );
                },
            );
        [sym, anti]
    }

    /// Values per tile of [`Sht::fold_ring_blocks`]: every order's two parts at a block's
    /// rings.
    fn ring_block_tile(&self) -> usize {
        (self.lmax + 1) * 2 * streamed::LANES
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

    /// Inverse of the folding: per ring, (cos, sin) sums = symmetric ± antisymmetric
    /// part, scaled by `ring_factors`, then an inverse real FFT. Input `[m][half ring][part][batch]`.
    fn unfold_rings(&self, sym: &[T], anti: &[T], batch: usize, ring_factors: &[f64], maps: &mut [T]) {
        let (nlat, half, width) = (self.nlat, self.half_rings(), 2 * batch);
        let half_t = T::of(0.5);
        maps.par_chunks_mut(self.nlon)
            .enumerate()
            .with_min_len(8)
            .for_each_init(
                || (self.inverse.make_input_vec(), self.inverse.make_scratch_vec()),
                |(spectrum, scratch), (row, ring)| {
                    let (b, j) = (row / nlat, row % nlat);
                    let (p, south) = if j < half { (j, false) } else { (nlat - 1 - j, true) };
                    let factor = T::of(ring_factors[j]);
                    spectrum
                        .iter_mut()
                        .for_each(|v| *v = Complex::new(T::zero(), T::zero()));
                    for (m, slot) in spectrum.iter_mut().enumerate().take(self.lmax + 1) {
                        let (cosine, sine) = ((m * half + p) * width + b, (m * half + p) * width + batch + b);
                        let (cos_sum, sin_sum) = if south {
                            (sym[cosine] - anti[cosine], sym[sine] - anti[sine])
                        } else {
                            (sym[cosine] + anti[cosine], sym[sine] + anti[sine])
                        };
                        // c2r computes Y_0 + 2 Re Σ_m Y_m e^{imφ}.
                        *slot = if m == 0 {
                            Complex::new(factor * cos_sum, T::zero())
                        } else {
                            Complex::new(factor * half_t * cos_sum, -(factor * half_t * sin_sum))
                        };
                    }
                    self.inverse
                        .process_with_scratch(spectrum, ring, scratch)
                        .expect("buffers sized by the plan");
                },
            );
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
                            offset: m * layout.order_stride,
                            rows: half,
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
                    matmul_packed(
                        MatMut {
                            data: destination,
                            offset: 0,
                            rows: half,
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

    /// Maps each order's folded spectra to other rings with a packed per-parity matrix
    /// (`matrices[m % 2][symmetric, antisymmetric]`): the equiangular → Gauss–Legendre
    /// resampling or its adjoint. Order m's input starts at `m · input.order_stride`, its
    /// rings `input.ring_stride` apart; the output is `[m][ring][part][batch]`.
    fn map_rings(
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

impl Grid {
    pub fn name(self) -> &'static str {
        match self {
            Grid::GaussLegendre => "Gauss–Legendre",
            Grid::Equiangular => "equiangular",
        }
    }
}

/// One complex FFT input for a ring pair: z = scale · ((n + s) + i(n − s)) for the north
/// and south rings, whose FFT gives both parts (see [`Sht::fold_rings`]); an equator ring,
/// which has no mirror, gives z = scale · n, no antisymmetric part.
fn pack_ring_pair<T: Real>(z: &mut [Complex<T>], north: &[T], south: Option<&[T]>, scale: T) {
    match south {
        Some(south) => {
            for ((z, &n), &s) in z.iter_mut().zip(north).zip(south) {
                *z = Complex::new(scale * (n + s), scale * (n - s));
            }
        }
        None => z
            .iter_mut()
            .zip(north)
            .for_each(|(z, &n)| *z = Complex::new(scale * n, T::zero())),
    }
}

/// Asks the cache to fetch `values` ahead of use.
#[inline]
fn prefetch<T>(values: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = values.as_ptr().cast::<i8>();
        for offset in (0..std::mem::size_of_val(values)).step_by(64) {
            // SAFETY: prefetching has no effect on memory; the address is within `values`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.add(offset)) };
        }
    }
}

/// 1 for m = 0, √2 otherwise: the real basis' normalisation.
fn order_scale<T: Real>(m: usize) -> T {
    T::of(if m == 0 { 1.0 } else { std::f64::consts::SQRT_2 })
}

/// Restricts the full resampling matrices (Gauss rings × equiangular rings) to folded
/// symmetric/antisymmetric parts on half rings, with the Gauss weights folded in.
///
/// A folded symmetric part holds g_j + g_j' on paired rings and g_j on an equator ring
/// (antisymmetric: g_j − g_j', and 0 on the equator); the rows are built so that the
/// output holds the same quantities at the Gauss rings, times their weights.
fn fold_resampling<T: Real>(full: &[Vec<f64>; 2], n_source: usize, gauss_weights: &[f64]) -> Resampling<T> {
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

#[cfg(test)]
mod tests;
