//! Sixteen f32 lanes, the unit of every loop of the kernel: one AVX-512 register, two AVX2
//! ones, or an array elsewhere. Written with intrinsics because, given plain arrays, the
//! compiler vectorised some loops across the wrong dimension (gathers over units instead of
//! vector loads over samples) and kept accumulators in memory.

pub const LANES: usize = 16;

pub trait Lanes: Copy {
    /// Whether there are registers enough to work on two units at once (8 vectors of sums).
    const PAIRS: bool;
    fn splat(value: f32) -> Self;
    fn load(values: &[f32; LANES]) -> Self;
    fn store(self, out: &mut [f32; LANES]);
    fn add(self, other: Self) -> Self;
    /// self · b + c, fused (rounded once).
    fn mul_add(self, b: Self, c: Self) -> Self;
    /// self where `gate` > 0, else 0 (a ReLU's pass, forward with gate = self, or backward).
    fn where_positive(self, gate: Self) -> Self;
    /// The sum of the lanes by halving: lane i += lane i + h for h = 8, 4, 2, 1, the same
    /// additions in the same order in every implementation.
    fn halving_sum(self) -> f32;
}

/// [`Lanes::halving_sum`] on an array (the portable lanes' and the loss's).
#[inline(always)]
pub fn halving_sum(mut lanes: [f32; LANES]) -> f32 {
    for half in [8, 4, 2, 1] {
        for i in 0..half {
            lanes[i] += lanes[i + half];
        }
    }
    lanes[0]
}

/// The portable lanes; with FMA-less x86-64 CPUs `mul_add` is a library call per value.
impl Lanes for [f32; LANES] {
    const PAIRS: bool = false;
    #[inline(always)]
    fn splat(value: f32) -> Self {
        [value; LANES]
    }
    #[inline(always)]
    fn load(values: &[f32; LANES]) -> Self {
        *values
    }
    #[inline(always)]
    fn store(self, out: &mut [f32; LANES]) {
        *out = self;
    }
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        std::array::from_fn(|k| self[k] + other[k])
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        std::array::from_fn(|k| self[k].mul_add(b[k], c[k]))
    }
    #[inline(always)]
    fn where_positive(self, gate: Self) -> Self {
        std::array::from_fn(|k| if gate[k] > 0.0 { self[k] } else { 0.0 })
    }
    #[inline(always)]
    fn halving_sum(self) -> f32 {
        halving_sum(self)
    }
}

#[cfg(target_arch = "x86_64")]
pub use x86::{Avx2, Avx512};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::{Lanes, LANES};

    /// Eight lanes summed by halving (4, 2, 1), in SSE registers: the compiler turned the
    /// array loop into scalar adds through the stack, a fifth of the kernel's time.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn halving_sum_of_eight(v: __m256) -> f32 {
        let four = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let two = _mm_add_ps(four, _mm_movehl_ps(four, four)); // lanes 0 + 2, 1 + 3
        _mm_cvtss_f32(_mm_add_ss(two, _mm_shuffle_ps::<0b01>(two, two)))
    }

    /// One 512-bit register. Only `kernel::part_gradient_avx512` creates values of this
    /// type, after checking that the CPU has AVX-512F and FMA: that makes the intrinsics
    /// below sound.
    #[derive(Clone, Copy)]
    pub struct Avx512(__m512);

    impl Lanes for Avx512 {
        const PAIRS: bool = true;
        #[inline(always)]
        fn splat(value: f32) -> Self {
            // SAFETY (every method): see the type's docs.
            Avx512(unsafe { _mm512_set1_ps(value) })
        }
        #[inline(always)]
        fn load(values: &[f32; LANES]) -> Self {
            Avx512(unsafe { _mm512_loadu_ps(values.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, out: &mut [f32; LANES]) {
            unsafe { _mm512_storeu_ps(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn add(self, other: Self) -> Self {
            Avx512(unsafe { _mm512_add_ps(self.0, other.0) })
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            Avx512(unsafe { _mm512_fmadd_ps(self.0, b.0, c.0) })
        }
        #[inline(always)]
        fn where_positive(self, gate: Self) -> Self {
            unsafe {
                Avx512(_mm512_maskz_mov_ps(
                    _mm512_cmp_ps_mask::<_CMP_GT_OQ>(gate.0, _mm512_setzero_ps()),
                    self.0,
                ))
            }
        }
        #[inline(always)]
        fn halving_sum(self) -> f32 {
            unsafe {
                let high = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(self.0)));
                halving_sum_of_eight(_mm256_add_ps(_mm512_castps512_ps256(self.0), high))
            }
        }
    }

    /// Two 256-bit registers. Only `kernel::part_gradient_avx2` creates values of this
    /// type, after checking that the CPU has AVX2 and FMA.
    #[derive(Clone, Copy)]
    pub struct Avx2(__m256, __m256);

    impl Lanes for Avx2 {
        const PAIRS: bool = false; // its 16 registers hold the 4 pairs of one unit's sums
        #[inline(always)]
        fn splat(value: f32) -> Self {
            // SAFETY (every method): see the type's docs.
            unsafe { Avx2(_mm256_set1_ps(value), _mm256_set1_ps(value)) }
        }
        #[inline(always)]
        fn load(values: &[f32; LANES]) -> Self {
            unsafe {
                Avx2(
                    _mm256_loadu_ps(values.as_ptr()),
                    _mm256_loadu_ps(values.as_ptr().add(8)),
                )
            }
        }
        #[inline(always)]
        fn store(self, out: &mut [f32; LANES]) {
            unsafe {
                _mm256_storeu_ps(out.as_mut_ptr(), self.0);
                _mm256_storeu_ps(out.as_mut_ptr().add(8), self.1);
            }
        }
        #[inline(always)]
        fn add(self, other: Self) -> Self {
            unsafe { Avx2(_mm256_add_ps(self.0, other.0), _mm256_add_ps(self.1, other.1)) }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            unsafe { Avx2(_mm256_fmadd_ps(self.0, b.0, c.0), _mm256_fmadd_ps(self.1, b.1, c.1)) }
        }
        #[inline(always)]
        fn where_positive(self, gate: Self) -> Self {
            unsafe {
                let zero = _mm256_setzero_ps();
                Avx2(
                    _mm256_and_ps(self.0, _mm256_cmp_ps::<_CMP_GT_OQ>(gate.0, zero)),
                    _mm256_and_ps(self.1, _mm256_cmp_ps::<_CMP_GT_OQ>(gate.1, zero)),
                )
            }
        }
        #[inline(always)]
        fn halving_sum(self) -> f32 {
            unsafe { halving_sum_of_eight(_mm256_add_ps(self.0, self.1)) }
        }
    }
}
