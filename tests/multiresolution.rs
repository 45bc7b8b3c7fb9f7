//! Multiresolution filters: exact biorthogonality, round trips, the detail-to-segment mapping
//! and the noise-level estimate (MODEL §2).

use std::f64::consts::TAU;

use glam::DVec2;
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use rugosa::ShapeError;
use rugosa::Spline;
use rugosa::interpolating_control_points;
use rugosa::{
    DETAIL_NOISE_GAIN, Decomposition, NoiseEstimator, decompose, noise_level, reconstruct, reverse_subdivide,
    segment_noise_levels, subdivide, synthesize,
};

/// Exact rational filters evaluated in f64: entries are O(1) sums of ≤ 7 products, so 1e-12
/// leaves three orders of magnitude above rounding and far below any wrong tap or shift (≥ 1e-2).
const EXACT: f64 = 1e-12;

type Matrix = Vec<Vec<f64>>;

fn unit(len: usize, k: usize) -> Vec<DVec2> {
    (0..len).map(|i| if i == k { DVec2::X } else { DVec2::ZERO }).collect()
}

/// The matrix of a linear map on x components, built column by column from unit vectors.
fn matrix_of(inputs: usize, outputs: usize, map: impl Fn(Vec<DVec2>) -> Vec<DVec2>) -> Matrix {
    let columns: Vec<Vec<DVec2>> = (0..inputs).map(|k| map(unit(inputs, k))).collect();
    (0..outputs).map(|r| columns.iter().map(|c| c[r].x).collect()).collect()
}

fn multiply(a: &Matrix, b: &Matrix) -> Matrix {
    a.iter()
        .map(|row| (0..b[0].len()).map(|j| row.iter().zip(b).map(|(x, brow)| x * brow[j]).sum()).collect())
        .collect()
}

fn add(a: &Matrix, b: &Matrix) -> Matrix {
    a.iter().zip(b).map(|(r, s)| r.iter().zip(s).map(|(x, y)| x + y).collect()).collect()
}

fn assert_identity_or_zero(m: &Matrix, identity: bool, what: &str) {
    for (i, row) in m.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let expected = if identity && i == j { 1.0 } else { 0.0 };
            assert!((v - expected).abs() < EXACT, "{what}[{i}][{j}] = {v}, expected {expected}");
        }
    }
}

struct Filters {
    p: Matrix,
    q: Matrix,
    a: Matrix,
    b: Matrix,
}

fn filters(n: usize) -> Filters {
    Filters {
        p: matrix_of(n, 2 * n, |c| subdivide(&c)),
        q: matrix_of(n, 2 * n, |d| synthesize(&vec![DVec2::ZERO; n], &d).unwrap()),
        a: matrix_of(2 * n, n, |f| reverse_subdivide(&f).unwrap().0),
        b: matrix_of(2 * n, n, |f| reverse_subdivide(&f).unwrap().1),
    }
}

#[test]
fn analysis_inverts_subdivision_exactly() {
    // 4 is the smallest coarse polygon (filters wrap onto themselves), 5 an odd count, 8 typical.
    for n in [4, 5, 8] {
        let f = filters(n);
        assert_identity_or_zero(&multiply(&f.a, &f.p), true, &format!("A·P (n = {n})"));
        assert_identity_or_zero(&multiply(&f.b, &f.p), false, &format!("B·P (n = {n})"));
        assert_identity_or_zero(&multiply(&f.a, &f.q), false, &format!("A·Q (n = {n})"));
        assert_identity_or_zero(&multiply(&f.b, &f.q), true, &format!("B·Q (n = {n})"));
    }
}

#[test]
fn synthesis_inverts_analysis_exactly() {
    for n in [4, 5, 8] {
        let f = filters(n);
        let sum = add(&multiply(&f.p, &f.a), &multiply(&f.q, &f.b));
        assert_identity_or_zero(&sum, true, &format!("P·A + Q·B (n = {n})"));
    }
}

#[test]
fn detail_gain_matches_the_applied_filter() {
    // Row j of ε ↦ d: the variance of d_j under i.i.d. unit noise is its squared norm.
    let f = filters(8);
    for row in &f.b {
        let gain: f64 = row.iter().map(|b| b * b).sum();
        assert!((gain - DETAIL_NOISE_GAIN).abs() < 1e-15, "{gain} vs {DETAIL_NOISE_GAIN}");
    }
}

fn blob(n: usize, radius: f64) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let theta = TAU * k as f64 / n as f64;
            radius * (1.0 + 0.2 * (3.0 * theta).cos() + 0.1 * (5.0 * theta + 1.0).sin()) * DVec2::from_angle(theta)
        })
        .collect()
}

#[test]
fn subdivided_coarse_polygon_has_zero_detail() {
    let coarse = blob(12, 1.0);
    let fine = subdivide(&subdivide(&subdivide(&coarse)));
    let decomposition = decompose(&fine, 3).unwrap();
    for (got, want) in decomposition.coarse().iter().zip(&coarse) {
        assert!((*got - *want).length() < EXACT, "coarse {got} vs {want}");
    }
    for (level, details) in decomposition.details().iter().enumerate() {
        assert_eq!(details.len(), 12 << level);
        assert!(details.iter().all(|d| d.length() < EXACT), "level {level}: {details:?}");
    }
}

#[test]
fn decompose_then_reconstruct_round_trips() {
    let mut rng = StdRng::seed_from_u64(11);
    let normal = Normal::new(0.0, 0.05).unwrap();
    let fine: Vec<DVec2> =
        blob(96, 1.0).iter().map(|p| *p + DVec2::new(normal.sample(&mut rng), normal.sample(&mut rng))).collect();
    let decomposition = decompose(&fine, 3).unwrap();
    assert_eq!(decomposition.coarse().len(), 12);
    assert_eq!(decomposition.fine_count(), 96);
    let rebuilt = reconstruct(&decomposition);
    assert_eq!(rebuilt.len(), 96);
    for (got, want) in rebuilt.iter().zip(&fine) {
        assert!((*got - *want).length() < EXACT, "{got} vs {want}");
    }
}

fn expect_parameter(result: Result<Decomposition, ShapeError>, what: &str, fragment: &str) {
    match result {
        Err(ShapeError::InvalidParameter { what: w, reason }) => {
            assert_eq!(w, what);
            assert!(reason.contains(fragment), "reason: {reason}");
        }
        other => panic!("expected {what} error, got {other:?}"),
    }
}

#[test]
fn decompose_refuses_bad_level_counts() {
    let fine = blob(24, 1.0);
    expect_parameter(decompose(&fine, 4), "decompose.levels", "not divisible by 2^4");
    expect_parameter(decompose(&fine, 3), "decompose.levels", "leave 3 coarse points");
    expect_parameter(decompose(&fine, 1000), "decompose.levels", "not divisible");
    assert!(matches!(decompose(&fine[..3], 0), Err(ShapeError::TooFewControlPoints { count: 3 })));
    let mut bad = fine.clone();
    bad[5].y = f64::NAN;
    assert!(matches!(decompose(&bad, 1), Err(ShapeError::NonFiniteControlPoint { index: 5, .. })));
    assert_eq!(decompose(&fine, 0).unwrap().coarse(), fine.as_slice());
}

#[test]
fn from_parts_checks_level_lengths() {
    let coarse = blob(6, 1.0);
    assert!(Decomposition::from_parts(coarse.clone(), vec![vec![DVec2::ZERO; 6], vec![DVec2::ZERO; 12]]).is_ok());
    let wrong = Decomposition::from_parts(coarse.clone(), vec![vec![DVec2::ZERO; 6], vec![DVec2::ZERO; 6]]);
    expect_parameter(wrong, "decomposition.details", "level 1 holds 6 details, expected 12");
    assert!(synthesize(&coarse, &[DVec2::ZERO; 5]).is_err());
}

/// Displacement of the reconstructed curve from the coarse curve at coarse parameter `u`,
/// after adding a unit normal-ish detail `(level, index)`.
fn bump(levels: usize, level: usize, index: usize) -> impl Fn(f64) -> f64 {
    let coarse = blob(16, 1.0);
    let mut details: Vec<Vec<DVec2>> = (0..levels).map(|l| vec![DVec2::ZERO; 16 << l]).collect();
    details[level][index] = DVec2::new(1e-3, 2e-3);
    let decomposition = Decomposition::from_parts(coarse.clone(), details).unwrap();
    let fine = Spline::from_control_points_unchecked(reconstruct(&decomposition));
    let coarse = Spline::from_control_points_unchecked(coarse);
    let scale = (1 << levels) as f64;
    move |u: f64| (fine.position(scale * u) - coarse.position(u)).length()
}

#[test]
fn detail_bump_is_centred_on_its_segment_midpoint() {
    // (levels, level, index) → centre (index + ½)/2^level and half-width 2.5/2^level.
    for (levels, level, index) in [(1, 0, 5), (2, 1, 11), (3, 2, 22), (3, 0, 0)] {
        let decomposition =
            Decomposition::from_parts(blob(16, 1.0), (0..levels).map(|l| vec![DVec2::ZERO; 16 << l]).collect())
                .unwrap();
        let centre = decomposition.detail_parameter(level, index);
        let half_width = 2.5 / (1 << level) as f64;
        assert_eq!(decomposition.detail_segment(level, index), centre.floor() as usize);
        let displacement = bump(levels, level, index);
        let step = 1.0 / 512.0; // a power of two: samples hit the joints and the centre exactly
        let samples: Vec<(f64, f64)> =
            (0..16 * 512).map(|k| (k as f64 * step, displacement(k as f64 * step))).collect();
        let periodic_offset = |u: f64| (u - centre + 8.0).rem_euclid(16.0) - 8.0;
        for &(u, d) in &samples {
            if periodic_offset(u).abs() >= half_width {
                assert!(d < 1e-15, "level {level} index {index}: displacement {d} at u = {u}, outside the support");
            }
        }
        let inside = samples.iter().filter(|(u, _)| periodic_offset(*u).abs() < half_width - step);
        assert!(inside.clone().all(|&(_, d)| d > 0.0), "support narrower than ±{half_width}");
        // Symmetric bump: its centroid in u lies on the centre.
        let (moment, mass) = samples.iter().fold((0.0, 0.0), |(m, w), &(u, d)| (m + periodic_offset(u) * d, w + d));
        assert!((moment / mass).abs() < 1e-9, "centroid offset {} for centre {centre}", moment / mass);
    }
}

const NOISE_SIGMA: f64 = 1e-3;

fn noisy_circle(seed: u64) -> Vec<DVec2> {
    let circle: Vec<DVec2> = (0..1024).map(|k| DVec2::from_angle(TAU * k as f64 / 1024.0)).collect();
    let mut rng = StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, NOISE_SIGMA).unwrap();
    interpolating_control_points(&circle)
        .unwrap()
        .into_iter()
        .map(|c| c + DVec2::new(normal.sample(&mut rng), normal.sample(&mut rng)))
        .collect()
}

/// 10 %: with 512 finest normal components the estimate's relative standard error is about
/// 3 % (standard deviation) and 5 % (median, asymptotic variance 1.36 σ²/n), so 10 % is ≥ 2
/// standard errors, while a missing filter gain is an 11 % error and a wrong component
/// (vector length) a 41 % one.
const NOISE_RECOVERY: f64 = 0.10;

#[test]
fn noise_level_recovers_control_point_noise() {
    let decomposition = decompose(&noisy_circle(2024), 5).unwrap();
    for estimator in [NoiseEstimator::StandardDeviation, NoiseEstimator::MedianAbsolute] {
        let sigma = noise_level(&decomposition, estimator).unwrap();
        assert!((sigma / NOISE_SIGMA - 1.0).abs() < NOISE_RECOVERY, "{estimator:?}: {sigma} vs {NOISE_SIGMA}");
        let per_segment = segment_noise_levels(&decomposition, estimator).unwrap();
        assert_eq!(per_segment.len(), 32);
        let mean = per_segment.iter().sum::<f64>() / 32.0;
        assert!((mean / NOISE_SIGMA - 1.0).abs() < NOISE_RECOVERY, "{estimator:?}: segment mean {mean}");
    }
}

#[test]
fn noise_level_of_a_smooth_curve_is_negligible() {
    let circle: Vec<DVec2> = (0..1024).map(|k| DVec2::from_angle(TAU * k as f64 / 1024.0)).collect();
    let decomposition = decompose(&interpolating_control_points(&circle).unwrap(), 5).unwrap();
    for estimator in [NoiseEstimator::StandardDeviation, NoiseEstimator::MedianAbsolute] {
        // A smooth curve's finest details are O(h⁴) with h = 2π/1024: far below 1e-3.
        let sigma = noise_level(&decomposition, estimator).unwrap();
        assert!(sigma < 1e-3 * NOISE_SIGMA, "{estimator:?}: {sigma}");
    }
}

#[test]
fn noise_needs_details() {
    let decomposition = decompose(&blob(16, 1.0), 0).unwrap();
    assert!(matches!(
        noise_level(&decomposition, NoiseEstimator::default()),
        Err(ShapeError::InvalidParameter { what, .. }) if what == "noise.levels"
    ));
}
