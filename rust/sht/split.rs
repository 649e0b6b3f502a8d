//! Analysis: one ring pair's FFTs, for a block of maps, split into the symmetric and
//! antisymmetric parts and written with the maps innermost (the Legendre step's layout).
//!
//! With z = (n + s) + i(n − s) for the north and south rings n and s, the FFT Z of z gives
//! SYM_m = (Z_m + conj Z_−m)/2 and ANTI_m = (Z_m − conj Z_−m)/2i; the cosine sums are the
//! real parts and the sine sums minus the imaginary parts. This is a transposition (each
//! map's spectrum is contiguous in m, the output is contiguous in maps), so on x86 with
//! AVX2 whole blocks of 8 maps go through vector registers: vectors of orders per map,
//! transposed with each complex value kept whole into vectors of maps per order, whose
//! real and imaginary parts are then separated. The scalar loop was a large share of a
//! batched 90 × 180 analysis (research/performance.md).

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

    use super::super::transpose::avx2::transpose_f64;
    use super::{PairParts, PairSpectra, BLOCK};

    const _: () = assert!(BLOCK == 8, "the transpositions below are for blocks of 8 maps");

    /// Orders per step: one 256-bit vector.
    pub const F64_ORDERS: usize = 4;
    pub const F32_ORDERS: usize = 8;

    /// Orders m0..m0 + 4 of the block's 8 maps (m0 ≥ 1, m0 + 4 ≤ orders), four maps at a
    /// time.
    ///
    /// As in [`split_f32`], no shuffle separates real from imaginary parts before the
    /// transposition: each complex value is a 128-bit lane, moved whole, and each order's
    /// values of four maps come out as two vectors, maps (0, 2) and (1, 3), which one
    /// unpack per part puts back in line. 32 shuffles a step of four maps instead of 64.
    ///
    /// # Safety
    /// AVX2 must be present, and `split_pair`'s asserts must hold.
    #[target_feature(enable = "avx2")]
    pub unsafe fn split_f64(pair: &PairSpectra<'_, f64>, out: &mut PairParts<'_, f64>, m0: usize) {
        let z = pair.spectra.as_ptr().cast::<f64>();
        let nlon = pair.nlon;
        let (f, minus_f, af) = (
            _mm256_set1_pd(pair.sym_factor),
            _mm256_set1_pd(-pair.sym_factor),
            _mm256_set1_pd(pair.anti_factor),
        );
        for half in 0..2 {
            let load = |map: usize, index: usize| _mm256_loadu_pd(z.add(2 * ((half * 4 + map) * nlon + index)));
            // Two complex values a vector: Z_m0, Z_m0+1 | Z_m0+2, Z_m0+3, and
            // Z_−m0−1, Z_−m0 | Z_−m0−3, Z_−m0−2.
            let ahead: [[__m256d; 4]; 2] = [m0, m0 + 2].map(|first| std::array::from_fn(|map| load(map, first)));
            let behind: [[__m256d; 4]; 2] =
                [nlon - m0 - 1, nlon - m0 - 3].map(|first| std::array::from_fn(|map| load(map, first)));
            // One lane of the four maps' vectors: that of maps (0, 2) and that of maps (1, 3).
            let lane = |vectors: &[__m256d; 4], high: bool| {
                if high {
                    [
                        _mm256_permute2f128_pd::<0x31>(vectors[0], vectors[2]),
                        _mm256_permute2f128_pd::<0x31>(vectors[1], vectors[3]),
                    ]
                } else {
                    [
                        _mm256_permute2f128_pd::<0x20>(vectors[0], vectors[2]),
                        _mm256_permute2f128_pd::<0x20>(vectors[1], vectors[3]),
                    ]
                }
            };
            for j in 0..4 {
                let [a_x, a_y] = lane(&ahead[j / 2], j % 2 == 1);
                // `behind`'s lanes run down: Z_−m0 is the high lane of its first pair.
                let [b_x, b_y] = lane(&behind[j / 2], j % 2 == 0);
                // Z_m + Z_−m: (SYM cos, ANTI cos) sums; Z_m − Z_−m: (ANTI sin, −SYM sin) sums.
                let (sum_x, sum_y) = (_mm256_add_pd(a_x, b_x), _mm256_add_pd(a_y, b_y));
                let (difference_x, difference_y) = (_mm256_sub_pd(a_x, b_x), _mm256_sub_pd(a_y, b_y));
                let parts = [
                    _mm256_mul_pd(f, _mm256_unpacklo_pd(sum_x, sum_y)),
                    _mm256_mul_pd(minus_f, _mm256_unpackhi_pd(difference_x, difference_y)),
                    _mm256_mul_pd(af, _mm256_unpackhi_pd(sum_x, sum_y)),
                    _mm256_mul_pd(af, _mm256_unpacklo_pd(difference_x, difference_y)),
                ];
                for (part, values) in parts.into_iter().enumerate() {
                    let destination = if part < 2 { &mut *out.sym } else { &mut *out.anti };
                    let at = (m0 + j) * out.width + (part % 2) * out.half_width + out.first + half * 4;
                    _mm256_storeu_pd(destination[at..at + 4].as_mut_ptr(), values);
                }
            }
        }
    }

    /// Orders m0..m0 + 8 of the block's 8 maps (m0 ≥ 1, m0 + 8 ≤ orders).
    ///
    /// The complex values are transposed as pairs (one f64 lane each), so that no shuffle
    /// separates real from imaginary parts before the transposition, and Z_−m needs no
    /// reversal: a column of the transposed block is an order whichever way it was read.
    /// Each order's values of the 8 maps come out as two vectors, maps (0, 1, 4, 5) and
    /// (2, 3, 6, 7), the order in which one shuffle per part puts them back in line. This
    /// takes 96 shuffles a step instead of 176 (research/performance.md).
    ///
    /// # Safety
    /// As [`split_f64`].
    #[target_feature(enable = "avx2")]
    pub unsafe fn split_f32(pair: &PairSpectra<'_, f32>, out: &mut PairParts<'_, f32>, m0: usize) {
        let z = pair.spectra.as_ptr().cast::<f32>();
        let nlon = pair.nlon;
        let load = |map: usize, index: usize| _mm256_castps_pd(_mm256_loadu_ps(z.add(2 * (map * nlon + index))));
        // Z_m0 … Z_m0+7 and Z_−m0−7 … Z_−m0 of every map, four complex values a vector.
        let columns = |first: usize| transpose_pairs(std::array::from_fn(|map| load(map, first)));
        let (ahead, behind) = ([m0, m0 + 4].map(columns), [nlon - m0 - 3, nlon - m0 - 7].map(columns));
        let (f, minus_f, af) = (
            _mm256_set1_ps(pair.sym_factor),
            _mm256_set1_ps(-pair.sym_factor),
            _mm256_set1_ps(pair.anti_factor),
        );
        for j in 0..8 {
            // Z_m and Z_−m for m = m0 + j: `behind`'s columns run down from Z_−m0 (its
            // first block) and from Z_−m0−4 (its second).
            let [a_x, a_y] = ahead[j / 4][j % 4];
            let [b_x, b_y] = behind[j / 4][3 - j % 4];
            let (a_x, a_y, b_x, b_y) = (
                _mm256_castpd_ps(a_x),
                _mm256_castpd_ps(a_y),
                _mm256_castpd_ps(b_x),
                _mm256_castpd_ps(b_y),
            );
            // Z_m + Z_−m: (SYM cos, ANTI cos) sums; Z_m − Z_−m: (ANTI sin, −SYM sin) sums.
            let (sum_x, sum_y) = (_mm256_add_ps(a_x, b_x), _mm256_add_ps(a_y, b_y));
            let (difference_x, difference_y) = (_mm256_sub_ps(a_x, b_x), _mm256_sub_ps(a_y, b_y));
            let real = |x, y| _mm256_shuffle_ps::<0b10_00_10_00>(x, y);
            let imaginary = |x, y| _mm256_shuffle_ps::<0b11_01_11_01>(x, y);
            let parts = [
                _mm256_mul_ps(f, real(sum_x, sum_y)),
                _mm256_mul_ps(minus_f, imaginary(difference_x, difference_y)),
                _mm256_mul_ps(af, imaginary(sum_x, sum_y)),
                _mm256_mul_ps(af, real(difference_x, difference_y)),
            ];
            for (part, values) in parts.into_iter().enumerate() {
                let destination = if part < 2 { &mut *out.sym } else { &mut *out.anti };
                let at = (m0 + j) * out.width + (part % 2) * out.half_width + out.first;
                _mm256_storeu_ps(destination[at..at + BLOCK].as_mut_ptr(), values);
            }
        }
    }

    /// Rows of 8 maps, each four complex values (one f64 lane each) → per column, the
    /// values of maps (0, 1, 4, 5) and of maps (2, 3, 6, 7): two 4 × 4 transpositions of
    /// 64-bit lanes, of those rows.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn transpose_pairs([r0, r1, r2, r3, r4, r5, r6, r7]: [__m256d; BLOCK]) -> [[__m256d; 2]; 4] {
        let (x, y) = (transpose_f64([r0, r1, r4, r5]), transpose_f64([r2, r3, r6, r7]));
        [0, 1, 2, 3].map(|column| [x[column], y[column]])
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
