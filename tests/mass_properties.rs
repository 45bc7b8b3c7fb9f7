//! Exact mass properties of spline bodies against independent references.
//!
//! References: (1) the closed-form area of a periodic uniform cubic B-spline as a quadratic
//! form of its control points, `A = Σ_i c_i × (49/144 c_{i+1} + 7/90 c_{i+2} + 1/720 c_{i+3})`
//! (from `∫ N_a N_b'` of the basis functions, exact rationals); (2) a dense inscribed polygon
//! of the spline itself, whose error is O(h²), Richardson-extrapolated to O(h⁴).

use std::f64::consts::PI;

use glam::DVec2;
use rugosa::{Generator, Spline, area_moments, mass_properties, recentre};

fn shapes() -> Vec<(&'static str, Spline)> {
    vec![
        ("circle16", Generator::Circle { radius: 1.0 }.build(16).unwrap()),
        ("ellipse24", Generator::Ellipse { a: 2.0, b: 0.7 }.build(24).unwrap()),
        ("blob32", Generator::Blob { radius: 1.3, roughness: 0.6, seed: 11 }.build(32).unwrap()),
        ("gear48", Generator::Gear { radius: 0.8, teeth: 6, depth: 0.2 }.build(48).unwrap()),
        (
            "offset_blob",
            Generator::Blob { radius: 0.5, roughness: 0.4, seed: 3 }
                .build(20)
                .unwrap()
                .translated(DVec2::new(3.0, -1.5)),
        ),
    ]
}

/// `(area, centroid, polar moment about the centroid)` of the polygon of `per_segment` samples per segment.
fn polygon_moments(spline: &Spline, per_segment: usize) -> (f64, DVec2, f64) {
    let count = spline.segment_count() * per_segment;
    let points: Vec<DVec2> = (0..count).map(|k| spline.position(k as f64 / per_segment as f64)).collect();
    let (mut area, mut first, mut polar) = (0.0, DVec2::ZERO, 0.0);
    for i in 0..count {
        let (p, q) = (points[i], points[(i + 1) % count]);
        let cross = p.perp_dot(q);
        area += cross;
        first += (p + q) * cross;
        polar += cross * (p.length_squared() + p.dot(q) + q.length_squared());
    }
    let area = 0.5 * area;
    let centroid = first / (6.0 * area);
    (area, centroid, polar / 12.0 - area * centroid.length_squared())
}

fn richardson(coarse: f64, fine: f64) -> f64 {
    (4.0 * fine - coarse) / 3.0
}

#[test]
fn area_matches_the_closed_form_quadratic_form() {
    for (name, spline) in shapes() {
        let c = spline.control_points();
        let n = c.len();
        let closed: f64 = (0..n)
            .map(|i| {
                c[i].perp_dot(
                    49.0 / 144.0 * c[(i + 1) % n] + 7.0 / 90.0 * c[(i + 2) % n] + 1.0 / 720.0 * c[(i + 3) % n],
                )
            })
            .sum();
        let area = area_moments(&spline).area;
        assert!((area - closed).abs() <= 1e-13 * closed.abs(), "{name}: {area} vs closed form {closed}");
    }
}

#[test]
fn moments_match_a_dense_polygon() {
    for (name, spline) in shapes() {
        let exact = area_moments(&spline);
        let (a1, c1, j1) = polygon_moments(&spline, 256);
        let (a2, c2, j2) = polygon_moments(&spline, 512);
        let area = richardson(a1, a2);
        let centroid = DVec2::new(richardson(c1.x, c2.x), richardson(c1.y, c2.y));
        let polar = richardson(j1, j2);
        let size = spline.extent();
        assert!((exact.area - area).abs() <= 1e-9 * exact.area, "{name}: area {} vs {area}", exact.area);
        assert!(
            (exact.centroid - centroid).length() <= 1e-9 * size,
            "{name}: centroid {} vs {centroid}",
            exact.centroid
        );
        assert!(
            (exact.polar_moment - polar).abs() <= 1e-9 * exact.polar_moment,
            "{name}: J {} vs {polar}",
            exact.polar_moment
        );
    }
}

#[test]
fn spline_circle_is_close_to_the_true_disc() {
    // The interpolating spline through 64 points of the unit circle deviates from it by about
    // (2π/64)⁴/384 ≈ 2.4e-7 in radius (cubic interpolation error), so area and inertia agree with
    // πr² and πr⁴/2 to a few 1e-7 relative; 1e-6 leaves room without hiding a real error.
    let spline = Generator::Circle { radius: 1.0 }.build(64).unwrap();
    let props = mass_properties(&spline, 2.0);
    assert!((props.mass - 2.0 * PI).abs() / (2.0 * PI) < 1e-6, "mass {}", props.mass);
    assert!((props.inertia - PI).abs() / PI < 1e-6, "inertia {}", props.inertia);
    assert!(props.centre_of_mass.length() < 1e-12);
}

#[test]
fn moments_are_invariant_under_rigid_motion() {
    for (name, spline) in shapes() {
        let base = area_moments(&spline);
        let rotation = DVec2::from_angle(0.83);
        let shift = DVec2::new(-7.5, 4.25);
        let moved = spline.mapped(|c| rotation.rotate(c) + shift);
        let after = area_moments(&moved);
        assert!((after.area - base.area).abs() <= 1e-13 * base.area, "{name}: area");
        let expected_centroid = rotation.rotate(base.centroid) + shift;
        assert!((after.centroid - expected_centroid).length() <= 1e-12 * (1.0 + shift.length()), "{name}: centroid");
        // The polar moment about the centroid loses digits to A|c|² cancellation: relative 1e-11.
        assert!((after.polar_moment - base.polar_moment).abs() <= 1e-11 * base.polar_moment, "{name}: inertia");
    }
}

#[test]
fn recentring_puts_the_centroid_at_the_origin() {
    for (name, spline) in shapes() {
        let (centred, centroid) = recentre(&spline);
        let after = area_moments(&centred);
        assert!(after.centroid.length() <= 1e-12 * spline.extent(), "{name}: {}", after.centroid);
        assert!((centroid - area_moments(&spline).centroid).length() == 0.0);
    }
}
