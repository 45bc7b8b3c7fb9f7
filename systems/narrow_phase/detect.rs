//! One candidate pair's detection ([`PairJob::detect`]): its query margin, the query (or a
//! carried pair's contacts reused and evaluated again), its overlap recovery and containment.

use glam::DVec2;
use hecs::PreparedView;

use crate::components::RigidState;
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::curve_pair::contact_moved;
use crate::geometry::overlap::{Containment, containment_recovery, overlap_recovery};
use crate::geometry::pose::Pose;
use crate::geometry::query::{BodyShape, Coherence, PairState, QuerySettings, query_bodies_within};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;
use crate::systems::{BodyMotion, BodyRecord, Drift, PairSlot, SolvedAt, closing_bound};

/// A pair's query margin covers this many horizons of the bodies' relative motion: a quarter
/// more than one, so that a pair moving steadily is not cut short by the rounding of its own
/// bound. Over 120 steps of the landing pile of 100 blobs, 2 (the refit's factor) cost 47.5 M
/// instructions a step, 1.25 cost 43.4 M and 1 cost 43.1 M; the sum of the bodies' own
/// margins, 52.1 M (a scratch count, docs/performance.md).
const PAIR_MARGIN_FACTOR: f64 = 1.25;

/// A reused contact is evaluated again once its bodies have moved by more than this fraction
/// of what the solver resolves (its tolerance times the contact's combined band): a still
/// structure's contacts are otherwise evaluated again at every sub-step for motions of 1e-18 m
/// (docs/model.md §3b, docs/performance.md).
const STALE_FRACTION: f64 = 1e-3;

/// Read-only inputs shared by the parallel pair tasks.
pub(super) struct PairJob<'a> {
    /// Each body's curve, tolerances and tree, by entity.
    pub(super) geometry: PreparedView<'a, (&'static Spline, &'static Rugosity, &'static AobbTree)>,
    pub(super) bodies: &'a [BodyRecord],
    pub(super) states: &'a [RigidState],
    /// Per body: its pose (from `states`).
    pub(super) poses: &'a [Pose],
    /// Per body: what the closing bound reads ([`body_motions`](crate::systems::body_motions)).
    pub(super) motions: &'a [BodyMotion],
    /// Each body's refit margin.
    pub(super) margins: &'a [f64],
    /// The time the margins cover: what is left of the step, or after its last sub-step the
    /// next ([`margin_horizon`](crate::systems::margin_horizon)), as for the carry.
    pub(super) horizon: f64,
    /// `SimulationSettings::coherence`.
    pub(super) tolerance: f64,
    /// `SolverSettings::tolerance`.
    pub(super) solver_tolerance: f64,
    pub(super) query: QuerySettings,
}

impl PairJob<'_> {
    /// The query margin of bodies `a` and `b`: how far they can close over
    /// [`PAIR_MARGIN_FACTOR`] times the horizon (what is left of the step) at their relative
    /// motion ([`closing_bound`]), at least their combined band, and never more than the sum of
    /// their own refit margins (the query margin before). Bodies falling side by side, or resting on each other, list only
    /// the leaf pairs that could meet; conservative advancement bounds the rest by this margin
    /// (docs/model.md §7).
    pub(super) fn query_margin(&self, (a, b): (usize, usize)) -> f64 {
        let (speed, growth) = closing_bound(self.motions, (a, b));
        let h = self.horizon;
        let relative = PAIR_MARGIN_FACTOR * (speed * h + growth * h * h);
        let band = self.bodies[a].band + self.bodies[b].band;
        (self.margins[a] + self.margins[b]).min(relative.max(band))
    }

    /// Queries the pair of `slot` (reusing a carried one's contacts), answering from
    /// `previous`, its slot of the last phase, where it has one: its memory of its searches.
    pub(super) fn detect(&self, slot: &mut PairSlot, previous: Option<&PairSlot>) {
        if slot.carried {
            if !slot.manifold().contacts.is_empty() {
                self.reuse_contacts(slot);
            }
            return;
        }
        let (a, b) = slot.body_indices();
        // The slot's buffers are recycled: no record of another pair's query may survive.
        slot.manifold_changed();
        slot.solved_at = None;
        let Some([(spline_a, rugosity_a, tree_a), (spline_b, rugosity_b, tree_b)]) = self.geometry_of(slot) else {
            return;
        };
        let (pose_a, pose_b) = (&self.poses[a], &self.poses[b]);
        let margin = self.query_margin((a, b));
        let memory = previous.map_or(&[][..], |previous| previous.query.memory.as_slice());
        let front = previous.filter(|_| self.tolerance > 0.0).and_then(|previous| previous.query.front());
        let coherence = Coherence { memory, tolerance: self.tolerance, front };
        slot.solved_at = Some(SolvedAt::new((&self.states[a], &self.states[b]), (pose_a, pose_b), margin));
        slot.evaluated_angle_b = Some(self.states[b].angle);
        slot.reused_at = None;
        slot.drift = Drift::default();
        let shape_a = BodyShape::new(spline_a, rugosity_a);
        let shape_b = BodyShape::new(spline_b, rugosity_b);
        let manifold = query_bodies_within(
            &shape_a,
            tree_a,
            pose_a,
            &shape_b,
            tree_b,
            pose_b,
            margin,
            coherence,
            &self.query,
            &mut slot.query,
        );
        slot.recovery = if manifold.state == PairState::Intersecting {
            overlap_recovery(&shape_a, pose_a, &shape_b, pose_b, &manifold.intersections)
        } else {
            None
        };
        // One body inside the other with no curves meeting: a sensor touches it; any other
        // pair overlaps (intersecting, never a retry once it is so at a sub-step's start) and
        // its recovery contact pushes the inner body out.
        let separate = manifold.state == PairState::Separate && manifold.contacts.is_empty();
        let containment = if separate { self.containment(a, pose_a, spline_a, b, pose_b, spline_b) } else { None };
        slot.contained = slot.sensor && containment.is_some();
        if let Some(which) = containment.filter(|_| !slot.sensor) {
            slot.recovery = containment_recovery(&shape_a, pose_a, &shape_b, pose_b, which);
            if slot.recovery.is_some() {
                slot.query.manifold.state = PairState::Intersecting;
            }
        }
    }

    /// The curve, tolerances and tree of each body of `slot`; `None`, the slot cleared, where a
    /// body has lost them.
    pub(super) fn geometry_of(&self, slot: &mut PairSlot) -> Option<[(&Spline, &Rugosity, &AobbTree); 2]> {
        let (a, b) = slot.body_indices();
        let found = self.geometry.get(self.bodies[a].entity).zip(self.geometry.get(self.bodies[b].entity));
        if found.is_none() {
            slot.clear();
        }
        found.map(|(a, b)| [a, b])
    }

    /// A carried pair in contact (see [`Carry::drift`](super::carry::Carry::drift)): each contact evaluated again at the
    /// same parameters of its two pieces, at the bodies' poses now, its normal turned with B —
    /// unless the bodies have barely moved since the last evaluation ([`PairJob::unmoved`]),
    /// when the contacts are kept as they were.
    /// (B's outward normal at a fixed parameter is fixed in B; the two ends of a conformal
    /// overlap carry the normal of its nearest points, which turns with B the same way, or with
    /// A where the patch took A's normal: A and B turn together to within the drift limit.)
    pub(super) fn reuse_contacts(&self, slot: &mut PairSlot) {
        let (a, b) = slot.body_indices();
        let now = self.states_now(slot);
        if slot.reused_at.is_some_and(|then| self.unmoved(slot, then, now)) {
            return;
        }
        let Some([(spline_a, _, _), (spline_b, _, _)]) = self.geometry_of(slot) else {
            return;
        };
        let (pose_a, pose_b) = (&self.poses[a], &self.poses[b]);
        let angle_b = self.states[b].angle;
        let turn = DVec2::from_angle(angle_b - slot.evaluated_angle_b.unwrap_or(angle_b));
        slot.manifold_changed();
        // The pieces as `BodyShape::world_segment` places them (the bands stay the contact's),
        // each placed once for the contacts one after the other on it (a patch's two ends).
        let place =
            |spline: &Spline, segment: u32, pose: &Pose| (segment, spline.segment(segment as usize).transformed(pose));
        let (mut piece_a, mut piece_b) = (None, None);
        for found in &mut slot.query.manifold.contacts {
            let (_, on_a) = match piece_a {
                Some(placed @ (segment, _)) if segment == found.segment_a => placed,
                _ => *piece_a.insert(place(spline_a, found.segment_a, pose_a)),
            };
            let (_, on_b) = match piece_b {
                Some(placed @ (segment, _)) if segment == found.segment_b => placed,
                _ => *piece_b.insert(place(spline_b, found.segment_b, pose_b)),
            };
            let normal = turn.rotate(found.contact.normal);
            found.contact = contact_moved(&on_a, &on_b, &found.contact, normal);
        }
        slot.evaluated_angle_b = Some(angle_b);
        slot.reused_at = Some(now);
    }

    /// Whether the bodies of `slot` have moved so little since its contacts were last evaluated
    /// again (states `then`, now `now`) that evaluating them again is skipped: the most any
    /// point of A has moved plus the most any point of B has moved is at most
    /// [`STALE_FRACTION`] of the solver's tolerance times the smallest combined band of its
    /// contacts (docs/model.md §3b). Written so that a NaN refuses it.
    pub(super) fn unmoved(&self, slot: &PairSlot, then: [(DVec2, f64); 2], now: [(DVec2, f64); 2]) -> bool {
        self.moved_since(slot, then, now) <= self.stale_motion(slot)
    }

    /// The most any point of A has moved plus the most any point of B has moved from states
    /// `then` to `now` (see [`PairJob::unmoved`]).
    pub(super) fn moved_since(&self, slot: &PairSlot, then: [(DVec2, f64); 2], now: [(DVec2, f64); 2]) -> f64 {
        let (a, b) = slot.body_indices();
        let moved = |(p, angle): (DVec2, f64), (q, turned): (DVec2, f64), radius: f64| {
            p.distance(q) + (angle - turned).abs() * radius
        };
        moved(then[0], now[0], self.bodies[a].radius) + moved(then[1], now[1], self.bodies[b].radius)
    }

    /// The motion beyond which the contacts of `slot` are evaluated again ([`PairJob::unmoved`]).
    pub(super) fn stale_motion(&self, slot: &PairSlot) -> f64 {
        let band = slot.query.manifold.contacts.iter().map(|found| found.contact.lambda_a + found.contact.lambda_b);
        STALE_FRACTION * self.solver_tolerance * band.fold(f64::INFINITY, f64::min)
    }

    /// The bodies' positions and angles now (as [`PairSlot::reused_at`] records them).
    pub(super) fn states_now(&self, slot: &PairSlot) -> [(DVec2, f64); 2] {
        let (a, b) = (&self.states[slot.bodies.0 as usize], &self.states[slot.bodies.1 as usize]);
        [(a.position, a.angle), (b.position, b.angle)]
    }

    /// Whether body `a` lies inside `b` or `b` inside `a` (its world box within the other's,
    /// and a point of its curve inside the other's, by the exact winding number).
    pub(super) fn containment(
        &self,
        a: usize,
        pose_a: &Pose,
        spline_a: &Spline,
        b: usize,
        pose_b: &Pose,
        spline_b: &Spline,
    ) -> Option<Containment> {
        // Each body's world box worked out once for both tests (it was twice, once inner and
        // once outer, for every separate pair).
        let world_box = |body: usize, pose: &Pose| self.bodies[body].root_box.transformed(pose).world_aabb();
        let (box_a, box_b) = (world_box(a, pose_a), world_box(b, pose_b));
        let within = |(inner_low, inner_high): (DVec2, DVec2), (outer_low, outer_high): (DVec2, DVec2)| {
            inner_low.cmpge(outer_low).all() && inner_high.cmple(outer_high).all()
        };
        let inside = |inner: &Spline, inner_pose: &Pose, outer: &Spline, outer_pose: &Pose| {
            let point = outer_pose.inverse_transform_point(inner_pose.transform_point(inner.position(0.0)));
            outer.winding_number(point) != 0
        };
        if within(box_a, box_b) && inside(spline_a, pose_a, spline_b, pose_b) {
            Some(Containment::AInB)
        } else if within(box_b, box_a) && inside(spline_b, pose_b, spline_a, pose_a) {
            Some(Containment::BInA)
        } else {
            None
        }
    }
}
