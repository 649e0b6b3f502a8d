//! The Legendre step of analysis with λ_lm recomputed in registers, for one order m:
//! `out[(l − m) · width + c]` = Σ_p λ_lm(θ_p) · part[(l − m) % 2](c, p), the symmetric part
//! of column c at half ring p for even l − m and the antisymmetric one for odd.
//!
//! Used where a stored table would cost more than recomputing it: grids whose table is
//! too large to keep or to stream from memory for every chunk of maps, and batches too
//! narrow for the matrix product to reuse each table value. The recurrence runs two
//! degrees a step in cos² θ ([`Paired`]): each value serves an even degree through the
//! symmetric part and an odd one through the antisymmetric part times cos θ (for one map,
//! three quarters of the operations of one degree a step). Columns are taken in groups of
//! up to four and rings in blocks of a few vectors of [`LANES`]; a block's recurrence
//! state and its group's spectra stay in registers while l runs (long orders stop every
//! [`PAIR_CHUNK`] pairs and resume block by block). Partial sums are kept per (pair of
//! degrees, part, column) as one vector of lanes, to which every block adds, and reduced
//! once at the end.
//!
//! Near the poles λ_mm underflows for large m (see [`legendre`](super::legendre)): a
//! block starts with careful steps that track each ring's scale, add nothing while every
//! value is negligible, and count scaled values as 0 (they are kept below 2^−70, so a
//! value turns plain as soon as it may matter), and hands over to the fast loop once all
//! are plain doubles. Vectors of rings next to the pole whose values stay negligible up
//! to lmax ([`silent_vectors`], counted once per plan) are not run at all.

use super::legendre::{Paired, Recurrence, BIG, SMALL};
use super::real::Real;
use lanes::Lanes;
pub(super) use lanes::LANES;

/// Partial sums whose λ are all below this are not added: next to values of order one
/// they change no coefficient (2^−70 × a few thousand rings is below 10^−17).
pub(super) const QUIET: f64 = 1.0 / (1u128 << 70) as f64;

/// Pairs of degrees whose sums the plain loop of long orders runs through for every block
/// before the next ones (one map's sums: 16 KB).
const PAIR_CHUNK: usize = 64;

/// An order's folded spectra, part 0 symmetric and part 1 antisymmetric, in vectors of
/// [`LANES`] rings: column c's rings `LANES · v ..` at `parts[part][c · column_stride +
/// v · vector_stride ..][..LANES]`, zero beyond the last ring. Columns of rings
/// (`vector_stride` = [`LANES`]) and tiles of [`LANES`] rings by columns both fit.
#[derive(Clone, Copy)]
pub(super) struct Spectra<'a> {
    pub parts: [&'a [f64]; 2],
    pub column_stride: usize,
    pub vector_stride: usize,
    pub width: usize,
}

impl Spectra<'_> {
    /// Vector `vector` of column `c` of `part`.
    #[inline(always)]
    fn load<V: Lanes>(&self, part: usize, c: usize, vector: usize) -> V {
        V::load(
            self.parts[part][c * self.column_stride + vector * self.vector_stride..][..LANES]
                .try_into()
                .unwrap(),
        )
    }
}

/// The half rings: cos θ_p and λ_mm(θ_p) of the order, as mantissa · 2^(600 · scale)
/// ([`Scaled`](super::legendre::Scaled)), zero-padded to whole vectors of [`LANES`].
/// `silent`: how many vectors of rings from the pole stay negligible up to lmax (see
/// [`silent_vectors`]); they add nothing, and are skipped.
#[derive(Clone, Copy)]
pub(super) struct Rings<'a> {
    pub cos_theta: &'a [f64],
    pub mantissa: &'a [f64],
    pub scale: &'a [i32],
    pub silent: usize,
}

impl Rings<'_> {
    /// Vectors of [`LANES`] rings.
    fn vectors(&self) -> usize {
        self.cos_theta.len() / LANES
    }

    /// The `R` vectors from ring `first`: cos θ, and λ_mm as mantissas and scales.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn load<V: Lanes, const R: usize>(&self, first: usize) -> ([V; R], [V; R], [[i32; LANES]; R]) {
        let (mut x, mut mantissa, mut scale) = ([V::splat(0.0); R], [V::splat(0.0); R], [[0; LANES]; R]);
        // A loop, not a closure: see `Order::careful_start`.
        for r in 0..R {
            let ring = first + r * LANES;
            x[r] = V::load(self.cos_theta[ring..][..LANES].try_into().unwrap());
            mantissa[r] = V::load(self.mantissa[ring..][..LANES].try_into().unwrap());
            scale[r] = self.scale[ring..][..LANES].try_into().unwrap();
        }
        (x, mantissa, scale)
    }
}

/// Reusable buffers of one worker.
#[derive(Default)]
pub(super) struct Scratch {
    sums: Vec<[f64; LANES]>,
    paired: Paired,
    /// The running odd-degree sums of the paired recurrence, per column.
    odd: Vec<f64>,
}

/// Spectra padded to whole vectors: the `stride` for `half_rings` rings. Columns a power
/// of two apart would share cache sets (seen at 512×1024, 8 maps: research/performance.md),
/// so such strides get one more vector.
pub(super) fn padded_stride(half_rings: usize) -> usize {
    let stride = half_rings.next_multiple_of(LANES);
    if stride.is_multiple_of(128) {
        stride + LANES
    } else {
        stride
    }
}

/// One order's analysis: its recurrence, rings and spectra.
pub(super) struct Job<'a> {
    pub recurrence: &'a Recurrence,
    pub m: usize,
    pub rings: Rings<'a>,
    pub spectra: Spectra<'a>,
}

/// One order's analysis, see the module docs; `out` holds (lmax + 1 − m) × width values.
pub(super) fn analysis_order<T: Real>(job: Job<'_>, out: &mut [T], scratch: &mut Scratch) {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { analysis_order_avx512(job, out, scratch) };
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { analysis_order_avx2(job, out, scratch) };
        }
    }
    analysis_order_inline::<T, [f64; LANES]>(job, out, scratch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn analysis_order_avx512<T: Real>(job: Job<'_>, out: &mut [T], scratch: &mut Scratch) {
    analysis_order_inline::<T, lanes::Avx512>(job, out, scratch)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn analysis_order_avx2<T: Real>(job: Job<'_>, out: &mut [T], scratch: &mut Scratch) {
    analysis_order_inline::<T, [f64; LANES]>(job, out, scratch)
}

/// How many vectors of [`LANES`] rings of order m, counted from the pole, have every
/// λ_lm, l ≤ lmax, negligible (below [`QUIET`]): the careful steps of a block made of them
/// would run to lmax and add nothing. Exact: each ring's values, rescaling and wake-up
/// follow the same steps as in [`analysis_order`], which are the same in any block. The
/// `silent` of `rings` is ignored.
pub(super) fn silent_vectors(recurrence: &Recurrence, m: usize, rings: Rings<'_>, paired: &mut Paired) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { silent_vectors_avx512(recurrence, m, rings, paired) };
        }
    }
    silent_vectors_inline::<[f64; LANES]>(recurrence, m, rings, paired)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn silent_vectors_avx512(recurrence: &Recurrence, m: usize, rings: Rings<'_>, paired: &mut Paired) -> usize {
    silent_vectors_inline::<lanes::Avx512>(recurrence, m, rings, paired)
}

#[inline(always)]
fn silent_vectors_inline<V: Lanes>(recurrence: &Recurrence, m: usize, rings: Rings<'_>, paired: &mut Paired) -> usize {
    let steps = &recurrence.paired(m, paired).steps;
    for vector in 0..rings.vectors() {
        let (x, mut current, scale) = rings.load::<V, 1>(vector * LANES);
        let mut previous = [V::splat(0.0)];
        let mut state = LaneState::<V, 1>::new(scale, &mut previous, &mut current);
        let x2 = squares(&x);
        for &coefficients in &steps[1..] {
            if state.live {
                break;
            }
            step(coefficients, &x2, &mut previous, &mut current);
            if current[0].any_reaches(state.threshold[0]) {
                state.update(&mut previous, &mut current);
            }
        }
        if state.live {
            return vector;
        }
    }
    rings.vectors()
}

#[inline(always)]
fn analysis_order_inline<T: Real, V: Lanes>(job: Job<'_>, out: &mut [T], scratch: &mut Scratch) {
    let Job {
        recurrence,
        m,
        rings,
        spectra,
    } = job;
    let half = rings.cos_theta.len();
    assert!(half.is_multiple_of(LANES) && rings.mantissa.len() == half && rings.scale.len() == half);
    let Scratch { sums, paired, odd } = scratch;
    let paired = recurrence.paired(m, paired);
    let (degrees, pairs, width) = (recurrence.lmax() + 1 - m, paired.steps.len(), spectra.width);
    assert_eq!(out.len(), degrees * width);
    // Columns in groups of four, two or one, each with its own loop over blocks of rings:
    // a group's spectra stay in registers while its recurrence runs.
    let mut first = 0;
    while first < width {
        let group = match width - first {
            4.. => 4,
            2 | 3 => 2,
            _ => 1,
        };
        sums.clear();
        sums.resize(pairs * 2 * group, [0.0; LANES]);
        let order = Order {
            steps: &paired.steps,
            spectra: Spectra {
                parts: spectra.parts.map(|part| &part[first * spectra.column_stride..]),
                width: group,
                ..spectra
            },
            rings,
        };
        match group {
            4 => order.blocks::<V, 4>(sums),
            2 => order.blocks::<V, 2>(sums),
            _ => order.blocks::<V, 1>(sums),
        }
        // Even degrees directly, odd ones by the running sum of the paired recurrence.
        odd.clear();
        odd.resize(group, 0.0);
        for (j, sums) in sums.chunks_exact(2 * group).enumerate() {
            let (even_sums, odd_sums) = sums.split_at(group);
            let i = 2 * j;
            for (value, sum) in out[i * width + first..][..group].iter_mut().zip(even_sums) {
                *value = T::of(paired.even_norm[j] * lane_sum(sum));
            }
            if i + 1 < degrees {
                let (gain, norm) = (paired.odd_gain[j], paired.odd_norm[j]);
                let values = out[(i + 1) * width + first..][..group].iter_mut();
                for ((value, sum), odd) in values.zip(odd_sums).zip(odd.iter_mut()) {
                    *odd = gain * lane_sum(sum) - *odd;
                    *value = T::of(norm * *odd);
                }
            }
        }
        first += group;
    }
}

/// The sum of a vector's lanes, as a tree: three additions deep instead of seven.
#[inline(always)]
fn lane_sum(v: &[f64; LANES]) -> f64 {
    ((v[0] + v[4]) + (v[2] + v[6])) + ((v[1] + v[5]) + (v[3] + v[7]))
}

/// One order's paired recurrence, rings and spectra.
struct Order<'a> {
    steps: &'a [[f64; 2]],
    spectra: Spectra<'a>,
    rings: Rings<'a>,
}

impl Order<'_> {
    /// Every block of rings, for `W` columns. The spectra take 2 · `W` · R registers for R
    /// ring vectors: four vectors a block (enough independent recurrences to hide their
    /// latency) while that fits in AVX-512's 32, two beyond.
    ///
    /// Silent vectors are skipped; the blocks start after them, partial ones first, so
    /// that whole blocks reach the equator.
    #[inline(always)]
    fn blocks<V: Lanes, const W: usize>(&self, sums: &mut [[f64; LANES]]) {
        let vectors = self.rings.vectors();
        let mut vector = self.rings.silent.min(vectors);
        if W <= 2 {
            if (vectors - vector) % 4 >= 2 {
                self.block::<V, 2, W>(vector * LANES, sums);
                vector += 2;
            }
            if (vectors - vector) % 2 == 1 {
                self.block::<V, 1, W>(vector * LANES, sums);
                vector += 1;
            }
            if self.steps.len() > PAIR_CHUNK {
                return self.blocks_by_pair_chunks::<V, W>(vector, sums);
            }
            while vector + 4 <= vectors {
                self.block::<V, 4, W>(vector * LANES, sums);
                vector += 4;
            }
        }
        while vector + 2 <= vectors {
            self.block::<V, 2, W>(vector * LANES, sums);
            vector += 2;
        }
        if vector < vectors {
            self.block::<V, 1, W>(vector * LANES, sums);
        }
    }

    /// [`Order::blocks`] for many pairs of degrees: every block's careful steps first, then
    /// the plain loop a chunk of pairs at a time for every block in turn, so that the
    /// chunk's sums stay in the first-level cache (a whole order's did not at lmax 511).
    /// Blocks of four vectors from vector `from` to the last one.
    #[inline(always)]
    fn blocks_by_pair_chunks<V: Lanes, const W: usize>(&self, from: usize, sums: &mut [[f64; LANES]]) {
        let first_ring = |block: usize| (from + 4 * block) * LANES;
        let blocks = (self.rings.vectors() - from) / 4;
        // Per block: the next pair, cos θ (zero past the last ring), and the recurrence's
        // two values there.
        let mut states = Vec::with_capacity(blocks);
        for block in 0..blocks {
            let (pair, x, previous, current) = self.careful_start::<V, 4, W>(first_ring(block), sums);
            let mut saved = [[[0.0; LANES]; 4]; 3];
            for r in 0..4 {
                x[r].store(&mut saved[0][r]);
                previous[r].store(&mut saved[1][r]);
                current[r].store(&mut saved[2][r]);
            }
            states.push((pair, saved));
        }
        let pairs = self.steps.len();
        for end in (PAIR_CHUNK..pairs + PAIR_CHUNK)
            .step_by(PAIR_CHUNK)
            .map(|end| end.min(pairs))
        {
            for (block, (pair, saved)) in states.iter_mut().enumerate() {
                if *pair >= end {
                    continue;
                }
                let (mut x, mut previous, mut current) = ([V::splat(0.0); 4], [V::splat(0.0); 4], [V::splat(0.0); 4]);
                for r in 0..4 {
                    x[r] = V::load(&saved[0][r]);
                    previous[r] = V::load(&saved[1][r]);
                    current[r] = V::load(&saved[2][r]);
                }
                (previous, current) =
                    self.plain_steps::<V, 4, W>(*pair..end, first_ring(block), &x, previous, current, sums);
                for r in 0..4 {
                    previous[r].store(&mut saved[1][r]);
                    current[r].store(&mut saved[2][r]);
                }
                *pair = end;
            }
        }
    }

    /// Adds the contribution of the `R` ring vectors from ring `first` to every sum.
    #[inline(always)]
    fn block<V: Lanes, const R: usize, const W: usize>(&self, first: usize, sums: &mut [[f64; LANES]]) {
        let (pair, x, previous, current) = self.careful_start::<V, R, W>(first, sums);
        self.plain_steps::<V, R, W>(pair..self.steps.len(), first, &x, previous, current, sums);
    }

    /// A block's start: its rings' cos θ and λ_mm, and careful steps until every value is
    /// plain. Returns the first pair not yet added, cos θ, and the recurrence's values.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn careful_start<V: Lanes, const R: usize, const W: usize>(
        &self,
        first: usize,
        sums: &mut [[f64; LANES]],
    ) -> (usize, [V; R], [V; R], [V; R]) {
        let (x, mut current, scales) = self.rings.load::<V, R>(first);
        let mut previous = [V::splat(0.0); R];
        // Loops, not closures, here and below: a closure does not inherit the caller's
        // target features, so its intrinsics become calls.
        let (mut scaled, mut something_to_add) = (false, false);
        for r in 0..R {
            scaled |= scales[r] != [0; LANES];
            something_to_add |= current[r].any_reaches(V::splat(QUIET));
        }
        let mut pair = 0;
        // Most blocks start plain: no scaled value, and something to add.
        if scaled || !something_to_add {
            let mut state = LaneState::<V, R>::new(scales, &mut previous, &mut current);
            pair = self.careful_steps::<V, R, W>(first, &x, &mut previous, &mut current, &mut state, sums);
        }
        (pair, x, previous, current)
    }

    /// The block's spectra for `W` columns in registers, the antisymmetric part times
    /// cos θ as the paired recurrence takes it.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops over constants: fully unrolled
    fn spectra_in_registers<V: Lanes, const R: usize, const W: usize>(
        &self,
        first: usize,
        x: &[V; R],
    ) -> [[[V; R]; W]; 2] {
        assert_eq!(self.spectra.width, W);
        let mut spectra = [[[V::splat(0.0); R]; W]; 2];
        for c in 0..W {
            for r in 0..R {
                spectra[0][c][r] = self.spectra.load(0, c, first / LANES + r);
                spectra[1][c][r] = self.spectra.load::<V>(1, c, first / LANES + r).mul(x[r]);
            }
        }
        spectra
    }

    /// The loop once every value is a plain double, for exactly `W` columns: the block's
    /// spectra held in registers, no bounds checks or column loops per step (a loop over
    /// any number of columns spent more time on its own overhead than on arithmetic).
    #[inline(always)]
    fn plain_steps<V: Lanes, const R: usize, const W: usize>(
        &self,
        pairs: std::ops::Range<usize>,
        first: usize,
        x: &[V; R],
        mut previous: [V; R],
        mut current: [V; R],
        sums: &mut [[f64; LANES]],
    ) -> ([V; R], [V; R]) {
        let x2 = &squares(x);
        let spectra = self.spectra_in_registers::<V, R, W>(first, x);
        let from = pairs.start;
        let mut pairs = self.steps[..pairs.end].iter().zip(pair_sums::<W>(sums)).skip(from);
        if from == 0 {
            if let Some((_, sums)) = pairs.next() {
                add_pair(&current, &spectra, sums);
            }
        }
        for (&coefficients, sums) in pairs {
            step(coefficients, x2, &mut previous, &mut current);
            add_pair(&current, &spectra, sums);
        }
        (previous, current)
    }

    /// Pairs of degrees while some ring carries a scaled value, which is negligible (see
    /// [`WAKE`]) and adds nothing, or while every value is negligible (nothing is added at
    /// all). One comparison per vector and step finds when either may end. Returns the
    /// first pair not yet added, with the block plain (or the order's end).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops over constants: fully unrolled
    fn careful_steps<V: Lanes, const R: usize, const W: usize>(
        &self,
        first: usize,
        x: &[V; R],
        previous: &mut [V; R],
        current: &mut [V; R],
        state: &mut LaneState<V, R>,
        sums: &mut [[f64; LANES]],
    ) -> usize {
        let x2 = &squares(x);
        let spectra = self.spectra_in_registers::<V, R, W>(first, x);
        for (j, (&coefficients, sums)) in self.steps.iter().zip(pair_sums::<W>(sums)).enumerate() {
            if j > 0 {
                step(coefficients, x2, previous, current);
            }
            let mut crossed = false;
            for r in 0..R {
                crossed |= current[r].any_reaches(state.threshold[r]);
            }
            if crossed {
                state.update(previous, current);
                if state.plain() {
                    add_pair(current, &spectra, sums);
                    return j + 1;
                }
            }
            if state.live {
                let mut plain = *current;
                for r in 0..R {
                    plain[r] = plain[r].mul(state.plain_lanes[r]);
                }
                add_pair(&plain, &spectra, sums);
            }
        }
        self.steps.len()
    }
}

/// The sums of every pair of degrees as fixed-size arrays, `[part][column]`: no bounds
/// checks in the loops over pairs.
#[inline(always)]
fn pair_sums<const W: usize>(sums: &mut [[f64; LANES]]) -> std::slice::IterMut<'_, [[[f64; LANES]; W]; 2]> {
    let (sums, _) = sums.as_chunks_mut::<W>();
    let (sums, _) = sums.as_chunks_mut::<2>();
    sums.iter_mut()
}

/// One pair's sums += ν × each spectrum (loops over constants, fully unrolled, so the
/// spectra stay in registers).
#[inline(always)]
fn add_pair<V: Lanes, const R: usize, const W: usize>(
    nu: &[V; R],
    spectra: &[[[V; R]; W]; 2],
    sums: &mut [[[f64; LANES]; W]; 2],
) {
    for part in 0..2 {
        for c in 0..W {
            let mut total = V::load(&sums[part][c]);
            for r in 0..R {
                total = nu[r].mul_add(spectra[part][c][r], total);
            }
            total.store(&mut sums[part][c]);
        }
    }
}

#[inline(always)]
fn squares<V: Lanes, const R: usize>(x: &[V; R]) -> [V; R] {
    let mut squares = *x;
    for r in 0..R {
        squares[r] = x[r].mul(x[r]);
    }
    squares
}

/// One pair of degrees up: ν_i = (a x² + b) ν_{i−2} − ν_{i−4}.
#[inline(always)]
fn step<V: Lanes, const R: usize>([a, b]: [f64; 2], x2: &[V; R], previous: &mut [V; R], current: &mut [V; R]) {
    let (a, b) = (V::splat(a), V::splat(b));
    for r in 0..R {
        let next = a.mul_add(x2[r], b).mul_sub(current[r], previous[r]);
        previous[r] = current[r];
        current[r] = next;
    }
}

/// A scaled mantissa (value mantissa · 2^(600 · scale), scale < 0) moves one scale up
/// once it passes this, so that every scaled value stays below 2^−70 ([`QUIET`]) and
/// counts as 0, and a value leaves scaling as soon as it may matter.
const WAKE: f64 = QUIET * BIG;

/// What a block's careful steps track per ring: the scale of its value, whether it is
/// plain (1) or scaled (0), and the magnitude at which the block's state may change.
struct LaneState<V, const R: usize> {
    scale: [[i32; LANES]; R],
    plain_lanes: [V; R],
    threshold: [V; R],
    /// Whether some value in the block is no longer negligible (then every step adds).
    live: bool,
}

impl<V: Lanes, const R: usize> LaneState<V, R> {
    #[inline(always)]
    fn new(scale: [[i32; LANES]; R], previous: &mut [V; R], current: &mut [V; R]) -> Self {
        let mut state = LaneState {
            scale,
            plain_lanes: [V::splat(0.0); R],
            threshold: [V::splat(0.0); R],
            live: false,
        };
        state.update(previous, current);
        state
    }

    /// No scaled values and something to add: the plain loop can take over.
    #[inline(always)]
    fn plain(&self) -> bool {
        self.live && self.scale.iter().flatten().all(|&s| s == 0)
    }

    /// Moves mantissas that have passed [`WAKE`] up a scale, and makes the block live if
    /// a plain value is no longer negligible. Inlined, rare as it is: called, it would
    /// lose the caller's target features.
    #[inline(always)]
    fn update(&mut self, previous: &mut [V; R], current: &mut [V; R]) {
        for r in 0..R {
            let (mut before, mut now) = (previous[r].to_array(), current[r].to_array());
            for k in 0..LANES {
                while self.scale[r][k] < 0 && now[k].abs() > WAKE {
                    now[k] *= SMALL;
                    before[k] *= SMALL;
                    self.scale[r][k] += 1;
                }
                self.live |= self.scale[r][k] == 0 && now[k].abs() >= QUIET;
            }
            (previous[r], current[r]) = (V::load(&before), V::load(&now));
        }
        for r in 0..R {
            let plain = self.scale[r].map(|s| if s == 0 { 1.0 } else { 0.0 });
            let threshold = std::array::from_fn(|k| match (self.scale[r][k] < 0, self.live) {
                (true, _) => WAKE,
                (false, false) => QUIET,
                (false, true) => f64::INFINITY,
            });
            self.plain_lanes[r] = V::load(&plain);
            self.threshold[r] = V::load(&threshold);
        }
    }
}

/// Eight f64 lanes: AVX-512 registers where the CPU has them, arrays elsewhere (which the
/// compiler vectorises as it can).
mod lanes {
    pub const LANES: usize = 8;

    pub trait Lanes: Copy {
        fn splat(value: f64) -> Self;
        fn load(values: &[f64; LANES]) -> Self;
        fn store(self, out: &mut [f64; LANES]);
        fn to_array(self) -> [f64; LANES] {
            let mut out = [0.0; LANES];
            self.store(&mut out);
            out
        }
        fn mul(self, other: Self) -> Self;
        /// self · b + c.
        fn mul_add(self, b: Self, c: Self) -> Self;
        /// self · b − c.
        fn mul_sub(self, b: Self, c: Self) -> Self;
        /// Whether |self| ≥ limit in some lane.
        fn any_reaches(self, limit: Self) -> bool;
    }

    impl Lanes for [f64; LANES] {
        #[inline(always)]
        fn splat(value: f64) -> Self {
            [value; LANES]
        }
        #[inline(always)]
        fn load(values: &[f64; LANES]) -> Self {
            *values
        }
        #[inline(always)]
        fn store(self, out: &mut [f64; LANES]) {
            *out = self;
        }
        #[inline(always)]
        fn mul(self, other: Self) -> Self {
            std::array::from_fn(|k| self[k] * other[k])
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            std::array::from_fn(|k| self[k].mul_add(b[k], c[k]))
        }
        #[inline(always)]
        fn mul_sub(self, b: Self, c: Self) -> Self {
            std::array::from_fn(|k| self[k].mul_add(b[k], -c[k]))
        }
        #[inline(always)]
        fn any_reaches(self, limit: Self) -> bool {
            (0..LANES).any(|k| self[k].abs() >= limit[k])
        }
    }

    /// A 512-bit register of eight f64.
    ///
    /// Only [`super::analysis_order_avx512`] creates values of this type, after checking
    /// that the CPU has AVX-512F: that is what makes the intrinsics below sound.
    #[cfg(target_arch = "x86_64")]
    #[derive(Clone, Copy)]
    pub struct Avx512(std::arch::x86_64::__m512d);

    #[cfg(target_arch = "x86_64")]
    impl Lanes for Avx512 {
        #[inline(always)]
        fn splat(value: f64) -> Self {
            // SAFETY (every method): see the type's docs.
            Avx512(unsafe { std::arch::x86_64::_mm512_set1_pd(value) })
        }
        #[inline(always)]
        fn load(values: &[f64; LANES]) -> Self {
            Avx512(unsafe { std::arch::x86_64::_mm512_loadu_pd(values.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f64; LANES]) {
            unsafe { std::arch::x86_64::_mm512_storeu_pd(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn mul(self, other: Self) -> Self {
            Avx512(unsafe { std::arch::x86_64::_mm512_mul_pd(self.0, other.0) })
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            Avx512(unsafe { std::arch::x86_64::_mm512_fmadd_pd(self.0, b.0, c.0) })
        }
        #[inline(always)]
        fn mul_sub(self, b: Self, c: Self) -> Self {
            Avx512(unsafe { std::arch::x86_64::_mm512_fmsub_pd(self.0, b.0, c.0) })
        }
        #[inline(always)]
        fn any_reaches(self, limit: Self) -> bool {
            use std::arch::x86_64::*;
            unsafe { _mm512_cmp_pd_mask::<_CMP_GE_OQ>(_mm512_abs_pd(self.0), limit.0) != 0 }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sht::legendre::Scaled;

    #[test]
    fn agrees_with_stored_rows_where_sectorals_underflow() {
        // Rings from the pole (λ_mm scaled or negligible at large m) to the equator: a
        // count that leaves a partial block, and one of whole blocks of four vectors
        // (the plain loop then runs in chunks of pairs); narrow and wide spectra.
        // At lmax 2500 scaled values grow back to plain ones within the order (e.g.
        // λ_{l,1000}(0.5) is O(1) from l ≈ 2100).
        for rings in [45, 64] {
            check_against_stored_rows(rings);
        }
    }

    fn check_against_stored_rows(rings: usize) {
        let lmax = 2500;
        let recurrence = Recurrence::new(lmax);
        let theta: Vec<f64> = (0..rings).map(|p| 1e-3 + p as f64 * 1.57 / rings as f64).collect();
        let cos_theta: Vec<f64> = theta.iter().map(|t| t.cos()).collect();
        let mut sectoral = vec![Scaled::ZERO; lmax + 1];
        let sectorals: Vec<Vec<Scaled>> = theta
            .iter()
            .map(|t| {
                recurrence.sectoral(t.sin(), &mut sectoral);
                sectoral.clone()
            })
            .collect();
        let stride = padded_stride(theta.len());
        let mut most_silent = 0;
        for (m, width) in [(0, 2), (150, 5), (1000, 2), (1500, 16), (2490, 3)] {
            let start: Vec<Scaled> = sectorals.iter().map(|s| s[m]).collect();
            // The kernel's rings, padded to whole vectors.
            let padded = theta.len().next_multiple_of(LANES);
            let pad = |values: Vec<f64>| [values, vec![0.0; padded - theta.len()]].concat();
            let mantissa = pad(start.iter().map(|s| s.mantissa).collect());
            let padded_cos_theta = pad(cos_theta.clone());
            let mut scale: Vec<i32> = start.iter().map(|s| s.scale).collect();
            scale.resize(padded, 0);
            let spectra: [Vec<f64>; 2] = [1, 2].map(|seed| {
                let mut column = vec![0.0; width * stride];
                for c in 0..width {
                    for p in 0..theta.len() {
                        column[c * stride + p] = ((seed * 7919 + c * 104729 + p * 31) % 1000) as f64 / 500.0 - 1.0;
                    }
                }
                column
            });
            let rings = Rings {
                cos_theta: &padded_cos_theta,
                mantissa: &mantissa,
                scale: &scale,
                silent: 0,
            };
            let silent = silent_vectors(&recurrence, m, rings, &mut Paired::default());
            let degrees = lmax + 1 - m;
            let mut rows = vec![0.0; degrees * theta.len()];
            recurrence.rows(m, &cos_theta, &start, &mut rows);
            let run = |rings| {
                let mut out = vec![0.0f64; degrees * width];
                let spectra = Spectra {
                    parts: [&spectra[0], &spectra[1]],
                    column_stride: stride,
                    vector_stride: LANES,
                    width,
                };
                let job = Job {
                    recurrence: &recurrence,
                    m,
                    rings,
                    spectra,
                };
                analysis_order(job, &mut out, &mut Scratch::default());
                out
            };
            let out = run(Rings { silent, ..rings });
            // Skipping the silent vectors changes nothing but the order of additions.
            let largest = out.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for (skipped, all) in out.iter().zip(run(rings)) {
                assert!((skipped - all).abs() <= 1e-14 * largest, "m {m}: {skipped} vs {all}");
            }
            most_silent = most_silent.max(silent);
            for i in 0..degrees {
                for c in 0..width {
                    let terms = (0..theta.len()).map(|p| rows[i * theta.len() + p] * spectra[i % 2][c * stride + p]);
                    let expected: f64 = terms.clone().sum();
                    let magnitude: f64 = terms.map(f64::abs).sum();
                    // Both recurrences lose about 10^−13 per degree near the poles.
                    let error = (out[i * width + c] - expected).abs();
                    assert!(
                        error <= 1e-13 * (i + 1) as f64 * magnitude + 1e-300,
                        "m {m} l {} c {c}: {} vs {expected}",
                        m + i,
                        out[i * width + c]
                    );
                }
            }
        }
        assert!(most_silent > 0, "no case skips a vector");
    }
}
