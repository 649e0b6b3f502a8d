//! A safe, bounds-checked front to the `gemm` crate's strided matrix product.

use crate::sht::Real;

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

/// A strided mutable matrix view, laid out like [`MatRef`].
pub struct MatMut<'a, T> {
    pub data: &'a mut [T],
    pub offset: usize,
    pub rows: usize,
    pub cols: usize,
    pub row_stride: usize,
    pub col_stride: usize,
}

fn last_index(offset: usize, rows: usize, cols: usize, row_stride: usize, col_stride: usize) -> Option<usize> {
    (rows > 0 && cols > 0).then(|| offset + (rows - 1) * row_stride + (cols - 1) * col_stride)
}

/// `dst = lhs · rhs`, or `dst += lhs · rhs` with `accumulate`. Single-threaded: callers
/// parallelise over independent products.
///
/// # Panics
/// If the shapes disagree or a view reaches past its slice.
pub fn matmul<T: Real>(dst: MatMut<'_, T>, lhs: MatRef<'_, T>, rhs: MatRef<'_, T>, accumulate: bool) {
    assert!(dst.rows == lhs.rows && dst.cols == rhs.cols && lhs.cols == rhs.rows, "matmul shapes disagree");
    for (len, last) in [
        (dst.data.len(), last_index(dst.offset, dst.rows, dst.cols, dst.row_stride, dst.col_stride)),
        (lhs.data.len(), last_index(lhs.offset, lhs.rows, lhs.cols, lhs.row_stride, lhs.col_stride)),
        (rhs.data.len(), last_index(rhs.offset, rhs.rows, rhs.cols, rhs.row_stride, rhs.col_stride)),
    ] {
        assert!(last.is_none_or(|last| last < len), "matrix view out of bounds");
    }
    if dst.rows == 0 || dst.cols == 0 {
        return;
    }
    if lhs.cols == 0 {
        if !accumulate {
            fill_zero(dst);
        }
        return;
    }
    // SAFETY: every element the product touches was bounds-checked above, and `dst` is a
    // unique borrow, so it cannot alias `lhs` or `rhs`.
    unsafe {
        gemm::gemm(
            dst.rows,
            dst.cols,
            lhs.cols,
            dst.data.as_mut_ptr().add(dst.offset),
            dst.col_stride as isize,
            dst.row_stride as isize,
            accumulate,
            lhs.data.as_ptr().add(lhs.offset),
            lhs.col_stride as isize,
            lhs.row_stride as isize,
            rhs.data.as_ptr().add(rhs.offset),
            rhs.col_stride as isize,
            rhs.row_stride as isize,
            T::one(),
            T::one(),
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

fn fill_zero<T: Real>(dst: MatMut<'_, T>) {
    for r in 0..dst.rows {
        for c in 0..dst.cols {
            dst.data[dst.offset + r * dst.row_stride + c * dst.col_stride] = T::zero();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_product_matches_a_loop() {
        let (m, k, n) = (5, 4, 3);
        let a: Vec<f64> = (0..m * k).map(|i| i as f64 * 0.5 - 3.0).collect();
        let b: Vec<f64> = (0..k * n).map(|i| (i * i) as f64 % 7.0).collect();
        // dst every other row of a 10 × 3 buffer; lhs transposed storage (k × m).
        let a_t: Vec<f64> = (0..k * m).map(|i| a[(i % m) * k + i / m]).collect();
        let mut dst = vec![0.0; 2 * m * n];
        matmul(
            MatMut { data: &mut dst, offset: n, rows: m, cols: n, row_stride: 2 * n, col_stride: 1 },
            MatRef { data: &a_t, offset: 0, rows: m, cols: k, row_stride: 1, col_stride: m },
            MatRef { data: &b, offset: 0, rows: k, cols: n, row_stride: n, col_stride: 1 },
            false,
        );
        for r in 0..m {
            for c in 0..n {
                let expected: f64 = (0..k).map(|i| a[r * k + i] * b[i * n + c]).sum();
                assert!((dst[n + r * 2 * n + c] - expected).abs() < 1e-12);
                assert_eq!(dst[r * 2 * n + c], 0.0);
            }
        }
    }
}
