//! The weight stage of `full` refinement (`_native::refine`): 100 Adam steps on one NBRDF
//! (6 → w → w → 3, the widths `full` refines) against 4000 samples, the budget's sample
//! count. The PyTorch loop it replaces is timed beside it by
//! `benches/studies/refine_timing.py --weights-only` (docs/performance.md).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

use _native::refine::{Loss, WeightFit};

const SAMPLES: usize = 4000;
const STEPS: usize = 100;

/// An NBRDF of hidden width `width` and samples, from a fixed generator.
fn example(width: usize) -> WeightFit {
    let mut state = 7u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32 / (1u64 << 24) as f32) - 0.5
    };
    let mut tensors = Vec::new();
    for (inputs, outputs) in [(6, width), (width, width), (width, 3)] {
        tensors.push(((0..inputs * outputs).map(|_| next()).collect(), vec![outputs, inputs]));
        tensors.push(((0..outputs).map(|_| 0.1 * next()).collect(), vec![outputs]));
    }
    let coords: Vec<f32> = (0..SAMPLES * 6).map(|_| next()).collect();
    let values: Vec<f32> = (0..SAMPLES * 3).map(|_| next()).collect();
    let cos_in: Vec<f32> = (0..SAMPLES).map(|_| next() + 0.5).collect();
    WeightFit::new(tensors, &[1e-5; 6], &coords, &values, &cos_in, Loss::L1).expect("a valid example")
}

fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("refine_weights");
    group.throughput(Throughput::Elements(STEPS as u64));
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(5));
    for width in [32, 48, 64] {
        let mut fit = example(width);
        group.bench_function(BenchmarkId::new("adam_steps_4000_samples", width), |b| {
            b.iter(|| fit.run(black_box(&[1e-4; STEPS]), None, 0).expect("valid steps"))
        });
    }
    group.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
