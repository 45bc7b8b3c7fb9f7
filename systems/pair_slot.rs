//! A candidate pair's slot: its narrow-phase result and the memory that produced it, how far
//! its bodies have moved since ([`Drift`]) and where they were ([`SolvedAt`]).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::{BodyRecord, BoundFloor, least};
use crate::components::RigidState;
use crate::geometry::aobb_tree::TraversalCounters;
use crate::geometry::overlap::RecoveryContact;
use crate::geometry::pose::Pose;
use crate::geometry::query::{BodyQuery, Manifold, PairState, QueryCapacity};

/// Per candidate pair: the narrow-phase result and the scratch memory that produced it.
#[derive(Debug, Default)]
pub struct PairSlot {
    /// Body slots `(a, b)` with `a < b`.
    pub bodies: (u32, u32),
    /// Contacts or intersections of the pair, a lower bound on its gap, and the tree-descent
    /// counters and scratch.
    pub query: BodyQuery,
    /// For a pair whose curves cross: the contact that pushes them apart.
    pub recovery: Option<RecoveryContact>,
    /// Whether one of the bodies is a sensor (or the contact hook ignores the pair this
    /// sub-step): the pair is detected (touch events) but never collides, never bounds the
    /// sub-step and never joins an island.
    pub sensor: bool,
    /// For a sensor pair: one body lies inside the other with no curves meeting.
    pub contained: bool,
    /// Friction and restitution the contact hook set for this sub-step (`None`: the materials').
    pub modified: (Option<f64>, Option<f64>),
    /// Where the bodies were when the manifold was last computed by a query (`None` before
    /// the first): a separate pair is carried from it while they have moved little (§3b).
    pub solved_at: Option<SolvedAt>,
    /// How far the bodies have moved since `solved_at` (zero when the manifold was computed at
    /// the current poses).
    pub drift: Drift,
    /// Whether the last narrow phase carried the pair instead of querying it (§3b).
    pub carried: bool,
    /// B's angle (rad) when the manifold's contacts were last evaluated, by a query or by
    /// reusing them (§3b): their normals turn with B from there. `None` where unknown (a
    /// snapshot written before it was recorded), which refuses the reuse.
    pub evaluated_angle_b: Option<f64>,
    /// The bodies' positions and angles when its contacts were last evaluated again by a
    /// reuse (`None` after a query): while the bodies have moved by at most a thousandth of what
    /// the solver resolves since, the contacts are not evaluated again (§3b).
    pub reused_at: Option<[(DVec2, f64); 2]>,
    /// Where the manifold's contacts as the solver takes them (each flat patch reduced to its
    /// two ends, `prepare_contacts::reduced_touches`; they depend on the manifold, the recovery
    /// contact, the pair's bodies and `min_band`) lie in the touch store of the last contact
    /// preparation. `None` where the manifold or recovery contact has changed since (a query,
    /// its contacts evaluated again, [`PairSlot::clear`]), and stale where the slot was not
    /// prepared last time (an older store's generation), so a carried pair is not reduced again
    /// at every sub-step.
    pub(crate) touches: Option<TouchRange>,
    /// The crossing check's last pass over the leaf memory (`narrow_phase::Carry::uncrossed`):
    /// A's pose in B's frame then, and the least of the memories' bounds less their motion.
    /// Valid while the leaf memory is: a query forgets it.
    pub(crate) crossing: Option<(Pose, f64)>,
    /// For a pair carried in a phase where every body had barely moved: the largest drift gap
    /// at which it is carried again as it is (`narrow_phase::still`); `None` otherwise.
    pub(crate) drift_budget: Option<f64>,
}

/// How far a carried pair's bodies have moved since its query (m): conservative advancement
/// shrinks its gaps by `gap` and grows its pieces' discs by `a` and `b` (docs/model.md §3b).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drift {
    /// How far any point of A (band included) has moved in the world.
    pub a: f64,
    /// How far any point of B (band included) has moved in the world.
    pub b: f64,
    /// How much the distance between any point of A and any point of B has changed: the
    /// smaller of `a + b` and A's motion in B's frame.
    pub gap: f64,
}

impl Drift {
    /// Whether every number is finite and not negative.
    #[must_use]
    pub fn is_sound(&self) -> bool {
        [self.a, self.b, self.gap].iter().all(|v| v.is_finite() && *v >= 0.0)
    }
}

/// A pair's touches in the step's touch store (`StepBuffers::touch_store`): `len` of them from
/// `start`, written when the store's generation was `generation` (a range of an older store is
/// stale).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TouchRange {
    pub(crate) start: u32,
    pub(crate) len: u32,
    pub(crate) generation: u64,
}

/// The poses of a pair's bodies, and the query margin, when its manifold was computed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolvedAt {
    /// A's pose.
    pub pose_a: Pose,
    /// B's pose.
    pub pose_b: Pose,
    /// A's angle (rad, as the state has it: turns are counted).
    pub angle_a: f64,
    /// B's angle (rad).
    pub angle_b: f64,
    /// The query margin then: leaf pairs not in the manifold's gaps were farther apart (m).
    pub margin: f64,
}

impl SolvedAt {
    /// The record for bodies at `states` (poses `poses`) queried with `margin`.
    #[must_use]
    pub fn new((state_a, state_b): (&RigidState, &RigidState), (pose_a, pose_b): (&Pose, &Pose), margin: f64) -> Self {
        Self { pose_a: *pose_a, pose_b: *pose_b, angle_a: state_a.angle, angle_b: state_b.angle, margin }
    }

    /// Whether every number is finite and the margin is not negative.
    #[must_use]
    pub fn is_sound(&self) -> bool {
        self.pose_a.is_finite()
            && self.pose_b.is_finite()
            && self.angle_a.is_finite()
            && self.angle_b.is_finite()
            && self.margin.is_finite()
            && self.margin >= 0.0
    }

    /// How far the bodies at `states` (poses `poses`) have moved since (radii `ρ_A`, `ρ_B` about
    /// the centres of mass): each point of a body by at most `|Δx| + |Δθ| ρ` in the world, and
    /// each point of A in B's frame by at most `|Δx_rel| + |Δr_rel| ρ_A`, where `x_rel` and the
    /// rotation vector `r_rel` are A's pose in B's frame (a turn by `Δ` moves a point at `ρ` by
    /// exactly `ρ |Δr|`; a still pair that moves as one moves nothing in it). `now` is A's pose
    /// in B's frame at `poses` (`pose_b.relative(pose_a)`, which the caller has at hand).
    #[must_use]
    #[inline]
    pub fn drift(
        &self,
        (state_a, state_b): (&RigidState, &RigidState),
        (pose_a, pose_b): (&Pose, &Pose),
        now: &Pose,
        (rho_a, rho_b): (f64, f64),
    ) -> Drift {
        let a = self.pose_a.position.distance(pose_a.position) + (state_a.angle - self.angle_a).abs() * rho_a;
        let b = self.pose_b.position.distance(pose_b.position) + (state_b.angle - self.angle_b).abs() * rho_b;
        let then = self.pose_b.relative(&self.pose_a);
        let relative = then.position.distance(now.position) + then.rotation.distance(now.rotation) * rho_a;
        Drift { a, b, gap: relative.min(a + b) }
    }
}

impl PairSlot {
    /// An empty slot whose buffers hold `capacity`.
    pub(crate) fn with_capacity(capacity: QueryCapacity) -> Self {
        let mut slot = Self::default();
        slot.query.reserve(capacity);
        slot
    }

    /// The least gap, less its drift, by which the pair bounds the sub-step
    /// (`integrate::pair_substep`): its listed gaps' and its query margin's, ∞ with neither,
    /// NaN if any is.
    pub(crate) fn nearest_gap(&self) -> f64 {
        let margin = self.solved_at.map_or(f64::INFINITY, |solved_at| solved_at.margin);
        self.query.manifold.gaps.iter().fold(margin, |nearest, leaf| least(nearest, leaf.gap)) - self.drift.gap
    }

    /// The least gap by which the pair bounds the sub-step ([`PairSlot::nearest_gap`]), ∞ for
    /// a sensor pair (it bounds nothing).
    pub(crate) fn bounding_gap(&self) -> f64 {
        if self.sensor { f64::INFINITY } else { self.nearest_gap() }
    }

    /// The pair's entry in the sub-step bound's dense list ([`BoundFloor`]), from its
    /// [`PairSlot::bounding_gap`] `gap`.
    pub(crate) fn bound_floor(&self, gap: f64) -> BoundFloor {
        let single = !self.sensor && self.query.manifold.gaps.len() == 1;
        BoundFloor {
            bodies: self.bodies,
            floor: if single { f64::NEG_INFINITY } else { gap },
            touching: self.touching(),
        }
    }

    /// Forgets its touches: the manifold is about to change.
    pub(crate) fn manifold_changed(&mut self) {
        self.touches = None;
    }

    /// The pair's contacts, intersections and gap.
    #[must_use]
    pub fn manifold(&self) -> &Manifold {
        &self.query.manifold
    }

    /// Whether the pair intersects (the sub-step must be retried). Never for a sensor pair:
    /// sensors pass through.
    #[must_use]
    pub fn intersecting(&self) -> bool {
        !self.sensor && self.query.manifold.state == PairState::Intersecting
    }

    /// The pair's two body slots `(a, b)`, as indices into the step's body arrays.
    #[must_use]
    #[inline]
    pub(crate) fn body_indices(&self) -> (usize, usize) {
        (self.bodies.0 as usize, self.bodies.1 as usize)
    }

    /// Whether the pair's contacts are resolved: not a sensor pair, and not two bodies of
    /// infinite mass (a kinematic body on a sleeping one is tested only to wake it).
    #[must_use]
    pub fn solvable(&self, bodies: &[BodyRecord]) -> bool {
        let both_fixed = bodies[self.bodies.0 as usize].is_static && bodies[self.bodies.1 as usize].is_static;
        !(self.sensor || both_fixed)
    }

    /// Whether the pair touches and takes part in the dynamics (not a sensor pair).
    #[must_use]
    pub fn colliding(&self) -> bool {
        !self.sensor && self.touching()
    }

    /// Whether the pair touches: contacts within the band, crossing curves, or (for a sensor
    /// pair) one body inside the other.
    #[must_use]
    pub fn touching(&self) -> bool {
        !self.query.manifold.contacts.is_empty() || self.recovery.is_some() || self.contained
    }

    /// Becomes `previous`, a separate pair or one whose contacts are reused, carried to the
    /// current poses (its bodies moved by `drift` since it was computed): takes its manifold,
    /// leaf memory and front by swapping buffers with it ([`BodyQuery::take_answer_from`]), and
    /// its record (`previous` is left with this slot's old buffers, which nothing reads). The
    /// query's leaf pairs and counters, which [`PairSlot::keep_carried`] clears, and its scratch
    /// stay where they are.
    pub(crate) fn take_carried(&mut self, previous: &mut PairSlot, drift: Drift) {
        self.query.take_answer_from(&mut previous.query);
        self.touches = previous.touches.take();
        self.solved_at = previous.solved_at;
        self.evaluated_angle_b = previous.evaluated_angle_b;
        self.reused_at = previous.reused_at;
        self.crossing = previous.crossing;
        self.keep_carried(drift);
    }

    /// Carries this slot's own manifold, leaf memory and record to the current poses (its
    /// bodies moved by `drift` since it was computed), where they are.
    pub(crate) fn keep_carried(&mut self, drift: Drift) {
        self.query.manifold.newton_iterations = 0;
        self.query.manifold.recalled_leaf_pairs = 0;
        self.query.leaf_pairs.clear();
        self.query.counters = TraversalCounters::default();
        self.recovery = None;
        self.contained = false;
        self.drift = drift;
        self.carried = true;
    }

    /// Forgets the result and the memory of its searches (keeps the buffers).
    pub fn clear(&mut self) {
        self.manifold_changed();
        self.solved_at = None;
        self.drift = Drift::default();
        self.carried = false;
        self.evaluated_angle_b = None;
        self.reused_at = None;
        self.crossing = None;
        self.drift_budget = None;
        self.recovery = None;
        self.contained = false;
        self.modified = (None, None);
        self.query.manifold.clear();
        self.query.leaf_pairs.clear();
        self.query.memory.clear();
        self.query.counters = TraversalCounters::default();
    }
}
