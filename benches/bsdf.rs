//! Evaluating a measured RGL BRDF (`.bsdf`, Dupuy & Jakob 2018) in float32 (vectorised
//! across pairs) and in float64 (one pair at a time):
//! - at 1,000,000 random direction pairs over the upper hemisphere (z ≥ 0.02), validation
//!   included, as `benches/peers/bsdf_eval.py` times them beside Mitsuba;
//! - at one MERL table's 1,458,000 bins (90 θ_h × 90 θ_d × 180 φ_d at their bin positions,
//!   φ_h = 0) into a MERL-shaped table. About a quarter of the bins have a direction below
//!   the horizon and cost little.
//!
//! Uses `../shared/data/rgl-measured/vch_golden_yellow_rgb.bsdf` (or under
//! `$FRENBRDF_SHARED_DATA`) when present, else a synthetic material of the same resolution.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};

use _native::bsdf::synthetic::MaterialArrays;
use _native::bsdf::tensor_file::TensorFile;
use _native::bsdf::{MeasuredBsdf, Precision};
use _native::coords::Vec3;
use _native::merl::N_BINS;
use rand::{Rng, SeedableRng};

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

const N_PAIRS: usize = 1_000_000;

/// Uniform over the upper hemisphere with z ≥ 0.02, as in `benches/peers/bsdf_eval.py`.
fn random_pairs() -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let mut upper = |_| {
        let (z, phi): (f64, f64) = (
            rng.random_range(0.02..1.0),
            rng.random_range(0.0..std::f64::consts::TAU),
        );
        let rho = (1.0 - z * z).sqrt();
        [rho * phi.cos(), rho * phi.sin(), z]
    };
    (
        (0..N_PAIRS).map(&mut upper).collect(),
        (0..N_PAIRS).map(&mut upper).collect(),
    )
}

const PRECISIONS: [(&str, Precision); 2] = [("single", Precision::Single), ("double", Precision::Double)];

fn eval(c: &mut Criterion) {
    let bsdf = material();
    let (wi, wo) = random_pairs();
    let mut group = c.benchmark_group("bsdf_eval");
    group.throughput(Throughput::Elements(N_PAIRS as u64));
    group.sampling_mode(SamplingMode::Flat);
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(5));
    for (name, precision) in PRECISIONS {
        group.bench_function(format!("random_pairs_{name}"), |b| {
            b.iter(|| {
                bsdf.eval(black_box(&wi), black_box(&wo), precision)
                    .expect("valid directions")
            })
        });
    }
    group.throughput(Throughput::Elements(N_BINS as u64));
    for (name, precision) in PRECISIONS {
        group.bench_function(format!("merl_table_{name}"), |b| {
            b.iter(|| bsdf.merl_table(black_box(precision)))
        });
    }
    group.finish();
}

criterion_group!(benches, eval);
criterion_main!(benches);
