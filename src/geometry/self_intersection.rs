//! Simplicity of a boundary: no two segments meet except adjacent ones at their shared joint
//! (MODEL §1, validity).

use crate::error::ShapeError;
use crate::geometry::curve_pair::{CurvePairSettings, intersect_segment_segment, pair_scale};
use crate::geometry::segment::CubicSegment;
use crate::geometry::spline::Spline;

/// Halvings towards a shared joint before the pieces left are too small to judge.
const JOINT_DEPTH: u32 = 40;

/// The first pair of segments `(i, j)`, `i < j`, that makes the curve non-simple, or `None`.
///
/// Non-adjacent segments must not meet at all. Adjacent segments (`j = i + 1`, and `n − 1`
/// with `0`, the wrap-around) must meet only at their shared joint, which matters at cusps
/// where repeated control points let the curve fold back on itself.
#[must_use]
pub fn find_self_intersection(spline: &Spline) -> Option<(usize, usize)> {
    find_self_intersection_with(spline, &CurvePairSettings::default())
}

/// [`find_self_intersection`] with explicit solver settings.
#[must_use]
pub fn find_self_intersection_with(spline: &Spline, settings: &CurvePairSettings) -> Option<(usize, usize)> {
    let n = spline.segment_count();
    let segments: Vec<CubicSegment> = spline.segments().collect();
    let bounds: Vec<_> = segments.iter().map(CubicSegment::bounds).collect();
    let margin = settings.intersection_tolerance * spline.extent();
    for i in 0..n {
        for j in i + 1..n {
            let ((lo_i, hi_i), (lo_j, hi_j)) = (bounds[i], bounds[j]);
            if lo_i.cmpgt(hi_j + margin).any() || lo_j.cmpgt(hi_i + margin).any() {
                continue;
            }
            let simple = if j == i + 1 {
                meet_only_at_joint(&segments[i], &segments[j], settings)
            } else if i == 0 && j == n - 1 {
                meet_only_at_joint(&segments[j], &segments[i], settings)
            } else {
                intersect_segment_segment(&segments[i], &segments[j], settings).is_none()
            };
            if !simple {
                return Some((i, j));
            }
        }
    }
    None
}

/// Whether `first` (ending at the joint) and `second` (starting there) meet nowhere else.
///
/// Halves both towards the joint: the halves away from it must not meet the other piece; the
/// two halves at the joint are split again, until they are too small to tell apart.
fn meet_only_at_joint(first: &CubicSegment, second: &CubicSegment, settings: &CurvePairSettings) -> bool {
    let smallest = 1e-9 * pair_scale(first, second);
    let (mut a, mut b) = (*first, *second);
    for _ in 0..JOINT_DEPTH {
        let (a_far, a_near) = a.split(0.5);
        let (b_near, b_far) = b.split(0.5);
        let meets = |x: &CubicSegment, y: &CubicSegment| intersect_segment_segment(x, y, settings).is_some();
        if meets(&a_far, &b) || meets(&a_near, &b_far) {
            return false;
        }
        (a, b) = (a_near, b_near);
        if pair_scale(&a, &b) <= smallest {
            break;
        }
    }
    true
}

/// Full validity of a boundary: [`Spline::validate`] plus simplicity.
///
/// # Errors
/// The first failure of [`Spline::validate`], else [`ShapeError::SelfIntersecting`] naming the
/// segment pair.
pub fn validate_boundary(spline: &Spline) -> Result<(), ShapeError> {
    spline.validate()?;
    match find_self_intersection(spline) {
        Some((first, second)) => Err(ShapeError::SelfIntersecting { first, second }),
        None => Ok(()),
    }
}
