//! Reading a full-size MERL file (34,992,012 bytes) in physical units: header checks,
//! one read into the output buffer, the finiteness scan and the channel scaling.
//!
//! The file is written once to a temporary folder and then read repeatedly, so it is
//! served from the page cache: this measures the parser, not the disk.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use _native::merl::{read_merl, write_merl, N_VALUES};

fn merl_read(c: &mut Criterion) {
    let mut rng = StdRng::seed_from_u64(0x4d45_524c);
    // Stored units, like real MERL tables, with about 1 % missing (negative) values.
    let values: Vec<f64> = (0..N_VALUES)
        .map(|_| {
            if rng.random_bool(0.01) {
                -1.0
            } else {
                rng.random_range(0.0..1500.0)
            }
        })
        .collect();
    let folder = tempfile::tempdir().expect("cannot create a temporary folder");
    let path = folder.path().join("bench.binary");
    write_merl(&path, &values, false).expect("cannot write the MERL file");
    drop(values);

    let mut group = c.benchmark_group("merl_read");
    group.throughput(Throughput::Elements(N_VALUES as u64));
    group.sampling_mode(SamplingMode::Flat);
    group.sample_size(20);
    group.warm_up_time(Duration::from_secs(2));
    group.measurement_time(Duration::from_secs(5));
    group.bench_function("read_merl_physical", |b| {
        b.iter(|| read_merl(black_box(&path), true).expect("cannot read the MERL file"))
    });
    group.finish();
    // `folder` lives until here, so the file exists for the whole benchmark.
    drop(folder);
}

criterion_group!(benches, merl_read);
criterion_main!(benches);
