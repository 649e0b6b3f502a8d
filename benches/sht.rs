//! Spherical harmonic analysis throughput in maps/s: Gauss–Legendre grids 90×180
//! (lmax 89, the project's workload) up to 512×1024 (lmax = nlat − 1), batches of 1 and
//! 192 maps (16 at 512×1024, to keep memory and time in bounds), f64 and f32.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode, Throughput};

use _native::sht::{Grid, Real, Sht};

const SIZES: [(usize, usize, usize); 4] = [(90, 180, 89), (128, 256, 127), (256, 512, 255), (512, 1024, 511)];

fn bench_type<T: Real>(c: &mut Criterion, name: &str) {
    let mut group = c.benchmark_group(format!("sht_analysis_{name}"));
    group
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1));
    for (nlat, nlon, lmax) in SIZES {
        let sht = Sht::<T>::new(nlat, nlon, lmax, Grid::GaussLegendre).expect("valid plan");
        for batch in [1, if nlat >= 512 { 16 } else { 192 }] {
            let coefficients: Vec<T> = (0..batch * sht.n_coefficients())
                .map(|i| T::of(((i * 7919) % 1000) as f64 / 1000.0 - 0.5))
                .collect();
            let maps = sht.synthesis(&coefficients, batch).expect("valid input");
            group.throughput(Throughput::Elements(batch as u64));
            group.measurement_time(Duration::from_secs(if nlat >= 512 { 8 } else { 3 }));
            group.bench_with_input(
                BenchmarkId::new(format!("{nlat}x{nlon}_lmax{lmax}"), batch),
                &maps,
                |b, maps| b.iter(|| sht.analysis(black_box(maps), batch).expect("valid input")),
            );
        }
    }
    group.finish();
}

fn sht(c: &mut Criterion) {
    bench_type::<f64>(c, "f64");
    bench_type::<f32>(c, "f32");
}

criterion_group!(benches, sht);
criterion_main!(benches);
