//! One part's loss and gradient: the forward and backward passes over its blocks of
//! samples (or of tied pairs), held feature-major (one [`Block`] per unit), in vectors of
//! [`LANES`]. Each parameter's gradient gathers [`LANES`] partial sums over the part's blocks,
//! added up once at its end. Every sum runs sample by sample (pair by pair, each pair's two
//! sides in turn) in order, so that the block's size (four vectors, eight where AVX-512's 32
//! registers hold a pair of units' sums) changes no result.

use super::lanes::{halving_sum, Lanes, LANES};
use super::{Loss, TiedPair, WeightFit, N_INPUTS, N_OUTPUTS};

/// Vectors per block: AVX-512's (fewer passes over the partial sums, which live in the
/// second-level cache), and the others'.
const WIDE: usize = 8;
const NARROW: usize = 4;
/// Samples per parallel task: a multiple of every block. (1,024 took 0.99 the time of 512 on
/// two threads, research/performance.md: 512 keeps eight tasks in a batch of 4,096.)
pub const PART: usize = 4 * WIDE * LANES;

/// One unit's values (or gradients) over a block's N vectors of samples.
type Block<const N: usize> = [[f32; LANES]; N];
/// One parameter's partial gradient sums.
type Partial = [f32; LANES];

/// What a part passes over: rows of the fit's samples, or some of its tied pairs.
#[derive(Clone, Copy)]
pub enum Part<'a> {
    Samples(&'a [u32]),
    Ties(&'a [TiedPair]),
}

/// The summed loss of a part, its gradient (times `scale`) added to `gradient`; compiled for
/// the widest vector unit the CPU has. A sample's loss is |e| or e², e = (predicted − true) ·
/// cos θ_i; a tied pair's is |e| or e², e = N(a) − N(b), the gap between the pair's outputs.
pub fn part_gradient(fit: &WeightFit, part: Part, scale: f32, gradient: &mut [f32]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { part_gradient_avx512(fit, part, scale, gradient) };
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { part_gradient_avx2(fit, part, scale, gradient) };
        }
    }
    part_gradient_inline::<[f32; LANES], NARROW>(fit, part, scale, gradient)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn part_gradient_avx512(fit: &WeightFit, part: Part, scale: f32, gradient: &mut [f32]) -> f64 {
    part_gradient_inline::<super::lanes::Avx512, WIDE>(fit, part, scale, gradient)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn part_gradient_avx2(fit: &WeightFit, part: Part, scale: f32, gradient: &mut [f32]) -> f64 {
    part_gradient_inline::<super::lanes::Avx2, NARROW>(fit, part, scale, gradient)
}

/// One part's passes: the activations of a block, the gradients flowing back, and each
/// parameter's partial sums.
struct Pass<const N: usize> {
    /// activations[0]: the inputs; activations[l + 1]: layer l's outputs.
    activations: Vec<Vec<Block<N>>>,
    upstream: Vec<Block<N>>,
    downstream: Vec<Block<N>>,
    partials: Vec<Partial>,
}

#[inline(always)]
fn part_gradient_inline<V: Lanes, const N: usize>(
    fit: &WeightFit,
    part: Part,
    scale: f32,
    gradient: &mut [f32],
) -> f64 {
    let zero: Block<N> = [[0.0; LANES]; N];
    let widest = fit.layers.iter().map(|l| l.outputs.max(l.inputs)).max().unwrap_or(0);
    let mut pass = Pass::<N> {
        activations: std::iter::once(N_INPUTS)
            .chain(fit.layers.iter().map(|l| l.outputs))
            .map(|width| vec![zero; width])
            .collect(),
        upstream: vec![zero; widest],
        downstream: vec![zero; widest],
        partials: vec![[0.0; LANES]; fit.params.len()],
    };
    let mut loss: Partial = [0.0; LANES];
    match part {
        Part::Samples(rows) => {
            let mut targets = [zero; N_OUTPUTS];
            for block in rows.chunks(N * LANES) {
                let cos_in = gather_samples(fit, block, &mut pass.activations[0], &mut targets);
                forward::<V, N>(fit, &mut pass);
                sample_slopes(fit, &mut pass, &targets, &cos_in, scale, &mut loss);
                backward::<V, N>(fit, &mut pass);
            }
        }
        Part::Ties(pairs) => {
            for block in pairs.chunks(N * LANES / 2) {
                gather_ties(block, &mut pass.activations[0]);
                forward::<V, N>(fit, &mut pass);
                tie_slopes(fit, &mut pass, scale, &mut loss);
                backward::<V, N>(fit, &mut pass);
            }
        }
    }
    for (g, partial) in gradient.iter_mut().zip(&pass.partials) {
        *g += V::load(partial).halving_sum();
    }
    halving_sum(loss) as f64
}

/// A block of samples gathered feature-major into `inputs` and `targets`; returns their cos θ_i.
/// Missing samples of a last block are 0 and weigh 0.
#[inline(always)]
fn gather_samples<const N: usize>(
    fit: &WeightFit,
    block: &[u32],
    inputs: &mut [Block<N>],
    targets: &mut [Block<N>; N_OUTPUTS],
) -> Block<N> {
    let zero: Block<N> = [[0.0; LANES]; N];
    if block.len() < N * LANES {
        inputs
            .iter_mut()
            .chain(targets.iter_mut())
            .for_each(|values| *values = zero);
    }
    let mut cos_in = zero;
    for (sample, &row) in block.iter().enumerate() {
        let (row, (vector, lane)) = (row as usize, (sample / LANES, sample % LANES));
        for (k, &value) in fit.coords[row].iter().enumerate() {
            inputs[k][vector][lane] = value;
        }
        for (j, &value) in fit.values[row].iter().enumerate() {
            targets[j][vector][lane] = value;
        }
        cos_in[vector][lane] = fit.cos_in[row];
    }
    cos_in
}

/// A block of tied pairs gathered feature-major: each pair's first input in an even vector,
/// its second in the same lane of the next (so that every sum runs in one order whatever the
/// block's size). Missing pairs of a last block are 0 on both sides: their gap is 0, and
/// nothing flows from them.
#[inline(always)]
fn gather_ties<const N: usize>(block: &[TiedPair], inputs: &mut [Block<N>]) {
    if block.len() < N * LANES / 2 {
        inputs.iter_mut().for_each(|values| *values = [[0.0; LANES]; N]);
    }
    for (pair, sides) in block.iter().enumerate() {
        let (vector, lane) = (pair / LANES, pair % LANES);
        for (side, input) in sides.iter().enumerate() {
            for (k, &value) in input.iter().enumerate() {
                inputs[k][2 * vector + side][lane] = value;
            }
        }
    }
}

/// The forward pass of the block in `pass.activations[0]` through every layer.
#[inline(always)]
fn forward<V: Lanes, const N: usize>(fit: &WeightFit, pass: &mut Pass<N>) {
    for (l, layer) in fit.layers.iter().enumerate() {
        let (inputs, outputs) = pass.activations.split_at_mut(l + 1);
        let (inputs, outputs) = (&inputs[l], &mut outputs[0]);
        dense::<V, N>(
            &fit.params[layer.weights()],
            Some(&fit.params[layer.biases()]),
            inputs,
            outputs,
        );
        if l + 1 < fit.layers.len() {
            for out in outputs.iter_mut() {
                relu::<V, N>(out);
            }
        }
    }
}

/// The loss's slope at a sample's error e: sgn(e) (torch's abs backward, 0 at 0) or 2e; adds
/// the loss to `loss`.
#[inline(always)]
fn slope(kind: Loss, error: f32, loss: &mut f32) -> f32 {
    match kind {
        Loss::L1 => {
            *loss += error.abs();
            if error > 0.0 {
                1.0
            } else if error < 0.0 {
                -1.0
            } else {
                0.0
            }
        }
        Loss::Mse => {
            *loss += error * error;
            2.0 * error
        }
    }
}

/// The samples' loss and its gradient at the outputs (into `pass.upstream`), sample by sample.
#[inline(always)]
fn sample_slopes<const N: usize>(
    fit: &WeightFit,
    pass: &mut Pass<N>,
    targets: &[Block<N>; N_OUTPUTS],
    cos_in: &Block<N>,
    scale: f32,
    loss: &mut Partial,
) {
    let predictions = &pass.activations[fit.layers.len()];
    for vector in 0..N {
        for (j, predicted) in predictions.iter().enumerate() {
            for lane in 0..LANES {
                let cos = cos_in[vector][lane];
                let error = (predicted[vector][lane] - targets[j][vector][lane]) * cos;
                pass.upstream[j][vector][lane] = slope(fit.loss, error, &mut loss[lane]) * cos * scale;
            }
        }
    }
}

/// The tied pairs' loss and its gradient at the outputs: +slope on a pair's first side (an
/// even vector), −slope on its second (the next).
#[inline(always)]
fn tie_slopes<const N: usize>(fit: &WeightFit, pass: &mut Pass<N>, scale: f32, loss: &mut Partial) {
    let predictions = &pass.activations[fit.layers.len()];
    for vector in (0..N).step_by(2) {
        for (j, predicted) in predictions.iter().enumerate() {
            for lane in 0..LANES {
                let gap = predicted[vector][lane] - predicted[vector + 1][lane];
                let up = slope(fit.loss, gap, &mut loss[lane]) * scale;
                pass.upstream[j][vector][lane] = up;
                pass.upstream[j][vector + 1][lane] = -up;
            }
        }
    }
}

/// Back through the layers from the gradient at the outputs in `pass.upstream`, adding each
/// parameter's products to its partial sums.
#[inline(always)]
fn backward<V: Lanes, const N: usize>(fit: &WeightFit, pass: &mut Pass<N>) {
    for (l, layer) in fit.layers.iter().enumerate().rev() {
        let inputs = &pass.activations[l];
        let (weights, biases) = (layer.weights(), layer.biases());
        for (j, up) in pass.upstream[..layer.outputs].iter().enumerate() {
            add_sum::<V, N>(&mut pass.partials[biases.start + j], up);
        }
        // Each output unit's row of weight gradients, two units at a time where the registers allow.
        let mut weight_rows = pass.partials[weights]
            .chunks_exact_mut(layer.inputs)
            .zip(&pass.upstream);
        let pairs = if V::PAIRS { layer.outputs / 2 } else { 0 };
        for _ in 0..pairs {
            let ((first, up0), (second, up1)) = (weight_rows.next().unwrap(), weight_rows.next().unwrap());
            add_products::<V, N, 2>([first, second], [up0, up1], inputs);
        }
        for (row, up) in weight_rows {
            add_products::<V, N, 1>([row], [up], inputs);
        }
        if l == 0 {
            break;
        }
        dense::<V, N>(
            &fit.transposed[l],
            None,
            &pass.upstream[..layer.outputs],
            &mut pass.downstream[..layer.inputs],
        );
        for (down, input) in pass.downstream.iter_mut().zip(inputs) {
            gate::<V, N>(down, input); // back through the ReLU: nothing flows where it gave 0
        }
        std::mem::swap(&mut pass.upstream, &mut pass.downstream);
    }
}

/// outputs[j] = biases[j] + Σ_k weights[j, k] · inputs[k] (row-major `weights`; no biases: 0),
/// two outputs at a time where the vector unit has the registers for it (eight independent
/// sums keep both of an AVX-512 core's FMA units busy).
#[inline(always)]
fn dense<V: Lanes, const N: usize>(
    weights: &[f32],
    biases: Option<&[f32]>,
    inputs: &[Block<N>],
    outputs: &mut [Block<N>],
) {
    let width = inputs.len();
    let start = |j: usize| biases.map_or(0.0, |b| b[j]);
    let pairs = if V::PAIRS { outputs.len() / 2 } else { 0 };
    let mut rows = weights.chunks_exact(width).zip(outputs.iter_mut()).enumerate();
    for _ in 0..pairs {
        let ((j, (w0, out0)), (_, (w1, out1))) = (rows.next().unwrap(), rows.next().unwrap());
        weighted_sums::<V, N, 2>([start(j), start(j + 1)], [w0, w1], inputs, [out0, out1]);
    }
    for (j, (w, out)) in rows {
        weighted_sums::<V, N, 1>([start(j)], [w], inputs, [out]);
    }
}

/// For each of the R rows of `weights`: outputs[r] = starts[r] + Σ w·x over the blocks the row
/// weighs. (Plain loops, no closures: a closure is compiled apart from the vector unit's
/// function and would call the intrinsics instead of inlining them.)
#[inline(always)]
fn weighted_sums<V: Lanes, const N: usize, const R: usize>(
    starts: [f32; R],
    weights: [&[f32]; R],
    blocks: &[Block<N>],
    outputs: [&mut Block<N>; R],
) {
    assert!(weights.iter().all(|w| w.len() == blocks.len()));
    let mut sums = [[V::splat(0.0); N]; R];
    for r in 0..R {
        sums[r] = [V::splat(starts[r]); N];
    }
    for (k, block) in blocks.iter().enumerate() {
        let values = load::<V, N>(block);
        for r in 0..R {
            let w = V::splat(weights[r][k]);
            for v in 0..N {
                sums[r][v] = w.mul_add(values[v], sums[r][v]);
            }
        }
    }
    for (sum, out) in sums.iter().zip(outputs) {
        for v in 0..N {
            sum[v].store(&mut out[v]);
        }
    }
}

#[inline(always)]
fn load<V: Lanes, const N: usize>(block: &Block<N>) -> [V; N] {
    let mut values = [V::splat(0.0); N];
    for v in 0..N {
        values[v] = V::load(&block[v]);
    }
    values
}

/// max(x, 0) of a block's values.
#[inline(always)]
fn relu<V: Lanes, const N: usize>(block: &mut Block<N>) {
    for values in block {
        let x = V::load(values);
        x.where_positive(x).store(values);
    }
}

/// Zeroes the values of `block` where `gate` is not positive (a ReLU's backward pass).
#[inline(always)]
fn gate<V: Lanes, const N: usize>(block: &mut Block<N>, gate: &Block<N>) {
    for (values, gate) in block.iter_mut().zip(gate) {
        V::load(values).where_positive(V::load(gate)).store(values);
    }
}

/// For each of R units: partials[r][k] += the products of its gradient `ups[r]` and the
/// block `inputs[k]`, vector by vector (the gradient of the weights from input k to it).
#[inline(always)]
fn add_products<V: Lanes, const N: usize, const R: usize>(
    partials: [&mut [Partial]; R],
    ups: [&Block<N>; R],
    inputs: &[Block<N>],
) {
    assert!(partials.iter().all(|row| row.len() == inputs.len()));
    let mut up = [[V::splat(0.0); N]; R];
    for r in 0..R {
        up[r] = load::<V, N>(ups[r]);
    }
    for (k, input) in inputs.iter().enumerate() {
        let values = load::<V, N>(input);
        for r in 0..R {
            let mut sum = V::load(&partials[r][k]);
            for v in 0..N {
                sum = up[r][v].mul_add(values[v], sum);
            }
            sum.store(&mut partials[r][k]);
        }
    }
}

/// partial += a block's values, vector by vector.
#[inline(always)]
fn add_sum<V: Lanes, const N: usize>(partial: &mut Partial, a: &Block<N>) {
    let mut sum = V::load(partial);
    for values in a {
        sum = sum.add(V::load(values));
    }
    sum.store(partial);
}

#[cfg(test)]
mod tests {
    use super::super::tests::tied_example;
    use super::*;

    #[test]
    fn every_vector_unit_takes_the_same_steps() {
        let fit = tied_example(300, Loss::L1);
        let rows: Vec<u32> = (0..300).collect();
        for part in [Part::Samples(&rows), Part::Ties(&fit.ties)] {
            let gradient_of = |kernel: &dyn Fn(&mut [f32]) -> f64| {
                let mut gradient = vec![0.0; fit.params.len()];
                let loss = kernel(&mut gradient);
                (loss, gradient)
            };
            let portable = gradient_of(&|g| part_gradient_inline::<[f32; LANES], NARROW>(&fit, part, 0.5, g));
            #[cfg(target_arch = "x86_64")]
            {
                if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                    // SAFETY: the CPU supports the features the function is compiled for.
                    let avx2 = gradient_of(&|g| unsafe { part_gradient_avx2(&fit, part, 0.5, g) });
                    assert_eq!(avx2, portable);
                }
                if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
                    // SAFETY: as above.
                    let avx512 = gradient_of(&|g| unsafe { part_gradient_avx512(&fit, part, 0.5, g) });
                    assert_eq!(avx512, portable);
                }
            }
        }
    }
}
