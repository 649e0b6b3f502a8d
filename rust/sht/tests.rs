use std::mem::MaybeUninit;

use super::analysis::SHARED_MAP_BYTES;
use super::*;

fn random(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

fn max_relative_error(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

#[test]
fn round_trip_on_both_grids() {
    for (grid, nlat, nlon, lmax) in [
        (Grid::GaussLegendre, 12, 23, 11),
        (Grid::GaussLegendre, 17, 40, 9),
        (Grid::Equiangular, 13, 23, 11),
        (Grid::Equiangular, 20, 30, 12),
    ] {
        let sht = Sht::<f64>::new(nlat, nlon, lmax, grid).unwrap();
        let coefficients = random(3 * sht.n_coefficients(), 7);
        let maps = sht.synthesis(&coefficients, 3).unwrap();
        let back = sht.analysis(&maps, 3).unwrap();
        let error = max_relative_error(&back, &coefficients);
        assert!(error < 1e-13, "{grid:?} {nlat}×{nlon} lmax {lmax}: {error}");
    }
}

#[test]
fn adjoint_satisfies_the_dot_product_identity() {
    for grid in [Grid::GaussLegendre, Grid::Equiangular] {
        let sht = Sht::<f64>::new(15, 29, 13, grid).unwrap();
        let maps = random(2 * 15 * 29, 3);
        let coefficients = random(2 * sht.n_coefficients(), 5);
        let lhs: f64 = sht
            .analysis(&maps, 2)
            .unwrap()
            .iter()
            .zip(&coefficients)
            .map(|(a, b)| a * b)
            .sum();
        let rhs: f64 = maps
            .iter()
            .zip(&sht.analysis_adjoint(&coefficients, 2).unwrap())
            .map(|(a, b)| a * b)
            .sum();
        assert!(
            (lhs - rhs).abs() < 1e-13 * lhs.abs().max(1.0),
            "{grid:?}: {lhs} vs {rhs}"
        );
    }
}

#[test]
fn constant_map_has_only_y00() {
    let sht = Sht::<f64>::new(8, 16, 7, Grid::GaussLegendre).unwrap();
    let coefficients = sht.analysis(&vec![1.0; 8 * 16], 1).unwrap();
    let expected = (4.0 * std::f64::consts::PI).sqrt();
    assert!((coefficients[0] - expected).abs() < 1e-14);
    assert!(coefficients[1..].iter().all(|c| c.abs() < 1e-14));
}

#[test]
fn rejects_grids_too_small_for_lmax() {
    assert!(Sht::<f64>::new(10, 21, 10, Grid::GaussLegendre).is_err());
    assert!(Sht::<f64>::new(11, 21, 10, Grid::Equiangular).is_err());
    assert!(Sht::<f64>::new(11, 20, 10, Grid::GaussLegendre).is_err());
}

#[test]
fn reused_plans_give_the_same_results() {
    // Scratch buffers are pooled without clearing: every stage must overwrite them fully.
    for grid in [Grid::GaussLegendre, Grid::Equiangular] {
        let sht = Sht::<f64>::new(17, 33, 14, grid).unwrap();
        let first = random(4 * 17 * 33, 1);
        let second = random(2 * 17 * 33, 2);
        let expected = sht.analysis(&second, 2).unwrap();
        sht.analysis(&first, 4).unwrap();
        assert_eq!(sht.analysis(&second, 2).unwrap(), expected);
        let coefficients = random(3 * sht.n_coefficients(), 3);
        let expected = (
            sht.synthesis(&coefficients, 3).unwrap(),
            sht.analysis_adjoint(&coefficients, 3).unwrap(),
        );
        sht.synthesis(&random(5 * sht.n_coefficients(), 4), 5).unwrap();
        sht.analysis(&first, 4).unwrap();
        assert_eq!(sht.synthesis(&coefficients, 3).unwrap(), expected.0);
        assert_eq!(sht.analysis_adjoint(&coefficients, 3).unwrap(), expected.1);
    }
}

#[test]
fn batches_match_single_maps() {
    // Batches take the wide-tile kernel in chunks; single maps the two-column tile on the
    // calling thread. Both must give the same transform.
    for grid in [Grid::GaussLegendre, Grid::Equiangular] {
        let sht = Sht::<f64>::new(24, 47, 21, grid).unwrap();
        let (batch, points, n) = (20, 24 * 47, sht.n_coefficients());
        let maps = random(batch * points, 9);
        let coefficients = random(batch * n, 10);
        let analysed = sht.analysis(&maps, batch).unwrap();
        let synthesised = sht.synthesis(&coefficients, batch).unwrap();
        for b in [0, 7, 8, 19] {
            let single = sht.analysis(&maps[b * points..][..points], 1).unwrap();
            assert!(
                max_relative_error(&analysed[b * n..][..n], &single) < 1e-13,
                "{grid:?} analysis map {b}"
            );
            let single = sht.synthesis(&coefficients[b * n..][..n], 1).unwrap();
            assert!(
                max_relative_error(&synthesised[b * points..][..points], &single) < 1e-13,
                "{grid:?} synthesis map {b}"
            );
        }
    }
}

#[test]
fn batches_of_maps_larger_than_a_cores_cache_match_single_maps() {
    // Maps over `SHARED_MAP_BYTES` analysed on the fly are transformed one after another,
    // each parallel inside, rather than one per worker.
    let (nlat, nlon, lmax) = (8, 40_000, 7);
    assert!(nlat * nlon * 8 > SHARED_MAP_BYTES);
    let sht = Sht::<f64>::with_cache_limit(nlat, nlon, lmax, Grid::GaussLegendre, 0).unwrap();
    let (batch, points, n) = (3, nlat * nlon, sht.n_coefficients());
    let maps = random(batch * points, 13);
    let analysed = sht.analysis(&maps, batch).unwrap();
    for b in 0..batch {
        let single = sht.analysis(&maps[b * points..][..points], 1).unwrap();
        assert!(max_relative_error(&analysed[b * n..][..n], &single) < 1e-13, "map {b}");
    }
}

#[test]
fn on_the_fly_legendre_agrees_with_the_matrix_product() {
    // Without a table cache, analysis computes λ on the fly (as for large grids): Gauss–
    // Legendre maps from tiles of ring blocks, with and without an equator ring (and a
    // partial last block), equiangular ones from gathered columns.
    // 180 rings: 90 half rings, whole blocks of four vectors but the last vector partial,
    // and more than 64 pairs of degrees (the plain loop in chunks). Batches of 3 take the
    // matrix product where the table is kept; single maps never do.
    let cases = [
        (Grid::GaussLegendre, 40, 80, 39),
        (Grid::GaussLegendre, 41, 82, 40),
        (Grid::GaussLegendre, 180, 360, 179),
        (Grid::Equiangular, 41, 80, 39),
    ];
    for (grid, nlat, nlon, lmax) in cases {
        let cached = Sht::<f32>::new(nlat, nlon, lmax, grid).unwrap();
        let on_the_fly = Sht::<f32>::with_cache_limit(nlat, nlon, lmax, grid, 0).unwrap();
        let maps: Vec<f32> = random(3 * nlat * nlon, 12).into_iter().map(|v| v as f32).collect();
        let [a, b] = [&on_the_fly, &cached].map(|sht| sht.analysis(&maps, 3).unwrap());
        let error = a.iter().zip(&b).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        let scale = b.iter().map(|b| b.abs()).fold(0.0, f32::max);
        assert!(error < 1e-5 * scale, "{grid:?} f32: {error} of {scale}");
    }
    for (grid, nlat, nlon, lmax) in cases {
        let cached = Sht::<f64>::new(nlat, nlon, lmax, grid).unwrap();
        let on_the_fly = Sht::<f64>::with_cache_limit(nlat, nlon, lmax, grid, 0).unwrap();
        let maps = random(3 * nlat * nlon, 11);
        for batch in [1, 3] {
            let maps = &maps[..batch * nlat * nlon];
            let error = max_relative_error(
                &on_the_fly.analysis(maps, batch).unwrap(),
                &cached.analysis(maps, batch).unwrap(),
            );
            assert!(error < 1e-13, "{grid:?} batch {batch}: {error}");
        }
    }
}

#[test]
fn a_transform_runs_on_the_calling_thread_only_where_the_global_pool_has_one_thread() {
    // A caller made a worker of a one-thread pool runs every later parallel loop, its own
    // and other kernels', on that one thread: right only where the global pool has one
    // thread anyway. `.ci/run` runs these tests with both widths.
    std::thread::spawn(|| {
        let sht = Sht::<f64>::new(12, 24, 11, Grid::GaussLegendre).unwrap();
        let maps = random(12 * 24, 1);
        let global_width = rayon::current_num_threads();
        let first = sht.analysis(&maps, 1).unwrap();
        assert_eq!(
            rayon::current_thread_index().is_some(),
            global_width == 1,
            "global pool of {global_width}"
        );
        // A second call, on the adopted thread where it was adopted, gives the same numbers.
        assert_eq!(sht.analysis(&maps, 1).unwrap(), first);
    })
    .join()
    .unwrap();
}

#[test]
fn transforms_into_given_outputs_overwrite_them_and_check_their_size() {
    for grid in [Grid::GaussLegendre, Grid::Equiangular] {
        let sht = Sht::<f64>::new(16, 32, 7, grid).unwrap();
        let (points, n_coefficients) = (16 * 32, sht.n_coefficients());
        let coefficients = random(2 * n_coefficients, 3);
        // Outputs full of NaN: anything added to rather than written would show.
        let mut maps = vec![f64::NAN; 2 * points];
        sht.synthesis_into(&coefficients, 2, &mut maps).unwrap();
        assert_eq!(maps, sht.synthesis(&coefficients, 2).unwrap());
        sht.analysis_adjoint_into(&coefficients, 2, &mut maps).unwrap();
        assert_eq!(maps, sht.analysis_adjoint(&coefficients, 2).unwrap());
        let mut out = vec![MaybeUninit::new(f64::NAN); 2 * n_coefficients];
        sht.analysis_into(&maps, 2, &mut out).unwrap();
        let out: Vec<f64> = out.iter().map(|v| unsafe { v.assume_init() }).collect();
        assert_eq!(out, sht.analysis(&maps, 2).unwrap());

        assert!(sht.synthesis_into(&coefficients, 2, &mut maps[..points]).is_err());
        assert!(sht
            .analysis_into(&maps, 2, &mut vec![MaybeUninit::uninit(); n_coefficients])
            .is_err());
    }
}

#[test]
fn products_skip_the_rings_near_the_pole_where_an_orders_values_are_negligible() {
    // λ_lm near the poles falls like sin^m θ: for large m the polar rings contribute
    // nothing, and the kept panels start after them (the results are checked against the
    // on-the-fly path and the round trips above).
    let sht = Sht::<f64>::new(90, 180, 89, Grid::GaussLegendre).unwrap();
    let panels = sht.at_grid.cached.as_ref().expect("a 90 × 180 table is kept");
    let quiet: Vec<[usize; 2]> = panels.iter().map(|order| order.quiet).collect();
    assert_eq!(quiet[0], [0, 0]);
    assert!(quiet[89][0] >= 10, "{:?}", quiet[89]);
    assert!(quiet.windows(2).all(|w| w[1][0] >= w[0][0]), "{quiet:?}");
}
