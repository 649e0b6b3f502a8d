//! The fixed matrices a plan builds once: λ_lm at a set of rings, packed for the kernel
//! per order (kept, or recomputed per call where too large), and on equiangular grids the
//! resampling onto Gauss–Legendre rings.

use std::sync::Arc;

use rayon::prelude::*;

use super::legendre::{Paired, Recurrence, Scaled};
use super::linalg::{MatRef, Packed};
use super::real::Real;
use super::streamed;

/// λ_lm at one set of rings, folded to the northern half (equator included).
pub(super) struct LegendreTable<T> {
    lmax: usize,
    half_rings: usize,
    recurrence: Arc<Recurrence>,
    /// cos θ and λ_mm per half ring, zero-padded to whole vectors of [`streamed::LANES`]
    /// rings (`padded` of them) for the on-the-fly kernel to load directly; λ_mm by
    /// order, as mantissas `sectoral.0[m * padded + p]` and scales `sectoral.1[..]`.
    cos_theta: Vec<f64>,
    sectoral: (Vec<f64>, Vec<i32>),
    padded: usize,
    /// Per order, the vectors of rings from the pole whose λ stay negligible to lmax
    /// ([`streamed::silent_vectors`]), which the on-the-fly kernel skips.
    silent: Vec<usize>,
    /// Per m, when within the cache budget.
    pub(super) cached: Option<Vec<OrderPanels<T>>>,
}

/// One order's λ_lm, split by the parity of l − m and packed for the kernel both ways:
/// degrees × half rings (analysis) and half rings × degrees (synthesis), each without
/// the `quiet` rings nearest the pole.
#[derive(Default)]
pub(super) struct OrderPanels<T> {
    pub(super) analysis: [Packed<T>; 2],
    pub(super) synthesis: [Packed<T>; 2],
    /// Per parity, how many half rings from the pole have every λ_lm of that parity
    /// negligible (below [`streamed::QUIET`]): the panels start after them, so the products
    /// skip them (for large m, a third of the rings at 90 × 180).
    pub(super) quiet: [usize; 2],
}

impl<T: Real> LegendreTable<T> {
    pub(super) fn new(recurrence: Arc<Recurrence>, theta: &[f64], cache_bytes: usize) -> Self {
        let lmax = recurrence.lmax();
        let half = &theta[..theta.len().div_ceil(2)];
        let padded = half.len().next_multiple_of(streamed::LANES);
        let mut by_ring = vec![Scaled::ZERO; half.len() * (lmax + 1)];
        by_ring
            .par_chunks_mut(lmax + 1)
            .zip(half)
            .for_each(|(row, t)| recurrence.sectoral(t.sin(), row));
        let (mut mantissas, mut scales) = (vec![0.0; (lmax + 1) * padded], vec![0; (lmax + 1) * padded]);
        for (p, row) in by_ring.chunks_exact(lmax + 1).enumerate() {
            for (m, value) in row.iter().enumerate() {
                mantissas[m * padded + p] = value.mantissa;
                scales[m * padded + p] = value.scale;
            }
        }
        let mut cos_theta: Vec<f64> = half.iter().map(|t| t.cos()).collect();
        cos_theta.resize(padded, 0.0);
        let mut table = LegendreTable {
            lmax,
            half_rings: half.len(),
            recurrence,
            cos_theta,
            sectoral: (mantissas, scales),
            padded,
            silent: Vec::new(),
            cached: None,
        };
        table.silent = (0..=lmax)
            .into_par_iter()
            .map_init(Paired::default, |paired, m| {
                streamed::silent_vectors(&table.recurrence, m, table.rings(m), paired)
            })
            .collect();
        // Two packed copies of every value.
        if 2 * table.bytes() <= cache_bytes {
            let panels = (0..=lmax)
                .into_par_iter()
                .map(|m| {
                    let mut panels = OrderPanels::default();
                    table.compute(m, &mut panels, Orientation::Both);
                    panels
                })
                .collect();
            table.cached = Some(panels);
        }
        table
    }

    pub(super) fn half_rings(&self) -> usize {
        self.half_rings
    }

    /// Size of one packed copy of the table (analysis or synthesis).
    pub(super) fn bytes(&self) -> usize {
        (self.lmax + 1) * (self.lmax + 2) / 2 * self.half_rings() * std::mem::size_of::<T>()
    }

    /// Computes order m's λ and packs the panels `orientation` asks for.
    fn compute(&self, m: usize, panels: &mut OrderPanels<T>, orientation: Orientation) {
        let (degrees, half) = (self.lmax + 1 - m, self.half_rings());
        let rings = self.rings(m);
        let start: Vec<Scaled> = (rings.mantissa.iter().zip(rings.scale))
            .take(half)
            .map(|(&mantissa, &scale)| Scaled { mantissa, scale })
            .collect();
        let mut values = vec![0f64; degrees * half];
        self.recurrence.rows(m, &self.cos_theta[..half], &start, &mut values);
        let quiet = [0, 1].map(|parity| {
            let rows = values[parity * half..].chunks(half).step_by(2);
            (0..half)
                .find(|&p| rows.clone().any(|row| row[p].abs() >= streamed::QUIET))
                .unwrap_or(half)
        });
        let lambda: Vec<T> = values.into_iter().map(T::of).collect();
        for parity in 0..2 {
            let rows = (degrees + 1 - parity) / 2;
            let quiet = quiet[parity];
            panels.quiet[parity] = quiet;
            if orientation != Orientation::Synthesis {
                panels.analysis[parity].pack(MatRef {
                    data: &lambda,
                    offset: parity * half + quiet,
                    rows,
                    cols: half - quiet,
                    row_stride: 2 * half,
                    col_stride: 1,
                });
            }
            if orientation != Orientation::Analysis {
                panels.synthesis[parity].pack(MatRef {
                    data: &lambda,
                    offset: parity * half + quiet,
                    rows: half - quiet,
                    cols: rows,
                    row_stride: 1,
                    col_stride: 2 * half,
                });
            }
        }
    }

    /// Order m's analysis with λ recomputed in registers ([`streamed`]): `spectra` at
    /// this table's rings → `out[(l − m) · width + c]`.
    pub(super) fn streamed_order(
        &self,
        m: usize,
        spectra: streamed::Spectra<'_>,
        out: &mut [T],
        scratch: &mut streamed::Scratch,
    ) {
        streamed::analysis_order(
            streamed::Job {
                recurrence: &self.recurrence,
                m,
                rings: streamed::Rings {
                    silent: self.silent[m],
                    ..self.rings(m)
                },
                spectra,
            },
            out,
            scratch,
        );
    }

    /// The half rings' cos θ and order m's λ_mm there, padded to whole vectors (none
    /// counted silent).
    fn rings(&self, m: usize) -> streamed::Rings<'_> {
        streamed::Rings {
            cos_theta: &self.cos_theta,
            mantissa: &self.sectoral.0[m * self.padded..][..self.padded],
            scale: &self.sectoral.1[m * self.padded..][..self.padded],
            silent: 0,
        }
    }

    /// Order m's panels: from the cache, or computed into `scratch` (only the
    /// `orientation` asked for).
    pub(super) fn panels<'a>(
        &'a self,
        m: usize,
        scratch: &'a mut OrderPanels<T>,
        orientation: Orientation,
    ) -> &'a OrderPanels<T> {
        match &self.cached {
            Some(panels) => &panels[m],
            None => {
                self.compute(m, scratch, orientation);
                scratch
            }
        }
    }
}

/// Which packed copies of λ a caller needs.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Orientation {
    Analysis,
    Synthesis,
    Both,
}

/// The equiangular → Gauss–Legendre resampling, `[m parity][symmetric, antisymmetric]`,
/// packed for both directions.
pub(super) struct Resampling<T> {
    pub(super) forward: [[Packed<T>; 2]; 2],
    pub(super) adjoint: [[Packed<T>; 2]; 2],
}

/// Restricts the full resampling matrices (Gauss rings × equiangular rings) to folded
/// symmetric/antisymmetric parts on half rings, with the Gauss weights folded in.
///
/// A folded symmetric part holds g_j + g_j' on paired rings and g_j on an equator ring
/// (antisymmetric: g_j − g_j', and 0 on the equator); the rows are built so that the
/// output holds the same quantities at the Gauss rings, times their weights.
pub(super) fn fold_resampling<T: Real>(full: &[Vec<f64>; 2], n_source: usize, gauss_weights: &[f64]) -> Resampling<T> {
    let n_target = gauss_weights.len();
    let (source_half, target_half) = (n_source.div_ceil(2), n_target.div_ceil(2));
    let folded: [[Vec<T>; 2]; 2] = full.each_ref().map(|matrix| {
        [1.0, -1.0].map(|sign: f64| {
            let mut folded = vec![T::zero(); target_half * source_half];
            for k in 0..target_half {
                let target_is_equator = n_target - 1 - k == k;
                let rows_per_part = match (target_is_equator, sign > 0.0) {
                    (true, true) => 1.0,
                    (true, false) => 0.0,
                    (false, _) => 2.0,
                };
                for j in 0..source_half {
                    let mirror = n_source - 1 - j;
                    let entry = &matrix[k * n_source..];
                    let value = if mirror == j {
                        if sign > 0.0 {
                            entry[j]
                        } else {
                            0.0
                        }
                    } else {
                        0.5 * (entry[j] + sign * entry[mirror])
                    };
                    folded[k * source_half + j] = T::of(rows_per_part * gauss_weights[k] * value);
                }
            }
            folded
        })
    });
    let pack = |transpose: bool| {
        folded.each_ref().map(|parts| {
            parts.each_ref().map(|matrix| {
                let (rows, cols, row_stride, col_stride) = if transpose {
                    (source_half, target_half, 1, source_half)
                } else {
                    (target_half, source_half, source_half, 1)
                };
                Packed::new(MatRef {
                    data: matrix,
                    offset: 0,
                    rows,
                    cols,
                    row_stride,
                    col_stride,
                })
            })
        })
    };
    Resampling {
        forward: pack(false),
        adjoint: pack(true),
    }
}
