//! The float32 evaluator's table lookups by AVX-512 gathers: two instructions fetch two
//! neighbouring values for all [`LANES`] pairs, where the per-lane path ([`super::batch`])
//! moves each lane's index out of the vector registers and loads four values at a time.
//!
//! Which of the two is faster depends on the CPU: on an Intel Xeon (Emerald Rapids) the
//! gathers take 0.76× the time on 2 threads; on an AMD Zen 4 gathers of one value each were
//! no faster than the per-lane loads (these of two values are not measured there;
//! research/performance.md). [`super::batch::Tables::eval_chunk`] uses them on Intel CPUs
//! with AVX-512 only, and not where the microcode's Downfall mitigation slows them
//! ([`preferred`]). Both paths add the same products in the same order: their results are
//! equal to the bit.
//!
//! Every function here is called only from code compiled with AVX-512 (F, BW, DQ, VL) for a
//! CPU that has it, which makes its intrinsics sound; each checks that its indices lie in
//! the table before it reads (as unsigned numbers: an index the gathers would read as
//! negative fails the check too).

use std::arch::x86_64::*;

use super::simd::{bilinear_weights, lanes, Lanes, LANES};

/// Lanes of u32 or f32 as a 512-bit register, and back.
#[inline(always)]
fn indices(values: &Lanes<u32>) -> __m512i {
    // SAFETY: see the module's docs; the array holds 16 u32.
    unsafe { _mm512_loadu_si512(values.as_ptr().cast()) }
}

#[inline(always)]
fn load(values: &Lanes<f32>) -> __m512 {
    // SAFETY: see the module's docs; the array holds 16 f32.
    unsafe { _mm512_loadu_ps(values.as_ptr()) }
}

#[inline(always)]
fn store(value: __m512) -> Lanes<f32> {
    let mut out = [0f32; LANES];
    // SAFETY: see the module's docs; the array holds 16 f32.
    unsafe { _mm512_storeu_ps(out.as_mut_ptr(), value) };
    out
}

/// `sums[v] + weight × table[at + v]` per lane for each `v` of `sums`: `at` the lanes'
/// entries, their first values' indices (the entry's values follow each other). The values
/// come two at a time, by gathers of 64 bits (eight lanes each): half the loads of one
/// gather per value.
#[inline(always)]
fn add_weighted<const N: usize>(sums: &mut [__m512; N], weight: __m512, table: &[f32], at: __m512i) {
    // SAFETY: see the module's docs. Every index read is at most the largest of `at` plus
    // N rounded up to even, less 1, checked against the table's length first.
    unsafe {
        let last = _mm512_reduce_max_epu32(at) as usize + N.next_multiple_of(2) - 1;
        assert!(last < table.len(), "table index {last} beyond {}", table.len());
        for first in (0..N).step_by(2) {
            let pairs = pairs(table, offset(at, first as u32));
            for (v, values) in pairs.into_iter().enumerate().take(N - first) {
                // A multiply and an add, not a fused one: the per-lane path's rounding.
                sums[first + v] = _mm512_add_ps(sums[first + v], _mm512_mul_ps(weight, values));
            }
        }
    }
}

/// `table[at]` and `table[at + 1]` of each lane, one register each.
///
/// # Safety
/// Every `at + 1` must lie in the table, and the CPU must have AVX-512 F.
#[inline(always)]
unsafe fn pairs(table: &[f32], at: __m512i) -> [__m512; 2] {
    // Lanes 0–7, then 8–15: 64 bits from each index (scale 4: the indices count f32).
    let base = table.as_ptr().cast::<f64>();
    let low = _mm512_castpd_ps(_mm512_i32gather_pd::<4>(_mm512_castsi512_si256(at), base));
    let high = _mm512_castpd_ps(_mm512_i32gather_pd::<4>(_mm512_extracti64x4_epi64::<1>(at), base));
    // Each register holds (first, second) per lane: the firsts, then the seconds.
    let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    let odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
    [
        _mm512_permutex2var_ps(low, even, high),
        _mm512_permutex2var_ps(low, odd, high),
    ]
}

#[inline(always)]
fn offset(at: __m512i, by: u32) -> __m512i {
    // SAFETY: see the module's docs.
    unsafe { _mm512_add_epi32(at, _mm512_set1_epi32(by as i32)) }
}

#[inline(always)]
fn scaled(at: __m512i, by: u32) -> __m512i {
    // SAFETY: see the module's docs.
    unsafe { _mm512_mullo_epi32(at, _mm512_set1_epi32(by as i32)) }
}

/// The VNDF's blended values at each lane's patch, as [`super::batch`]'s per-lane path has
/// them: the density and CDF at the patch's lower-left node and the density at its right
/// neighbour (`low`), the same a row up (`high`), and the row's integral, the marginal CDF
/// and the next row's integral (`rows`). `nodes` holds (density, CDF) per node of each
/// slice's `nx` × `ny` grid, `row_values` (integral, marginal CDF) per row of each slice.
#[inline(always)]
pub(super) fn vndf<const CORNERS: usize>(
    nodes: &[f32],
    row_values: &[f32],
    (nx, ny): (u32, u32),
    corners: &[(Lanes<u32>, Lanes<f32>); CORNERS],
    node: &Lanes<u32>,
    row: &Lanes<u32>,
) -> [[Lanes<f32>; 3]; 3] {
    // SAFETY: see the module's docs.
    let zero = unsafe { _mm512_setzero_ps() };
    let (mut low, mut high, mut rows) = ([zero; 3], [zero; 3], [zero; 3]);
    let (node, row) = (indices(node), indices(row));
    for (slice, weight) in corners {
        let (slice, weight) = (indices(slice), load(weight));
        // 2 × (slice · plane + node): the index of the node's density.
        let at = scaled(offset_by(scaled(slice, nx * ny), node), 2);
        add_weighted(&mut low, weight, nodes, at);
        add_weighted(&mut high, weight, nodes, offset(at, 2 * nx));
        add_weighted(
            &mut rows,
            weight,
            row_values,
            scaled(offset_by(scaled(slice, ny), row), 2),
        );
    }
    [low.map(store), high.map(store), rows.map(store)]
}

/// The RGB table's values at each lane's patch, blended over the slices with the bilinear
/// weights ([`bilinear_weights`]), as the per-lane path sums them.
/// `nodes` holds (red, green, blue, 0) per node of each slice's `nx` × `ny` grid.
#[inline(always)]
pub(super) fn rgb<const CORNERS: usize>(
    nodes: &[f32],
    (nx, ny): (u32, u32),
    corners: &[(Lanes<u32>, Lanes<f32>); CORNERS],
    node: &Lanes<u32>,
    (s, t): (&Lanes<f32>, &Lanes<f32>),
) -> [Lanes<f32>; 3] {
    // [`bilinear_weights`] as one array per corner (lanes innermost, as the sums want them).
    let bilinear: [Lanes<f32>; 4] = [
        lanes!(|k| bilinear_weights(s[k], t[k])[0]),
        lanes!(|k| bilinear_weights(s[k], t[k])[1]),
        lanes!(|k| bilinear_weights(s[k], t[k])[2]),
        lanes!(|k| bilinear_weights(s[k], t[k])[3]),
    ];
    // SAFETY: see the module's docs.
    let mut sums = [unsafe { _mm512_setzero_ps() }; 3];
    let node = indices(node);
    for (slice, weight) in corners {
        let base = offset_by(scaled(indices(slice), nx * ny), node);
        for (corner, b) in [0, 1, nx, nx + 1].into_iter().zip(&bilinear) {
            let product = lanes!(|k| weight[k] * b[k]);
            add_weighted(&mut sums, load(&product), nodes, scaled(offset(base, corner), 4));
        }
    }
    sums.map(store)
}

/// A one-channel table's values at the corners of each lane's patch: at `node`, its right
/// neighbour, and the two a row of `nx` up.
#[inline(always)]
pub(super) fn patch(values: &[f32], nx: u32, node: &Lanes<u32>) -> [Lanes<f32>; 4] {
    // SAFETY: see the module's docs.
    let (zero, one) = unsafe { (_mm512_setzero_ps(), _mm512_set1_ps(1.0)) };
    let (mut low, mut high) = ([zero; 2], [zero; 2]);
    let node = indices(node);
    // Weight 1: each value as it is (1 × v + 0 is v, to the bit).
    add_weighted(&mut low, one, values, node);
    add_weighted(&mut high, one, values, offset(node, nx));
    [store(low[0]), store(low[1]), store(high[0]), store(high[1])]
}

#[inline(always)]
fn offset_by(at: __m512i, by: __m512i) -> __m512i {
    // SAFETY: see the module's docs.
    unsafe { _mm512_add_epi32(at, by) }
}

/// Whether a CPU with AVX-512 should take the gathers: an Intel CPU whose gathers run at
/// full speed. Intel's microcode against Gather Data Sampling ("Downfall", Skylake to
/// Tiger Lake) makes every gather several times slower; where the kernel does not say that
/// no such mitigation runs, the per-lane loads stay.
pub(super) fn preferred() -> bool {
    intel()
        && std::fs::read_to_string("/sys/devices/system/cpu/vulnerabilities/gather_data_sampling")
            .is_ok_and(|status| gathers_at_full_speed(&status))
}

/// Whether the kernel's Gather Data Sampling status leaves the gathers as fast as the CPU
/// makes them: not affected, or affected without the microcode's mitigation.
fn gathers_at_full_speed(status: &str) -> bool {
    status.starts_with("Not affected") || status.starts_with("Vulnerable")
}

/// The CPU's vendor is Intel (CPUID leaf 0: "GenuineIntel").
fn intel() -> bool {
    let id = __cpuid(0); // leaf 0 exists on every x86_64 CPU
    [id.ebx, id.edx, id.ecx].map(u32::to_le_bytes).concat() == b"GenuineIntel"
}

#[cfg(test)]
mod tests {
    use super::gathers_at_full_speed;

    #[test]
    fn gathers_are_taken_only_where_no_mitigation_slows_them() {
        assert!(gathers_at_full_speed("Not affected\n"));
        assert!(gathers_at_full_speed("Vulnerable: No microcode\n"));
        assert!(!gathers_at_full_speed("Mitigation: Microcode\n"));
        assert!(!gathers_at_full_speed("Unknown: Dependent on hypervisor status\n"));
    }
}
