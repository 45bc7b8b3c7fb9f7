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

use crate::components::{
    AppliedForce, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, Sleep, SpawnOrder,
};
use crate::dynamics::impulse::{BodyVelocity, ImpulseKind};
use crate::dynamics::mass::MassProperties;
use crate::dynamics::solver::{CachedImpulse, PairVelocities, SolverContact};
use crate::events::{ContactEvent, EventKind, EventLog};
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::obb::Obb;
use crate::geometry::octagon::Octagon;
use crate::geometry::pose::Pose;
use crate::geometry::query::QueryCapacity;
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
mod motion_bounds;
pub mod narrow_phase;
mod pair_slot;
pub mod position_correction;
pub mod prepare_contacts;
pub mod refit;
pub mod sleep;
mod step;
#[cfg(debug_assertions)]
mod validate;

pub use motion_bounds::{BodyMotion, motion_bound};
pub(crate) use motion_bounds::{BoundFloor, body_motions, closing_bound, fastest, margin_horizon};
pub(crate) use pair_slot::TouchRange;
pub use pair_slot::{Drift, PairSlot, SolvedAt};
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

pub(crate) use crate::geometry::least;
