//! Analysis: one ring pair's FFTs, for a block of maps, split into the symmetric and
//! antisymmetric parts and written with the maps innermost (the Legendre step's layout).
//!
//! With z = (n + s) + i(n − s) for the north and south rings n and s, the FFT Z of z gives
//! SYM_m = (Z_m + conj Z_−m)/2 and ANTI_m = (Z_m − conj Z_−m)/2i; the cosine sums are the
//! real parts and the sine sums minus the imaginary parts. This is a transposition (each
//! map's spectrum is contiguous in m, the output is contiguous in maps), so on x86 with
//! AVX2 whole blocks of 8 maps go through vector registers: a vector of orders per map,
//! then a transposition of the block to a vector of maps per order. The scalar loop was
//! a large share of a batched 90 × 180 analysis (research/performance.md).

use realfft::num_complex::Complex;

use super::real::Real;
use super::transpose::{same_type, same_type_mut};

/// One ring pair's spectra: `block` maps of `nlon` values, and the scale of each part.
pub(super) struct PairSpectra<'a, T> {
    pub spectra: &'a [Complex<T>],
    pub nlon: usize,
    /// Scale of SYM (half the ring pair's quadrature factor: SYM is half a sum).
    pub sym_factor: T,
    /// Scale of ANTI: as `sym_factor`, or zero for an equator ring, which has no mirror.
    pub anti_factor: T,
}

/// Where the parts go: order m's cosine sums of map `first + i` at `sym[m·width + first + i]`,
/// its sine sums `half_width` further (and the same in `anti`).
pub(super) struct PairParts<'a, T> {
    pub sym: &'a mut [T],
    pub anti: &'a mut [T],
    pub width: usize,
    pub half_width: usize,
    pub first: usize,
}

/// Maps per vector block.
pub(super) const BLOCK: usize = 8;

/// Splits orders 0..orders of every map in `pair`; `on_order(m)` runs before each group
/// of orders (the caller spreads its prefetches with it).
pub(super) fn split_pair<T: Real>(
    pair: &PairSpectra<'_, T>,
    out: &mut PairParts<'_, T>,
    orders: usize,
    on_order: &mut dyn FnMut(usize),
) {
    let block = pair.spectra.len() / pair.nlon;
    assert!(orders <= pair.nlon / 2 + 1 && block * pair.nlon == pair.spectra.len());
    assert!(out.first + block <= out.half_width && 2 * out.half_width <= out.width);
    assert!(out.sym.len() >= orders * out.width && out.anti.len() >= out.sym.len());
    let mut m = 0;
    #[cfg(target_arch = "x86_64")]
    if block == BLOCK && is_x86_feature_detected!("avx2") {
        use std::any::TypeId;
        // Order 0 pairs Z_0 with itself; the vector loop starts at 1.
        on_order(0);
        split_scalar(pair, out, 0..1);
        m = 1;
        if TypeId::of::<T>() == TypeId::of::<f64>() {
            while m + avx2::F64_ORDERS <= orders {
                on_order(m);
                // SAFETY: AVX2 is present; T is f64; the asserts above bound every access.
                unsafe { avx2::split_f64(same_type(pair), same_type_mut(out), m) };
                m += avx2::F64_ORDERS;
            }
        } else if TypeId::of::<T>() == TypeId::of::<f32>() {
            while m + avx2::F32_ORDERS <= orders {
                on_order(m);
                // SAFETY: as above, with T f32.
                unsafe { avx2::split_f32(same_type(pair), same_type_mut(out), m) };
                m += avx2::F32_ORDERS;
            }
        }
    }
    for m in m..orders {
        on_order(m);
        split_scalar(pair, out, m..m + 1);
    }
}

fn split_scalar<T: Real>(pair: &PairSpectra<'_, T>, out: &mut PairParts<'_, T>, orders: std::ops::Range<usize>) {
    let nlon = pair.nlon;
    for m in orders {
        let cosine = m * out.width + out.first;
        let sine = cosine + out.half_width;
        for (i, z) in pair.spectra.chunks_exact(nlon).enumerate() {
            let (a, b) = (z[m], z[(nlon - m) % nlon].conj());
            let (sum, difference) = (a + b, a - b);
            // SYM = sum/2, ANTI = −i·difference/2 (the halves are in the factors).
            out.sym[cosine + i] = pair.sym_factor * sum.re;
            out.sym[sine + i] = -(pair.sym_factor * sum.im);
            out.anti[cosine + i] = pair.anti_factor * difference.im;
            out.anti[sine + i] = pair.anti_factor * difference.re;
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::super::transpose::avx2::{transpose_f32, transpose_f64};
    use super::{PairParts, PairSpectra, BLOCK};

    const _: () = assert!(BLOCK == 8, "the transpositions below are for blocks of 8 maps");

    /// Orders per step: one 256-bit vector.
    pub const F64_ORDERS: usize = 4;
    pub const F32_ORDERS: usize = 8;

    /// Orders m0..m0 + 4 of the block's 8 maps (m0 ≥ 1, m0 + 4 ≤ orders).
    ///
    /// # Safety
    /// AVX2 must be present, and `split_pair`'s asserts must hold.
    #[target_feature(enable = "avx2")]
    pub unsafe fn split_f64(pair: &PairSpectra<'_, f64>, out: &mut PairParts<'_, f64>, m0: usize) {
        let z = pair.spectra.as_ptr().cast::<f64>();
        let (nlon, f, af) = (
            pair.nlon,
            _mm256_set1_pd(pair.sym_factor),
            _mm256_set1_pd(pair.anti_factor),
        );
        for half in 0..2 {
            // Per map of this half: [SYM cos, SYM sin, ANTI cos, ANTI sin] over the 4 orders.
            let mut parts = [[_mm256_setzero_pd(); 4]; 4];
            for (i, map_parts) in parts.iter_mut().enumerate() {
                let spectrum = z.add(2 * (half * 4 + i) * nlon);
                // Z_m0..Z_m0+3, deinterleaved into real and imaginary parts.
                let (lo, hi) = (
                    _mm256_loadu_pd(spectrum.add(2 * m0)),
                    _mm256_loadu_pd(spectrum.add(2 * m0 + 4)),
                );
                let a_re = _mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_unpacklo_pd(lo, hi));
                let a_im = _mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_unpackhi_pd(lo, hi));
                // Z_−m0..Z_−m0−3 = Z_(nlon−m0−3..=nlon−m0) reversed.
                let (lo, hi) = (
                    _mm256_loadu_pd(spectrum.add(2 * (nlon - m0 - 3))),
                    _mm256_loadu_pd(spectrum.add(2 * (nlon - m0 - 1))),
                );
                let b_re = _mm256_permute4x64_pd::<0b00_10_01_11>(_mm256_unpacklo_pd(lo, hi));
                let b_im = _mm256_permute4x64_pd::<0b00_10_01_11>(_mm256_unpackhi_pd(lo, hi));
                *map_parts = [
                    _mm256_mul_pd(f, _mm256_add_pd(a_re, b_re)),
                    _mm256_mul_pd(f, _mm256_sub_pd(b_im, a_im)),
                    _mm256_mul_pd(af, _mm256_add_pd(a_im, b_im)),
                    _mm256_mul_pd(af, _mm256_sub_pd(a_re, b_re)),
                ];
            }
            let by_part: [[__m256d; 4]; 4] = std::array::from_fn(|part| parts.map(|map_parts| map_parts[part]));
            for (part, rows) in by_part.into_iter().enumerate() {
                let columns = transpose_f64(rows);
                let destination = if part < 2 { &mut *out.sym } else { &mut *out.anti };
                let offset = (part % 2) * out.half_width + out.first + half * 4;
                for (j, column) in columns.into_iter().enumerate() {
                    let at = (m0 + j) * out.width + offset;
                    _mm256_storeu_pd(destination[at..at + 4].as_mut_ptr(), column);
                }
            }
        }
    }

    /// Orders m0..m0 + 8 of the block's 8 maps (m0 ≥ 1, m0 + 8 ≤ orders).
    ///
    /// # Safety
    /// As [`split_f64`].
    #[target_feature(enable = "avx2")]
    pub unsafe fn split_f32(pair: &PairSpectra<'_, f32>, out: &mut PairParts<'_, f32>, m0: usize) {
        let z = pair.spectra.as_ptr().cast::<f32>();
        let (nlon, f, af) = (
            pair.nlon,
            _mm256_set1_ps(pair.sym_factor),
            _mm256_set1_ps(pair.anti_factor),
        );
        let reverse = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
        // Even and odd lanes of two vectors, in order: the real and imaginary parts.
        let deinterleave = |lo: __m256, hi: __m256| {
            let re = _mm256_shuffle_ps::<0b10_00_10_00>(lo, hi);
            let im = _mm256_shuffle_ps::<0b11_01_11_01>(lo, hi);
            let order = |v: __m256| _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(v)));
            (order(re), order(im))
        };
        // Per map: [SYM cos, SYM sin, ANTI cos, ANTI sin] over the 8 orders.
        let mut parts = [[_mm256_setzero_ps(); 4]; BLOCK];
        for (i, map_parts) in parts.iter_mut().enumerate() {
            let spectrum = z.add(2 * i * nlon);
            let (a_re, a_im) = deinterleave(
                _mm256_loadu_ps(spectrum.add(2 * m0)),
                _mm256_loadu_ps(spectrum.add(2 * m0 + 8)),
            );
            let (b_re, b_im) = deinterleave(
                _mm256_loadu_ps(spectrum.add(2 * (nlon - m0 - 7))),
                _mm256_loadu_ps(spectrum.add(2 * (nlon - m0 - 3))),
            );
            let (b_re, b_im) = (
                _mm256_permutevar8x32_ps(b_re, reverse),
                _mm256_permutevar8x32_ps(b_im, reverse),
            );
            *map_parts = [
                _mm256_mul_ps(f, _mm256_add_ps(a_re, b_re)),
                _mm256_mul_ps(f, _mm256_sub_ps(b_im, a_im)),
                _mm256_mul_ps(af, _mm256_add_ps(a_im, b_im)),
                _mm256_mul_ps(af, _mm256_sub_ps(a_re, b_re)),
            ];
        }
        let by_part: [[__m256; BLOCK]; 4] = std::array::from_fn(|part| parts.map(|map_parts| map_parts[part]));
        for (part, rows) in by_part.into_iter().enumerate() {
            let columns = transpose_f32(rows);
            let destination = if part < 2 { &mut *out.sym } else { &mut *out.anti };
            let offset = (part % 2) * out.half_width + out.first;
            for (j, column) in columns.into_iter().enumerate() {
                let at = (m0 + j) * out.width + offset;
                _mm256_storeu_ps(destination[at..at + BLOCK].as_mut_ptr(), column);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vector paths against the scalar loop, for every order count (whole groups and
    /// remainders) on even and odd ring lengths, in both precisions.
    fn agrees_with_scalar<T: Real>() {
        for nlon in [17, 36, 37, 180] {
            let spectra: Vec<Complex<T>> = (0..BLOCK * nlon)
                .map(|k| Complex::new(T::of((k as f64 * 0.37).sin()), T::of((k as f64 * 0.91).cos())))
                .collect();
            let pair = PairSpectra {
                spectra: &spectra,
                nlon,
                sym_factor: T::of(0.3),
                anti_factor: T::of(0.7),
            };
            for orders in 1..=nlon / 2 + 1 {
                let (width, half_width, first) = (2 * BLOCK + 6, BLOCK + 3, 2);
                let run = |vector: bool| {
                    let (mut sym, mut anti) = (vec![T::zero(); orders * width], vec![T::zero(); orders * width]);
                    let mut out = PairParts {
                        sym: &mut sym,
                        anti: &mut anti,
                        width,
                        half_width,
                        first,
                    };
                    let mut calls = Vec::new();
                    if vector {
                        split_pair(&pair, &mut out, orders, &mut |m| calls.push(m));
                    } else {
                        split_scalar(&pair, &mut out, 0..orders);
                    }
                    (sym, anti, calls)
                };
                let (vector, scalar) = (run(true), run(false));
                assert!(
                    vector.0 == scalar.0 && vector.1 == scalar.1,
                    "nlon {nlon}, orders {orders}"
                );
                assert_eq!(vector.2.first(), Some(&0));
                assert!(vector.2.windows(2).all(|w| w[0] < w[1]) && vector.2.last() < Some(&orders));
            }
        }
    }

    #[test]
    fn vector_split_agrees_with_scalar_f64() {
        agrees_with_scalar::<f64>();
    }

    #[test]
    fn vector_split_agrees_with_scalar_f32() {
        agrees_with_scalar::<f32>();
    }
}
