//! Polygons with rounded corners whose straight sides are exactly straight: the construction
//! is documented on [`rounded_polygon`].

use std::sync::{Mutex, PoisonError};

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::ShapeError;
use crate::geometry::segment::CubicSegment;
use crate::geometry::spline::Spline;

mod checks;
mod outline;

use checks::{check_budget, check_corners, check_radius};
use outline::Outline;

/// How many control points [`rounded_polygon`] places along the straight parts of the sides.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ControlPointBudget {
    /// At most this distance (m) between neighbouring control points on a straight part.
    MaxSpacing(f64),
    /// Exactly this many segments; what the corners leave is spread over the straight parts in
    /// proportion to their lengths.
    Segments(usize),
}

/// How closely a built curve follows its nominal shape.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapeFit {
    /// Largest distance (m) from a point of the curve to the nominal outline, by dense sampling.
    pub max_deviation: f64,
    /// Number of segments of the curve.
    pub segments: usize,
}

/// Corners turning by less than this (rad) are collinear with their neighbours; by more than
/// π minus this the outline folds back on itself.
const MIN_TURN: f64 = 1e-6;
/// Sides shorter than this fraction of the polygon's bounding-box diagonal have zero length.
const ZERO_LENGTH_FRACTION: f64 = 1e-12;
/// Relative slack of the radius fit `t_k + t_{k+1} ≤ L_k`, so a radius of exactly half a
/// rectangle's side survives the rounding of `tan(π/4)`.
const FIT_SLACK: f64 = 1e-12;
/// Upper end of the search for `q`; the free optimum is 1.05–1.19, so this never binds.
const MAX_FAR: f64 = 1.25;
/// A `q` within this fraction of its cap snaps to the cap, so two corners meet exactly instead
/// of leaving a sliver of a segment between them. Near its optimum the deviation is flat in `q`:
/// at a right angle it is 0.0021 r at the optimum q = 1.18 and 0.0033 r at q = 1.15.
const SNAP_FRACTION: f64 = 0.02;
/// Straight parts shorter than this fraction of their side are merged into one doubled point.
const MERGE_FRACTION: f64 = 1e-6;
/// Samples per segment of the reported deviation; the deviation is smooth within a segment, and
/// at a right angle 64 samples find its maximum to within 0.1 % of 1024 samples.
pub(crate) const DEVIATION_SAMPLES: usize = 64;
/// Samples per segment while searching a corner design (only the relative order matters there).
const DESIGN_SAMPLES: usize = 16;
/// Golden-section steps: the bracket shrinks by 0.618²⁴ ≈ 1e-5, far below what changes the deviation.
const GOLDEN_STEPS: usize = 24;
/// Most control points a [`ControlPointBudget::MaxSpacing`] may ask for.
const MAX_CONTROL_POINTS: usize = 1_000_000;

/// A closed polygon with every corner rounded at `corner_radius`, as a B-spline whose straight
/// parts are exactly straight, with the deviation from the nominal outline it measured.
///
/// `corners` run either way round (clockwise input is reversed). The corner construction, its
/// deviation and what a zero radius does are below. The polygon is checked to be simple, but not
/// the curve: a concave corner's rounding can reach a side that is not its own (a slot narrower
/// than its roundings); `Simulation::add_body` and scenes check the curve for self-intersection.
///
/// A uniform cubic B-spline segment is a straight line exactly when its four control points
/// `c_{i-1}..c_{i+2}` are collinear. This function places every control point on a side
/// line of the polygon, so every segment whose four control points lie on one side is exactly
/// on that side (to rounding, about 1e-16 of the coordinates), and only the segments that
/// straddle a corner bend.
///
/// # Corners
///
/// A corner that turns the outline by `θ` and is rounded at radius `r` has tangent length
/// `t = r tan(|θ|/2)`: the nominal arc meets each side `t` from the vertex. The corner owns six
/// control points, three on each side: one `p·t` from the vertex and a doubled one `q·t` from it
/// (`a_q a_q a_p | b_p b_q b_q`). The vertex itself is not a control point. The three segments
/// whose control points lie on both sides form the rounding; the curve is straight from
/// `(p + 5q)/6 · t` from the vertex on (at most 1.08 t, measured over all turns). `p` and `q`
/// minimise the largest distance
/// of those three segments from the arc, by nested golden-section searches on a canonical corner
/// (`q ≤ 1.25`; the free optimum is `q ≈ 1.05–1.19`). The doubled points never pass the point that
/// splits a side between its two corners in proportion to their tangent lengths, so roundings never
/// overlap; when two corners meet there, their doubled points are one.
///
/// A B-spline is C², so its curvature cannot jump from 0 on a side to `1/r` on the arc: the
/// rounding is a curvature ramp that stays close to the arc. The largest deviations from the
/// nominal outline (distance to the nearest line or arc, 1024 samples per segment, rounded up;
/// `tests/flat_shapes.rs` checks the right-angle bounds), in units of the corner radius `r`.
/// "Room" means the side is longer than its two roundings need (`L ≥ 1.22 (t_k + t_{k+1})`
/// suffices); "whole side" that they take all of it (`L = t_k + t_{k+1}`, e.g. a rounded
/// rectangle whose `r` is half its shorter side):
///
/// | corner (turn) | room on both sides | radius takes a whole side (`q` capped at 1) |
/// |---|---|---|
/// | 30° | 0.00017 r | 0.0012 r |
/// | 60° | 0.00077 r | 0.0051 r |
/// | 90° (rectangle) | 0.0022 r | 0.0126 r |
/// | 120° | 0.0049 r | 0.026 r |
/// | 150° | 0.0101 r | 0.047 r |
/// | 170° | 0.0157 r | 0.068 r |
///
/// For example a 0.5 m box with 0.05 m corners is within 0.11 mm of its nominal outline, and a
/// 40 m × 2 m ground with 0.05 m corners likewise; the width and height, measured on the exactly
/// straight sides, are the nominal ones to rounding. Every build reports the deviation it
/// measured in [`ShapeFit::max_deviation`].
///
/// # Zero radius
///
/// A `corner_radius` of 0 asks for a sharp corner, which a C² curve cannot have. Each corner is
/// then rounded with the corner design above at tangent length
/// `t₀ = ½ min(h, L_in, L_out)`, where `h` is the control-point spacing (the maximum spacing, or
/// the perimeter over the segment count) and `L_in`, `L_out` are the adjacent sides. The nominal
/// outline is the sharp polygon, so the reported deviation is how far the rounding cuts the corner:
/// 0.29 t₀ at a right angle (measured; 0.15 m on a 40 m × 2 m box of 84 segments, where
/// `h` = 1 m and `t₀` = 0.5 m).
///
/// # Cost
///
/// Each distinct corner (turn and cap) costs a few hundred evaluations of its three bending
/// segments (about 1 ms in all for a rectangle); the reported deviation costs
/// `64 · segments · 2 · corners` distance evaluations.
///
/// # Errors
/// [`ShapeError::InvalidParameter`] naming `rounded_polygon.corners` (fewer than 3, non-finite,
/// a zero-length side, a corner collinear with its neighbours or folding back, crossing sides),
/// `rounded_polygon.corner_radius` (negative, non-finite, or too large for a side: the message
/// gives the largest radius that fits), `rounded_polygon.spacing` or `segments` (a budget too
/// small, naming the minimum, or more than the straight parts can hold).
pub fn rounded_polygon(
    corners: &[DVec2],
    corner_radius: f64,
    budget: ControlPointBudget,
) -> Result<(Spline, ShapeFit), ShapeError> {
    check_corners(corners)?;
    check_radius(corners, corner_radius)?;
    check_budget(budget)?;
    let ccw = counter_clockwise(corners);
    let geometry = corner_geometry(&ccw, corner_radius, budget);
    let plan = plan_sides(&ccw, &geometry, budget)?;
    let spline = Spline::from_control_points(control_points(&ccw, &geometry, &plan))?;
    let outline = Outline::rounded_polygon(&ccw, corner_radius);
    let fit = ShapeFit { max_deviation: outline.max_deviation(&spline), segments: spline.segment_count() };
    Ok((spline, fit))
}

// ---- polygon geometry ----

fn side_length(corners: &[DVec2], k: usize) -> f64 {
    corners[k].distance(corners[(k + 1) % corners.len()])
}

/// Signed turn (rad) of the outline at corner `k`: positive to the left.
fn turning_angle(corners: &[DVec2], k: usize) -> f64 {
    let n = corners.len();
    let incoming = corners[k] - corners[(k + n - 1) % n];
    let outgoing = corners[(k + 1) % n] - corners[k];
    incoming.perp_dot(outgoing).atan2(incoming.dot(outgoing))
}

fn bounding_diagonal(points: &[DVec2]) -> f64 {
    let lo = points.iter().copied().fold(DVec2::splat(f64::INFINITY), DVec2::min);
    let hi = points.iter().copied().fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
    (hi - lo).length()
}

/// The corners in counter-clockwise order (shoelace sign).
fn counter_clockwise(corners: &[DVec2]) -> Vec<DVec2> {
    let n = corners.len();
    let twice_area: f64 = (0..n).map(|k| corners[k].perp_dot(corners[(k + 1) % n])).sum();
    let mut ccw = corners.to_vec();
    if twice_area < 0.0 {
        ccw.reverse();
    }
    ccw
}

/// Where a corner's control points sit: `near = p·t` and the doubled `far = q·t` from the vertex (m).
#[derive(Clone, Copy, Debug)]
struct CornerPlacement {
    near: f64,
    far: f64,
}

/// Each corner's placement on the CCW polygon.
fn corner_geometry(ccw: &[DVec2], radius: f64, budget: ControlPointBudget) -> Vec<CornerPlacement> {
    let n = ccw.len();
    let lengths: Vec<f64> = (0..n).map(|k| side_length(ccw, k)).collect();
    let spacing = match budget {
        ControlPointBudget::MaxSpacing(h) => h,
        ControlPointBudget::Segments(count) => lengths.iter().sum::<f64>() / count.max(1) as f64,
    };
    let tangent: Vec<f64> = (0..n)
        .map(|k| {
            if radius > 0.0 {
                radius * (0.5 * turning_angle(ccw, k).abs()).tan()
            } else {
                0.5 * spacing.min(lengths[(k + n - 1) % n]).min(lengths[k])
            }
        })
        .collect();
    (0..n)
        .map(|k| {
            let (previous, next) = ((k + n - 1) % n, (k + 1) % n);
            // The split point of each side, in units of this corner's tangent length.
            let cap =
                (lengths[previous] / (tangent[previous] + tangent[k])).min(lengths[k] / (tangent[k] + tangent[next]));
            let design = remembered_design(turning_angle(ccw, k).abs(), cap);
            CornerPlacement { near: design.near * tangent[k], far: design.far * tangent[k] }
        })
        .collect()
}

// ---- corner design ----

/// `p` and `q` of a corner, in units of its tangent length.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CornerDesign {
    near: f64,
    far: f64,
}

/// Corner designs already worked out, by the bits of `(turn, cap)`: a design is a pure function
/// of the two, about 8 M instructions of golden-section search, and a scene of many equal
/// rounded boxes needs the same few again and again. The most recent [`REMEMBERED_DESIGNS`] are
/// kept (a process-wide cache: the same inputs give the same design bit for bit, so what it holds
/// never changes a result, only how long building takes).
static DESIGNS: Mutex<Vec<((u64, u64), CornerDesign)>> = Mutex::new(Vec::new());

/// How many corner designs [`DESIGNS`] keeps.
const REMEMBERED_DESIGNS: usize = 64;

/// [`design_corner`] through [`DESIGNS`].
fn remembered_design(turn: f64, cap: f64) -> CornerDesign {
    let key = (turn.to_bits(), cap.to_bits());
    // A poisoned lock still holds whole entries (each is written in one push).
    let seen = |designs: &Vec<((u64, u64), CornerDesign)>| designs.iter().find(|(k, _)| *k == key).map(|&(_, d)| d);
    if let Some(design) = seen(&DESIGNS.lock().unwrap_or_else(PoisonError::into_inner)) {
        return design;
    }
    let design = design_corner(turn, cap);
    let mut designs = DESIGNS.lock().unwrap_or_else(PoisonError::into_inner);
    if seen(&designs).is_none() {
        if designs.len() >= REMEMBERED_DESIGNS {
            designs.remove(0);
        }
        designs.push((key, design));
    }
    design
}

/// The design minimising the corner's deviation for a turn `turn ∈ (0, π)` (rad), with `q ≤ cap`.
fn design_corner(turn: f64, cap: f64) -> CornerDesign {
    let best_near =
        |far: f64| golden_section_min(|near| corner_deviation(turn, CornerDesign { near, far }), 0.2 * far, 0.98 * far);
    let (far, _) = golden_section_min(|far| best_near(far).1, cap.min(1.0), cap.min(MAX_FAR));
    let far = if far >= (1.0 - SNAP_FRACTION) * cap { cap } else { far };
    CornerDesign { near: best_near(far).0, far }
}

/// Largest distance (in tangent lengths) of a corner's three bending segments from the arc, on a
/// canonical corner: vertex at the origin, incoming side along +x, tangent length 1.
fn corner_deviation(turn: f64, design: CornerDesign) -> f64 {
    let outgoing = DVec2::from_angle(turn);
    let incoming = |s: f64| DVec2::new(-s, 0.0);
    let (near, far) = (design.near, design.far);
    let points = [incoming(far), incoming(far), incoming(near), near * outgoing, far * outgoing, far * outgoing];
    let outline = Outline::canonical_corner(turn);
    (0..3)
        .flat_map(|i| {
            let segment = CubicSegment::from_bspline(points[i], points[i + 1], points[i + 2], points[i + 3]);
            (0..=DESIGN_SAMPLES).map(move |k| segment.position(k as f64 / DESIGN_SAMPLES as f64))
        })
        .map(|p| outline.distance(p))
        .fold(0.0, f64::max)
}

/// `(x, f(x))` at the minimum of a unimodal `f` on `[lo, hi]`.
fn golden_section_min(mut f: impl FnMut(f64) -> f64, lo: f64, hi: f64) -> (f64, f64) {
    let ratio = 0.5 * (5.0_f64.sqrt() - 1.0);
    let (mut a, mut b) = (lo, hi);
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..GOLDEN_STEPS {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - ratio * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + ratio * (b - a);
            fd = f(d);
        }
    }
    if fc < fd { (c, fc) } else { (d, fd) }
}

// ---- control points ----

/// Side `k`'s straight part: interior control points, or merged with its neighbours'.
#[derive(Clone, Copy, Debug)]
struct SidePlan {
    /// Control points strictly between the two doubled points.
    interior: usize,
    /// The two corners' doubled points coincide (no straight part left).
    merged: bool,
}

/// Room (m) between the doubled points of side `k`'s two corners.
fn room(ccw: &[DVec2], geometry: &[CornerPlacement], k: usize) -> f64 {
    side_length(ccw, k) - geometry[k].far - geometry[(k + 1) % ccw.len()].far
}

fn plan_sides(
    ccw: &[DVec2],
    geometry: &[CornerPlacement],
    budget: ControlPointBudget,
) -> Result<Vec<SidePlan>, ShapeError> {
    let n = ccw.len();
    let rooms: Vec<f64> = (0..n).map(|k| room(ccw, geometry, k)).collect();
    let merged: Vec<bool> = (0..n).map(|k| rooms[k] <= MERGE_FRACTION * side_length(ccw, k)).collect();
    let base: usize = merged.iter().map(|&m| if m { 4 } else { 6 }).sum();
    let interior = match budget {
        ControlPointBudget::MaxSpacing(h) => spaced_interior(&rooms, &merged, h, base)?,
        ControlPointBudget::Segments(count) => shared_interior(&rooms, &merged, count, base)?,
    };
    Ok(interior.into_iter().zip(merged).map(|(interior, merged)| SidePlan { interior, merged }).collect())
}

fn spaced_interior(rooms: &[f64], merged: &[bool], spacing: f64, base: usize) -> Result<Vec<usize>, ShapeError> {
    let counts: Vec<usize> = rooms
        .iter()
        .zip(merged)
        .map(|(&room, &merged)| if merged { 0 } else { ((room / spacing).ceil() as usize).max(1) - 1 })
        .collect();
    let total = counts.iter().fold(base, |total, &count| total.saturating_add(count));
    if total > MAX_CONTROL_POINTS {
        return Err(ShapeError::parameter(
            "rounded_polygon.spacing",
            format!("{spacing} m would need {total} control points, more than {MAX_CONTROL_POINTS}"),
        ));
    }
    Ok(counts)
}

/// `count − base` interior points spread over the unmerged sides in proportion to their room
/// (largest remainders first, ties to the lower side).
fn shared_interior(rooms: &[f64], merged: &[bool], count: usize, base: usize) -> Result<Vec<usize>, ShapeError> {
    if count < base {
        let corners = rooms.len();
        return Err(ShapeError::parameter(
            "segments",
            format!(
                "a rounded polygon of {corners} corners needs at least {base} segments (6 per corner), got {count}"
            ),
        ));
    }
    let extra = count - base;
    let total_room: f64 = rooms.iter().zip(merged).filter(|(_, m)| !**m).map(|(r, _)| r).sum();
    if extra > 0 && total_room <= 0.0 {
        return Err(ShapeError::parameter(
            "segments",
            format!("every side is taken by its two corners, so the curve has exactly {base} segments, got {count}"),
        ));
    }
    let shares: Vec<f64> =
        rooms.iter().zip(merged).map(|(&r, &m)| if m { 0.0 } else { extra as f64 * r / total_room }).collect();
    let mut counts: Vec<usize> = shares.iter().map(|s| s.floor() as usize).collect();
    let mut order: Vec<usize> = (0..rooms.len()).filter(|&k| !merged[k]).collect();
    order.sort_by(|&i, &j| (shares[j] - shares[j].floor()).total_cmp(&(shares[i] - shares[i].floor())).then(i.cmp(&j)));
    let missing = extra - counts.iter().sum::<usize>();
    for &k in order.iter().cycle().take(missing) {
        counts[k] += 1;
    }
    Ok(counts)
}

/// Control points side by side: `b_p b_q b_q (interior) a_q a_q a_p` of each side, as distances
/// from its first corner, all on the side's line.
fn control_points(ccw: &[DVec2], geometry: &[CornerPlacement], plan: &[SidePlan]) -> Vec<DVec2> {
    let n = ccw.len();
    let mut points = Vec::new();
    for (k, side) in plan.iter().enumerate() {
        let (from, to) = (ccw[k], ccw[(k + 1) % n]);
        let length = side_length(ccw, k);
        let (start, end) = (geometry[k], geometry[(k + 1) % n]);
        let at = |distance: f64| from.lerp(to, distance / length);
        let (first, last) = (start.far, length - end.far);
        let (first, last) = if side.merged { (0.5 * (first + last), 0.5 * (first + last)) } else { (first, last) };
        points.extend([at(start.near), at(first), at(first)]);
        let step = (last - first) / (side.interior + 1) as f64;
        points.extend((1..=side.interior).map(|i| at(first + step * i as f64)));
        if !side.merged {
            points.extend([at(last), at(last)]);
        }
        points.push(at(length - end.near));
    }
    points
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn square() -> Vec<DVec2> {
        vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)]
    }

    #[test]
    fn remembered_designs_are_the_designs() {
        // More turns than the cache keeps, twice over: each answer is the search's own, whether
        // it was remembered, worked out, or worked out again after being dropped.
        let turns: Vec<f64> = (0..REMEMBERED_DESIGNS + 8).map(|k| 0.3 + 0.03 * k as f64).collect();
        for _ in 0..2 {
            for &turn in &turns {
                assert_eq!(remembered_design(turn, 1.5), design_corner(turn, 1.5), "turn {turn}");
            }
        }
        assert!(DESIGNS.lock().unwrap_or_else(PoisonError::into_inner).len() <= REMEMBERED_DESIGNS);
    }

    #[test]
    fn right_angle_design_matches_the_documented_deviation() {
        let free = design_corner(0.5 * PI, 10.0);
        let free_deviation = corner_deviation(0.5 * PI, free) / 1.0; // t = r at a right angle
        assert!(free_deviation < 0.0023, "{free:?}: {free_deviation}");
        let capped = design_corner(0.5 * PI, 1.0);
        assert_eq!(capped.far, 1.0);
        assert!(corner_deviation(0.5 * PI, capped) < 0.0130);
    }

    #[test]
    fn clockwise_corners_give_the_same_curve_as_counter_clockwise() {
        let mut cw = square();
        cw.reverse();
        let (a, fit_a) = rounded_polygon(&square(), 0.1, ControlPointBudget::Segments(32)).unwrap();
        let (b, fit_b) = rounded_polygon(&cw, 0.1, ControlPointBudget::Segments(32)).unwrap();
        assert!(a.signed_area() > 0.0 && b.signed_area() > 0.0);
        assert!((a.signed_area() - b.signed_area()).abs() < 1e-14);
        assert_eq!(fit_a.segments, 32);
        assert!((fit_a.max_deviation - fit_b.max_deviation).abs() < 1e-15);
    }

    #[test]
    fn shared_interior_spreads_by_room() {
        let counts = shared_interior(&[3.0, 1.0, 0.0], &[false, false, true], 14 + 8, 14).unwrap();
        assert_eq!(counts, vec![6, 2, 0]);
    }
}
