//! The input checks of [`rounded_polygon`](super::rounded_polygon): each refusal names the
//! parameter and the reason.

use std::f64::consts::PI;

use glam::DVec2;

use super::{
    ControlPointBudget, FIT_SLACK, MIN_TURN, ZERO_LENGTH_FRACTION, bounding_diagonal, side_length, turning_angle,
};
use crate::error::ShapeError;

fn corners_error(reason: impl Into<String>) -> ShapeError {
    ShapeError::parameter("rounded_polygon.corners", reason)
}

pub(super) fn check_corners(corners: &[DVec2]) -> Result<(), ShapeError> {
    let n = corners.len();
    if n < 3 {
        return Err(corners_error(format!("a polygon needs at least 3 corners, got {n}")));
    }
    if let Some((k, p)) = corners.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(corners_error(format!("corner {k} is not finite: ({}, {})", p.x, p.y)));
    }
    let extent = bounding_diagonal(corners);
    for k in 0..n {
        if side_length(corners, k) <= ZERO_LENGTH_FRACTION * extent {
            return Err(corners_error(format!("side {k} (corner {k} to corner {}) has zero length", (k + 1) % n)));
        }
    }
    for k in 0..n {
        let turn = turning_angle(corners, k);
        if turn.abs() < MIN_TURN {
            return Err(corners_error(format!("corner {k} is collinear with its neighbours (turn {turn:e} rad)")));
        }
        if turn.abs() > PI - MIN_TURN {
            return Err(corners_error(format!("the outline folds back on itself at corner {k}")));
        }
    }
    check_simple(corners)
}

/// No two non-adjacent sides touch or cross.
fn check_simple(corners: &[DVec2]) -> Result<(), ShapeError> {
    let n = corners.len();
    for i in 0..n {
        for j in i + 2..n {
            if (j + 1) % n == i {
                continue; // sides n-1 and 0 share corner 0
            }
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            let (c, d) = (corners[j], corners[(j + 1) % n]);
            if segments_touch(a, b, c, d) {
                return Err(corners_error(format!("the polygon intersects itself: sides {i} and {j} cross")));
            }
        }
    }
    Ok(())
}

/// Whether the closed segments `ab` and `cd` share a point (orientation tests).
fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let side = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let within = |p: DVec2, q: DVec2, r: DVec2| r.cmpge(p.min(q)).all() && r.cmple(p.max(q)).all();
    let (d1, d2) = (side(c, d, a), side(c, d, b));
    let (d3, d4) = (side(a, b, c), side(a, b, d));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return true;
    }
    (d1 == 0.0 && within(c, d, a))
        || (d2 == 0.0 && within(c, d, b))
        || (d3 == 0.0 && within(a, b, c))
        || (d4 == 0.0 && within(a, b, d))
}

pub(super) fn check_radius(corners: &[DVec2], radius: f64) -> Result<(), ShapeError> {
    let what = "rounded_polygon.corner_radius";
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(ShapeError::parameter(what, format!("must be finite and >= 0, got {radius}")));
    }
    let n = corners.len();
    let half_tan = |k: usize| (0.5 * turning_angle(corners, k % n).abs()).tan();
    let largest =
        (0..n).map(|k| side_length(corners, k) / (half_tan(k) + half_tan(k + 1))).fold(f64::INFINITY, f64::min);
    for k in 0..n {
        let needed = radius * (half_tan(k) + half_tan(k + 1));
        let length = side_length(corners, k);
        if needed > length * (1.0 + FIT_SLACK) {
            return Err(ShapeError::parameter(
                what,
                format!(
                    "{radius} does not fit side {k}: its two roundings need {} m of it but it is {} m long \
                     (the largest radius that fits every side is {})",
                    significant(needed),
                    significant(length),
                    significant(largest)
                ),
            ));
        }
    }
    Ok(())
}

/// `x` to 6 significant digits without trailing zeros (1.1999999999999997 → 1.2).
fn significant(x: f64) -> String {
    let decimals = (5 - x.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_owned() } else { text }
}

pub(super) fn check_budget(budget: ControlPointBudget) -> Result<(), ShapeError> {
    match budget {
        ControlPointBudget::MaxSpacing(h) if !(h.is_finite() && h > 0.0) => {
            Err(ShapeError::parameter("rounded_polygon.spacing", format!("must be finite and > 0, got {h}")))
        }
        _ => Ok(()),
    }
}
