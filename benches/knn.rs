//! kNN Gaussian interpolation on the unit sphere: N = 1,458,000 sources (one per MERL
//! bin) to M = 1,000,000 targets, k = 8.
//!
//! `knn_build` times `KnnInterpolator::new`: input validation, the parallel k-d tree
//! build, the M k-nearest queries and the weights. `knn_apply` times interpolating three
//! channels with a prebuilt interpolator. Both report throughput in targets.

use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use _native::coords::Vec3;
use _native::knn::KnnInterpolator;

const N_SOURCES: usize = 1_458_000;
const N_TARGETS: usize = 1_000_000;
const K: usize = 8;
const SIGMA: f64 = 0.05;
const CHANNELS: usize = 3;

/// Uniform on the sphere (Archimedes: z uniform in [−1, 1], φ uniform).
fn unit_vectors(rng: &mut StdRng, n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|_| {
            let z: f64 = rng.random_range(-1.0..=1.0);
            let phi: f64 = rng.random_range(0.0..TAU);
            let rho = (1.0 - z * z).max(0.0).sqrt();
            [rho * phi.cos(), rho * phi.sin(), z]
        })
        .collect()
}

fn knn(c: &mut Criterion) {
    let mut rng = StdRng::seed_from_u64(0x6b6e_6e21);
    let sources = unit_vectors(&mut rng, N_SOURCES);
    let targets = unit_vectors(&mut rng, N_TARGETS);
    let values: Vec<f64> = (0..N_SOURCES * CHANNELS).map(|_| rng.random_range(0.0..1.0)).collect();

    {
        let mut group = c.benchmark_group("knn_build");
        group.throughput(Throughput::Elements(N_TARGETS as u64));
        // ~2 s per iteration on two cores: flat sampling, criterion's minimum of 10
        // samples, and enough time for two iterations per sample.
        group.sampling_mode(SamplingMode::Flat);
        group.sample_size(10);
        group.warm_up_time(Duration::from_secs(3));
        group.measurement_time(Duration::from_secs(40));
        group.bench_function("new_k8_1458000src_1Mdst", |b| {
            b.iter(|| KnnInterpolator::new(black_box(&sources), black_box(&targets), K, SIGMA).expect("valid inputs"))
        });
        group.finish();
    }

    let interpolator = KnnInterpolator::new(&sources, &targets, K, SIGMA).expect("valid inputs");
    {
        let mut group = c.benchmark_group("knn_apply");
        group.throughput(Throughput::Elements(N_TARGETS as u64));
        group.sampling_mode(SamplingMode::Flat);
        group.sample_size(20);
        group.measurement_time(Duration::from_secs(12));
        group.bench_function("apply_3ch_1Mdst", |b| {
            b.iter(|| interpolator.apply(black_box(&values), CHANNELS).expect("valid values"))
        });
        group.finish();
    }
}

criterion_group!(benches, knn);
criterion_main!(benches);
