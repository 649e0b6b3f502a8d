//! The lane arithmetic of the float32 evaluator ([`super::batch`]): arrays of [`LANES`]
//! values, in loops that the compiler turns into SIMD code.

use std::f32::consts::{FRAC_PI_2, PI};

/// Pairs per step: a 512-bit register of float32, two of AVX2's, four of SSE's.
pub const LANES: usize = 16;

pub type Lanes<T> = [T; LANES];

/// `lanes!(|k| value)`: the array of `value` for each lane `k`. A macro, so that the body
/// is written out in the loop: a closure is not always inlined, and where it is not it is
/// compiled without the caller's target features.
macro_rules! lanes {
    (|$k:ident| $value:expr) => {{
        let mut out = [Default::default(); $crate::bsdf::simd::LANES];
        for $k in 0..$crate::bsdf::simd::LANES {
            out[$k] = $value;
        }
        out
    }};
}
pub(super) use lanes;

#[inline(always)]
pub fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + t * (b - a)
}

/// The bilinear interpolant of a patch's corners (x fastest) at (s, t).
#[inline(always)]
pub fn bilinear([v00, v10, v01, v11]: [f32; 4], s: f32, t: f32) -> f32 {
    lerp(lerp(v00, v10, s), lerp(v01, v11, s), t)
}

/// The weights of a patch's corners (x fastest) at (s, t): `(1 − s)(1 − t)`, `s(1 − t)`,
/// `(1 − s)t`, `st`, in the order both table-reading paths of [`super::batch`] sum them.
#[inline(always)]
pub fn bilinear_weights(s: f32, t: f32) -> [f32; 4] {
    [(1.0 - s) * (1.0 - t), s * (1.0 - t), (1.0 - s) * t, s * t]
}

/// atan2 in float32 within a few ulp, branch-free so that it vectorises: an odd polynomial
/// for atan on [0, 1] (SLEEF's `atanf` coefficients), then the octant.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (small, large) = (ax.min(ay), ax.max(ay));
    let a = if large > 0.0 { small / large } else { 0.0 };
    let t = a * a;
    let mut u = 0.002_823_639;
    for c in [
        -0.015_956_903,
        0.042_504_99,
        -0.074_890_09,
        0.106_347_93,
        -0.142_027_36,
        0.199_926_96,
        -0.333_331,
    ] {
        u = u * t + c;
    }
    let mut angle = a + a * t * u;
    if ay > ax {
        angle = FRAC_PI_2 - angle;
    }
    if x < 0.0 {
        angle = PI - angle;
    }
    if y.is_sign_negative() {
        -angle
    } else {
        angle
    }
}

/// The angle of each lane's vector from the pole, accurate near it (unlike acos).
#[inline(always)]
pub fn elevation(v: &[Lanes<f32>; 3]) -> Lanes<f32> {
    lanes!(|k| atan2((v[0][k] * v[0][k] + v[1][k] * v[1][k]).sqrt(), v[2][k]))
}

/// Four float32 values of one table entry (a VNDF node's density and CDF and its right
/// neighbour's, a node's three colours and a pad), summed with weights in one 128-bit
/// register. Written out with SSE on x86_64: the compiler keeps a sum of four scalars apart
/// when one of them goes unused, and then each weight costs four multiplies and four adds.
#[derive(Clone, Copy)]
pub struct Quad(
    #[cfg(target_arch = "x86_64")] std::arch::x86_64::__m128,
    #[cfg(not(target_arch = "x86_64"))] [f32; 4],
);

#[cfg(target_arch = "x86_64")]
impl Quad {
    #[inline(always)]
    pub fn zero() -> Quad {
        // SAFETY: SSE is part of every x86_64 CPU.
        Quad(unsafe { std::arch::x86_64::_mm_setzero_ps() })
    }

    /// `self + weight × table[at..at + 4]`.
    #[inline(always)]
    pub fn add_weighted(self, weight: f32, table: &[f32], at: usize) -> Quad {
        use std::arch::x86_64::{_mm_add_ps, _mm_loadu_ps, _mm_mul_ps, _mm_set1_ps};
        let entry = &table[at..at + 4];
        // SAFETY: `entry` holds the four values read, and SSE is part of every x86_64 CPU.
        Quad(unsafe { _mm_add_ps(self.0, _mm_mul_ps(_mm_set1_ps(weight), _mm_loadu_ps(entry.as_ptr()))) })
    }

    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        // SAFETY: __m128 and [f32; 4] have the same size, and every bit pattern is valid.
        unsafe { std::mem::transmute(self.0) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl Quad {
    #[inline(always)]
    pub fn zero() -> Quad {
        Quad([0.0; 4])
    }

    /// `self + weight × table[at..at + 4]`.
    #[inline(always)]
    pub fn add_weighted(self, weight: f32, table: &[f32], at: usize) -> Quad {
        let values = &table[at..at + 4];
        Quad(std::array::from_fn(|c| self.0[c] + weight * values[c]))
    }

    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        self.0
    }
}

/// `table[at..at + 2]`, loaded at once.
#[inline(always)]
pub fn two(table: &[f32], at: usize) -> [f32; 2] {
    table[at..at + 2].try_into().unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_within_a_few_ulp() {
        let mut worst = 0f64;
        for a in 0..2000 {
            for r in [1e-30f64, 1e-6, 0.3, 1.0, 7.0, 1e20] {
                let angle = -std::f64::consts::PI + std::f64::consts::TAU * a as f64 / 1999.0;
                let (y, x) = ((r * angle.sin()) as f32, (r * angle.cos()) as f32);
                let exact = (y as f64).atan2(x as f64);
                let error = (atan2(y, x) as f64 - exact).abs() / exact.abs().max(1e-30);
                worst = worst.max(error);
            }
        }
        assert!(worst < 5e-7, "relative error {worst}");
        assert_eq!(atan2(0.0, 1.0), 0.0);
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(atan2(1.0, 0.0), FRAC_PI_2);
    }
}
