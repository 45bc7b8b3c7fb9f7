//! Oriented bounding boxes: fitting around a segment's tolerance band, and the separating-axis test (MODEL §3).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::pose::Pose;
use crate::geometry::segment::CubicSegment;

/// Points sampled on a segment (at `t = k/(m−1)`, `k = 0..m`) for its covariance (MODEL §3's `m`).
pub const COVARIANCE_SAMPLES: usize = 9;

/// A point set counts as isotropic (no principal axis) when the eigenvalue gap of its covariance is
/// below this fraction of the mean eigenvalue.
pub const ISOTROPY_TOLERANCE: f64 = 1e-9;

/// Relative slack of [`Obb::overlaps`]: two boxes count as separated only if a separating axis has a
/// gap larger than `OVERLAP_RELATIVE_SLACK · (radii along the axis + |centres|∞)`.
///
/// A few rounding errors of `2.2e-16` each enter the test (the transform of a centre, the dot
/// products); `1e-12` covers them with a wide margin, so the test never reports a separation that
/// exact arithmetic would not. The price is that boxes closer than ~`1e-12` of the body size count as
/// overlapping.
pub const OVERLAP_RELATIVE_SLACK: f64 = 1e-12;

/// Relative padding of fitted boxes, `FIT_RELATIVE_PAD · max |projection|`, so every point the box was
/// fitted to lies inside it even after the rounding of the centre reconstruction.
pub const FIT_RELATIVE_PAD: f64 = 1e-13;

/// An oriented bounding box in 2-D: plain `Copy` data.
///
/// The box is `{ centre + a·axis + b·axis.perp() : |a| ≤ half_extents.x, |b| ≤ half_extents.y }`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Obb {
    /// Centre of the box.
    pub centre: DVec2,
    /// Unit x-axis of the box; its y-axis is `axis.perp()` (counter-clockwise by 90°).
    pub axis: DVec2,
    /// Half-widths along `axis` (x) and `axis.perp()` (y), both `≥ 0`.
    pub half_extents: DVec2,
}

impl Obb {
    /// A box from its centre, unit x-axis and half-extents.
    #[must_use]
    pub fn new(centre: DVec2, axis: DVec2, half_extents: DVec2) -> Self {
        debug_assert!((axis.length() - 1.0).abs() < 1e-9, "OBB axis {axis} is not a unit vector");
        debug_assert!(half_extents.cmpge(DVec2::ZERO).all(), "negative OBB half-extents {half_extents}");
        Self { centre, axis, half_extents }
    }

    /// The box's y-axis, `axis` turned counter-clockwise by 90°.
    #[must_use]
    pub fn perp_axis(&self) -> DVec2 {
        self.axis.perp()
    }

    /// The smallest box with x-axis `axis` (unit) holding every point of `points`.
    ///
    /// # Panics
    /// In debug builds, if `points` is empty.
    #[must_use]
    pub fn fitted(axis: DVec2, points: impl IntoIterator<Item = DVec2>) -> Self {
        let perp = axis.perp();
        let mut low = DVec2::splat(f64::INFINITY);
        let mut high = DVec2::splat(f64::NEG_INFINITY);
        for p in points {
            let local = DVec2::new(p.dot(axis), p.dot(perp));
            low = low.min(local);
            high = high.max(local);
        }
        debug_assert!(low.cmple(high).all(), "Obb::fitted needs at least one point");
        Self::from_local_ranges(axis, low, high)
    }

    /// The box with x-axis `axis` whose projections on `axis` and `axis.perp()` span `low..=high`.
    fn from_local_ranges(axis: DVec2, low: DVec2, high: DVec2) -> Self {
        let pad = FIT_RELATIVE_PAD * low.abs().max(high.abs()).max_element();
        let middle = 0.5 * (low + high);
        let centre = middle.x * axis + middle.y * axis.perp();
        Self::new(centre, axis, 0.5 * (high - low) + DVec2::splat(pad))
    }

    /// The elementary box of a segment (MODEL §3): x-axis the principal axis of
    /// [`COVARIANCE_SAMPLES`] points on the segment, extents the exact projection ranges of the
    /// segment, fattened on every side by `band` (the maximum tolerance on the segment).
    #[must_use]
    pub fn around_segment(segment: &CubicSegment, band: f64) -> Self {
        debug_assert!(band >= 0.0 && band.is_finite(), "band {band} must be finite and >= 0");
        let axis = segment_principal_axis(segment);
        let (x_low, x_high) = segment.projection_range(axis);
        let (y_low, y_high) = segment.projection_range(axis.perp());
        Self::from_local_ranges(axis, DVec2::new(x_low, y_low), DVec2::new(x_high, y_high)).fattened(band)
    }

    /// The box grown by `margin` on every side.
    #[must_use]
    pub fn fattened(&self, margin: f64) -> Self {
        Self { half_extents: self.half_extents + DVec2::splat(margin), ..*self }
    }

    /// The box moved by a rigid motion (body frame → world, or any frame → another).
    #[must_use]
    pub fn transformed(&self, pose: &Pose) -> Self {
        Self { centre: pose.transform_point(self.centre), axis: pose.rotate(self.axis), ..*self }
    }

    /// The four corners, counter-clockwise from `centre − hx·axis − hy·perp`.
    #[must_use]
    pub fn corners(&self) -> [DVec2; 4] {
        let x = self.half_extents.x * self.axis;
        let y = self.half_extents.y * self.perp_axis();
        [self.centre - x - y, self.centre + x - y, self.centre + x + y, self.centre - x + y]
    }

    /// Whether `point` lies in the box grown by `slack` on every side (a negative slack asks for
    /// a margin: the point is then at least `−slack` inside each side).
    #[must_use]
    pub fn contains_point(&self, point: DVec2, slack: f64) -> bool {
        let local = point - self.centre;
        local.dot(self.axis).abs() <= self.half_extents.x + slack
            && local.dot(self.perp_axis()).abs() <= self.half_extents.y + slack
    }

    /// Axis-aligned bounds `(min, max)` of the box.
    #[must_use]
    pub fn world_aabb(&self) -> (DVec2, DVec2) {
        let reach = self.half_extents.x * self.axis.abs() + self.half_extents.y * self.perp_axis().abs();
        (self.centre - reach, self.centre + reach)
    }

    /// Largest gap over the four edge normals: `> 0` is the width of a separating slab, `≤ 0` means
    /// the boxes overlap (exact arithmetic; no slack). For tests and diagnostics.
    #[must_use]
    pub fn separation(&self, other: &Obb) -> f64 {
        self.axis_gaps(other).into_iter().map(|(gap, _)| gap).fold(f64::NEG_INFINITY, f64::max)
    }

    /// Separating-axis test on the four edge normals; conservative under rounding
    /// (see [`OVERLAP_RELATIVE_SLACK`]): a pair reported disjoint is disjoint.
    ///
    /// Always inlined: called, the tree descents stored both boxes to memory for it at every
    /// test (in the landing pile of 100 blobs, 0.3 M instructions a step).
    #[must_use]
    #[inline(always)]
    pub fn overlaps(&self, other: &Obb) -> bool {
        self.overlaps_reaching(other, (self.centre_reach(), other.centre_reach()))
    }

    /// `|centre|∞`, what [`Obb::overlaps`] scales its slack by (with the other box's).
    #[must_use]
    #[inline(always)]
    pub fn centre_reach(&self) -> f64 {
        self.centre.abs().max_element()
    }

    /// [`Obb::overlaps`] with each box's [`Obb::centre_reach`] given, for a caller that tests a
    /// box many times: the same operations on the same numbers, so the same answer.
    #[must_use]
    #[inline(always)]
    pub fn overlaps_reaching(&self, other: &Obb, (reach, other_reach): (f64, f64)) -> bool {
        let scale = reach + other_reach;
        // The same tests as `axis_gaps`, stopping at the first separating axis (most pairs of a
        // tree descent are told apart by one or two axes).
        let (a, b) = (self.axis, other.axis);
        let (cos, sin) = (a.dot(b).abs(), a.perp_dot(b).abs());
        let (ha, hb) = (self.half_extents, other.half_extents);
        let d = other.centre - self.centre;
        let apart = |distance: f64, radii: f64| distance - radii > OVERLAP_RELATIVE_SLACK * (radii + scale);
        !(apart(d.dot(a).abs(), ha.x + hb.x * cos + hb.y * sin)
            || apart(d.dot(a.perp()).abs(), ha.y + hb.x * sin + hb.y * cos)
            || apart(d.dot(b).abs(), hb.x + ha.x * cos + ha.y * sin)
            || apart(d.dot(b.perp()).abs(), hb.y + ha.x * sin + ha.y * cos))
    }

    /// `(|d·n| − rA − rB, rA + rB)` for the normals `n` = a, a⊥, b, b⊥ (Gottschalk's 2-D form:
    /// the relative rotation is `(cos, sin) = (a·b, a×b)`).
    fn axis_gaps(&self, other: &Obb) -> [(f64, f64); 4] {
        let (a, b) = (self.axis, other.axis);
        let (cos, sin) = (a.dot(b).abs(), a.perp_dot(b).abs());
        let (ha, hb) = (self.half_extents, other.half_extents);
        let d = other.centre - self.centre;
        let radii = [
            ha.x + hb.x * cos + hb.y * sin,
            ha.y + hb.x * sin + hb.y * cos,
            hb.x + ha.x * cos + ha.y * sin,
            hb.y + ha.x * sin + ha.y * cos,
        ];
        let distances = [d.dot(a).abs(), d.dot(a.perp()).abs(), d.dot(b).abs(), d.dot(b.perp()).abs()];
        std::array::from_fn(|k| (distances[k] - radii[k], radii[k]))
    }
}

/// Unit eigenvector of the largest eigenvalue of the points' covariance (closed-form 2×2), with a
/// non-negative x (or, for x = 0, positive y) so the result is deterministic.
///
/// `None` for fewer than two points, coincident points, an isotropic spread (eigenvalue gap below
/// [`ISOTROPY_TOLERANCE`] of the mean) or non-finite input.
#[must_use]
pub fn principal_axis(points: &[DVec2]) -> Option<DVec2> {
    if points.len() < 2 {
        return None;
    }
    let mean = points.iter().copied().sum::<DVec2>() / points.len() as f64;
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for &p in points {
        let d = p - mean;
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
    }
    let half_difference = 0.5 * (xx - yy);
    let gap = half_difference.hypot(xy); // half the eigenvalue gap
    let anisotropic = gap > ISOTROPY_TOLERANCE * 0.5 * (xx + yy); // false for NaN too
    if !anisotropic {
        return None;
    }
    // (A − λ₁I) has rows (xx − λ₁, xy), (xy, yy − λ₁); take the eigenvector from the row that
    // does not cancel: λ₁ − yy = half_difference + gap, λ₁ − xx = gap − half_difference.
    let vector = if half_difference >= 0.0 {
        DVec2::new(half_difference + gap, xy)
    } else {
        DVec2::new(xy, gap - half_difference)
    };
    vector.try_normalize().map(canonical_direction)
}

/// `axis` or `−axis`, whichever has x > 0 (or x = 0 and y > 0).
fn canonical_direction(axis: DVec2) -> DVec2 {
    if axis.x < 0.0 || (axis.x == 0.0 && axis.y < 0.0) { -axis } else { axis }
}

/// The x-axis of a segment's elementary box: the principal axis of [`COVARIANCE_SAMPLES`] regular
/// samples, else (isotropic or degenerate samples) the chord direction, else `X`.
#[must_use]
pub fn segment_principal_axis(segment: &CubicSegment) -> DVec2 {
    let last = (COVARIANCE_SAMPLES - 1) as f64;
    let samples: [DVec2; COVARIANCE_SAMPLES] = std::array::from_fn(|k| segment.position(k as f64 / last));
    principal_axis(&samples)
        .or_else(|| (segment.bezier[3] - segment.bezier[0]).try_normalize().map(canonical_direction))
        .unwrap_or(DVec2::X)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_axis_of_a_tilted_line_is_the_line() {
        let direction = DVec2::new(3.0, -4.0).normalize();
        let points: Vec<DVec2> = (0..10).map(|k| DVec2::new(1.0, 2.0) + k as f64 * direction).collect();
        let axis = principal_axis(&points).unwrap();
        assert!(axis.perp_dot(direction).abs() < 1e-14 && axis.x > 0.0);
    }

    #[test]
    fn isotropic_and_degenerate_points_have_no_axis() {
        let square = [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y];
        assert_eq!(principal_axis(&square), None);
        assert_eq!(principal_axis(&[DVec2::ONE; 5]), None);
        assert_eq!(principal_axis(&[DVec2::ONE]), None);
    }

    #[test]
    fn straight_segment_box_is_the_fattened_chord() {
        let segment =
            CubicSegment { bezier: [DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, 2.0), DVec2::splat(3.0)] };
        let obb = Obb::around_segment(&segment, 0.1);
        assert!((obb.half_extents - DVec2::new(18f64.sqrt() / 2.0 + 0.1, 0.1)).abs().max_element() < 1e-12);
        assert!((obb.centre - DVec2::splat(1.5)).length() < 1e-12);
    }

    #[test]
    fn world_aabb_holds_the_corners_tightly() {
        let obb = Obb::new(DVec2::new(1.0, -2.0), DVec2::from_angle(0.6), DVec2::new(2.0, 0.5));
        let (low, high) = obb.world_aabb();
        let corners = obb.corners();
        let seen_low = corners.iter().copied().fold(DVec2::INFINITY, DVec2::min);
        let seen_high = corners.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max);
        assert!((low - seen_low).abs().max_element() < 1e-14 && (high - seen_high).abs().max_element() < 1e-14);
    }

    #[test]
    fn separation_is_the_gap_of_axis_aligned_boxes() {
        let a = Obb::new(DVec2::ZERO, DVec2::X, DVec2::ONE);
        let b = Obb::new(DVec2::new(2.5, 0.3), DVec2::X, DVec2::ONE);
        assert!((a.separation(&b) - 0.5).abs() < 1e-15);
        assert!(!a.overlaps(&b));
        assert!(a.overlaps(&Obb { centre: DVec2::new(2.0, 0.0), ..b }), "touching boxes overlap");
    }
}
