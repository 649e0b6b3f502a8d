//! One part's loss and gradient: the forward and backward passes over its blocks of
//! samples, held feature-major (one [`Block`] per unit), in vectors of [`LANES`]. Each
//! parameter's gradient gathers [`LANES`] partial sums over the part's blocks, added up once
//! at its end. Every sum runs sample by sample in order, so that the block's size (four
//! vectors, eight where AVX-512's 32 registers hold a pair of units' sums) changes no result.

use super::lanes::{halving_sum, Lanes, LANES};
use super::{Loss, WeightFit, N_INPUTS, N_OUTPUTS};

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

/// The summed loss of a part's `rows`, its gradient (times `scale`) added to `gradient`;
/// compiled for the widest vector unit the CPU has.
pub fn part_gradient(fit: &WeightFit, rows: &[u32], scale: f32, gradient: &mut [f32]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports the features the function is compiled for.
            return unsafe { part_gradient_avx512(fit, rows, scale, gradient) };
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            return unsafe { part_gradient_avx2(fit, rows, scale, gradient) };
        }
    }
    part_gradient_inline::<[f32; LANES], NARROW>(fit, rows, scale, gradient)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn part_gradient_avx512(fit: &WeightFit, rows: &[u32], scale: f32, gradient: &mut [f32]) -> f64 {
    part_gradient_inline::<super::lanes::Avx512, WIDE>(fit, rows, scale, gradient)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn part_gradient_avx2(fit: &WeightFit, rows: &[u32], scale: f32, gradient: &mut [f32]) -> f64 {
    part_gradient_inline::<super::lanes::Avx2, NARROW>(fit, rows, scale, gradient)
}

#[inline(always)]
fn part_gradient_inline<V: Lanes, const N: usize>(
    fit: &WeightFit,
    rows: &[u32],
    scale: f32,
    gradient: &mut [f32],
) -> f64 {
    let layers = &fit.layers;
    let zero: Block<N> = [[0.0; LANES]; N];
    // activations[0]: the inputs; activations[l + 1]: layer l's outputs.
    let mut activations: Vec<Vec<Block<N>>> = std::iter::once(N_INPUTS)
        .chain(layers.iter().map(|l| l.outputs))
        .map(|width| vec![zero; width])
        .collect();
    let widest = layers.iter().map(|l| l.outputs.max(l.inputs)).max().unwrap_or(0);
    let (mut upstream, mut downstream) = (vec![zero; widest], vec![zero; widest]);
    let mut targets = [zero; N_OUTPUTS];
    let mut partials: Vec<Partial> = vec![[0.0; LANES]; fit.params.len()];
    let mut loss: Partial = [0.0; LANES];

    for block in rows.chunks(N * LANES) {
        // Gather the block feature-major; missing samples of a last block are 0 and weigh 0.
        if block.len() < N * LANES {
            activations[0]
                .iter_mut()
                .chain(&mut targets)
                .for_each(|values| *values = zero);
        }
        let mut cos_in = zero;
        for (sample, &row) in block.iter().enumerate() {
            let (row, (vector, lane)) = (row as usize, (sample / LANES, sample % LANES));
            for (k, &value) in fit.coords[row].iter().enumerate() {
                activations[0][k][vector][lane] = value;
            }
            for (j, &value) in fit.values[row].iter().enumerate() {
                targets[j][vector][lane] = value;
            }
            cos_in[vector][lane] = fit.cos_in[row];
        }

        for (l, layer) in layers.iter().enumerate() {
            let (inputs, outputs) = activations.split_at_mut(l + 1);
            let (inputs, outputs) = (&inputs[l], &mut outputs[0]);
            let weights = &fit.params[layer.weights()];
            let biases = &fit.params[layer.biases()];
            let hidden = l + 1 < layers.len();
            dense::<V, N>(weights, Some(biases), inputs, outputs);
            if hidden {
                for out in outputs.iter_mut() {
                    relu::<V, N>(out);
                }
            }
        }

        // The loss and its gradient at the outputs, sample by sample.
        for vector in 0..N {
            for (j, predicted) in activations[layers.len()].iter().enumerate() {
                for lane in 0..LANES {
                    let cos = cos_in[vector][lane];
                    let error = (predicted[vector][lane] - targets[j][vector][lane]) * cos;
                    let slope = match fit.loss {
                        Loss::L1 => {
                            loss[lane] += error.abs();
                            // sgn(e) · cos: torch's abs backward, 0 at 0.
                            if error > 0.0 {
                                cos
                            } else if error < 0.0 {
                                -cos
                            } else {
                                0.0
                            }
                        }
                        Loss::Mse => {
                            loss[lane] += error * error;
                            2.0 * error * cos
                        }
                    };
                    upstream[j][vector][lane] = slope * scale;
                }
            }
        }

        // Back through the layers: `upstream` holds the gradient at layer l's outputs.
        for (l, layer) in layers.iter().enumerate().rev() {
            let inputs = &activations[l];
            let (weights, biases) = (layer.weights(), layer.biases());
            for (j, up) in upstream[..layer.outputs].iter().enumerate() {
                add_sum::<V, N>(&mut partials[biases.start + j], up);
            }
            // Each output unit's row of weight gradients, two units at a time where the registers allow.
            let mut weight_rows = partials[weights].chunks_exact_mut(layer.inputs).zip(&upstream);
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
            let transposed = &fit.transposed[l];
            dense::<V, N>(
                transposed,
                None,
                &upstream[..layer.outputs],
                &mut downstream[..layer.inputs],
            );
            for (down, input) in downstream.iter_mut().zip(inputs) {
                gate::<V, N>(down, input); // back through the ReLU: nothing flows where it gave 0
            }
            std::mem::swap(&mut upstream, &mut downstream);
        }
    }
    for (g, partial) in gradient.iter_mut().zip(&partials) {
        *g += V::load(partial).halving_sum();
    }
    halving_sum(loss) as f64
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
    use super::super::tests::example;
    use super::*;

    #[test]
    fn every_vector_unit_takes_the_same_steps() {
        let fit = example(300, Loss::L1);
        let rows: Vec<u32> = (0..300).collect();
        let gradient_of = |kernel: &dyn Fn(&mut [f32]) -> f64| {
            let mut gradient = vec![0.0; fit.params.len()];
            let loss = kernel(&mut gradient);
            (loss, gradient)
        };
        let portable = gradient_of(&|g| part_gradient_inline::<[f32; LANES], NARROW>(&fit, &rows, 0.5, g));
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                // SAFETY: the CPU supports the features the function is compiled for.
                let avx2 = gradient_of(&|g| unsafe { part_gradient_avx2(&fit, &rows, 0.5, g) });
                assert_eq!(avx2, portable);
            }
            if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma") {
                // SAFETY: as above.
                let avx512 = gradient_of(&|g| unsafe { part_gradient_avx512(&fit, &rows, 0.5, g) });
                assert_eq!(avx512, portable);
            }
        }
    }
}
