//! Conformal pieces (parallel or matching): whether the nearest points are conformal, and the
//! two ends of the overlap in the band.

use super::straight::{FlatSide, curved_overlap, flat_side, straight_overlap};
use super::*;

/// Whether the pieces are conformal at their nearest points: the gap between them, which grows
/// like `½ (k_a + k_b) x² + ⅙ (k′_a + k′_b) x³` along the common tangent (`k` the curvature of
/// each piece bending away from the other, `k′` its rate of change along A's direction),
/// changes by at most `conformal_fraction` of the band over the pieces.
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
    // Each piece's curvature, positive where it bends towards `away`: its acceleration across
    // its own tangent. (The acceleration along `away` is the same where `away` is normal to the
    // piece, at an inner nearest point, but at a nearest point on a piece's end it also counts
    // the acceleration along the tangent: a straight piece whose control points are unevenly
    // spaced then looked bent once tilted, and a box tilted by 1e-4 rad on the ground kept only
    // the contact at its lower corner and rocked from corner to corner.)
    // With its rate of change along the piece, `p‴` across over `|p′|³` (constant on a cubic):
    // the gap grows like `½ k x² + ⅙ k′ x³`. That term is odd in `x`, the arc length along A's
    // piece: B's pieces facing A's usually run the other way, and then B's term changes sign.
    let bend = |velocity: DVec2, acceleration: DVec2, jerk: DVec2, speed: f64| {
        let normal = velocity.perp() / speed.sqrt();
        let towards = if normal.dot(away) < 0.0 { -normal } else { normal };
        (acceleration.dot(towards) / speed, jerk.dot(towards) / (speed * speed.sqrt()))
    };
    let (bend_a, turn_a) = bend(p1, p2, a.segment.third_derivative(), speed_a);
    let (bend_b, turn_b) = bend(q1, q2, b.segment.third_derivative(), speed_b);
    let band = contact.lambda_a + contact.lambda_b;
    let along = if p1.dot(q1) < 0.0 { -1.0 } else { 1.0 };
    let growth =
        0.5 * (bend_a - bend_b).abs() * scale * scale + (turn_a - along * turn_b).abs() * scale * scale * scale / 6.0;
    growth <= settings.conformal_fraction * band
}

/// The two ends of the stretch of A's piece, around the nearest point, that lies in the
/// combined band and between the normals of B's piece at its ends (so that its nearest points
/// on B are feet inside the piece). Returns the contacts and the Newton-equivalent work
/// (evaluations of the margins).
pub(super) fn overlap_ends(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    centre: SegmentContact,
) -> (ContactPoints, u32) {
    let (mut low, mut high, steps) =
        fast_ends(a, b, orientation_b, centre).unwrap_or_else(|| secant_ends(a, b, orientation_b, None, centre));
    // A conformal patch has one normal: that of the nearest points. The ends' own normals can
    // tilt where the stretch climbs a rounded corner, and impulses along them would plough.
    let normal = patch_normal(a, b, &centre);
    low.normal = normal;
    high.normal = normal;
    let scale = pair_scale(&a.segment, &b.segment);
    let contacts = if low.point_a.distance(high.point_a) <= 1e-9 * scale {
        ContactPoints::one(SegmentContact { normal, ..centre })
    } else {
        ContactPoints::two(low, high)
    };
    (contacts, steps)
}

/// The normal of a conformal patch: that of the piece the line between the nearest points is
/// normal to, pointing from B to A.
///
/// Where both nearest points are inside their pieces the line is normal to both and the two
/// normals agree. Where one is a piece's end (a flat tilted against another within the band
/// touches it with its end first), only the other piece's normal is the normal of the nearest
/// points: a corner on a face pushes along the face's normal. B's normal at its end, taken
/// before, made the result depend on which body came first: a box tilted by 2e-3 rad on flat
/// frictionless ground slid sideways at 1.45 cm/s when added after the ground and not at all
/// when added before it.
fn patch_normal(a: &TolerancedSegment, b: &TolerancedSegment, centre: &SegmentContact) -> DVec2 {
    let Some(away) = (centre.point_a - centre.point_b).try_normalize() else { return centre.normal };
    let tangent = |segment: &CubicSegment, u: f64| segment.derivative(u).try_normalize();
    match (tangent(&a.segment, centre.t), tangent(&b.segment, centre.s)) {
        (Some(along_a), Some(along_b)) if along_a.dot(away).abs() < along_b.dot(away).abs() => {
            let normal = along_a.perp();
            if normal.dot(centre.normal) < 0.0 { -normal } else { normal }
        }
        _ => centre.normal,
    }
}

/// The ends when one piece is straight and the bands constant: when B's is, in closed form if
/// A's is straight too, else by the secant on margins affine in A's point; when only A's is, by
/// the secant in B's parameter, where the foot on A's line is explicit ([`curved_overlap`]).
/// `None`: the general path.
///
/// (Measuring the stretch of B's piece between A's normals where only A's is straight was
/// tried: it is as cheap, but near a rounded corner its ends differ from those of A's stretch
/// by up to the band times the slope between the pieces, and at a joint of B's pieces the two
/// views gave two ends 5e-7 m apart that did not merge: 4 % more contacts in a pyramid.
/// [`curved_overlap`] finds A's stretch, only searched through B's parameter.)
fn fast_ends(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    centre: SegmentContact,
) -> Option<(SegmentContact, SegmentContact, u32)> {
    match flat_side(a, b) {
        Some(flat) => Some(
            straight_overlap(a, b, orientation_b, &flat, centre)
                .unwrap_or_else(|| secant_ends(a, b, orientation_b, Some(&flat), centre)),
        ),
        None => curved_overlap(a, b, orientation_b, centre),
    }
}

/// The ends of the stretch of A's piece around `centre` in the band and between B's normals,
/// each by the secant on its margins ([`overlap_end`]) from an anchor inside B's normals.
fn secant_ends(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    flat: Option<&FlatSide>,
    centre: SegmentContact,
) -> (SegmentContact, SegmentContact, u32) {
    let (anchor, steps_anchor) = anchor(a, b, orientation_b, centre);
    let (low, steps_low) = overlap_end(a, b, orientation_b, flat, anchor, 0.0);
    let (high, steps_high) = overlap_end(a, b, orientation_b, flat, anchor, 1.0);
    (low, high, steps_anchor + steps_low + steps_high)
}

/// A point of the overlap to search its ends from: the nearest points, unless they lie just
/// beyond the normal at an end of B's piece (the nearest point is that end), when the overlap
/// ends before them: then the last point inside that normal. So the ends found do not depend on
/// where along the overlap the search starts.
fn anchor(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    centre: SegmentContact,
) -> (SegmentContact, u32) {
    let mut steps = 0;
    for foot in foot_margins(&b.segment) {
        let margin = |t: f64| foot(a.segment.position(t));
        let at_centre = margin(centre.t);
        steps += 1;
        if at_centre >= 0.0 {
            continue;
        }
        // The side of the centre where the margin turns positive, if any.
        let Some((side, at_side)) = [0.0, 1.0].into_iter().map(|t| (t, margin(t))).find(|&(_, g)| g >= 0.0) else {
            break;
        };
        let (inside, spent) = last_inside(&margin, side, at_side, centre.t, at_centre);
        let point = b.segment.nearest_parameter(a.segment.position(inside)).0;
        let moved = contact_at(a, b, orientation_b, inside, point);
        steps += spent + 3;
        if moved.penetration >= 0.0 {
            return (moved, steps);
        }
        break;
    }
    (centre, steps)
}

/// How closely the ends of an overlap are found, in the piece's parameter: 1e-9 of a segment,
/// far below anything the band resolves.
pub(super) const END_TOLERANCE: f64 = 1e-9;

/// The end of the overlap from the centre towards `bound` (0 or 1). The overlap ends where the
/// first of three margins turns negative: how far `p(t)` lies inside the normal of B's piece at
/// either end, and the penetration into the band. Each margin is smooth in `t` (the
/// penetration as long as the foot is inside B's piece), so each root is found by a secant
/// ([`last_inside`]) between the centre and the nearest root so far.
fn overlap_end(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    flat: Option<&FlatSide>,
    centre: SegmentContact,
    bound: f64,
) -> (SegmentContact, u32) {
    // The 1-D nearest point (bracketed roots of the quintic, then Newton): exact, and far cheaper
    // than a 2-D search with a point piece.
    // The last contact evaluated is kept: where the whole stretch up to `bound` is in the band
    // (a flat on a flat), the end's contact is the one its penetration was tested with.
    let last = std::cell::Cell::new(None::<SegmentContact>);
    let contact = |t: f64| {
        let found = contact_at(a, b, orientation_b, t, b.segment.nearest_parameter(a.segment.position(t)).0);
        last.set(Some(found));
        found
    };
    // Against a flat B with A's piece on one side of its line, the penetration within B's
    // normals is affine in A's point: no nearest point per evaluation.
    let affine = flat.and_then(|flat| flat.one_side(&a.segment).map(|sign| (flat, sign)));
    let penetration = |t: f64| match affine {
        Some((flat, sign)) => flat.band - sign * flat.side(a.segment.position(t)),
        None => contact(t).penetration,
    };
    let [from_start, to_end] = foot_margins(&b.segment);
    // The feet first: they are cheap and linear in t, and within them the penetration is smooth
    // (beyond a piece's end it grows a kink).
    let margins: [&dyn Fn(f64) -> f64; 3] =
        [&|t| from_start(a.segment.position(t)), &|t| to_end(a.segment.position(t)), &penetration];
    let mut end = bound;
    let mut steps = 0;
    for margin in margins {
        let at_end = margin(end);
        steps += 1;
        if at_end >= 0.0 {
            continue;
        }
        let (inside, spent) = last_inside(margin, centre.t, margin(centre.t).max(0.0), end, at_end);
        steps += spent + 1;
        end = inside;
    }
    match last.get() {
        Some(found) if found.t == end => (found, steps),
        _ => (contact(end), steps + 1),
    }
}

/// The last `t` from `from` (margin `g_from ≥ 0`) towards `to` (margin `g_to < 0`) where the
/// margin is still ≥ 0, to [`END_TOLERANCE`]: regula falsi with the Illinois modification
/// (superlinear on a smooth margin), a step of at least a fraction of the tolerance from either
/// end (as in Brent's method), and a bisection step whenever two steps fail to halve the
/// bracket, so it never takes many more than bisection's thirty. Returns it and the
/// evaluations spent.
pub(super) fn last_inside(margin: &dyn Fn(f64) -> f64, from: f64, g_from: f64, to: f64, g_to: f64) -> (f64, u32) {
    let (mut inside, mut g_inside) = (from, g_from);
    let (mut outside, mut g_outside) = (to, g_to);
    let mut steps = 0;
    let mut run = 0i32; // consecutive moves of one end: +n the inside one, −n the outside one
    let (mut checkpoint, mut since, mut bisect) = ((outside - inside).abs(), 0, false);
    while (outside - inside).abs() > END_TOLERANCE && steps < 120 {
        let direction = (outside - inside).signum();
        let t = if bisect || g_inside.partial_cmp(&g_outside) != Some(std::cmp::Ordering::Greater) {
            0.5 * (inside + outside)
        } else {
            let secant = inside + g_inside * (outside - inside) / (g_inside - g_outside);
            let (near_inside, near_outside) =
                (inside + 0.4 * END_TOLERANCE * direction, outside - 0.4 * END_TOLERANCE * direction);
            if !secant.is_finite() || (secant - near_inside) * direction < 0.0 {
                near_inside
            } else if (near_outside - secant) * direction < 0.0 {
                near_outside
            } else {
                secant
            }
        };
        let g = margin(t);
        steps += 1;
        if g >= 0.0 {
            (inside, g_inside) = (t, g);
            run = run.max(0) + 1;
            if run > 1 {
                g_outside *= 0.5; // Illinois: the outside end has stalled
            }
        } else {
            (outside, g_outside) = (t, g);
            run = run.min(0) - 1;
            if run < -1 {
                g_inside *= 0.5;
            }
        }
        since += 1;
        bisect = false;
        if since == 2 {
            let width = (outside - inside).abs();
            bisect = width > 0.5 * checkpoint;
            (checkpoint, since) = (width, 0);
        }
    }
    (inside, steps)
}

/// How far a point lies inside the normal of B's piece at its start and at its end (m; negative
/// beyond): for the nearly straight pieces of a conformal contact, whether its nearest point on
/// the piece is a foot of the perpendicular inside it rather than an end. Smooth in the point,
/// unlike the nearest parameter, which stops at the ends.
fn foot_margins(b: &CubicSegment) -> [impl Fn(DVec2) -> f64; 2] {
    let [q0, q1] = [b.position(0.0), b.position(1.0)];
    let chord = (q1 - q0).try_normalize().unwrap_or(DVec2::X);
    // Outward along the piece at each end: back from the start, on from the end.
    let outward =
        [-b.derivative(0.0).try_normalize().unwrap_or(chord), b.derivative(1.0).try_normalize().unwrap_or(chord)];
    // A relative tolerance keeps a point on the normal itself inside (as the foot test did).
    [(q0, outward[0]), (q1, outward[1])].map(|(end, out)| move |p: DVec2| -(p - end).dot(out) + 1e-9 * p.distance(end))
}

/// Where nearly coincident pieces cross, as `(t, s)`, searched between the two `contacts` (a
/// conformal overlap's ends) or over A's whole piece (one nearest point); `None` when A's piece
/// stays outside B's there.
///
/// Newton's nearest points cannot tell two curves that cross at an angle of 1e-9 rad from two
/// that only touch: the distance at the crossing is zero, but so nearly zero all along the
/// overlap that the search stops at any point of it. The sign of the gap can: A's point minus
/// its foot on B, along B's outward normal, is positive outside B's piece and negative inside.
/// A sign change between neighbouring points across the overlap, each gap beyond the
/// intersection tolerance, is a crossing where bisection on A's parameter finds a root (a jump
/// of the foot across zero is not one). A point whose
/// nearest point on B is an end of B's piece has no signed gap and is skipped.
pub(super) fn overlap_crossing(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    contacts: &ContactPoints,
    settings: &CurvePairSettings,
) -> Option<(f64, f64)> {
    let nearest = contacts.deepest()?;
    // Along conformal pieces the gap varies by at most `conformal_fraction` of the band, so a
    // crossing (the gap through zero) leaves the pieces at most that far apart where they are
    // nearest: a contact farther apart (every resting contact, deep in the band) cannot cross.
    // Twice the bound, as the conformal test estimates the variation from the curvature at one
    // point; pieces that are not conformal diverge faster still away from their nearest points.
    let band = nearest.lambda_a + nearest.lambda_b;
    if nearest.distance > 2.0 * settings.conformal_fraction * band {
        return None;
    }
    // A conformal overlap is searched between its ends; a single point over A's whole piece.
    let (first, last) = match contacts.as_slice() {
        [low, high] => (low.t, high.t),
        _ => (0.0, 1.0),
    };
    let tolerance = settings.intersection_tolerance * pair_scale(&a.segment, &b.segment);
    // Only a foot inside B's piece makes the gap a signed distance (`p − q` along B's normal).
    // Where the nearest point is at an end of B's piece (to 1e-6 in `s`) the point may lie
    // beyond it, off the normal, and its side is not this piece's to tell: `None`.
    let gap = |t: f64| {
        let p = a.segment.position(t);
        let s = b.segment.nearest_parameter(p).0;
        let q = b.segment.position(s);
        let foot = s > FOOT_MARGIN && s < 1.0 - FOOT_MARGIN;
        foot.then(|| ((p - q).dot(outward_normal(&b.segment, s, orientation_b, p - q)), s))
    };
    // The gap at points across the overlap, closer together near its ends, where a foot may
    // fall on an end of B's piece (no signed gap there): a sign change between two neighbouring
    // points with a signed gap is a crossing.
    const FRACTIONS: [f64; 13] = [0.0, 1e-6, 1e-3, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 0.999, 0.999_999, 1.0];
    let mut previous: Option<(f64, f64, f64)> = None;
    for fraction in FRACTIONS {
        let t = first + (last - first) * fraction;
        let Some((g, s)) = gap(t) else { continue };
        if let Some((t0, g0, s0)) = previous
            && ((g0 < -tolerance && g > tolerance) || (g0 > tolerance && g < -tolerance))
            && let Some(root) = bisect_crossing(&gap, (t0, g0, s0), (t, g, s), tolerance)
        {
            return Some(root);
        }
        if g.abs() > tolerance {
            previous = Some((t, g, s));
        }
    }
    None
}

/// How far inside B's piece (in its parameter) a foot must lie for the gap to be signed.
const FOOT_MARGIN: f64 = 1e-6;

/// The root of the signed gap between `a` and `b` (of opposite signs), by bisection on A's
/// parameter, as `(t, s)`; `None` when the gap jumps across zero instead (the foot on B leapt
/// from one stretch of B's piece to another): that is no crossing.
fn bisect_crossing(
    gap: &impl Fn(f64) -> Option<(f64, f64)>,
    a: (f64, f64, f64),
    b: (f64, f64, f64),
    tolerance: f64,
) -> Option<(f64, f64)> {
    let (mut inside, mut outside) = if a.1 < 0.0 { (a.0, b.0) } else { (b.0, a.0) };
    for _ in 0..64 {
        let middle = 0.5 * (inside + outside);
        let (g, s) = gap(middle)?;
        if g.abs() <= tolerance {
            return Some((middle, s));
        }
        if (inside - outside).abs() <= f64::EPSILON {
            return None;
        }
        if g < 0.0 { inside = middle } else { outside = middle }
    }
    None
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::*;

    /// A piece from `from` to `to`, its inner Bézier points at fractions `inner` of the chord
    /// and `bend` (m) off it to the left.
    fn piece(from: DVec2, to: DVec2, inner: [f64; 2], bend: f64) -> CubicSegment {
        let left = (to - from).perp().normalize() * bend;
        CubicSegment { bezier: [from, from.lerp(to, inner[0]) + left, from.lerp(to, inner[1]) + left, to] }
    }

    /// The closed-form nearest points of two straight pieces reach the search's minimum distance,
    /// crossing, apart, parallel (one case in four: the chords exactly parallel) or end to end.
    #[test]
    fn straight_nearest_points_match_the_search() {
        let mut rng = StdRng::seed_from_u64(5);
        let settings = CurvePairSettings::default();
        for case in 0..2000 {
            let mut inner = || {
                let mut x = [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)];
                x.sort_by(f64::total_cmp);
                x
            };
            let (inner_a, inner_b) = (inner(), inner());
            let mut point = || DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let (a0, a1, b0) = (point(), point(), point());
            let b1 = if case % 4 == 0 { b0 + (a1 - a0) * rng.random_range(-2.0..2.0) } else { point() };
            let (a, b) = (piece(a0, a1, inner_a, 0.0), piece(b0, b1, inner_b, 0.0));
            let seed = DVec2::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
            let x = straight_nearest(&a, &b, seed).expect("both pieces are straight");
            let got = a.position(x.x).distance(b.position(x.y));
            let want = closest_points_segment_segment(&a, &b, &settings).distance;
            let scale = pair_scale(&a, &b);
            assert!((got - want).abs() <= 1e-12 * scale, "case {case}: {got} against the search's {want}");
        }
        let bent = piece(DVec2::ZERO, DVec2::X, [0.3, 0.6], 1e-3);
        assert!(straight_nearest(&bent, &piece(DVec2::Y, DVec2::ONE, [0.3, 0.6], 0.0), DVec2::ZERO).is_none());
    }

    /// The fast paths (two straight pieces in closed form; B's straight, by margins affine in
    /// A's point) against the secant on the exact margins, on flat-on-flat pairs: the same ends,
    /// to the secant's tolerance; and none where only A's piece is straight.
    #[test]
    fn fast_overlap_ends_match_the_secant_on_exact_margins() {
        let mut rng = StdRng::seed_from_u64(11);
        let (lambda, mut checked, mut kinds) = (0.002, 0, [0usize; 3]);
        for case in 0..3000 {
            let kind = case % 3; // 0: both straight, 1: A bent, 2: B bent
            let mut inner = || {
                let mut x = [rng.random_range(0.05..0.95), rng.random_range(0.05..0.95)];
                x.sort_by(f64::total_cmp);
                x
            };
            let (inner_a, inner_b) = (inner(), inner());
            let bend = |rng: &mut StdRng, on: bool| if on { rng.random_range(-2e-5..2e-5) } else { 0.0 };
            // B: the top of a body below (running in −x, outward normal up), A: the bottom of a
            // body above (running in +x), tilted and shifted along.
            let length_b = rng.random_range(0.05..0.3);
            let b = piece(DVec2::new(length_b, 0.0), DVec2::ZERO, inner_b, bend(&mut rng, kind == 2));
            let length_a = rng.random_range(0.05..0.3);
            let start = rng.random_range(-0.5 * length_a..length_b);
            let tilt = rng.random_range(-2e-3..2e-3);
            let height = rng.random_range(0.3..0.95) * 2.0 * lambda;
            let from = DVec2::new(start, height);
            let a = piece(from, from + DVec2::from_angle(tilt) * length_a, inner_a, bend(&mut rng, kind == 1));
            let Some((a, b, centre)) = conformal_centre(a, b, lambda) else { continue };
            let Some(fast) = fast_ends(&a, &b, ORIENTATION, centre) else { continue };
            assert_same_ends(&a, &b, centre, fast, &format!("case {case} (kind {kind})"));
            checked += 1;
            kinds[kind] += 1;
        }
        assert!(checked > 1500 && kinds.iter().all(|&k| k > 300), "{checked} checked, {kinds:?} by kind");
    }

    /// Two straight sides whose joints line up (A's piece starts where B's ends, to within 1e-12
    /// of the length either way, as in a pyramid of boxes): the closed-form stretch is empty or
    /// a point, and the overlap is the nearest points alone, as the secant finds it.
    #[test]
    fn a_sliver_of_two_straight_sides_is_the_nearest_points() {
        let mut rng = StdRng::seed_from_u64(13);
        let (lambda, mut checked) = (0.002, 0);
        for case in 0..1000 {
            let length_b = rng.random_range(0.05..0.3);
            let b = piece(DVec2::new(length_b, 0.0), DVec2::ZERO, [1.0 / 3.0, 2.0 / 3.0], 0.0);
            let length_a = rng.random_range(0.05..0.3);
            let start = length_b * (1.0 + rng.random_range(-1e-12..1e-12));
            let from = DVec2::new(start, rng.random_range(0.3..0.95) * 2.0 * lambda);
            let to = from + DVec2::from_angle(rng.random_range(-2e-3..2e-3)) * length_a;
            let a = piece(from, to, [1.0 / 3.0, 2.0 / 3.0], 0.0);
            let Some((a, b, centre)) = conformal_centre(a, b, lambda) else { continue };
            let (contacts, _) = overlap_ends(&a, &b, ORIENTATION, centre);
            // (With the patch's normal: the nearest points are ends of both pieces here.)
            let nearest = SegmentContact { normal: patch_normal(&a, &b, &centre), ..centre };
            assert_eq!(contacts.as_slice(), [nearest], "case {case}: the sliver is not the nearest points");
            // The secant's two ends coincide too (to the 1e-9 of the size at which `overlap_ends`
            // takes the nearest points for them).
            let (low, high, _) = secant_ends(&a, &b, ORIENTATION, None, centre);
            let scale = pair_scale(&a.segment, &b.segment);
            assert!(low.point_a.distance(high.point_a) <= 1e-9 * scale, "case {case}: {low:?} {high:?}");
            checked += 1;
        }
        assert!(checked > 500, "only {checked} slivers were conformal");
    }

    /// A straight side over B's piece at `s` (and where it touches from).
    struct Over {
        /// B's point at `s`, its unit tangent and its outward normal there.
        q: DVec2,
        tangent: DVec2,
        outward: DVec2,
        /// The point over `q`, 0.3–0.95 of the combined band `2λ` out, that the side covers.
        touch: DVec2,
        /// The side: 5–30 cm along B's tangent reversed (the body above's side), tilted by up
        /// to 2e-3 rad.
        side: CubicSegment,
    }

    fn side_over(b: &CubicSegment, s: f64, lambda: f64, rng: &mut StdRng) -> Over {
        let (q, tangent) = (b.position(s), b.derivative(s).normalize());
        let outward = DVec2::new(tangent.y, -tangent.x);
        let direction = DVec2::from_angle(rng.random_range(-2e-3..2e-3)).rotate(-tangent);
        let length = rng.random_range(0.05..0.3);
        let touch = q + outward * rng.random_range(0.3..0.95) * 2.0 * lambda;
        let from = touch - direction * rng.random_range(0.0..length);
        Over { q, tangent, outward, touch, side: piece(from, from + direction * length, [0.3, 0.7], 0.0) }
    }

    /// B's orientation in these tests: B is the body below, its outward normal up.
    const ORIENTATION: Orientation = Orientation::CounterClockwise;

    /// The pieces with the band `λ` on each, and their nearest points if these are in the band
    /// and conformal (else `None`: no overlap to end).
    fn conformal_centre(
        a: CubicSegment,
        b: CubicSegment,
        lambda: f64,
    ) -> Option<(TolerancedSegment, TolerancedSegment, SegmentContact)> {
        let settings = CurvePairSettings::default();
        let tolerance = SegmentTolerance::constant(lambda, 0.0);
        let (a, b) = (TolerancedSegment { segment: a, tolerance }, TolerancedSegment { segment: b, tolerance });
        let closest = closest_points_segment_segment(&a.segment, &b.segment, &settings);
        let centre = contact_at(&a, &b, ORIENTATION, closest.t, closest.s);
        (centre.penetration >= 0.0 && is_conformal(&a, &b, &centre, &settings)).then_some((a, b, centre))
    }

    /// The fast ends against the secant on the exact margins (nearest points per evaluation):
    /// each end at the same point, to twice the secant's tolerance, and inside the band.
    fn assert_same_ends(
        a: &TolerancedSegment,
        b: &TolerancedSegment,
        centre: SegmentContact,
        fast: (SegmentContact, SegmentContact, u32),
        case: &str,
    ) {
        let secant = secant_ends(a, b, ORIENTATION, None, centre);
        let allowed = 2e-9 * pair_scale(&a.segment, &b.segment);
        for (got, want) in [(fast.0, secant.0), (fast.1, secant.1)] {
            let off = got.point_a.distance(want.point_a);
            assert!(off <= allowed, "{case}: an end {off:e} off, allowed {allowed:e}\n{got:?}\n{want:?}");
            assert!(got.penetration >= -1e-15, "{case}: an end outside the band {got:?}");
        }
    }

    /// A box's straight side touching the rounding of another box's corner (the pieces that
    /// bend, of a rounded square of side 0.5 m and corner radius 0.05 m) near where the rounding
    /// meets a side: the rounding's curvature is nearly zero there, but it grows along the piece
    /// (the gap grows like `⅙ k′ x³`), so the pair is not conformal. Measured by the curvature
    /// at the nearest points alone, those that touched at a piece's end were conformal and those
    /// that touched just inside it were not: a box resting on the ground had its patch reach
    /// 4 cm up one corner's rounding or stop at the side's end as it tilted by ±1e-7 rad. In
    /// half the cases A is the rounding's mirror image across the tangent (two boxes side by
    /// side, corner facing corner): the two pieces run opposite ways, their `k′` terms add, and
    /// they are not conformal either (taken with the same sign they cancelled, and a box pushed
    /// by a wall had its patch reach one corner's rounding and not the other's, and turned).
    #[test]
    fn a_side_on_a_corner_rounding_is_not_conformal() {
        use crate::geometry::rounded_polygon::{ControlPointBudget, rounded_polygon};
        let square = [DVec2::ZERO, DVec2::new(0.5, 0.0), DVec2::new(0.5, 0.5), DVec2::new(0.0, 0.5)];
        let (spline, _) = rounded_polygon(&square, 0.05, ControlPointBudget::MaxSpacing(0.1)).expect("a valid square");
        let bends: Vec<CubicSegment> =
            (0..spline.segment_count()).map(|i| spline.segment(i)).filter(|piece| piece.straight().is_none()).collect();
        assert!(bends.len() >= 12, "three bending pieces per corner, {} found", bends.len());
        let settings = CurvePairSettings::default();
        let mut rng = StdRng::seed_from_u64(17);
        let (lambda, mut touching) = (0.002, 0);
        for case in 0..8000 {
            let b = bends[case % bends.len()];
            // A touches B's outside near an end of the piece (at its very end in one case in
            // four), its chord along B's tangent there, reversed (the body above's side).
            let s = match case % 4 {
                0 => 0.0,
                1 => 1.0,
                2 => rng.random_range(0.0..0.01),
                _ => rng.random_range(0.99..1.0),
            };
            let over = side_over(&b, s, lambda, &mut rng);
            let (q, tangent, outward, touch) = (over.q, over.tangent, over.outward, over.touch);
            let a = if case % 8 < 4 {
                over.side
            } else {
                // Mirrored across the tangent line at q, lifted to `touch`, and reversed.
                let mirror = |p: DVec2| {
                    let d = p - q;
                    touch + tangent * d.dot(tangent) - outward * d.dot(outward)
                };
                let [b0, b1, b2, b3] = b.bezier.map(mirror);
                CubicSegment { bezier: [b3, b2, b1, b0] }
            };
            let tolerance = SegmentTolerance::constant(lambda, 0.0);
            let (a, b) = (TolerancedSegment { segment: a, tolerance }, TolerancedSegment { segment: b, tolerance });
            let closest = closest_points_segment_segment(&a.segment, &b.segment, &settings);
            let centre = contact_at(&a, &b, ORIENTATION, closest.t, closest.s);
            if centre.penetration < 0.0 {
                continue;
            }
            touching += 1;
            assert!(!is_conformal(&a, &b, &centre, &settings), "case {case}: conformal at s = {}", closest.s);
        }
        assert!(touching > 4000, "{touching} of 8000 cases in the band");
    }

    /// A straight side resting on a gently bent piece (its curvature nearly constant, as along
    /// a blob): the ends found in B's parameter ([`curved_overlap`]) are the secant's on the
    /// exact margins. Pieces that bend within the band of the side go the general path; most do
    /// not.
    #[test]
    fn curved_overlap_ends_match_the_secant_on_exact_margins() {
        let mut rng = StdRng::seed_from_u64(17);
        let (lambda, mut checked, mut fast_count) = (0.002, 0, 0);
        for case in 0..3000 {
            // B: the top of a body below (running in −x), bent up or down by up to 2e-5 m at its
            // middle; A: the bottom of a body above, over a point of B's piece, along its
            // tangent there, reversed, and tilted.
            let length_b = rng.random_range(0.05..0.3);
            let bend = rng.random_range(-2e-5..2e-5);
            let b = piece(DVec2::new(length_b, 0.0), DVec2::ZERO, [1.0 / 3.0, 2.0 / 3.0], bend);
            let s = rng.random_range(0.1..0.9);
            let a = side_over(&b, s, lambda, &mut rng).side;
            let Some((a, b, centre)) = conformal_centre(a, b, lambda) else { continue };
            checked += 1;
            let Some(fast) = curved_overlap(&a, &b, ORIENTATION, centre) else { continue };
            assert_same_ends(&a, &b, centre, fast, &format!("case {case}"));
            fast_count += 1;
        }
        assert!(
            checked > 1000 && fast_count * 10 > checked * 9,
            "{fast_count} of {checked} conformal pairs took the fast path"
        );
    }
}
