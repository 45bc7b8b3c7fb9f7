//! Tolerance rules, the rugosity pattern library and rugosity measured from an outline.

use std::f64::consts::TAU;

use glam::DVec2;
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};
use rugosa::NoiseEstimator;
use rugosa::ShapeError;
use rugosa::Spline;
use rugosa::interpolating_control_points;
use rugosa::{RugosityPattern, ToleranceRule, rugosity_from_outline};

const SIGMA: f64 = 1e-3;

/// Outline of a unit circle whose 1024 fine control points carry i.i.d. N(0, SIGMA²) noise:
/// the points are the noisy curve at its joints, so interpolation recovers those control points.
fn rough_circle_outline(seed: u64) -> Vec<DVec2> {
    let circle: Vec<DVec2> = (0..1024).map(|k| DVec2::from_angle(TAU * k as f64 / 1024.0)).collect();
    let mut rng = StdRng::seed_from_u64(seed);
    let normal = Normal::new(0.0, SIGMA).unwrap();
    let noisy: Vec<DVec2> = interpolating_control_points(&circle)
        .unwrap()
        .into_iter()
        .map(|c| c + DVec2::new(normal.sample(&mut rng), normal.sample(&mut rng)))
        .collect();
    let curve = Spline::from_control_points_unchecked(noisy);
    (0..1024).map(|k| curve.position(k as f64)).collect()
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// 10 %: the mean over 32 segments pools all 512 finest normal components, whose estimate has a
/// relative standard error of about 3 % (RMS) or 5 % (median); see tests/multiresolution.rs.
const RECOVERY: f64 = 0.10;

#[test]
fn outline_rugosity_is_k_sigma() {
    let outline = rough_circle_outline(7);
    for estimator in [NoiseEstimator::StandardDeviation, NoiseEstimator::MedianAbsolute] {
        let (curve, rugosity) =
            rugosity_from_outline(&outline, 5, ToleranceRule::ToleranceInterval { k: 3.0 }, estimator).unwrap();
        assert_eq!(curve.segment_count(), 32);
        assert_eq!(rugosity.tolerances().len(), 32);
        curve.validate().unwrap();
        // The coarse curve still follows the unit circle (32 control points: error ≪ 1 %).
        for k in 0..64 {
            let r = curve.position(k as f64 * 0.5).length();
            assert!((r - 1.0).abs() < 1e-2, "radius {r}");
        }
        let r = mean(rugosity.tolerances());
        assert!((r / (3.0 * SIGMA) - 1.0).abs() < RECOVERY, "{estimator:?}: mean R {r} vs {}", 3.0 * SIGMA);
    }
}

#[test]
fn outline_rugosity_by_universal_threshold() {
    let outline = rough_circle_outline(8);
    let (_, rugosity) =
        rugosity_from_outline(&outline, 5, ToleranceRule::UniversalThreshold, NoiseEstimator::StandardDeviation)
            .unwrap();
    let expected = SIGMA * (2.0 * 512f64.ln()).sqrt();
    let r = mean(rugosity.tolerances());
    assert!((r / expected - 1.0).abs() < RECOVERY, "mean R {r} vs {expected}");
}

#[test]
fn clockwise_outline_gives_the_same_rugosity() {
    let outline = rough_circle_outline(9);
    let mut reversed = outline.clone();
    reversed.reverse();
    let rule = ToleranceRule::default();
    let (ccw_curve, ccw) = rugosity_from_outline(&outline, 4, rule, NoiseEstimator::StandardDeviation).unwrap();
    let (cw_curve, cw) = rugosity_from_outline(&reversed, 4, rule, NoiseEstimator::StandardDeviation).unwrap();
    assert!(cw_curve.signed_area() > 0.0);
    // The clockwise outline's control points are reversed back to the counter-clockwise ones
    // before the analysis (the coarse grid would otherwise sit on the odd fine points), so the
    // results agree up to the solver's rounding: 1e-15 on R ≈ 3e-3 is a few ulps.
    for (i, (x, y)) in ccw.tolerances().iter().zip(cw.tolerances()).enumerate() {
        assert!((x - y).abs() < 1e-15, "segment {i}: {x} vs {y}");
    }
    assert!((ccw_curve.signed_area() - cw_curve.signed_area()).abs() < 1e-12);
}

#[test]
fn outline_errors_are_typed() {
    let outline = rough_circle_outline(1);
    let rule = ToleranceRule::default();
    let estimator = NoiseEstimator::default();
    let what = |r: Result<(Spline, rugosa::Rugosity), ShapeError>| match r {
        Err(ShapeError::InvalidParameter { what, .. }) => what,
        other => panic!("expected a parameter error, got {other:?}"),
    };
    assert_eq!(what(rugosity_from_outline(&outline, 0, rule, estimator)), "noise.levels");
    assert_eq!(what(rugosity_from_outline(&outline, 9, rule, estimator)), "decompose.levels");
    assert_eq!(what(rugosity_from_outline(&outline[..1000], 4, rule, estimator)), "decompose.levels");
    let bad_k = ToleranceRule::ToleranceInterval { k: -1.0 };
    assert_eq!(what(rugosity_from_outline(&outline, 4, bad_k, estimator)), "tolerance_interval.k");
    assert!(matches!(
        rugosity_from_outline(&outline[..3], 0, rule, estimator),
        Err(ShapeError::TooFewControlPoints { count: 3 })
    ));
}

#[test]
fn tolerance_rules() {
    assert_eq!(ToleranceRule::default(), ToleranceRule::ToleranceInterval { k: 3.0 });
    assert_eq!(ToleranceRule::default().tolerance(0.5, 100).unwrap(), 1.5);
    let universal = ToleranceRule::UniversalThreshold.tolerance(0.5, 100).unwrap();
    assert!((universal - 0.5 * (2.0 * 100f64.ln()).sqrt()).abs() < 1e-15);
    assert!(ToleranceRule::UniversalThreshold.tolerance(0.5, 0).is_err());
    assert!(ToleranceRule::default().tolerance(f64::NAN, 10).is_err());
    let err = ToleranceRule::ToleranceInterval { k: f64::INFINITY }.tolerance(1.0, 10).unwrap_err();
    assert_eq!(err.to_string(), "tolerance_interval.k: inf is not finite");
}

fn all_types() -> [RugosityPattern; 4] {
    [
        RugosityPattern::Constant { value: 0.01 },
        RugosityPattern::Smooth { mean: 0.01, amplitude: 0.005, periods: 3, phase: 0.4 },
        RugosityPattern::Random { mean: 0.01, std_dev: 0.004, seed: 5 },
        RugosityPattern::Patches { rough: 0.02, smooth: 0.001, patches: 3, seed: 5 },
    ]
}

#[test]
fn type_numbers_and_ron_round_trip() {
    for (k, pattern) in all_types().iter().enumerate() {
        assert_eq!(pattern.type_number() as usize, k + 1);
        let text = ron::to_string(pattern).unwrap();
        assert_eq!(&ron::from_str::<RugosityPattern>(&text).unwrap(), pattern, "{text}");
        let rugosity = pattern.rugosity(40).unwrap();
        rugosity.validate(40).unwrap();
        assert_eq!(rugosity.tolerances(), pattern.tolerances(40).unwrap().as_slice());
    }
}

#[test]
fn seeded_patterns_repeat_for_a_seed_and_change_with_it() {
    let random = |seed| RugosityPattern::Random { mean: 0.01, std_dev: 0.004, seed }.tolerances(64).unwrap();
    let patches =
        |seed| RugosityPattern::Patches { rough: 0.02, smooth: 0.0, patches: 4, seed }.tolerances(64).unwrap();
    assert_eq!(random(1), random(1));
    assert_ne!(random(1), random(2));
    assert_eq!(patches(1), patches(1));
    assert_ne!(patches(1), patches(2));
}

#[test]
fn constant_and_smooth_values() {
    assert_eq!(RugosityPattern::Constant { value: 0.3 }.tolerances(5).unwrap(), vec![0.3; 5]);
    let smooth = RugosityPattern::Smooth { mean: 0.01, amplitude: 0.005, periods: 3, phase: 0.4 };
    let r = smooth.tolerances(48).unwrap();
    for (i, &v) in r.iter().enumerate() {
        let expected = 0.01 + 0.005 * (TAU * 3.0 * (i as f64 + 0.5) / 48.0 + 0.4).sin();
        assert!((v - expected).abs() < 1e-15, "segment {i}");
    }
    // Whole periods: the sine sums to zero over the boundary (rounding ~1e-18 per term).
    assert!((mean(&r) - 0.01).abs() < 1e-15);
    let clamped =
        RugosityPattern::Smooth { mean: 0.01, amplitude: 0.03, periods: 2, phase: 0.0 }.tolerances(48).unwrap();
    assert!(clamped.iter().all(|&v| v >= 0.0) && clamped.contains(&0.0));
}

#[test]
fn random_pattern_has_its_statistics() {
    let r = RugosityPattern::Random { mean: 0.01, std_dev: 0.002, seed: 3 }.tolerances(10_000).unwrap();
    let m = mean(&r);
    let sd = (r.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / 9999.0).sqrt();
    // 10 000 samples: standard errors 2e-5 on the mean and 0.7 % on the sd; 5σ-wide bounds.
    assert!((m - 0.01).abs() < 1e-4, "mean {m}");
    assert!((sd / 0.002 - 1.0).abs() < 0.035, "sd {sd}");
    let clamped = RugosityPattern::Random { mean: 0.001, std_dev: 0.01, seed: 3 }.tolerances(1000).unwrap();
    assert!(clamped.iter().all(|&v| v >= 0.0) && clamped.contains(&0.0));
}

/// Runs of equal values around the closed boundary: (value, length), starting at segment 0.
fn cyclic_runs(values: &[f64]) -> Vec<(f64, usize)> {
    let mut runs: Vec<(f64, usize)> = Vec::new();
    for &v in values {
        match runs.last_mut() {
            Some((last, len)) if *last == v => *len += 1,
            _ => runs.push((v, 1)),
        }
    }
    if runs.len() > 1 && runs[0].0 == runs[runs.len() - 1].0 {
        let (_, len) = runs.pop().unwrap();
        runs[0].1 += len;
    }
    runs
}

#[test]
fn patches_alternate_rough_and_smooth() {
    for seed in 0..50 {
        for (segments, patches) in [(64, 4), (10, 5), (33, 1), (7, 2)] {
            let pattern = RugosityPattern::Patches { rough: 0.02, smooth: 0.001, patches, seed };
            let values = pattern.tolerances(segments).unwrap();
            assert_eq!(values.len(), segments);
            assert_eq!(values[0], 0.02, "arc 0 is rough");
            let runs = cyclic_runs(&values);
            assert_eq!(runs.len(), 2 * patches, "seed {seed}: {values:?}");
            for (k, run) in runs.iter().enumerate() {
                assert_eq!(run.0, if k % 2 == 0 { 0.02 } else { 0.001 }, "seed {seed}: {values:?}");
            }
        }
    }
}

fn expect_error(pattern: RugosityPattern, segments: usize, what: &str, message: &str) {
    match pattern.tolerances(segments) {
        Err(err @ ShapeError::InvalidParameter { .. }) => {
            assert!(matches!(&err, ShapeError::InvalidParameter { what: w, .. } if w == what), "{err}");
            assert_eq!(err.to_string(), message);
            assert_eq!(pattern.rugosity(segments).unwrap_err(), err);
        }
        other => panic!("{pattern:?}: expected {what} error, got {other:?}"),
    }
}

#[test]
fn pattern_parameters_are_validated() {
    use RugosityPattern::*;
    expect_error(Constant { value: -0.1 }, 8, "constant.value", "constant.value: -0.1 is negative; it must be >= 0");
    expect_error(Constant { value: f64::NAN }, 8, "constant.value", "constant.value: NaN is not finite");
    expect_error(Constant { value: 0.1 }, 0, "constant.segments", "constant.segments: needs at least one segment");
    let smooth = |mean, amplitude, phase| Smooth { mean, amplitude, periods: 2, phase };
    expect_error(smooth(-1.0, 0.1, 0.0), 8, "smooth.mean", "smooth.mean: -1 is negative; it must be >= 0");
    expect_error(smooth(1.0, -0.1, 0.0), 8, "smooth.amplitude", "smooth.amplitude: -0.1 is negative; it must be >= 0");
    expect_error(smooth(1.0, 0.1, f64::INFINITY), 8, "smooth.phase", "smooth.phase: inf is not finite");
    let random = |mean, std_dev| Random { mean, std_dev, seed: 1 };
    expect_error(random(-0.5, 0.1), 8, "random.mean", "random.mean: -0.5 is negative; it must be >= 0");
    expect_error(random(0.5, -0.1), 8, "random.std_dev", "random.std_dev: -0.1 is negative; it must be >= 0");
    expect_error(random(0.5, f64::NAN), 8, "random.std_dev", "random.std_dev: NaN is not finite");
    let patches = |rough, smooth, patches| Patches { rough, smooth, patches, seed: 1 };
    expect_error(patches(-1.0, 0.0, 2), 8, "patches.rough", "patches.rough: -1 is negative; it must be >= 0");
    expect_error(patches(1.0, f64::NEG_INFINITY, 2), 8, "patches.smooth", "patches.smooth: -inf is not finite");
    expect_error(
        patches(1.0, 0.0, 0),
        8,
        "patches.patches",
        "patches.patches: 0 rough patches need 1 <= patches <= segments/2 = 4",
    );
    expect_error(
        patches(1.0, 0.0, 5),
        9,
        "patches.patches",
        "patches.patches: 5 rough patches need 1 <= patches <= segments/2 = 4",
    );
}
