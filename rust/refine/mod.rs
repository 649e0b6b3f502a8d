//! The weight stage of test-time refinement (`frenbrdf.models.reconstruct`): Adam on one
//! NBRDF's weights (ReLU hidden layers, a linear output) against samples of a material,
//! with the forward pass, the backward pass and the update in one native loop.
//!
//! In PyTorch such a step is ~40 small operations on 4000 × 48 arrays, and most of its time
//! goes between them (research/performance.md). Here a step passes over blocks of samples held
//! feature-major (`kernel`), so that every inner loop runs over a block's samples in vector
//! registers and nothing is allocated per operation.
//! The samples are cut into parts of [`PART`] (tied pairs, [`WeightFit::tie`], into parts of
//! half as many) whatever the number of threads and the parts' gradients are summed in order:
//! a fit takes the same steps on any number of threads, and on AVX2 as on AVX-512 (both fuse
//! multiply-adds; a CPU without FMA rounds differently).

mod kernel;
mod lanes;

use rayon::prelude::*;

use crate::error::{invalid_argument, Result};
use crate::parallel::in_pool;
use kernel::{part_gradient, Part, PART};
/// An NBRDF's inputs (Rusinkiewicz coordinates) and outputs (mapped RGB).
pub const N_INPUTS: usize = 6;
pub const N_OUTPUTS: usize = 3;
/// Adam's constants: torch.optim.Adam's defaults.
const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f32 = 1e-8;

/// The reconstruction error, as `frenbrdf.models.losses.reconstruction_loss`: the mean over
/// samples and channels of |e| or e², e = (predicted − true) · cos θ_i.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Loss {
    L1,
    Mse,
}

/// Two NBRDF inputs that the fit should give one value ([`WeightFit::tie`]).
pub type TiedPair = [[f32; N_INPUTS]; 2];

/// One dense layer: `outputs × inputs` weights (row-major) at `offset` of the flat
/// parameters, then `outputs` biases.
#[derive(Clone, Copy, Debug)]
struct Layer {
    inputs: usize,
    outputs: usize,
    offset: usize,
}

impl Layer {
    fn weights(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.inputs * self.outputs
    }
    fn biases(&self) -> std::ops::Range<usize> {
        let start = self.offset + self.inputs * self.outputs;
        start..start + self.outputs
    }
}

/// Adam on one NBRDF's weights against fixed samples.
#[derive(Debug)]
pub struct WeightFit {
    layers: Vec<Layer>,
    /// Every layer's weights then biases, in order (PyTorch's layout).
    params: Vec<f32>,
    /// Each layer's weights transposed (`inputs × outputs`), for the backward pass.
    transposed: Vec<Vec<f32>>,
    /// Adam's weight decay of each parameter (L2, added to the gradient, as torch's).
    decays: Vec<f32>,
    first_moment: Vec<f32>,
    second_moment: Vec<f32>,
    steps: u64,
    coords: Vec<[f32; N_INPUTS]>,
    values: Vec<[f32; N_OUTPUTS]>,
    cos_in: Vec<f32>,
    all_rows: Vec<u32>,
    loss: Loss,
    /// Pairs of inputs the NBRDF should give one value (the two sides of the reciprocity
    /// fold's edge), and the weight of their gap in the loss ([`WeightFit::tie`]).
    ties: Vec<TiedPair>,
    tie_weight: f32,
}

impl WeightFit {
    /// `tensors`: each layer's weights `(outputs × inputs, row-major)` and biases, in
    /// order, with their shapes `(outputs, inputs)`; `decays`: Adam's weight decay per
    /// tensor; samples: `coords` (N × 6), mapped `values` (N × 3) and `cos_in` (N).
    pub fn new(
        tensors: Vec<(Vec<f32>, Vec<usize>)>,
        decays: &[f32],
        coords: &[f32],
        values: &[f32],
        cos_in: &[f32],
        loss: Loss,
    ) -> Result<Self> {
        let layers = layout(&tensors)?;
        if decays.len() != tensors.len() || decays.iter().any(|d| !(d.is_finite() && *d >= 0.0)) {
            return invalid_argument!(
                "expected {} finite non-negative weight decays (one per tensor), got {decays:?}",
                tensors.len()
            );
        }
        let n = cos_in.len();
        if n == 0 || n > u32::MAX as usize || coords.len() != n * N_INPUTS || values.len() != n * N_OUTPUTS {
            return invalid_argument!(
                "expected N ≥ 1 samples: coords N × {N_INPUTS}, values N × {N_OUTPUTS}, cos_in N; got {}, {} and {} values",
                coords.len(),
                values.len(),
                n
            );
        }
        if let Some(name) = [("coords", coords), ("values", values), ("cos_in", cos_in)]
            .iter()
            .find(|(_, a)| a.iter().any(|v| !v.is_finite()))
            .map(|(name, _)| name)
        {
            return invalid_argument!("the samples' {name} hold NaN or inf");
        }
        let mut params = Vec::new();
        let mut element_decays = Vec::new();
        for ((tensor, _), &decay) in tensors.iter().zip(decays) {
            if tensor.iter().any(|v| !v.is_finite()) {
                return invalid_argument!("the NBRDF's weights hold NaN or inf");
            }
            params.extend_from_slice(tensor);
            element_decays.extend(std::iter::repeat_n(decay, tensor.len()));
        }
        let mut fit = WeightFit {
            transposed: layers.iter().map(|l| vec![0.0; l.inputs * l.outputs]).collect(),
            first_moment: vec![0.0; params.len()],
            second_moment: vec![0.0; params.len()],
            layers,
            params,
            decays: element_decays,
            steps: 0,
            coords: coords.chunks_exact(N_INPUTS).map(|c| c.try_into().unwrap()).collect(),
            values: values.chunks_exact(N_OUTPUTS).map(|c| c.try_into().unwrap()).collect(),
            cos_in: cos_in.to_vec(),
            all_rows: (0..n as u32).collect(),
            loss,
            ties: Vec::new(),
            tie_weight: 0.0,
        };
        fit.transpose();
        Ok(fit)
    }

    /// A random NBRDF with the `hidden` widths and `samples` samples of a target it can learn (an affine
    /// function of the coordinates), from a fixed generator seeded by `seed`: for tests and benches.
    pub fn synthetic(hidden: &[usize], samples: usize, loss: Loss, seed: u64) -> Self {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) - 0.5
        };
        let widths: Vec<usize> = [N_INPUTS].iter().chain(hidden).chain(&[N_OUTPUTS]).copied().collect();
        let mut tensors = Vec::new();
        for pair in widths.windows(2) {
            let (inputs, outputs) = (pair[0], pair[1]);
            tensors.push(((0..inputs * outputs).map(|_| next()).collect(), vec![outputs, inputs]));
            tensors.push(((0..outputs).map(|_| 0.1 * next()).collect(), vec![outputs]));
        }
        let coords: Vec<f32> = (0..samples * N_INPUTS).map(|_| 2.0 * next()).collect();
        let values: Vec<f32> = coords
            .chunks_exact(N_INPUTS)
            .flat_map(|c| [0.3 * c[0] + 0.1, -0.2 * c[1], 0.5 * c[2]])
            .collect();
        let cos_in: Vec<f32> = (0..samples).map(|_| next() + 0.5).collect();
        let decays: Vec<f32> = (0..tensors.len())
            .map(|i| if i % 2 == 0 { 1e-3 } else { 0.0 })
            .collect();
        Self::new(tensors, &decays, &coords, &values, &cos_in, loss).expect("a valid synthetic fit")
    }

    /// Ties `pairs` (P × 2 × 6 inputs: each pair's two inputs in turn) with `weight`: every
    /// step's loss adds `weight` times the mean over pairs and channels of |N(a) − N(b)| (or
    /// its square, as the samples' loss), so that the fit gives each pair's inputs one value.
    /// No pairs or a weight of 0: no tie (the default).
    pub fn tie(&mut self, pairs: &[f32], weight: f32) -> Result<()> {
        if !pairs.len().is_multiple_of(2 * N_INPUTS) {
            return invalid_argument!("tied pairs must be P × 2 × {N_INPUTS} values, got {}", pairs.len());
        }
        if pairs.iter().any(|v| !v.is_finite()) {
            return invalid_argument!("the tied pairs hold NaN or inf");
        }
        if !(weight.is_finite() && weight >= 0.0) {
            return invalid_argument!("the tie's weight must be finite and ≥ 0, got {weight}");
        }
        self.ties = pairs
            .chunks_exact(2 * N_INPUTS)
            .map(|pair| {
                [
                    pair[..N_INPUTS].try_into().unwrap(),
                    pair[N_INPUTS..].try_into().unwrap(),
                ]
            })
            .collect();
        self.tie_weight = weight;
        Ok(())
    }

    /// Each tensor's values, in the order given to [`WeightFit::new`].
    pub fn tensors(&self) -> Vec<Vec<f32>> {
        self.layers
            .iter()
            .flat_map(|l| [self.params[l.weights()].to_vec(), self.params[l.biases()].to_vec()])
            .collect()
    }

    /// The loss on all samples (and the tie's term, if any) at the current weights.
    pub fn loss(&self) -> f64 {
        in_pool(|| self.gradient(&self.all_rows).0)
    }

    /// One Adam step per learning rate; each step's batch is `batch` rows of `rows` in turn
    /// (and every tied pair: the tie's term joins each step's loss)
    /// (`None`: every sample each step). Returns each step's loss before its update; stops
    /// after the first that is not finite, without updating.
    pub fn run(&mut self, learning_rates: &[f32], rows: Option<&[u32]>, batch: usize) -> Result<Vec<f64>> {
        if let Some(lr) = learning_rates.iter().find(|lr| !(lr.is_finite() && **lr > 0.0)) {
            return invalid_argument!("learning rates must be positive and finite, got {lr}");
        }
        if let Some(rows) = rows {
            if batch == 0 || rows.len() != batch * learning_rates.len() {
                return invalid_argument!(
                    "expected {} steps × a batch of ≥ 1 rows, got {} rows for batch {batch}",
                    learning_rates.len(),
                    rows.len()
                );
            }
            if let Some(row) = rows.iter().find(|&&r| r as usize >= self.cos_in.len()) {
                return invalid_argument!("row {row} is out of range for {} samples", self.cos_in.len());
            }
        }
        in_pool(|| {
            let mut losses = Vec::with_capacity(learning_rates.len());
            for (step, &lr) in learning_rates.iter().enumerate() {
                let step_rows = rows.map_or(&self.all_rows[..], |r| &r[step * batch..(step + 1) * batch]);
                let (loss, gradient) = self.gradient(step_rows);
                losses.push(loss);
                if !loss.is_finite() {
                    break;
                }
                self.adam(&gradient, lr);
            }
            Ok(losses)
        })
    }

    /// The loss on `rows` (`None`: every sample; with the tie's term, if any) and its gradient,
    /// at the flat `weights` (every layer's weights then biases, as [`WeightFit::new`] lays them out), which
    /// become the fit's weights; Adam's state is untouched. The latent stage of refinement
    /// chains this gradient through the decoder to the latent.
    pub fn gradient_at(&mut self, weights: &[f32], rows: Option<&[u32]>) -> Result<(f64, Vec<f32>)> {
        if weights.len() != self.params.len() {
            return invalid_argument!("expected {} weights, got {}", self.params.len(), weights.len());
        }
        if weights.iter().any(|w| !w.is_finite()) {
            return invalid_argument!("the NBRDF's weights hold NaN or inf");
        }
        if let Some(row) = rows.and_then(|r| r.iter().find(|&&r| r as usize >= self.cos_in.len())) {
            return invalid_argument!("row {row} is out of range for {} samples", self.cos_in.len());
        }
        if rows.is_some_and(|r| r.is_empty()) {
            return invalid_argument!("expected at least one row");
        }
        self.params.copy_from_slice(weights);
        self.transpose();
        Ok(in_pool(|| self.gradient(rows.unwrap_or(&self.all_rows))))
    }

    /// The loss and its gradient on `rows` (and the tied pairs, all of them), summed part by
    /// part in order.
    fn gradient(&self, rows: &[u32]) -> (f64, Vec<f32>) {
        let scale = 1.0 / (N_OUTPUTS * rows.len()) as f32;
        let mut parts: Vec<Part> = rows.chunks(PART).map(Part::Samples).collect();
        let tie_scale = self.tie_weight / (N_OUTPUTS * self.ties.len().max(1)) as f32;
        if self.tie_weight > 0.0 {
            parts.extend(self.ties.chunks(PART / 2).map(Part::Ties));
        }
        let sums: Vec<(f64, Vec<f32>)> = parts
            .par_iter()
            .map(|&part| {
                let part_scale = match part {
                    Part::Samples(_) => scale,
                    Part::Ties(_) => tie_scale,
                };
                let mut gradient = vec![0.0; self.params.len()];
                let loss = part_gradient(self, part, part_scale, &mut gradient);
                (loss, gradient)
            })
            .collect();
        let mut total = vec![0.0; self.params.len()];
        let (mut sample_loss, mut tie_loss) = (0.0, 0.0);
        for (part, (part_loss, gradient)) in parts.iter().zip(sums) {
            match part {
                Part::Samples(_) => sample_loss += part_loss,
                Part::Ties(_) => tie_loss += part_loss,
            }
            total.iter_mut().zip(&gradient).for_each(|(t, g)| *t += g);
        }
        (sample_loss * scale as f64 + tie_loss * tie_scale as f64, total)
    }

    /// One step of torch.optim.Adam (its fused form's arithmetic) at learning rate `lr`.
    fn adam(&mut self, gradient: &[f32], lr: f32) {
        self.steps += 1;
        let steps = self.steps.min(i32::MAX as u64) as i32;
        let step_size = (lr as f64 / (1.0 - BETA1.powi(steps))) as f32;
        let correction2_sqrt = (1.0 - BETA2.powi(steps)).sqrt() as f32;
        let (beta1, beta2) = (BETA1 as f32, BETA2 as f32);
        let moments = self.first_moment.iter_mut().zip(&mut self.second_moment);
        for (((param, &decay), (m, v)), &g) in self.params.iter_mut().zip(&self.decays).zip(moments).zip(gradient) {
            let g = g + decay * *param;
            *m += (1.0 - beta1) * (g - *m);
            *v = beta2 * *v + (1.0 - beta2) * g * g;
            *param -= step_size * *m / (v.sqrt() / correction2_sqrt + EPSILON);
        }
        self.transpose();
    }

    fn transpose(&mut self) {
        for (layer, transposed) in self.layers.iter().zip(&mut self.transposed) {
            let weights = &self.params[layer.weights()];
            for j in 0..layer.outputs {
                for k in 0..layer.inputs {
                    transposed[k * layer.outputs + j] = weights[j * layer.inputs + k];
                }
            }
        }
    }
}

/// The layers of (weight, bias) tensors from 6 inputs to 3 outputs.
fn layout(tensors: &[(Vec<f32>, Vec<usize>)]) -> Result<Vec<Layer>> {
    if tensors.len() < 2 || tensors.len() % 2 == 1 {
        return invalid_argument!(
            "expected (weight, bias) pairs of tensors, got {} tensors",
            tensors.len()
        );
    }
    let (mut layers, mut inputs, mut offset) = (Vec::new(), N_INPUTS, 0);
    for (index, pair) in tensors.chunks_exact(2).enumerate() {
        let [(weights, weight_shape), (biases, bias_shape)] = pair else {
            unreachable!()
        };
        let last = index + 1 == tensors.len() / 2;
        let outputs = *weight_shape.first().unwrap_or(&0);
        let fits = weight_shape.len() == 2
            && weight_shape[1] == inputs
            && outputs >= 1
            && (!last || outputs == N_OUTPUTS)
            && weights.len() == outputs * inputs
            && bias_shape.as_slice() == [outputs]
            && biases.len() == outputs;
        if !fits {
            return invalid_argument!(
                "layer {index}: weights {weight_shape:?} and biases {bias_shape:?} do not chain from {inputs} inputs{}",
                if last {
                    format!(" to {N_OUTPUTS} outputs")
                } else {
                    String::new()
                }
            );
        }
        layers.push(Layer {
            inputs,
            outputs,
            offset,
        });
        offset += outputs * (inputs + 1);
        inputs = outputs;
    }
    Ok(layers)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A 6 → 5 → 4 → 3 NBRDF and `n` samples.
    pub(super) fn example(n: usize, loss: Loss) -> WeightFit {
        WeightFit::synthetic(&[5, 4], n, loss, 12345)
    }

    /// The NBRDF's outputs at one input, in plain arithmetic: for tests.
    fn outputs(fit: &WeightFit, input: &[f32; N_INPUTS]) -> Vec<f32> {
        let mut x = input.to_vec();
        for (l, layer) in fit.layers.iter().enumerate() {
            let weights = &fit.params[layer.weights()];
            x = (0..layer.outputs)
                .map(|j| {
                    let sum: f32 = weights[j * layer.inputs..(j + 1) * layer.inputs]
                        .iter()
                        .zip(&x)
                        .map(|(w, v)| w * v)
                        .sum();
                    let value = sum + fit.params[layer.biases()][j];
                    if l + 1 < fit.layers.len() {
                        value.max(0.0)
                    } else {
                        value
                    }
                })
                .collect();
        }
        x
    }

    /// Each tied pair's gap N(a) − N(b), channel by channel.
    fn gaps(fit: &WeightFit) -> Vec<f32> {
        let gap = |[a, b]: &[[f32; N_INPUTS]; 2]| outputs(fit, a).into_iter().zip(outputs(fit, b)).map(|(a, b)| a - b);
        fit.ties.iter().flat_map(gap).collect()
    }

    /// Each input beside itself with its first input negated (on which the example's target
    /// depends, so the samples pull against a tie of the two), flat as [`WeightFit::tie`] takes them.
    fn mirrored_pairs<'a>(inputs: impl IntoIterator<Item = &'a [f32; N_INPUTS]>) -> Vec<f32> {
        inputs
            .into_iter()
            .flat_map(|input| {
                let mut mirrored = *input;
                mirrored[0] = -mirrored[0];
                input.iter().chain(&mirrored).copied().collect::<Vec<_>>()
            })
            .collect()
    }

    /// [`example`] with 37 tied pairs (a last block of them partial): [`mirrored_pairs`] of its
    /// samples, kept where every channel's gap lies away from 0 (the kink of |·|, where a finite
    /// difference straddles two slopes).
    pub(super) fn tied_example(n: usize, loss: Loss) -> WeightFit {
        let mut fit = example(n, loss);
        let pairs = mirrored_pairs(
            fit.coords
                .iter()
                .filter(|input| {
                    let mut mirrored = **input;
                    mirrored[0] = -mirrored[0];
                    let (a, b) = (outputs(&fit, input), outputs(&fit, &mirrored));
                    a.iter().zip(&b).all(|(a, b)| (a - b).abs() > 0.005)
                })
                .take(37),
        );
        fit.tie(&pairs, 0.7).unwrap();
        assert_eq!(fit.ties.len(), 37);
        fit
    }

    /// The mean |gap| over the tied pairs and channels.
    fn mean_gap(fit: &WeightFit) -> f32 {
        let gaps = gaps(fit);
        gaps.iter().map(|g| g.abs()).sum::<f32>() / gaps.len() as f32
    }

    #[test]
    fn the_tie_adds_its_weight_times_the_mean_gap() {
        for loss in [Loss::L1, Loss::Mse] {
            let mut fit = tied_example(300, loss);
            let (tied, gaps) = (fit.loss(), gaps(&fit));
            fit.tie_weight = 0.0;
            let term = match loss {
                Loss::L1 => gaps.iter().map(|g| g.abs() as f64).sum::<f64>(),
                Loss::Mse => gaps.iter().map(|g| (g * g) as f64).sum::<f64>(),
            } / gaps.len() as f64;
            let expected = fit.loss() + 0.7 * term;
            assert!(
                (tied - expected).abs() < 1e-5 * expected,
                "{loss:?}: {tied} against {expected}"
            );
        }
    }

    #[test]
    fn a_tie_closes_the_gap_between_its_pairs() {
        let (mut tied, mut free) = (tied_example(500, Loss::L1), tied_example(500, Loss::L1));
        free.tie_weight = 0.0;
        tied.run(&[1e-2; 300], None, 0).unwrap();
        free.run(&[1e-2; 300], None, 0).unwrap();
        assert!(
            mean_gap(&tied) < 0.2 * mean_gap(&free),
            "{} against {}",
            mean_gap(&tied),
            mean_gap(&free)
        );
        let error = |r: Result<()>| r.unwrap_err().to_string();
        assert!(error(free.tie(&[0.0; 11], 1.0)).contains("P × 2 × 6"));
        assert!(error(free.tie(&[f32::NAN; 12], 1.0)).contains("NaN"));
        assert!(error(free.tie(&[0.0; 12], -1.0)).contains("≥ 0"));
    }

    #[test]
    fn the_gradient_is_the_loss_slope() {
        for loss in [Loss::Mse, Loss::L1] {
            let mut fit = tied_example(700, loss); // two parts, the second with a partial block
            let (_, gradient) = fit.gradient(&fit.all_rows.clone());
            for (i, &expected) in gradient.iter().enumerate() {
                let h = 1e-3;
                let original = fit.params[i];
                fit.params[i] = original + h;
                fit.transpose();
                let above = fit.loss();
                fit.params[i] = original - h;
                fit.transpose();
                let below = fit.loss();
                fit.params[i] = original;
                fit.transpose();
                let slope = (above - below) / (2.0 * h as f64);
                assert!(
                    (slope - expected as f64).abs() < 2e-3 * (1.0 + slope.abs()),
                    "{loss:?} parameter {i}: gradient {expected} against the slope {slope}"
                );
            }
        }
    }

    #[test]
    fn adam_fits_and_batches_draw_the_given_rows() {
        let mut fit = example(300, Loss::L1);
        let before = fit.loss();
        let losses = fit.run(&[1e-2; 300], None, 0).unwrap();
        assert_eq!(losses.len(), 300);
        assert!(fit.loss() < 0.3 * before, "{} → {}", before, fit.loss());
        // A batch of one row repeated is that row's loss.
        let single = fit.run(&[1e-9], Some(&[7]), 1).unwrap()[0];
        let mut only_seven = example(300, Loss::L1);
        only_seven.params.clone_from(&fit.params);
        only_seven.transpose();
        assert!((single - only_seven.gradient(&[7]).0).abs() < 1e-9);
    }

    #[test]
    fn the_steps_are_the_same_on_any_number_of_threads() {
        let steps = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut fit = example(2000, Loss::L1); // four parts
            fit.tie(&mirrored_pairs(&fit.coords[..600]), 0.5).unwrap(); // three parts of pairs
            let losses = pool.install(|| fit.run(&[1e-2; 20], None, 0).unwrap());
            (losses, fit.tensors())
        };
        assert_eq!(steps(1), steps(3));
    }

    #[test]
    fn gradient_at_given_weights_is_the_fits_gradient_there() {
        let mut fit = example(600, Loss::L1);
        fit.run(&[1e-2; 5], None, 0).unwrap();
        let (weights, rows) = (fit.params.clone(), [3, 5, 599, 5]);
        let expected = fit.gradient(&rows);
        let mut other = example(600, Loss::L1);
        assert_eq!(other.gradient_at(&weights, Some(&rows)).unwrap(), expected);
        assert_eq!(
            other.gradient_at(&weights, None).unwrap(),
            fit.gradient(&fit.all_rows.clone())
        );
        let error = |r: Result<(f64, Vec<f32>)>| r.unwrap_err().to_string();
        assert!(error(other.gradient_at(&weights[1..], None)).contains("weights"));
        assert!(error(other.gradient_at(&weights, Some(&[600]))).contains("out of range"));
        assert!(error(other.gradient_at(&weights, Some(&[]))).contains("at least one row"));
        let mut nan = weights.clone();
        nan[4] = f32::NAN;
        assert!(error(other.gradient_at(&nan, None)).contains("NaN"));
    }

    #[test]
    fn bad_arguments_are_named() {
        let mut fit = example(10, Loss::L1);
        let error = |r: Result<Vec<f64>>| r.unwrap_err().to_string();
        assert!(error(fit.run(&[0.0], None, 0)).contains("positive"));
        assert!(error(fit.run(&[1e-3], Some(&[10]), 1)).contains("out of range"));
        assert!(error(fit.run(&[1e-3; 2], Some(&[1, 2, 3]), 2)).contains("steps"));
        let shapes = |shape: Vec<usize>| {
            let tensors = vec![(vec![0.0; 18], shape), (vec![0.0; 3], vec![3])];
            WeightFit::new(tensors, &[0.0, 0.0], &[0.0; 6], &[0.0; 3], &[1.0], Loss::L1)
        };
        assert!(shapes(vec![3, 6]).is_ok());
        assert!(shapes(vec![6, 3]).unwrap_err().to_string().contains("do not chain"));
        let nan = WeightFit::new(
            vec![(vec![0.0; 18], vec![3, 6]), (vec![0.0; 3], vec![3])],
            &[0.0, 0.0],
            &[f32::NAN; 6],
            &[0.0; 3],
            &[1.0],
            Loss::L1,
        );
        assert!(nan.unwrap_err().to_string().contains("coords hold NaN"));
    }
}
