//! Ring positions and quadrature for the two grids, and the exact resampling that lets
//! the equiangular grid be analysed up to lmax = nlat − 2.

use std::f64::consts::PI;

/// Gauss–Legendre colatitudes θ_j (ascending, so cos θ descends from ≈1) and weights
/// w_j with Σ w_j = 2. Newton's method in θ keeps full precision near the poles.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut theta = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for j in 0..n.div_ceil(2) {
        // Tricomi's initial guess, then Newton on P_n(cos θ) with dP_n/dθ = −P¹_n.
        let mut t = PI * (j as f64 + 0.75) / (n as f64 + 0.5);
        let mut derivative = 0.0;
        for _ in 0..100 {
            let (p, p1) = legendre_and_first_associated(n, t);
            derivative = p1;
            let step = p / p1;
            t += step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        let (_, p1) = legendre_and_first_associated(n, t);
        if p1.is_finite() {
            derivative = p1;
        }
        theta[j] = t;
        theta[n - 1 - j] = PI - t;
        weights[j] = 2.0 / (derivative * derivative);
        weights[n - 1 - j] = weights[j];
    }
    if n % 2 == 1 {
        theta[n / 2] = PI / 2.0;
    }
    (theta, weights)
}

/// P_n(cos θ) and P¹_n(cos θ) = sin θ · P_n'(cos θ), by their upward recurrences.
fn legendre_and_first_associated(n: usize, theta: f64) -> (f64, f64) {
    let (x, s) = (theta.cos(), theta.sin());
    let (mut p_previous, mut p) = (1.0, x);
    let (mut q_previous, mut q) = (0.0, s); // P¹_0 = 0, P¹_1 = sin θ
    if n == 0 {
        return (1.0, 0.0);
    }
    for l in 2..=n {
        let l_f = l as f64;
        let p_next = ((2.0 * l_f - 1.0) * x * p - (l_f - 1.0) * p_previous) / l_f;
        let q_next = ((2.0 * l_f - 1.0) * x * q - l_f * q_previous) / (l_f - 1.0);
        (p_previous, p) = (p, p_next);
        (q_previous, q) = (q, q_next);
    }
    (p, q)
}

/// Equiangular colatitudes θ_j = π j / (n − 1), both poles included.
pub fn equiangular(n: usize) -> Vec<f64> {
    (0..n)
        .map(|j| if n == 1 { 0.0 } else { PI * j as f64 / (n - 1) as f64 })
        .collect()
}

/// Clenshaw–Curtis weights for the equiangular rings (exact for polynomials in cos θ of
/// degree ≤ n − 1); Σ w_j = 2.
pub fn clenshaw_curtis_weights(n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![2.0];
    }
    let intervals = n - 1;
    (0..n)
        .map(|j| {
            let theta = PI * j as f64 / intervals as f64;
            let mut sum = 0.0;
            for k in 1..=intervals / 2 {
                let b = if 2 * k == intervals { 1.0 } else { 2.0 };
                sum += b / (4.0 * (k * k) as f64 - 1.0) * (2.0 * k as f64 * theta).cos();
            }
            let c = if j == 0 || j == intervals { 1.0 } else { 2.0 };
            c / intervals as f64 * (1.0 - sum)
        })
        .collect()
}

/// Interpolation from the equiangular rings to Gauss–Legendre rings, exact for the
/// colatitude profile g_m(θ) of any band-limited map.
///
/// For even m, g_m is a polynomial of degree ≤ lmax in cos θ, fixed by the n equiangular
/// samples (Chebyshev–Lobatto points) when lmax ≤ n − 1. For odd m, g_m = sin θ · p(cos θ)
/// with deg p ≤ lmax − 1, fixed by the n − 2 samples off the poles when lmax ≤ n − 2.
/// Both use barycentric Lagrange interpolation with the closed-form weights of those
/// node sets. Returns `[even m, odd m]`, each row-major (n_target × n_source).
pub fn equiangular_to_gauss(source_theta: &[f64], target_theta: &[f64]) -> [Vec<f64>; 2] {
    let n = source_theta.len();
    let x: Vec<f64> = source_theta.iter().map(|t| t.cos()).collect();
    // Lobatto: w_j = (−1)^j, halved at the ends. Interior (roots of U_{n−2}): (−1)^j sin² θ_j.
    let sign = |j: usize| if j.is_multiple_of(2) { 1.0 } else { -1.0 };
    let is_pole = |j: usize| j == 0 || j == n - 1;
    let even_weights: Vec<f64> = (0..n).map(|j| sign(j) * if is_pole(j) { 0.5 } else { 1.0 }).collect();
    let odd_weights: Vec<f64> = (0..n)
        .map(|j| {
            if is_pole(j) {
                0.0
            } else {
                sign(j) * source_theta[j].sin().powi(2)
            }
        })
        .collect();

    let mut even = vec![0.0; target_theta.len() * n];
    let mut odd = vec![0.0; target_theta.len() * n];
    for (k, &t) in target_theta.iter().enumerate() {
        let y = t.cos();
        barycentric_row(&x, &even_weights, y, &mut even[k * n..(k + 1) * n]);
        barycentric_row(&x, &odd_weights, y, &mut odd[k * n..(k + 1) * n]);
        // g = sin θ · p: divide the samples by sin θ_j, multiply the result by sin θ_k.
        for j in 1..n - 1 {
            odd[k * n + j] *= t.sin() / source_theta[j].sin();
        }
    }
    [even, odd]
}

/// Lagrange basis values L_j(y) for nodes `x` with barycentric weights `w` (nodes with
/// zero weight are left out).
fn barycentric_row(x: &[f64], w: &[f64], y: f64, row: &mut [f64]) {
    if let Some(j) = (0..x.len()).find(|&j| w[j] != 0.0 && y == x[j]) {
        row.iter_mut().for_each(|v| *v = 0.0);
        row[j] = 1.0;
        return;
    }
    let mut total = 0.0;
    for j in 0..x.len() {
        row[j] = if w[j] == 0.0 { 0.0 } else { w[j] / (y - x[j]) };
        total += row[j];
    }
    row.iter_mut().for_each(|v| *v /= total);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |Σ w_j cos^d θ_j − ∫_{−1}^{1} x^d dx|.
    fn quadrature_error(theta: &[f64], weights: &[f64], degree: usize) -> f64 {
        let integral: f64 = theta
            .iter()
            .zip(weights)
            .map(|(t, w)| w * t.cos().powi(degree as i32))
            .sum();
        let exact = if degree.is_multiple_of(2) {
            2.0 / (degree as f64 + 1.0)
        } else {
            0.0
        };
        (integral - exact).abs()
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [1, 2, 5, 90, 91, 1024] {
            let (theta, weights) = gauss_legendre(n);
            assert!((weights.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n={n}");
            for degree in [2 * n - 2, 2 * n - 1] {
                assert!(
                    quadrature_error(&theta, &weights, degree) < 1e-13,
                    "n={n} degree={degree}"
                );
            }
        }
    }

    #[test]
    fn clenshaw_curtis_integrates_polynomials_exactly() {
        for n in [2, 3, 10, 91] {
            let (theta, weights) = (equiangular(n), clenshaw_curtis_weights(n));
            for degree in 0..n {
                assert!(
                    quadrature_error(&theta, &weights, degree) < 1e-13,
                    "n={n} degree={degree}"
                );
            }
        }
    }

    #[test]
    fn resampling_is_exact_for_band_limited_profiles() {
        let n = 12;
        let source = equiangular(n);
        let (target, _) = gauss_legendre(11);
        let [even, odd] = equiangular_to_gauss(&source, &target);
        let p = |x: f64| 0.3 + x - 2.0 * x.powi(5) + 0.7 * x.powi(11); // degree n − 1
        let q = |x: f64| 1.0 - x.powi(3) + 0.5 * x.powi(9); // degree n − 3
        for (k, t) in target.iter().enumerate() {
            let even_value: f64 = (0..n).map(|j| even[k * n + j] * p(source[j].cos())).sum();
            let odd_value: f64 = (0..n)
                .map(|j| odd[k * n + j] * source[j].sin() * q(source[j].cos()))
                .sum();
            assert!((even_value - p(t.cos())).abs() < 1e-12);
            assert!((odd_value - t.sin() * q(t.cos())).abs() < 1e-12);
        }
    }
}
