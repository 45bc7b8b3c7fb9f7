//! The body-level narrow phase: contacts and intersections of two bodies from candidate leaf
//! pairs (segment of A, segment of B), as a broad phase or the AOBB tree supplies them.

mod classify;
mod coherence;
mod manifold;

use classify::classify_leaf_pairs;
pub use classify::query_leaf_pairs;
pub use coherence::{Coherence, LeafFront, LeafMemory};
pub use manifold::{LeafGap, Manifold, SegmentIntersection};

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::aobb_tree::{AobbTree, TraversalCounters, TraversalWorkspace};
use crate::geometry::curve_pair::{CurvePairSettings, Orientation, PieceHull, SegmentContact, TolerancedSegment};
use crate::geometry::pose::Pose;
use crate::geometry::rugosity::{Rugosity, SegmentTolerance};
use crate::geometry::segment::CubicSegment;
use crate::geometry::spline::Spline;

/// A body's boundary and rugosity, borrowed for a query (poses are passed separately).
#[derive(Clone, Copy, Debug)]
pub struct BodyShape<'a> {
    /// Boundary in the body frame.
    pub spline: &'a Spline,
    /// One tolerance per segment of `spline`.
    pub rugosity: &'a Rugosity,
    /// Running direction of `spline` (counter-clockwise for every validated body).
    pub orientation: Orientation,
}

impl<'a> BodyShape<'a> {
    /// A counter-clockwise body (as [`Spline::from_control_points`] builds it).
    #[must_use]
    pub fn new(spline: &'a Spline, rugosity: &'a Rugosity) -> Self {
        Self { spline, rugosity, orientation: Orientation::CounterClockwise }
    }

    /// Segment `index` with its tolerance, moved into the world by `pose`.
    #[must_use]
    pub fn world_segment(&self, index: usize, pose: &Pose, min_band: f64) -> TolerancedSegment {
        let mut leaf = unplaced();
        self.place_segment(index, pose, min_band, None, &mut leaf);
        leaf
    }

    /// [`BodyShape::world_segment`] written into `leaf`: the narrow phase places its pieces
    /// where it keeps them (`PLACED` in `query/classify.rs`); returned and moved into place, each piece's 152 bytes
    /// were copied once more (0.5 % of a landing pile's instructions, docs/performance.md).
    /// `uniform` is the tolerance of every segment where it is the same on each
    /// ([`Rugosity::uniform_tolerance`]): a query works it out once instead of looking it up for
    /// each piece.
    fn place_segment(
        &self,
        index: usize,
        pose: &Pose,
        min_band: f64,
        uniform: Option<&SegmentTolerance>,
        leaf: &mut TolerancedSegment,
    ) {
        leaf.segment = self.spline.segment(index).transformed(pose);
        // Each arm writes in place: a `match` giving the value to assign built it on the stack
        // first, and copied its 88 bytes twice.
        match uniform {
            Some(tolerance) => leaf.tolerance = *tolerance,
            None => leaf.tolerance = self.rugosity.segment_tolerance(index, min_band),
        }
    }

    /// How far segment `index` lies from the body's origin (its farthest Bézier point): a turn
    /// by `δθ` moves it by at most `δθ` times this.
    fn reach(&self, index: usize) -> f64 {
        self.spline.segment(index).bezier.iter().map(|p| p.length_squared()).fold(0.0, f64::max).sqrt()
    }
}

/// Settings of the body-level query.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct QuerySettings {
    /// Minimum band λ_min (m): λ is floored at it, so smooth bodies (all R = 0) still have a
    /// band in which resting contact lives (MODEL §4, our choice). Default 1e-3 m, i.e. 1e-3 of
    /// a 1 m body: far above the solver's accuracy (~1e-12 of the segment size), below the
    /// shape error of a coarse spline. Used by [`query_leaf_pairs`]; a query through AOBB
    /// trees ([`query_bodies`]) floors each body at its own tree's [`AobbTree::floor`], the
    /// one its boxes were fattened with.
    pub min_band: f64,
    /// Two contacts whose global parameters on both bodies differ by at most this are the
    /// same contact found by adjacent leaves at a joint (default 1e-7, parameter units).
    pub duplicate_tolerance: f64,
    /// The leaf solver's settings.
    pub curve_pair: CurvePairSettings,
    /// How deep into its combined band `λ_A + λ_B` conservative advancement lets a separate
    /// leaf pair come, as a fraction of the band: each [`LeafGap`] is how far the pair may close
    /// before its distance falls to `(1 − approach_depth)(λ_A + λ_B)` (docs/model.md §7; the
    /// simulation's is `SimulationSettings::approach_depth`, checked to lie in [0.05, 0.9]).
    /// Default 0.75; a value outside [0, 1] is taken at the nearer end, so that a gap never
    /// exceeds the distance.
    pub approach_depth: f64,
}

impl Default for QuerySettings {
    fn default() -> Self {
        Self {
            min_band: 1e-3,
            duplicate_tolerance: 1e-7,
            curve_pair: CurvePairSettings::default(),
            approach_depth: 0.75,
        }
    }
}

/// Overall state of a body pair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PairState {
    /// No leaf pair in contact or intersecting.
    #[default]
    Separate,
    /// At least one contact, no intersection.
    Contact,
    /// At least one leaf pair intersects: the step must be retried (MODEL §4).
    Intersecting,
}

/// A contact between two bodies: which segments, where on each body, and the contact record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyContact {
    /// Segment of A.
    pub segment_a: u32,
    /// Segment of B.
    pub segment_b: u32,
    /// Global parameter on A, `u = i + t`.
    pub u_a: f64,
    /// Global parameter on B, `u = j + s`.
    pub u_b: f64,
    /// Points, normal (outward of B), distance, penetration and tolerances, in the world.
    pub contact: SegmentContact,
}

/// A disc holding the piece: centred on the mean of its Bézier points, through the farthest one
/// (one square root: it is monotone, so that of the largest square is the largest distance).
fn hull_disc(segment: &CubicSegment) -> (DVec2, f64) {
    let centre = segment.bezier.iter().fold(DVec2::ZERO, |acc, &p| acc + p) / 4.0;
    (centre, segment.bezier.iter().map(|p| p.distance_squared(centre)).fold(0.0, f64::max).sqrt())
}

/// A zero piece with a zero band, for a place no piece has been written into yet.
fn unplaced() -> TolerancedSegment {
    TolerancedSegment {
        segment: CubicSegment { bezier: [DVec2::ZERO; 4] },
        tolerance: SegmentTolerance::constant(0.0, 0.0),
    }
}

/// A leaf's piece moved into the world, with what its hull tests read of it alone
/// ([`PieceHull`]) and the disc that holds it ([`hull_disc`]), worked out once for all the leaf
/// pairs the piece is in (docs/performance.md, "Where a landing pile's narrow phase goes").
#[derive(Clone, Copy, Debug)]
struct PlacedLeaf {
    /// The segment's index ([`PlacedLeaf::EMPTY`] before any is placed).
    index: u32,
    leaf: TolerancedSegment,
    hull: PieceHull,
    disc: (DVec2, f64),
}

impl PlacedLeaf {
    /// The index of a place that holds no segment yet.
    const EMPTY: u32 = u32::MAX;

    fn empty() -> Self {
        let leaf = unplaced();
        Self { index: Self::EMPTY, hull: PieceHull::of(&leaf.segment), disc: hull_disc(&leaf.segment), leaf }
    }

    /// Segment `index` of `shape` moved into the world by `pose` ([`BodyShape::world_segment`]),
    /// written where it is kept (`PLACED` in `query/classify.rs`); `uniform` as for [`BodyShape::place_segment`].
    fn place(
        &mut self,
        shape: &BodyShape<'_>,
        index: u32,
        pose: &Pose,
        min_band: f64,
        uniform: Option<&SegmentTolerance>,
    ) -> &Self {
        self.index = index;
        shape.place_segment(index as usize, pose, min_band, uniform, &mut self.leaf);
        self.hull = PieceHull::of(&self.leaf.segment);
        self.disc = hull_disc(&self.leaf.segment);
        self
    }
}

/// How many entries each buffer of a [`BodyQuery`] holds without growing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QueryCapacity {
    /// Leaf pairs of the tree descent.
    pub leaf_pairs: usize,
    /// The descent's stack.
    pub stack: usize,
    /// Contacts.
    pub contacts: usize,
    /// Intersecting leaf pairs.
    pub intersections: usize,
    /// Gaps of separate leaf pairs.
    pub gaps: usize,
    /// Memory of the leaf pairs' searches.
    pub memory: usize,
    /// Leaf pairs of the last descent (the front).
    pub front: usize,
}

impl QueryCapacity {
    /// The bytes buffers of this capacity take on the heap.
    #[must_use]
    pub fn bytes(&self) -> usize {
        use std::mem::size_of;
        (self.leaf_pairs + self.stack + self.front) * size_of::<(u32, u32)>()
            + self.contacts * size_of::<BodyContact>()
            + self.intersections * size_of::<SegmentIntersection>()
            + self.gaps * size_of::<LeafGap>()
            + self.memory * size_of::<LeafMemory>()
    }

    /// The larger of each buffer's capacity.
    #[must_use]
    pub fn max(self, other: Self) -> Self {
        Self {
            leaf_pairs: self.leaf_pairs.max(other.leaf_pairs),
            stack: self.stack.max(other.stack),
            contacts: self.contacts.max(other.contacts),
            intersections: self.intersections.max(other.intersections),
            gaps: self.gaps.max(other.gaps),
            memory: self.memory.max(other.memory),
            front: self.front.max(other.front),
        }
    }
}

impl BodyQuery {
    /// What each buffer holds without growing.
    #[must_use]
    pub fn capacity(&self) -> QueryCapacity {
        QueryCapacity {
            leaf_pairs: self.leaf_pairs.capacity(),
            stack: self.workspace.capacity(),
            contacts: self.manifold.contacts.capacity(),
            intersections: self.manifold.intersections.capacity(),
            gaps: self.manifold.gaps.capacity(),
            memory: self.memory.capacity(),
            front: self.front_pairs.capacity(),
        }
    }

    /// Grows every buffer to at least `capacity` (nothing happens where it already holds that).
    pub fn reserve(&mut self, capacity: QueryCapacity) {
        fn grow<T>(buffer: &mut Vec<T>, capacity: usize) {
            buffer.reserve_exact(capacity.saturating_sub(buffer.len()));
        }
        grow(&mut self.leaf_pairs, capacity.leaf_pairs);
        self.workspace.reserve(capacity.stack);
        grow(&mut self.manifold.contacts, capacity.contacts);
        grow(&mut self.manifold.intersections, capacity.intersections);
        grow(&mut self.manifold.gaps, capacity.gaps);
        grow(&mut self.memory, capacity.memory);
        grow(&mut self.front_pairs, capacity.front);
    }

    /// Takes from `other` what the pair's next query reads of its last one: the leaf memory
    /// ([`BodyQuery::memory`]) and the front ([`BodyQuery::front`]), the buffers swapped
    /// (nothing is copied or allocated, and `other` keeps buffers for its next query to write
    /// into) and the front's pose and reach copied. `other` is left with this query's old
    /// memory and front buffers beside its own pose and reach, which nothing may read before its
    /// next query writes them. The rest of each query stays where it is: the answer, which a
    /// query writes over, and the descent's leaf pairs, counters and scratch, which describe one
    /// query's work. Swapping the whole query moved its 248 bytes both ways, where a query reads
    /// of its last one two buffers (48 bytes) and the front's pose and reach (40).
    pub(crate) fn take_memory_from(&mut self, other: &mut BodyQuery) {
        std::mem::swap(&mut self.memory, &mut other.memory);
        std::mem::swap(&mut self.front_pairs, &mut other.front_pairs);
        (self.front_relative, self.front_reach) = (other.front_relative, other.front_reach);
    }

    /// Takes `other`'s answer ([`BodyQuery::manifold`]) with what the pair's next query reads
    /// of it ([`BodyQuery::take_memory_from`]): all that is read of a carried query until the
    /// pair is queried again (its contacts, gaps and state by the carry, the sub-step bound,
    /// the contact preparation and snapshots; its memory and front by the next query). The
    /// manifold's buffers are swapped and its state and counts copied; `other` is left with
    /// this query's old buffers, which nothing may read before its next query writes them. The
    /// descent's leaf pairs, counters and scratch stay where they are, each query's own: a
    /// carried query clears its leaf pairs and counters (`PairSlot::keep_carried`). Swapping
    /// the whole query instead cost the landing pile of 500 blobs about 1.0 M more instructions
    /// a step, of 78 M (docs/performance.md, "A carried pair's answer without its scratch").
    pub(crate) fn take_answer_from(&mut self, other: &mut BodyQuery) {
        self.take_memory_from(other);
        let (to, from) = (&mut self.manifold, &mut other.manifold);
        std::mem::swap(&mut to.contacts, &mut from.contacts);
        std::mem::swap(&mut to.intersections, &mut from.intersections);
        std::mem::swap(&mut to.gaps, &mut from.gaps);
        (to.state, to.newton_iterations, to.recalled_leaf_pairs) =
            (from.state, from.newton_iterations, from.recalled_leaf_pairs);
    }

    /// The leaf pairs of this query's tree descent (or of the one it kept), for the pair's next
    /// query; `None` before any.
    #[must_use]
    pub fn front(&self) -> Option<LeafFront<'_>> {
        (!self.front_reach.is_nan()).then_some(LeafFront {
            leaf_pairs: &self.front_pairs,
            relative: self.front_relative,
            reach: self.front_reach,
        })
    }
}

/// Scratch memory and result of [`query_bodies`]: reuse it and repeated queries allocate nothing.
#[derive(Clone, Debug)]
pub struct BodyQuery {
    /// The answer: separate, contacts, or intersecting.
    pub manifold: Manifold,
    /// Leaf pairs the tree descent handed to the solver.
    pub leaf_pairs: Vec<(u32, u32)>,
    /// Box tests and leaf pairs of the tree descent.
    pub counters: TraversalCounters,
    /// What the searches of this query proved, one entry per leaf pair, sorted by segments:
    /// the [`Coherence`] memory of the pair's next query.
    pub memory: Vec<LeafMemory>,
    workspace: TraversalWorkspace,
    /// The leaf pairs of the last descent, within `front_reach` (see [`LeafFront`]).
    front_pairs: Vec<(u32, u32)>,
    /// B's pose in A's frame at that descent.
    front_relative: Pose,
    /// Its margin; NaN before the first descent.
    front_reach: f64,
}

impl Default for BodyQuery {
    fn default() -> Self {
        Self {
            manifold: Manifold::default(),
            leaf_pairs: Vec::new(),
            counters: TraversalCounters::default(),
            memory: Vec::new(),
            workspace: TraversalWorkspace::default(),
            front_pairs: Vec::new(),
            front_relative: Pose::IDENTITY,
            front_reach: f64::NAN,
        }
    }
}

/// The body-pair query: two bodies at two poses → intersecting, a list of contacts, or separate.
///
/// Descends both AOBB trees and classifies the leaf
/// pairs whose boxes overlap with the curve-pair solver.
#[allow(clippy::too_many_arguments)]
pub fn query_bodies<'q>(
    a: &BodyShape<'_>,
    tree_a: &AobbTree,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    tree_b: &AobbTree,
    pose_b: &Pose,
    settings: &QuerySettings,
    query: &'q mut BodyQuery,
) -> &'q Manifold {
    query_bodies_within(a, tree_a, pose_a, b, tree_b, pose_b, 0.0, Coherence::OFF, settings, query)
}

/// As [`query_bodies`], also examining leaf pairs up to `margin` apart so that
/// [`Manifold::gaps`] bound how far the bodies may close (conservative advancement), and
/// answering from `coherence` the leaf pairs that have moved little since they were searched.
/// [`BodyQuery::memory`] then holds the memory of the next query. With a positive `margin`, a
/// separate leaf pair whose clearance (its distance less the combined band) is at least `margin`
/// is left out of the gaps, as the leaf pairs beyond the margin are: motions within the margin
/// cannot close it.
#[allow(clippy::too_many_arguments)]
pub fn query_bodies_within<'q>(
    a: &BodyShape<'_>,
    tree_a: &AobbTree,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    tree_b: &AobbTree,
    pose_b: &Pose,
    margin: f64,
    coherence: Coherence<'_>,
    settings: &QuerySettings,
    query: &'q mut BodyQuery,
) -> &'q Manifold {
    // The leaf pairs within the margin: those of the front that pass the leaf test, the front
    // being last query's while it covers the motion since, else a new descent with room to move
    // ([`FRONT_ROOM`] times the trees' floors). Without coherence there is no
    // next query to keep a front for: the descent lists the leaf pairs itself.
    if coherence.tolerance > 0.0 {
        leaf_pairs_from_front(tree_a, pose_a, tree_b, pose_b, margin, coherence.front, query);
    } else {
        query.front_reach = f64::NAN;
        let (workspace, leaf_pairs) = (&mut query.workspace, &mut query.leaf_pairs);
        query.counters = tree_a.overlapping_leaves_within(pose_a, tree_b, pose_b, margin, workspace, leaf_pairs);
    }
    // Leaf pairs beyond the band cost one hull test, whose gap bounds their distance well enough
    // for the sub-step; searching their exact distance up to the margin would cost far more.
    let (leaf_pairs, memory) = (&query.leaf_pairs, &mut query.memory);
    let floors = (tree_a.floor(), tree_b.floor());
    let out = &mut query.manifold;
    let gap_limit = if margin > 0.0 { margin } else { f64::INFINITY };
    let memory = Some(memory);
    classify_leaf_pairs(a, pose_a, b, pose_b, leaf_pairs, floors, coherence, settings, out, memory, gap_limit);
    query.memory.sort_unstable_by_key(|m| (m.segment_a, m.segment_b));
    &query.manifold
}

/// The leaf pairs within `margin` into `query.leaf_pairs`, by the leaf test on `front` where it
/// covers the motion since its descent, else on a new descent with the trees' floors as extra
/// reach, which becomes the query's front (see [`LeafFront`]).
fn leaf_pairs_from_front(
    tree_a: &AobbTree,
    pose_a: &Pose,
    tree_b: &AobbTree,
    pose_b: &Pose,
    margin: f64,
    front: Option<LeafFront<'_>>,
    query: &mut BodyQuery,
) {
    let relative = pose_a.relative(pose_b);
    let kept = front.filter(|front| front.covers(&relative, tree_b.reach(), margin));
    query.counters = match kept {
        Some(front) => {
            query.front_pairs.clear();
            query.front_pairs.extend_from_slice(front.leaf_pairs);
            (query.front_relative, query.front_reach) = (front.relative, front.reach);
            TraversalCounters::default()
        }
        None => {
            let reach = margin + FRONT_ROOM * (tree_a.floor() + tree_b.floor());
            (query.front_relative, query.front_reach) = (relative, reach);
            let (workspace, front) = (&mut query.workspace, &mut query.front_pairs);
            tree_a.overlapping_leaves_within(pose_a, tree_b, pose_b, reach, workspace, front)
        }
    };
    query.counters.box_tests +=
        tree_a.leaf_pairs_within(pose_a, tree_b, pose_b, margin, &query.front_pairs, &mut query.leaf_pairs);
    query.counters.leaf_pairs = query.leaf_pairs.len();
    #[cfg(debug_assertions)]
    if kept.is_some() {
        // Every leaf pair a descent finds now is among those the kept front gave.
        let (workspace, found) = (&mut query.workspace, &query.leaf_pairs);
        tree_a.visit_leaves_within(pose_a, tree_b, pose_b, margin, workspace, |pair| {
            assert!(found.binary_search(&pair).is_ok(), "leaf pair {pair:?} is missing from the kept front");
        });
    }
}

/// How much farther than its margin a new descent lists the leaf pairs of the front, in
/// multiples of the two trees' floors (the least band each tree's boxes were fattened with, so
/// the room scales with the bodies): the front then spares the descents until the bodies have
/// moved that far relative to each other. A wider front lasts more sub-steps and costs more to
/// filter at each. The landing pile of 100 blobs (bands of 2 mm, steps 61–70) took 36.9 M
/// instructions a step with 1, 36.2 M with 2, 35.3 M with 4, 34.7 M with 8 and 16 and 36.0 M with
/// 32 (docs/performance.md, "Where a landing pile's narrow phase goes"); the same leaf pairs and
/// bits with any.
const FRONT_ROOM: f64 = 8.0;

/// Every `(segment of A, segment of B)` pair: the trivial candidate generator.
pub fn all_segment_pairs(segments_a: usize, segments_b: usize, out: &mut Vec<(u32, u32)>) {
    out.clear();
    out.extend((0..segments_a as u32).flat_map(|i| (0..segments_b as u32).map(move |j| (i, j))));
}
