//! The narrow phase against a brute-force reference on random body pairs.
//!
//! Reference, independent of the solver: for every leaf pair whose boxes come within the bodies' largest combined band, the
//! distance from `p(t)` to the whole piece of B (33 samples in `s`, slope sign changes refined by
//! bisection-safeguarded Newton: the exact 1-D global minimum) sampled at 129 values of `t`, each sampled local minimum refined by golden
//! section. On top, every case samples both
//! whole curves at 4096 points and checks that the solver's minimum is never above the sampled
//! one. Tolerance: 1e-9 × body size (the larger control-box diagonal of the two bodies).
//!
//! The bodies are queried through the public [`query_bodies`] (both AOBB trees descended), so a
//! leaf pair the trees wrongly prune shows up as a missed contact or intersection.
//!
//! Every run checks 10,000 cases; statistics with
//! `cargo test --test query_brute_force -- --nocapture`.
//! One case: `RUGOSA_CASE=1234 cargo test --test query_brute_force -- --nocapture`.

use std::f64::consts::TAU;

use glam::DVec2;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rugosa::AobbTree;
use rugosa::{BodyQuery, BodyShape, Manifold, PairState, QuerySettings, query_bodies};
use rugosa::{CubicSegment, Generator, Pose, Rugosity, Spline};
use rugosa::{
    CurvePairSettings, Orientation, SegmentPairState, TolerancedSegment, query_segment_segment, separating_axes,
};

const BASE_SEED: u64 = 0x05ee_d202_40b0_d1e5;
/// Relative accuracy demanded of distances and decisions.
const RELATIVE_TOLERANCE: f64 = 1e-9;
/// Points per whole curve in the dense global check.
const DENSE_SAMPLES: usize = 4096;

/// One random body pair.
struct Case {
    kind: &'static str,
    a: Spline,
    rugosity_a: Rugosity,
    pose_a: Pose,
    b: Spline,
    rugosity_b: Rugosity,
    pose_b: Pose,
}

impl Case {
    fn size(&self) -> f64 {
        self.a.extent().max(self.b.extent())
    }
}

fn random_generator(rng: &mut StdRng, radius: f64) -> Generator {
    match rng.random_range(0..7) {
        0 => Generator::Circle { radius },
        1 => Generator::Ellipse { a: radius, b: radius * rng.random_range(0.3..1.0) },
        2 => {
            let (width, height) = (2.0 * radius, 2.0 * radius * rng.random_range(0.3..1.0));
            Generator::RoundedRectangle { width, height, corner_radius: rng.random_range(0.05..0.5) * height }
        }
        3 => Generator::Superellipse {
            a: radius,
            b: radius * rng.random_range(0.4..1.0),
            exponent: rng.random_range(1.5..6.0),
        },
        4 => Generator::Gear { radius, teeth: rng.random_range(3..9), depth: rng.random_range(0.05..0.3) },
        _ => Generator::Blob { radius, roughness: rng.random_range(0.0..0.95), seed: rng.random_range(0..u64::MAX) },
    }
}

fn random_shape(rng: &mut StdRng, radius: f64) -> Spline {
    loop {
        let segments = rng.random_range(8..=32);
        if let Ok(spline) = random_generator(rng, radius).build(segments) {
            return spline;
        }
    }
}

fn random_rugosity(rng: &mut StdRng, segments: usize, size: f64) -> Rugosity {
    match rng.random_range(0..4) {
        0 => Rugosity::constant(segments, 0.0),
        1 => Rugosity::constant(segments, rng.random_range(0.0..0.03) * size),
        _ => Rugosity::new((0..segments).map(|_| rng.random_range(0.0..0.03) * size).collect()),
    }
    .unwrap()
}

/// World position and outward normal of a body at global parameter `u`.
fn frame_at(spline: &Spline, pose: &Pose, u: f64) -> (DVec2, DVec2) {
    (pose.transform_point(spline.position(u)), pose.rotate(spline.outward_normal(u)))
}

/// A parameter in a concave stretch of `spline` if it has one (curvature `p' × p'' < 0`).
fn concave_parameter(rng: &mut StdRng, spline: &Spline) -> f64 {
    let n = spline.segment_count() as f64;
    let concave: Vec<f64> = (0..512)
        .map(|k| n * k as f64 / 512.0)
        .filter(|&u| spline.derivative(u).perp_dot(spline.second_derivative(u)) < 0.0)
        .collect();
    if concave.is_empty() { rng.random_range(0.0..n) } else { concave[rng.random_range(0..concave.len())] }
}

/// Gap between the bodies at the touching points of a tangential placement.
fn random_gap(rng: &mut StdRng, band: f64, size: f64) -> f64 {
    match rng.random_range(0..8) {
        0 => 0.0,
        1 => 1e-12 * size * if rng.random_bool(0.5) { 1.0 } else { -1.0 },
        2 => 1e-8 * size * if rng.random_bool(0.5) { 1.0 } else { -1.0 },
        3 => band * (1.0 + 1e-6 * rng.random_range(-1.0..1.0)),
        _ => band * rng.random_range(-0.5..2.0),
    }
}

fn make_case(index: u64) -> Case {
    let mut rng = StdRng::seed_from_u64(BASE_SEED ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let radius_a = rng.random_range(0.3..1.5);
    let kind = ["random", "tangential", "tangential", "concave"][rng.random_range(0..4)];
    let radius_b = if kind == "concave" { radius_a * rng.random_range(0.05..0.3) } else { rng.random_range(0.3..1.5) };
    let a = random_shape(&mut rng, radius_a);
    let b = random_shape(&mut rng, radius_b);
    let size = a.extent().max(b.extent());
    let rugosity_a = random_rugosity(&mut rng, a.segment_count(), size);
    let rugosity_b = random_rugosity(&mut rng, b.segment_count(), size);
    let pose_a =
        Pose::new(DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)), rng.random_range(0.0..TAU));
    let pose_b = if kind == "random" {
        let reach = a.extent() + b.extent();
        let offset = DVec2::new(rng.random_range(-0.6..0.6), rng.random_range(-0.6..0.6)) * reach;
        Pose::new(pose_a.position + offset, rng.random_range(0.0..TAU))
    } else {
        let u_a = if kind == "concave" {
            concave_parameter(&mut rng, &a)
        } else {
            rng.random_range(0.0..a.segment_count() as f64)
        };
        let u_b = rng.random_range(0.0..b.segment_count() as f64);
        let (x_a, n_a) = frame_at(&a, &pose_a, u_a);
        let (x_b, n_b) = (b.position(u_b), b.outward_normal(u_b));
        // Rotate B so its normal at u_b opposes A's, then touch at x_a moved out by the gap.
        let angle = (-n_a).to_angle() - n_b.to_angle();
        let band = QuerySettings::default().min_band.max(rugosity_a.tolerance_at(u_a))
            + QuerySettings::default().min_band.max(rugosity_b.tolerance_at(u_b));
        let gap = random_gap(&mut rng, band, size);
        let rotation = DVec2::from_angle(angle);
        Pose::new(x_a + gap * n_a - rotation.rotate(x_b), angle)
    };
    Case { kind, a, rugosity_a, pose_a, b, rugosity_b, pose_b }
}

// ---------------------------------------------------------------------------------------------
// Reference.

/// Reference nearest points of a leaf pair.
#[derive(Clone, Copy, Debug)]
struct Reference {
    t: f64,
    s: f64,
    distance: f64,
}

/// Distance from `p(t)` to the whole piece `b`, `(s, distance)`: the global minimum over `s`
/// from 33 samples, each bracketed slope sign change refined by bisection-safeguarded Newton.
fn distance_to_piece(a: &CubicSegment, b: &CubicSegment, t: f64) -> (f64, f64) {
    const SAMPLES: usize = 32;
    let x = a.position(t);
    let slope = |s: f64| (b.position(s) - x).dot(b.derivative(s));
    let distance = |s: f64| b.position(s).distance(x);
    let mut best = (0.0, distance(0.0));
    let end = distance(1.0);
    if end < best.1 {
        best = (1.0, end);
    }
    for k in 0..SAMPLES {
        let (mut low, mut high) = (k as f64 / SAMPLES as f64, (k + 1) as f64 / SAMPLES as f64);
        if !(slope(low) < 0.0 && slope(high) >= 0.0) {
            continue;
        }
        // Bisection safeguarding Newton on the slope: stops when the bracket stops shrinking.
        let mut s = 0.5 * (low + high);
        for _ in 0..100 {
            let f = slope(s);
            if f < 0.0 {
                low = s
            } else {
                high = s
            }
            let [p, d, dd] = b.jet(s);
            let newton = s - f / (d.length_squared() + (p - x).dot(dd));
            let next = if newton > low && newton < high { newton } else { 0.5 * (low + high) };
            if next == s || high - low <= 1e-16 {
                break;
            }
            s = next;
        }
        for s in [low, high] {
            if distance(s) < best.1 {
                best = (s, distance(s));
            }
        }
    }
    best
}

/// Golden-section minimisation of `t ↦ distance_to_piece` on `[low, high]`.
fn golden_section(a: &CubicSegment, b: &CubicSegment, mut low: f64, mut high: f64) -> f64 {
    const INVERSE_PHI: f64 = 0.618_033_988_749_894_9;
    let f = |t: f64| distance_to_piece(a, b, t).1;
    let mut x1 = high - INVERSE_PHI * (high - low);
    let mut x2 = low + INVERSE_PHI * (high - low);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..64 {
        if f1 <= f2 {
            high = x2;
            (x2, f2) = (x1, f1);
            x1 = high - INVERSE_PHI * (high - low);
            f1 = f(x1);
        } else {
            low = x1;
            (x1, f1) = (x2, f2);
            x2 = low + INVERSE_PHI * (high - low);
            f2 = f(x2);
        }
    }
    if f1 <= f2 { x1 } else { x2 }
}

const GRID: usize = 128;

/// Global minimum of `f(t) = min_s |p(t) − q(s)|`: sampled at 129 values of `t` (each an exact
/// point-to-piece distance), every sampled local minimum refined by golden section.
fn reference_leaf(a: &CubicSegment, b: &CubicSegment) -> Reference {
    let samples: Vec<(f64, f64)> = (0..=GRID).map(|k| distance_to_piece(a, b, k as f64 / GRID as f64)).collect();
    let mut best = Reference { t: 0.0, s: 0.0, distance: f64::INFINITY };
    let mut consider = |t: f64| {
        let (s, d) = distance_to_piece(a, b, t);
        if d < best.distance {
            best = Reference { t, s, distance: d };
        }
    };
    for k in 0..=GRID {
        let v = samples[k].1;
        let left = if k > 0 { samples[k - 1].1 } else { f64::INFINITY };
        let right = if k < GRID { samples[k + 1].1 } else { f64::INFINITY };
        if v <= left && v <= right {
            consider(k as f64 / GRID as f64);
            let low = k.saturating_sub(1) as f64 / GRID as f64;
            let high = (k + 1).min(GRID) as f64 / GRID as f64;
            consider(golden_section(a, b, low, high));
        }
    }
    best
}

/// Global minimum distance between the two whole curves sampled at `DENSE_SAMPLES` points each,
/// with blocks of 64 consecutive samples pruned by their bounding boxes.
fn dense_sampled_minimum(a: &[DVec2], b: &[DVec2]) -> f64 {
    const BLOCK: usize = 64;
    let boxes = |points: &[DVec2]| -> Vec<(DVec2, DVec2)> {
        points
            .chunks(BLOCK)
            .map(|c| {
                c.iter().fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(l, h), p| {
                    (l.min(*p), h.max(*p))
                })
            })
            .collect()
    };
    let (boxes_a, boxes_b) = (boxes(a), boxes(b));
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(boxes_a.len() * boxes_b.len());
    for (i, (la, ha)) in boxes_a.iter().enumerate() {
        for (j, (lb, hb)) in boxes_b.iter().enumerate() {
            pairs.push(((*la - *hb).max(*lb - *ha).max(DVec2::ZERO).length_squared(), i, j));
        }
    }
    pairs.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut best = f64::INFINITY; // squared
    for (gap, i, j) in pairs {
        if gap >= best {
            break;
        }
        for p in &a[i * BLOCK..((i + 1) * BLOCK).min(a.len())] {
            for q in &b[j * BLOCK..((j + 1) * BLOCK).min(b.len())] {
                best = best.min(p.distance_squared(*q));
            }
        }
    }
    best.sqrt()
}

fn dense_samples(spline: &Spline, pose: &Pose) -> Vec<DVec2> {
    let n = spline.segment_count() as f64;
    (0..DENSE_SAMPLES).map(|k| pose.transform_point(spline.position(n * k as f64 / DENSE_SAMPLES as f64))).collect()
}

// ---------------------------------------------------------------------------------------------
// Comparison.

#[derive(Debug, Default)]
struct Stats {
    cases: usize,
    leaf_pairs_checked: usize,
    intersecting_leaves: usize,
    contact_leaves: usize,
    contact_newton_iterations: u64,
    alternative_minimisers: usize,
    reference_improved_by_solver: usize,
    body_states: [usize; 3],
    worst_distance_error: f64,
    worst_dense_excess: f64,
    reference_time: std::time::Duration,
    solver_time: std::time::Duration,
    body_query_time: std::time::Duration,
    generation_time: std::time::Duration,
    dense_time: std::time::Duration,
}

/// The largest combined band of two bodies: no leaf pair farther apart can be in contact.
fn reach(case: &Case) -> f64 {
    let min_band = QuerySettings::default().min_band;
    case.rugosity_a.max_tolerance().max(min_band) + case.rugosity_b.max_tolerance().max(min_band) + 1e-9
}

/// Checks one leaf pair; returns the reference (for the body-level checks) or a failure message.
fn check_leaf(a: &TolerancedSegment, b: &TolerancedSegment, size: f64, stats: &mut Stats) -> Result<Reference, String> {
    let tolerance = RELATIVE_TOLERANCE * size;
    let clock = std::time::Instant::now();
    let reference = reference_leaf(&a.segment, &b.segment);
    stats.reference_time += clock.elapsed();
    let clock = std::time::Instant::now();
    let query = query_segment_segment(a, b, Orientation::CounterClockwise, &CurvePairSettings::default());
    stats.solver_time += clock.elapsed();
    // The solver's nearest points are real points: where they are nearer than the reference,
    // the reference missed a minimum (a sampling limit), and they become the reference.
    let mut reference = reference;
    if let Some(c) = query.closest.filter(|c| c.distance < reference.distance - RELATIVE_TOLERANCE * size) {
        stats.reference_improved_by_solver += 1;
        reference = Reference { t: c.t, s: c.s, distance: c.distance };
    }
    let band_ref = a.tolerance.at(reference.t) + b.tolerance.at(reference.s);
    let cutoff = a.tolerance.max + b.tolerance.max;
    stats.leaf_pairs_checked += 1;
    if let Some(c) = query.closest.filter(|c| c.distance <= cutoff) {
        let error = c.distance - reference.distance;
        stats.worst_distance_error = stats.worst_distance_error.max(error.abs());
        if error.abs() > tolerance {
            return Err(format!("distance {} vs reference {reference:?} (error {error:.3e})", c.distance));
        }
    } else if reference.distance <= cutoff - tolerance {
        return Err(format!("pruned as separate but the reference {reference:?} is within the cutoff {cutoff}"));
    }
    // The bounds conservative advancement relies on never exceed the distance: a projection
    // gap along any axis is at most the distance, and so is the search's lower bound.
    for (axis, gap) in separating_axes(&a.segment, &b.segment) {
        if gap > reference.distance + tolerance {
            return Err(format!("gap {gap} along {axis} above the reference {reference:?}"));
        }
    }
    if matches!(query.state, SegmentPairState::Separate) && query.distance_lower_bound > reference.distance + tolerance
    {
        return Err(format!("distance lower bound {} above the reference {reference:?}", query.distance_lower_bound));
    }
    match query.state {
        SegmentPairState::Intersecting { .. } => {
            stats.intersecting_leaves += 1;
            if reference.distance > tolerance {
                return Err(format!("invented intersection: reference {reference:?}"));
            }
        }
        SegmentPairState::Contact => {
            stats.contact_leaves += 1;
            stats.contact_newton_iterations += u64::from(query.newton_iterations);
            if reference.distance <= 1e-14 * size {
                return Err(format!("missed intersection: reported contact, reference {reference:?}"));
            }
            if reference.distance > band_ref + tolerance {
                // Allowed only when the solver's point is another global minimiser.
                stats.alternative_minimisers += 1;
            }
            for contact in query.contacts.as_slice() {
                if contact.distance < reference.distance - tolerance
                    || contact.penetration < 0.0
                    || !contact.normal.is_finite()
                {
                    return Err(format!("bad contact {contact:?} vs reference {reference:?}"));
                }
            }
        }
        SegmentPairState::Separate => {
            if reference.distance <= 1e-14 * size {
                return Err(format!("missed intersection: reference {reference:?}"));
            }
            let alternative = query.closest.is_some_and(|c| (c.distance - reference.distance).abs() <= tolerance);
            if reference.distance < band_ref - tolerance && !alternative {
                return Err(format!("missed contact: reference {reference:?}, band {band_ref}"));
            }
        }
    }
    Ok(reference)
}

fn world_segments(shape: &BodyShape<'_>, pose: &Pose, min_band: f64) -> Vec<TolerancedSegment> {
    (0..shape.spline.segment_count()).map(|i| shape.world_segment(i, pose, min_band)).collect()
}

fn check_case(index: u64, stats: &mut Stats, query: &mut BodyQuery) -> Result<(), String> {
    let clock = std::time::Instant::now();
    let case = make_case(index);
    stats.generation_time += clock.elapsed();
    let settings = QuerySettings::default();
    let size = case.size();
    let tolerance = RELATIVE_TOLERANCE * size;
    let shape_a = BodyShape::new(&case.a, &case.rugosity_a);
    let shape_b = BodyShape::new(&case.b, &case.rugosity_b);
    let leaves_a = world_segments(&shape_a, &case.pose_a, settings.min_band);
    let leaves_b = world_segments(&shape_b, &case.pose_b, settings.min_band);
    let mut references = Vec::new();
    let bounds_a: Vec<_> = leaves_a.iter().map(|l| l.segment.bounds()).collect();
    let bounds_b: Vec<_> = leaves_b.iter().map(|l| l.segment.bounds()).collect();
    let reach = reach(&case);
    for (i, la) in leaves_a.iter().enumerate() {
        for (j, lb) in leaves_b.iter().enumerate() {
            let ((low_a, high_a), (low_b, high_b)) = (bounds_a[i], bounds_b[j]);
            if (low_a - high_b).max(low_b - high_a).max_element() <= reach {
                let reference = check_leaf(la, lb, size, stats).map_err(|e| format!("leaf ({i}, {j}): {e}"))?;
                references.push((i, j, reference, la.tolerance.at(reference.t) + lb.tolerance.at(reference.s)));
            }
        }
    }
    // The public query: both AOBB trees descended, overlapping leaves solved.
    let tree_a = AobbTree::build(&case.a, &case.rugosity_a, settings.min_band);
    let tree_b = AobbTree::build(&case.b, &case.rugosity_b, settings.min_band);
    let clock = std::time::Instant::now();
    let manifold = query_bodies(&shape_a, &tree_a, &case.pose_a, &shape_b, &tree_b, &case.pose_b, &settings, query);
    stats.body_query_time += clock.elapsed();
    stats.body_states[manifold.state as usize] += 1;
    check_body(manifold, &references, size, tolerance)?;
    check_dense(&case, &references, size, stats)
}

fn check_body(
    manifold: &Manifold,
    references: &[(usize, usize, Reference, f64)],
    size: f64,
    tolerance: f64,
) -> Result<(), String> {
    let nearest = references.iter().min_by(|x, y| x.2.distance.total_cmp(&y.2.distance));
    let must_intersect = nearest.is_some_and(|r| r.2.distance <= 1e-14 * size);
    let may_intersect = nearest.is_some_and(|r| r.2.distance <= tolerance);
    match manifold.state {
        PairState::Intersecting if !may_intersect => {
            return Err(format!("body: invented intersection, nearest {nearest:?}"));
        }
        PairState::Contact | PairState::Separate if must_intersect => {
            return Err(format!("body: missed intersection {nearest:?}"));
        }
        _ => {}
    }
    if manifold.state == PairState::Intersecting {
        return Ok(());
    }
    if let Some(&(i, j, r, band)) = nearest.filter(|r| r.2.distance < r.3 - tolerance) {
        let found = manifold.contacts.iter().map(|c| c.contact.distance).fold(f64::INFINITY, f64::min);
        // A conformal leaf reports the ends of its overlap, which may lie higher in the valley.
        let conformal_slack = CurvePairSettings::default().conformal_fraction * band;
        if found < r.distance - tolerance || found > r.distance + tolerance + conformal_slack {
            return Err(format!("body: deepest contact at distance {found}, reference ({i}, {j}) {r:?} band {band}"));
        }
    }
    for c in &manifold.contacts {
        let leaf = references.iter().find(|r| r.0 == c.segment_a as usize && r.1 == c.segment_b as usize);
        match leaf {
            Some(r) if c.contact.distance >= r.2.distance - tolerance => {}
            _ => return Err(format!("body: contact {c:?} has no reference leaf below it: {leaf:?}")),
        }
    }
    Ok(())
}

/// The reference minimum (which the solver matches leaf by leaf) never exceeds the minimum of
/// 4096 dense samples per curve when that sampled minimum lies within reach of a band.
fn check_dense(
    case: &Case,
    references: &[(usize, usize, Reference, f64)],
    size: f64,
    stats: &mut Stats,
) -> Result<(), String> {
    let clock = std::time::Instant::now();
    let sampled = dense_sampled_minimum(&dense_samples(&case.a, &case.pose_a), &dense_samples(&case.b, &case.pose_b));
    stats.dense_time += clock.elapsed();
    let reference = references.iter().map(|r| r.2.distance).fold(f64::INFINITY, f64::min);
    if sampled <= reach(case) {
        let excess = reference - sampled;
        stats.worst_dense_excess = stats.worst_dense_excess.max(excess);
        if excess > 1e-12 * size {
            return Err(format!("dense samples reach {sampled} below the reference minimum {reference}"));
        }
    }
    Ok(())
}

fn run_cases(count: u64) {
    let only: Option<u64> = std::env::var("RUGOSA_CASE").ok().and_then(|v| v.parse().ok());
    let mut stats = Stats::default();
    let mut query = BodyQuery::default();
    let started = std::time::Instant::now();
    for index in (0..count).filter(|i| only.is_none_or(|o| o == *i)) {
        if let Err(message) = check_case(index, &mut stats, &mut query) {
            let case = make_case(index);
            panic!(
                "case {index} ({}, seed {BASE_SEED:#x} ^ {index} * golden): {message}\n  rerun: RUGOSA_CASE={index} cargo test --test query_brute_force -- --nocapture",
                case.kind
            );
        }
        stats.cases += 1;
    }
    let mean = stats.contact_newton_iterations as f64 / stats.contact_leaves.max(1) as f64;
    eprintln!("{stats:#?}\nmean Newton iterations per contact leaf: {mean:.2}\nelapsed: {:?}", started.elapsed());
}

/// The full 10,000-case run (about 35 s in the test profile on the 2-core machine); statistics
/// with `cargo test --test query_brute_force -- --nocapture`.
#[test]
fn ten_thousand_random_pairs_match_the_brute_force_reference() {
    run_cases(10_000);
}
