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
//! separately, since in a nearly flat valley a cell can hold an interior minimum and a lower
//! one on its edge.
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

/// Hard cap on [`CurvePairSettings::max_subdivision_depth`]; it sizes the search stack.
pub const MAX_SUBDIVISION_DEPTH: u32 = 30;

/// Depth-first stack size: each level leaves at most three siblings waiting.
const STACK_CAPACITY: usize = 3 * MAX_SUBDIVISION_DEPTH as usize + 4;

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
    /// A [`SettingsError`] naming the field (`curve_pair.newton_step_tolerance`, …).
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
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Nearest points, when the search had to find them (`None` when pruned as far apart).
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
    let cutoff = a.tolerance.max + b.tolerance.max;
    let found = search(&a.segment, &b.segment, settings, cutoff);
    let distance_lower_bound = match found.closest {
        Some(closest) if closest.distance <= cutoff => closest.distance,
        _ => found.lower_bound.max(cutoff),
    };
    let mut query = SegmentPairQuery {
        state: SegmentPairState::Separate,
        contacts: ContactPoints::default(),
        closest: found.closest,
        newton_iterations: found.iterations,
        distance_lower_bound,
    };
    let Some(closest) = found.closest.filter(|c| c.distance <= cutoff) else { return query };
    if closest.distance <= settings.intersection_tolerance * pair_scale(&a.segment, &b.segment) {
        query.state = SegmentPairState::Intersecting { t: closest.t, s: closest.s };
        return query;
    }
    let single = contact_at(a, b, orientation_b, closest.t, closest.s);
    if single.penetration < 0.0 {
        return query;
    }
    query.state = SegmentPairState::Contact;
    query.contacts = if is_conformal(a, b, &single, settings) {
        let (contacts, steps) = overlap_ends(a, b, orientation_b, single);
        query.newton_iterations += steps;
        contacts
    } else {
        ContactPoints::one(single)
    };
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
        normal: outward_normal(&b.segment, s, orientation_b, point_a - point_b),
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
    if derivative.length() > 1e-12 * scale {
        if let Some(n) = from_tangent(derivative) {
            return n;
        }
    }
    let h = 1e-4;
    let chord = segment.position((s + h).min(1.0)) - segment.position((s - h).max(0.0));
    from_tangent(chord).or_else(|| away.try_normalize()).unwrap_or(DVec2::Y)
}

// ---------------------------------------------------------------------------------------------
// Branch-and-bound search.

/// A cell of the parameter square with the pieces over its intervals and its distance bound.
#[derive(Clone, Copy, Debug)]
struct Cell {
    a: CubicSegment,
    b: CubicSegment,
    t0: f64,
    t1: f64,
    s0: f64,
    s1: f64,
    depth: u32,
    lower_bound: f64,
}

impl Cell {
    fn centre(&self) -> DVec2 {
        DVec2::new(0.5 * (self.t0 + self.t1), 0.5 * (self.s0 + self.s1))
    }

    fn contains(&self, x: DVec2) -> bool {
        x.x >= self.t0 && x.x <= self.t1 && x.y >= self.s0 && x.y <= self.s1
    }

    /// The four children, each with its lower bound and the distance of its centre points.
    fn children(&self) -> [(Cell, f64); 4] {
        let (a0, a1) = self.a.split(0.5);
        let (b0, b1) = self.b.split(0.5);
        let tm = 0.5 * (self.t0 + self.t1);
        let sm = 0.5 * (self.s0 + self.s1);
        let child = |a: CubicSegment, b: CubicSegment, t0, t1, s0, s1| {
            let cell = Cell { a, b, t0, t1, s0, s1, depth: self.depth + 1, lower_bound: hull_gap(&a, &b) };
            (cell, midpoint(&a).distance(midpoint(&b)))
        };
        [
            child(a0, b0, self.t0, tm, self.s0, sm),
            child(a0, b1, self.t0, tm, sm, self.s1),
            child(a1, b0, tm, self.t1, self.s0, sm),
            child(a1, b1, tm, self.t1, sm, self.s1),
        ]
    }
}

/// `p(½)` of a piece, straight from its Bézier points.
fn midpoint(piece: &CubicSegment) -> DVec2 {
    let [b0, b1, b2, b3] = piece.bezier;
    0.125 * (b0 + b3 + 3.0 * (b1 + b2))
}

/// Best point found so far; `polished` when Newton converged there.
#[derive(Clone, Copy, Debug)]
struct Best {
    x: DVec2,
    distance: f64,
    polished: bool,
}

struct SearchResult {
    closest: Option<ClosestPoints>,
    iterations: u32,
    /// A lower bound on the distance over the whole square: the smaller of the distance found
    /// and the bounds of the cells set aside unsearched (by the cutoff or the best distance).
    lower_bound: f64,
}

/// Global minimum of the distance, searched only where it can be at most `cutoff`.
///
/// `closest` is `None` when every cell was pruned by the cutoff.
fn search(a: &CubicSegment, b: &CubicSegment, settings: &CurvePairSettings, cutoff: f64) -> SearchResult {
    let scale = pair_scale(a, b);
    let touch = settings.intersection_tolerance * scale;
    let slack = settings.distance_tolerance * scale;
    let max_depth = settings.max_subdivision_depth.min(MAX_SUBDIVISION_DEPTH);
    let root = Cell { a: *a, b: *b, t0: 0.0, t1: 1.0, s0: 0.0, s1: 1.0, depth: 0, lower_bound: hull_gap(a, b) };
    if root.lower_bound > cutoff {
        // Far apart: one hull test, and nothing to search.
        return SearchResult { closest: None, iterations: 0, lower_bound: root.lower_bound };
    }
    let mut stack = CellStack::new();
    stack.push(root);
    let mut best = Best { x: DVec2::splat(0.5), distance: f64::INFINITY, polished: false };
    let mut iterations = 0;
    let mut budget = settings.max_cells;
    let mut set_aside = f64::INFINITY;
    while best.distance > touch
        && let Some(cell) = stack.pop()
    {
        if cell.lower_bound > cutoff || cell.lower_bound > best.distance - slack {
            set_aside = set_aside.min(cell.lower_bound);
            continue;
        }
        budget = budget.saturating_sub(1);
        let refine = budget > 0 && cell.depth < max_depth;
        if !is_newton_cell(&cell, settings, max_depth, scale) {
            push_children(&cell, &mut stack, &mut best, (cutoff, slack), &mut set_aside);
        } else if cell.lower_bound <= touch {
            // The hulls overlap: look for a crossing, else keep subdividing while allowed.
            if let Some(x) = crossing_in_cell(a, b, &cell, touch, settings) {
                best = Best { x, distance: a.position(x.x).distance(b.position(x.y)), polished: true };
            } else if refine {
                push_children(&cell, &mut stack, &mut best, (cutoff, slack), &mut set_aside);
            } else {
                iterations += minimize_in_cell(a, b, &cell, settings, &mut best);
            }
        } else if !(best.polished && cell.contains(best.x)) {
            iterations += minimize_in_cell(a, b, &cell, settings, &mut best);
        }
    }
    if best.distance > touch {
        iterations += edge_minima(a, b, settings, cutoff, slack, &mut best);
    }
    let (closest, iterations) = finish_search(a, b, best, iterations, settings);
    let searched = closest.map_or(f64::INFINITY, |c| c.distance - slack);
    SearchResult { closest, iterations, lower_bound: searched.min(set_aside).max(root.lower_bound) }
}

/// The minima on the four edges of the square (an end of one piece against the other piece),
/// each found exactly by the 1-D nearest point and polished in the whole square. In a nearly
/// flat valley a leaf cell can hold an interior minimum and a lower one on the edge; this
/// finds the latter.
fn edge_minima(
    a: &CubicSegment,
    b: &CubicSegment,
    settings: &CurvePairSettings,
    cutoff: f64,
    slack: f64,
    best: &mut Best,
) -> u32 {
    let mut iterations = 0;
    for end in [0.0, 1.0] {
        let (end_a, end_b) = (a.position(end), b.position(end));
        let candidates = [(end_a, b, true), (end_b, a, false)];
        for (point, piece, t_fixed) in candidates {
            let point_piece = CubicSegment { bezier: [point; 4] };
            let gap = hull_gap(&point_piece, piece);
            if gap > cutoff || gap > best.distance - slack {
                continue;
            }
            let (along, distance) = piece.nearest_parameter(point);
            iterations += 1;
            if distance > cutoff || distance > best.distance {
                continue;
            }
            let start = if t_fixed { DVec2::new(end, along) } else { DVec2::new(along, end) };
            let polished = minimize_distance(a, b, start, ParamBox::UNIT, settings);
            iterations += polished.iterations;
            if polished.distance < best.distance {
                *best = Best { x: polished.x, distance: polished.distance, polished: true };
            }
        }
    }
    iterations
}

/// Runs Newton from a cell and keeps the result if it beats `best`; returns the iterations.
fn minimize_in_cell(
    a: &CubicSegment,
    b: &CubicSegment,
    cell: &Cell,
    settings: &CurvePairSettings,
    best: &mut Best,
) -> u32 {
    let found = minimize_from_cell(a, b, cell, settings);
    if found.distance < best.distance {
        *best = Best { x: found.x, distance: found.distance, polished: true };
    }
    found.iterations
}

/// Polishes an unpolished best point (one found only as a cell centre): the nearest points,
/// if any cell was searched, and the iterations spent in all.
fn finish_search(
    a: &CubicSegment,
    b: &CubicSegment,
    mut best: Best,
    mut iterations: u32,
    settings: &CurvePairSettings,
) -> (Option<ClosestPoints>, u32) {
    if best.distance.is_infinite() {
        return (None, iterations);
    }
    if !best.polished {
        let found = minimize_distance(a, b, best.x, ParamBox::UNIT, settings);
        iterations += found.iterations;
        if found.distance <= best.distance {
            best = Best { x: found.x, distance: found.distance, polished: true };
        }
    }
    (Some(closest_at(a, b, best.x, iterations)), iterations)
}

/// A crossing `p(t) = q(s)` inside the cell by Newton on `p(t) − q(s) = 0` from its centre
/// (quadratic at a transversal crossing, whatever other minima of the distance are near).
fn crossing_in_cell(
    a: &CubicSegment,
    b: &CubicSegment,
    cell: &Cell,
    touch: f64,
    settings: &CurvePairSettings,
) -> Option<DVec2> {
    let bounds = ParamBox { low: DVec2::new(cell.t0, cell.s0), high: DVec2::new(cell.t1, cell.s1) };
    let mut x = cell.centre();
    for _ in 0..settings.max_newton_iterations.min(24) {
        let residual = a.position(x.x) - b.position(x.y);
        if residual.length() <= touch {
            return Some(x);
        }
        let (pa, qb) = (a.derivative(x.x), b.derivative(x.y));
        // Solve pa·δt − qb·δs = −residual by Cramer's rule.
        let det = -pa.perp_dot(qb);
        if det.abs() <= 1e-14 * pa.length() * qb.length() || !det.is_finite() {
            return None;
        }
        let step = DVec2::new(-(-residual).perp_dot(qb) / det, pa.perp_dot(-residual) / det);
        let next = bounds.clamp(x + step);
        if next == x {
            return None;
        }
        x = next;
    }
    None
}

/// Pushes the children that survive pruning, nearest centres on top; the smallest bound of the
/// children set aside lowers `set_aside`.
fn push_children(
    cell: &Cell,
    stack: &mut CellStack,
    best: &mut Best,
    (cutoff, slack): (f64, f64),
    set_aside: &mut f64,
) {
    let mut all = cell.children();
    // A point-like piece (an edge of the square seen from the other piece) is not split.
    let children: &mut [(Cell, f64)] = match (is_point(&cell.a), is_point(&cell.b)) {
        (true, true) => &mut all[..1],
        (true, false) => &mut all[..2],
        (false, true) => {
            all[1] = all[2];
            &mut all[..2]
        }
        (false, false) => &mut all[..],
    };
    for (child, centre_distance) in children.iter() {
        if *centre_distance < best.distance {
            *best = Best { x: child.centre(), distance: *centre_distance, polished: false };
        }
    }
    // Farthest first onto the stack so the nearest centres are searched first.
    children.sort_unstable_by(|x, y| y.1.total_cmp(&x.1));
    for &mut (child, _) in children {
        if child.lower_bound <= cutoff && child.lower_bound <= best.distance - slack {
            // Cannot overflow: each level leaves at most three siblings waiting.
            stack.push(child);
        } else {
            *set_aside = set_aside.min(child.lower_bound);
        }
    }
}

fn is_point(piece: &CubicSegment) -> bool {
    let [b0, b1, b2, b3] = piece.bezier;
    b0 == b1 && b1 == b2 && b2 == b3
}

fn is_newton_cell(cell: &Cell, settings: &CurvePairSettings, max_depth: u32, scale: f64) -> bool {
    cell.depth >= max_depth
        || (cell.depth >= settings.seed_depth
            && is_flat(&cell.a, settings.flatness_ratio, scale)
            && is_flat(&cell.b, settings.flatness_ratio, scale))
}

/// Inner Bézier points within `ratio` × chord of the chord (a point-like piece is flat).
fn is_flat(piece: &CubicSegment, ratio: f64, scale: f64) -> bool {
    let [b0, b1, b2, b3] = piece.bezier;
    let chord = b3 - b0;
    let length = chord.length();
    let size = bezier_diagonal(piece);
    if size <= 1e-12 * scale {
        return true;
    }
    if length <= 1e-3 * size {
        return false;
    }
    let deviation = (b1 - b0).perp_dot(chord).abs().max((b2 - b0).perp_dot(chord).abs()) / length;
    // The inner points must also project inside the chord, or the piece folds back on itself.
    let inside = |p: DVec2| (-ratio..=1.0 + ratio).contains(&((p - b0).dot(chord) / (length * length)));
    deviation <= ratio * length && inside(b1) && inside(b2)
}

/// Lower bound of the distance between two pieces: the largest gap between the projections of
/// their Bézier points on the centre line, the two chord normals and the coordinate axes.
fn hull_gap(a: &CubicSegment, b: &CubicSegment) -> f64 {
    // The coordinate axes need no products and no normalisation.
    let mut gap = axis_gap(&a.bezier.map(|p| p.x), &b.bezier.map(|p| p.x))
        .max(axis_gap(&a.bezier.map(|p| p.y), &b.bezier.map(|p| p.y)))
        .max(0.0);
    for axis in oblique_axes(a, b) {
        // Projections on the unnormalised axis scale the gap by |axis|: only a gap larger
        // than the best so far needs the square root (overlapping hulls, the common case deep
        // in a search, skip it).
        let scaled = axis_gap(&a.bezier.map(|p| p.dot(axis)), &b.bezier.map(|p| p.dot(axis)));
        if scaled > 0.0 && scaled * scaled > gap * gap * axis.length_squared() {
            let length = axis.length();
            if length > 0.0 && length.is_finite() {
                gap = gap.max(scaled / length);
            }
        }
    }
    gap
}

/// The axes of [`hull_gap`] besides the coordinate axes (not normalised): the line between the
/// pieces' Bézier centroids and the two chord normals.
fn oblique_axes(a: &CubicSegment, b: &CubicSegment) -> [DVec2; 3] {
    let centre = |s: &CubicSegment| 0.25 * (s.bezier[0] + s.bezier[1] + s.bezier[2] + s.bezier[3]);
    let chord_normal = |s: &CubicSegment| (s.bezier[3] - s.bezier[0]).perp();
    [centre(b) - centre(a), chord_normal(a), chord_normal(b)]
}

/// Number of axes [`separating_axes`] tries.
pub const SEPARATING_AXES: usize = 5;

/// The pieces' gaps along the axes of [`hull_gap`] (the centre line, the two chord normals and
/// the coordinate axes), each between the pieces' exact projections on that fixed world axis:
/// `(unit axis, gap)`, the gap ≤ 0 where the axis does not separate them. Unlike a distance
/// bound, a gap along a fixed axis closes only as fast as the relative velocity along that
/// axis, which conservative advancement uses for pieces that slide past each other.
#[must_use]
pub fn separating_axes(a: &CubicSegment, b: &CubicSegment) -> [(DVec2, f64); SEPARATING_AXES] {
    let [centre_line, normal_a, normal_b] = oblique_axes(a, b);
    [centre_line, normal_a, normal_b, DVec2::X, DVec2::Y].map(|axis| {
        let Some(axis) = axis.try_normalize() else { return (DVec2::ZERO, f64::NEG_INFINITY) };
        let (a_low, a_high) = a.projection_range(axis);
        let (b_low, b_high) = b.projection_range(axis);
        (axis, (b_low - a_high).max(a_low - b_high))
    })
}

/// Gap between the ranges of two sets of four projections (negative when they overlap).
fn axis_gap(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let (a_low, a_high) = range4(a);
    let (b_low, b_high) = range4(b);
    let forward = b_low - a_high;
    let backward = a_low - b_high;
    if forward > backward { forward } else { backward }
}

/// Smallest and largest of four finite values, by plain comparisons.
fn range4(v: &[f64; 4]) -> (f64, f64) {
    let (low01, high01) = if v[0] < v[1] { (v[0], v[1]) } else { (v[1], v[0]) };
    let (low23, high23) = if v[2] < v[3] { (v[2], v[3]) } else { (v[3], v[2]) };
    (if low01 < low23 { low01 } else { low23 }, if high01 > high23 { high01 } else { high23 })
}

fn bezier_diagonal(piece: &CubicSegment) -> f64 {
    let low = piece.bezier.iter().copied().fold(DVec2::splat(f64::INFINITY), DVec2::min);
    let high = piece.bezier.iter().copied().fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
    (high - low).length()
}

/// Size of a piece pair: the larger control-box diagonal (lengths in the settings scale by it).
#[must_use]
pub fn pair_scale(a: &CubicSegment, b: &CubicSegment) -> f64 {
    bezier_diagonal(a).max(bezier_diagonal(b))
}

fn closest_at(a: &CubicSegment, b: &CubicSegment, x: DVec2, newton_iterations: u32) -> ClosestPoints {
    let point_a = a.position(x.x);
    let point_b = b.position(x.y);
    ClosestPoints { t: x.x, s: x.y, point_a, point_b, distance: point_a.distance(point_b), newton_iterations }
}

// ---------------------------------------------------------------------------------------------
// Safeguarded Newton on D = ½|p(t) − q(s)|².

/// `D`, its gradient and Hessian at one parameter pair.
#[derive(Clone, Copy, Debug)]
struct DistanceJet {
    value: f64,
    gradient: DVec2,
    /// `[H_tt, H_ts, H_ss]`.
    hessian: [f64; 3],
    /// `|p'|² + |q'|²`, the scale of the Hessian.
    speed: f64,
}

fn distance_jet(a: &CubicSegment, b: &CubicSegment, x: DVec2) -> DistanceJet {
    let [p, p1, p2] = a.jet(x.x);
    let [q, q1, q2] = b.jet(x.y);
    let r = p - q;
    DistanceJet {
        value: 0.5 * r.length_squared(),
        gradient: DVec2::new(r.dot(p1), -r.dot(q1)),
        hessian: [p1.length_squared() + r.dot(p2), -p1.dot(q1), q1.length_squared() - r.dot(q2)],
        speed: p1.length_squared() + q1.length_squared(),
    }
}

struct NewtonResult {
    x: DVec2,
    distance: f64,
    iterations: u32,
}

/// A box of parameter pairs `(t, s)`.
#[derive(Clone, Copy, Debug)]
struct ParamBox {
    low: DVec2,
    high: DVec2,
}

impl ParamBox {
    const UNIT: Self = Self { low: DVec2::ZERO, high: DVec2::ONE };

    fn clamp(&self, x: DVec2) -> DVec2 {
        x.clamp(self.low, self.high)
    }

    /// Whether `x` lies on a side of this box that is not a side of the unit square.
    fn on_inner_side(&self, x: DVec2) -> bool {
        let inner = |xi: f64, lo: f64, hi: f64| (xi <= lo && lo > 0.0) || (xi >= hi && hi < 1.0);
        inner(x.x, self.low.x, self.high.x) || inner(x.y, self.low.y, self.high.y)
    }
}

/// Newton confined to the cell first, so that every flat cell yields its own minimum even
/// where a nearly flat valley would carry an unconfined iterate to another basin; a minimum
/// on an inner side of the cell is then released into the whole square.
fn minimize_from_cell(a: &CubicSegment, b: &CubicSegment, cell: &Cell, settings: &CurvePairSettings) -> NewtonResult {
    let bounds = ParamBox { low: DVec2::new(cell.t0, cell.s0), high: DVec2::new(cell.t1, cell.s1) };
    let local = minimize_distance(a, b, cell.centre(), bounds, settings);
    if !bounds.on_inner_side(local.x) {
        return local;
    }
    let released = minimize_distance(a, b, local.x, ParamBox::UNIT, settings);
    NewtonResult { iterations: local.iterations + released.iterations, ..released }
}

/// Local minimum of `D` over `bounds` from `start`, by Newton with an active set, a
/// Levenberg–Marquardt shift and backtracking. Never increases `D`.
fn minimize_distance(
    a: &CubicSegment,
    b: &CubicSegment,
    start: DVec2,
    bounds: ParamBox,
    settings: &CurvePairSettings,
) -> NewtonResult {
    let mut x = bounds.clamp(start);
    let mut jet = distance_jet(a, b, x);
    let mut iterations = 0;
    let mut previous_move = f64::INFINITY;
    while iterations < settings.max_newton_iterations {
        let Some(step) = newton_step(x, &jet, &bounds) else { break };
        let Some((mut next, mut next_jet, full_step)) = backtrack(a, b, x, &jet, step, &bounds) else { break };
        iterations += 1;
        let moved = (next - x).abs().max_element();
        // Near a tangency D is quartic along the valley and Newton only shrinks the error by
        // 2/3 per step; the step that removes it is three times as long: try it.
        if (0.55..0.8).contains(&(moved / previous_move)) {
            let far = bounds.clamp(x + 3.0 * (next - x));
            let far_jet = distance_jet(a, b, far);
            if far_jet.value < next_jet.value {
                (next, next_jet) = (far, far_jet);
            }
        }
        previous_move = moved;
        x = next;
        jet = next_jet;
        if moved <= settings.newton_step_tolerance && full_step {
            break;
        }
    }
    NewtonResult { x, distance: (2.0 * jet.value).sqrt(), iterations }
}

/// Parameters within this fraction of the box width of a bound count as on it (active set).
const ACTIVE_BOUND: f64 = 1e-9;

/// The Newton step on the free variables (pinned ones snap to their bound); `None` at a
/// Karush–Kuhn–Tucker point.
fn newton_step(x: DVec2, jet: &DistanceJet, bounds: &ParamBox) -> Option<DVec2> {
    let g = jet.gradient;
    let margin = ACTIVE_BOUND * (bounds.high - bounds.low);
    // ε-active set: a variable this close to a bound, pushed outward, is pinned and snapped to
    // the bound; plain projection would crawl towards it in ever shorter steps.
    let pinned = |xi: f64, gi: f64, lo: f64, hi: f64, m: f64| (xi <= lo + m && gi > 0.0) || (xi >= hi - m && gi < 0.0);
    let free_t = !pinned(x.x, g.x, bounds.low.x, bounds.high.x, margin.x);
    let free_s = !pinned(x.y, g.y, bounds.low.y, bounds.high.y, margin.y);
    let snap = |xi: f64, gi: f64, lo: f64, hi: f64| if gi > 0.0 { lo - xi } else { hi - xi };
    let snap_t = || snap(x.x, g.x, bounds.low.x, bounds.high.x);
    let snap_s = || snap(x.y, g.y, bounds.low.y, bounds.high.y);
    let [htt, hts, hss] = jet.hessian;
    // A Hessian eigenvalue below this is shifted up to it (Levenberg–Marquardt). Small, so
    // the nearly singular Hessian of a tangency still gives full Newton steps.
    let floor = 1e-14 * jet.speed + f64::MIN_POSITIVE;
    let step = match (free_t, free_s) {
        (false, false) => DVec2::new(snap_t(), snap_s()),
        (true, false) => DVec2::new((-g.x / htt.max(floor)).clamp(-1.0, 1.0), snap_s()),
        (false, true) => DVec2::new(snap_t(), (-g.y / hss.max(floor)).clamp(-1.0, 1.0)),
        (true, true) => solve_shifted([htt, hts, hss], g, floor),
    };
    (step != DVec2::ZERO && step.is_finite()).then_some(step)
}

/// Solves `(H + μI) Δ = −g` with μ lifting the smallest eigenvalue of `H` to at least `floor`
/// and, where that step would leave a box of unit width, raised further (Levenberg–Marquardt):
/// a nearly singular `H` (parallel tangents) must not turn rounding noise into the step.
fn solve_shifted([htt, hts, hss]: [f64; 3], g: DVec2, floor: f64) -> DVec2 {
    let mean = 0.5 * (htt + hss);
    let radius = (0.25 * (htt - hss) * (htt - hss) + hts * hts).sqrt();
    let mut shift = (floor - (mean - radius)).max(0.0);
    let scale = htt.abs() + hss.abs() + floor;
    for _ in 0..64 {
        let (a, c) = (htt + shift, hss + shift);
        let det = a * c - hts * hts;
        let step = DVec2::new(-(c * g.x - hts * g.y) / det, -(a * g.y - hts * g.x) / det);
        if det > 0.0 && step.is_finite() && step.abs().max_element() <= 1.0 {
            return step;
        }
        shift = (4.0 * shift).max(1e-12 * scale);
    }
    DVec2::ZERO
}

/// Projected backtracking (Armijo) on `D`: the new point, its jet and whether the full step was
/// taken; `None` when no step length decreases `D`.
fn backtrack(
    a: &CubicSegment,
    b: &CubicSegment,
    x: DVec2,
    jet: &DistanceJet,
    step: DVec2,
    bounds: &ParamBox,
) -> Option<(DVec2, DistanceJet, bool)> {
    let mut alpha = 1.0;
    for _ in 0..40 {
        let next = bounds.clamp(x + alpha * step);
        if next == x {
            return None;
        }
        let next_jet = distance_jet(a, b, next);
        if next_jet.value <= jet.value + 1e-4 * jet.gradient.dot(next - x) {
            return Some((next, next_jet, alpha == 1.0));
        }
        alpha *= 0.5;
    }
    None
}

// ---------------------------------------------------------------------------------------------
// Conformal pieces: the ends of the overlap.

/// Whether the pieces are conformal at their nearest points: the gap between them, which grows
/// like `½ (k_a + k_b) x²` along the common tangent (`k` the curvature of each piece bending
/// away from the other), changes by at most `conformal_fraction` of the band over the pieces.
fn is_conformal(
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
fn overlap_ends(
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
fn overlap_end(
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
fn is_foot(b: &CubicSegment, s: f64, p: DVec2) -> bool {
    let along = (p - b.position(s)).dot(b.derivative(s));
    let tolerance = 1e-9 * (p - b.position(s)).length() * b.derivative(s).length() + f64::MIN_POSITIVE;
    (s > 0.0 || along >= -tolerance) && (s < 1.0 || along <= tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(from: DVec2, to: DVec2) -> CubicSegment {
        CubicSegment { bezier: [from, from.lerp(to, 1.0 / 3.0), from.lerp(to, 2.0 / 3.0), to] }
    }

    #[test]
    fn crossing_lines_intersect_at_the_crossing() {
        let a = line(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0));
        let b = line(DVec2::new(0.0, 1.0), DVec2::new(1.0, 0.0));
        let (t, s) = intersect_segment_segment(&a, &b, &CurvePairSettings::default()).unwrap();
        assert!((t - 0.5).abs() < 1e-12 && (s - 0.5).abs() < 1e-12);
    }

    #[test]
    fn skew_lines_have_their_nearest_points_at_an_end() {
        let a = line(DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0));
        let b = line(DVec2::new(2.0, 1.0), DVec2::new(3.0, 5.0));
        let c = closest_points_segment_segment(&a, &b, &CurvePairSettings::default());
        assert!((c.t - 1.0).abs() < 1e-15 && c.s.abs() < 1e-15);
        assert!((c.distance - 2f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn parallel_lines_in_the_band_give_two_points() {
        let a = TolerancedSegment {
            segment: line(DVec2::new(0.0, 0.0), DVec2::new(2.0, 0.0)),
            tolerance: SegmentTolerance::constant(0.05, 0.0),
        };
        let b = TolerancedSegment {
            segment: line(DVec2::new(1.5, 0.08), DVec2::new(0.5, 0.08)),
            tolerance: SegmentTolerance::constant(0.05, 0.0),
        };
        let q = query_segment_segment(&a, &b, Orientation::Clockwise, &CurvePairSettings::default());
        assert_eq!(q.state, SegmentPairState::Contact, "{q:?}");
        let ends = q.contacts.as_slice();
        assert_eq!(ends.len(), 2);
        let mut xs = [ends[0].point_a.x, ends[1].point_a.x];
        xs.sort_by(f64::total_cmp);
        assert!((xs[0] - 0.5).abs() < 1e-9 && (xs[1] - 1.5).abs() < 1e-9, "{xs:?}");
        for e in ends {
            assert!((e.distance - 0.08).abs() < 1e-12 && (e.penetration - 0.02).abs() < 1e-12);
            assert!((e.normal - DVec2::new(0.0, -1.0)).length() < 1e-12, "{:?}", e.normal);
        }
    }
}
