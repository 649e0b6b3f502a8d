//! The FFT stage: rings to folded spectra (symmetric and antisymmetric parts of each
//! ring pair) for analysis, and folded spectra back to rings for synthesis.

use rayon::prelude::*;
use realfft::num_complex::Complex;

use super::real::Real;
#[cfg(target_arch = "x86_64")]
use super::transpose::{same_type, same_type_slice};
use super::{split, streamed, Sht, MAP_BLOCK};

impl<T: Real> Sht<T> {
    /// FFT of every ring, north and south rings folded into symmetric and antisymmetric
    /// parts scaled by `ring_factors`. Layout `[half ring][m][part][batch]`, part 0 the
    /// cosine sums Σ_k x_k cos mφ_k and part 1 the sine sums Σ_k x_k sin mφ_k.
    ///
    /// One complex FFT per ring pair gives both parts: with z = (n + s) + i(n − s) for the
    /// north and south rings n and s, Z = SYM + i·ANTI, and since both are spectra of real
    /// rings, SYM_m = (Z_m + conj Z_−m)/2 and ANTI_m = (Z_m − conj Z_−m)/2i. This takes
    /// less time than two real FFTs (realfft) of the rings (research/performance.md).
    pub(super) fn fold_rings(&self, maps: &[T], batch: usize, ring_factors: &[f64]) -> (Vec<T>, Vec<T>) {
        let (nlat, nlon, orders, width) = (self.nlat, self.nlon, self.lmax + 1, 2 * batch);
        let ring = |b: usize, j: usize| &maps[(b * nlat + j) * nlon..][..nlon];
        let slab = orders * width;
        let mut sym = self.pool.take(self.half_rings() * slab);
        let mut anti = self.pool.take(self.half_rings() * slab);
        let zero = Complex::new(T::zero(), T::zero());
        let prefetching = Prefetching::for_this_cpu();
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
                        // A later pair's rings, fetched one at a time while this pair is
                        // transformed: they lie a whole map apart, beyond the hardware
                        // prefetcher, and fetching them all at once stalled on the cache's
                        // queue of misses (research/performance.md).
                        let ahead = prefetching.pairs_ahead;
                        let next_maps = if p + 2 * ahead <= mirror { block } else { 0 };
                        let mut next =
                            (0..next_maps).flat_map(|i| [ring(b0 + i, p + ahead), ring(b0 + i, mirror - ahead)]);
                        let spectra = &mut spectra[..block * nlon];
                        for (i, z) in spectra.chunks_exact_mut(nlon).enumerate() {
                            let south = (mirror != p).then(|| ring(b0 + i, mirror));
                            pack_ring_pair(z, ring(b0 + i, p), south, T::one());
                            self.fft.process_with_scratch(z, scratch);
                            if let Some(ring) = next.next() {
                                prefetching.fetch(ring);
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
                                        prefetching.fetch(ring);
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
    pub(super) fn fold_ring_blocks(&self, map: &[T], ring_factors: &[f64]) -> [Vec<T>; 2] {
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
    pub(super) fn ring_block_tile(&self) -> usize {
        (self.lmax + 1) * 2 * streamed::LANES
    }

    /// Inverse of the folding: per ring, (cos, sin) sums = symmetric ± antisymmetric
    /// part, scaled by `ring_factors`, then an inverse real FFT. Input `[m][half ring][part][batch]`.
    pub(super) fn unfold_rings(&self, sym: &[T], anti: &[T], batch: usize, ring_factors: &[f64], maps: &mut [T]) {
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
}

/// One complex FFT input for a ring pair: z = scale · ((n + s) + i(n − s)) for the north
/// and south rings, whose FFT gives both parts (see [`Sht::fold_rings`]); an equator ring,
/// which has no mirror, gives z = scale · n, no antisymmetric part.
fn pack_ring_pair<T: Real>(z: &mut [Complex<T>], north: &[T], south: Option<&[T]>, scale: T) {
    match south {
        #[cfg(target_arch = "x86_64")]
        Some(south)
            if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f32>() && is_x86_feature_detected!("avx2") =>
        {
            assert!(north.len() == z.len() && south.len() == z.len());
            // SAFETY: AVX2 is present, T is f32 (Complex<f32> is two f32s), and the lengths agree.
            unsafe {
                avx2::pack_pair_f32(
                    std::slice::from_raw_parts_mut(z.as_mut_ptr().cast::<f32>(), 2 * z.len()),
                    same_type_slice(north),
                    same_type_slice(south),
                    *same_type(&scale),
                )
            }
        }
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

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    /// [`super::pack_ring_pair`] for f32, eight values a step: the scalar loop compiled
    /// for the baseline moved two a step, a tenth of the f32 analysis (research/performance.md).
    ///
    /// # Safety
    /// AVX2 must be present; `z` holds two values per value of `north` and `south`.
    #[target_feature(enable = "avx2")]
    pub unsafe fn pack_pair_f32(z: &mut [f32], north: &[f32], south: &[f32], scale: f32) {
        let n = north.len();
        let whole = n / 8 * 8;
        let factor = _mm256_set1_ps(scale);
        let (zp, np, sp) = (z.as_mut_ptr(), north.as_ptr(), south.as_ptr());
        for k in (0..whole).step_by(8) {
            let (a, b) = (_mm256_loadu_ps(np.add(k)), _mm256_loadu_ps(sp.add(k)));
            let (sum, difference) = (
                _mm256_mul_ps(factor, _mm256_add_ps(a, b)),
                _mm256_mul_ps(factor, _mm256_sub_ps(a, b)),
            );
            // (sum, difference) pairs in order: within each 128-bit lane, then the lanes.
            let (low, high) = (_mm256_unpacklo_ps(sum, difference), _mm256_unpackhi_ps(sum, difference));
            _mm256_storeu_ps(zp.add(2 * k), _mm256_permute2f128_ps::<0x20>(low, high));
            _mm256_storeu_ps(zp.add(2 * k + 8), _mm256_permute2f128_ps::<0x31>(low, high));
        }
        for k in whole..n {
            let (a, b) = (north[k], south[k]);
            z[2 * k] = scale * (a + b);
            z[2 * k + 1] = scale * (a - b);
        }
    }
}

/// How [`Sht::fold_rings`] fetches the rings of later pairs ahead of use.
#[derive(Clone, Copy)]
struct Prefetching {
    /// How many ring pairs ahead.
    pairs_ahead: usize,
    /// Into the second-level cache only, not the first.
    l2_only: bool,
}

impl Prefetching {
    /// On AMD (Zen 4, 32 KB first-level cache), the next pair's 16 rings fetched into the
    /// first-level cache evicted the block being transformed; two pairs ahead into the
    /// second-level cache took 10 % off the batched 90 × 180 analysis
    /// (research/performance.md). Elsewhere the next pair into the first-level cache, as
    /// measured on the Intel Xeon. Asked once a process: CPUID traps to the hypervisor on
    /// a virtual machine, and asked every chunk it took 1 % of the batched analysis
    /// (research/performance.md).
    fn for_this_cpu() -> Self {
        static CHOICE: std::sync::OnceLock<Prefetching> = std::sync::OnceLock::new();
        *CHOICE.get_or_init(Self::by_vendor)
    }

    fn by_vendor() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: CPUID leaf 0 (the vendor) exists on every x86-64 CPU. (`__cpuid` is a
            // safe function in recent Rust; the block is for older compilers.)
            #[allow(unused_unsafe)]
            let vendor = unsafe { std::arch::x86_64::__cpuid(0) };
            // "AuthenticAMD" in EBX, EDX, ECX.
            if (vendor.ebx, vendor.edx, vendor.ecx) == (0x6874_7541, 0x6974_6e65, 0x444d_4163) {
                return Prefetching {
                    pairs_ahead: 2,
                    l2_only: true,
                };
            }
        }
        Prefetching {
            pairs_ahead: 1,
            l2_only: false,
        }
    }

    /// Asks the cache to fetch `values` ahead of use.
    #[inline]
    fn fetch<T>(self, values: &[T]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0, _MM_HINT_T1};
            let start = values.as_ptr().cast::<i8>();
            for offset in (0..std::mem::size_of_val(values)).step_by(64) {
                // SAFETY: prefetching has no effect on memory; the address is within `values`.
                unsafe {
                    if self.l2_only {
                        _mm_prefetch::<_MM_HINT_T1>(start.add(offset))
                    } else {
                        _mm_prefetch::<_MM_HINT_T0>(start.add(offset))
                    }
                }
            }
        }
    }
}
