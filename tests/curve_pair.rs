//! Degenerate inputs of the curve-pair solver and the self-intersection check.

use std::f64::consts::TAU;

use glam::DVec2;
use rugosa::{BodyShape, Manifold, PairState, QuerySettings, all_segment_pairs, query_leaf_pairs};
use rugosa::{CubicSegment, Generator, Pose, Rugosity, SegmentTolerance, ShapeError, Spline};
use rugosa::{
    CurvePairSettings, Orientation, SegmentPairState, TolerancedSegment, closest_points_segment_segment,
    intersect_segment_segment, query_segment_segment,
};
use rugosa::{find_self_intersection, validate_boundary};

fn settings() -> CurvePairSettings {
    CurvePairSettings::default()
}

/// Minimum distance between two pieces from a 2001 × 2001 grid.
fn sampled_distance(a: &CubicSegment, b: &CubicSegment) -> f64 {
    const N: usize = 2000;
    let pa: Vec<DVec2> = (0..=N).map(|k| a.position(k as f64 / N as f64)).collect();
    let pb: Vec<DVec2> = (0..=N).map(|k| b.position(k as f64 / N as f64)).collect();
    pa.iter().flat_map(|p| pb.iter().map(move |q| p.distance(*q))).fold(f64::INFINITY, f64::min)
}

fn query_bodies(a: &Spline, ra: &Rugosity, pose_a: Pose, b: &Spline, rb: &Rugosity, pose_b: Pose) -> Manifold {
    let mut pairs = Vec::new();
    all_segment_pairs(a.segment_count(), b.segment_count(), &mut pairs);
    let mut manifold = Manifold::default();
    let (shape_a, shape_b) = (BodyShape::new(a, ra), BodyShape::new(b, rb));
    query_leaf_pairs(&shape_a, &pose_a, &shape_b, &pose_b, &pairs, &QuerySettings::default(), &mut manifold);
    manifold
}

fn assert_finite(manifold: &Manifold) {
    for c in &manifold.contacts {
        let x = c.contact;
        let values = [x.t, x.s, x.distance, x.penetration, x.lambda_a, x.lambda_b, x.raw_lambda_a, x.raw_lambda_b];
        assert!(values.iter().all(|v| v.is_finite()), "{c:?}");
        assert!(x.point.is_finite() && x.point_a.is_finite() && x.point_b.is_finite(), "{c:?}");
        assert!((x.normal.length() - 1.0).abs() < 1e-12, "{c:?}");
    }
}

/// A rectangle control polygon with `per_side` collinear points on every side: straight pieces.
fn box_polygon(width: f64, height: f64, per_side: usize) -> Vec<DVec2> {
    let corners = [DVec2::new(0.0, 0.0), DVec2::new(width, 0.0), DVec2::new(width, height), DVec2::new(0.0, height)];
    let mut points = Vec::new();
    for k in 0..4 {
        let (from, to) = (corners[k], corners[(k + 1) % 4]);
        points.extend((0..per_side).map(|j| from.lerp(to, j as f64 / per_side as f64)));
    }
    points
}

// ---------------------------------------------------------------------------------------------
// Leaf level.

#[test]
fn a_point_piece_from_four_equal_control_points_has_no_nan() {
    let point = CubicSegment::from_bspline(DVec2::ONE, DVec2::ONE, DVec2::ONE, DVec2::ONE);
    let line = CubicSegment {
        bezier: [DVec2::new(-1.0, 0.0), DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(2.0, 0.0)],
    };
    let c = closest_points_segment_segment(&point, &line, &settings());
    assert!((c.distance - 1.0).abs() < 1e-14 && (c.point_b - DVec2::new(1.0, 0.0)).length() < 1e-12, "{c:?}");
    let both = closest_points_segment_segment(&point, &point, &settings());
    assert_eq!(both.distance, 0.0);
    let tol = SegmentTolerance::constant(0.0, 1e-3);
    let q = query_segment_segment(
        &TolerancedSegment { segment: point, tolerance: tol },
        &TolerancedSegment { segment: point, tolerance: tol },
        Orientation::CounterClockwise,
        &settings(),
    );
    assert!(matches!(q.state, SegmentPairState::Intersecting { .. }), "{q:?}");
}

#[test]
fn cusps_from_repeated_control_points_give_finite_exact_answers() {
    // c1 = c2 = c3: the piece starts with zero velocity (a corner of the curve).
    let cusp = CubicSegment::from_bspline(DVec2::new(0.0, 0.0), DVec2::ONE, DVec2::ONE, DVec2::ONE);
    let cusp_end = CubicSegment::from_bspline(DVec2::ONE, DVec2::ONE, DVec2::ONE, DVec2::new(3.0, 0.0));
    assert!(cusp.derivative(1.0).length() < 1e-14);
    let others = [
        CubicSegment::from_bspline(
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(1.0, 3.0),
            DVec2::new(0.0, 2.5),
        ),
        CubicSegment { bezier: [DVec2::new(0.5, 1.5); 4] },
        cusp_end,
    ];
    for other in &others {
        let c = closest_points_segment_segment(&cusp, other, &settings());
        assert!(c.distance.is_finite() && c.t.is_finite() && c.s.is_finite(), "{c:?}");
        assert!(c.distance <= sampled_distance(&cusp, other) + 1e-12, "{c:?}");
        let tol = SegmentTolerance::constant(0.01, 1e-3);
        let q = query_segment_segment(
            &TolerancedSegment { segment: cusp, tolerance: tol },
            &TolerancedSegment { segment: *other, tolerance: tol },
            Orientation::CounterClockwise,
            &settings(),
        );
        for contact in q.contacts.as_slice() {
            assert!((contact.normal.length() - 1.0).abs() < 1e-12, "{contact:?}");
        }
    }
    // The two pieces meeting at the cusp touch there.
    assert!(intersect_segment_segment(&cusp, &cusp_end, &settings()).is_some());
}

#[test]
fn straight_pieces_from_collinear_control_points() {
    let a = CubicSegment::from_bspline(
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(3.0, 0.0),
    );
    // Crossing at a shallow angle, then parallel above.
    let crossing = CubicSegment::from_bspline(
        DVec2::new(0.0, -0.01),
        DVec2::new(1.0, -0.003),
        DVec2::new(2.0, 0.004),
        DVec2::new(3.0, 0.011),
    );
    let (t, s) = intersect_segment_segment(&a, &crossing, &settings()).expect("shallow crossing");
    assert!(a.position(t).distance(crossing.position(s)) < 1e-12);
    let above = CubicSegment::from_bspline(
        DVec2::new(0.0, 0.2),
        DVec2::new(1.0, 0.2),
        DVec2::new(2.0, 0.2),
        DVec2::new(3.0, 0.2),
    );
    let c = closest_points_segment_segment(&a, &above, &settings());
    assert!((c.distance - 0.2).abs() < 1e-14, "{c:?}");
    assert!(intersect_segment_segment(&a, &above, &settings()).is_none());
}

#[test]
fn identical_pieces_on_top_of_each_other_intersect() {
    let piece =
        CubicSegment { bezier: [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, -1.0), DVec2::new(3.0, 0.0)] };
    let (t, s) = intersect_segment_segment(&piece, &piece, &settings()).unwrap();
    assert!(piece.position(t).distance(piece.position(s)) < 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Body level.

#[test]
fn parallel_flat_sides_give_a_two_point_manifold_at_the_overlap_ends() {
    let floor = Spline::from_control_points(box_polygon(4.0, 1.0, 6)).unwrap();
    let block = Spline::from_control_points(box_polygon(1.0, 1.0, 6)).unwrap();
    let rug_floor = Rugosity::constant(floor.segment_count(), 0.01).unwrap();
    let rug_block = Rugosity::constant(block.segment_count(), 0.01).unwrap();
    // The flat middle of the floor's top side is at y = 1; the block's bottom is at y = 0.
    let pose_block = Pose::new(DVec2::new(1.5, 1.015), 0.0);
    let m = query_bodies(&floor, &rug_floor, Pose::IDENTITY, &block, &rug_block, pose_block);
    assert_eq!(m.state, PairState::Contact, "{m:?}");
    assert_finite(&m);
    let xs: Vec<f64> = m.contacts.iter().map(|c| c.contact.point.x).collect();
    let (low, high) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(m.contacts.len() >= 2, "{xs:?}");
    // The block's flat bottom spans the middle of its width (the rounded B-spline corners do not).
    assert!(high - low > 0.3, "{xs:?}");
    // Overlap ends lie where the gap leaves the band (up the block's rounded corners) or where
    // the flat pieces end; every point is in the band, the flat ones at the true gap 0.015.
    for c in &m.contacts {
        assert!(c.contact.distance > 0.015 - 1e-9 && c.contact.penetration >= -1e-12, "{c:?}");
    }
    let flat = m.contacts.iter().filter(|c| (c.contact.distance - 0.015).abs() < 1e-9);
    let flat_xs: Vec<f64> = flat.clone().map(|c| c.contact.point.x).collect();
    assert!(flat_xs.len() >= 2, "{xs:?}");
    for c in flat {
        assert!((c.contact.normal - DVec2::new(0.0, -1.0)).length() < 1e-9, "{c:?}");
    }
}

#[test]
fn identical_bodies_on_top_of_each_other_intersect() {
    let blob = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 3 }.build(16).unwrap();
    let rug = Rugosity::constant(16, 0.0).unwrap();
    let pose = Pose::new(DVec2::new(0.3, -0.2), 0.4);
    let m = query_bodies(&blob, &rug, pose, &blob, &rug, pose);
    assert_eq!(m.state, PairState::Intersecting);
    assert!(!m.intersections.is_empty());
}

#[test]
fn a_body_deep_in_another_bodys_concavity_has_a_defined_answer() {
    let gear = Generator::Gear { radius: 1.0, teeth: 5, depth: 0.3 }.build(40).unwrap();
    let pebble = Generator::Circle { radius: 0.05 }.build(8).unwrap();
    let rug_gear = Rugosity::constant(40, 0.002).unwrap();
    let rug_pebble = Rugosity::constant(8, 0.002).unwrap();
    // Between two teeth: the valley bottom of r(θ) = 1 + 0.3 cos(5θ) is at θ = π/5, r = 0.7.
    let valley = DVec2::from_angle(TAU / 10.0);
    for (depth, expected) in
        [(0.70 + 0.05 + 0.0021, PairState::Contact), (0.9, PairState::Separate), (0.74, PairState::Intersecting)]
    {
        let m = query_bodies(&gear, &rug_gear, Pose::IDENTITY, &pebble, &rug_pebble, Pose::new(valley * depth, 0.0));
        assert_finite(&m);
        assert_eq!(m.state, expected, "pebble centre at radius {depth}: {m:?}");
    }
}

#[test]
fn a_body_nested_inside_another_without_touching_is_separate() {
    let big = Generator::Circle { radius: 2.0 }.build(24).unwrap();
    let small = Generator::Ellipse { a: 0.5, b: 0.3 }.build(12).unwrap();
    let rug_big = Rugosity::constant(24, 0.01).unwrap();
    let rug_small = Rugosity::constant(12, 0.01).unwrap();
    let m = query_bodies(&big, &rug_big, Pose::IDENTITY, &small, &rug_small, Pose::new(DVec2::new(0.2, 0.1), 1.0));
    assert_eq!(m.state, PairState::Separate);
}

#[test]
fn adjacent_leaves_report_a_contact_at_a_joint_once() {
    let a = Generator::Circle { radius: 1.0 }.build(8).unwrap();
    let b = Generator::Circle { radius: 1.0 }.build(8).unwrap();
    let rug = Rugosity::constant(8, 0.01).unwrap();
    // The joints u = 0 of both circles face each other (at angle 0 and, rotated by π, at π).
    let m = query_bodies(&a, &rug, Pose::IDENTITY, &b, &rug, Pose::new(DVec2::new(2.01, 0.0), std::f64::consts::PI));
    assert_eq!(m.state, PairState::Contact);
    assert_eq!(m.contacts.len(), 1, "{:?}", m.contacts);
    let c = m.contacts[0];
    assert!((c.contact.point - DVec2::new(1.005, 0.0)).length() < 1e-9, "{c:?}");
}

// ---------------------------------------------------------------------------------------------
// Self-intersection.

#[test]
fn a_figure_eight_control_polygon_is_caught() {
    // A lemniscate with unequal lobes: the curve crosses itself once, near the origin.
    let points: Vec<DVec2> = (0..16)
        .map(|k| {
            let theta = TAU * k as f64 / 16.0;
            DVec2::new(theta.cos() * (1.0 + 0.3 * theta.cos()), (2.0 * theta).sin() * 0.6)
        })
        .collect();
    let spline = Spline::from_control_points_unchecked(points);
    let (i, j) = find_self_intersection(&spline).expect("figure eight");
    let (a, b) = (spline.segment(i), spline.segment(j));
    let (t, s) = intersect_segment_segment(&a, &b, &settings()).expect("the reported pair meets");
    assert!(a.position(t).length() < 0.2, "crossing at {}", a.position(t));
    assert!(b.position(s).distance(a.position(t)) < 1e-9);
}

#[test]
fn valid_generator_shapes_are_simple() {
    let shapes = [
        Generator::Circle { radius: 1.0 }.build(4).unwrap(),
        Generator::Ellipse { a: 2.0, b: 0.3 }.build(8).unwrap(),
        Generator::RoundedRectangle { width: 2.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap(),
        Generator::Superellipse { a: 1.0, b: 0.5, exponent: 5.0 }.build(32).unwrap(),
        Generator::Gear { radius: 1.0, teeth: 8, depth: 0.2 }.build(64).unwrap(),
        Generator::Blob { radius: 1.0, roughness: 0.8, seed: 11 }.build(20).unwrap(),
        Spline::from_control_points(box_polygon(2.0, 1.0, 3)).unwrap(),
    ];
    for (k, spline) in shapes.iter().enumerate() {
        assert_eq!(find_self_intersection(spline), None, "shape {k}");
        assert!(validate_boundary(spline).is_ok(), "shape {k}");
    }
}

#[test]
fn a_corner_from_a_tripled_control_point_is_simple_but_a_fold_back_is_not() {
    let corner = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 2.0),
        DVec2::new(0.0, 2.0),
    ];
    let spline = Spline::from_control_points(corner).unwrap();
    assert_eq!(find_self_intersection(&spline), None);
    // A spike that runs out along a line and straight back retraces itself.
    let spike = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(4.0, 1.0),
        DVec2::new(4.0, 1.0),
        DVec2::new(4.0, 1.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(2.0, 2.0),
        DVec2::new(0.0, 2.0),
    ];
    let spline = Spline::from_control_points(spike).unwrap();
    assert!(find_self_intersection(&spline).is_some());
    assert!(matches!(validate_boundary(&spline), Err(ShapeError::SelfIntersecting { .. })));
}

#[test]
fn four_segment_curves_wrap_around() {
    // n = 4: segments 0 and 2 (and 1 and 3) are not adjacent; 0 and 3 are, across the wrap.
    let square = Spline::from_control_points(vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y]).unwrap();
    assert_eq!(find_self_intersection(&square), None);
    let bow_tie = Spline::from_control_points_unchecked(vec![DVec2::ZERO, DVec2::ONE, DVec2::X, DVec2::Y]);
    assert!(find_self_intersection(&bow_tie).is_some());
}

#[test]
fn a_tree_query_floors_each_body_at_its_own_trees_band() {
    // Two smooth discs (rugosity 0, so every band is the floor) 1.5 mm apart: in contact with a
    // floor of 1 mm (combined band 2 mm), separate with 0.1 mm. The trees are built with 1 mm;
    // query settings asking 0.1 mm must not shrink the band below the one the trees' boxes were
    // fattened with (they would then miss pairs the settings' band still reaches, or the reverse).
    let disc = Generator::Circle { radius: 0.5 }.build(16).unwrap();
    let smooth = Rugosity::constant(16, 0.0).unwrap();
    let tree = rugosa::AobbTree::build(&disc, &smooth, 1e-3);
    assert_eq!(tree.floor(), 1e-3);
    let shape = BodyShape::new(&disc, &smooth);
    let (pose_a, pose_b) = (Pose::IDENTITY, Pose::new(DVec2::new(1.0015, 0.0), 0.0));
    let state = |min_band: f64| {
        let settings = QuerySettings { min_band, ..QuerySettings::default() };
        let mut query = rugosa::BodyQuery::default();
        rugosa::query_bodies(&shape, &tree, &pose_a, &shape, &tree, &pose_b, &settings, &mut query).state
    };
    assert_eq!(state(1e-3), PairState::Contact);
    assert_eq!(state(1e-4), PairState::Contact, "the trees' floor, not the settings', sets the band");
}

#[test]
fn nearly_coincident_curves_that_cross_are_intersecting() {
    // A closed curve and its own copy moved by a tiny vector always cross (twice). At 1e-11 to
    // 1.8e-8 m the curves meet at angles near 1e-9 rad and the distance is nearly zero all along
    // the overlap, so the nearest points alone read it as a conformal contact; the sign of the
    // gap along the overlap must still tell the crossing (the case found by an independent check:
    // an 8-point circle against itself moved by (3.146479e-10, 3.157010e-11)).
    let shapes = [
        Generator::Circle { radius: 0.5 }.build(8).unwrap(),
        Generator::Ellipse { a: 0.6, b: 0.3 }.build(16).unwrap(),
        Generator::RoundedRectangle { width: 1.0, height: 0.6, corner_radius: 0.1 }.build(24).unwrap(),
    ];
    let mut checked = 0;
    for spline in &shapes {
        let smooth = Rugosity::constant(spline.segment_count(), 0.0).unwrap();
        let mut shifts = vec![DVec2::new(3.146479e-10, 3.157010e-11)];
        for k in 0..24 {
            let length = 1e-11 * (1800.0_f64).powf(k as f64 / 23.0);
            let angle = 2.399963 * k as f64;
            shifts.push(length * DVec2::new(angle.cos(), angle.sin()));
        }
        for shift in shifts {
            let m = query_bodies(spline, &smooth, Pose::IDENTITY, spline, &smooth, Pose::new(shift, 0.0));
            assert_eq!(m.state, PairState::Intersecting, "shift {shift:?}: {} contacts", m.contacts.len());
            checked += 1;
        }
    }
    assert_eq!(checked, 75);
}
