//! What a body-pair query answers: its contacts, intersections and the gaps of its separate
//! leaf pairs ([`Manifold`]).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::{BodyContact, PairState, PlacedLeaf};
use crate::geometry::curve_pair::{SEPARATING_AXES, gap_along, hull_axes, nearest_separating_axis, separating_axes};
use crate::geometry::segment::CubicSegment;

/// An intersecting leaf pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentIntersection {
    /// Segment of A.
    pub segment_a: u32,
    /// Segment of B.
    pub segment_b: u32,
    /// Parameter on A's segment where the curves meet.
    pub t: f64,
    /// Parameter on B's segment where the curves meet.
    pub s: f64,
}

/// Result of a body-pair query; owns its buffers so that repeated queries do not allocate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifold {
    /// Separate, contact or intersecting.
    pub state: PairState,
    /// Contacts, in candidate order, each reported once.
    pub contacts: Vec<BodyContact>,
    /// Intersecting leaf pairs, in candidate order (empty unless `state` is intersecting).
    pub intersections: Vec<SegmentIntersection>,
    /// Newton iterations spent by the leaf solver.
    pub newton_iterations: u64,
    /// Leaf pairs answered from the pair's memory instead of a search (temporal coherence).
    pub recalled_leaf_pairs: u64,
    /// Per candidate leaf pair that is not in contact: a lower bound on how far it may close
    /// before it is `approach_depth` into the band ([`QuerySettings::approach_depth`](super::QuerySettings::approach_depth)), with
    /// where its two pieces are, so that conservative advancement can use the relative velocity
    /// of the pieces rather than of the whole bodies.
    pub gaps: Vec<LeafGap>,
}

/// How far one separate leaf pair may close, and the discs (in the world) that hold its pieces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeafGap {
    /// Lower bound on `distance − approach` for the two pieces.
    pub gap: f64,
    /// Centre of a disc holding A's piece.
    pub centre_a: DVec2,
    /// Radius of that disc.
    pub radius_a: f64,
    /// Centre of a disc holding B's piece.
    pub centre_b: DVec2,
    /// Radius of that disc.
    pub radius_b: f64,
    /// A's piece, in the world.
    pub piece_a: CubicSegment,
    /// B's piece, in the world.
    pub piece_b: CubicSegment,
    /// The distance at which conservative advancement stops the pieces,
    /// `(1 − approach_depth)(λ_A + λ_B)` with the maxima of the pieces' tolerances (named
    /// `half_band` in older snapshots, when it was always half the band).
    #[serde(alias = "half_band")]
    pub approach: f64,
    /// The combined band `λ_A + λ_B` with the maxima of the pieces' tolerances (NaN when read
    /// from a snapshot older than it: the pair's clearance is then unknown and it is not
    /// carried until its next query).
    #[serde(default = "unknown_band")]
    pub band: f64,
}

/// The band of a leaf gap read from an older snapshot ([`LeafGap::band`]).
fn unknown_band() -> f64 {
    f64::NAN
}

impl LeafGap {
    pub(super) fn new((gap, approach, band): (f64, f64, f64), a: &PlacedLeaf, b: &PlacedLeaf) -> Self {
        let ((centre_a, radius_a), (centre_b, radius_b)) = (a.disc, b.disc);
        let (piece_a, piece_b) = (a.leaf.segment, b.leaf.segment);
        Self { gap, centre_a, radius_a, centre_b, radius_b, piece_a, piece_b, approach, band }
    }

    /// Fixed world axes (unit) with the pieces' gap along each less the approach (at most the
    /// distance less the approach; meaningful only when positive). A gap along a fixed axis
    /// closes only as fast as the relative velocity along that axis. Computed on demand: only
    /// pairs that would otherwise shorten a sub-step need it.
    #[must_use]
    pub fn axis_gaps(&self) -> [(DVec2, f64); SEPARATING_AXES] {
        separating_axes(&self.piece_a, &self.piece_b).map(|(axis, gap)| (axis, gap - self.approach))
    }

    /// The first five of [`LeafGap::axis_gaps`] (the hull test's axes, without Newton), each
    /// worked out as it is read, so that a caller looking for one that allows its sub-step
    /// stops at it: the chord normals first (pieces facing each other are apart along them
    /// most often: 0.2 % fewer instructions in a landing pile than the hull's own order), then
    /// the centre line and the coordinate axes.
    pub(crate) fn hull_axis_gaps(&self) -> impl Iterator<Item = (DVec2, f64)> + '_ {
        let gap = move |axis| {
            let (axis, gap) = gap_along(&self.piece_a, &self.piece_b, axis);
            (axis, gap - self.approach)
        };
        let [c, na, nb, x, y] = hull_axes(&self.piece_a, &self.piece_b);
        [na, nb, c, x, y].into_iter().map(gap)
    }

    /// The last of [`LeafGap::axis_gaps`]: towards the pieces' nearest points.
    pub(crate) fn nearest_axis_gap(&self) -> (DVec2, f64) {
        let (axis, gap) = nearest_separating_axis(&self.piece_a, &self.piece_b);
        (axis, gap - self.approach)
    }
}

impl Default for Manifold {
    fn default() -> Self {
        Self {
            state: PairState::Separate,
            contacts: Vec::new(),
            intersections: Vec::new(),
            newton_iterations: 0,
            recalled_leaf_pairs: 0,
            gaps: Vec::new(),
        }
    }
}

impl Manifold {
    /// Lists a separate leaf pair whose distance is at least `lower_bound`, if its clearance
    /// `lower_bound − (λ_A + λ_B)` is within `gap_limit`, with its gap `lower_bound − approach`
    /// (`approach = (1 − depth)(λ_A + λ_B)`, `depth` the approach depth).
    pub(super) fn push_gap(
        &mut self,
        lower_bound: f64,
        (a, b): (&PlacedLeaf, &PlacedLeaf),
        (gap_limit, depth): (f64, f64),
    ) {
        let band = a.leaf.tolerance.max + b.leaf.tolerance.max;
        if lower_bound - band < gap_limit {
            let approach = (1.0 - depth.clamp(0.0, 1.0)) * band;
            self.gaps.push(LeafGap::new((lower_bound - approach, approach, band), a, b));
        }
    }

    /// The smallest clearance of its separate leaf pairs, their gap less what the band holds
    /// beyond the approach, which is at most their distance less the combined band (`∞` with no
    /// gaps, NaN where a gap's band is unknown).
    #[must_use]
    pub fn clearance(&self) -> f64 {
        self.gaps.iter().map(|leaf| leaf.gap - (leaf.band - leaf.approach)).fold(f64::INFINITY, crate::geometry::least)
    }

    /// Empties the manifold, keeping its buffers.
    pub fn clear(&mut self) {
        self.state = PairState::Separate;
        self.contacts.clear();
        self.intersections.clear();
        self.newton_iterations = 0;
        self.recalled_leaf_pairs = 0;
        self.gaps.clear();
    }
}
