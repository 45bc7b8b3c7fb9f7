//! The leaf solver of MODEL §4: intersection, nearest points and contact state of two cubic
//! pieces, one of body A and one of body B, both in world coordinates.
//!
//! One branch-and-bound search serves all three questions. The square `[0,1]²` of parameter
//! pairs `(t, s)` is subdivided depth first; each cell carries the Bézier pieces over its two
//! parameter intervals, and the gap between their Bézier hulls (projected on the centre line,
//! the chord normals and the axes) is a lower bound of the distance inside the cell. Children
//! are visited nearest centres first; cells whose bound cannot beat the best distance found (or
//! the contact cutoff) are pruned. Once both pieces of a cell are flat:
//!
//! - if their hulls overlap, Newton on `p(t) = q(s)` looks for a crossing in the cell
//!   (quadratic at a transversal crossing); failing that the cell is subdivided further, as in
//!   Bézier hull subdivision, down to `max_subdivision_depth`;
//! - otherwise a safeguarded Newton minimises `D = ½|p(t) − q(s)|²`, first confined to the cell
//!   and then released into the square (ε-active set on the box, Levenberg–Marquardt shift
//!   where the Hessian is not positive definite or the step too long, backtracking on `D`,
//!   a triple step where convergence turns linear at a tangency).
//!
//! The four edges of the square (an end of one piece against the other piece) are searched
//! separately where a Newton cell ran, since in a nearly flat valley a cell can hold an interior
//! minimum and a lower one on its edge (where every cell was set aside by a bound, nothing in
//! the square is nearer than the best point).
//!
//! A search that starts from a true minimum (a moved contact's last answer, or once a Newton
//! cell has found one) also bounds each cell by the slab between that minimum's points
//! (`search::Slab`): cells where the pieces bend away from each other near it are set aside
//! without being split.
//!
//! With a finite cutoff (the combined band of a query), a search whose cells all proved to lie
//! beyond it before any Newton answer came nearer than a cell's centre stops there: the pair is
//! separate, with the cells' bounds as its lower bound, and its best centre is not polished.
//!
//! The pieces intersect when the global minimum distance is at most the intersection tolerance
//! (a small fraction of the pieces' size): a transversal crossing and a tangency are both
//! caught by distance, so the decision never rests on finding an exact root.
//!
//! Everything lives on the stack: no allocation per call, no randomness, no NaN.

use arrayvec::ArrayVec;
use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::rugosity::SegmentTolerance;
use crate::geometry::segment::CubicSegment;

mod conformal;
mod newton;
mod search;
mod straight;

use conformal::*;
use newton::*;
use search::*;
pub(crate) use search::{PieceHull, gap_along, hull_axes, nearest_separating_axis};
pub use search::{SEPARATING_AXES, pair_scale, separating_axes};
use straight::straight_nearest;

/// Hard cap on [`CurvePairSettings::max_subdivision_depth`]; it sizes the search stack.
pub const MAX_SUBDIVISION_DEPTH: u32 = 30;

/// Depth-first stack size: each level leaves at most three siblings waiting.
pub(super) const STACK_CAPACITY: usize = 3 * MAX_SUBDIVISION_DEPTH as usize + 4;

/// The depth-first stack of cells, on the call stack and left uninitialised until used (a
/// zeroed array of this size costs more than a typical search).
type CellStack = ArrayVec<Cell, STACK_CAPACITY>;

/// Tuning of the curve-pair solver. Lengths are relative to the size of the two pieces
/// (the larger diagonal of their Bézier control boxes), so the settings are unit-free.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CurvePairSettings {
    /// Newton stops when a step moves both parameters by less than this (default 1e-13).
    pub newton_step_tolerance: f64,
    /// Newton iteration cap per start (default 48; tangencies converge linearly and need ~40).
    pub max_newton_iterations: u32,
    /// Cells are not handed to Newton above this depth (default 3, an 8 × 8 grid of seeds).
    pub seed_depth: u32,
    /// Deepest subdivision (default 16, at most [`MAX_SUBDIVISION_DEPTH`]); pieces that are
    /// still not flat there (cusps) are handed to Newton anyway.
    pub max_subdivision_depth: u32,
    /// A piece is flat when its inner Bézier points lie within this fraction of its chord
    /// from the chord (default 0.02; Newton then sees a nearly quadratic `D`).
    pub flatness_ratio: f64,
    /// Distances at or below this fraction of the piece size count as touching, i.e.
    /// intersecting (default 1e-12, a few hundred ulps of the coordinates).
    pub intersection_tolerance: f64,
    /// Cells whose lower bound is within this fraction of the piece size of the best distance
    /// are not searched (default 1e-13): the answer is that accurate.
    pub distance_tolerance: f64,
    /// Cells visited per piece pair before subdivision stops where hulls overlap (default 4096):
    /// bounds the work on nearly coincident pieces, whose hulls overlap at every depth.
    pub max_cells: u32,
    /// Nearest points are conformal (parallel or matching pieces: a continuum of near-nearest
    /// points) when the gap between the pieces, extrapolated from its curvature over the
    /// pieces' size, changes by at most this fraction of the combined band (default 0.1); the
    /// contact is then the two ends of the overlap in the band. A disc on a flat is not
    /// conformal, a box on a box is.
    pub conformal_fraction: f64,
}

impl Default for CurvePairSettings {
    fn default() -> Self {
        Self {
            newton_step_tolerance: 1e-13,
            max_newton_iterations: 48,
            seed_depth: 3,
            max_subdivision_depth: 16,
            flatness_ratio: 0.02,
            intersection_tolerance: 1e-12,
            distance_tolerance: 1e-13,
            max_cells: 4096,
            conformal_fraction: 0.1,
        }
    }
}

impl CurvePairSettings {
    /// Checks every setting against the domain in which the solver keeps its accuracy and
    /// its work bounded (documented in docs/scenes.md).
    ///
    /// # Errors
    /// A [`SettingsError`](crate::SettingsError) naming the field (`curve_pair.newton_step_tolerance`, …).
    pub fn validate(&self) -> Result<(), crate::error::SettingsError> {
        use crate::error::{SettingsError, check_range};
        let count = |field: &str, value: u32, low: u32, high: u32| {
            if value < low || value > high {
                return Err(SettingsError::new(field, value, format!("must lie in [{low}, {high}]")));
            }
            Ok(())
        };
        check_range("curve_pair.newton_step_tolerance", self.newton_step_tolerance, 1e-16, 0.1)?;
        count("curve_pair.max_newton_iterations", self.max_newton_iterations, 1, 1000)?;
        count("curve_pair.max_subdivision_depth", self.max_subdivision_depth, 1, MAX_SUBDIVISION_DEPTH)?;
        count("curve_pair.seed_depth", self.seed_depth, 0, self.max_subdivision_depth.min(10))?;
        check_range("curve_pair.flatness_ratio", self.flatness_ratio, 1e-6, 0.5)?;
        check_range("curve_pair.intersection_tolerance", self.intersection_tolerance, 0.0, 1e-6)?;
        check_range("curve_pair.distance_tolerance", self.distance_tolerance, 0.0, 1e-6)?;
        count("curve_pair.max_cells", self.max_cells, 1, 1 << 20)?;
        check_range("curve_pair.conformal_fraction", self.conformal_fraction, 0.0, 1.0)
    }
}

/// Which way a closed curve runs; it fixes which side of a piece is outside.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Orientation {
    /// Counter-clockwise: outward normal `normalize((y', −x'))` (every validated body).
    #[default]
    CounterClockwise,
    /// Clockwise: outward normal `normalize((−y', x'))`.
    Clockwise,
}

/// One piece of a body boundary in world coordinates with its rugosity tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TolerancedSegment {
    /// The piece, in world coordinates.
    pub segment: CubicSegment,
    /// λ over the piece (floored at the minimum band).
    pub tolerance: SegmentTolerance,
}

/// Nearest points of two pieces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoints {
    /// Parameter on the first piece.
    pub t: f64,
    /// Parameter on the second piece.
    pub s: f64,
    /// `p(t)`.
    pub point_a: DVec2,
    /// `q(s)`.
    pub point_b: DVec2,
    /// `|p(t) − q(s)|`.
    pub distance: f64,
    /// Newton iterations spent, over all starts.
    pub newton_iterations: u32,
}

/// One contact point between a piece of A and a piece of B (MODEL §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SegmentContact {
    /// Parameter on A's piece.
    pub t: f64,
    /// Parameter on B's piece.
    pub s: f64,
    /// `p(t)` on A.
    pub point_a: DVec2,
    /// `q(s)` on B.
    pub point_b: DVec2,
    /// Contact point `x = q(s) + ½ (p(t) − q(s))`, in the common band.
    pub point: DVec2,
    /// Outward unit normal of B at `s`.
    pub normal: DVec2,
    /// `d = |p(t) − q(s)|`.
    pub distance: f64,
    /// Penetration into the band `δ = λ_A + λ_B − d ≥ 0`.
    pub penetration: f64,
    /// λ_A(t), floored at the minimum band.
    pub lambda_a: f64,
    /// λ_B(s), floored at the minimum band.
    pub lambda_b: f64,
    /// λ_A(t) without the floor (for friction).
    pub raw_lambda_a: f64,
    /// λ_B(s) without the floor (for friction).
    pub raw_lambda_b: f64,
}

/// Up to two contact points (two for parallel or conformal pieces: the ends of the overlap).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactPoints {
    points: [SegmentContact; 2],
    len: usize,
}

impl ContactPoints {
    /// A single contact point.
    #[must_use]
    pub fn one(contact: SegmentContact) -> Self {
        Self { points: [contact, contact], len: 1 }
    }

    /// Two contact points (the ends of an overlap).
    #[must_use]
    pub fn two(first: SegmentContact, second: SegmentContact) -> Self {
        Self { points: [first, second], len: 2 }
    }

    /// The contact points, one or two.
    #[must_use]
    pub fn as_slice(&self) -> &[SegmentContact] {
        &self.points[..self.len]
    }

    /// The contact of smallest distance, `None` when empty.
    #[must_use]
    pub fn deepest(&self) -> Option<&SegmentContact> {
        self.as_slice().iter().min_by(|x, y| x.distance.total_cmp(&y.distance))
    }
}

/// State of a piece pair (MODEL §4, step 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentPairState {
    /// The pieces meet at `p(t) = q(s)`: the step must be retried.
    Intersecting {
        /// Parameter on A's piece.
        t: f64,
        /// Parameter on B's piece.
        s: f64,
    },
    /// Nearest points within the combined band: see [`SegmentPairQuery::contacts`].
    Contact,
    /// Nearest points farther apart than the combined band.
    Separate,
}

/// Answer of [`query_segment_segment`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentPairQuery {
    /// Intersecting, contact or separate.
    pub state: SegmentPairState,
    /// The contact points when `state` is [`SegmentPairState::Contact`], else empty.
    pub contacts: ContactPoints,
    /// Nearest points, when the search had to find them: exact within the combined band;
    /// beyond it, the nearest the search came, unpolished where its cells proved the pair apart
    /// first (exact distances at any range: [`closest_points_segment_segment`]). `None` when
    /// the hulls alone set the pair apart.
    pub closest: Option<ClosestPoints>,
    /// Newton iterations spent.
    pub newton_iterations: u32,
    /// A lower bound on the distance between the pieces: exact when the nearest points were
    /// found within the combined band, else at least the combined band: the smaller of the
    /// distance found and the hull bounds of the cells the search set aside, or the root hulls'
    /// gap when larger.
    pub distance_lower_bound: f64,
}

/// Nearest points of two pieces: global minimum of `|p(t) − q(s)|` over `[0,1]²`.
#[must_use]
pub fn closest_points_segment_segment(
    a: &CubicSegment,
    b: &CubicSegment,
    settings: &CurvePairSettings,
) -> ClosestPoints {
    let found = search(a, b, settings, f64::INFINITY);
    found.closest.unwrap_or_else(|| closest_at(a, b, DVec2::splat(0.5), found.iterations))
}

/// Whether two pieces meet: `Some((t, s))` with `|p(t) − q(s)|` within the intersection tolerance.
#[must_use]
pub fn intersect_segment_segment(
    a: &CubicSegment,
    b: &CubicSegment,
    settings: &CurvePairSettings,
) -> Option<(f64, f64)> {
    let touch = settings.intersection_tolerance * pair_scale(a, b);
    search(a, b, settings, touch).closest.filter(|c| c.distance <= touch).map(|c| (c.t, c.s))
}

/// Intersection, nearest points and contact state of a piece of A and a piece of B (MODEL §4).
///
/// `orientation_b` is the running direction of B's boundary; it fixes the outward normal.
#[must_use]
pub fn query_segment_segment(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    settings: &CurvePairSettings,
) -> SegmentPairQuery {
    let gap = hull_gap(&a.segment, &b.segment);
    query_segment_segment_from(a, b, orientation_b, settings, None, gap)
}

/// [`query_segment_segment`] for a leaf pair whose last answer `seed` (its nearest parameters)
/// can no longer be trusted as it stands (docs/model.md §3a): the search starts with the local
/// minimum Newton reaches from it as its best point, so the cells that cannot beat it are set
/// aside at once. Whatever the seed, the answer is the search's. `hull_gap` is the pieces'
/// ([`Hulls::of`]).
pub(crate) fn query_segment_segment_from(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    settings: &CurvePairSettings,
    seed: Option<DVec2>,
    hull_gap: f64,
) -> SegmentPairQuery {
    let cutoff = a.tolerance.max + b.tolerance.max;
    let found = search_from(&a.segment, &b.segment, settings, cutoff, (seed, Some(hull_gap)));
    let distance_lower_bound = match found.closest {
        Some(closest) if closest.distance <= cutoff => closest.distance,
        _ => found.lower_bound.max(cutoff),
    };
    classify(a, b, orientation_b, settings, found.closest, distance_lower_bound, found.iterations)
}

/// The gap of two pieces' Bézier hulls, where a search of the pair starts (its root cell's
/// bound), and whether it sets them apart.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Hulls {
    /// The gap exceeds the combined band: the pair is separate, and
    /// [`query_segment_segment_from`] would answer it from its root cell alone, with this gap
    /// as its lower bound, no nearest points and no Newton step, whatever its seed. Three
    /// quarters of a landing pile's leaf pairs end here, answered without building a query.
    Apart(f64),
    /// The gap (possibly NaN) is within the band: the pair is searched.
    Near(f64),
}

impl Hulls {
    /// The hulls of pieces `a` and `b`, each with its [`PieceHull`] (worked out once for all
    /// the leaf pairs it is in).
    pub(crate) fn of(
        (a, hull_a): (&TolerancedSegment, &PieceHull),
        (b, hull_b): (&TolerancedSegment, &PieceHull),
    ) -> Self {
        let gap = hull_gap_of((&a.segment, hull_a), (&b.segment, hull_b));
        if gap > a.tolerance.max + b.tolerance.max { Self::Apart(gap) } else { Self::Near(gap) }
    }
}

/// What a leaf pair's memory tells a recalled query (docs/model.md §3a).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Recalled {
    /// Where Newton starts: the last answer's nearest parameters.
    pub seed: DVec2,
    /// A proven lower bound on the distance over the whole square, which keeps the pieces from
    /// meeting (the caller checks that it exceeds the intersection tolerance).
    pub lower_bound: f64,
    /// The distance the answer of a point contact may not exceed: the searched minimum plus
    /// the motion since, which the searched point itself still meets (so the answer is at most
    /// twice the motion above the true minimum).
    pub ceiling: f64,
}

/// The answer of [`query_segment_segment`] from a persistent contact, without the search
/// (docs/model.md §3a); `None` where a search is needed.
///
/// - A point contact: the local minimum reached by Newton from the last answer, classified as
///   the search's global one would be, if its distance is within the ceiling.
/// - A `conformal` one: at most six Newton steps from the last answer reach the valley of the
///   distance (along a conformal overlap it hardly changes, which is what conformal means, and
///   Newton's later steps only crawl along it; from last step's point in the valley, two steps
///   that gain nothing end it); if the pieces are still conformal and in the band there, the
///   overlap's two ends are found as the search's answer finds them, and carry their own
///   distances. Otherwise (an overlap shrunk to a point included) the nearest points are
///   polished as for a point contact.
pub(crate) fn query_segment_segment_recalled(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    settings: &CurvePairSettings,
    recalled: Recalled,
    conformal: bool,
) -> Option<SegmentPairQuery> {
    let mut start = ParamBox::UNIT.clamp(recalled.seed);
    let mut spent = 0;
    if conformal {
        let capped = CurvePairSettings { max_newton_iterations: settings.max_newton_iterations.min(6), ..*settings };
        let found = recalled_minimum(&a.segment, &b.segment, start, &capped);
        let centre = contact_at(a, b, orientation_b, found.x.x, found.x.y);
        let ends = if centre.penetration >= 0.0 && is_conformal(a, b, &centre, settings) {
            Some(overlap_ends(a, b, orientation_b, centre))
        } else {
            None
        };
        // An overlap shrunk to a point is a point contact: its nearest points, not the centre.
        if let Some((contacts, steps)) = ends.filter(|(contacts, _)| contacts.as_slice().len() == 2) {
            let crossing = overlap_crossing(a, b, orientation_b, &contacts, settings);
            let (state, contacts) = match crossing {
                Some((t, s)) => (SegmentPairState::Intersecting { t, s }, ContactPoints::default()),
                None => (SegmentPairState::Contact, contacts),
            };
            return Some(SegmentPairQuery {
                state,
                contacts,
                closest: Some(closest_at(&a.segment, &b.segment, found.x, found.iterations)),
                newton_iterations: found.iterations + steps,
                distance_lower_bound: recalled.lower_bound,
            });
        }
        spent = found.iterations + ends.map_or(0, |(_, steps)| steps);
        start = found.x;
    }
    let cutoff = a.tolerance.max + b.tolerance.max;
    let found = recalled_minimum(&a.segment, &b.segment, start, settings);
    // To the search's own accuracy; a NaN refuses the answer.
    let slack = settings.distance_tolerance * pair_scale(&a.segment, &b.segment);
    let within = found.distance <= recalled.ceiling + slack;
    if !within {
        return None;
    }
    let closest = closest_at(&a.segment, &b.segment, found.x, found.iterations);
    let distance_lower_bound = if closest.distance <= cutoff { closest.distance } else { recalled.lower_bound };
    Some(classify(a, b, orientation_b, settings, Some(closest), distance_lower_bound, spent + found.iterations))
}

/// The minimum a recalled query starts from: of two straight pieces, their nearest points in
/// closed form ([`straight_nearest`]: the global minimum, no iteration); else Newton from `start`,
/// stopping at the rounding floor of `D`.
fn recalled_minimum(a: &CubicSegment, b: &CubicSegment, start: DVec2, settings: &CurvePairSettings) -> NewtonResult {
    match straight_nearest(a, b, start) {
        Some(x) => NewtonResult { x, distance: a.position(x.x).distance(b.position(x.y)), iterations: 0, jet: None },
        None => minimize_distance(a, b, start, ParamBox::UNIT, settings, RoundingFloor::Stop),
    }
}

/// Intersecting, contact (one point, or the two ends of a conformal overlap) or separate, from
/// the nearest points found.
fn classify(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    settings: &CurvePairSettings,
    closest: Option<ClosestPoints>,
    distance_lower_bound: f64,
    newton_iterations: u32,
) -> SegmentPairQuery {
    let cutoff = a.tolerance.max + b.tolerance.max;
    let mut query = SegmentPairQuery {
        state: SegmentPairState::Separate,
        contacts: ContactPoints::default(),
        closest,
        newton_iterations,
        distance_lower_bound,
    };
    let Some(closest) = closest.filter(|c| c.distance <= cutoff) else { return query };
    if closest.distance <= settings.intersection_tolerance * pair_scale(&a.segment, &b.segment) {
        query.state = SegmentPairState::Intersecting { t: closest.t, s: closest.s };
        return query;
    }
    let single = contact_at(a, b, orientation_b, closest.t, closest.s);
    if single.penetration < 0.0 {
        return query;
    }
    query.state = SegmentPairState::Contact;
    let contacts = if is_conformal(a, b, &single, settings) {
        let (contacts, steps) = overlap_ends(a, b, orientation_b, single);
        query.newton_iterations += steps;
        contacts
    } else {
        ContactPoints::one(single)
    };
    // Nearly coincident pieces that cross look like a contact to the nearest points (see
    // `overlap_crossing`).
    if let Some((t, s)) = overlap_crossing(a, b, orientation_b, &contacts, settings) {
        query.state = SegmentPairState::Intersecting { t, s };
        return query;
    }
    query.contacts = contacts;
    query
}

/// The contact record at `(t, s)`; `penetration` is negative when outside the band.
#[must_use]
pub fn contact_at(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    orientation_b: Orientation,
    t: f64,
    s: f64,
) -> SegmentContact {
    contact_from(a, b, (t, s), |away| outward_normal(&b.segment, s, orientation_b, away))
}

/// A reused contact `old` evaluated again on A's and B's pieces as they lie now, with the normal
/// `normal` given (turned with B: computing B's normal there again would be thrown away). Its
/// parameters are kept, and so are its bands, which depend on them alone.
#[must_use]
#[inline]
pub(crate) fn contact_moved(a: &CubicSegment, b: &CubicSegment, old: &SegmentContact, normal: DVec2) -> SegmentContact {
    let point_a = a.position(old.t);
    let point_b = b.position(old.s);
    let distance = point_a.distance(point_b);
    SegmentContact {
        point_a,
        point_b,
        point: point_b + 0.5 * (point_a - point_b),
        normal,
        distance,
        penetration: old.lambda_a + old.lambda_b - distance,
        ..*old
    }
}

/// The contact record at `(t, s)`, its normal from `normal` (given the vector from B's point
/// to A's).
#[inline(always)]
fn contact_from(
    a: &TolerancedSegment,
    b: &TolerancedSegment,
    (t, s): (f64, f64),
    normal: impl FnOnce(DVec2) -> DVec2,
) -> SegmentContact {
    let point_a = a.segment.position(t);
    let point_b = b.segment.position(s);
    let distance = point_a.distance(point_b);
    let lambda_a = a.tolerance.at(t);
    let lambda_b = b.tolerance.at(s);
    SegmentContact {
        t,
        s,
        point_a,
        point_b,
        point: point_b + 0.5 * (point_a - point_b),
        normal: normal(point_a - point_b),
        distance,
        penetration: lambda_a + lambda_b - distance,
        lambda_a,
        lambda_b,
        raw_lambda_a: a.tolerance.raw_at(t),
        raw_lambda_b: b.tolerance.raw_at(s),
    }
}

/// Outward unit normal of a piece at `s`, always finite and of unit length.
///
/// Where `q'(s)` vanishes (a cusp from repeated control points) the chord through nearby
/// parameters gives the tangent; failing that, `away` (from B towards A) is used.
#[must_use]
pub fn outward_normal(segment: &CubicSegment, s: f64, orientation: Orientation, away: DVec2) -> DVec2 {
    let sign = match orientation {
        Orientation::CounterClockwise => 1.0,
        Orientation::Clockwise => -1.0,
    };
    let from_tangent = |d: DVec2| (sign * DVec2::new(d.y, -d.x)).try_normalize();
    let scale = bezier_diagonal(segment).max(f64::MIN_POSITIVE);
    let derivative = segment.derivative(s);
    if derivative.length() > 1e-12 * scale
        && let Some(n) = from_tangent(derivative)
    {
        return n;
    }
    let h = 1e-4;
    let chord = segment.position((s + h).min(1.0)) - segment.position((s - h).max(0.0));
    from_tangent(chord).or_else(|| away.try_normalize()).unwrap_or(DVec2::Y)
}

#[cfg(test)]
mod tests;
