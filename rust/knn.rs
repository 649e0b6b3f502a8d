//! k-nearest-neighbour Gaussian interpolation between point sets on the unit sphere
//! (FreNBRDF, Eq. 5–7), on kiddo's immutable k-d tree.
//!
//! Each target takes the weighted mean of its k nearest sources by chordal distance d,
//! with w ∝ exp(−d² / 2σ²). Neighbours and weights depend only on the positions, so an
//! [`KnnInterpolator`] computes them once and applies them to any number of value sets.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::coords::Vec3;
use crate::error::{invalid_argument, Result};
use crate::parallel;

/// How far from 1 a "unit" vector's norm may be.
pub const UNIT_TOLERANCE: f64 = 1e-6;

/// Neighbour indices and normalised weights, row-major `(n_targets, k)`.
#[derive(Clone, Debug)]
pub struct KnnInterpolator {
    n_sources: usize,
    k: usize,
    indices: Vec<u32>,
    weights: Vec<f64>,
}

impl KnnInterpolator {
    /// Finds the `k` nearest `sources` of every target and their Gaussian weights.
    pub fn new(sources: &[Vec3], targets: &[Vec3], k: usize, sigma: f64) -> Result<Self> {
        if sources.is_empty() {
            return invalid_argument!("src is empty: need at least one source point");
        }
        if sources.len() > u32::MAX as usize {
            return invalid_argument!("src has {} points; at most {} are supported", sources.len(), u32::MAX);
        }
        if k == 0 || k > sources.len() {
            return invalid_argument!(
                "k = {k} must be between 1 and the number of sources ({})",
                sources.len()
            );
        }
        if !(sigma.is_finite() && sigma > 0.0) {
            return invalid_argument!("sigma = {sigma} must be a finite positive number");
        }
        check_unit_vectors("src", sources)?;
        check_unit_vectors("dst", targets)?;

        let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice_parallel(sources)
            .map_err(|e| crate::error::Error::InvalidArgument(format!("cannot build the k-d tree: {e:?}")))?;
        let neighbours = NonZero::new(k).expect("k checked above");
        let inverse_two_variance = 1.0 / (2.0 * sigma * sigma);

        let mut indices = vec![0u32; targets.len() * k];
        let mut weights = vec![0f64; targets.len() * k];
        indices
            .par_chunks_mut(k)
            .zip(weights.par_chunks_mut(k))
            .zip(targets.par_iter())
            .with_min_len(256)
            .for_each(|((row_indices, row_weights), target)| {
                let found = tree
                    .query(target)
                    .nearest_n::<SquaredEuclidean<f64>>(neighbours)
                    .execute();
                // Results come sorted by distance. Measuring from the nearest keeps the
                // largest weight at exp(0) = 1, so a σ so small that every exp(−d²/2σ²)
                // would underflow still returns the nearest neighbour, never 0/0.
                let nearest = found[0].distance;
                let mut total = 0.0;
                for (j, neighbour) in found.iter().enumerate() {
                    let excess = neighbour.distance - nearest;
                    let weight = if excess > 0.0 {
                        (-excess * inverse_two_variance).exp()
                    } else {
                        1.0
                    };
                    row_indices[j] = neighbour.item;
                    row_weights[j] = weight;
                    total += weight;
                }
                row_weights.iter_mut().for_each(|w| *w /= total);
            });
        Ok(KnnInterpolator {
            n_sources: sources.len(),
            k,
            indices,
            weights,
        })
    }

    pub fn k(&self) -> usize {
        self.k
    }
    pub fn n_sources(&self) -> usize {
        self.n_sources
    }
    pub fn n_targets(&self) -> usize {
        self.indices.len() / self.k
    }
    /// Source index of each neighbour, `(n_targets, k)`, nearest first.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }
    /// Normalised weight of each neighbour, `(n_targets, k)`; rows sum to 1.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Interpolates `values`, row-major `(n_sources, channels)`, to `(n_targets, channels)`.
    pub fn apply(&self, values: &[f64], channels: usize) -> Result<Vec<f64>> {
        if channels == 0 || values.len() != self.n_sources * channels {
            return invalid_argument!(
                "values has {} entries; expected (n_sources = {}) × (channels = {channels})",
                values.len(),
                self.n_sources
            );
        }
        if let Some(position) = parallel::position_first(values, |v| !v.is_finite()) {
            return invalid_argument!("values row {} is not finite", position / channels);
        }
        let mut out = vec![0f64; self.n_targets() * channels];
        out.par_chunks_mut(channels)
            .zip(self.indices.par_chunks(self.k).zip(self.weights.par_chunks(self.k)))
            .with_min_len(1024)
            .for_each(|(row, (row_indices, row_weights))| {
                for (&index, &weight) in row_indices.iter().zip(row_weights) {
                    let source = &values[index as usize * channels..][..channels];
                    row.iter_mut().zip(source).for_each(|(o, v)| *o += weight * v);
                }
            });
        Ok(out)
    }
}

fn check_unit_vectors(name: &str, points: &[Vec3]) -> Result<()> {
    let bad = parallel::position_first(points, |p| {
        let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        norm.is_nan() || (norm - 1.0).abs() > UNIT_TOLERANCE
    });
    match bad {
        Some(row) => invalid_argument!(
            "{name} row {row} = {:?} is not a unit vector (norm must be within {UNIT_TOLERANCE} of 1)",
            points[row]
        ),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_sigma_returns_the_nearest_value() {
        let sources = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let target = [[0.8f64, 0.6, 0.0]];
        let knn = KnnInterpolator::new(&sources, &target, 3, 1e-300).unwrap();
        let out = knn.apply(&[10.0, 20.0, 30.0], 1).unwrap();
        assert_eq!(out, vec![10.0]);
    }

    #[test]
    fn duplicate_sources_share_the_weight() {
        let sources = [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
        let knn = KnnInterpolator::new(&sources, &[[0.0, 0.0, 1.0]], 2, 0.1).unwrap();
        assert_eq!(knn.weights(), &[0.5, 0.5]);
    }

    #[test]
    fn rejects_bad_arguments() {
        let sources = [[0.0, 0.0, 1.0]];
        assert!(KnnInterpolator::new(&sources, &sources, 0, 0.1).is_err());
        assert!(KnnInterpolator::new(&sources, &sources, 2, 0.1).is_err());
        assert!(KnnInterpolator::new(&sources, &sources, 1, f64::NAN).is_err());
        assert!(KnnInterpolator::new(&sources, &[[0.0, 0.0, 2.0]], 1, 0.1).is_err());
    }
}
