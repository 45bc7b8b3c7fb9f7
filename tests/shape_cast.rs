//! Shape casts against brute force: the time of first approach found by conservative
//! advancement against a dense scan of the same motion.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rugosa::glam::DVec2;
use rugosa::{BodyDesc, Generator, QueryFilter, Rugosity, ShapeCast, Simulation, SimulationSettings, Spline};

fn body(generator: Generator, segments: usize) -> BodyDesc {
    let spline = generator.build(segments).unwrap();
    BodyDesc::new(spline, Rugosity::constant(segments, 0.0).unwrap())
}

/// Distance between two closed curves: from dense samples of the first to the exact nearest
/// point of the second (an upper bound of the true distance, above it by at most the first
/// curve's chord error between samples, a few 1e-6 m for these sizes).
fn sampled_distance(a: &Spline, pose_a: (DVec2, f64), b: &Spline, pose_b: (DVec2, f64)) -> f64 {
    let n = a.segment_count() * 64;
    (0..n)
        .map(|k| {
            let p = pose_a.0
                + DVec2::from_angle(pose_a.1).rotate(a.position(k as f64 * a.segment_count() as f64 / n as f64));
            let local = DVec2::from_angle(-pose_b.1).rotate(p - pose_b.0);
            b.nearest_point(local).distance
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_disc_cast_at_a_wall_stops_where_the_gap_closes() {
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let mover = sim.add_body(body(Generator::Circle { radius: 0.5 }, 32).at(DVec2::ZERO, 0.0)).unwrap();
    let wall = Generator::RoundedRectangle { width: 1.0, height: 4.0, corner_radius: 0.1 };
    let wall = sim.add_body(body(wall, 24).at(DVec2::new(3.0, 0.0), 0.0).fixed()).unwrap();
    let filter = QueryFilter::default();
    for target in [0.0, 0.01] {
        let cast = ShapeCast { linear_velocity: DVec2::new(4.0, 0.0), target_distance: target, ..ShapeCast::default() };
        let hit = sim.cast_shape(mover, &cast, &filter).unwrap().expect("a hit");
        assert_eq!(hit.body, wall);
        // The wall's left face is the line x = 2.5; the disc's curve reaches x = 0.5 (its
        // 32-segment spline is within 2e-6 of the circle): the gap is 2 m, closed at 4 m/s.
        let expected = (2.0 - target) / 4.0;
        assert!((hit.time - expected).abs() < 1e-6, "target {target}: time {} against {expected}", hit.time);
        assert!((hit.distance - target).abs() < 1e-8);
        assert!((hit.point.x - 2.5).abs() < 1e-9 && (hit.normal + DVec2::X).length() < 1e-9, "{hit:?}");
    }
    // Moving away, or not far enough, meets nothing; a bad argument is a typed error.
    let away = ShapeCast { linear_velocity: DVec2::new(-4.0, 0.0), ..ShapeCast::default() };
    assert!(sim.cast_shape(mover, &away, &filter).unwrap().is_none());
    let short = ShapeCast { linear_velocity: DVec2::new(4.0, 0.0), max_time: 0.4, ..ShapeCast::default() };
    assert!(sim.cast_shape(mover, &short, &filter).unwrap().is_none());
    let bad = ShapeCast { max_time: f64::NAN, ..ShapeCast::default() };
    let err = sim.cast_shape(mover, &bad, &filter).unwrap_err();
    assert!(err.to_string().contains("max_time"), "{err}");
    // Excluding the wall leaves nothing to meet.
    let cast = ShapeCast { linear_velocity: DVec2::new(4.0, 0.0), ..ShapeCast::default() };
    let without = QueryFilter { exclude: Some(wall), ..QueryFilter::default() };
    assert!(sim.cast_shape(mover, &cast, &without).unwrap().is_none());
}

#[test]
fn casts_of_turning_shapes_match_a_dense_scan_of_the_motion() {
    // Random shapes and motions, translating and turning: the cast's time is the first time
    // the sampled distance falls to the target (scanned at 2000 steps of the motion, refined by
    // bisection), to within what the sampling resolves.
    let mut rng = StdRng::seed_from_u64(0x5ca57);
    let shapes = [
        Generator::Ellipse { a: 0.6, b: 0.25 },
        Generator::RoundedRectangle { width: 0.8, height: 0.4, corner_radius: 0.05 },
        Generator::Blob { radius: 0.4, roughness: 0.5, seed: 7 },
        Generator::Gear { radius: 0.4, teeth: 6, depth: 0.2 },
    ];
    let mut hits = 0;
    for case in 0..24 {
        let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
        let a = shapes[case % 4].clone();
        let b = shapes[(case / 4) % 4].clone();
        let mover = sim.add_body(body(a, 24).at(DVec2::ZERO, rng.random_range(0.0..std::f64::consts::TAU))).unwrap();
        let other = sim
            .add_body(
                body(b, 24)
                    .at(DVec2::new(2.5, rng.random_range(-0.5..0.5)), rng.random_range(0.0..std::f64::consts::TAU))
                    .fixed(),
            )
            .unwrap();
        let cast = ShapeCast {
            linear_velocity: DVec2::new(rng.random_range(1.0..3.0), rng.random_range(-0.5..0.5)),
            angular_velocity: rng.random_range(-3.0..3.0),
            max_time: 2.0,
            target_distance: 0.0,
        };
        let (sa, sb) = (sim.state(mover).unwrap(), sim.state(other).unwrap());
        let spline = |e| sim.world().get::<&Spline>(e).unwrap().clone();
        let (spline_a, spline_b) = (spline(mover), spline(other));
        let at = |t: f64| {
            sampled_distance(
                &spline_a,
                (sa.position + cast.linear_velocity * t, sa.angle + cast.angular_velocity * t),
                &spline_b,
                (sb.position, sb.angle),
            )
        };
        // Sampled points lie on A's curve, so the sampled distance bounds the true one from
        // above by the sampling's chord error (a few 1e-6 m): a contact within 1e-5 m.
        let resolution = 1e-5;
        let steps = 400;
        let first = (1..=steps).map(|k| cast.max_time * k as f64 / steps as f64).find(|&t| at(t) <= resolution);
        let hit = sim.cast_shape(mover, &cast, &QueryFilter::default()).unwrap();
        match (first, hit) {
            (None, None) => {}
            (first, Some(hit)) => {
                hits += 1;
                // Never late: conservative advancement only stops short of the first contact.
                assert!(
                    first.is_none_or(|t| hit.time <= t + 1e-12),
                    "case {case}: cast {} after the scan's {first:?}",
                    hit.time
                );
                // A genuine contact: the reported distance is the distance then, and it is 0. (It
                // may come before the scan's first contact, or without one: a graze between two
                // scanned times.)
                assert!((at(hit.time) - hit.distance).abs() <= resolution, "case {case}: {hit:?}");
                assert!(hit.distance <= 1e-8, "case {case}: stopped {} short of contact", hit.distance);
            }
            (Some(t), None) => panic!("case {case}: the scan meets the other body at {t}, the cast does not"),
        }
    }
    assert!(hits >= 12, "most motions meet the other body: {hits} of 24");
}
