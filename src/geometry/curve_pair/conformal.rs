//! Conformal pieces (parallel or matching): whether the nearest points are conformal, and the
//! two ends of the overlap in the band.

use super::*;

/// Whether the pieces are conformal at their nearest points: the gap between them, which grows
/// like `½ (k_a + k_b) x²` along the common tangent (`k` the curvature of each piece bending
/// away from the other), changes by at most `conformal_fraction` of the band over the pieces.
pub(super) fn is_conformal(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    contact: &SegmentContact,
    settings: &CurvePairSettings,
) -> bool {
    let [_, p1, p2] = a.segment.jet(contact.t);
    let [_, q1, q2] = b.segment.jet(contact.s);
    let (speed_a, speed_b) = (p1.length_squared(), q1.length_squared());
    let scale = pair_scale(&a.segment, &b.segment);
    if speed_a <= 1e-24 * scale * scale || speed_b <= 1e-24 * scale * scale {
        return false; // a cusp is a corner, never a flat contact
    }
    // Unit vector from B's point to A's point (the contact is not an intersection, so d > 0).
    let away = (contact.point_a - contact.point_b).try_normalize().unwrap_or(-contact.normal);
    let bend_a = p2.dot(away) / speed_a;
    let bend_b = -q2.dot(away) / speed_b;
    let band = contact.lambda_a + contact.lambda_b;
    0.5 * (bend_a + bend_b).abs() * scale * scale <= settings.conformal_fraction * band
}

/// The two ends of the stretch of A's piece, around the nearest point, whose nearest points on
/// B's piece are feet inside it and lie in the combined band. Returns the contacts and the
/// Newton-equivalent work (bisection steps).
pub(super) fn overlap_ends(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    centre: SegmentContact,
) -> (ContactPoints, u32) {
    let in_overlap = |t: f64| -> Option<SegmentContact> {
        let p = a.segment.position(t);
        // The 1-D nearest point (bracketed roots of the quintic, then Newton): exact, and far
        // cheaper than a 2-D search with a point piece at each of the bisection's ~40 steps.
        let s = b.segment.nearest_parameter(p).0;
        let contact = contact_at(a, b, orientation_b, t, s);
        (contact.penetration >= 0.0 && is_foot(&b.segment, s, p)).then_some(contact)
    };
    let (mut low, steps_low) = overlap_end(centre, 0.0, &in_overlap);
    let (mut high, steps_high) = overlap_end(centre, 1.0, &in_overlap);
    // A conformal patch has one normal: that of the nearest points. The ends' own normals can
    // tilt where the stretch climbs a rounded corner, and impulses along them would plough.
    low.normal = centre.normal;
    high.normal = centre.normal;
    let scale = pair_scale(&a.segment, &b.segment);
    let contacts = if low.point_a.distance(high.point_a) <= 1e-9 * scale {
        ContactPoints::one(centre)
    } else {
        ContactPoints::two(low, high)
    };
    (contacts, steps_low + steps_high)
}

/// Bisection from the centre (in the overlap) towards `bound` for the last `t` in the overlap.
pub(super) fn overlap_end(
    centre: SegmentContact,
    bound: f64,
    in_overlap: &impl Fn(f64) -> Option<SegmentContact>,
) -> (SegmentContact, u32) {
    if let Some(contact) = in_overlap(bound) {
        return (contact, 1);
    }
    let (mut inside, mut outside) = (centre, bound);
    let mut steps = 1;
    while (outside - inside.t).abs() > 1e-12 && steps < 60 {
        let mid = 0.5 * (inside.t + outside);
        match in_overlap(mid) {
            Some(contact) => inside = contact,
            None => outside = mid,
        }
        steps += 1;
    }
    (inside, steps)
}

/// Whether `q(s)` is the foot of the perpendicular from `p`: at an end of the piece, `p` must not lie
/// beyond that end.
pub(super) fn is_foot(b: &CubicSegment, s: f64, p: DVec2) -> bool {
    let along = (p - b.position(s)).dot(b.derivative(s));
    let tolerance = 1e-9 * (p - b.position(s)).length() * b.derivative(s).length() + f64::MIN_POSITIVE;
    (s > 0.0 || along >= -tolerance) && (s < 1.0 || along <= tolerance)
}
