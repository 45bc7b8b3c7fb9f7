//! Pieces that are straight (the sides of rounded polygons): nearest points and conformal
//! overlap ends in closed form or on margins that need no nearest point per evaluation.

use super::*;
use crate::geometry::segment::StraightPiece;

/// B's piece as a stretch of a line, with the combined band, when B's piece is straight and
/// both bands are constant along the pieces: then each margin of `overlap_end` is an affine
/// function of A's point (the penetration one while A's point stays on one side of the line),
/// no nearest point needed.
pub(super) struct FlatSide {
    pub(super) line: StraightPiece,
    /// Unit vector along B's chord.
    pub(super) along: DVec2,
    /// Unit normal of B's chord.
    pub(super) across: DVec2,
    /// Length of B's chord.
    pub(super) length: f64,
    /// `λ_A + λ_B`.
    pub(super) band: f64,
}

pub(super) fn flat_side(a: &TolerancedSegment, b: &TolerancedSegment) -> Option<FlatSide> {
    let line = b.segment.straight()?;
    let band = a.tolerance.uniform()? + b.tolerance.uniform()?;
    let length = line.length_squared.sqrt();
    Some(FlatSide { line, along: line.chord / length, across: line.chord.perp() / length, length, band })
}

impl FlatSide {
    /// Signed distance of `point` from B's line.
    pub(super) fn side(&self, point: DVec2) -> f64 {
        (point - self.line.start).dot(self.across)
    }

    /// The sign of A's side of B's line, if all of A's piece (its Bézier hull) is strictly on
    /// one side: then the distance of A's point from B's piece, while its foot is inside, is
    /// that sign times [`Self::side`].
    pub(super) fn one_side(&self, a: &CubicSegment) -> Option<f64> {
        let sides = a.bezier.map(|p| self.side(p));
        let sign = sides[0].signum();
        sides.iter().all(|&x| x * sign > 0.0).then_some(sign)
    }
}

/// The nearest parameters `(t, s)` of two straight pieces, if both are: the textbook nearest
/// points of two line segments (Ericson, *Real-Time Collision Detection* §5.1.9) as fractions of
/// the chords, then each piece's parameter there. Where the chords are parallel (to 1e-12 in
/// the sine squared of their angle) the nearest points fill a stretch, and the one through
/// `seed`'s point on A is taken, so that a persistent contact stays where it was.
pub(super) fn straight_nearest(a: &CubicSegment, b: &CubicSegment, seed: DVec2) -> Option<DVec2> {
    let (line_a, line_b) = (a.straight()?, b.straight()?);
    let (da, db, r) = (line_a.chord, line_b.chord, line_a.start - line_b.start);
    let (aa, bb, ab) = (line_a.length_squared, line_b.length_squared, da.dot(db));
    let (ar, br) = (da.dot(r), db.dot(r));
    let denominator = aa * bb - ab * ab;
    let mut tau = if denominator > 1e-12 * aa * bb {
        (ab * br - ar * bb) / denominator
    } else {
        line_a.fraction(a.position(seed.x))
    }
    .clamp(0.0, 1.0);
    let mut sigma = (ab * tau + br) / bb;
    if sigma < 0.0 {
        (sigma, tau) = (0.0, (-ar / aa).clamp(0.0, 1.0));
    } else if sigma > 1.0 {
        (sigma, tau) = (1.0, ((ab - ar) / aa).clamp(0.0, 1.0));
    }
    let x = DVec2::new(line_a.parameter(tau), line_b.parameter(sigma));
    x.is_finite().then_some(x)
}

/// The overlap of two straight pieces with bands constant along them, in closed form: the ends
/// of the stretch of A's piece that lies in the combined band and between B's end normals.
/// Along A's chord, `p(τ) = a₀ + τ (a₃ − a₀)`, all three margins of `overlap_end` are linear
/// in `τ` while A's piece stays on one side of B's line (its signed distance from that line
/// is, and the feet lie on the line), so the stretch is the interval where all three are
/// non-negative, found from their roots; each end's parameter then solves the scalar cubic
/// `φ_A(t) = τ`. The ends are exact to rounding rather than to [`END_TOLERANCE`], and cost two
/// contact evaluations instead of a secant per margin. Where the interval is empty or a point
/// (two pieces whose joints line up leave such a sliver) the overlap is `centre`, the nearest
/// points, alone: the secant found the same in each of the 7,934 slivers of a settling pyramid's
/// 20 steps (a scratch count), and 80 steps answered so were bit-identical. `None` (the general
/// path) when A's piece is not straight or reaches B's line.
pub(super) fn straight_overlap(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    flat: &FlatSide,
    centre: SegmentContact,
) -> Option<(SegmentContact, SegmentContact, u32)> {
    let line_a = a.segment.straight()?;
    let sign = flat.one_side(&a.segment)?;
    let offset = line_a.start - flat.line.start;
    // Each margin as its value at τ = 0 and its slope in τ: past B's start, before B's end, and
    // the penetration into the band.
    let (along, across) = (line_a.chord.dot(flat.along), line_a.chord.dot(flat.across));
    let margins = [
        (offset.dot(flat.along), along),
        (flat.length - offset.dot(flat.along), -along),
        (flat.band - sign * offset.dot(flat.across), -sign * across),
    ];
    if margins.iter().any(|(value, slope)| !(value.is_finite() && slope.is_finite())) {
        return None;
    }
    let (mut low, mut high) = (0.0_f64, 1.0_f64);
    for (value, slope) in margins {
        if slope > 0.0 {
            low = low.max(-value / slope);
        } else if slope < 0.0 {
            high = high.min(-value / slope);
        } else if value < 0.0 {
            return None;
        }
    }
    if low >= high {
        // No stretch of A's piece is both in the band and between B's normals (two pieces whose
        // joints line up leave such a sliver): the overlap is the nearest points alone.
        return Some((centre, centre, 0));
    }
    // The foot on B's piece as its nearest parameter finds it (the same straight path).
    let end = |tau: f64| {
        let t = line_a.parameter(tau);
        let s = flat.line.parameter(flat.line.fraction(a.segment.position(t)));
        contact_at(a, b, orientation_b, t, s)
    };
    Some((end(low), end(high), 2))
}

/// A's straight piece against B's curved one, both bands constant: B's piece as seen from A's
/// line. Parameterised by B's `s`, the foot on A's line of B's normal at `s` is explicit, so the
/// margins of `overlap_end` (how far A's point lies within the stretch of its piece, and the
/// penetration into the band) need no nearest point per evaluation.
struct CurvedSide<'a> {
    line: StraightPiece,
    b: &'a CubicSegment,
    /// `λ_A + λ_B`.
    band: f64,
}

impl CurvedSide<'_> {
    /// The foot on A's line of B's normal at `s`, `p = a₀ + τ c` with `(p − q(s))·q'(s) = 0`,
    /// as `(τ, |p − q(s)|)`.
    fn foot(&self, s: f64) -> (f64, f64) {
        let (q, velocity) = (self.b.position(s), self.b.derivative(s));
        let tau = (q - self.line.start).dot(velocity) / self.line.chord.dot(velocity);
        (tau, (self.line.start + tau * self.line.chord).distance(q))
    }
}

/// B's curved piece seen from A's straight one ([`CurvedSide`]) and the sign of `dτ/ds`, when
/// the foot map `s ↦ τ(s)` is strictly monotone wherever B's point lies within twice the band of
/// A's line. With `c` A's chord, `p` the foot and `d = |q − p|` (along B's normal),
/// `τ'(s) c·q' = |q'|² + (q − p)·q'' ≥ |q'|² − d |q' × q''| / |q'|`. B's velocity keeps one side
/// of A's chord when its Bézier coefficients along the chord, `g_i`, share a sign: then `c·q'`
/// does, and `|q'| ≥ g(s) = |q'·ĉ|`. So `g(s)³ > 2 (λ_A + λ_B) |q'(s) × q''(s)|` keeps `τ'` of
/// one sign for `d ≤ 2 (λ_A + λ_B)`; it is checked on the Bernstein coefficients of both sides
/// (degree 6). Then each point of A's stretch in the band has one foot on B's piece, and the
/// stretch is the image of an interval of `s`. `None` (the general path) otherwise: a piece
/// turning across A's chord, or curving within the band of it.
fn curved_side<'a>(a: &TolerancedSegment, b: &'a TolerancedSegment) -> Option<(CurvedSide<'a>, f64)> {
    let line = a.segment.straight()?;
    let band = a.tolerance.uniform()? + b.tolerance.uniform()?;
    let unit = line.chord / line.length_squared.sqrt();
    let [b0, b1, b2, b3] = b.segment.bezier;
    let velocity = [b1 - b0, b2 - b1, b3 - b2].map(|d| 3.0 * d);
    let along = velocity.map(|d| d.dot(unit));
    let sign = along[0].signum();
    if !along.iter().all(|&x| x * sign > 0.0) {
        return None;
    }
    let speed: [f64; 3] = along.map(f64::abs);
    let cube: [f64; 7] = bernstein_product(bernstein_product::<3, 3, 5>(speed, speed), speed);
    let acceleration = [2.0 * (velocity[1] - velocity[0]), 2.0 * (velocity[2] - velocity[1])];
    let mut turn = [0.0; 4];
    for (i, d) in velocity.iter().enumerate() {
        for (j, e) in acceleration.iter().enumerate() {
            turn[i + j] += binomial(2, i) * binomial(1, j) / binomial(3, i + j) * d.perp_dot(*e);
        }
    }
    let turn: [f64; 7] = bernstein_product(turn, [1.0; 4]);
    let monotone = cube.iter().zip(turn).all(|(&g, w)| g > 2.0 * band * w.abs());
    monotone.then_some((CurvedSide { line, b: &b.segment, band }, sign))
}

/// `C(n, k)` as a float, for the small degrees of Bernstein products.
fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |c, i| c * (n - i) as f64 / (i + 1) as f64)
}

/// The Bernstein coefficients (degree `K − 1 = (M − 1) + (N − 1)`) of the product of two
/// polynomials given by theirs (degrees `M − 1` and `N − 1`).
fn bernstein_product<const M: usize, const N: usize, const K: usize>(a: [f64; M], b: [f64; N]) -> [f64; K] {
    debug_assert_eq!(K + 1, M + N);
    let mut product = [0.0; K];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            product[i + j] += binomial(M - 1, i) * binomial(N - 1, j) / binomial(K - 1, i + j) * x * y;
        }
    }
    product
}

/// The overlap of A's straight piece with B's curved one ([`curved_side`]): the same stretch of
/// A's piece as `overlap_end` finds, searched in B's parameter instead. Where the foot map is
/// monotone, A's point is inside B's end normals exactly when its foot is inside `[0, 1]`, so
/// the stretch is the interval of `s` around the centre's where the foot is on A's piece
/// (`0 ≤ τ ≤ 1`) and within the band, each end by the secant ([`last_inside`]) on those margins
/// towards the end of B's piece that runs to that end of A's. Each end is then checked against
/// B's nearest point to A's point (the one `overlap_end` measures from): were any nearer,
/// the general path takes the pair. `None` also when the centre is not inside all margins.
pub(super) fn curved_overlap(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    centre: SegmentContact,
) -> Option<(SegmentContact, SegmentContact, u32)> {
    let (side, direction) = curved_side(a, b)?;
    let from = centre.s;
    let (tau, distance) = side.foot(from);
    // A centre at an end of A's piece (a straight side tilted on a bent one touches with an
    // end) has its foot there to the rounding of the foot map.
    if !((-1e-12..=1.0 + 1e-12).contains(&tau) && distance <= side.band) {
        return None;
    }
    let scale = pair_scale(&a.segment, &b.segment);
    let mut steps = 1;
    // The end of A's stretch towards `reach` (τ = 0 or 1), as a contact.
    let mut end = |reach: f64| {
        let bound = if (reach > 0.5) == (direction > 0.0) { 1.0 } else { 0.0 };
        let within = |s: f64| {
            let tau = side.foot(s).0;
            if reach > 0.5 { 1.0 - tau } else { tau }
        };
        let penetration = |s: f64| side.band - side.foot(s).1;
        let margins: [&dyn Fn(f64) -> f64; 2] = [&within, &penetration];
        let mut end = bound;
        for margin in margins {
            let at_end = margin(end);
            steps += 1;
            if at_end >= 0.0 {
                continue;
            }
            let (inside, spent) = last_inside(margin, from, margin(from).max(0.0), end, at_end);
            steps += spent + 1;
            end = inside;
        }
        let t = side.line.parameter(side.foot(end).0);
        let found = contact_at(a, b, orientation_b, t, end);
        let nearest = b.segment.nearest_parameter(found.point_a).1;
        steps += 2;
        (nearest >= found.distance - 1e-12 * scale).then_some(found)
    };
    let low = end(0.0)?;
    let high = end(1.0)?;
    Some((low, high, steps))
}
