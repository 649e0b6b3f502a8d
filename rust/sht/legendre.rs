//! Orthonormal associated Legendre functions by a scaled three-term recurrence.
//!
//! λ_lm(θ) is normalised so that Y_lm = λ_lm(θ) e^{imφ} has unit norm on the sphere,
//! without the Condon–Shortley phase: λ_mm = √((2m+1)/4π · (2m−1)!!/(2m)!!) sin^m θ ≥ 0.
//! Upwards in l: λ_{m+1,m} = √(2m+3) cos θ λ_mm and
//! λ_lm = a_lm (cos θ λ_{l−1,m} − λ_{l−2,m} / a_{l−1,m}), a_lm = √((4l²−1)/(l²−m²)).
//! The recurrence runs rescaled, for two operations a step: with λ_lm = N_lm μ_lm,
//! μ_lm = (α_lm cos θ) μ_{l−1,m} − μ_{l−2,m} (see [`Recurrence::rescaled`]).
//!
//! sin^m θ underflows long before λ_lm does (m = 1000 at θ = 0.5 rad gives 10^−320, yet
//! λ_{4000,1000}(0.5) is of order 1), so values are carried as mantissa × 2^(600·scale)
//! and only turned into plain doubles once they are representable.

/// 2^600 and 2^−600: rescaling by them is exact.
pub(crate) const BIG: f64 = f64::from_bits((1023 + 600) << 52);
pub(crate) const SMALL: f64 = f64::from_bits((1023 - 600) << 52);

/// A value `mantissa · 2^(600·scale)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaled {
    pub mantissa: f64,
    pub scale: i32,
}

impl Scaled {
    pub const ZERO: Scaled = Scaled {
        mantissa: 0.0,
        scale: 0,
    };

    /// The value as a plain double; 0 where it is below ~10^−180, where it can no longer
    /// matter next to the O(1) values of the same transform.
    #[inline]
    pub fn value(self) -> f64 {
        match self.scale {
            0 => self.mantissa,
            -1 => self.mantissa * SMALL,
            _ => 0.0,
        }
    }
}

/// a_lm = √((4l²−1)/(l²−m²)), for l > m.
fn coefficient(l: usize, m: usize) -> f64 {
    let (l, m) = (l as f64, m as f64);
    ((4.0 * l * l - 1.0) / (l * l - m * m)).sqrt()
}

/// Recurrence coefficients for every m ≤ lmax.
pub struct Recurrence {
    lmax: usize,
    /// α_lm and N_lm (see [`Recurrence::rescaled`]) at `offset[m] + (l − m)`.
    alpha: Vec<f64>,
    norm: Vec<f64>,
    offset: Vec<usize>,
    /// Every order's [`Paired`] form, where lmax ≤ [`PAIRED_KEPT_LMAX`]. Computing it
    /// takes divisions in a chain, a noticeable share of a single-map analysis
    /// (research/performance.md).
    paired: Vec<Paired>,
}

/// Largest lmax whose [`Paired`] forms a [`Recurrence`] keeps (about 10 MB at 1023, as
/// much as its α and N); beyond it each order's form is computed again for every map,
/// which the kept ones avoid.
const PAIRED_KEPT_LMAX: usize = 1023;

impl Recurrence {
    pub fn new(lmax: usize) -> Self {
        let size = (lmax + 1) * (lmax + 2) / 2;
        let (mut alpha, mut norm) = (Vec::with_capacity(size), Vec::with_capacity(size));
        let mut offset = Vec::with_capacity(lmax + 1);
        for m in 0..=lmax {
            offset.push(alpha.len());
            // λ_l = a_l cos θ λ_{l−1} − (a_l / a_{l−1}) λ_{l−2}; dividing by N_l leaves μ_{l−2}
            // alone when N_l = (a_l / a_{l−1}) N_{l−2}, and then α_l = a_l N_{l−1} / N_l.
            let (mut before, mut last) = (1.0, 1.0); // N_{l−2}, N_{l−1}
            for l in m..=lmax {
                let n = if l < m + 2 {
                    1.0
                } else {
                    coefficient(l, m) / coefficient(l - 1, m) * before
                };
                alpha.push(if l == m { 0.0 } else { coefficient(l, m) * last / n });
                norm.push(n);
                (before, last) = (last, n);
            }
        }
        let mut recurrence = Recurrence {
            lmax,
            alpha,
            norm,
            offset,
            paired: Vec::new(),
        };
        if lmax <= PAIRED_KEPT_LMAX {
            recurrence.paired = (0..=lmax)
                .map(|m| {
                    let mut paired = Paired::default();
                    recurrence.compute_paired(m, &mut paired);
                    paired.gain = Vec::new(); // only needed while computing
                    paired
                })
                .collect();
        }
        recurrence
    }

    pub fn lmax(&self) -> usize {
        self.lmax
    }

    /// Order m's recurrence, (α_lm, N_lm) for l = m..=lmax: with λ_lm = N_lm μ_lm,
    /// μ_lm = (α_lm cos θ) μ_{l−1,m} − μ_{l−2,m} from μ_mm = λ_mm and μ_{m−1,m} = 0
    /// (α unused at l = m). N stays within about [0.1, 1.2], so μ is as safe from
    /// overflow and underflow as λ.
    pub fn rescaled(&self, m: usize) -> (&[f64], &[f64]) {
        let degrees = self.lmax + 1 - m;
        (
            &self.alpha[self.offset[m]..][..degrees],
            &self.norm[self.offset[m]..][..degrees],
        )
    }

    /// Order m's recurrence two degrees a step (see [`Paired`]): kept, or computed into
    /// `scratch`.
    pub fn paired<'a>(&'a self, m: usize, scratch: &'a mut Paired) -> &'a Paired {
        match self.paired.get(m) {
            Some(paired) => paired,
            None => {
                self.compute_paired(m, scratch);
                scratch
            }
        }
    }

    fn compute_paired(&self, m: usize, out: &mut Paired) {
        let (alpha, norm) = self.rescaled(m);
        let degrees = alpha.len();
        let pairs = degrees.div_ceil(2);
        out.clear();
        // With x = cos θ, two steps of μ_l = α_l x μ_{l−1} − μ_{l−2} give, for even offsets i,
        // μ_i = (α_i α_{i−1} x² − 1 − c_i) μ_{i−2} − c_i μ_{i−4}, c_i = α_i / α_{i−2} (c_2 = 0:
        // μ_{m−1} = 0). ν_i = g_i μ_i with g_i = g_{i−4} / c_i (g_0 = g_2 = 1) turns c_i into 1.
        let gain = &mut out.gain;
        gain.resize(pairs, 1.0);
        for j in 0..pairs {
            let i = 2 * j;
            if j > 0 {
                let c = if i >= 4 { alpha[i] / alpha[i - 2] } else { 0.0 };
                gain[j] = if i >= 4 { gain[j - 2] / c } else { 1.0 };
                let ratio = gain[j] / gain[j - 1];
                out.steps.push([ratio * alpha[i] * alpha[i - 1], ratio * (-1.0 - c)]);
            } else {
                out.steps.push([0.0, 0.0]);
            }
            out.even_norm.push(norm[i] / gain[j]);
            // x μ_i = (μ_{i+1} + μ_{i−1}) / α_{i+1}.
            if i + 1 < degrees {
                out.odd_gain.push(alpha[i + 1] / gain[j]);
                out.odd_norm.push(norm[i + 1]);
            }
        }
    }

    /// λ_lm for l = m..=lmax (rows) at many rings (columns), row-major into `out`;
    /// `start` holds λ_mm per ring.
    pub fn rows(&self, m: usize, cos_theta: &[f64], start: &[Scaled], out: &mut [f64]) {
        let mut rows = RowCursor::new(self, m, cos_theta, start);
        for row in out.chunks_exact_mut(cos_theta.len()) {
            rows.next_row(row);
        }
    }

    /// λ_mm(θ) for m = 0..=lmax, carried in scaled form: `out[m]`.
    pub fn sectoral(&self, sin_theta: f64, out: &mut [Scaled]) {
        let mut current = Scaled {
            mantissa: (0.25 / std::f64::consts::PI).sqrt(),
            scale: 0,
        };
        out[0] = current;
        for (m, slot) in out.iter_mut().enumerate().take(self.lmax + 1).skip(1) {
            current.mantissa *= ((2 * m + 1) as f64 / (2 * m) as f64).sqrt() * sin_theta;
            if current.mantissa != 0.0 && current.mantissa.abs() < SMALL {
                current.mantissa *= BIG;
                current.scale -= 1;
            }
            *slot = current;
        }
    }

    /// λ_lm(θ) for l = m..=lmax into `out[(l − m) · stride]`, starting from λ_mm, by the
    /// plain (not rescaled) recurrence: the tests' reference.
    #[cfg(test)]
    pub fn column(&self, m: usize, cos_theta: f64, start: Scaled, out: &mut [f64], stride: usize) {
        let (mut previous, mut current, mut scale) = (0.0, start.mantissa, start.scale);
        out[0] = start.value();
        for i in 1..=self.lmax - m {
            let l = m + i;
            let inverse_previous = if i > 1 { 1.0 / coefficient(l - 1, m) } else { 0.0 };
            let next = coefficient(l, m) * (cos_theta * current - previous * inverse_previous);
            previous = current;
            current = next;
            if scale < 0 && current.abs() > BIG {
                current *= SMALL;
                previous *= SMALL;
                scale += 1;
            }
            out[i * stride] = Scaled {
                mantissa: current,
                scale,
            }
            .value();
        }
    }
}

/// One order's recurrence over its even offsets i = l − m = 0, 2, … (pair j = i / 2), in
/// x² = cos² θ: ν_i = (a_j x² + b_j) ν_{i−2} − ν_{i−4} from ν_0 = λ_mm and ν_{−2} = 0, two
/// operations for two degrees. Then λ_{m+i} = `even_norm[j]` · ν_i, and the odd degrees
/// come from sums against x ν_i: with S_j = Σ f x ν_i over rings, d_{i+1} =
/// `odd_gain[j]` · S_j − d_{i−1} (d_{−1} = 0) gives Σ f λ_{m+i+1} = `odd_norm[j]` · d_{i+1}.
/// So one λ per two degrees meets both halves of a ring pair, the antisymmetric one
/// multiplied by x once per ring (the scheme of libsharp and ducc0).
#[derive(Default)]
pub struct Paired {
    /// (a_j, b_j); unused at j = 0.
    pub steps: Vec<[f64; 2]>,
    pub even_norm: Vec<f64>,
    /// Only for pairs with an odd degree (i + 1 ≤ lmax − m).
    pub odd_gain: Vec<f64>,
    pub odd_norm: Vec<f64>,
    /// g_i: ν_i = g_i μ_i.
    gain: Vec<f64>,
}

impl Paired {
    fn clear(&mut self) {
        self.gain.clear();
        self.steps.clear();
        self.even_norm.clear();
        self.odd_gain.clear();
        self.odd_norm.clear();
    }
}

/// λ_lm of one order at many rings, one degree l = m, m + 1, … per call, for callers
/// that use each row at once (the on-the-fly Legendre step) or store them all
/// ([`Recurrence::rows`]). Runs across rings, so it vectorises.
pub struct RowCursor<'a> {
    alpha: &'a [f64],
    norm: &'a [f64],
    cos_theta: &'a [f64],
    /// Degree index l − m of the next row.
    next: usize,
    previous: Vec<f64>,
    current: Vec<f64>,
    scale: Vec<i32>,
    /// The plain value of a mantissa per ring: 1, 2^−600 or 0, by its scale
    /// (as [`Scaled::value`]), so that rows are written by one multiplication.
    factor: Vec<f64>,
    /// Rings at and beyond this index carry no scaling (scale 0).
    scaled_end: usize,
}

impl<'a> RowCursor<'a> {
    pub fn new(recurrence: &'a Recurrence, m: usize, cos_theta: &'a [f64], start: &[Scaled]) -> Self {
        let (alpha, norm) = recurrence.rescaled(m);
        RowCursor {
            alpha,
            norm,
            cos_theta,
            next: 0,
            previous: vec![0.0; cos_theta.len()],
            current: start.iter().map(|s| s.mantissa).collect(),
            scale: start.iter().map(|s| s.scale).collect(),
            factor: start
                .iter()
                .map(|s| {
                    Scaled {
                        mantissa: 1.0,
                        scale: s.scale,
                    }
                    .value()
                })
                .collect(),
            scaled_end: start.iter().rposition(|s| s.scale < 0).map_or(0, |p| p + 1),
        }
    }

    /// Writes the next degree's λ_lm at every ring into `row`.
    ///
    /// # Panics
    /// Past l = lmax.
    #[inline(always)]
    pub fn next_row(&mut self, row: &mut [f64]) {
        let i = self.next;
        assert!(i < self.alpha.len(), "past lmax");
        if i > 0 {
            let alpha = self.alpha[i];
            for ((p, c), &x) in self
                .previous
                .iter_mut()
                .zip(self.current.iter_mut())
                .zip(self.cos_theta)
            {
                let next = (alpha * x).mul_add(*c, -*p);
                *p = *c;
                *c = next;
            }
            // Scaled values that have grown past 2^600 lose one scale step. A branch-free
            // scan finds whether any has; the rescaling itself is rare.
            let end = self.scaled_end;
            let largest = self.current[..end]
                .iter()
                .fold(0.0f64, |largest, c| if c.abs() > largest { c.abs() } else { largest });
            if largest > BIG {
                self.rescale();
            }
        }
        self.next += 1;
        let (end, norm) = (self.scaled_end, self.norm[i]);
        for ((value, &mantissa), &factor) in row[..end].iter_mut().zip(&self.current).zip(&self.factor) {
            *value = mantissa * factor * norm;
        }
        for (value, &mantissa) in row[end..].iter_mut().zip(&self.current[end..]) {
            *value = mantissa * norm;
        }
    }

    #[cold]
    fn rescale(&mut self) {
        let end = self.scaled_end;
        for p in 0..end {
            if self.scale[p] < 0 && self.current[p].abs() > BIG {
                self.current[p] *= SMALL;
                self.previous[p] *= SMALL;
                self.scale[p] += 1;
                self.factor[p] = Scaled {
                    mantissa: 1.0,
                    scale: self.scale[p],
                }
                .value();
            }
        }
        while self.scaled_end > 0 && self.scale[self.scaled_end - 1] == 0 {
            self.scaled_end -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn values(lmax: usize, m: usize, theta: f64) -> Vec<f64> {
        let recurrence = Recurrence::new(lmax);
        let mut sectoral = vec![Scaled::ZERO; lmax + 1];
        recurrence.sectoral(theta.sin(), &mut sectoral);
        let mut out = vec![0.0; lmax + 1 - m];
        recurrence.column(m, theta.cos(), sectoral[m], &mut out, 1);
        out
    }

    #[test]
    fn low_degrees_match_closed_forms() {
        let theta: f64 = 0.7;
        let (x, s) = (theta.cos(), theta.sin());
        let c = 1.0 / (4.0 * PI);
        let m0 = values(2, 0, theta);
        assert!((m0[0] - c.sqrt()).abs() < 1e-15);
        assert!((m0[1] - (3.0 * c).sqrt() * x).abs() < 1e-15);
        assert!((m0[2] - (5.0 * c).sqrt() * 0.5 * (3.0 * x * x - 1.0)).abs() < 1e-15);
        let m1 = values(2, 1, theta);
        assert!((m1[0] - (3.0 * c / 2.0).sqrt() * s).abs() < 1e-15);
        assert!((m1[1] - (15.0 * c / 2.0).sqrt() * s * x).abs() < 1e-15);
    }

    #[test]
    fn rows_agree_with_columns() {
        let (lmax, m) = (600, 150);
        let recurrence = Recurrence::new(lmax);
        let thetas: Vec<f64> = (1..40).map(|i| i as f64 * 0.04).collect();
        let mut sectoral = vec![Scaled::ZERO; lmax + 1];
        let mut starts = Vec::new();
        for t in &thetas {
            recurrence.sectoral(t.sin(), &mut sectoral);
            starts.push(sectoral[m]);
        }
        let cos: Vec<f64> = thetas.iter().map(|t| t.cos()).collect();
        let mut rows = vec![0.0; (lmax + 1 - m) * thetas.len()];
        recurrence.rows(m, &cos, &starts, &mut rows);
        for (p, t) in thetas.iter().enumerate() {
            let column = values(lmax, m, *t);
            for (i, v) in column.iter().enumerate() {
                // The rows come from the rescaled recurrence, the column from the plain one.
                let row = rows[i * thetas.len() + p];
                assert!(
                    (row - v).abs() <= 1e-13 * (i + 1) as f64 * v.abs().max(1.0),
                    "l={} θ={t}: {row} vs {v}",
                    m + i
                );
            }
        }
    }

    #[test]
    fn paired_recurrence_gives_every_degree() {
        let lmax = 300;
        let recurrence = Recurrence::new(lmax);
        let thetas: Vec<f64> = (1..30).map(|i| i as f64 * 0.05).collect();
        let weights: Vec<f64> = (0..thetas.len()).map(|p| ((p * 37) % 11) as f64 / 5.0 - 1.0).collect();
        let mut paired = Paired::default();
        for m in [0, 1, 2, 7, 150, 298, 299, 300] {
            recurrence.compute_paired(m, &mut paired);
            let degrees = lmax + 1 - m;
            let columns: Vec<Vec<f64>> = thetas.iter().map(|t| values(lmax, m, *t)).collect();
            // Sums over rings of weights × λ (expected) and of weights × x ν (paired).
            let mut odd_sums = vec![0.0; paired.odd_gain.len()];
            for (p, t) in thetas.iter().enumerate() {
                let (x, start) = (t.cos(), columns[p][0]);
                let (mut previous, mut current) = (0.0, start);
                for (j, step) in paired.steps.iter().enumerate() {
                    if j > 0 {
                        (previous, current) = (current, (step[0] * x * x + step[1]) * current - previous);
                    }
                    let expected = columns[p][2 * j];
                    let even = paired.even_norm[j] * current;
                    assert!(
                        (even - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                        "m {m} l {}",
                        m + 2 * j
                    );
                    if let Some(sum) = odd_sums.get_mut(j) {
                        *sum += weights[p] * x * current;
                    }
                }
            }
            let mut odd = 0.0;
            for (j, sum) in odd_sums.iter().enumerate() {
                odd = paired.odd_gain[j] * sum - odd;
                let expected: f64 = (0..thetas.len()).map(|p| weights[p] * columns[p][2 * j + 1]).sum();
                let got = paired.odd_norm[j] * odd;
                assert!(
                    (got - expected).abs() <= 1e-11,
                    "m {m} l {}: {got} vs {expected}",
                    m + 2 * j + 1
                );
            }
            assert_eq!(paired.steps.len(), degrees.div_ceil(2));
            assert_eq!(paired.odd_gain.len(), degrees / 2);
        }
    }

    #[test]
    fn high_degree_values_survive_underflowing_sectorals() {
        // sin^1000(0.5) ≈ 1e−320, yet λ_{4000,1000}(0.5) is O(1): without scaling it is 0.
        let column = values(4095, 1000, 0.5);
        assert!(column.iter().all(|v| v.is_finite()));
        let largest = column.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(largest > 0.1 && largest < 10.0, "{largest}");
    }

    #[test]
    fn normalisation_holds_at_degree_4095() {
        // ∫ λ_lm² sin θ dθ = 1/2π, by Gauss–Legendre quadrature with enough nodes.
        let lmax = 4095;
        let (theta, weights) = crate::sht::grid::gauss_legendre(lmax + 1);
        let recurrence = Recurrence::new(lmax);
        let mut sectoral = vec![Scaled::ZERO; lmax + 1];
        for m in [0, 1, 700, 2048, 4095] {
            let mut norm = vec![0.0; lmax + 1 - m];
            let mut column = vec![0.0; lmax + 1 - m];
            for (t, w) in theta.iter().zip(&weights) {
                recurrence.sectoral(t.sin(), &mut sectoral);
                recurrence.column(m, t.cos(), sectoral[m], &mut column, 1);
                norm.iter_mut().zip(&column).for_each(|(n, v)| *n += w * v * v);
            }
            for (i, n) in norm.iter().enumerate() {
                assert!(
                    (n * 2.0 * PI - 1.0).abs() < 1e-11,
                    "l={} m={m}: {}",
                    m + i,
                    n * 2.0 * PI
                );
            }
        }
    }
}
