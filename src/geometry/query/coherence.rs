//! A pair's memory of its leaf pairs' last searches and of its last tree descent, and when a
//! leaf pair is answered from it instead of searched (temporal coherence, docs/model.md §3a).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::curve_pair::{
    ContactPoints, CurvePairSettings, Orientation, Recalled, SegmentPairQuery, SegmentPairState, TolerancedSegment,
    pair_scale, query_segment_segment_recalled,
};
use crate::geometry::pose::Pose;

/// What the last full search of one leaf pair proved (temporal coherence, docs/model.md §3a).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeafMemory {
    /// Segment of A.
    pub segment_a: u32,
    /// Segment of B.
    pub segment_b: u32,
    /// A's pose in B's frame at the search.
    pub relative: Pose,
    /// Lower bound on the pieces' distance then (their distance, when it was within the band).
    pub lower_bound: f64,
    /// The nearest parameters `(t, s)` when they were within the band: the search's, then those
    /// of each answer from this memory (where the next one's Newton starts).
    pub seed: Option<[f64; 2]>,
    /// Whether the pieces were in conformal contact then (the two ends of an overlap).
    pub conformal: bool,
}

/// A body pair's memory of its last full searches, and how far it may be trusted.
#[derive(Clone, Copy, Debug)]
pub struct Coherence<'m> {
    /// One entry per leaf pair searched, sorted by `(segment_a, segment_b)`.
    pub memory: &'m [LeafMemory],
    /// How far (as a fraction of a leaf pair's combined band) its pieces may move relative to
    /// each other before it is searched again; 0 searches every time.
    pub tolerance: f64,
    /// The leaf pairs of the pair's last tree descent ([`BodyQuery::front`](super::BodyQuery::front)), which spare the
    /// descent while the bodies have moved less than its extra reach.
    pub front: Option<LeafFront<'m>>,
}

impl Coherence<'static> {
    /// No memory: every leaf pair is searched, the trees descended.
    pub const OFF: Self = Self { memory: &[], tolerance: 0.0, front: None };
}

/// The leaf pairs a tree descent found within a reach wider than the query's margin, and the
/// bodies' relative pose then (docs/model.md §3a). A leaf pair whose boxes come within `m` of
/// each other now came within `m + δ` at the descent, if no point of B has moved by more than
/// `δ` in A's frame since: so while `m + δ` stays within the reach, the leaf pairs within the
/// margin are those of the front that pass the leaf test now — the same pairs the descent
/// would give, found without it.
#[derive(Clone, Copy, Debug)]
pub struct LeafFront<'m> {
    /// Leaf pairs within `reach`, sorted.
    pub leaf_pairs: &'m [(u32, u32)],
    /// B's pose in A's frame at the descent.
    pub relative: Pose,
    /// The margin of the descent (m).
    pub reach: f64,
}

impl LeafFront<'_> {
    /// Whether every leaf pair within `margin` at the relative pose `relative` is in the front:
    /// `margin` plus how far any point of B (at most `reach_b` from its origin) has moved in A's
    /// frame stays within the front's reach, with a relative allowance for the rounding of the
    /// box tests. Written so that a NaN refuses the front.
    pub(super) fn covers(&self, relative: &Pose, reach_b: f64, margin: f64) -> bool {
        let moved = self.relative.position.distance(relative.position)
            + self.relative.rotation.distance(relative.rotation) * reach_b;
        let rounding = 1e-9 * (reach_b + relative.position.abs().max_element());
        margin + moved + rounding <= self.reach
    }
}

impl<'m> Coherence<'m> {
    /// The memory of leaf pair `(i, j)`, if it was searched last time and memory is on.
    /// `cursor` carries what the last look-up of the same query learnt: the candidates come
    /// sorted, as the memory is, so each look-up walks on from where the last one stopped
    /// instead of searching the whole memory (a binary search per leaf pair, and the entry
    /// copied out, cost the landing pile of 100 blobs 0.12 M of its 24.2 M instructions a step).
    /// Candidates out of order are searched for; the memory holds each leaf pair at most once,
    /// so either way finds the same entry.
    pub(super) fn remembered(&self, (i, j): (u32, u32), cursor: &mut MemoryCursor) -> Option<&'m LeafMemory> {
        if self.tolerance <= 0.0 {
            return None;
        }
        let memory = self.memory;
        let key = leaf_key(i, j);
        // Every entry before the cursor is below the last key looked up: below this one too
        // while the keys ascend.
        let mut at = if key > cursor.last {
            cursor.next
        } else {
            memory.partition_point(|m| leaf_key(m.segment_a, m.segment_b) < key)
        };
        while memory.get(at).is_some_and(|m| leaf_key(m.segment_a, m.segment_b) < key) {
            at += 1;
        }
        *cursor = MemoryCursor { last: key, next: at };
        memory.get(at).filter(|m| leaf_key(m.segment_a, m.segment_b) == key)
    }

    /// The answer for a leaf pair from its memory, when the pieces have moved little enough
    /// since it was searched: `None` where a search is needed. Moving by `δ` changes the
    /// distance at every parameter pair by at most `δ`, so the distance over the square is
    /// still at least `lower_bound − δ`: while that exceeds the intersection tolerance the
    /// pieces cannot cross; a pair then separate beyond its band stays separate, and a contact
    /// is found again by Newton from the last answer's parameters, at most `2δ` above the true
    /// minimum (the memory keeps the search's pose and bound; each answer renews the parameters).
    /// A pair proven apart needs no trust radius: it stays apart while it keeps half its
    /// clearance beyond the band.
    pub(super) fn recall(
        &self,
        memory: &LeafMemory,
        relative: &Pose,
        reach_a: f64,
        (a, b): (&TolerancedSegment, &TolerancedSegment),
        orientation_b: Orientation,
        settings: &CurvePairSettings,
    ) -> Option<(SegmentPairQuery, LeafMemory)> {
        let cutoff = a.tolerance.max + b.tolerance.max;
        let moved = memory.relative.position.distance(relative.position)
            + memory.relative.rotation.distance(relative.rotation) * reach_a;
        // A pair proven apart stays apart, with a gap that shrinks by the motion, for as long as
        // it keeps half its clearance beyond the band; any other memory within the trust radius.
        // Written so that a NaN anywhere refuses the memory.
        let apart = memory.seed.is_none() && moved <= 0.5 * (memory.lower_bound - cutoff);
        let trusted = apart || moved <= self.tolerance * cutoff;
        let bound = memory.lower_bound - moved;
        if !trusted || bound.is_nan() || bound <= settings.intersection_tolerance * pair_scale(&a.segment, &b.segment) {
            return None;
        }
        let query = match memory.seed.map(DVec2::from) {
            Some(seed) => {
                let recalled = Recalled { seed, lower_bound: bound, ceiling: memory.lower_bound + moved };
                let query = query_segment_segment_recalled(a, b, orientation_b, settings, recalled, memory.conformal)?;
                let seed = query.closest.map(|c| [c.t, c.s]);
                return Some((query, LeafMemory { seed, ..*memory }));
            }
            None if bound > cutoff => SegmentPairQuery {
                state: SegmentPairState::Separate,
                contacts: ContactPoints::default(),
                closest: None,
                newton_iterations: 0,
                distance_lower_bound: bound,
            },
            None => return None,
        };
        Some((query, *memory))
    }
}

/// Where [`Coherence::remembered`] goes on looking in a query's memory: the last key looked
/// up, and the first entry not below it.
#[derive(Clone, Copy, Debug)]
pub(super) struct MemoryCursor {
    last: u64,
    next: usize,
}

impl MemoryCursor {
    /// Before a query's first look-up.
    pub(super) const START: Self = Self { last: 0, next: 0 };
}

/// A leaf pair's key, ordered as `(segment_a, segment_b)`.
fn leaf_key(i: u32, j: u32) -> u64 {
    (u64::from(i) << 32) | u64::from(j)
}

/// The memory of a full search of leaf pair `(i, j)` at relative pose `relative`.
pub(super) fn remember(i: u32, j: u32, relative: Pose, query: &SegmentPairQuery, cutoff: f64) -> LeafMemory {
    let seed = match query.state {
        SegmentPairState::Intersecting { .. } => None,
        _ => query.closest.filter(|c| c.distance <= cutoff).map(|c| [c.t, c.s]),
    };
    let conformal = query.state == SegmentPairState::Contact && query.contacts.as_slice().len() == 2;
    LeafMemory { segment_a: i, segment_b: j, relative, lower_bound: query.distance_lower_bound, seed, conformal }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    /// The cursor finds what a binary search finds, for candidates in order, out of order and
    /// missing from the memory.
    #[test]
    fn remembered_is_the_binary_search() {
        let entry = |segment_a, segment_b| LeafMemory {
            segment_a,
            segment_b,
            relative: Pose::IDENTITY,
            lower_bound: f64::from(segment_a * 100 + segment_b),
            seed: None,
            conformal: false,
        };
        let memory: Vec<LeafMemory> = (0..12u32)
            .flat_map(|i| (0..12u32).filter(move |j| (i * 7 + j * 3) % 4 != 0).map(move |j| entry(i, j)))
            .collect();
        let coherence = Coherence { memory: &memory, tolerance: 1e-3, front: None };
        let mut rng = crate::random::seeded(12345);
        for run in 0..200 {
            let mut candidates: Vec<(u32, u32)> =
                (0..30).map(|_| (rng.random_range(0..13), rng.random_range(0..13))).collect();
            if run % 2 == 0 {
                candidates.sort_unstable();
                candidates.dedup();
            }
            let mut cursor = MemoryCursor::START;
            for &(i, j) in &candidates {
                let searched =
                    memory.binary_search_by_key(&(i, j), |m| (m.segment_a, m.segment_b)).ok().map(|k| &memory[k]);
                assert_eq!(coherence.remembered((i, j), &mut cursor), searched, "{candidates:?} at {:?}", (i, j));
            }
        }
    }
}
