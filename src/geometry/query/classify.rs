//! The leaf pairs of a body-pair query classed one by one (by the curve-pair solver, or from the
//! pair's memory where it may be trusted), their pieces placed in the world once a query, and
//! what each answer adds to the manifold.

use glam::DVec2;

use super::coherence::{MemoryCursor, remember};
use super::{
    BodyContact, BodyShape, Coherence, LeafMemory, Manifold, PairState, PlacedLeaf, QuerySettings, SegmentIntersection,
};
use crate::geometry::curve_pair::{
    Hulls, SegmentContact, SegmentPairQuery, SegmentPairState, query_segment_segment_from,
};
use crate::geometry::pose::Pose;
use crate::geometry::segment::CubicSegment;

/// Contacts and intersections of bodies A and B over the candidate leaf pairs (MODEL §4).
///
/// Each leaf pair reports its nearest points when they lie in the combined band (two points
/// for conformal pieces). A leaf's nearest point on the border of its square that is not a
/// local minimum of the whole curves (the distance keeps falling into the neighbouring segment)
/// is dropped: the neighbour's leaf pair, whose fattened boxes then overlap too, reports the
/// true minimum. The same contact found by adjacent leaves at a joint is reported once.
pub fn query_leaf_pairs(
    a: &BodyShape<'_>,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    pose_b: &Pose,
    candidate_pairs: &[(u32, u32)],
    settings: &QuerySettings,
    out: &mut Manifold,
) {
    let floors = (settings.min_band, settings.min_band);
    let gap_limit = f64::INFINITY;
    classify_leaf_pairs(a, pose_a, b, pose_b, candidate_pairs, floors, Coherence::OFF, settings, out, None, gap_limit);
}

/// [`query_leaf_pairs`] with the band floors of A and B, answering from `coherence` where it
/// may be trusted and writing the memory of every leaf pair to `memory` (in candidate order);
/// leaf pairs whose clearance is at least `gap_limit` are left out of the gaps.
#[allow(clippy::too_many_arguments)]
pub(super) fn classify_leaf_pairs(
    a: &BodyShape<'_>,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    pose_b: &Pose,
    candidate_pairs: &[(u32, u32)],
    floors: (f64, f64),
    coherence: Coherence<'_>,
    settings: &QuerySettings,
    out: &mut Manifold,
    mut memory: Option<&mut Vec<LeafMemory>>,
    gap_limit: f64,
) {
    out.clear();
    if let Some(memory) = memory.as_deref_mut() {
        memory.clear();
    }
    let relative = pose_b.relative(pose_a);
    PLACED.with_borrow_mut(|Placed { a: cached_a, b: cached_b }| {
        cached_a.index = PlacedLeaf::EMPTY;
        cached_b.iter_mut().for_each(|leaf| leaf.index = PlacedLeaf::EMPTY);
        let uniform = (a.rugosity.uniform_tolerance(floors.0), b.rugosity.uniform_tolerance(floors.1));
        // How far A's piece reaches from A's origin, worked out when a memory first needs it
        // (NaN before: most pieces have none).
        let mut reach_a = f64::NAN;
        let mut cursor = MemoryCursor::START;
        for &(i, j) in candidate_pairs {
            // Candidates usually come grouped by A's segment: move each of A's segments once.
            // Read where it is kept: copying its 152 bytes for every leaf pair cost the landing pile
            // of 100 blobs 0.85 M instructions a step (docs/performance.md).
            if cached_a.index != i {
                cached_a.place(a, i, pose_a, floors.0, uniform.0.as_ref());
                reach_a = f64::NAN;
            }
            let placed_a = &*cached_a;
            // B's pieces recur for each of A's segments near them: the last few are kept, by index.
            let placed_b = match &mut cached_b[j as usize % CACHED_B] {
                kept if kept.index == j => &*kept,
                kept => kept.place(b, j, pose_b, floors.1, uniform.1.as_ref()),
            };
            let (leaf_a, leaf_b) = (&placed_a.leaf, &placed_b.leaf);
            let curve_pair = &settings.curve_pair;
            let remembered = coherence.remembered((i, j), &mut cursor);
            let recalled = remembered.and_then(|memory| {
                if reach_a.is_nan() {
                    reach_a = a.reach(i as usize);
                }
                coherence.recall(memory, &relative, reach_a, (leaf_a, leaf_b), b.orientation, curve_pair)
            });
            // Each answer is read where it was built: moved out of its branch, each search's
            // 376 bytes were copied once more (0.09 M of the landing pile of 100 blobs' 24.1 M
            // instructions a step).
            if let Some((query, kept)) = &recalled {
                out.recalled_leaf_pairs += 1;
                if let Some(memory) = memory.as_deref_mut() {
                    memory.push(*kept);
                }
                answer(out, query, (i, j), (placed_a, placed_b), (a, b), settings, gap_limit);
                continue;
            }
            // A pair the hulls alone set apart: separate, nothing to search or remember.
            let hull_gap = match Hulls::of((leaf_a, &placed_a.hull), (leaf_b, &placed_b.hull)) {
                Hulls::Apart(gap) => {
                    out.push_gap(gap, (placed_a, placed_b), (gap_limit, settings.approach_depth));
                    continue;
                }
                Hulls::Near(gap) => gap,
            };
            // A contact moved past its trust radius is searched again, from its last answer.
            let seed = remembered.and_then(|memory| memory.seed).map(DVec2::from);
            let query = query_segment_segment_from(leaf_a, leaf_b, b.orientation, curve_pair, seed, hull_gap);
            // A pair the hulls alone set apart costs one hull test: nothing to remember.
            if let Some(memory) = memory.as_deref_mut().filter(|_| query.closest.is_some()) {
                let cutoff = leaf_a.tolerance.max + leaf_b.tolerance.max;
                memory.push(remember(i, j, relative, &query, cutoff));
            }
            answer(out, &query, (i, j), (placed_a, placed_b), (a, b), settings, gap_limit);
        }
    });
    out.state = if !out.intersections.is_empty() {
        PairState::Intersecting
    } else if out.contacts.is_empty() {
        PairState::Separate
    } else {
        PairState::Contact
    };
}

/// What the answer `query` of leaf pair `(i, j)` adds to `out`: its Newton steps, and its gap,
/// intersection or contacts (a contact whose distance falls across the border of the leaf square
/// left to the neighbour's leaf pair, one found again at a joint reported once).
fn answer(
    out: &mut Manifold,
    query: &SegmentPairQuery,
    (i, j): (u32, u32),
    (placed_a, placed_b): (&PlacedLeaf, &PlacedLeaf),
    (a, b): (&BodyShape<'_>, &BodyShape<'_>),
    settings: &QuerySettings,
    gap_limit: f64,
) {
    out.newton_iterations += u64::from(query.newton_iterations);
    match query.state {
        SegmentPairState::Separate => {
            out.push_gap(query.distance_lower_bound, (placed_a, placed_b), (gap_limit, settings.approach_depth));
        }
        SegmentPairState::Intersecting { t, s } => {
            out.intersections.push(SegmentIntersection { segment_a: i, segment_b: j, t, s });
        }
        SegmentPairState::Contact => {
            let single = query.contacts.as_slice().len() == 1;
            for contact in query.contacts.as_slice() {
                if single && leaves_through_border(&placed_a.leaf.segment, &placed_b.leaf.segment, contact) {
                    continue;
                }
                let found = BodyContact {
                    segment_a: i,
                    segment_b: j,
                    u_a: f64::from(i) + contact.t,
                    u_b: f64::from(j) + contact.s,
                    contact: *contact,
                };
                push_unique(
                    out,
                    found,
                    a.spline.segment_count(),
                    b.spline.segment_count(),
                    settings.duplicate_tolerance,
                );
            }
        }
    }
}

thread_local! {
    /// The pieces [`classify_leaf_pairs`] has placed in the world, kept by each thread from one
    /// query to the next (each query starts by marking them empty), so that a piece is built
    /// where it is read: built in the query and moved into place, each piece's 250 bytes were
    /// copied twice (1 % of a landing pile's instructions, docs/performance.md).
    static PLACED: std::cell::RefCell<Placed> = std::cell::RefCell::new(Placed::default());
}

/// A query's placed pieces: the last of A's, and the last few of B's by index ([`CACHED_B`]).
struct Placed {
    a: PlacedLeaf,
    b: [PlacedLeaf; CACHED_B],
}

impl Default for Placed {
    fn default() -> Self {
        Self { a: PlacedLeaf::empty(), b: [PlacedLeaf::empty(); CACHED_B] }
    }
}

/// How many of B's pieces [`classify_leaf_pairs`] keeps moved into the world (by segment index,
/// modulo this).
const CACHED_B: usize = 8;

/// Whether the distance decreases across the border of the leaf square at this contact, i.e.
/// the neighbouring segment holds a nearer point.
fn leaves_through_border(a: &CubicSegment, b: &CubicSegment, contact: &SegmentContact) -> bool {
    // Only a contact on a border of the square can leave through it (a NaN parameter is on
    // none): the slopes below are worked out only there (for every contact, they cost the landing
    // pile of 100 blobs 0.014 M of its 23.9 M instructions a step).
    let on_border = |x: f64| x >= 1.0 || x <= 0.0;
    if !on_border(contact.t) && !on_border(contact.s) {
        return false;
    }
    let r = contact.point_a - contact.point_b;
    let (da, db) = (a.derivative(contact.t), b.derivative(contact.s));
    let slope_t = r.dot(da);
    let slope_s = -r.dot(db);
    let leaves = |x: f64, slope: f64, speed: f64| {
        let tolerance = 1e-9 * r.length() * speed;
        (x >= 1.0 && slope < -tolerance) || (x <= 0.0 && slope > tolerance)
    };
    leaves(contact.t, slope_t, da.length()) || leaves(contact.s, slope_s, db.length())
}

fn push_unique(out: &mut Manifold, found: BodyContact, n_a: usize, n_b: usize, tolerance: f64) {
    let same = |c: &BodyContact| {
        periodic_gap(c.u_a, found.u_a, n_a as f64) <= tolerance
            && periodic_gap(c.u_b, found.u_b, n_b as f64) <= tolerance
    };
    if !out.contacts.iter().any(same) {
        out.contacts.push(found);
    }
}

/// Distance between two global parameters on a closed curve of period `n`.
fn periodic_gap(u: f64, v: f64, n: f64) -> f64 {
    let gap = (u - v).rem_euclid(n);
    gap.min(n - gap)
}
