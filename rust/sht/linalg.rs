//! The matrix product behind the spherical harmonic transform's Legendre step.
//!
//! Every product in the transform is small (tens to hundreds of rows and inner length)
//! with contiguous columns in the right factor and the result, so one register-tiled
//! kernel serves them all: a 4 × 16 tile of the result stays in registers while the
//! inner index runs (4 × 32 in f32), each value of the right factor loaded once per 4 rows. General
//! GEMM libraries spend more on packing than on arithmetic at these sizes (the `gemm`
//! crate took a large share of a 90 × 180 transform: research/performance.md). The kernel is
//! compiled for AVX-512 and AVX2+FMA and chosen at run time.

use super::real::Real;

/// A strided read-only matrix view: element (r, c) is `data[offset + r·row_stride + c·col_stride]`.
#[derive(Clone, Copy)]
pub struct MatRef<'a, T> {
    pub data: &'a [T],
    pub offset: usize,
    pub rows: usize,
    pub cols: usize,
    pub row_stride: usize,
    pub col_stride: usize,
}

/// A mutable matrix view with contiguous rows: element (r, c) is
/// `data[offset + r·row_stride + c]`.
pub struct MatMut<'a, T> {
    pub data: &'a mut [T],
    pub offset: usize,
    pub rows: usize,
    pub cols: usize,
    pub row_stride: usize,
}

const TILE_ROWS: usize = 4;
/// Columns per tile: two 512-bit registers per row, 16 f64 or 32 f32.
const TILE_BYTES: usize = 128;

/// A left factor packed for the kernel: rows in tiles of [`TILE_ROWS`], each tile stored
/// k-major (`[tile][k][row in tile]`, zero-padded), so the kernel reads it without strides.
/// Fixed matrices (Legendre tables) are packed once per plan.
#[derive(Clone, Debug, Default)]
pub struct Packed<T> {
    rows: usize,
    depth: usize,
    data: Vec<T>,
}

impl<T: Real> Packed<T> {
    pub fn new(lhs: MatRef<'_, T>) -> Self {
        let mut packed = Packed::default();
        packed.pack(lhs);
        packed
    }

    /// Packs `lhs` into this buffer, reusing its allocation.
    pub fn pack(&mut self, lhs: MatRef<'_, T>) {
        assert!(
            reaches(
                lhs.data.len(),
                lhs.offset,
                lhs.rows,
                lhs.cols,
                lhs.row_stride,
                lhs.col_stride
            ),
            "lhs out of bounds"
        );
        let tiles = lhs.rows.div_ceil(TILE_ROWS);
        self.rows = lhs.rows;
        self.depth = lhs.cols;
        self.data.clear();
        self.data.resize(tiles * lhs.cols * TILE_ROWS, T::zero());
        if lhs.cols == 0 {
            return;
        }
        for (tile, panel) in self.data.chunks_exact_mut(lhs.cols * TILE_ROWS).enumerate() {
            for (k, values) in panel.chunks_exact_mut(TILE_ROWS).enumerate() {
                for (r, value) in values.iter_mut().enumerate() {
                    let row = tile * TILE_ROWS + r;
                    if row < lhs.rows {
                        *value = lhs.data[lhs.offset + row * lhs.row_stride + k * lhs.col_stride];
                    }
                }
            }
        }
    }

    /// The inner dimension: columns of the packed matrix.
    pub fn depth(&self) -> usize {
        self.depth
    }
}

fn reaches(len: usize, offset: usize, rows: usize, cols: usize, row_stride: usize, col_stride: usize) -> bool {
    rows == 0 || cols == 0 || offset + (rows - 1) * row_stride + (cols - 1) * col_stride < len
}

/// `dst = lhs · rhs` for a strided `lhs` (packed on the fly). The transform packs its
/// factors itself; the tests check the kernel through this.
#[cfg(test)]
pub fn matmul<T: Real>(dst: MatMut<'_, T>, lhs: MatRef<'_, T>, rhs: MatRef<'_, T>) {
    matmul_packed(dst, &Packed::new(lhs), rhs)
}

/// `dst = lhs · rhs`. `rhs` must have contiguous columns (`col_stride == 1`).
///
/// # Panics
/// If the shapes disagree or a view reaches past its slice.
pub fn matmul_packed<T: Real>(dst: MatMut<'_, T>, lhs: &Packed<T>, rhs: MatRef<'_, T>) {
    assert!(
        dst.rows == lhs.rows && dst.cols == rhs.cols && lhs.depth == rhs.rows,
        "matmul shapes disagree"
    );
    assert!(
        rhs.col_stride == 1 || rhs.cols <= 1,
        "matmul needs contiguous columns on the right"
    );
    assert!(
        reaches(dst.data.len(), dst.offset, dst.rows, dst.cols, dst.row_stride, 1),
        "dst out of bounds"
    );
    assert!(
        reaches(rhs.data.len(), rhs.offset, rhs.rows, rhs.cols, rhs.row_stride, 1),
        "rhs out of bounds"
    );

    match std::mem::size_of::<T>() {
        4 => dispatch::<T, { TILE_BYTES / 4 }>(dst, lhs, rhs),
        _ => dispatch::<T, { TILE_BYTES / 8 }>(dst, lhs, rhs),
    }
}

/// Runs the kernel compiled for the widest vector unit the CPU has.
fn dispatch<T: Real, const TILE_COLS: usize>(dst: MatMut<'_, T>, lhs: &Packed<T>, rhs: MatRef<'_, T>) {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { kernel_avx512::<T, TILE_COLS>(dst, lhs, rhs) };
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { kernel_avx2::<T, TILE_COLS>(dst, lhs, rhs) };
        }
    }
    kernel::<T, TILE_COLS>(dst, lhs, rhs)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn kernel_avx512<T: Real, const TILE_COLS: usize>(dst: MatMut<'_, T>, lhs: &Packed<T>, rhs: MatRef<'_, T>) {
    kernel::<T, TILE_COLS>(dst, lhs, rhs)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn kernel_avx2<T: Real, const TILE_COLS: usize>(dst: MatMut<'_, T>, lhs: &Packed<T>, rhs: MatRef<'_, T>) {
    kernel::<T, TILE_COLS>(dst, lhs, rhs)
}

#[inline(always)]
fn kernel<T: Real, const TILE_COLS: usize>(dst: MatMut<'_, T>, lhs: &Packed<T>, rhs: MatRef<'_, T>) {
    let MatMut {
        data: out,
        offset: out_offset,
        rows,
        cols,
        row_stride: out_stride,
    } = dst;
    if lhs.depth == 0 {
        for r in 0..rows {
            out[out_offset + r * out_stride..][..cols]
                .iter_mut()
                .for_each(|v| *v = T::zero());
        }
        return;
    }
    for (tile, panel) in lhs.data.chunks_exact(lhs.depth * TILE_ROWS).enumerate() {
        let r0 = tile * TILE_ROWS;
        let tile_rows = TILE_ROWS.min(rows - r0);
        if cols == 2 {
            // One map's (cosine, sine) pair: vectorise across the tile's rows instead.
            let [first, second] = pair_tile(panel, rhs);
            for (r, (a, b)) in first.iter().zip(&second).enumerate().take(tile_rows) {
                let start = out_offset + (r0 + r) * out_stride;
                out[start] = *a;
                out[start + 1] = *b;
            }
            continue;
        }
        for c0 in (0..cols).step_by(TILE_COLS) {
            let tile_cols = TILE_COLS.min(cols - c0);
            // A narrower tile (fewer maps than a tile's columns) runs as a full one where the
            // right factor's slice holds a full tile's columns from it (the next values,
            // whose products are computed and not stored): the narrow loop runs in scalars,
            // and took five times as long a map for batches of two or three maps
            // (research/performance.md). The last tile of a product (an order's last
            // degrees) computes only its own rows: padding rows cost as much as real ones,
            // 7 % of a 90 × 180 analysis's products.
            let acc = if tile_cols == TILE_COLS || full_width_fits(&rhs, c0, TILE_COLS) {
                match tile_rows {
                    1 => full_tile::<T, 1, TILE_COLS>(panel, rhs, c0),
                    2 => full_tile::<T, 2, TILE_COLS>(panel, rhs, c0),
                    3 => full_tile::<T, 3, TILE_COLS>(panel, rhs, c0),
                    _ => full_tile::<T, 4, TILE_COLS>(panel, rhs, c0),
                }
            } else {
                edge_tile::<T, TILE_COLS>(panel, rhs, c0, tile_cols)
            };
            let start = out_offset + r0 * out_stride + c0;
            store_rows(out, start, out_stride, &acc[..tile_rows], tile_cols);
        }
    }
}

/// Whether every row of `rhs` has `width` values from column `c0` inside its slice.
#[inline(always)]
fn full_width_fits<T>(rhs: &MatRef<'_, T>, c0: usize, width: usize) -> bool {
    rhs.rows == 0 || rhs.offset + (rhs.rows - 1) * rhs.row_stride + c0 + width <= rhs.data.len()
}

/// The first `ROWS` rows of a tile (the others are left zero).
#[inline(always)]
fn full_tile<T: Real, const ROWS: usize, const TILE_COLS: usize>(
    panel: &[T],
    rhs: MatRef<'_, T>,
    c0: usize,
) -> [[T; TILE_COLS]; TILE_ROWS] {
    // Separate accumulators per row keep the whole tile in registers; the rows past `ROWS`
    // are compiled out.
    let (mut acc0, mut acc1, mut acc2, mut acc3) = (
        [T::zero(); TILE_COLS],
        [T::zero(); TILE_COLS],
        [T::zero(); TILE_COLS],
        [T::zero(); TILE_COLS],
    );
    let stride = rhs.row_stride;
    let b_rows = &rhs.data[rhs.offset + c0..];
    for (k, a) in panel.chunks_exact(TILE_ROWS).enumerate() {
        let b: &[T; TILE_COLS] = b_rows[k * stride..][..TILE_COLS].try_into().unwrap();
        let (a0, a1, a2, a3) = (a[0], a[1], a[2], a[3]);
        for c in 0..TILE_COLS {
            acc0[c] = a0.mul_add(b[c], acc0[c]);
            if ROWS > 1 {
                acc1[c] = a1.mul_add(b[c], acc1[c]);
            }
            if ROWS > 2 {
                acc2[c] = a2.mul_add(b[c], acc2[c]);
            }
            if ROWS > 3 {
                acc3[c] = a3.mul_add(b[c], acc3[c]);
            }
        }
    }
    [acc0, acc1, acc2, acc3]
}

/// Writes a tile's first `cols` columns of `rows` from `start`, rows `stride` apart. A whole
/// tile's row is copied as one fixed-size array, which compiles to vector stores (a
/// run-time length became a call to `memcpy` a row).
#[inline(always)]
fn store_rows<T: Real, const TILE_COLS: usize>(
    out: &mut [T],
    start: usize,
    stride: usize,
    rows: &[[T; TILE_COLS]],
    cols: usize,
) {
    for (r, row) in rows.iter().enumerate() {
        let line = &mut out[start + r * stride..];
        if cols == TILE_COLS {
            line[..TILE_COLS].copy_from_slice(row);
        } else {
            line[..cols].copy_from_slice(&row[..cols]);
        }
    }
}

#[inline(always)]
fn pair_tile<T: Real>(panel: &[T], rhs: MatRef<'_, T>) -> [[T; TILE_ROWS]; 2] {
    let (mut first, mut second) = ([T::zero(); TILE_ROWS], [T::zero(); TILE_ROWS]);
    let b_rows = &rhs.data[rhs.offset..];
    for (k, a) in panel.chunks_exact(TILE_ROWS).enumerate() {
        let (b0, b1) = (b_rows[k * rhs.row_stride], b_rows[k * rhs.row_stride + 1]);
        let a: &[T; TILE_ROWS] = a.try_into().unwrap();
        for r in 0..TILE_ROWS {
            first[r] = a[r].mul_add(b0, first[r]);
            second[r] = a[r].mul_add(b1, second[r]);
        }
    }
    [first, second]
}

#[inline(always)]
fn edge_tile<T: Real, const TILE_COLS: usize>(
    panel: &[T],
    rhs: MatRef<'_, T>,
    c0: usize,
    tile_cols: usize,
) -> [[T; TILE_COLS]; TILE_ROWS] {
    let mut acc = [[T::zero(); TILE_COLS]; TILE_ROWS];
    for (k, a) in panel.chunks_exact(TILE_ROWS).enumerate() {
        let b = &rhs.data[rhs.offset + k * rhs.row_stride + c0..][..tile_cols];
        for r in 0..TILE_ROWS {
            for (acc_value, &b_value) in acc[r].iter_mut().zip(b) {
                *acc_value = a[r].mul_add(b_value, *acc_value);
            }
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each shape twice: with the right factor's slice ending at its last column, and going on past
    /// it (as a batch of a few maps in the transform's buffers does), where narrow tiles run as
    /// full ones: the NaNs past the columns must reach no stored product.
    #[test]
    fn strided_product_matches_a_loop() {
        let shapes = [
            (5, 4, 3),
            (9, 45, 40),
            (4, 1, 16),
            (1, 7, 33),
            (7, 9, 2),
            (9, 45, 6),
            (6, 5, 40),
            (3, 20, 1),
        ];
        for ((m, k, n), tail) in shapes.into_iter().flat_map(|shape| [(shape, 0), (shape, 64)]) {
            let a: Vec<f64> = (0..m * k).map(|i| i as f64 * 0.5 - 3.0).collect();
            let mut b: Vec<f64> = (0..k * n).map(|i| (i * i) as f64 % 7.0).collect();
            b.extend(std::iter::repeat_n(f64::NAN, tail));
            // lhs stored transposed (k × m); dst every other row of a 2m × n buffer.
            let a_t: Vec<f64> = (0..k * m).map(|i| a[(i % m) * k + i / m]).collect();
            let mut dst = vec![0.0; 2 * m * n];
            matmul(
                MatMut {
                    data: &mut dst,
                    offset: n,
                    rows: m,
                    cols: n,
                    row_stride: 2 * n,
                },
                MatRef {
                    data: &a_t,
                    offset: 0,
                    rows: m,
                    cols: k,
                    row_stride: 1,
                    col_stride: m,
                },
                MatRef {
                    data: &b,
                    offset: 0,
                    rows: k,
                    cols: n,
                    row_stride: n,
                    col_stride: 1,
                },
            );
            for r in 0..m {
                for c in 0..n {
                    let expected: f64 = (0..k).map(|i| a[r * k + i] * b[i * n + c]).sum();
                    assert!((dst[n + r * 2 * n + c] - expected).abs() < 1e-9 * expected.abs().max(1.0));
                    assert_eq!(dst[r * 2 * n + c], 0.0);
                }
            }
        }
    }
}
