//! Periodic uniform cubic B-spline boundaries (MODEL §1).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::error::ShapeError;
use crate::geometry::quadrature::gauss_legendre_6;
use crate::geometry::ray::{Ray, ray_crossings};
use crate::geometry::segment::CubicSegment;

/// Areas below this fraction of the squared bounding-box diagonal count as degenerate.
pub const DEGENERATE_AREA_FRACTION: f64 = 1e-9;

/// A closed, periodic, uniform cubic B-spline curve: the boundary of a body in its body frame.
///
/// Segment `i` (for `i` in `0..n`) uses control points `c[i-1], c[i], c[i+1], c[i+2]` (indices
/// mod `n`); the global parameter is `u = i + t ∈ [0, n)`, `t ∈ [0, 1]`.
/// Built through [`Spline::from_control_points`], the curve runs counter-clockwise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "ControlPoints", into = "ControlPoints")]
pub struct Spline {
    control_points: Vec<DVec2>,
    /// Each segment in Bézier form ([`Spline::segment`]), worked out once from the control
    /// points: the narrow phase places a body's pieces, and re-evaluates its reused contacts,
    /// at every sub-step (docs/performance.md). Not serialised.
    segments: Vec<CubicSegment>,
}

/// What a [`Spline`] is serialised as: its control points alone (the segments follow from them).
#[derive(Clone, Serialize, Deserialize)]
#[serde(rename = "Spline")]
struct ControlPoints {
    control_points: Vec<DVec2>,
}

impl From<ControlPoints> for Spline {
    fn from(points: ControlPoints) -> Self {
        Self::with_segments(points.control_points)
    }
}

impl From<Spline> for ControlPoints {
    fn from(spline: Spline) -> Self {
        Self { control_points: spline.control_points }
    }
}

/// A point on a curve: global parameter, position and distance to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint {
    /// Global parameter `u ∈ [0, n)`.
    pub parameter: f64,
    /// Position on the curve.
    pub position: DVec2,
    /// Distance from the query point.
    pub distance: f64,
}

impl Spline {
    /// Builds a curve from control points that run counter-clockwise.
    ///
    /// Clockwise input is refused, not reversed: segment `i` of the curve is the one the user
    /// numbered `i`, so per-segment rugosity, contacts and events all speak of the user's own
    /// segments. Reverse the list to use a clockwise outline.
    ///
    /// # Errors
    /// [`ShapeError::TooFewControlPoints`], [`ShapeError::NonFiniteControlPoint`],
    /// [`ShapeError::DegenerateArea`] or [`ShapeError::NegativeArea`] (clockwise).
    /// Self-intersection is checked by [`validate_boundary`](crate::validate_boundary), which needs the
    /// curve-pair solver.
    pub fn from_control_points(control_points: Vec<DVec2>) -> Result<Self, ShapeError> {
        let spline = Self::with_segments(control_points);
        spline.validate()?;
        Ok(spline)
    }

    /// Wraps control points as they are: no checks, no reordering. Call [`Spline::validate`] later.
    #[must_use]
    pub fn from_control_points_unchecked(control_points: Vec<DVec2>) -> Self {
        Self::with_segments(control_points)
    }

    /// The curve of `control_points` with its segments worked out (none without control
    /// points: [`Spline::validate`] refuses that curve).
    fn with_segments(control_points: Vec<DVec2>) -> Self {
        let n = control_points.len() as isize;
        let point = |i: isize| control_points[i.rem_euclid(n) as usize];
        let segments =
            (0..n).map(|i| CubicSegment::from_bspline(point(i - 1), point(i), point(i + 1), point(i + 2))).collect();
        Self { control_points, segments }
    }

    /// Checks the invariants: at least 4 finite control points, CCW, area clearly positive.
    ///
    /// # Errors
    /// The first violated invariant as a [`ShapeError`].
    pub fn validate(&self) -> Result<(), ShapeError> {
        check_control_points(&self.control_points)?;
        let area = self.signed_area();
        check_area(area, self.extent())?;
        if area < 0.0 {
            return Err(ShapeError::NegativeArea { area });
        }
        Ok(())
    }

    /// The control points, in order.
    #[must_use]
    pub fn control_points(&self) -> &[DVec2] {
        &self.control_points
    }

    /// Number of segments (equal to the number of control points).
    #[must_use]
    pub fn segment_count(&self) -> usize {
        self.control_points.len()
    }

    /// Control point `i` with periodic indexing (any integer).
    #[must_use]
    pub fn control_point(&self, i: isize) -> DVec2 {
        let n = self.control_points.len() as isize;
        self.control_points[i.rem_euclid(n) as usize]
    }

    /// Segment `i` in Bézier form.
    #[must_use]
    pub fn segment(&self, i: usize) -> CubicSegment {
        // Indices past the last segment wrap, as the parameter does.
        match self.segments.get(i) {
            Some(&segment) => segment,
            None => self.segments[i % self.segments.len()],
        }
    }

    /// Iterator over all segments in Bézier form.
    pub fn segments(&self) -> impl ExactSizeIterator<Item = CubicSegment> + '_ {
        self.segments.iter().copied()
    }

    /// Splits a global parameter into `(segment, local t)`, wrapping `u` into `[0, n)`.
    #[must_use]
    pub fn split_parameter(&self, u: f64) -> (usize, f64) {
        let n = self.segment_count();
        let wrapped = u.rem_euclid(n as f64);
        let segment = (wrapped.floor() as usize).min(n - 1);
        (segment, (wrapped - segment as f64).clamp(0.0, 1.0))
    }

    /// Position at global parameter `u`.
    #[must_use]
    pub fn position(&self, u: f64) -> DVec2 {
        let (i, t) = self.split_parameter(u);
        self.segment(i).position(t)
    }

    /// First derivative `dp/du` at `u`.
    #[must_use]
    pub fn derivative(&self, u: f64) -> DVec2 {
        let (i, t) = self.split_parameter(u);
        self.segment(i).derivative(t)
    }

    /// Second derivative `d²p/du²` at `u`.
    #[must_use]
    pub fn second_derivative(&self, u: f64) -> DVec2 {
        let (i, t) = self.split_parameter(u);
        self.segment(i).second_derivative(t)
    }

    /// Outward unit normal `normalize((y', −x'))` of the CCW curve at `u`.
    ///
    /// Where the derivative vanishes (a cusp from repeated control points) the normal of the
    /// chord through the neighbouring parameters is used, so the result is always a unit vector.
    #[must_use]
    pub fn outward_normal(&self, u: f64) -> DVec2 {
        outward_normal_from_tangent(self.derivative(u))
            .or_else(|| outward_normal_from_tangent(self.position(u + 1e-4) - self.position(u - 1e-4)))
            .unwrap_or(DVec2::Y)
    }

    /// Signed enclosed area `½∮(x dy − y dx)`; positive for a CCW curve.
    #[must_use]
    pub fn signed_area(&self) -> f64 {
        self.segments()
            .map(|s| {
                gauss_legendre_6(0.0, 1.0, |t| {
                    let p = s.position(t);
                    p.perp_dot(s.derivative(t))
                })
            })
            .sum::<f64>()
            * 0.5
    }

    /// Total arc length.
    #[must_use]
    pub fn arc_length(&self) -> f64 {
        self.segments().map(|s| s.arc_length()).sum()
    }

    /// Tight axis-aligned bounds `(min, max)` of the curve.
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        self.segments()
            .map(|s| s.bounds())
            .fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(lo, hi), (a, b)| {
                (lo.min(a), hi.max(b))
            })
    }

    /// Diagonal of the control polygon's bounding box: the size scale of the curve.
    #[must_use]
    pub fn extent(&self) -> f64 {
        let lo = self.control_points.iter().copied().fold(DVec2::splat(f64::INFINITY), DVec2::min);
        let hi = self.control_points.iter().copied().fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
        (hi - lo).length()
    }

    /// Largest distance from `centre` to the curve (the boundary radius about it).
    #[must_use]
    pub fn radius_about(&self, centre: DVec2) -> f64 {
        self.segments().map(|s| s.bezier.iter().map(|b| b.distance(centre)).fold(0.0, f64::max)).fold(0.0, f64::max)
    }

    /// Nearest point of the curve to `point` (global minimum over all segments).
    #[must_use]
    pub fn nearest_point(&self, point: DVec2) -> CurvePoint {
        let mut best = CurvePoint { parameter: 0.0, position: self.position(0.0), distance: f64::INFINITY };
        for (i, segment) in self.segments().enumerate() {
            if segment.hull_distance_squared_lower_bound(point) >= best.distance * best.distance {
                continue;
            }
            let (t, distance) = segment.nearest_parameter(point);
            if distance < best.distance {
                best = CurvePoint { parameter: i as f64 + t, position: segment.position(t), distance };
            }
        }
        best
    }

    /// Winding number of the curve around `point` (1 inside a CCW simple curve, 0 outside),
    /// summed exactly over the crossings of a ray from the point along +x (`+1` where the curve
    /// crosses it upwards, `−1` downwards, 0 at a tangency; `geometry::ray`). A point on the
    /// curve itself may fall either way.
    #[must_use]
    pub fn winding_number(&self, point: DVec2) -> i32 {
        let ray = Ray { origin: point, direction: DVec2::X, max_distance: f64::INFINITY };
        let mut winding = 0.0;
        for piece in self.segments() {
            let (low, high) =
                piece.bezier.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.y), hi.max(p.y)));
            if low > point.y || high < point.y || piece.bezier.iter().all(|p| p.x < point.x) {
                continue;
            }
            winding += ray_crossings(&ray, &piece).iter().map(|c| c.side).sum::<f64>();
        }
        winding as i32
    }

    /// The curve with every control point mapped by `f` (e.g. a rigid motion or a scaling).
    #[must_use]
    pub fn mapped(&self, f: impl Fn(DVec2) -> DVec2) -> Self {
        Self::with_segments(self.control_points.iter().map(|&c| f(c)).collect())
    }

    /// The curve shifted by `offset`.
    #[must_use]
    pub fn translated(&self, offset: DVec2) -> Self {
        self.mapped(|c| c + offset)
    }
}

/// Outward normal of a CCW curve from its tangent, `None` for a (near-)zero tangent.
#[must_use]
pub fn outward_normal_from_tangent(tangent: DVec2) -> Option<DVec2> {
    DVec2::new(tangent.y, -tangent.x).try_normalize()
}

fn check_control_points(points: &[DVec2]) -> Result<(), ShapeError> {
    if points.len() < 4 {
        return Err(ShapeError::TooFewControlPoints { count: points.len() });
    }
    if let Some((index, p)) = points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(ShapeError::NonFiniteControlPoint { index, x: p.x, y: p.y });
    }
    Ok(())
}

fn check_area(area: f64, extent: f64) -> Result<(), ShapeError> {
    if !area.is_finite() || area.abs() <= DEGENERATE_AREA_FRACTION * extent * extent || extent == 0.0 {
        return Err(ShapeError::DegenerateArea { area, extent });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<DVec2> {
        vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)]
    }

    #[test]
    fn clockwise_input_is_refused_not_renumbered() {
        let mut cw = square();
        cw.reverse();
        let error = Spline::from_control_points(cw.clone()).unwrap_err();
        assert!(matches!(error, ShapeError::NegativeArea { area } if area < 0.0), "{error}");
        cw.reverse();
        let spline = Spline::from_control_points(cw.clone()).unwrap();
        assert_eq!(spline.control_points(), cw.as_slice(), "kept in the user's order");
    }

    #[test]
    fn curve_is_c2_across_joints() {
        let spline = Spline::from_control_points(vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, -0.5),
            DVec2::new(3.0, 1.0),
            DVec2::new(1.5, 2.5),
            DVec2::new(-0.5, 1.5),
        ])
        .unwrap();
        for i in 0..5 {
            let a = spline.segment(i);
            let b = spline.segment((i + 1) % 5);
            assert!((a.position(1.0) - b.position(0.0)).length() < 1e-14);
            assert!((a.derivative(1.0) - b.derivative(0.0)).length() < 1e-13);
            assert!((a.second_derivative(1.0) - b.second_derivative(0.0)).length() < 1e-13);
        }
    }

    #[test]
    fn outward_normal_points_away_from_the_inside() {
        let spline = Spline::from_control_points(square()).unwrap();
        let centre = DVec2::splat(0.5);
        for k in 0..40 {
            let u = k as f64 * 0.1;
            assert!((spline.position(u) - centre).dot(spline.outward_normal(u)) > 0.0);
        }
    }

    #[test]
    fn nearest_point_matches_dense_sampling() {
        let spline = Spline::from_control_points(square()).unwrap();
        for &q in &[DVec2::new(2.0, 0.3), DVec2::new(0.5, 0.5), DVec2::new(-1.0, -1.0)] {
            let found = spline.nearest_point(q);
            let sampled =
                (0..40_000).map(|k| spline.position(k as f64 * 1e-4).distance(q)).fold(f64::INFINITY, f64::min);
            assert!(found.distance <= sampled + 1e-12 && sampled - found.distance < 1e-7);
        }
    }

    #[test]
    fn winding_number_inside_and_outside() {
        let spline = Spline::from_control_points(square()).unwrap();
        assert_eq!(spline.winding_number(DVec2::splat(0.5)), 1);
        assert_eq!(spline.winding_number(DVec2::splat(5.0)), 0);
    }
}
