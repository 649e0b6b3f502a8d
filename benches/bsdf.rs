//! Evaluating a measured RGL BRDF (`.bsdf`, Dupuy & Jakob 2018) at one MERL table's
//! 1,458,000 bins (90 θ_h × 90 θ_d × 180 φ_d at their bin positions, φ_h = 0), as direction
//! pairs, validation included. About a quarter of the pairs have a direction below the
//! horizon and cost little, as when a MERL-sized table is tabulated from a measurement.
//!
//! Uses `../shared/data/rgl-measured/vch_golden_yellow_rgb.bsdf` (or under
//! `$FRENBRDF_SHARED_DATA`) when present, else a synthetic material of the same resolution.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};

use _native::bsdf::synthetic::MaterialArrays;
use _native::bsdf::tensor_file::TensorFile;
use _native::bsdf::MeasuredBsdf;
use _native::coords::{from_rusinkiewicz, Vec3};
use _native::merl::{phi_d_of_bin, theta_d_of_bin, theta_h_of_bin, N_BINS, N_PHI_D, N_THETA_D, N_THETA_H};

fn material() -> MeasuredBsdf {
    let data = std::env::var_os("FRENBRDF_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let path = data.join("rgl-measured/vch_golden_yellow_rgb.bsdf");
    if path.is_file() {
        eprintln!("material: {}", path.display());
        MeasuredBsdf::read(&path).expect("cannot read the RGL file")
    } else {
        eprintln!("material: synthetic ({} not found)", path.display());
        let bytes = MaterialArrays::example(0.1, 1).encode();
        let file = TensorFile::parse(Path::new("synthetic.bsdf"), bytes).expect("a valid synthetic file");
        MeasuredBsdf::from_tensor_file(&file).expect("a valid synthetic material")
    }
}

fn merl_bin_pairs() -> (Vec<Vec3>, Vec<Vec3>) {
    let mut pairs = Vec::with_capacity(N_BINS);
    for h in 0..N_THETA_H {
        for d in 0..N_THETA_D {
            for p in 0..N_PHI_D {
                let angles = [
                    theta_h_of_bin(h as f64),
                    0.0,
                    theta_d_of_bin(d as f64),
                    phi_d_of_bin(p as f64),
                ];
                pairs.push(from_rusinkiewicz(angles));
            }
        }
    }
    pairs.into_iter().unzip()
}

fn eval(c: &mut Criterion) {
    let bsdf = material();
    let (wi, wo) = merl_bin_pairs();
    let mut group = c.benchmark_group("bsdf_eval");
    group.throughput(Throughput::Elements(N_BINS as u64));
    group.sampling_mode(SamplingMode::Flat);
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(10));
    group.bench_function("merl_table_bins", |b| {
        b.iter(|| bsdf.eval(black_box(&wi), black_box(&wo)).expect("valid directions"))
    });
    group.finish();
}

criterion_group!(benches, eval);
criterion_main!(benches);
