//! A spline boundary as a polygon at a verified geometric error, and that polygon as convex
//! pieces for rapier.
//!
//! The polygon's vertices lie on the curve. Each spline segment is cut into the fewest equal
//! parameter pieces whose chords stay within the tolerance of their arcs. The bound reported is
//! the largest, over all polygon edges, of the two one-sided distances between an edge and *its
//! own* arc (each sampled at [`SAMPLES_PER_EDGE`] points, the arc side against the exact chord,
//! the chord side against the arc's fine polyline): since an edge's own arc is one part of the
//! curve and an edge one part of the polygon, this is an upper bound of the Hausdorff distance
//! between curve and polygon, up to the sampling.

use glam::DVec2;
use rugosa::Spline;

/// Samples per polygon edge when an edge is checked against its arc.
const SAMPLES_PER_EDGE: usize = 32;

/// A closed polygon approximating a spline: vertices in counter-clockwise order, each with
/// the spline parameter it was sampled at.
#[derive(Clone, Debug)]
pub struct SplinePolygon {
    /// Vertices (m), counter-clockwise, in the spline's frame.
    pub vertices: Vec<DVec2>,
    /// Spline parameter of each vertex, increasing.
    pub parameters: Vec<f64>,
    /// Verified bound of the Hausdorff distance between polygon and curve (m).
    pub hausdorff: f64,
}

/// The polygon of `spline` whose Hausdorff distance to the curve is at most `tolerance`.
#[must_use]
pub fn polygon_within(spline: &Spline, tolerance: f64) -> SplinePolygon {
    let mut parameters = Vec::new();
    for segment in 0..spline.segment_count() {
        let start = segment as f64;
        let pieces = (1..=4096)
            .find(|&pieces| {
                (0..pieces).all(|k| {
                    let (a, b) = (start + k as f64 / pieces as f64, start + (k + 1) as f64 / pieces as f64);
                    edge_arc_distance(spline, a, b) <= tolerance
                })
            })
            .unwrap_or(4096);
        parameters.extend((0..pieces).map(|k| start + k as f64 / pieces as f64));
    }
    from_parameters(spline, parameters)
}

/// The polygon through the curve points at `parameters` (increasing), with its bound.
#[must_use]
pub fn from_parameters(spline: &Spline, parameters: Vec<f64>) -> SplinePolygon {
    let vertices: Vec<DVec2> = parameters.iter().map(|&u| spline.position(u)).collect();
    let total = spline.segment_count() as f64;
    let hausdorff = (0..parameters.len())
        .map(|i| {
            let next = if i + 1 < parameters.len() { parameters[i + 1] } else { parameters[0] + total };
            edge_arc_distance(spline, parameters[i], next)
        })
        .fold(0.0, f64::max);
    SplinePolygon { vertices, parameters, hausdorff }
}

/// Larger of the two one-sided distances between the chord from `u(a)` to `u(b)` and the arc
/// between them, from samples.
fn edge_arc_distance(spline: &Spline, a: f64, b: f64) -> f64 {
    let (p, q) = (spline.position(a), spline.position(b));
    let arc: Vec<DVec2> =
        (0..=SAMPLES_PER_EDGE).map(|k| spline.position(a + (b - a) * k as f64 / SAMPLES_PER_EDGE as f64)).collect();
    let arc_to_chord = arc.iter().map(|&x| point_segment_distance(x, p, q)).fold(0.0, f64::max);
    let chord_to_arc = (0..=SAMPLES_PER_EDGE)
        .map(|k| {
            let x = p.lerp(q, k as f64 / SAMPLES_PER_EDGE as f64);
            arc.windows(2).map(|w| point_segment_distance(x, w[0], w[1])).fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    arc_to_chord.max(chord_to_arc)
}

/// Distance from `x` to the segment `p q`.
#[must_use]
pub fn point_segment_distance(x: DVec2, p: DVec2, q: DVec2) -> f64 {
    let d = q - p;
    let t = if d.length_squared() > 0.0 { ((x - p).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    x.distance(p + t * d)
}

/// `> 0` when `a → b → c` turns left (counter-clockwise).
fn turn(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - b)
}

/// The convex hull of the polygon as a polygon of the same curve (a subset of its vertices, so
/// its bound is again edge against own arc), or `None` if the polygon has fewer than 3 vertices.
#[must_use]
pub fn convex_hull(spline: &Spline, polygon: &SplinePolygon) -> Option<SplinePolygon> {
    let n = polygon.vertices.len();
    if n < 3 {
        return None;
    }
    // Start at the lowest-leftmost vertex (on the hull), walk the CCW sequence with a stack.
    let start = (0..n)
        .min_by(|&i, &j| {
            let (a, b) = (polygon.vertices[i], polygon.vertices[j]);
            a.y.total_cmp(&b.y).then(a.x.total_cmp(&b.x))
        })
        .expect("n ≥ 3");
    let mut stack: Vec<usize> = Vec::new();
    for k in 0..=n {
        let index = (start + k) % n;
        while stack.len() >= 2
            && turn(
                polygon.vertices[stack[stack.len() - 2]],
                polygon.vertices[stack[stack.len() - 1]],
                polygon.vertices[index],
            ) <= 0.0
        {
            stack.pop();
        }
        stack.push(index);
    }
    stack.pop(); // the start again
    if stack.len() < 3 {
        return None;
    }
    // Melkman-style monotone walk is valid for a simple polygon whose hull is reached in order;
    // check the result really is convex and encloses every vertex.
    let hull: Vec<DVec2> = stack.iter().map(|&i| polygon.vertices[i]).collect();
    let convex = (0..hull.len()).all(|i| turn(hull[i], hull[(i + 1) % hull.len()], hull[(i + 2) % hull.len()]) > 0.0);
    let encloses = polygon
        .vertices
        .iter()
        .all(|&v| (0..hull.len()).all(|i| turn(hull[i], hull[(i + 1) % hull.len()], v) >= -1e-12 * (1.0 + v.length())));
    if !(convex && encloses) {
        return None;
    }
    let total = spline.segment_count() as f64;
    let parameters: Vec<f64> = stack
        .iter()
        .map(|&i| {
            let u = polygon.parameters[i];
            if i < start { u + total } else { u }
        })
        .collect();
    Some(from_parameters(spline, parameters))
}

/// Convex pieces (each counter-clockwise) whose union is the polygon: the fan of triangles from
/// `kernel`, consecutive triangles merged while the piece stays convex. `None` if the polygon is
/// not star-shaped about `kernel` (the fan would not cover it exactly).
#[must_use]
pub fn fan_decomposition(vertices: &[DVec2], kernel: DVec2) -> Option<Vec<Vec<DVec2>>> {
    let n = vertices.len();
    let star = (0..n).all(|i| turn(kernel, vertices[i], vertices[(i + 1) % n]) > 0.0);
    let total_angle: f64 = (0..n).map(|i| (vertices[i] - kernel).angle_to(vertices[(i + 1) % n] - kernel)).sum();
    if !star || (total_angle - std::f64::consts::TAU).abs() > 1e-9 {
        return None;
    }
    // Begin a piece at a reflex vertex if there is one, so no piece has to wrap around.
    let first =
        (0..n).find(|&i| turn(vertices[(i + n - 1) % n], vertices[i], vertices[(i + 1) % n]) <= 0.0).unwrap_or(0);
    let mut pieces = Vec::new();
    let mut piece = vec![vertices[first]];
    for k in 1..=n {
        let next = vertices[(first + k) % n];
        if piece.len() >= 2 && !stays_convex(&piece, next, kernel) {
            pieces.push(close_piece(&piece, kernel));
            piece = vec![*piece.last().expect("non-empty")];
        }
        piece.push(next);
    }
    pieces.push(close_piece(&piece, kernel));
    Some(pieces)
}

/// Whether the piece `kernel, chain…, next` is convex at every vertex.
fn stays_convex(chain: &[DVec2], next: DVec2, kernel: DVec2) -> bool {
    let m = chain.len();
    let first = chain[0];
    let last = chain[m - 1];
    turn(chain[m - 2], last, next) > 0.0
        && turn(last, next, kernel) > 0.0
        && turn(next, kernel, first) > 0.0
        && turn(kernel, first, chain[1]) > 0.0
}

fn close_piece(chain: &[DVec2], kernel: DVec2) -> Vec<DVec2> {
    let mut piece = Vec::with_capacity(chain.len() + 1);
    piece.push(kernel);
    piece.extend_from_slice(chain);
    piece
}

/// Signed area of a closed polygon (counter-clockwise positive).
#[cfg(test)]
fn signed_area(vertices: &[DVec2]) -> f64 {
    let n = vertices.len();
    0.5 * (0..n).map(|i| vertices[i].perp_dot(vertices[(i + 1) % n])).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rugosa::Generator;

    #[test]
    fn polygon_of_a_circle_meets_the_tolerance_and_the_sagitta_formula() {
        let radius = 1.0;
        let spline = Generator::Circle { radius }.build(16).unwrap();
        let tolerance = 1e-4;
        let polygon = polygon_within(&spline, tolerance);
        assert!(polygon.hausdorff <= tolerance, "bound {}", polygon.hausdorff);
        // A regular n-gon inscribed in a circle has sagitta r (1 − cos(π/n)) ≤ tol, so
        // n ≥ π / acos(1 − tol/r) = 223 for tol = 1e-4 r; pieces per segment are whole numbers,
        // hence at most 16 more than that minimum, and never fewer.
        let minimum = (std::f64::consts::PI / (1.0 - tolerance / radius).acos()).ceil() as usize;
        assert!(polygon.vertices.len() >= minimum && polygon.vertices.len() <= minimum + 16);
    }

    #[test]
    fn fan_pieces_are_convex_and_cover_the_blob_area() {
        let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: 3 }.build(16).unwrap();
        let polygon = polygon_within(&spline, 1e-4);
        let pieces = fan_decomposition(&polygon.vertices, DVec2::ZERO).expect("blobs are star-shaped");
        let area: f64 = pieces.iter().map(|p| signed_area(p)).sum();
        // The pieces tile the polygon, so the areas agree to rounding (~1e-16 per triangle).
        assert!((area - signed_area(&polygon.vertices)).abs() < 1e-12);
        for piece in &pieces {
            let m = piece.len();
            assert!((0..m).all(|i| turn(piece[i], piece[(i + 1) % m], piece[(i + 2) % m]) > 0.0));
        }
    }

    #[test]
    fn hull_of_a_convex_curve_keeps_the_bound() {
        let spline = Generator::Circle { radius: 1.0 }.build(16).unwrap();
        let polygon = polygon_within(&spline, 1e-3);
        let hull = convex_hull(&spline, &polygon).unwrap();
        // A circle's inscribed polygon is convex: the hull keeps every vertex and the bound.
        assert_eq!(hull.vertices.len(), polygon.vertices.len());
        assert!((hull.hausdorff - polygon.hausdorff).abs() < 1e-15);
    }

    #[test]
    fn rounded_square_spline_is_convex_within_the_pyramid_tolerance() {
        // The pyramid's box (side 1 m, diameter ≈ 1.4 m, tolerance 1e-3 of that): its sides are
        // exactly straight (control points on the side lines), so the curve is convex and the
        // hull of its polygon keeps the bound; the box reaches rapier as one convex polygon.
        let spline = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
        let tolerance = 1.4e-3;
        let polygon = polygon_within(&spline, tolerance);
        let hull = convex_hull(&spline, &polygon).expect("a hull");
        assert!(polygon.hausdorff <= tolerance);
        assert!(hull.hausdorff <= tolerance, "hull bound {}", hull.hausdorff);
    }
}
