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

use std::time::Instant;

use glam::DVec2;
use hecs::{Entity, World};

use crate::components::{AppliedForce, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, SpawnOrder};
use crate::dynamics::impulse::{BodyVelocity, ImpulseKind};
use crate::dynamics::mass::MassProperties;
use crate::dynamics::solver::{CachedImpulse, PairVelocities, SolverContact};
use crate::events::{ContactEvent, EventKind, EventLog};
use crate::geometry::aobb_tree::{AobbTree, TraversalCounters};
use crate::geometry::obb::Obb;
use crate::geometry::overlap::RecoveryContact;
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
pub mod islands;
pub mod micro_collision;
pub mod narrow_phase;
pub mod position_correction;
pub mod prepare_contacts;
pub mod refit;
pub mod sleep;
#[cfg(debug_assertions)]
mod validate;

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

/// Cold per-body data, rebuilt when bodies are added or removed; indexed by body slot.
#[derive(Clone, Debug)]
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
}

impl PairSlot {
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

    /// Forgets the result (keeps the buffers).
    pub fn clear(&mut self) {
        self.recovery = None;
        self.contained = false;
        self.modified = (None, None);
        self.query.manifold.clear();
        self.query.leaf_pairs.clear();
        self.query.counters = TraversalCounters::default();
    }
}

/// Buffers reused from step to step: a step allocates nothing once they have grown.
#[derive(Debug, Default)]
pub struct StepBuffers {
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
    /// Body slots sorted by the lower x bound (broad-phase scratch).
    pub sweep_order: Vec<u32>,
    /// Candidate pairs of the last broad phase (body slots, `a < b`, sorted).
    pub candidate_pairs: Vec<(u32, u32)>,
    /// Narrow-phase result per candidate pair (only the first `candidate_pairs.len()` are live).
    pub pair_slots: Vec<PairSlot>,
    /// How many slots the last narrow phase filled (zero when body slots may have changed).
    pub detected_pairs: usize,
    /// The narrow phase's slots before the last: swapped with `pair_slots` at each phase, so
    /// the last phase's results, each pair's memory of its searches, are read in place.
    pub previous_slots: Vec<PairSlot>,
    /// The largest buffers any pair slot has needed: every slot is grown to it, so a pair that
    /// lands in another slot from one sub-step to the next finds its memory there.
    pub slot_capacity: QueryCapacity,
    /// Length of the current sub-step (s).
    pub substep: f64,
    /// Simulated time at the start of the current sub-step (s).
    pub substep_time: f64,
    /// Solver contacts of the current sub-step, from the ground up.
    pub solver_contacts: Vec<SolverContact>,
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
    /// Per island representative: whether the island has a heavy-on-light contact (scratch of
    /// the contact solver).
    pub shock_islands: Vec<bool>,
    /// Per body: the weight it and the bodies above it put on its supports (N; scratch of the
    /// cold-start estimate).
    pub loads: Vec<f64>,
    /// Per body: how many contacts hold it up (scratch of the cold-start estimate).
    pub supports: Vec<u32>,
    /// Scratch: states moving at the solved velocities, for the bound after the solve.
    pub motion_states: Vec<RigidState>,
    /// Length of the step being taken (s).
    pub step_length: f64,
    /// Per body: its acceleration over the step (gravity and applied forces).
    pub accelerations: Vec<BodyAcceleration>,
    /// Per body: whether the user applied a force or torque for this step (cleared after it).
    pub applied: Vec<bool>,
    /// Slot pairs `(a, b)`, `a < b`, sorted, that never collide (`Simulation::exclude_pair`).
    pub excluded_pairs: Vec<(u32, u32)>,
    /// Slot pairs that touched at the end of any sub-step of the step (sorted, deduplicated at
    /// the step's end): a bounce within one step still begins and ends a touch.
    pub touched_pairs: Vec<(u32, u32)>,
    /// Per body: whether it slept at the start of the step (scratch of the sleep stage).
    pub sleeping: Vec<bool>,
    /// Per island representative: whether every body of the island has been still long
    /// enough (scratch of the sleep stage).
    pub island_still: Vec<bool>,
    /// Islands to wake (scratch of the sleep stage and its preparation).
    pub wake_tags: Vec<u64>,
    /// Whether the sleep stage woke a body in the last step (its contacts must be redetected).
    pub woke_in_step: bool,
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
    /// Reusable buffers, including the current states.
    pub buffers: &'a mut StepBuffers,
    /// Event log (appended to).
    pub(crate) events: &'a mut EventLog<ContactEvent>,
    /// Profile (accumulated into).
    pub profile: &'a mut Profile,
    /// The worker pool for parallel systems.
    pub pool: &'a rayon::ThreadPool,
    /// Simulated time at the start of the step (s).
    pub time: f64,
    /// The user's contact hook, called by the narrow phase for each pair in contact.
    pub(crate) contact_hook: Option<&'a (dyn Fn(&PairContacts<'_>) -> PairAction + Send + Sync)>,
}

/// `1/I` of a body: zero with fixed rotation (an infinite moment of inertia).
pub(crate) fn inverse_inertia(mass: &MassProperties, motion: &Motion) -> f64 {
    if motion.fixed_rotation { 0.0 } else { mass.inverse_inertia() }
}

/// Reads every body's cold data from the world, in spawn order.
#[must_use]
pub fn collect_bodies(world: &World, min_band: f64) -> Vec<BodyRecord> {
    let mut query = world.query::<(
        Entity,
        &SpawnOrder,
        &MassProperties,
        &Material,
        &AobbTree,
        &Spline,
        &Rugosity,
        Option<&Motion>,
        Option<&CollisionGroups>,
        Option<&Sensor>,
        Option<&Kinematic>,
    )>();
    let mut bodies: Vec<(SpawnOrder, BodyRecord)> = query
        .iter()
        .map(|(entity, order, mass, material, tree, spline, rugosity, motion, groups, sensor, kinematic)| {
            let root_box = tree.root().obb;
            let band = rugosity.max_tolerance().max(min_band);
            let motion = motion.copied().unwrap_or_default();
            let record = BodyRecord {
                entity,
                is_static: crate::simulation::is_static(world, entity),
                inverse_mass: mass.inverse_mass(),
                inverse_inertia: inverse_inertia(mass, &motion),
                radius: spline.radius_about(DVec2::ZERO) + band,
                material: *material,
                root_box,
                motion,
                groups: groups.copied().unwrap_or_default(),
                sensor: sensor.is_some(),
                kinematic: kinematic.is_some(),
                asleep: false,
            };
            (*order, record)
        })
        .collect();
    bodies.sort_by_key(|(order, _)| *order);
    bodies.into_iter().map(|(_, record)| record).collect()
}

/// Runs one step of length `dt`; `stale` forces detection at the current poses first.
pub fn run_step(ctx: &mut StepContext<'_>, dt: f64, stale: bool) {
    gather_states(ctx, stale);
    ctx.buffers.step_length = dt;
    ctx.buffers.woke_in_step = false;
    ctx.buffers.previous_states.clone_from(&ctx.buffers.states);
    ctx.buffers.substep_time = ctx.time;
    let seed = ctx.settings.contact_model == ContactModel::SeedMicroCollisions;
    if stale {
        ctx.buffers.substep = dt;
        ctx.buffers.frozen.clear();
        ctx.buffers.frozen.resize(ctx.bodies.len(), true); // detect without moving
        ctx.buffers.detected_pairs = 0; // body slots may have changed: search everything
        run_table(ctx, &ADVANCE);
        if seed {
            run_table(ctx, &RESOLVE);
        }
        ctx.buffers.contact_cache.clear(); // slots may have changed: nothing to warm-start from
    }
    ctx.buffers.touched_pairs.clear();
    let floor = dt / f64::from(1u32 << ctx.settings.max_retry_depth.min(30));
    let mut remaining = dt;
    let mut substeps = 0;
    while remaining > 1e-12 * dt {
        let h = if seed {
            let h = advance_with_retry(ctx, remaining, floor, substeps);
            run_table(ctx, &RESOLVE);
            h
        } else {
            solve_and_advance(ctx, remaining, floor, substeps)
        };
        substeps += 1;
        remaining -= h;
        let buffers = &mut *ctx.buffers;
        let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
        buffers.touched_pairs.extend(live.iter().filter(|slot| slot.touching()).map(|slot| slot.bodies));
        ctx.buffers.substep_time += h;
        ctx.profile.counters.substeps += 1;
    }
    ctx.buffers.touched_pairs.sort_unstable();
    ctx.buffers.touched_pairs.dedup();
    run_table(ctx, &FINISH);
    scatter_states(ctx);
}

/// Rounds of shortening a sub-step because the solved velocities move faster than the ones it
/// was chosen for; after them the retry guards the rest.
const MAX_BOUND_ROUNDS: u32 = 4;

/// Solver: one sub-step of solving, motion and detection, shortened when the solved velocities
/// would outrun the conservative bound and halved on intersection; returns its length. At the
/// retry limit the sub-step is accepted as it is (counted): the pair then overlaps, and its
/// recovery contact pushes it apart — no body is ever held with a velocity its position ignores.
fn solve_and_advance(ctx: &mut StepContext<'_>, remaining: f64, floor: f64, substeps: u32) -> f64 {
    let mut h = integrate::choose_substep(ctx, remaining, floor, substeps);
    remember_overlaps(ctx);
    ctx.buffers.substep = h;
    run_table(ctx, &PREPARE);
    ctx.buffers.saved_states.clone_from(&ctx.buffers.states);
    ctx.buffers.frozen.clear();
    ctx.buffers.frozen.resize(ctx.bodies.len(), false);
    let mut bound_rounds = 0;
    loop {
        ctx.buffers.states.clone_from(&ctx.buffers.saved_states);
        ctx.buffers.substep = h;
        run_table(ctx, &SOLVE);
        // Once the step has used its sub-step budget the rest is taken at once (as in
        // `choose_substep`), so a step always ends.
        if bound_rounds < MAX_BOUND_ROUNDS && substeps < ctx.settings.max_substeps {
            let bound = solved_motion_bound(ctx, h);
            if bound < h * (1.0 - 1e-9) {
                bound_rounds += 1;
                h = bound.max(MIN_SUBSTEP_FRACTION * remaining);
                ctx.profile.counters.bound_shrinks += 1;
                continue;
            }
        }
        run_table(ctx, &ADVANCE);
        if !moving_pair_intersects(ctx) {
            break;
        }
        if h > floor {
            h = (0.5 * h).max(floor);
            ctx.profile.counters.retries += 1;
        } else {
            ctx.profile.counters.retry_limit_hits += 1;
            break;
        }
    }
    commit_contacts(ctx, h);
    h
}

/// Smallest sub-step as a fraction of what remains of the step.
const MIN_SUBSTEP_FRACTION: f64 = 1e-9;

/// The conservative bound for bodies moving as the integrator will move them after the solve:
/// touched bodies at `(v₀ + v)/2 + v_bias`, free ones along their parabola from `v₀`.
fn solved_motion_bound(ctx: &mut StepContext<'_>, h: f64) -> f64 {
    let buffers = &mut *ctx.buffers;
    buffers.motion_states.clone_from(&buffers.states);
    for (i, state) in buffers.motion_states.iter_mut().enumerate() {
        if buffers.touched[i] {
            let (start, bias) = (buffers.start_velocities[i], buffers.bias[i]);
            state.linear_velocity = 0.5 * (start.linear + state.linear_velocity) + bias.linear;
            state.angular_velocity = 0.5 * (start.angular + state.angular_velocity) + bias.angular;
        } else if !ctx.bodies[i].is_static {
            let acceleration = buffers.accelerations[i];
            state.linear_velocity -= acceleration.linear * h;
            state.angular_velocity -= acceleration.angular * h;
        }
    }
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    integrate::substep_bound(ctx.bodies, &buffers.motion_states, &buffers.accelerations, &buffers.margins, live, h)
}

/// After a sub-step is accepted: counts its impulses, records its events, and keeps its
/// contacts' forces for the next sub-step's warm start.
fn commit_contacts(ctx: &mut StepContext<'_>, h: f64) {
    let buffers = &mut *ctx.buffers;
    buffers.contact_cache.clear();
    let time = buffers.substep_time + h;
    for contact in &buffers.solver_contacts {
        if contact.collided {
            ctx.profile.counters.impulses += 1;
        } else if contact.normal_impulse > 0.0 {
            ctx.profile.counters.resting_contacts += 1;
        }
        if contact.normal_impulse > 0.0 {
            buffers.contact_cache.push(cached_force(contact, h, ctx.settings.time_step));
        }
        if ctx.settings.record_events && (contact.collided || contact.normal_impulse > 0.0) {
            ctx.events.push(contact_event(ctx.bodies, &buffers.states, contact, time), &mut ctx.profile.counters);
        }
    }
    buffers.contact_cache.sort_unstable_by_key(|c| c.key);
}

/// The force a contact carried over a sub-step of length `h`, for the next warm start: `P / h`,
/// except where the contact collided in the sub-step, when its resting impulse is spread over at
/// least a whole `time_step`. Right after a collision that impulse is mostly a velocity
/// correction, not a lasting force; as `P / h` over a short sub-step it would be large, and the
/// next, longer sub-step's warm start would throw the bodies apart (a stack settling from its
/// bands' outer edge was kicked up at 0.3 m/s and fell 5 m away).
fn cached_force(contact: &SolverContact, h: f64, time_step: f64) -> CachedImpulse {
    let span = if contact.collided { h.max(time_step) } else { h };
    CachedImpulse {
        key: contact.key,
        normal_force: contact.normal_impulse / span,
        tangent_force: contact.tangent_impulse / span,
    }
}

/// The event of one solved contact: its impulse over the sub-step and what it did.
fn contact_event(bodies: &[BodyRecord], states: &[RigidState], contact: &SolverContact, time: f64) -> ContactEvent {
    let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
    let after = (states[a].velocity_at(contact.point) - states[b].velocity_at(contact.point)).dot(contact.normal);
    let kind = match contact.collision_kind {
        Some(ImpulseKind::Sticking) => EventKind::Sticking,
        Some(ImpulseKind::Sliding) => EventKind::Sliding,
        Some(_) => EventKind::Collision,
        None => EventKind::Resting,
    };
    ContactEvent {
        time,
        body_a: bodies[a].entity,
        body_b: bodies[b].entity,
        segment_a: contact.key.segment_a as usize,
        parameter_a: contact.parameters.0,
        segment_b: contact.key.segment_b as usize,
        parameter_b: contact.parameters.1,
        point: contact.point,
        normal: contact.normal,
        lambda_a: contact.raw_lambda.0,
        lambda_b: contact.raw_lambda.1,
        mu_a: contact.mu.0,
        mu_b: contact.mu.1,
        mu: contact.friction,
        kind,
        normal_velocity_before: contact.normal_velocity_before,
        normal_velocity_after: after,
        impulse: contact.total_impulse(),
    }
}

/// Velocities of the two bodies of a pair.
pub(crate) fn pair_velocities(states: &[RigidState], (a, b): (u32, u32)) -> (BodyVelocity, BodyVelocity) {
    let v = |s: &RigidState| BodyVelocity { linear: s.linear_velocity, angular: s.angular_velocity };
    (v(&states[a as usize]), v(&states[b as usize]))
}

/// Writes back the velocities of the two bodies of a pair.
pub(crate) fn store_velocities(states: &mut [RigidState], (a, b): (u32, u32), va: BodyVelocity, vb: BodyVelocity) {
    let sa = &mut states[a as usize];
    sa.linear_velocity = va.linear;
    sa.angular_velocity = va.angular;
    let sb = &mut states[b as usize];
    sb.linear_velocity = vb.linear;
    sb.angular_velocity = vb.angular;
}

impl PairVelocities for [RigidState] {
    fn pair(&self, bodies: (u32, u32)) -> (BodyVelocity, BodyVelocity) {
        pair_velocities(self, bodies)
    }

    fn set_pair(&mut self, bodies: (u32, u32), a: BodyVelocity, b: BodyVelocity) {
        store_velocities(self, bodies, a, b);
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

fn run_table(ctx: &mut StepContext<'_>, table: &[(Stage, System)]) {
    for &(stage, system) in table {
        let start = Instant::now();
        system(ctx);
        ctx.profile.record(stage, start.elapsed());
        #[cfg(debug_assertions)]
        validate::after(ctx, stage);
    }
}

/// One sub-step of motion and detection, halved on intersection; returns its length.
fn advance_with_retry(ctx: &mut StepContext<'_>, remaining: f64, floor: f64, substeps: u32) -> f64 {
    let mut h = integrate::choose_substep(ctx, remaining, floor, substeps);
    remember_overlaps(ctx);
    ctx.buffers.saved_states.clone_from(&ctx.buffers.states);
    ctx.buffers.frozen.clear();
    ctx.buffers.frozen.resize(ctx.bodies.len(), false);
    loop {
        ctx.buffers.substep = h;
        run_table(ctx, &ADVANCE);
        if !moving_pair_intersects(ctx) {
            return h;
        }
        ctx.buffers.states.clone_from(&ctx.buffers.saved_states);
        if h > floor {
            h = (0.5 * h).max(floor);
            ctx.profile.counters.retries += 1;
        } else {
            ctx.profile.counters.retry_limit_hits += 1;
            // An intersecting pair that did not overlap at the start has a moving body, so
            // there is always one to hold; each round holds at least one more, so this ends.
            let held_one = freeze_intersecting(ctx);
            debug_assert!(held_one, "an intersecting pair with a moving body had no body to hold");
            if !held_one {
                return h;
            }
        }
    }
}

/// Records the pairs that intersect at the start of the sub-step (overlapping input or a
/// teleport): retrying cannot separate them, so they do not trigger retries; counted.
fn remember_overlaps(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    buffers.overlapping_pairs.clear();
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    buffers.overlapping_pairs.extend(live.iter().filter(|slot| slot.intersecting()).map(|slot| slot.bodies));
    ctx.profile.counters.persistent_overlaps += buffers.overlapping_pairs.len() as u64;
}

/// Whether a pair that did not overlap at the start of the sub-step now intersects, with at
/// least one of its bodies moving.
fn moving_pair_intersects(ctx: &StepContext<'_>) -> bool {
    let overlapping = &ctx.buffers.overlapping_pairs;
    ctx.buffers.live_pairs().iter().any(|slot| {
        slot.intersecting() && pair_moves(ctx, slot.bodies) && overlapping.binary_search(&slot.bodies).is_err()
    })
}

fn pair_moves(ctx: &StepContext<'_>, (a, b): (u32, u32)) -> bool {
    let moves = |i: u32| !ctx.bodies[i as usize].is_static && !ctx.buffers.frozen[i as usize];
    moves(a) || moves(b)
}

/// Holds the moving bodies of intersecting pairs at their saved states; `false` if none was new.
fn freeze_intersecting(ctx: &mut StepContext<'_>) -> bool {
    let mut any = false;
    for k in 0..ctx.buffers.candidate_pairs.len() {
        let slot = &ctx.buffers.pair_slots[k];
        if !slot.intersecting() || ctx.buffers.overlapping_pairs.binary_search(&slot.bodies).is_ok() {
            continue;
        }
        for i in [slot.bodies.0, slot.bodies.1] {
            let i = i as usize;
            if !ctx.bodies[i].is_static && !ctx.buffers.frozen[i] {
                ctx.buffers.frozen[i] = true;
                any = true;
            }
        }
    }
    any
}

/// Reads every body's state and applied force. A body broken through `world_mut` — its state
/// or geometry removed, or its state made non-finite — is counted (`broken_bodies`), never
/// passed on quietly: a missing or non-finite state is replaced by the body's last good one
/// (from the step before, when the body table has not changed since), else by rest at the
/// origin.
fn gather_states(ctx: &mut StepContext<'_>, stale: bool) {
    let gravity = ctx.settings.gravity;
    let (states, accelerations, applied_any) =
        (&mut ctx.buffers.states, &mut ctx.buffers.accelerations, &mut ctx.buffers.applied);
    let last_good = if stale { 0 } else { states.len() };
    states.resize(ctx.bodies.len(), RigidState::default());
    accelerations.clear();
    applied_any.clear();
    for (i, body) in ctx.bodies.iter().enumerate() {
        let read = ctx.world.get::<&RigidState>(body.entity).map(|s| *s).ok().filter(RigidState::is_finite);
        let whole = ctx.world.satisfies::<(&Spline, &Rugosity, &AobbTree)>(body.entity);
        match read {
            Some(state) => states[i] = state,
            None if i < last_good => {} // the last good state stays
            None => states[i] = RigidState::default(),
        }
        ctx.profile.counters.broken_bodies += u64::from(read.is_none() || !whole);
        accelerations.push(if body.is_static {
            applied_any.push(false);
            BodyAcceleration::default()
        } else {
            let applied = ctx.world.get::<&AppliedForce>(body.entity).map(|a| *a).unwrap_or_default();
            applied_any.push(applied != AppliedForce::default());
            BodyAcceleration {
                linear: gravity * body.motion.gravity_scale + applied.force * body.inverse_mass,
                angular: applied.torque * body.inverse_inertia,
            }
        });
    }
}

/// Writes the states back and clears the applied forces (they acted over this step).
fn scatter_states(ctx: &mut StepContext<'_>) {
    for ((body, state), &applied) in ctx.bodies.iter().zip(&ctx.buffers.states).zip(&ctx.buffers.applied) {
        if let Ok(mut target) = ctx.world.get::<&mut RigidState>(body.entity) {
            *target = *state;
        }
        if applied && let Ok(mut force) = ctx.world.get::<&mut AppliedForce>(body.entity) {
            *force = AppliedForce::default();
        }
    }
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
