//! Flat things are flat: rounded rectangles and polygons have exactly straight sides, their
//! nominal width and height, corners within the documented deviation (checked against an
//! independent distance to the nominal outline), the closed-form area, and typed errors.

use std::f64::consts::PI;

use glam::DVec2;
use rugosa::{
    AobbTree, BodyQuery, BodyShape, ControlPointBudget, Generator, Pose, QuerySettings, Rugosity, ShapeError, ShapeFit,
    Spline, mass_properties, query_bodies, rounded_polygon,
};

/// Samples per segment of the independent measurements (4× the library's 64, a superset of them).
const SAMPLES: usize = 256;

/// Documented largest corner deviation (module docs of `src/geometry/rounded_polygon.rs`), in
/// corner radii, for right-angle corners with room on both sides (measured 0.00213 r) and when the
/// radius takes a whole side (measured 0.01258 r).
const RIGHT_ANGLE_BOUND: f64 = 0.0022;
const RIGHT_ANGLE_CAPPED_BOUND: f64 = 0.0127;
/// Documented: the curve is straight from 1.08 tangent lengths from each vertex on.
const STRAIGHT_FROM: f64 = 1.08;

fn samples(spline: &Spline) -> impl Iterator<Item = DVec2> + '_ {
    (0..spline.segment_count() * SAMPLES).map(|k| spline.position(k as f64 / SAMPLES as f64))
}

fn rectangle(width: f64, height: f64, corner_radius: f64, segments: usize) -> (Spline, ShapeFit) {
    Generator::RoundedRectangle { width, height, corner_radius }.build_with_fit(segments).unwrap()
}

/// Exact distance from `p` to the outline of a rounded `width × height` box (rounded-box
/// signed distance, written here independently of the library).
fn rounded_box_distance(p: DVec2, width: f64, height: f64, radius: f64) -> f64 {
    let q = p.abs() - DVec2::new(0.5 * width - radius, 0.5 * height - radius);
    let outside = q.max(DVec2::ZERO).length();
    let inside = q.x.max(q.y).min(0.0);
    (outside + inside - radius).abs()
}

/// Every sample of a rounded box farther than `STRAIGHT_FROM · r` from the corners along a
/// side is on that side's line, to `1e-12` of the box size; returns how many were checked.
fn assert_box_sides_straight(spline: &Spline, width: f64, height: f64, radius: f64) -> usize {
    let half = 0.5 * DVec2::new(width, height);
    let flat = half - DVec2::splat(STRAIGHT_FROM * radius);
    let tolerance = 1e-12 * width.max(height);
    let mut checked = 0;
    for p in samples(spline) {
        let off_line = if p.x.abs() <= flat.x {
            (p.y.abs() - half.y).abs()
        } else if p.y.abs() <= flat.y {
            (p.x.abs() - half.x).abs()
        } else {
            continue;
        };
        assert!(off_line <= tolerance, "{width}×{height} r {radius}: {p} is {off_line:e} off its side");
        checked += 1;
    }
    checked
}

#[test]
fn rounded_rectangle_sides_are_straight() {
    for (width, height, radius, segments) in
        [(0.5, 0.5, 0.05, 32), (2.0, 1.0, 0.2, 40), (10.0, 1.0, 0.1, 64), (3.0, 1.0, 0.5, 48), (1.0, 0.3, 0.0, 32)]
    {
        let (spline, fit) = rectangle(width, height, radius, segments);
        assert_eq!((spline.segment_count(), fit.segments), (segments, segments));
        // With radius 0 each corner is rounded over half the mean control-point spacing.
        let reach = if radius > 0.0 { radius } else { (width + height) / segments as f64 };
        let checked = assert_box_sides_straight(&spline, width, height, reach);
        assert!(checked > segments * SAMPLES / 2, "only {checked} samples on the straight parts");
    }
}

#[test]
fn rounded_rectangle_has_its_nominal_width_and_height() {
    for (width, height, radius) in [(0.5, 0.5, 0.05), (2.0, 1.0, 0.5), (40.0, 2.0, 0.05), (0.4, 0.2, 0.0)] {
        let (spline, fit) = rectangle(width, height, radius, 48);
        let (lo, hi) = spline.bounds();
        let size = hi - lo;
        // The width and height are measured on exactly straight sides: nominal to rounding,
        // which is well within the corner error the fit reports.
        let error = (size - DVec2::new(width, height)).abs().max_element();
        assert!(error <= 1e-12 * width.max(height) && error <= fit.max_deviation, "{width}×{height}: {size}");
        assert!((lo + hi).abs().max_element() <= 1e-12 * width.max(height), "not centred: {lo} {hi}");
    }
}

#[test]
fn ground_box_top_is_flat_for_x_within_19() {
    for radius in [0.05, 0.1, 0.0] {
        let (spline, _) = rectangle(40.0, 2.0, radius, 84);
        let mut checked = 0;
        for p in samples(&spline).filter(|p| p.x.abs() < 19.0 && p.y > 0.0) {
            assert!((p.y - 1.0).abs() <= 1e-12 * 40.0, "radius {radius}: {p} is off the top");
            checked += 1;
        }
        assert!(checked > 1000, "radius {radius}: only {checked} samples on the top");
    }
}

#[test]
fn rounded_rectangle_deviation_is_within_the_documented_bound_and_measured_independently() {
    let cases = [
        (0.5, 0.5, 0.05, 32, RIGHT_ANGLE_BOUND),
        (40.0, 2.0, 0.05, 84, RIGHT_ANGLE_BOUND),
        (2.0, 1.0, 0.2, 24, RIGHT_ANGLE_BOUND),
        (2.0, 1.0, 0.5, 32, RIGHT_ANGLE_CAPPED_BOUND), // the short sides are all corner
        (1.0, 1.0, 0.5, 16, RIGHT_ANGLE_CAPPED_BOUND), // four corners and nothing else
    ];
    for (width, height, radius, segments, bound) in cases {
        let (spline, fit) = rectangle(width, height, radius, segments);
        let independent = samples(&spline).map(|p| rounded_box_distance(p, width, height, radius)).fold(0.0, f64::max);
        let reported = Generator::RoundedRectangle { width, height, corner_radius: radius }.max_deviation(segments);
        assert_eq!(reported, Ok(fit.max_deviation));
        assert!(fit.max_deviation <= bound * radius, "{width}×{height} r {radius}: {} > {bound} r", fit.max_deviation);
        // The library samples a subset of these points: it can only find less, and not much less.
        assert!(
            fit.max_deviation <= independent * (1.0 + 1e-9) && fit.max_deviation >= 0.99 * independent,
            "{width}×{height} r {radius}: reported {} vs independent {independent}",
            fit.max_deviation
        );
    }
}

/// A convex pentagon (turns 60°–90°), given clockwise.
fn pentagon_clockwise() -> Vec<DVec2> {
    let mut corners = vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.5, 1.0),
        DVec2::new(1.0, 2.0),
        DVec2::new(-0.5, 1.0),
    ];
    corners.reverse();
    corners
}

/// Distance to a convex polygon rounded at `radius`: the polygon is its arc centres' polygon
/// grown by `radius`, so the distance is `|signed distance to the centres' polygon − radius|`.
fn rounded_convex_distance(p: DVec2, ccw: &[DVec2], radius: f64) -> f64 {
    let n = ccw.len();
    let inward = |k: usize| (ccw[(k + 1) % n] - ccw[k]).normalize().perp();
    // Each centre is `radius` inside both sides of its corner.
    let centres: Vec<DVec2> = (0..n)
        .map(|k| {
            let (a, b) = (inward((k + n - 1) % n), inward(k));
            ccw[k] + radius * (a + b) / (1.0 + a.dot(b))
        })
        .collect();
    let to_edge = |k: usize| {
        let (a, b) = (centres[k], centres[(k + 1) % n]);
        let s = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        p.distance(a + s * (b - a))
    };
    let nearest = (0..n).map(to_edge).fold(f64::INFINITY, f64::min);
    let inside = (0..n).all(|k| (centres[(k + 1) % n] - centres[k]).perp_dot(p - centres[k]) >= 0.0);
    ((if inside { -nearest } else { nearest }) - radius).abs()
}

#[test]
fn rounded_polygon_sides_are_straight_and_its_deviation_is_measured_independently() {
    let corners = pentagon_clockwise();
    let radius = 0.15;
    let (spline, fit) = rounded_polygon(&corners, radius, ControlPointBudget::MaxSpacing(0.1)).unwrap();
    assert!(spline.signed_area() > 0.0, "clockwise corners must give a counter-clockwise curve");
    let mut ccw = corners.clone();
    ccw.reverse();
    let n = ccw.len();
    let turn = |k: usize| {
        let (a, b) = (ccw[k] - ccw[(k + n - 1) % n], ccw[(k + 1) % n] - ccw[k]);
        a.perp_dot(b).atan2(a.dot(b))
    };
    let tangent = |k: usize| radius * (0.5 * turn(k % n)).tan();
    let mut checked = 0;
    for p in samples(&spline) {
        for k in 0..n {
            let (a, b) = (ccw[k], ccw[(k + 1) % n]);
            let along = (p - a).dot((b - a).normalize());
            let off_line = (b - a).normalize().perp_dot(p - a).abs();
            let straight =
                along >= STRAIGHT_FROM * tangent(k) && along <= a.distance(b) - STRAIGHT_FROM * tangent(k + 1);
            if straight && off_line < 0.01 {
                assert!(off_line <= 1e-12 * 3.0, "{p} is {off_line:e} off side {k}");
                checked += 1;
            }
        }
    }
    assert!(checked > spline.segment_count() * SAMPLES / 2, "only {checked} samples on the straight parts");
    // Turns of 60°–90° with room on every side: documented at most 0.0022 r (90°).
    let independent = samples(&spline).map(|p| rounded_convex_distance(p, &ccw, radius)).fold(0.0, f64::max);
    assert!(fit.max_deviation <= RIGHT_ANGLE_BOUND * radius, "deviation {}", fit.max_deviation);
    assert!(fit.max_deviation <= independent * (1.0 + 1e-9) && fit.max_deviation >= 0.99 * independent);
}

#[test]
fn concave_corners_keep_straight_sides() {
    // An L-shape: one concave corner (turn −90°), whose rounding is a fillet outside the material.
    let corners = [
        DVec2::new(0.0, 0.0),
        DVec2::new(2.0, 0.0),
        DVec2::new(2.0, 1.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(1.0, 2.0),
        DVec2::new(0.0, 2.0),
    ];
    let generator = Generator::RoundedPolygon { corners: corners.to_vec(), corner_radius: 0.1 };
    let (spline, fit) = generator.build_with_fit(60).unwrap();
    assert_eq!(fit.segments, 60);
    assert!(fit.max_deviation <= RIGHT_ANGLE_BOUND * 0.1, "deviation {}", fit.max_deviation);
    let flat = 0.1 * STRAIGHT_FROM;
    for p in samples(&spline) {
        // The inner sides x = 1 (y in 1..2) and y = 1 (x in 1..2), away from their corners.
        if (p.x - 1.0).abs() < 0.01 && p.y > 1.0 + flat && p.y < 2.0 - flat {
            assert!((p.x - 1.0).abs() <= 1e-12, "{p}");
        }
        if (p.y - 1.0).abs() < 0.01 && p.x > 1.0 + flat && p.x < 2.0 - flat {
            assert!((p.y - 1.0).abs() <= 1e-12, "{p}");
        }
    }
    // The area of the L (3 m²), less five convex roundings, plus one concave fillet.
    let corner = (1.0 - PI / 4.0) * 0.01;
    let area = spline.signed_area();
    assert!((area - (3.0 - 5.0 * corner + corner)).abs() <= fit.max_deviation * 8.0, "area {area}");
}

#[test]
fn max_spacing_bounds_the_gaps_on_the_straight_parts() {
    let corners = pentagon_clockwise();
    let (spline, _) = rounded_polygon(&corners, 0.1, ControlPointBudget::MaxSpacing(0.07)).unwrap();
    let points = spline.control_points();
    let n = points.len();
    let on_one_side = |p: DVec2, q: DVec2| {
        (0..corners.len()).any(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            let direction = (b - a).normalize();
            direction.perp_dot(p - a).abs() < 1e-12 && direction.perp_dot(q - a).abs() < 1e-12
        })
    };
    let gaps: Vec<f64> = (0..n)
        .filter(|&i| on_one_side(points[i], points[(i + 1) % n]))
        .map(|i| points[i].distance(points[(i + 1) % n]))
        .collect();
    assert!(gaps.len() > n / 2);
    let largest = gaps.iter().copied().fold(0.0, f64::max);
    assert!(largest <= 0.07 + 1e-12, "largest gap {largest}");
}

#[test]
fn rounded_rectangle_area_matches_the_closed_form() {
    for (width, height, radius, segments) in [(0.5, 0.5, 0.05, 32), (2.0, 1.0, 0.3, 40), (40.0, 2.0, 0.05, 84)] {
        let (spline, fit) = rectangle(width, height, radius, segments);
        let exact = width * height - (4.0 - PI) * radius * radius;
        let perimeter = 2.0 * (width + height) - (8.0 - 2.0 * PI) * radius;
        let props = mass_properties(&spline, 1.0);
        assert!(
            (props.mass - exact).abs() <= fit.max_deviation * perimeter,
            "{width}×{height} r {radius}: area {} vs {exact} (allowed {})",
            props.mass,
            fit.max_deviation * perimeter
        );
        assert!(props.centre_of_mass.length() <= 1e-12 * width.max(height));
    }
}

#[test]
fn circle_max_deviation_matches_the_exact_distance() {
    let (spline, fit) = Generator::Circle { radius: 2.0 }.build_with_fit(32).unwrap();
    let independent = samples(&spline).map(|p| (p.length() - 2.0).abs()).fold(0.0, f64::max);
    assert!(fit.max_deviation <= independent * (1.0 + 1e-9) && fit.max_deviation >= 0.99 * independent);
    // Cubic interpolation of 32 points: about 2 (2π/32)⁴/384 ≈ 7.8e-6.
    assert!(fit.max_deviation < 1e-5, "{}", fit.max_deviation);
}

fn invalid(result: Result<(Spline, ShapeFit), ShapeError>) -> (String, String) {
    match result {
        Err(ShapeError::InvalidParameter { what, reason }) => (what, reason),
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

fn polygon(corners: &[DVec2], radius: f64) -> (String, String) {
    invalid(rounded_polygon(corners, radius, ControlPointBudget::MaxSpacing(0.1)))
}

fn square() -> Vec<DVec2> {
    vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)]
}

#[test]
fn bad_corners_are_refused_with_the_reason() {
    let corners = "rounded_polygon.corners".to_owned();
    let (what, reason) = polygon(&square()[..2], 0.1);
    assert_eq!((what, reason.as_str()), (corners.clone(), "a polygon needs at least 3 corners, got 2"));
    let mut nan = square();
    nan[2].x = f64::NAN;
    assert_eq!(polygon(&nan, 0.1), (corners.clone(), "corner 2 is not finite: (NaN, 1)".to_owned()));
    let mut repeated = square();
    repeated.insert(2, repeated[1]);
    assert_eq!(polygon(&repeated, 0.1), (corners.clone(), "side 1 (corner 1 to corner 2) has zero length".to_owned()));
    let mut collinear = square();
    collinear.insert(1, DVec2::new(0.5, 0.0));
    let (what, reason) = polygon(&collinear, 0.1);
    assert!(what == corners && reason.starts_with("corner 1 is collinear with its neighbours"), "{reason}");
    let folded = [DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0)];
    assert_eq!(polygon(&folded, 0.0), (corners.clone(), "the outline folds back on itself at corner 1".to_owned()));
    let bow_tie = [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
    assert_eq!(polygon(&bow_tie, 0.0), (corners, "the polygon intersects itself: sides 0 and 2 cross".to_owned()));
}

#[test]
fn bad_radius_and_budget_are_refused_with_the_reason() {
    let radius = "rounded_polygon.corner_radius".to_owned();
    assert_eq!(polygon(&square(), -0.1), (radius.clone(), "must be finite and >= 0, got -0.1".to_owned()));
    assert_eq!(polygon(&square(), f64::INFINITY), (radius.clone(), "must be finite and >= 0, got inf".to_owned()));
    let (what, reason) = polygon(&square(), 0.6);
    assert_eq!(what, radius);
    assert!(reason.starts_with("0.6 does not fit side 0: its two roundings need"), "{reason}");
    assert!(reason.ends_with("(the largest radius that fits every side is 0.5)"), "{reason}");

    let (what, reason) = invalid(rounded_polygon(&square(), 0.1, ControlPointBudget::MaxSpacing(0.0)));
    assert_eq!((what.as_str(), reason.as_str()), ("rounded_polygon.spacing", "must be finite and > 0, got 0"));
    let (what, reason) = invalid(rounded_polygon(&square(), 0.1, ControlPointBudget::Segments(20)));
    assert_eq!(what, "segments");
    assert_eq!(reason, "a rounded polygon of 4 corners needs at least 24 segments (6 per corner), got 20");
    // A rounded square of radius half its side is four corners and nothing else: exactly 16.
    let (what, reason) = invalid(rounded_polygon(&square(), 0.5, ControlPointBudget::Segments(20)));
    assert_eq!(what, "segments");
    assert_eq!(reason, "every side is taken by its two corners, so the curve has exactly 16 segments, got 20");
}

#[test]
fn generators_return_the_same_typed_errors() {
    let triangle = vec![DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
    let generator = Generator::RoundedPolygon { corners: triangle.clone(), corner_radius: 0.1 };
    let err = generator.build(12).unwrap_err();
    assert_eq!(
        err.to_string(),
        "segments: a rounded polygon of 3 corners needs at least 18 segments (6 per corner), got 12"
    );
    assert_eq!(generator.max_deviation(12), Err(err));
    let err = Generator::RoundedPolygon { corners: triangle[..2].to_vec(), corner_radius: 0.1 }.build(18).unwrap_err();
    assert_eq!(err.to_string(), "rounded_polygon.corners: a polygon needs at least 3 corners, got 2");
    let err = Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.1 }.build(16).unwrap_err();
    assert_eq!(
        err.to_string(),
        "segments: a rounded polygon of 4 corners needs at least 24 segments (6 per corner), got 16"
    );
    let err = Generator::RoundedRectangle { width: 1.0, height: 0.5, corner_radius: 0.3 }.build(32).unwrap_err();
    assert!(err.to_string().starts_with("rounded_rectangle.corner_radius: must lie in [0, half the smaller side"));
    assert_eq!(generator.build(3).unwrap_err(), ShapeError::TooFewControlPoints { count: 3 });
}

#[cfg(feature = "scene")]
#[test]
fn scene_parses_a_rounded_polygon_generator() {
    use rugosa::{Scene, ShapeScene};

    let text = r#"(
        bodies: [
            (name: "ramp", static: true, shape: Generator(
                generator: RoundedPolygon(corners: [(0, 0), (4, 0), (4, 1)], corner_radius: 0.05),
                segments: 30)),
            (name: "crate", shape: Generator(
                generator: RoundedRectangle(width: 0.5, height: 0.5, corner_radius: 0.05), segments: 24),
                position: (2.0, 1.5)),
        ],
    )"#;
    let scene = Scene::from_ron_str(text, "inline").unwrap();
    let ShapeScene::Generator { generator, segments } = &scene.bodies[0].shape else { panic!("a generator") };
    let corners = vec![DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(4.0, 1.0)];
    assert_eq!(*generator, Generator::RoundedPolygon { corners, corner_radius: 0.05 });
    assert_eq!(*segments, 30);
    let descs = scene.body_descs().unwrap();
    assert_eq!(descs[0].spline.segment_count(), 30);
    // The ramp's base is the line y = 0 away from its corners.
    let base = samples(&descs[0].spline).filter(|p| p.y < 0.01 && p.x > 0.5 && p.x < 3.9);
    assert!(base.map(|p| p.y.abs()).fold(0.0, f64::max) <= 1e-12);

    let too_round = text.replacen("corner_radius: 0.05)", "corner_radius: 5.0)", 1);
    let err = Scene::from_ron_str(&too_round, "inline").unwrap().body_descs().unwrap_err();
    assert_eq!(
        err.to_string(),
        "inline: body 0 ('ramp'): shape: rounded_polygon.corner_radius: 5 does not fit side 0: its two roundings \
         need 45.6155 m of it but it is 4 m long (the largest radius that fits every side is 0.438447)"
    );
}

#[test]
fn a_tilted_flat_side_in_the_band_touches_along_its_whole_length() {
    // A 1 m rounded box (corners 0.1 m) tilted by up to 5e-3 rad either way above a flat slab,
    // its flat bottom between 4.6 mm and at most 8.6 mm from the slab: inside the combined band
    // of 10 mm everywhere. The contacts must span the flat, from one end (x = ±0.4 in the
    // box's frame, where the corners begin) to the other: geometry, with 1 cm to spare.
    let band = 0.005;
    let slab = Generator::RoundedRectangle { width: 30.0, height: 1.0, corner_radius: 0.1 }.build(32).unwrap();
    let slab_bands = Rugosity::constant(slab.segment_count(), band).unwrap();
    let block = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
    let block_bands = Rugosity::constant(block.segment_count(), band).unwrap();
    let (slab_tree, block_tree) =
        (AobbTree::build(&slab, &slab_bands, 0.0), AobbTree::build(&block, &block_bands, 0.0));
    let (slab_shape, block_shape) = (BodyShape::new(&slab, &slab_bands), BodyShape::new(&block, &block_bands));
    let slab_pose = Pose::new(DVec2::new(0.0, -0.5), 0.0);
    for tilt in [1e-5, 1e-4, 2.4e-4, 1e-3, 5e-3] {
        for angle in [tilt, -tilt] {
            let centre = DVec2::new(0.3, 0.5 + 0.0046 + 0.4 * tilt);
            let pose = Pose::new(centre, angle);
            let mut query = BodyQuery::default();
            let settings = QuerySettings::default();
            let manifold = query_bodies(
                &slab_shape,
                &slab_tree,
                &slab_pose,
                &block_shape,
                &block_tree,
                &pose,
                &settings,
                &mut query,
            );
            let along = DVec2::from_angle(angle);
            let span = manifold.contacts.iter().map(|c| (c.contact.point - centre).dot(along));
            let (low, high) = span.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)));
            assert!(
                low <= -0.39 && high >= 0.39,
                "tilt {angle:e}: contacts span {low:.4} .. {high:.4} of the flat's -0.4 .. 0.4"
            );
        }
    }
}
