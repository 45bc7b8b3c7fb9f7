//! Scene queries against brute force on seeded random scenes: ray casts (first hit and all
//! hits) against dense sampling of every boundary; point containment against the winding
//! number of a polyline of 64 points per segment (within 2e-7 m of the curves here; points
//! within 1e-3 m of a boundary are skipped); nearest points against
//! every body's exact nearest point; box queries against sampled boundaries.
//! Statistics: `cargo test --test queries -- --nocapture`.

use std::f64::consts::TAU;

use glam::DVec2;
use hecs::Entity;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rugosa::{
    BodyDesc, CubicSegment, Generator, QueryFilter, RigidState, Rugosity, Simulation, SimulationSettings, Spline,
};

const SCENES: u64 = 150;
const RAYS: usize = 20;
/// Samples per segment of the brute-force ray reference.
const SAMPLES: usize = 1024;

fn random_shape(rng: &mut StdRng) -> Spline {
    let radius = rng.random_range(0.2..0.8);
    loop {
        let generator = match rng.random_range(0..5) {
            0 => Generator::Circle { radius },
            1 => Generator::Ellipse { a: radius, b: radius * rng.random_range(0.3..1.0) },
            2 => Generator::RoundedRectangle {
                width: 2.0 * radius,
                height: radius * rng.random_range(0.5..2.0),
                corner_radius: 0.1 * radius,
            },
            3 => Generator::Gear { radius, teeth: rng.random_range(3..9), depth: rng.random_range(0.05..0.3) },
            _ => Generator::Blob { radius, roughness: rng.random_range(0.0..0.9), seed: rng.random_range(0..u64::MAX) },
        };
        if let Ok(spline) = generator.build(rng.random_range(24..=40)) {
            return spline;
        }
    }
}

/// A scene of eight fixed bodies in a 6 m square (they may overlap: queries do not care).
fn scene(rng: &mut StdRng) -> (Simulation, Vec<Entity>) {
    let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    let mut bodies = Vec::new();
    for _ in 0..8 {
        let spline = random_shape(rng);
        let rugosity = Rugosity::constant(spline.segment_count(), 0.002).unwrap();
        let at = DVec2::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
        let desc = BodyDesc::new(spline, rugosity).at(at, rng.random_range(0.0..TAU)).fixed();
        bodies.push(sim.add_body(desc).unwrap());
    }
    (sim, bodies)
}

/// A body's boundary pieces in the world.
fn world_pieces(sim: &Simulation, body: Entity) -> Vec<CubicSegment> {
    let pose = sim.world().get::<&RigidState>(body).unwrap().pose();
    let spline = sim.world().get::<&Spline>(body).unwrap();
    spline.segments().map(|s| CubicSegment { bezier: s.bezier.map(|p| pose.transform_point(p)) }).collect()
}

/// Brute force: every crossing distance of the ray with every body, from sign changes of the
/// signed distance to the ray's line at `SAMPLES` points per segment, refined by bisection.
fn reference_hits(sim: &Simulation, bodies: &[Entity], origin: DVec2, d: DVec2, max: f64) -> Vec<(f64, Entity)> {
    let mut hits = Vec::new();
    for &body in bodies {
        for piece in world_pieces(sim, body) {
            let g = |s: f64| (piece.position(s) - origin).perp_dot(d);
            let mut previous = (0.0, g(0.0));
            for k in 1..=SAMPLES {
                let s = k as f64 / SAMPLES as f64;
                let value = g(s);
                if (previous.1 < 0.0) != (value < 0.0) {
                    let (mut a, mut b) = (previous.0, s);
                    for _ in 0..80 {
                        let m = 0.5 * (a + b);
                        if (g(m) < 0.0) == (previous.1 < 0.0) { a = m } else { b = m }
                    }
                    let tau = (piece.position(0.5 * (a + b)) - origin).dot(d);
                    if (0.0..=max).contains(&tau) {
                        hits.push((tau, body));
                    }
                }
                previous = (s, value);
            }
        }
    }
    hits.sort_by(|x, y| x.0.total_cmp(&y.0));
    hits
}

#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    hits: usize,
    grazes_found_only_exactly: usize,
    worst_distance_error: f64,
    worst_normal_error: f64,
}

#[test]
fn ray_casts_match_brute_force() {
    let mut tally = Tally::default();
    let tolerance = 1e-9; // m, in a scene a few metres across
    for index in 0..SCENES {
        let mut rng = StdRng::seed_from_u64(0x5ca7_7e4e ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let (sim, bodies) = scene(&mut rng);
        for _ in 0..RAYS {
            let origin = DVec2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0));
            // Aimed at a random point of the scene's square, so that most rays meet something.
            let target = DVec2::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
            let direction = (target - origin).normalize_or(DVec2::X);
            let max = rng.random_range(1.0..12.0);
            let context = format!("scene {index}, ray from {origin} along {direction} to {max}");
            let reference = reference_hits(&sim, &bodies, origin, direction, max);
            let mut all = Vec::new();
            sim.cast_ray_all(origin, direction, max, &QueryFilter::default(), &mut all);
            let first = sim.cast_ray(origin, direction, max, &QueryFilter::default());
            assert_eq!(first.map(|h| h.distance), all.first().map(|h| h.distance), "{context}");
            // Every crossing the sampling found is found exactly, at the same distance.
            for &(tau, body) in &reference {
                let nearest = all
                    .iter()
                    .filter(|h| h.body == body)
                    .map(|h| (h.distance - tau).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(nearest <= tolerance, "{context}: reference crossing at {tau} of {body:?} missed ({nearest})");
                tally.worst_distance_error = tally.worst_distance_error.max(nearest);
            }
            // Every exact crossing lies on the ray and on the curve, with the curve's normal;
            // the ones the sampling missed are grazes (two roots closer than its spacing).
            for hit in &all {
                let pose = sim.world().get::<&RigidState>(hit.body).unwrap().pose();
                let spline = sim.world().get::<&Spline>(hit.body).unwrap();
                let u = hit.segment as f64 + hit.parameter;
                let on_curve = pose.transform_point(spline.position(u));
                assert!(on_curve.distance(hit.point) <= tolerance, "{context}: {hit:?} is {on_curve} on the curve");
                let normal = pose.rotate(spline.outward_normal(u));
                tally.worst_normal_error = tally.worst_normal_error.max(normal.distance(hit.normal));
                assert!(normal.distance(hit.normal) <= 1e-9, "{context}: normal {} against {normal}", hit.normal);
                assert_eq!(hit.entering, hit.normal.dot(direction) < 0.0, "{context}: {hit:?}");
                let matched =
                    reference.iter().any(|&(tau, body)| body == hit.body && (tau - hit.distance).abs() <= tolerance);
                tally.grazes_found_only_exactly += usize::from(!matched);
            }
            tally.rays += 1;
            tally.hits += usize::from(first.is_some());
            // Leaving the first body out finds the next one, never it again.
            if let Some(hit) = first {
                let filter = QueryFilter { exclude: Some(hit.body), ..QueryFilter::default() };
                let next = sim.cast_ray(origin, direction, max, &filter);
                assert!(next.is_none_or(|n| n.body != hit.body && n.distance >= hit.distance), "{context}");
            }
        }
    }
    println!("{tally:?}");
    assert!(tally.hits * 2 > tally.rays, "too few rays hit anything: {tally:?}");
}

/// Distance from `point` to the boundary of `body` (exact nearest point).
fn boundary_distance(sim: &Simulation, body: Entity, point: DVec2) -> f64 {
    let pose = sim.world().get::<&RigidState>(body).unwrap().pose();
    let spline = sim.world().get::<&Spline>(body).unwrap();
    spline.nearest_point(pose.inverse_transform_point(point)).distance
}

#[test]
fn point_queries_match_brute_force() {
    let (mut checked, mut inside) = (0, 0);
    for index in 0..SCENES {
        let mut rng = StdRng::seed_from_u64(0x9017 ^ index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let (sim, bodies) = scene(&mut rng);
        for _ in 0..RAYS {
            let point = DVec2::new(rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0));
            // Containment against the winding number of a fine polyline, away from boundaries.
            let distances: Vec<f64> = bodies.iter().map(|&b| boundary_distance(&sim, b, point)).collect();
            if distances.iter().all(|&d| d > 1e-3) {
                let expected: Vec<Entity> = bodies
                    .iter()
                    .filter(|&&b| {
                        let pose = sim.world().get::<&RigidState>(b).unwrap().pose();
                        let spline = sim.world().get::<&Spline>(b).unwrap();
                        polyline_winding(&spline, pose.inverse_transform_point(point)) != 0
                    })
                    .copied()
                    .collect();
                assert_eq!(sim.bodies_containing(point, &QueryFilter::default()), expected, "scene {index}, {point}");
                checked += 1;
                inside += usize::from(!expected.is_empty());
            }
            // The nearest boundary within a distance, against every body's exact nearest point.
            let max = rng.random_range(0.1..3.0);
            let nearest = bodies.iter().zip(&distances).filter(|(_, d)| **d <= max).min_by(|a, b| a.1.total_cmp(b.1));
            let got = sim.project_point(point, max, &QueryFilter::default());
            match (nearest, got) {
                (None, None) => {}
                (Some((_, &d)), Some(p)) => {
                    assert!((p.distance - d).abs() <= 1e-12, "scene {index}, {point}: {p:?} against {d}");
                    assert!((p.point.distance(point) - p.distance).abs() <= 1e-12);
                }
                other => panic!("scene {index}, {point}: {other:?}"),
            }
            // A box query returns every body with a boundary point in the box.
            let half = DVec2::new(rng.random_range(0.05..1.0), rng.random_range(0.05..1.0));
            let found = sim.bodies_in_aabb(point - half, point + half, &QueryFilter::default());
            for &body in &bodies {
                let touches = world_pieces(&sim, body).iter().any(|piece| {
                    (0..=32).any(|k| {
                        let p = piece.position(k as f64 / 32.0);
                        p.cmpge(point - half).all() && p.cmple(point + half).all()
                    })
                });
                assert!(!touches || found.contains(&body), "scene {index}: box at {point} misses {body:?}");
            }
        }
    }
    println!("containment checked at {checked} points, {inside} inside a body");
    assert!(checked > 1000 && inside > 100, "{checked}, {inside}");
}

/// Winding number of the polyline through 64 points per segment (the exact one is what the
/// queries use).
fn polyline_winding(spline: &Spline, point: DVec2) -> i32 {
    let points: Vec<DVec2> =
        (0..spline.segment_count() * 64).map(|k| spline.position(k as f64 / 64.0) - point).collect();
    let mut winding = 0;
    for (k, &previous) in points.iter().enumerate() {
        let current = points[(k + 1) % points.len()];
        if previous.y <= 0.0 && current.y > 0.0 && previous.perp_dot(current) > 0.0 {
            winding += 1;
        } else if previous.y > 0.0 && current.y <= 0.0 && previous.perp_dot(current) < 0.0 {
            winding -= 1;
        }
    }
    winding
}

#[test]
fn filters_leave_out_what_they_name() {
    let mut rng = StdRng::seed_from_u64(11);
    let (sim, bodies) = scene(&mut rng);
    let all = QueryFilter::default();
    let none_fixed = QueryFilter { exclude_fixed: true, ..all };
    // Every body of the scene is fixed.
    assert!(sim.bodies_in_aabb(DVec2::splat(-10.0), DVec2::splat(10.0), &none_fixed).is_empty());
    assert_eq!(sim.bodies_in_aabb(DVec2::splat(-10.0), DVec2::splat(10.0), &all).len(), bodies.len());
    assert!(sim.cast_ray(DVec2::ZERO, DVec2::ZERO, 1.0, &all).is_none(), "a zero direction casts nothing");
    assert!(sim.cast_ray(DVec2::ZERO, DVec2::X, f64::NAN, &all).is_none(), "a NaN distance casts nothing");
}
