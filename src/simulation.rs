//! The simulation: a hecs world of bodies, the settings, a rayon pool, reusable buffers,
//! the event log and the per-stage profile; the step itself is the table in `systems/mod.rs`.

mod actions;
mod touches;

use std::sync::Arc;
use std::time::Instant;

use glam::DVec2;
use hecs::{Entity, World};
use serde::{Deserialize, Serialize};

use crate::components::{
    AppliedForce, BodyName, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, Sleep, SpawnOrder, Static,
};
use crate::dynamics::impulse::ImpulseLaw;
use crate::dynamics::mass::{MassProperties, mass_properties, recentre};
use crate::error::{BodyError, BodyLabel, SettingsError, check_range};
use crate::events::{ContactEvent, EventLog, TouchEvent};
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::curve_pair::CurvePairSettings;
use crate::geometry::rugosity::Rugosity;
use crate::geometry::self_intersection::find_self_intersection;
use crate::geometry::spline::Spline;
use crate::profile::{Profile, Stage};
use crate::systems::{self, BodyRecord, StepBuffers};

/// Everything a user can set about the dynamics. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulationSettings {
    /// Gravity (m/s²); its magnitude is the `g` of micro-collisions.
    pub gravity: DVec2,
    /// Fixed step of [`Simulation::advance`] (s).
    pub time_step: f64,
    /// Minimum half-width of every tolerance band (m): smooth bodies (R = 0) still need a band.
    pub min_band: f64,
    /// How many times a step may be halved (retry on intersection, and the floor of
    /// conservative advancement, `time_step / 2^depth`).
    pub max_retry_depth: u32,
    /// Most sub-steps conservative advancement may split one step into; the rest of a step
    /// that reaches it is taken at once (counted in the profile).
    pub max_substeps: u32,
    /// Collision law: the seed's as written, or the energy-safe one (MODEL §6).
    pub impulse_law: ImpulseLaw,
    /// How contacts are resolved: the iterated solver (default) or the seed's micro-collisions.
    pub contact_model: ContactModel,
    /// Settings of the iterated contact solver (used with [`ContactModel::Solver`]).
    pub solver: SolverSettings,
    /// Sweeps of the collision loop before the final inelastic sweep.
    pub max_impulse_iterations: u32,
    /// Normal speed (m/s) below which a contact counts as resting, on top of `2 |g| h`
    /// (the speed one sub-step of gravity gives a resting body).
    pub resting_speed: f64,
    /// Worker threads; 0 lets rayon choose. Results are identical for any count.
    pub threads: usize,
    /// Whether every impulse is recorded in the event log.
    pub record_events: bool,
    /// Most events the log keeps between two [`Simulation::drain_events`]; later ones are
    /// dropped and counted (`StepCounters::dropped_events`), so a program that never drains
    /// the log stays within about `event_capacity × 200` bytes.
    pub event_capacity: usize,
    /// Settings of the curve-pair solver.
    pub curve_pair: CurvePairSettings,
    /// When bodies at rest go to sleep (docs/model.md §8, our choice).
    pub sleep: SleepSettings,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self {
            gravity: DVec2::new(0.0, -9.81),
            time_step: 1.0 / 120.0,
            min_band: 1e-3,
            max_retry_depth: 8,
            max_substeps: 256,
            impulse_law: ImpulseLaw::default(),
            contact_model: ContactModel::default(),
            solver: SolverSettings::default(),
            max_impulse_iterations: 16,
            resting_speed: 1e-3,
            threads: 0,
            record_events: true,
            event_capacity: 1 << 16,
            curve_pair: CurvePairSettings::default(),
            sleep: SleepSettings::default(),
        }
    }
}

impl SimulationSettings {
    /// Checks every setting against its domain.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if !self.gravity.is_finite() {
            return Err(SettingsError::new("gravity", self.gravity, "must be finite"));
        }
        // 10⁵ g: beyond it velocities over a step leave any meaningful range (and at 1e308
        // overflow to infinity).
        if self.gravity.length() > MAX_GRAVITY {
            return Err(SettingsError::new(
                "gravity",
                self.gravity,
                format!("must have a magnitude of at most {MAX_GRAVITY:e} m/s²"),
            ));
        }
        check_range("time_step", self.time_step, 1e-9, 10.0)?;
        check_range("min_band", self.min_band, f64::MIN_POSITIVE, f64::MAX)?;
        if self.max_retry_depth > 30 {
            return Err(SettingsError::new("max_retry_depth", self.max_retry_depth, "must be at most 30"));
        }
        if self.max_substeps == 0 {
            return Err(SettingsError::new("max_substeps", 0, "must be at least 1"));
        }
        if self.max_impulse_iterations == 0 {
            return Err(SettingsError::new("max_impulse_iterations", 0, "must be at least 1"));
        }
        check_range("resting_speed", self.resting_speed, 0.0, f64::MAX)?;
        self.sleep.validate()?;
        self.curve_pair.validate()?;
        self.solver.validate()
    }
}

/// When bodies go to sleep (docs/model.md §8, our choice). `Default` gives the documented defaults.
///
/// A body is *still* while `|v| + ρ |ω| ≤ speed` at the end of a step (ρ its radius, band
/// included: the fastest point of the body moves slower than `speed`). An island of touching
/// bodies that have all been still for `time` sleeps: its velocities are set to zero and it
/// costs nothing in any stage — to the bodies around it, it is static. It wakes when an awake
/// body touches it, when its state is changed between steps (through
/// [`Simulation::world_mut`]), when a body it touches is removed, or by
/// [`Simulation::wake`]. Like Box2D's `sleepThreshold` the speed is in m/s: scale it with the
/// scene (a millimetre-sized scene wants about `5e-5`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SleepSettings {
    /// Whether islands at rest sleep.
    pub enabled: bool,
    /// Speed below which a body counts as still (m/s, Box2D's default).
    pub speed: f64,
    /// Time an island must stay still before it sleeps (s, Box2D's default).
    pub time: f64,
}

impl Default for SleepSettings {
    fn default() -> Self {
        Self { enabled: true, speed: 0.05, time: 0.5 }
    }
}

impl SleepSettings {
    /// Sleeping switched off (every body stays awake).
    #[must_use]
    pub fn off() -> Self {
        Self { enabled: false, ..Self::default() }
    }

    /// Checks every setting against its domain.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field (`sleep.speed`, `sleep.time`).
    pub fn validate(&self) -> Result<(), SettingsError> {
        check_range("sleep.speed", self.speed, 0.0, f64::MAX)?;
        check_range("sleep.time", self.time, 0.0, f64::MAX)
    }
}

/// Low bits of a body handle's generation that count the reuse of its slot.
const REUSE_BITS: u32 = 12;

/// A tag for a new simulation: 1 to 2²⁰ − 1, in turn (after about a million simulations in one
/// process the tags repeat, and only then could two live simulations share one).
fn next_tag() -> u32 {
    use std::sync::atomic::{AtomicU32, Ordering};
    static NEXT: AtomicU32 = AtomicU32::new(0);
    NEXT.fetch_add(1, Ordering::Relaxed) % ((1 << (32 - REUSE_BITS)) - 1) + 1
}

/// Largest magnitude of gravity a simulation accepts (m/s², 10⁵ g).
pub const MAX_GRAVITY: f64 = 1e6;

/// How contacts are resolved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ContactModel {
    /// The iterated contact solver (MODEL §7a): collisions by the impulse law, resting contacts
    /// solved together by sequential impulses warm-started from the persistent manifold, shock
    /// propagation, and position error removed by split impulses. Bodies rest, stack and stick.
    #[default]
    Solver,
    /// The seed paper's model as written (MODEL §7): every resting contact is a micro-collision
    /// at `u_n = −√(2gδ)` with restitution `e_c(δ)`, resolved contact by contact. Resting bodies
    /// hop and creep; kept for the seed's experiments.
    SeedMicroCollisions,
}

/// Settings of the iterated contact solver. `Default` gives the documented defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// Most sequential-impulse sweeps over the resting contacts per sub-step; the sweeps stop
    /// earlier once converged (see `tolerance`).
    pub iterations: u32,
    /// Convergence test of the resting solve: it stops after the first sweep whose largest
    /// change of a contact's relative velocity `|Δu|` would move that contact by at most
    /// `tolerance` times its combined band over the sub-step, `|Δu| h ≤ tolerance (λ_A + λ_B)`.
    /// Relative to the band, so a scene's scale does not change what converged means.
    pub tolerance: f64,
    /// Sweeps of the split-impulse (position) pass per sub-step.
    pub position_iterations: u32,
    /// Whether the push-out pass ends with shock propagation (Guendelman et al. 2003): level by
    /// level from the ground up, each lower body held while the contacts above it are pushed
    /// out, so a level pushed out carries the levels above instead of being held down by them.
    /// (The velocity pass does not use it: holding bodies that the relaxation left moving
    /// carried their error up a pyramid and kept it creeping.)
    pub shock_propagation: bool,
    /// Depth in the band at which a contact rests, as a fraction of the combined band
    /// `λ_A + λ_B`: deeper contacts are pushed out to it (0.5: the band's middle).
    pub rest_depth: f64,
    /// Smallest push-out rate `β`: at least `β x / h` of an excess depth `x` is removed per
    /// sub-step (the seed's `e_c(δ) √(2 g x)` is used where larger).
    pub position_correction: f64,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            iterations: 100,
            tolerance: 1e-5,
            position_iterations: 4,
            shock_propagation: true,
            rest_depth: 0.5,
            position_correction: 0.2,
        }
    }
}

impl SolverSettings {
    /// Checks every setting against its domain.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field (`solver.iterations`, …).
    pub fn validate(&self) -> Result<(), SettingsError> {
        if self.iterations == 0 || self.iterations > 1000 {
            return Err(SettingsError::new("solver.iterations", self.iterations, "must lie in [1, 1000]"));
        }
        if self.position_iterations > 1000 {
            return Err(SettingsError::new(
                "solver.position_iterations",
                self.position_iterations,
                "must be at most 1000",
            ));
        }
        check_range("solver.tolerance", self.tolerance, 0.0, 1.0)?;
        check_range("solver.rest_depth", self.rest_depth, 0.0, 1.0)?;
        check_range("solver.position_correction", self.position_correction, 0.0, 1.0)
    }
}

/// Description of a body to spawn. The curve is given in its own frame; `position` and
/// `angle` place that frame in the world (the body's centre of mass is computed from it).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyDesc {
    /// Boundary curve in the body's own frame.
    pub spline: Spline,
    /// Per-segment tolerances.
    pub rugosity: Rugosity,
    /// Density, restitution and friction law.
    pub material: Material,
    /// World position of the curve's frame origin (m).
    pub position: DVec2,
    /// Orientation of the curve's frame (rad).
    pub angle: f64,
    /// Initial velocity of the centre of mass (m/s).
    pub linear_velocity: DVec2,
    /// Initial angular velocity (rad/s).
    pub angular_velocity: f64,
    /// A static body never moves.
    pub is_static: bool,
    /// A kinematic body moves at the velocity the user gives it, with infinite mass.
    pub is_kinematic: bool,
    /// Gravity scale, damping and fixed rotation (ignored for static bodies).
    pub motion: Motion,
    /// Which bodies it collides with (default: all).
    pub groups: CollisionGroups,
    /// A sensor reports what it touches (touch events) and never collides.
    pub sensor: bool,
    /// Optional name, used in errors and events.
    pub name: Option<String>,
}

impl BodyDesc {
    /// A dynamic body at rest at the origin with the default material.
    #[must_use]
    pub fn new(spline: Spline, rugosity: Rugosity) -> Self {
        Self {
            spline,
            rugosity,
            material: Material::default(),
            position: DVec2::ZERO,
            angle: 0.0,
            linear_velocity: DVec2::ZERO,
            angular_velocity: 0.0,
            is_static: false,
            is_kinematic: false,
            motion: Motion::default(),
            groups: CollisionGroups::ALL,
            sensor: false,
            name: None,
        }
    }

    /// Makes the body a sensor: it reports the bodies it touches and never collides.
    #[must_use]
    pub fn sensor(mut self) -> Self {
        self.sensor = true;
        self
    }

    /// Sets which bodies it collides with.
    #[must_use]
    pub fn with_groups(mut self, groups: CollisionGroups) -> Self {
        self.groups = groups;
        self
    }

    /// Sets the gravity scale, damping and fixed rotation.
    #[must_use]
    pub fn with_motion(mut self, motion: Motion) -> Self {
        self.motion = motion;
        self
    }

    /// Sets the material.
    #[must_use]
    pub fn with_material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// Places the curve's frame origin at `position`, rotated by `angle`.
    #[must_use]
    pub fn at(mut self, position: DVec2, angle: f64) -> Self {
        self.position = position;
        self.angle = angle;
        self
    }

    /// Sets the initial linear and angular velocity.
    #[must_use]
    pub fn with_velocity(mut self, linear: DVec2, angular: f64) -> Self {
        self.linear_velocity = linear;
        self.angular_velocity = angular;
        self
    }

    /// Makes the body kinematic: it moves at its velocity (the initial one, then what
    /// [`Simulation::set_velocity`] gives), with infinite mass.
    #[must_use]
    pub fn kinematic(mut self) -> Self {
        self.is_kinematic = true;
        self
    }

    /// Makes the body static.
    #[must_use]
    pub fn fixed(mut self) -> Self {
        self.is_static = true;
        self
    }

    /// Names the body.
    #[must_use]
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Checks the curve (including self-intersection), the rugosity and the material.
    ///
    /// # Errors
    /// A [`BodyError`] naming `label` and the reason.
    pub fn validate(&self, label: &BodyLabel) -> Result<(), BodyError> {
        let fail = |reason| BodyError { body: label.clone(), reason };
        self.spline.validate().map_err(fail)?;
        if let Some((first, second)) = find_self_intersection(&self.spline) {
            return Err(fail(crate::ShapeError::SelfIntersecting { first, second }));
        }
        self.rugosity.validate(self.spline.segment_count()).map_err(fail)?;
        self.material
            .validate()
            .map_err(|e| fail(crate::ShapeError::parameter(e.field.clone(), format!("{} ({})", e.reason, e.value))))?;
        let finite = [self.position.x, self.position.y, self.angle, self.linear_velocity.x, self.linear_velocity.y]
            .iter()
            .chain(std::iter::once(&self.angular_velocity))
            .all(|v| v.is_finite());
        if !finite {
            return Err(fail(crate::ShapeError::parameter(
                "initial state",
                "position, angle and velocities must be finite",
            )));
        }
        self.motion
            .validate()
            .map_err(|e| fail(crate::ShapeError::parameter(e.field.clone(), format!("{} ({})", e.reason, e.value))))?;
        if self.motion.fixed_rotation && !self.is_static && self.angular_velocity != 0.0 {
            return Err(fail(crate::ShapeError::parameter(
                "angular_velocity",
                "a body with fixed rotation does not turn: its angular velocity must be 0",
            )));
        }
        Ok(())
    }
}

/// The physics world and its step.
pub struct Simulation {
    world: World,
    settings: SimulationSettings,
    pool: Arc<rayon::ThreadPool>,
    pub(crate) bodies: Vec<BodyRecord>,
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
    profile: Profile,
    time: f64,
    next_spawn: u64,
    /// This simulation's tag in its bodies' handles (see `owned_entity`).
    tag: u32,
    /// Pairs of bodies that never collide ([`Simulation::exclude_pair`]).
    excluded: Vec<(Entity, Entity)>,
    accumulator: f64,
    stale: bool,
}

impl Simulation {
    /// A simulation with its own rayon pool of `settings.threads` workers.
    ///
    /// # Errors
    /// A [`SettingsError`] for an invalid setting, or if the pool cannot be built.
    pub fn new(settings: SimulationSettings) -> Result<Self, SettingsError> {
        settings.validate()?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .map_err(|e| SettingsError::new("threads", settings.threads, e.to_string()))?;
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
            step_bodies: Vec::new(),
            buffers: StepBuffers::default(),
            events,
            touch_events,
            touching: Vec::new(),
            touching_now: Vec::new(),
            touch_scratch: Vec::new(),
            profile: Profile::default(),
            time: 0.0,
            next_spawn: 0,
            tag: next_tag(),
            excluded: Vec::new(),
            accumulator: 0.0,
            stale: true,
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
        let order = SpawnOrder(self.next_spawn);
        self.next_spawn += 1;
        let entity = self.owned_entity();
        self.world.spawn_at(entity, (spline, desc.rugosity, tree, state, desc.material, mass, order, desc.groups));
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
        self.rebuild_body_table();
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
                let (a, b) = (pair.bodies.0 as usize, pair.bodies.1 as usize);
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
        self.bodies = systems::collect_bodies(&self.world, self.settings.min_band);
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
    /// A `dt` that is not finite and positive is ignored (the state is never made NaN).
    pub fn step(&mut self, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) || self.bodies.is_empty() {
            self.time += if dt.is_finite() && dt > 0.0 { dt } else { 0.0 };
            return;
        }
        let bodies = if self.settings.sleep.enabled {
            let start = Instant::now();
            let buffers = &mut self.buffers;
            let prepared = systems::sleep::prepare(
                &mut self.world,
                &self.bodies,
                &mut self.step_bodies,
                &mut buffers.wake_tags,
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
                self.buffers.previous_states.clear();
                let world = &self.world;
                self.buffers.previous_states.extend(
                    self.bodies.iter().map(|b| world.get::<&RigidState>(b.entity).map(|s| *s).unwrap_or_default()),
                );
                self.profile.counters.skipped_stages += 1;
                self.time += dt;
                self.profile.steps += 1;
                return;
            }
            &self.step_bodies
        } else {
            &self.bodies
        };
        let mut ctx = systems::StepContext {
            world: &mut self.world,
            settings: &self.settings,
            bodies,
            buffers: &mut self.buffers,
            events: &mut self.events,
            profile: &mut self.profile,
            pool: &self.pool,
            time: self.time,
        };
        let stale = std::mem::take(&mut self.stale);
        if self.pool.current_num_threads() > 1 {
            // The whole step runs on a worker of the pool, which then takes part in the
            // parallel stages: the caller's thread only waits, so the workers never compete
            // with it for the cores while the serial stages run, and one job enters the pool
            // per step rather than one per sub-step.
            self.pool.install(|| systems::run_step(&mut ctx, dt, stale));
            self.profile.counters.pool_jobs += 1;
        } else {
            systems::run_step(&mut ctx, dt, stale);
        }
        if self.buffers.woke_in_step {
            self.stale = true; // pairs of the woken bodies were not tested
        }
        self.time += dt;
        self.record_touches();
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
        while self.accumulator >= step {
            self.step(step);
            self.accumulator -= step;
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
        }
        Ok(())
    }
}

/// Whether `entity` carries the [`Static`] marker.
pub(crate) fn is_static(world: &World, entity: Entity) -> bool {
    world.get::<&Static>(entity).is_ok()
}
