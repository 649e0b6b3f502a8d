//! The float32 path ([`super::batch`]) against the float64 one.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use super::batch::Tables;
use super::eval::tests::real_files;
use super::synthetic::{MaterialArrays, TestRng as Rng};
use super::tensor_file::TensorFile;
use super::{MeasuredBsdf, Precision};
use crate::coords::Vec3;
use crate::merl::{MISSING, N_BINS};

fn build(arrays: &MaterialArrays) -> MeasuredBsdf {
    MeasuredBsdf::from_tensor_file(&TensorFile::parse(Path::new("synthetic.bsdf"), arrays.encode()).unwrap()).unwrap()
}

/// Random pairs, some below the horizon; a count that leaves a partial block of lanes.
fn pairs(seed: u64, n: usize) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = Rng(seed);
    let mut upper = |_| rng.upper(-0.1).map(|x| 2.5 * x);
    ((0..n).map(&mut upper).collect(), (0..n).map(&mut upper).collect())
}

/// The relative differences of float32 from float64 (both evaluated), where float64's
/// value exceeds 1 % of its largest: (max, median). Both give 0 for the same pairs.
fn differences(bsdf: &MeasuredBsdf, wi: &[Vec3], wo: &[Vec3]) -> (f64, f64) {
    let single = bsdf.eval(wi, wo, Precision::Single).unwrap();
    let double = bsdf.eval(wi, wo, Precision::Double).unwrap();
    let largest = double.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    let mut relative = Vec::new();
    for (s, d) in single.iter().flatten().zip(double.iter().flatten()) {
        assert!(
            s.is_finite() && *s >= 0.0 && (*s == 0.0) == (*d == 0.0) || d.abs() < 1e-6 * largest,
            "{s} vs {d}"
        );
        if *d > 0.01 * largest {
            relative.push((s - d).abs() / d);
        }
    }
    relative.sort_by(f64::total_cmp);
    (relative[relative.len() - 1], relative[relative.len() / 2])
}

#[test]
fn single_precision_follows_double_on_synthetic_materials() {
    let mut quarter = MaterialArrays::example(0.2, 3);
    quarter.phi_i = (0..3).map(|k| (-PI + FRAC_PI_2 * k as f64 / 2.0) as f32).collect();
    let mut half = MaterialArrays::example(0.3, 3);
    half.phi_i = (0..3).map(|k| (-PI + PI * k as f64 / 2.0) as f32).collect();
    let mut flat = MaterialArrays::example(0.4, 1);
    flat.jacobian = false;
    let materials = [
        MaterialArrays::example(0.1, 1),
        MaterialArrays::example(0.2, 5),
        quarter,
        half,
        flat,
    ];
    let (wi, wo) = pairs(1, 50_007);
    for (index, arrays) in materials.iter().enumerate() {
        let bsdf = build(arrays);
        let (max, median) = differences(&bsdf, &wi, &wo);
        eprintln!(
            "material {index} (reduction {}): max {max:.1e}, median {median:.1e}",
            bsdf.reduction()
        );
        assert!(
            max < 3e-5 && median < 3e-6,
            "material {index}: max {max}, median {median}"
        );
    }
}

#[test]
fn tiny_and_huge_rows_give_the_values_of_unit_rows() {
    // Rows are scaled by a power of two before they are normalised: a row of subnormal or
    // near-overflowing components gives its direction's value (1 / 1e-310 would overflow).
    let bsdf = build(&MaterialArrays::example(0.2, 1));
    let (wi, wo) = pairs(8, 3001);
    let unit = bsdf.eval(&wi, &wo, Precision::Single).unwrap();
    for scale in [1e-310, 1e-300, 1e300, 1.7e308 / 2.5] {
        let scaled = |rows: &[Vec3]| -> Vec<Vec3> { rows.iter().map(|v| v.map(|x| x * scale)).collect() };
        let values = bsdf.eval(&scaled(&wi), &scaled(&wo), Precision::Single).unwrap();
        for (a, b) in values.iter().flatten().zip(unit.iter().flatten()) {
            assert!((a - b).abs() <= 1e-5 * b.abs() + 1e-9, "scale {scale:e}: {a} vs {b}");
        }
    }
}

#[test]
fn every_instruction_set_gives_the_same_values() {
    let bsdf = build(&MaterialArrays::example(0.2, 1));
    let (wi, wo) = pairs(4, 5000);
    let results = Tables::new(&bsdf).eval_chunk_each_way(&wi, &wo);
    assert!(results.iter().all(|values| *values == results[0]));
    assert_eq!(results[0], bsdf.eval(&wi, &wo, Precision::Single).unwrap());
}

#[test]
fn single_precision_checks_rows_as_double_does() {
    let bsdf = build(&MaterialArrays::example(0.2, 1));
    let (wi, mut wo) = pairs(3, 1000);
    wo[517] = [1.0, f64::INFINITY, 0.0];
    for precision in [Precision::Single, Precision::Double] {
        let message = bsdf.eval(&wi, &wo, precision).unwrap_err().to_string();
        assert!(message.contains("wo row 517"), "{message}");
    }
}

#[test]
fn single_precision_follows_double_on_the_rgl_files() {
    let (wi, wo) = pairs(2, 200_000);
    for path in real_files() {
        let bsdf = MeasuredBsdf::read(&path).unwrap();
        let (max, median) = differences(&bsdf, &wi, &wo);
        eprintln!(
            "{}: max {max:.1e}, median {median:.1e}",
            path.file_name().unwrap().to_string_lossy()
        );
        assert!(
            max < 3e-5 && median < 3e-6,
            "{}: max {max}, median {median}",
            path.display()
        );
    }
}

#[test]
fn merl_table_holds_the_evaluation_at_each_bin() {
    let bsdf = build(&MaterialArrays::example(0.15, 1));
    let (wi, wo) = super::merl_table::bin_directions();
    let bins: Vec<usize> = (0..N_BINS).step_by(997).collect();
    let (wi, wo): (Vec<Vec3>, Vec<Vec3>) = bins.iter().map(|&b| (wi[b], wo[b])).unzip();
    for precision in [Precision::Single, Precision::Double] {
        let table = bsdf.merl_table(precision);
        let values = bsdf.eval(&wi, &wo, precision).unwrap();
        for (k, &bin) in bins.iter().enumerate() {
            let above = wi[k][2] > 0.0 && wo[k][2] > 0.0;
            let expected = if above { values[k] } else { [MISSING; 3] };
            assert_eq!([0, 1, 2].map(|c| table[c * N_BINS + bin]), expected, "bin {bin}");
        }
        let missing = table[..N_BINS].iter().filter(|&&v| v == MISSING).count();
        assert!((0.2..0.3).contains(&(missing as f64 / N_BINS as f64)), "{missing}");
    }
}
