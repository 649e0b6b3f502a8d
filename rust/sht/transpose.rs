//! Transpositions between the per-order blocks of the Legendre step (maps innermost) and
//! per-map layouts (degrees or orders innermost), in AVX2 registers where the CPU has them:
//! 4 × 4 blocks of f64, 8 × 8 of f32. The analysis split ([`super::split`]) and the final
//! scatter of coefficients use them. The scatter is a sizeable part of a batched f32
//! analysis and bound by writing the output, so the vector scatter gains little over
//! contiguous scalar runs, but some (research/performance.md).

use std::mem::MaybeUninit;

use super::real::Real;

/// One order's block of the Legendre step's output, `block[(2 (l − m) + part) · batch + b]`,
/// and where its coefficients go: `out[b · stride + offset + part · degrees + (l − m)]`.
pub(super) struct OrderBlock<'a, T> {
    pub block: &'a [T],
    pub batch: usize,
    pub degrees: usize,
    /// 1 for m = 0 (no sine part), else 2.
    pub parts: usize,
    pub scale: T,
    pub stride: usize,
    pub offset: usize,
}

/// Writes `order`'s coefficients, times its scale, into `out`.
pub(super) fn scatter_order<T: Real>(order: &OrderBlock<'_, T>, out: &mut [MaybeUninit<T>]) {
    let OrderBlock {
        block,
        batch,
        degrees,
        parts,
        stride,
        offset,
        ..
    } = *order;
    assert!(block.len() >= 2 * degrees * batch && parts <= 2);
    assert!(batch == 0 || (batch - 1) * stride + offset + parts * degrees <= out.len());
    let (mut maps_done, mut degrees_done) = (0, 0);
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") {
        use std::any::TypeId;
        if TypeId::of::<T>() == TypeId::of::<f64>() {
            (maps_done, degrees_done) = (batch / 4 * 4, vector_degrees(degrees, 4));
            // SAFETY: AVX2 is present, T is f64, and the asserts above bound every access.
            unsafe { avx2::scatter_f64(same_type(order), same_type_slice_mut(out)) };
        } else if TypeId::of::<T>() == TypeId::of::<f32>() {
            (maps_done, degrees_done) = (batch / 8 * 8, vector_degrees(degrees, 8));
            // SAFETY: as above, with T f32.
            unsafe { avx2::scatter_f32(same_type(order), same_type_slice_mut(out)) };
        }
    }
    // What the vector blocks left: all degrees of the remaining maps, and the remaining
    // degrees of the others.
    for b in 0..batch {
        let first_degree = if b < maps_done { degrees_done } else { 0 };
        for part in 0..parts {
            for i in first_degree..degrees {
                out[b * stride + offset + part * degrees + i].write(order.scale * block[(2 * i + part) * batch + b]);
            }
        }
    }
}

/// The degrees the vector kernels scatter, in blocks of `width`: all of them where there
/// is at least one block, the last block overlapping the one before it (its values are
/// written twice, the same both times). The scalar loop that took the remainder cost a
/// tenth of the f32 scatter's time again (research/performance.md).
#[cfg(target_arch = "x86_64")]
fn vector_degrees(degrees: usize, width: usize) -> usize {
    if degrees >= width {
        degrees
    } else {
        0
    }
}

/// The first degree of each block of `width` degrees the vector kernels scatter (see
/// [`vector_degrees`]).
#[cfg(target_arch = "x86_64")]
fn degree_blocks(degrees: usize, width: usize) -> impl Iterator<Item = usize> {
    let whole = degrees / width * width;
    let overlapping = (degrees > whole && degrees >= width).then(|| degrees - width);
    (0..whole).step_by(width).chain(overlapping)
}

/// `value` as the same type under another name (the caller has checked that A is B).
pub(super) fn same_type<A, B>(value: &A) -> &B {
    assert_eq!(std::mem::size_of::<A>(), std::mem::size_of::<B>());
    // SAFETY: A and B are one type.
    unsafe { &*(value as *const A as *const B) }
}

pub(super) fn same_type_mut<A, B>(value: &mut A) -> &mut B {
    assert_eq!(std::mem::size_of::<A>(), std::mem::size_of::<B>());
    // SAFETY: as in `same_type`.
    unsafe { &mut *(value as *mut A as *mut B) }
}

pub(super) fn same_type_slice<A, B>(values: &[A]) -> &[B] {
    assert_eq!(std::mem::size_of::<A>(), std::mem::size_of::<B>());
    // SAFETY: as in `same_type`.
    unsafe { std::slice::from_raw_parts(values.as_ptr().cast(), values.len()) }
}

fn same_type_slice_mut<A, B>(values: &mut [A]) -> &mut [B] {
    assert_eq!(std::mem::size_of::<A>(), std::mem::size_of::<B>());
    // SAFETY: as in `same_type`.
    unsafe { std::slice::from_raw_parts_mut(values.as_mut_ptr().cast(), values.len()) }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod avx2 {
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

    use super::OrderBlock;

    /// Rows of a 4 × 4 block → its columns.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn transpose_f64([r0, r1, r2, r3]: [__m256d; 4]) -> [__m256d; 4] {
        let (t0, t1) = (_mm256_unpacklo_pd(r0, r1), _mm256_unpackhi_pd(r0, r1));
        let (t2, t3) = (_mm256_unpacklo_pd(r2, r3), _mm256_unpackhi_pd(r2, r3));
        [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ]
    }

    /// Rows of an 8 × 8 block → its columns.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn transpose_f32([r0, r1, r2, r3, r4, r5, r6, r7]: [__m256; 8]) -> [__m256; 8] {
        let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
        let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
        let (t4, t5) = (_mm256_unpacklo_ps(r4, r5), _mm256_unpackhi_ps(r4, r5));
        let (t6, t7) = (_mm256_unpacklo_ps(r6, r7), _mm256_unpackhi_ps(r6, r7));
        let (u0, u1) = (_mm256_shuffle_ps::<0x44>(t0, t2), _mm256_shuffle_ps::<0xEE>(t0, t2));
        let (u2, u3) = (_mm256_shuffle_ps::<0x44>(t1, t3), _mm256_shuffle_ps::<0xEE>(t1, t3));
        let (u4, u5) = (_mm256_shuffle_ps::<0x44>(t4, t6), _mm256_shuffle_ps::<0xEE>(t4, t6));
        let (u6, u7) = (_mm256_shuffle_ps::<0x44>(t5, t7), _mm256_shuffle_ps::<0xEE>(t5, t7));
        [
            _mm256_permute2f128_ps::<0x20>(u0, u4),
            _mm256_permute2f128_ps::<0x20>(u1, u5),
            _mm256_permute2f128_ps::<0x20>(u2, u6),
            _mm256_permute2f128_ps::<0x20>(u3, u7),
            _mm256_permute2f128_ps::<0x31>(u0, u4),
            _mm256_permute2f128_ps::<0x31>(u1, u5),
            _mm256_permute2f128_ps::<0x31>(u2, u6),
            _mm256_permute2f128_ps::<0x31>(u3, u7),
        ]
    }

    /// [`super::scatter_order`] for whole 4 × 4 blocks of (maps, degrees), the last block of
    /// degrees overlapping ([`super::degree_blocks`]).
    ///
    /// # Safety
    /// AVX2 must be present, and `scatter_order`'s asserts must hold.
    #[target_feature(enable = "avx2")]
    pub unsafe fn scatter_f64(order: &OrderBlock<'_, f64>, out: &mut [MaybeUninit<f64>]) {
        let OrderBlock {
            block,
            batch,
            degrees,
            parts,
            scale,
            stride,
            offset,
        } = *order;
        let scale = _mm256_set1_pd(scale);
        let (source, destination) = (block.as_ptr(), out.as_mut_ptr().cast::<f64>());
        for b0 in (0..batch / 4 * 4).step_by(4) {
            for part in 0..parts {
                for i0 in super::degree_blocks(degrees, 4) {
                    let rows = [0, 1, 2, 3].map(|j| _mm256_loadu_pd(source.add((2 * (i0 + j) + part) * batch + b0)));
                    for (b, column) in transpose_f64(rows).into_iter().enumerate() {
                        let at = (b0 + b) * stride + offset + part * degrees + i0;
                        _mm256_storeu_pd(destination.add(at), _mm256_mul_pd(scale, column));
                    }
                }
            }
        }
    }

    /// [`super::scatter_order`] for whole 8 × 8 blocks of (maps, degrees), as [`scatter_f64`].
    ///
    /// # Safety
    /// As [`scatter_f64`].
    #[target_feature(enable = "avx2")]
    pub unsafe fn scatter_f32(order: &OrderBlock<'_, f32>, out: &mut [MaybeUninit<f32>]) {
        let OrderBlock {
            block,
            batch,
            degrees,
            parts,
            scale,
            stride,
            offset,
        } = *order;
        let scale = _mm256_set1_ps(scale);
        let (source, destination) = (block.as_ptr(), out.as_mut_ptr().cast::<f32>());
        for b0 in (0..batch / 8 * 8).step_by(8) {
            for part in 0..parts {
                for i0 in super::degree_blocks(degrees, 8) {
                    let rows = [0, 1, 2, 3, 4, 5, 6, 7]
                        .map(|j| _mm256_loadu_ps(source.add((2 * (i0 + j) + part) * batch + b0)));
                    for (b, column) in transpose_f32(rows).into_iter().enumerate() {
                        let at = (b0 + b) * stride + offset + part * degrees + i0;
                        _mm256_storeu_ps(destination.add(at), _mm256_mul_ps(scale, column));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vector blocks and scalar remainders against a plain loop, for batch and degree
    /// counts around the block sizes, in both precisions.
    fn scatter_matches_loop<T: Real>() {
        for batch in [1, 3, 4, 5, 8, 9, 13, 16] {
            for degrees in [1, 3, 4, 7, 8, 9, 17] {
                for parts in [1, 2] {
                    let block: Vec<T> = (0..2 * degrees * batch).map(|k| T::of(k as f64 + 0.25)).collect();
                    let (stride, offset) = (2 * degrees + 5, 3);
                    let order = OrderBlock {
                        block: &block,
                        batch,
                        degrees,
                        parts,
                        scale: T::of(1.5),
                        stride,
                        offset,
                    };
                    let mut out = vec![MaybeUninit::new(T::of(-1.0)); batch * stride];
                    scatter_order(&order, &mut out);
                    for b in 0..batch {
                        for k in 0..stride {
                            // SAFETY: every value was initialised above.
                            let value = unsafe { out[b * stride + k].assume_init() };
                            let expected = match k.checked_sub(offset) {
                                Some(j) if j < parts * degrees => {
                                    let (part, i) = (j / degrees, j % degrees);
                                    T::of(1.5) * block[(2 * i + part) * batch + b]
                                }
                                _ => T::of(-1.0),
                            };
                            assert!(
                                value == expected,
                                "batch {batch}, degrees {degrees}, parts {parts}, map {b}, slot {k}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn scatter_matches_loop_f64() {
        scatter_matches_loop::<f64>();
    }

    #[test]
    fn scatter_matches_loop_f32() {
        scatter_matches_loop::<f32>();
    }
}
