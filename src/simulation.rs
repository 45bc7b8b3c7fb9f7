//! The simulation: a hecs world of bodies, the settings, a rayon pool, reusable buffers,
//! the event log and the per-stage profile; the step itself is the table in `systems/mod.rs`.

mod actions;
mod body_desc;
mod contact_hook;
mod queries;
mod restore;
mod settings;
mod shape_cast;
mod snapshot;
mod touches;
mod workers;

pub use body_desc::BodyDesc;
pub use contact_hook::{ContactHook, PairAction, PairContacts};
pub use queries::{PointProjection, QueryFilter, RayHit};
pub use restore::MAX_ENTITY_INDEX;
pub use settings::{
    ContactModel, MAX_ANGULAR_SPEED, MAX_COORDINATE, MAX_GRAVITY, MAX_SPEED, MAX_STEP, MIN_STEP, SimulationSettings,
    SleepSettings, SolverSettings,
};
pub use shape_cast::{SHAPE_CAST_TOLERANCE, ShapeCast, ShapeHit};
pub use snapshot::{BodyKind, BodySnapshot, SNAPSHOT_VERSION, Snapshot, StepMemory};

use std::sync::Arc;
use std::time::Instant;

use glam::DVec2;
use hecs::{Entity, World};

use crate::components::{AppliedForce, BodyName, Kinematic, RigidState, Sensor, Sleep, SpawnOrder, Static};
use crate::dynamics::mass::{MassProperties, mass_properties, recentre};
use crate::error::{BodyError, BodyLabel, SettingsError};
use crate::events::{ContactEvent, EventLog, TouchEvent};
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::octagon::Octagon;
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;
use crate::profile::{Profile, Stage};
use crate::systems::{self, BodyRecord, StepBuffers};

/// Low bits of a body handle's generation that count the reuse of its slot.
const REUSE_BITS: u32 = 12;

/// A tag for a new simulation: 1 to 2²⁰ − 1, in turn (after about a million simulations in one
/// process the tags repeat, and only then could two live simulations share one).
fn next_tag() -> u32 {
    use std::sync::atomic::{AtomicU32, Ordering};
    static NEXT: AtomicU32 = AtomicU32::new(0);
    NEXT.fetch_add(1, Ordering::Relaxed) % ((1 << (32 - REUSE_BITS)) - 1) + 1
}

/// The physics world and its step.
pub struct Simulation {
    world: World,
    settings: SimulationSettings,
    pool: Arc<rayon::ThreadPool>,
    pub(crate) bodies: Vec<BodyRecord>,
    /// Each body's bounding octagon, by slot (beside `bodies`, not in it: with sleeping on a
    /// step copies that table).
    pub(crate) octagons: Vec<Octagon>,
    /// The body table a step sees: `bodies` with sleeping bodies made static.
    step_bodies: Vec<BodyRecord>,
    pub(crate) buffers: StepBuffers,
    events: EventLog<ContactEvent>,
    /// Begin and end of touching, per pair.
    touch_events: EventLog<TouchEvent>,
    /// Pairs touching at the end of the last step, `(a, b)` with `a < b`, sorted.
    touching: Vec<(Entity, Entity)>,
    /// Scratch: the pairs touching now.
    touching_now: Vec<(Entity, Entity)>,
    /// Scratch: the pairs that began touching in the step.
    touch_scratch: Vec<(Entity, Entity)>,
    /// The slot pairs that touched during the step of the last record, and whether they were
    /// those touching at its end (then `touching` was found from them).
    touched_slots: (Vec<(u32, u32)>, bool),
    profile: Profile,
    time: f64,
    next_spawn: u64,
    /// This simulation's tag in its bodies' handles (see `owned_entity`).
    tag: u32,
    /// Pairs of bodies that never collide ([`Simulation::exclude_pair`]).
    excluded: Vec<(Entity, Entity)>,
    accumulator: f64,
    stale: bool,
    /// The last step's work (`StepCounters::work`) and whether it ran on the pool after another step (the
    /// first runs there for want of a measure); `None` before the first step, after a restore
    /// and after a step with every body asleep (see `runs_on_pool`).
    last_step_work: Option<(u64, bool)>,
    /// The user's contact hook ([`Simulation::set_contact_hook`]).
    contact_hook: Option<ContactHook>,
}

impl Simulation {
    /// A simulation with its own rayon pool of `settings.threads` workers.
    ///
    /// # Errors
    /// A [`SettingsError`] for an invalid setting, or if the pool cannot be built.
    pub fn new(settings: SimulationSettings) -> Result<Self, SettingsError> {
        settings.validate()?;
        let pool = build_pool(settings.threads)?;
        Ok(Self::with_pool(settings, Arc::new(pool)))
    }

    /// A simulation that runs its parallel stages on a pool the caller owns.
    ///
    /// # Panics
    /// Never for valid settings; call [`SimulationSettings::validate`] first (debug-asserted).
    #[must_use]
    pub fn with_pool(settings: SimulationSettings, pool: Arc<rayon::ThreadPool>) -> Self {
        debug_assert!(settings.validate().is_ok());
        let events = EventLog::new(settings.event_capacity);
        let touch_events = EventLog::new(settings.event_capacity);
        Self {
            world: World::new(),
            settings,
            pool,
            bodies: Vec::new(),
            octagons: Vec::new(),
            step_bodies: Vec::new(),
            buffers: StepBuffers::default(),
            events,
            touch_events,
            touching: Vec::new(),
            touching_now: Vec::new(),
            touch_scratch: Vec::new(),
            touched_slots: (Vec::new(), false),
            profile: Profile::default(),
            time: 0.0,
            next_spawn: 0,
            tag: next_tag(),
            excluded: Vec::new(),
            accumulator: 0.0,
            stale: true,
            last_step_work: None,
            contact_hook: None,
        }
    }

    /// The settings in force.
    #[must_use]
    pub fn settings(&self) -> &SimulationSettings {
        &self.settings
    }

    /// The hecs world: read components, or add your own to the bodies.
    #[must_use]
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Mutable access to the world. Changing a body's [`RigidState`] here is allowed between
    /// steps; call [`Simulation::mark_moved`] after teleporting bodies so contacts are redone.
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// Forces contact detection at the current poses before the next step (after a teleport).
    pub fn mark_moved(&mut self) {
        self.stale = true;
    }

    /// Simulated time (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Number of bodies.
    #[must_use]
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    /// Bodies in processing (spawn) order.
    pub fn bodies(&self) -> impl ExactSizeIterator<Item = Entity> + '_ {
        self.bodies.iter().map(|b| b.entity)
    }

    /// Validates and spawns a body; the curve is re-centred on its centroid.
    ///
    /// # Errors
    /// A [`BodyError`] naming the body (spawn index and name) and the reason.
    pub fn add_body(&mut self, desc: BodyDesc) -> Result<Entity, BodyError> {
        let label = BodyLabel { index: Some(self.next_spawn as usize), name: desc.name.clone() };
        desc.validate(&label)?;
        desc.check_band(self.settings.min_band, &label)?;
        let (spline, centroid) = recentre(&desc.spline);
        let state = RigidState {
            position: desc.position + DVec2::from_angle(desc.angle).rotate(centroid),
            angle: desc.angle,
            linear_velocity: if desc.is_static && !desc.is_kinematic { DVec2::ZERO } else { desc.linear_velocity },
            angular_velocity: if desc.is_static && !desc.is_kinematic { 0.0 } else { desc.angular_velocity },
        };
        let mass = if desc.is_static || desc.is_kinematic {
            MassProperties::STATIC
        } else {
            mass_properties(&spline, desc.material.density)
        };
        let tree = AobbTree::build(&spline, &desc.rugosity, self.settings.min_band);
        let octagon = Octagon::of_body(&spline, &desc.rugosity, self.settings.min_band);
        let order = SpawnOrder(self.next_spawn);
        self.next_spawn += 1;
        let entity = self.owned_entity();
        let components = (spline, desc.rugosity, tree, octagon, state, desc.material, mass, order, desc.groups);
        self.world.spawn_at(entity, components);
        if desc.is_kinematic {
            self.world.insert(entity, (Static, Kinematic)).expect("entity was just spawned");
        } else if desc.is_static {
            self.world.insert_one(entity, Static).expect("entity was just spawned");
        } else {
            let dynamic = (Sleep::default(), desc.motion, AppliedForce::default());
            self.world.insert(entity, dynamic).expect("entity was just spawned");
        }
        if desc.sensor {
            self.world.insert_one(entity, Sensor).expect("entity was just spawned");
        }
        if let Some(name) = desc.name {
            self.world.insert_one(entity, BodyName(name)).expect("entity was just spawned");
        }
        // The newest body comes last in spawn order: its record joins the table at the end, and
        // the others' slots (so the excluded pairs') stay as they were. Rebuilding the whole table
        // instead made spawning n bodies cost O(n²).
        let (_, record, octagon) = systems::collect_body(&self.world, entity, self.settings.min_band)
            .expect("a body was just spawned with every component");
        self.bodies.push(record);
        self.octagons.push(octagon);
        self.stale = true;
        Ok(entity)
    }

    /// A free entity handle that carries this simulation's tag in its generation, so that no
    /// other simulation's handle is ever one of ours (hecs handles of two worlds otherwise
    /// coincide: removing "body 0" of another simulation removed ours). The generation is
    /// `tag << 12 | reuse`: the slot's reuse count (mod 4096, from hecs's own generation) keeps a
    /// removed body's handle from naming the body that later takes its slot.
    fn owned_entity(&mut self) -> Entity {
        let free = self.world.spawn(());
        self.world.despawn(free).expect("entity was just spawned");
        let reuse = ((free.to_bits().get() >> 32) as u32) & ((1 << REUSE_BITS) - 1);
        let generation = (self.tag << REUSE_BITS) | reuse;
        Entity::from_bits((u64::from(generation) << 32) | u64::from(free.id())).expect("the tag makes it non-zero")
    }

    /// Removes a body; `false` if it was not a body of this simulation. Sleeping bodies it
    /// touched wake (every sleeping body, if bodies were added or removed since the last step
    /// and its contacts are not known).
    pub fn remove_body(&mut self, entity: Entity) -> bool {
        let Some(slot) = self.bodies.iter().position(|b| b.entity == entity) else {
            return false;
        };
        let mut tags = std::mem::take(&mut self.buffers.wake_tags);
        tags.clear();
        let sleeping_tag = |world: &World, e: Entity| world.get::<&Sleep>(e).ok().and_then(|s| s.island);
        if self.stale {
            tags.extend(self.bodies.iter().filter_map(|b| sleeping_tag(&self.world, b.entity)));
        } else {
            for pair in self.buffers.live_pairs().iter().filter(|p| p.colliding()) {
                let (a, b) = pair.body_indices();
                let partner = if a == slot {
                    b
                } else if b == slot {
                    a
                } else {
                    continue;
                };
                tags.extend(sleeping_tag(&self.world, self.bodies[partner].entity));
            }
        }
        tags.sort_unstable();
        tags.dedup();
        for &tag in &tags {
            let woken = systems::sleep::wake_island(&mut self.world, &self.bodies, tag);
            self.profile.counters.woken_bodies += woken as u64;
        }
        self.buffers.wake_tags = tags;
        self.end_touches_of(entity);
        let removed = self.world.despawn(entity).is_ok();
        self.rebuild_body_table();
        removed
    }

    fn rebuild_body_table(&mut self) {
        (self.bodies, self.octagons) = systems::collect_bodies(&self.world, self.settings.min_band);
        self.map_excluded_pairs();
        self.stale = true;
    }

    /// The excluded pairs as sorted slot pairs, for the broad phase (removed bodies dropped).
    fn map_excluded_pairs(&mut self) {
        let slot = |e: Entity| self.bodies.iter().position(|b| b.entity == e).map(|s| s as u32);
        self.excluded.retain(|&(a, b)| slot(a).is_some() && slot(b).is_some());
        let pairs = &mut self.buffers.excluded_pairs;
        pairs.clear();
        pairs.extend(
            self.excluded.iter().filter_map(|&(a, b)| Some((slot(a)?, slot(b)?))).map(|(a, b)| (a.min(b), a.max(b))),
        );
        pairs.sort_unstable();
    }

    /// The state of a body.
    #[must_use]
    pub fn state(&self, entity: Entity) -> Option<RigidState> {
        self.world.get::<&RigidState>(entity).ok().map(|s| *s)
    }

    /// Whether a body sleeps (`false` for static bodies and for entities that are not bodies).
    #[must_use]
    pub fn is_sleeping(&self, entity: Entity) -> bool {
        self.world.get::<&Sleep>(entity).is_ok_and(|s| s.is_asleep())
    }

    /// Changes when bodies sleep (Box2D's `b2World_EnableSleeping`); switching sleeping off
    /// wakes every sleeping body.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field (`sleep.speed`, `sleep.time`); nothing changes.
    pub fn set_sleep(&mut self, sleep: SleepSettings) -> Result<(), SettingsError> {
        sleep.validate()?;
        self.settings.sleep = sleep;
        if !sleep.enabled {
            let mut woken = 0;
            for body in &self.bodies {
                if let Ok(mut state) = self.world.get::<&mut Sleep>(body.entity) {
                    woken += usize::from(state.is_asleep());
                    *state = Sleep::default();
                }
            }
            self.profile.counters.woken_bodies += woken as u64;
            self.stale |= woken > 0;
        }
        Ok(())
    }

    /// Wakes a body and the island it sleeps in (nothing if it is awake); `false` if it is not
    /// a dynamic body of this simulation.
    pub fn wake(&mut self, entity: Entity) -> bool {
        if !self.bodies.iter().any(|b| b.entity == entity) {
            return false;
        }
        let Ok(tag) = self.world.get::<&Sleep>(entity).map(|s| s.island) else { return false };
        if let Some(tag) = tag {
            let woken = systems::sleep::wake_island(&mut self.world, &self.bodies, tag);
            self.profile.counters.woken_bodies += woken as u64;
            self.stale = true;
        }
        true
    }

    /// Advances the simulation by `dt` seconds (one step, possibly split into sub-steps).
    ///
    /// A `dt` outside [[`MIN_STEP`], [`MAX_STEP`]] (or NaN) is refused and counted
    /// (`StepCounters::refused_steps`): nothing changes. [`Simulation::try_step`] returns the
    /// reason instead.
    pub fn step(&mut self, dt: f64) {
        if self.try_step(dt).is_err() {
            self.profile.counters.refused_steps += 1;
        }
    }

    /// As [`Simulation::step`], with a typed error for a refused `dt`.
    ///
    /// # Errors
    /// A [`SettingsError`] naming `dt`, its value and the range.
    pub fn try_step(&mut self, dt: f64) -> Result<(), SettingsError> {
        crate::error::check_range("dt", dt, MIN_STEP, MAX_STEP)?;
        self.run_one_step(dt);
        Ok(())
    }

    fn run_one_step(&mut self, dt: f64) {
        if self.bodies.is_empty() {
            self.time += dt;
            return;
        }
        let bodies = if self.settings.sleep.enabled {
            let start = Instant::now();
            let buffers = &mut self.buffers;
            let prepared = systems::sleep::prepare(
                &mut self.world,
                &self.bodies,
                &mut self.step_bodies,
                (&mut buffers.wake_tags, &mut buffers.state_query, &mut buffers.sleep_query),
                &buffers.swept_bounds,
            );
            self.profile.record(Stage::Sleep, start.elapsed());
            self.profile.counters.sleeping_bodies += prepared.asleep as u64;
            self.profile.counters.woken_bodies += prepared.woken as u64;
            if prepared.woken > 0 {
                self.stale = true; // pairs of sleeping bodies were not tested
            }
            if prepared.awake == 0 {
                // Everything sleeps: nothing moves, nothing is tested.
                let buffers = &mut self.buffers;
                buffers.previous_states.clear();
                let mut states = buffers.state_query.0.view_mut(&mut self.world);
                buffers
                    .previous_states
                    .extend(self.bodies.iter().map(|b| states.get_mut(b.entity).map(|s| *s).unwrap_or_default()));
                self.profile.counters.skipped_stages += 1;
                // The step that wakes them measures nothing before it: it runs on the pool.
                self.last_step_work = None;
                self.time += dt;
                self.profile.steps += 1;
                return;
            }
            &self.step_bodies
        } else {
            &self.bodies
        };
        // The step runs on the pool where it has more than one thread and work to share
        // (`runs_on_pool`), else on this thread alone; either way its results are the same to
        // the bit.
        let pooled =
            self.pool.current_num_threads() > 1 && runs_on_pool(self.last_step_work, self.settings.min_parallel_work);
        let work_before = self.profile.counters.work();
        let mut ctx = systems::StepContext {
            world: &mut self.world,
            settings: &self.settings,
            bodies,
            octagons: &self.octagons,
            buffers: &mut self.buffers,
            events: &mut self.events,
            profile: &mut self.profile,
            pool: pooled.then_some(&*self.pool),
            time: self.time,
            contact_hook: self.contact_hook.as_deref(),
        };
        let stale = std::mem::take(&mut self.stale);
        if pooled {
            // The whole step runs on a worker of the pool, which then takes part in the
            // parallel stages: the caller's thread only waits, so the workers never compete
            // with it for the cores while the serial stages run, and one job enters the pool
            // per step rather than one per sub-step. The other workers spin through the step,
            // ready for its parallel stages (`simulation/workers.rs`).
            let spin = self.settings.worker_spin;
            self.pool.install(|| workers::with_workers_at_hand(spin, || systems::run_step(&mut ctx, dt, stale)));
            self.profile.counters.pool_jobs += 1;
        } else {
            systems::run_step(&mut ctx, dt, stale);
        }
        // The first step's work decides alone: it ran on the pool for want of any.
        let held = pooled && self.last_step_work.is_some();
        self.last_step_work = Some((self.profile.counters.work().saturating_sub(work_before), held));
        if self.buffers.woke_in_step {
            self.stale = true; // pairs of the woken bodies were not tested
        }
        self.time += dt;
        self.record_touches(stale);
        self.profile.steps += 1;
    }

    /// Game-loop entry: accumulates `frame_dt` and takes as many fixed steps of
    /// `settings.time_step` as fit. Returns the interpolation factor `α ∈ [0, 1)` for
    /// rendering between the previous and the current state ([`Simulation::interpolated_state`]).
    pub fn advance(&mut self, frame_dt: f64) -> f64 {
        if frame_dt.is_finite() && frame_dt > 0.0 {
            self.accumulator += frame_dt;
        }
        let step = self.settings.time_step;
        let mut taken = 0;
        while self.accumulator >= step && taken < self.settings.max_steps_per_advance {
            self.run_one_step(step);
            self.accumulator -= step;
            taken += 1;
        }
        if self.accumulator >= step {
            // A stalled frame: drop what does not fit, count it, keep the blend factor.
            let dropped = (self.accumulator / step).floor() as u64; // saturates at u64::MAX
            self.profile.counters.dropped_steps = self.profile.counters.dropped_steps.saturating_add(dropped);
            self.accumulator = self.accumulator.rem_euclid(step);
        }
        self.accumulator / step
    }

    /// State blended between the start and the end of the last step: `α = 0` is the start.
    /// `α` is clamped to `[0, 1]`; a NaN `α` gives the end of the step (never a NaN state).
    #[must_use]
    pub fn interpolated_state(&self, entity: Entity, alpha: f64) -> Option<RigidState> {
        let slot = self.bodies.iter().position(|b| b.entity == entity)?;
        let current = self.state(entity)?;
        let previous = self.buffers.previous_states.get(slot).copied().unwrap_or(current);
        let a = if alpha.is_nan() { 1.0 } else { alpha.clamp(0.0, 1.0) };
        Some(RigidState {
            position: previous.position.lerp(current.position, a),
            angle: previous.angle + (current.angle - previous.angle) * a,
            linear_velocity: previous.linear_velocity.lerp(current.linear_velocity, a),
            angular_velocity: previous.angular_velocity + (current.angular_velocity - previous.angular_velocity) * a,
        })
    }

    /// Takes the events recorded since the last call (in application order).
    pub fn drain_events(&mut self) -> std::vec::Drain<'_, ContactEvent> {
        self.events.drain()
    }

    /// Profile accumulated since the last [`Simulation::take_profile`].
    #[must_use]
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// Returns the accumulated profile and starts a new one.
    pub fn take_profile(&mut self) -> Profile {
        std::mem::take(&mut self.profile)
    }

    /// Kinetic energy of all bodies (J).
    #[must_use]
    pub fn kinetic_energy(&self) -> f64 {
        self.bodies
            .iter()
            .filter(|b| !b.is_static)
            .filter_map(|b| self.state(b.entity).map(|s| (b, s)))
            .map(|(b, s)| {
                // A body with fixed rotation (1/I = 0) does not turn.
                let turning =
                    if b.inverse_inertia > 0.0 { s.angular_velocity.powi(2) / b.inverse_inertia } else { 0.0 };
                0.5 * (s.linear_velocity.length_squared() / b.inverse_mass + turning)
            })
            .sum()
    }

    /// Hash of every body's state bits in spawn order: equal hashes mean bit-identical states.
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        let mut hash = 0xcbf2_9ce4_8422_2325_u64; // FNV-1a
        for body in &self.bodies {
            let Some(s) = self.state(body.entity) else { continue };
            for value in
                [s.position.x, s.position.y, s.angle, s.linear_velocity.x, s.linear_velocity.y, s.angular_velocity]
            {
                for byte in value.to_bits().to_le_bytes() {
                    hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
                }
            }
        }
        hash
    }

    /// Checks the invariants of every body: finite state, valid curve, rugosity and tree.
    ///
    /// # Errors
    /// A description of the first violation, naming the body.
    pub fn validate(&self) -> Result<(), String> {
        for (index, body) in self.bodies.iter().enumerate() {
            let state = self.state(body.entity).ok_or_else(|| format!("body {index}: missing RigidState"))?;
            if !state.is_finite() {
                return Err(format!("body {index}: non-finite state {state:?}"));
            }
            let spline = self.world.get::<&Spline>(body.entity).map_err(|e| format!("body {index}: {e}"))?;
            let rugosity = self.world.get::<&Rugosity>(body.entity).map_err(|e| format!("body {index}: {e}"))?;
            let tree = self.world.get::<&AobbTree>(body.entity).map_err(|e| format!("body {index}: {e}"))?;
            spline.validate().map_err(|e| format!("body {index}: {e}"))?;
            rugosity.validate(spline.segment_count()).map_err(|e| format!("body {index}: {e}"))?;
            tree.validate(&spline, &rugosity, self.settings.min_band).map_err(|e| format!("body {index}: {e}"))?;
            let octagon = self.world.get::<&Octagon>(body.entity).map_err(|e| format!("body {index}: {e}"))?;
            if *octagon != Octagon::of_body(&spline, &rugosity, self.settings.min_band)
                || self.octagons[index] != *octagon
            {
                return Err(format!("body {index}: its bounding octagon is not its boundary's"));
            }
        }
        Ok(())
    }
}

/// A rayon pool of `threads` workers (0: rayon chooses).
fn build_pool(threads: usize) -> Result<rayon::ThreadPool, SettingsError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| SettingsError::new("threads", threads, e.to_string()))
}

/// Whether `entity` carries the [`Static`] marker.
pub(crate) fn is_static(world: &World, entity: Entity) -> bool {
    world.get::<&Static>(entity).is_ok()
}

/// Whether a step of a pool of more than one thread runs on it, after a step of `last` work
/// ([`StepCounters::work`](crate::StepCounters::work)) that did or did not (`None`: no step
/// yet, a restore, or every body asleep): after one on the caller's thread once that work
/// reaches `min_parallel_work`, after one on the pool while it stays at three quarters of it or
/// more. A scene whose work wanders about the threshold would otherwise
/// switch back and forth, and a step on the pool after one off it finds the workers asleep and
/// the data in the other core's cache: such a scene took 1.3 times its one-thread time, more
/// than on the pool alone or off it alone (docs/performance.md).
fn runs_on_pool(last: Option<(u64, bool)>, min_parallel_work: u64) -> bool {
    let limit = |pooled: bool| {
        if pooled { (3 * u128::from(min_parallel_work)).div_ceil(4) } else { u128::from(min_parallel_work) }
    };
    last.is_none_or(|(work, pooled)| u128::from(work) >= limit(pooled))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::{CollisionGroups, Motion};
    use crate::geometry::construct::Generator;

    /// Spawning appends each new body's record; the table is the one a rebuild from the world
    /// gives, through adds, removals and adds again, for every kind of body.
    #[test]
    fn the_body_table_grows_as_a_rebuild_would_make_it() {
        let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
        let spline = Generator::Circle { radius: 0.5 }.build(8).unwrap();
        let rugosity = Rugosity::constant(8, 0.002).unwrap();
        let body = |x: f64| BodyDesc::new(spline.clone(), rugosity.clone()).at(DVec2::new(x, 0.0), 0.0);
        let fixed_rotation = Motion { fixed_rotation: true, ..Motion::default() };
        let descs = [
            body(0.0),
            body(2.0).fixed(),
            body(4.0).kinematic(),
            body(6.0).sensor(),
            body(8.0).with_motion(fixed_rotation),
            body(10.0).with_groups(CollisionGroups { memberships: 2, filter: 1 }),
        ];
        let mut spawned = Vec::new();
        for desc in descs.clone() {
            spawned.push(sim.add_body(desc).unwrap());
            let table = systems::collect_bodies(&sim.world, sim.settings.min_band);
            assert_eq!((&sim.bodies, &sim.octagons), (&table.0, &table.1));
        }
        assert!(sim.remove_body(spawned[2]));
        for desc in descs {
            sim.add_body(desc).unwrap();
            let table = systems::collect_bodies(&sim.world, sim.settings.min_band);
            assert_eq!((&sim.bodies, &sim.octagons), (&table.0, &table.1));
        }
    }
}
