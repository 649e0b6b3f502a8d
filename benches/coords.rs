//! Batched Rusinkiewicz conversions on 1,000,000 random direction pairs in the upper
//! hemisphere (validation included, as callers pay for it).

use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode, Throughput};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use _native::coords::{batch_from_rusinkiewicz, batch_to_rusinkiewicz, Vec3};

const N_PAIRS: usize = 1_000_000;

/// A uniformly distributed direction in the upper hemisphere (z uniform in [0, 1]).
fn upper_hemisphere(rng: &mut StdRng) -> Vec3 {
    let z: f64 = rng.random_range(0.0..=1.0);
    let phi: f64 = rng.random_range(0.0..TAU);
    let rho = (1.0 - z * z).max(0.0).sqrt();
    [rho * phi.cos(), rho * phi.sin(), z]
}

fn inputs() -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = StdRng::seed_from_u64(0x5275_7369);
    (0..N_PAIRS)
        .map(|_| (upper_hemisphere(&mut rng), upper_hemisphere(&mut rng)))
        .unzip()
}

/// One kernel call takes a good fraction of a second on two cores (research/performance.md),
/// so flat sampling with a few iterations per sample; criterion's default of 100 linear
/// samples would take minutes.
fn configure(group: &mut BenchmarkGroup<'_, WallTime>) {
    group.throughput(Throughput::Elements(N_PAIRS as u64));
    group.sampling_mode(SamplingMode::Flat);
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(10));
}

fn to_rusinkiewicz(c: &mut Criterion) {
    let (wi, wo) = inputs();
    let mut group = c.benchmark_group("batch_to_rusinkiewicz");
    configure(&mut group);
    group.bench_function("1M_pairs", |b| {
        b.iter(|| batch_to_rusinkiewicz(black_box(&wi), black_box(&wo)).expect("valid directions"))
    });
    group.finish();
}

fn from_rusinkiewicz(c: &mut Criterion) {
    let (wi, wo) = inputs();
    let angles = batch_to_rusinkiewicz(&wi, &wo).expect("valid directions");
    drop((wi, wo));
    let mut group = c.benchmark_group("batch_from_rusinkiewicz");
    configure(&mut group);
    group.bench_function("1M_pairs", |b| {
        b.iter(|| batch_from_rusinkiewicz(black_box(&angles)).expect("finite angles"))
    });
    group.finish();
}

criterion_group!(benches, to_rusinkiewicz, from_rusinkiewicz);
criterion_main!(benches);
