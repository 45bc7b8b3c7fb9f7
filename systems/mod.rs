//! The step, as ordered tables of systems. Each system lives in its own file and never
//! calls another; the tables below are the only place the order exists.
//!
//! A step of length `dt` is a sequence of sub-steps chosen by conservative advancement. With
//! the iterated solver ([`ContactModel::Solver`], the default) a sub-step runs [`PREPARE`]
//! (islands and solver contacts from the last narrow phase, warm-started), then [`SOLVE`]
//! (collisions, gravity, resting contacts, position correction) and [`ADVANCE`] (move, then
//! detect at the new poses) — both redone shorter if a pair intersects. With the seed's
//! micro-collisions ([`ContactModel::SeedMicroCollisions`]) a sub-step runs [`ADVANCE`] (redone
//! shorter on intersection) and then [`RESOLVE`] (impulses at the new poses), as the seed does.
//! Parallel systems write only their own slots; everything across bodies is applied serially
//! in body and pair order, so results are bit-identical for any number of threads.

use glam::DVec2;
use hecs::{Entity, World};
use serde::{Deserialize, Serialize};

use crate::components::{
    AppliedForce, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, Sleep, SpawnOrder,
};
use crate::dynamics::impulse::{BodyVelocity, ImpulseKind};
use crate::dynamics::mass::MassProperties;
use crate::dynamics::solver::{CachedImpulse, PairVelocities, SolverContact};
use crate::events::{ContactEvent, EventKind, EventLog};
use crate::geometry::aobb_tree::{AobbTree, TraversalCounters};
use crate::geometry::obb::Obb;
use crate::geometry::octagon::Octagon;
use crate::geometry::overlap::RecoveryContact;
use crate::geometry::pose::Pose;
use crate::geometry::query::{BodyQuery, Manifold, PairState, QueryCapacity};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;
use crate::profile::{Profile, Stage};
use crate::simulation::{ContactModel, PairAction, PairContacts, SimulationSettings};

pub mod broad_phase;
pub mod collide;
pub mod contact_solver;
mod contacts;
pub mod forces;
pub mod impulse;
pub mod integrate;
mod island_solve;
pub mod islands;
pub mod micro_collision;
pub mod narrow_phase;
pub mod position_correction;
pub mod prepare_contacts;
pub mod refit;
pub mod sleep;
mod step;
#[cfg(debug_assertions)]
mod validate;

pub use step::run_step;

/// A system: one stage of the step.
pub type System = fn(&mut StepContext<'_>);

/// Move and detect: redone with a shorter sub-step when a pair intersects.
pub const ADVANCE: [(Stage, System); 4] = [
    (Stage::Integrate, integrate::run),
    (Stage::Refit, refit::run),
    (Stage::BroadPhase, broad_phase::run),
    (Stage::NarrowPhase, narrow_phase::run),
];

/// Seed model: resolve the contacts found at the accepted poses.
pub const RESOLVE: [(Stage, System); 2] =
    [(Stage::Impulse, impulse::run), (Stage::MicroCollision, micro_collision::run)];

/// Solver: once per sub-step, before the retry loop — islands, then the solver contacts of the
/// last narrow phase (the poses have not changed since).
pub const PREPARE: [(Stage, System); 2] =
    [(Stage::Islands, islands::run), (Stage::PrepareContacts, prepare_contacts::run)];

/// After the last sub-step, once per step: islands at rest fall asleep, sleeping islands an
/// awake body touches wake.
pub const FINISH: [(Stage, System); 1] = [(Stage::Sleep, sleep::run)];

/// Solver: change velocities over the sub-step; redone with [`ADVANCE`] on a retry.
pub const SOLVE: [(Stage, System); 4] = [
    (Stage::Collide, collide::run),
    (Stage::Forces, forces::run),
    (Stage::ContactSolver, contact_solver::run),
    (Stage::PositionCorrection, position_correction::run),
];

/// Cold per-body data, appended when a body is added and rebuilt when one is removed; indexed by
/// body slot.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyRecord {
    /// The hecs entity.
    pub entity: Entity,
    /// Whether the body has infinite mass and is moved by nothing in the step (static or
    /// kinematic; a sleeping body in the step's table).
    pub is_static: bool,
    /// Whether the body is kinematic: it moves at its own velocity.
    pub kinematic: bool,
    /// Whether the body sleeps this step (then also `is_static` in the step's table).
    pub asleep: bool,
    /// `1/m` (0 for static).
    pub inverse_mass: f64,
    /// `1/I` (0 for static).
    pub inverse_inertia: f64,
    /// Largest distance from the centre of mass to the outside of the band (m).
    pub radius: f64,
    /// Largest tolerance of the boundary, floored at `min_band` (m).
    pub band: f64,
    /// Material (restitution and friction law).
    pub material: Material,
    /// Root box of the tree, in the body frame.
    pub root_box: Obb,
    /// Gravity scale, damping and fixed rotation (defaults for static bodies).
    pub motion: Motion,
    /// Which bodies it collides with.
    pub groups: CollisionGroups,
    /// A sensor reports what it touches and never collides.
    pub sensor: bool,
}

/// A body's acceleration over the step from gravity (times its scale) and the force and
/// torque the user applied (zero for static and sleeping bodies).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyAcceleration {
    /// Linear acceleration (m/s²).
    pub linear: DVec2,
    /// Angular acceleration (rad/s²).
    pub angular: f64,
}

impl BodyAcceleration {
    /// Bound on the acceleration of any point of `body`: `|a| + |α| ρ`.
    #[must_use]
    pub fn bound(&self, body: &BodyRecord) -> f64 {
        self.linear.length() + self.angular.abs() * body.radius
    }
}

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
    /// leaf memory and record by swapping buffers with it (`previous` is left with this slot's
    /// old buffers, which nothing reads).
    pub(crate) fn take_carried(&mut self, previous: &mut PairSlot, drift: Drift) {
        std::mem::swap(&mut self.query, &mut previous.query);
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

/// A prepared query the step keeps: its views read components by entity without the per-call
/// lookups and borrows of `World::get`. The geometry's gives the narrow phase's parallel tasks
/// each body's curve, tolerances and tree, borrowed once per narrow phase (borrowing through
/// `World::entity` per pair took six atomic borrows and releases per pair on counters that every
/// task shares: 8 % of the narrow phase's time on one thread, more on two); the states' and the
/// applied forces' gather and scatter them (through `World::get` they cost the settled 210-box
/// pyramid 0.2 M of its 3.6 M instructions a step), and the states' and sleep records' serve
/// the sleep stage (a step with every body asleep: 0.0205 → 0.0039 ms). Its archetype table is
/// rebuilt only when the world gains an archetype (no allocation per step).
pub struct Prepared<Q: hecs::Query>(pub(crate) hecs::PreparedQuery<Q>);

impl<Q: hecs::Query> Default for Prepared<Q> {
    fn default() -> Self {
        Self(hecs::PreparedQuery::new())
    }
}

// SAFETY: hecs leaves `PreparedQuery` `!Send` because it caches raw pointers to archetype
// columns between uses (the fetches of component references). They are only written and read
// while a `PreparedQueryBorrow` or a `PreparedView` of the world is alive, which needs `&mut`
// access to the query (so one thread at a time), and every view overwrites them from the live
// archetypes before reading one (`PreparedView::new`); in between they are inert data, which may
// move to another thread with the step's buffers. Only for the queries the step keeps: plain
// component references, whose fetches are nothing but such pointers.
#[allow(unsafe_code)]
unsafe impl Send for GeometryQuery {}
#[allow(unsafe_code)]
unsafe impl Send for StateQuery {}
#[allow(unsafe_code)]
unsafe impl Send for ForceQuery {}
#[allow(unsafe_code)]
unsafe impl Send for SleepQuery {}

impl<Q: hecs::Query> std::fmt::Debug for Prepared<Q> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Prepared")
    }
}

/// The bodies' geometry, as the narrow phase reads it.
pub type GeometryQuery = Prepared<(&'static Spline, &'static Rugosity, &'static AobbTree)>;

/// The bodies' states, as the gather, the scatter and the sleep stage read and write them.
pub type StateQuery = Prepared<&'static mut RigidState>;

/// The bodies' sleep records, as the sleep stage reads them.
pub type SleepQuery = Prepared<&'static mut Sleep>;

/// The forces applied to bodies, as the gather and the scatter read and clear them.
pub type ForceQuery = Prepared<&'static mut AppliedForce>;

/// One island of the contact solver: its contacts and its bodies' velocities, as `[start, end)`
/// ranges of `solver_contacts` and `island_velocities`.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolverIsland {
    /// Its contacts.
    pub contacts: (usize, usize),
    /// Its bodies (static and kinematic ones it touches included, read only).
    pub bodies: (usize, usize),
}

/// Buffers reused from step to step: a step allocates nothing once they have grown.
#[derive(Debug, Default)]
pub struct StepBuffers {
    /// The bodies' geometry, for the narrow phase.
    pub geometry: GeometryQuery,
    /// The bodies' states, for the gather, the scatter and the sleep stage.
    pub state_query: StateQuery,
    /// The bodies' sleep records, for the sleep stage.
    pub sleep_query: SleepQuery,
    /// The forces applied to bodies, for the gather and the scatter.
    pub force_query: ForceQuery,
    /// Current state per body slot.
    pub states: Vec<RigidState>,
    /// States at the start of the sub-step, restored on retry.
    pub saved_states: Vec<RigidState>,
    /// States at the start of the last step, for render interpolation.
    pub previous_states: Vec<RigidState>,
    /// Bodies held in place for the rest of the sub-step after the retry depth ran out.
    pub frozen: Vec<bool>,
    /// Pairs intersecting at the start of the sub-step (sorted): they do not trigger retries.
    pub overlapping_pairs: Vec<(u32, u32)>,
    /// World bounds per body, swept by its margin: `(min, max)`.
    pub swept_bounds: Vec<(DVec2, DVec2)>,
    /// Motion margin per body used by the last refit (m).
    pub margins: Vec<f64>,
    /// The bodies' swept bounds in sweep order (broad-phase scratch).
    pub sweep_order: Vec<SweepEntry>,
    /// The pairs each stretch of the sweep found (broad-phase scratch, one buffer per stretch).
    pub sweep_pairs: Vec<Vec<(u32, u32)>>,
    /// Candidate pairs of the last broad phase (body slots, `a < b`, sorted).
    pub candidate_pairs: Vec<(u32, u32)>,
    /// Per body: its swept bounds enlarged when the broad phase last swept (`(min, max)`); empty
    /// when it must sweep again (body slots may have changed).
    pub enlarged_bounds: Vec<(DVec2, DVec2)>,
    /// The pairs whose enlarged bounds overlap (sorted): while every body's swept bounds lie in
    /// its enlarged ones, they hold every candidate pair.
    pub enlarged_pairs: Vec<(u32, u32)>,
    /// The broad phase's last filter of the pairs (kept while no bound moves beyond its room).
    pub filter: broad_phase::FilterRecord,
    /// The broad phase's sorting scratch: the pairs by first body, and a count per body.
    pub pair_sort: (Vec<(u32, u32)>, Vec<u32>),
    /// Narrow-phase result per candidate pair (only the first `candidate_pairs.len()` are live).
    pub pair_slots: Vec<PairSlot>,
    /// How many slots the last narrow phase filled (zero when body slots may have changed).
    pub detected_pairs: usize,
    /// The narrow phase's slots before the last: swapped with `pair_slots` at each phase, so
    /// the last phase's results, each pair's memory of its searches, are read in place.
    pub previous_slots: Vec<PairSlot>,
    /// The buffers every pair slot holds: the largest any slot has needed, while all the slots
    /// together stay within `narrow_phase::SHARED_SLOT_BYTES`, so a pair that lands in another
    /// slot from one sub-step to the next finds its memory there.
    pub slot_capacity: QueryCapacity,
    /// The largest buffers any pair slot has needed (at least `slot_capacity`).
    pub largest_slot: QueryCapacity,
    /// Length of the current sub-step (s).
    pub substep: f64,
    /// Whether the last step was quiet (one sub-step, the whole step, no collision, every body
    /// that can move held by a resting contact) and no action has touched a body since: the
    /// next one then starts without the bound of the velocities before its solve
    /// (`step::solve_and_advance`).
    pub quiet: bool,
    /// Simulated time at the start of the current sub-step (s).
    pub substep_time: f64,
    /// Solver contacts of the current sub-step, island by island, each from the ground up.
    pub solver_contacts: Vec<SolverContact>,
    /// The touches of every pair the last contact preparation built contacts for, pair after
    /// pair (`PairSlot::touches` ranges), and the store's generation (one per preparation).
    pub touch_store: (Vec<prepare_contacts::Touch>, u64),
    /// The store the next preparation writes (then swapped with `touch_store`).
    pub next_touch_store: Vec<prepare_contacts::Touch>,
    /// What each stretch of pair slots gathered for the contact preparation (scratch).
    pub(crate) touch_chunks: Vec<prepare_contacts::TouchChunk>,
    /// The prepared contacts' places in solving order, sorted (scratch of the preparation).
    pub(crate) contact_keys: Vec<prepare_contacts::OrderKey>,
    /// What sorting the keys into solving order works in (scratch of the preparation).
    pub(crate) order_scratch: prepare_contacts::OrderScratch,
    /// The contact solver's islands in `solver_contacts` order: each one's contacts and bodies.
    pub solver_islands: Vec<SolverIsland>,
    /// The islands' body velocities, island after island (`SolverIsland::bodies` ranges).
    pub island_velocities: Vec<BodyVelocity>,
    /// The body slot of each entry of `island_velocities`.
    pub island_slots: Vec<u32>,
    /// The runs of the island whose sweeps two threads share, and their copies
    /// (`island_solve/wavefront.rs`).
    pub(crate) island_runs: island_solve::Runs,
    /// The resting solve's subspace scratch (`island_solve/subspace.rs`).
    pub(crate) subspace_scratch: island_solve::ScratchBuffers,
    /// Per body slot: its index among the velocities of the island being gathered (`u32::MAX`
    /// when not in it). Scratch of the contact solver, left all `u32::MAX`.
    pub island_index: Vec<u32>,
    /// Forces of the last accepted sub-step's contacts, sorted by key (warm start).
    pub contact_cache: Vec<CachedImpulse>,
    /// Per body: its velocity after the collisions, before gravity and the contact solver.
    pub start_velocities: Vec<BodyVelocity>,
    /// Split-impulse pseudo-velocity per body (discarded after the sub-step's motion).
    pub bias: Vec<BodyVelocity>,
    /// Per body: whether any contact acted on it this sub-step.
    pub touched: Vec<bool>,
    /// Per body: the slot representing its island.
    pub island_of: Vec<u32>,
    /// Per body: its distance from a static body in the contact graph.
    pub levels: Vec<u32>,
    /// What `island_of` and `levels` were found from: the colliding pairs, each body's
    /// `is_static`, and the count of islands (while they are the same, so are the islands).
    pub island_inputs: (Vec<(u32, u32)>, Vec<bool>, u64),
    /// Per island representative: whether the island has a heavy-on-light contact (scratch of
    /// the contact solver).
    pub shock_islands: Vec<bool>,
    /// Which contacts the collision sweeps need not test again (scratch of `collide.rs`).
    pub(crate) collide_marks: collide::SweepMarks,
    /// Per body: the weight it and the bodies above it put on its supports (N; scratch of the
    /// cold-start estimate).
    pub loads: Vec<f64>,
    /// Per body: how many contacts hold it up (scratch of the cold-start estimate).
    pub supports: Vec<u32>,
    /// Every body's masses, material, level and island as the last contact preparation read them.
    pub(crate) prepared_bodies: Vec<prepare_contacts::PreparedBody>,
    /// The touch store generation the solver contacts were prepared from.
    pub prepared_generation: u64,
    /// Scratch: states moving at the solved velocities, for the bound after the solve.
    pub motion_states: Vec<RigidState>,
    /// Length of the step being taken (s).
    pub step_length: f64,
    /// What is left of the step after the sub-step being detected (s), as the step's loop counts
    /// it: the next sub-step ends the step at the latest (the narrow phase's carry, §3b). At
    /// most `1e-12` of the step after its last sub-step, and the whole step at a detection
    /// before its first.
    pub step_left: f64,
    /// Per body: its acceleration over the step (gravity and applied forces).
    pub accelerations: Vec<BodyAcceleration>,
    /// Per body: what the closing bound of a pair reads ([`body_motions`]), for the narrow
    /// phase and the sub-step bound.
    pub motions: Vec<BodyMotion>,
    /// Per body: whether the user applied a force or torque for this step (cleared after it).
    pub applied: Vec<bool>,
    /// Slot pairs `(a, b)`, `a < b`, sorted, that never collide (`Simulation::exclude_pair`).
    pub excluded_pairs: Vec<(u32, u32)>,
    /// Slot pairs that touched at the end of any sub-step of the step (sorted, deduplicated at
    /// the step's end): a bounce within one step still begins and ends a touch.
    pub touched_pairs: Vec<(u32, u32)>,
    /// Per body: its pose at the current state (placed by the refit, read by the narrow phase).
    pub poses: Vec<Pose>,
    /// The least gap, less its drift, that any separate leaf pair of the last narrow phase
    /// bounds the sub-step by (its listed gaps and its query margin), gathered where every body
    /// had barely moved since the phase before (`None` otherwise): while no two bodies can close
    /// it, no pair bounds the sub-step.
    pub nearest_gap: Option<f64>,
    /// How many live pair slots the last narrow phase found intersecting, before the contact
    /// hook (which can only make fewer of them count: an ignored pair is a sensor pair); `None`
    /// where unknown (a restored snapshot before its first narrow phase). Where it is zero, the
    /// retry's checks read no slot.
    pub(crate) intersecting_pairs: Option<usize>,
    /// Per live pair slot, in pair order: what the sub-step bound reads first ([`BoundFloor`]),
    /// written by the narrow phase with the slots. Of another length than the live slots (a
    /// restored snapshot's, before its first narrow phase) it is not read: the bound reads
    /// every slot.
    pub(crate) bound_floors: Vec<BoundFloor>,
    /// Whether every live pair slot holds a drift budget of the last narrow phase, which
    /// found every body still (`narrow_phase::still`).
    pub still_budgets: bool,
    /// Per body: its position and angle at the last narrow phase (empty when body slots may
    /// have changed since).
    pub phase_poses: Vec<(DVec2, f64)>,
    /// Per body: how far any of its points has moved since the last narrow phase (scratch of
    /// the narrow phase; empty where that is not known).
    pub phase_motion: Vec<f64>,
    /// Per body: whether `world_mut` broke it (state or geometry gone; read with the states).
    pub broken: Vec<bool>,
    /// Per body: whether it slept at the start of the step (scratch of the sleep stage).
    pub sleeping: Vec<bool>,
    /// Per island representative: whether every body of the island has been still long
    /// enough (scratch of the sleep stage).
    pub island_still: Vec<bool>,
    /// Islands to wake (scratch of the sleep stage and its preparation).
    pub wake_tags: Vec<u64>,
    /// Whether the sleep stage woke a body in the last step (its contacts must be redetected).
    pub woke_in_step: bool,
    /// Scratch of the debug build's invariant checks (`validate::after`).
    #[cfg(debug_assertions)]
    pub(crate) validation: validate::Scratch,
}

impl StepBuffers {
    /// The live narrow-phase slots, in pair order.
    #[must_use]
    pub fn live_pairs(&self) -> &[PairSlot] {
        &self.pair_slots[..self.candidate_pairs.len()]
    }
}

/// What a system sees: the world, the settings, the body table and the buffers.
pub struct StepContext<'a> {
    /// The ECS world (states are gathered from it before and written back after the step).
    pub world: &'a mut World,
    /// Settings in force.
    pub settings: &'a SimulationSettings,
    /// Cold per-body data in slot order.
    pub bodies: &'a [BodyRecord],
    /// Each body's bounding octagon, in slot order (the broad phase's bounds).
    pub octagons: &'a [Octagon],
    /// Reusable buffers, including the current states.
    pub buffers: &'a mut StepBuffers,
    /// Event log (appended to).
    pub(crate) events: &'a mut EventLog<ContactEvent>,
    /// Profile (accumulated into).
    pub profile: &'a mut Profile,
    /// The worker pool the parallel stages split their work on, the step running on one of its
    /// workers; `None` where the step runs on the caller's thread alone (a pool of one thread,
    /// or a step after too light a one, `SimulationSettings::min_parallel_work`): then no
    /// stage hands work to any pool.
    pub pool: Option<&'a rayon::ThreadPool>,
    /// Simulated time at the start of the step (s).
    pub time: f64,
    /// The user's contact hook, called by the narrow phase for each pair in contact.
    pub(crate) contact_hook: Option<&'a (dyn Fn(&PairContacts<'_>) -> PairAction + Send + Sync)>,
}

/// `1/I` of a body: zero with fixed rotation (an infinite moment of inertia).
pub(crate) fn inverse_inertia(mass: &MassProperties, motion: &Motion) -> f64 {
    if motion.fixed_rotation { 0.0 } else { mass.inverse_inertia() }
}

/// Reads every body's cold data from the world, in spawn order, and each one's bounding octagon
/// (a component worked out when the body was added; kept beside the table, not in it: a step
/// with sleeping on copies the table).
#[must_use]
pub fn collect_bodies(world: &World, min_band: f64) -> (Vec<BodyRecord>, Vec<Octagon>) {
    let mut query = world.query::<BodyComponents<'_>>();
    let mut bodies: Vec<(SpawnOrder, BodyRecord, Octagon)> =
        query.iter().map(|components| body_record(world, components, min_band)).collect();
    bodies.sort_by_key(|(order, _, _)| *order);
    bodies.into_iter().map(|(_, record, octagon)| (record, octagon)).unzip()
}

/// The record of one body (as [`collect_bodies`] makes it) with its spawn order and bounding
/// octagon; `None` when the entity is not a whole body.
pub fn collect_body(world: &World, entity: Entity, min_band: f64) -> Option<(SpawnOrder, BodyRecord, Octagon)> {
    let mut query = world.query_one::<BodyComponents<'_>>(entity);
    query.get().ok().map(|components| body_record(world, components, min_band))
}

/// What a body's record is read from.
type BodyComponents<'a> = (
    Entity,
    &'a SpawnOrder,
    &'a MassProperties,
    &'a Material,
    &'a AobbTree,
    &'a Octagon,
    &'a Spline,
    &'a Rugosity,
    Option<&'a Motion>,
    Option<&'a CollisionGroups>,
    Option<&'a Sensor>,
    Option<&'a Kinematic>,
);

fn body_record(world: &World, components: BodyComponents<'_>, min_band: f64) -> (SpawnOrder, BodyRecord, Octagon) {
    let (entity, order, mass, material, tree, octagon, spline, rugosity, motion, groups, sensor, kinematic) =
        components;
    let root_box = tree.root().obb;
    let band = rugosity.body_band(min_band);
    let motion = motion.copied().unwrap_or_default();
    let record = BodyRecord {
        entity,
        is_static: crate::simulation::is_static(world, entity),
        inverse_mass: mass.inverse_mass(),
        inverse_inertia: inverse_inertia(mass, &motion),
        radius: spline.radius_about(DVec2::ZERO) + band,
        band,
        material: *material,
        root_box,
        motion,
        groups: groups.copied().unwrap_or_default(),
        sensor: sensor.is_some(),
        kinematic: kinematic.is_some(),
        asleep: false,
    };
    (*order, record, *octagon)
}

/// One body in the broad phase's sweep: its swept bounds along the sweep axis and across it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepEntry {
    /// `(min, max)` along the sweep axis.
    pub along: (f64, f64),
    /// `(min, max)` across it.
    pub across: (f64, f64),
    /// The body's slot.
    pub slot: u32,
}

/// Velocities of the two bodies of a pair.
pub(crate) fn pair_velocities(states: &[RigidState], (a, b): (u32, u32)) -> (BodyVelocity, BodyVelocity) {
    (body_velocity(&states[a as usize]), body_velocity(&states[b as usize]))
}

/// A body's velocity, from its state.
pub(crate) fn body_velocity(state: &RigidState) -> BodyVelocity {
    BodyVelocity { linear: state.linear_velocity, angular: state.angular_velocity }
}

/// Writes back the velocities of the two bodies of a pair.
pub(crate) fn store_velocities(states: &mut [RigidState], (a, b): (u32, u32), va: BodyVelocity, vb: BodyVelocity) {
    store_velocity(&mut states[a as usize], va);
    store_velocity(&mut states[b as usize], vb);
}

/// Writes a body's velocity into its state.
pub(crate) fn store_velocity(state: &mut RigidState, velocity: BodyVelocity) {
    state.linear_velocity = velocity.linear;
    state.angular_velocity = velocity.angular;
}

impl PairVelocities for [RigidState] {
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity) {
        pair_velocities(self, contact.key.bodies)
    }

    fn set_pair(&mut self, contact: &SolverContact, a: BodyVelocity, b: BodyVelocity) {
        store_velocities(self, contact.key.bodies, a, b);
    }
}

/// The island of a contact's bodies `(a, b)`: the representative of its dynamic body (static
/// bodies join no island).
pub(crate) fn contact_island(bodies: &[BodyRecord], island_of: &[u32], (a, b): (u32, u32)) -> usize {
    island_of[if bodies[a as usize].is_static { b } else { a } as usize] as usize
}

/// Union-find: the representative of `i`'s set (path halving).
pub(crate) fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i
}

/// Union-find: joins the sets of `a` and `b`; the smaller slot becomes the root
/// (deterministic: islands are named by their first body).
pub(crate) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (low, high) = (ra.min(rb), ra.max(rb));
        parent[high as usize] = low;
    }
}

/// What [`closing_bound`] reads of one body, worked out once per pass over the pairs (the
/// bound is taken two to four times a pair a sub-step): its velocity, `|ω| ρ`, `ω² ρ`, its
/// acceleration and `|α| ρ`.
#[derive(Clone, Copy, Debug, Default)]
pub struct BodyMotion {
    velocity: DVec2,
    turning: f64,
    turning_growth: f64,
    acceleration: DVec2,
    angular_acceleration: f64,
}

/// Fills `motions` with every body's [`BodyMotion`] at `states` (no allocation once grown).
pub(crate) fn body_motions(
    bodies: &[BodyRecord],
    states: &[RigidState],
    accelerations: &[BodyAcceleration],
    motions: &mut Vec<BodyMotion>,
) {
    motions.clear();
    motions.extend(bodies.iter().zip(states).zip(accelerations).map(|((body, state), acceleration)| {
        let (omega, radius) = (state.angular_velocity, body.radius);
        BodyMotion {
            velocity: state.linear_velocity,
            turning: omega.abs() * radius,
            turning_growth: omega * omega * radius,
            acceleration: acceleration.linear,
            angular_acceleration: acceleration.angular.abs() * radius,
        }
    }));
}

pub(crate) use crate::geometry::least;

/// What the sub-step bound reads of a live pair before the pair's slot: its bodies and the
/// least gap, less its drift, it bounds the sub-step by ([`PairSlot::nearest_gap`]). Kept
/// apart from the slots, in pair order, so that the bound's pass over a few thousand pairs
/// reads a dense list: a pair whose bodies' closing bound clears its floor over the sub-step
/// bounds nothing (`integrate::pair_substep` would return the sub-step it is given), and only
/// the others' slots are read. A sensor pair's floor is ∞ (it bounds nothing); a pair with
/// exactly one listed gap has −∞ (its pieces are bounded by their own motion, never by the
/// bodies' closing bound, so it is always read); NaN never clears. The list also says whether
/// the pair touches ([`PairSlot::touching`]), which the step's record of touching pairs reads
/// after every sub-step instead of the slots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BoundFloor {
    /// Body slots `(a, b)` of the pair.
    pub bodies: (u32, u32),
    /// The least gap less the drift, ±∞ as above.
    pub floor: f64,
    /// Whether the pair touches.
    pub touching: bool,
}

/// How fast any point of A (band included) can approach any point of B, and how fast that can
/// grow: `speed = |v_A − v_B| + |ω_A| ρ_A + |ω_B| ρ_B` and
/// `growth = ½ (ω_A² ρ_A + ω_B² ρ_B + |a_A − a_B| + |α_A| ρ_A + |α_B| ρ_B)`, so that they close
/// at most `speed·h + growth·h²` in time `h` (a point's velocity turns at `ω²|r|`; two bodies
/// under gravity alone have no difference of accelerations).
#[must_use]
pub(crate) fn closing_bound(motions: &[BodyMotion], (a, b): (usize, usize)) -> (f64, f64) {
    let (ma, mb) = (&motions[a], &motions[b]);
    let speed = (ma.velocity - mb.velocity).length() + ma.turning + mb.turning;
    let driven = (ma.acceleration - mb.acceleration).length() + ma.angular_acceleration + mb.angular_acceleration;
    let growth = 0.5 * (ma.turning_growth + mb.turning_growth + driven);
    (speed, growth)
}

/// A bound of [`closing_bound`] over every pair of bodies at once: twice the fastest body's
/// `|v| + |ω| ρ`, and the largest `ω² ρ` and `|α| ρ` with half the spread of the accelerations
/// (the diagonal of their bounding box), so that no two bodies close faster than
/// `speed·h + growth·h²`.
#[must_use]
pub(crate) fn fastest(motions: &[BodyMotion]) -> (f64, f64) {
    let (mut speed, mut turning_growth, mut angular) = (0.0f64, 0.0f64, 0.0f64);
    let (mut low, mut high) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for motion in motions {
        speed = speed.max(motion.velocity.length() + motion.turning);
        turning_growth = turning_growth.max(motion.turning_growth);
        angular = angular.max(motion.angular_acceleration);
        (low, high) = (low.min(motion.acceleration), high.max(motion.acceleration));
    }
    let spread = if motions.is_empty() { 0.0 } else { (high - low).length() };
    (2.0 * speed, turning_growth + 0.5 * spread + angular)
}

/// The time the margins cover: a nominal step, or the last sub-step if that was longer.
pub(crate) fn margin_horizon(settings: &SimulationSettings, substep: f64) -> f64 {
    settings.time_step.max(substep)
}

/// Bound on how far any point of a body (band included) moves in time `h` under an
/// acceleration bound `acceleration` ([`BodyAcceleration::bound`]):
/// `(|v| + |ω| ρ) h + ½ (|a| + |α| ρ) h²` (zero for static bodies).
#[must_use]
pub fn motion_bound(body: &BodyRecord, state: &RigidState, acceleration: f64, h: f64) -> f64 {
    if body.is_static && !body.kinematic {
        return 0.0;
    }
    (state.linear_velocity.length() + state.angular_velocity.abs() * body.radius) * h + 0.5 * acceleration * h * h
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{BodyMotion, closing_bound, fastest};

    /// The bound over every pair at once is at least each pair's closing bound, speed and growth
    /// (`integrate::substep_bound` skips the pairs while it clears the least gap).
    #[test]
    fn the_fastest_bodies_bound_every_pair() {
        let mut rng = crate::random::seeded(20);
        use rand::RngExt;
        for _ in 0..200 {
            let count = rng.random_range(1..8);
            let mut value = |scale: f64| scale * (2.0 * rng.random::<f64>() - 1.0);
            let motions: Vec<BodyMotion> = (0..count)
                .map(|_| {
                    let (omega, radius) = (value(5.0), value(1.0).abs());
                    BodyMotion {
                        velocity: DVec2::new(value(3.0), value(3.0)),
                        turning: omega.abs() * radius,
                        turning_growth: omega * omega * radius,
                        acceleration: DVec2::new(value(10.0), value(10.0)),
                        angular_acceleration: value(2.0).abs() * radius,
                    }
                })
                .collect();
            let (speed, growth) = fastest(&motions);
            for a in 0..count {
                for b in 0..count {
                    let (pair_speed, pair_growth) = closing_bound(&motions, (a, b));
                    assert!(pair_speed <= speed && pair_growth <= growth, "pair ({a}, {b}) outruns the bound");
                }
            }
        }
        assert_eq!(fastest(&[]), (0.0, 0.0), "no body closes on anything");
    }
}
