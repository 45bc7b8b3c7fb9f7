//! Snapshots: the whole state of a simulation as plain data ([`Snapshot`], serde; RON text with
//! the `scene` feature), and [`Simulation::snapshot`], which takes one. A simulation restored
//! from a snapshot ([`Simulation::from_snapshot`], `restore.rs`) continues bit-identically.

use glam::DVec2;
use hecs::Entity;
use serde::{Deserialize, Serialize};

use super::{Simulation, SimulationSettings};
use crate::components::{
    AppliedForce, BodyName, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, Sleep, SpawnOrder, Static,
};
use crate::dynamics::mass::MassProperties;
use crate::dynamics::solver::CachedImpulse;
use crate::error::SnapshotError;
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::overlap::RecoveryContact;
use crate::geometry::query::{BodyQuery, LeafMemory, Manifold};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;
use crate::systems::{BodyRecord, Drift, PairSlot, SolvedAt, StepBuffers};

/// Version of the snapshot format this build writes and reads ([`Snapshot::version`]).
pub const SNAPSHOT_VERSION: u32 = 1;

/// The whole state of a [`Simulation`]: everything its future steps depend on, as plain data
/// (serde; [`Snapshot::to_ron`] and [`Snapshot::from_ron`] with the `scene` feature). Taken by
/// [`Simulation::snapshot`]; [`Simulation::from_snapshot`] checks it and restores a simulation
/// that continues bit-identically: the same states, events and touch events, step after step,
/// for any thread count.
///
/// **Saved:** the settings; the time and what [`Simulation::advance`] has accumulated; every
/// body with its handle, spawn order, name, curve, rugosity, material, state, kind (static,
/// kinematic, or dynamic with its motion settings, sleep state and the force applied for the
/// next step), collision groups and sensor flag; the excluded pairs; the pairs touching (for
/// begin and end events); and the step's memory ([`StepMemory`]: the last narrow phase's
/// contacts and gaps, each pair's memory of its leaf searches, the warm-start forces).
///
/// **Not saved:** the contact hook (a closure: install it again with
/// [`Simulation::set_contact_hook`]); the events not yet drained (drain them before taking the
/// snapshot: a restored simulation starts with empty event logs); the profile (it restarts);
/// components you added to the bodies yourself. A body's mass properties and AOBB tree are not
/// saved either: they are rebuilt from its curve, rugosity and material, bit for bit as
/// [`Simulation::add_body`] built them.
///
/// **Handles:** every body keeps its handle (`hecs::Entity`), so handles you stored are valid
/// in the restored simulation. Bodies added after restoring get handles of the restored
/// simulation's own tag, never one of the original's; they may differ from the handles the
/// original simulation would have given them.
///
/// The public fields may be read and edited (say `settings.threads`, which does not change
/// results); an edited snapshot is checked like any other. After moving a body in a snapshot,
/// set `needs_detection` (as [`Simulation::mark_moved`] does).
///
/// ```
/// use rugosa::glam::DVec2;
/// use rugosa::{BodyDesc, Generator, Rugosity, Simulation, SimulationSettings};
///
/// let mut sim = Simulation::new(SimulationSettings::default())?;
/// let disc = Generator::Circle { radius: 0.5 }.build(16)?;
/// let ball = sim.add_body(BodyDesc::new(disc, Rugosity::constant(16, 0.002)?).at(DVec2::new(0.0, 2.0), 0.0))?;
/// sim.step(1.0 / 120.0);
/// let mut copy = Simulation::from_snapshot(sim.snapshot()?)?;
/// sim.step(1.0 / 120.0);
/// copy.step(1.0 / 120.0);
/// assert_eq!(copy.state(ball), sim.state(ball)); // the same handle, the same bits
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Snapshot {
    /// Format version ([`SNAPSHOT_VERSION`]); another version is refused.
    pub version: u32,
    /// The settings in force.
    pub settings: SimulationSettings,
    /// Simulated time (s).
    pub time: f64,
    /// Frame time accumulated by [`Simulation::advance`] and not yet stepped (s, in
    /// `[0, time_step)`).
    pub accumulator: f64,
    /// Spawn order of the next body added.
    pub next_spawn: u64,
    /// Every body, in spawn order.
    pub bodies: Vec<BodySnapshot>,
    /// Pairs that never collide ([`Simulation::exclude_pair`]), `(a, b)` with `a < b`.
    pub excluded_pairs: Vec<(Entity, Entity)>,
    /// Pairs touching at the end of the last step, `(a, b)` with `a < b`, sorted.
    pub touching_pairs: Vec<(Entity, Entity)>,
    /// Whether contacts must be detected at the current poses before the next step (bodies
    /// added or removed, woken, or moved by the user since the last step); `step` then holds
    /// only the swept bounds and the interpolation states, and anything else in it is dropped.
    pub needs_detection: bool,
    /// The step's memory from one step to the next (the engine's internals).
    pub step: StepMemory,
}

/// One body of a [`Snapshot`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySnapshot {
    /// Its handle.
    pub entity: Entity,
    /// Its spawn sequence number ([`SpawnOrder`]): bodies are processed in this order.
    pub spawn_order: u64,
    /// The user's name ([`BodyName`]).
    pub name: Option<String>,
    /// Boundary curve in the body frame (centred on the centre of mass).
    pub spline: Spline,
    /// Per-segment tolerances.
    pub rugosity: Rugosity,
    /// Density, restitution and friction law.
    pub material: Material,
    /// Position, angle and velocities of the centre of mass.
    pub state: RigidState,
    /// Static, kinematic, or dynamic with its dynamic state.
    pub kind: BodyKind,
    /// Which bodies it collides with.
    pub groups: CollisionGroups,
    /// Whether it is a sensor.
    pub sensor: bool,
}

/// What kind of body, with what a dynamic body carries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum BodyKind {
    /// Never moves ([`Static`]).
    Static,
    /// Moves at its own velocity ([`Kinematic`]).
    Kinematic,
    /// Moved by gravity, forces and contacts.
    Dynamic {
        /// Gravity scale, damping and fixed rotation.
        motion: Motion,
        /// Still-time, island and the pose it fell asleep at.
        sleep: Sleep,
        /// Force and torque applied for the next step.
        applied: AppliedForce,
    },
}

/// What the step carries from one step to the next besides the bodies: the last refit's swept
/// bounds and margins, the last narrow phase's candidate pairs and, per pair, its contacts,
/// leaf gaps and memory of its leaf searches (temporal coherence: a recalled result differs
/// from a fresh search in the last bits, so it is saved, not redone), the contact hook's word
/// on the pair, the warm-start forces, and the states at the start of the last step (for
/// [`Simulation::interpolated_state`]). Everything else in the step's buffers is scratch,
/// rewritten before it is read, or a cache a restored simulation builds again from nothing (the
/// broad phase's enlarged boxes and their pairs, the pairs' reduced touches, the islands' inputs),
/// which gives the same results. The fields are the engine's internals: written and read
/// through serde only, and checked on restore. `Default` is an empty memory, valid with
/// `needs_detection` set.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepMemory {
    /// Per body slot: the world box swept by the motion margin, `(min, max)`.
    pub(crate) swept_bounds: Vec<(DVec2, DVec2)>,
    /// Per body slot: the motion margin of the last refit (m).
    pub(crate) margins: Vec<f64>,
    /// Candidate pairs of the last broad phase (body slots, `a < b`, sorted).
    pub(crate) candidate_pairs: Vec<(u32, u32)>,
    /// How many of `pairs` the last narrow phase filled.
    pub(crate) detected_pairs: usize,
    /// The narrow phase's pairs: the first `candidate_pairs.len()` are live, the first
    /// `detected_pairs` are remembered.
    pub(crate) pairs: Vec<PairMemory>,
    /// Forces of the last sub-step's contacts, sorted by key (warm start).
    pub(crate) contact_cache: Vec<CachedImpulse>,
    /// Per body slot: the state at the start of the last step.
    pub(crate) previous_states: Vec<RigidState>,
    /// Whether the last step was quiet: one sub-step, the whole step, no collision, every body
    /// that can move held by a resting contact (absent in older snapshots: the next step then
    /// takes the bound before its solve, as they did).
    #[serde(default)]
    pub(crate) quiet: bool,
    /// Per body slot: its position and angle at the last narrow phase, from which the next one
    /// measures how far it has moved (absent in older snapshots, or empty: the next phase then
    /// works out every carried pair's drift from its query's poses).
    #[serde(default)]
    pub(crate) phase_poses: Vec<(DVec2, f64)>,
}

/// One pair of the last narrow phase.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PairMemory {
    /// Body slots `(a, b)`, `a < b`.
    pub(crate) bodies: (u32, u32),
    /// Contacts, intersections and leaf gaps.
    pub(crate) manifold: Manifold,
    /// What its leaf searches proved, sorted by segments.
    pub(crate) leaves: Vec<LeafMemory>,
    /// The contact that pushes crossing curves apart.
    pub(crate) recovery: Option<RecoveryContact>,
    /// A sensor pair, or one the contact hook ignored.
    pub(crate) sensor: bool,
    /// A sensor pair with one body inside the other.
    pub(crate) contained: bool,
    /// Friction and restitution the contact hook set.
    pub(crate) modified: (Option<f64>, Option<f64>),
    /// Where the bodies were when the manifold was computed (absent in older snapshots).
    #[serde(default)]
    pub(crate) solved_at: Option<SolvedAt>,
    /// How far the bodies have moved since (m).
    #[serde(default)]
    pub(crate) drift: Drift,
    /// Whether the last narrow phase carried it.
    #[serde(default)]
    pub(crate) carried: bool,
    /// B's angle when its contacts were last evaluated (absent in older snapshots).
    #[serde(default)]
    pub(crate) evaluated_angle_b: Option<f64>,
    /// The bodies' positions and angles when its contacts were last evaluated again (absent in
    /// older snapshots).
    #[serde(default)]
    pub(crate) reused_at: Option<[(DVec2, f64); 2]>,
}

impl PairMemory {
    fn of(slot: &PairSlot) -> Self {
        Self {
            bodies: slot.bodies,
            manifold: slot.query.manifold.clone(),
            leaves: slot.query.memory.clone(),
            recovery: slot.recovery,
            sensor: slot.sensor,
            contained: slot.contained,
            modified: slot.modified,
            solved_at: slot.solved_at,
            drift: slot.drift,
            carried: slot.carried,
            evaluated_angle_b: slot.evaluated_angle_b,
            reused_at: slot.reused_at,
        }
    }

    /// The pair slot this memory describes (the query's scratch empty).
    fn into_slot(self) -> PairSlot {
        let mut query = BodyQuery::default();
        query.manifold = self.manifold;
        query.memory = self.leaves;
        PairSlot {
            bodies: self.bodies,
            query,
            recovery: self.recovery,
            sensor: self.sensor,
            contained: self.contained,
            modified: self.modified,
            solved_at: self.solved_at,
            drift: self.drift,
            carried: self.carried,
            evaluated_angle_b: self.evaluated_angle_b,
            reused_at: self.reused_at,
            ..PairSlot::default()
        }
    }
}

impl StepMemory {
    /// The memory in `buffers`; with `stale`, only what is read before contacts are detected
    /// again (the swept bounds, by the sleep stage; the interpolation states).
    fn of(buffers: &StepBuffers, stale: bool) -> Self {
        let mut memory = Self {
            swept_bounds: buffers.swept_bounds.clone(),
            previous_states: buffers.previous_states.clone(),
            ..Self::default()
        };
        if !stale {
            // A narrow phase with no candidate keeps the slots of the one before, and their
            // memory serves the next phase that has candidates.
            let remembered = buffers.candidate_pairs.len().max(buffers.detected_pairs).min(buffers.pair_slots.len());
            memory.margins.clone_from(&buffers.margins);
            memory.candidate_pairs.clone_from(&buffers.candidate_pairs);
            memory.detected_pairs = buffers.detected_pairs;
            memory.pairs = buffers.pair_slots[..remembered].iter().map(PairMemory::of).collect();
            memory.contact_cache.clone_from(&buffers.contact_cache);
            memory.quiet = buffers.quiet;
            memory.phase_poses.clone_from(&buffers.phase_poses);
        }
        memory
    }

    /// Writes the memory into fresh buffers (already checked against the bodies).
    pub(crate) fn into_buffers(self, buffers: &mut StepBuffers) {
        buffers.swept_bounds = self.swept_bounds;
        buffers.margins = self.margins;
        buffers.candidate_pairs = self.candidate_pairs;
        buffers.detected_pairs = self.detected_pairs;
        buffers.pair_slots = self.pairs.into_iter().map(PairMemory::into_slot).collect();
        buffers.intersecting_pairs = None; // counted again by the next narrow phase
        buffers.contact_cache = self.contact_cache;
        // Sorted by key, as the warm start walks it (a snapshot written by the engine already is).
        buffers.contact_cache.sort_unstable_by_key(|cached| cached.key);
        buffers.previous_states = self.previous_states;
        buffers.quiet = self.quiet;
        buffers.phase_poses = self.phase_poses;
    }
}

impl Simulation {
    /// The whole state of the simulation ([`Snapshot`]: what is saved and what is not).
    /// Between steps, any time; the simulation is not changed.
    ///
    /// # Errors
    /// [`SnapshotError::Broken`] for a body that lacks a component it needs or whose state is
    /// not finite (possible only through [`Simulation::world_mut`]).
    pub fn snapshot(&self) -> Result<Snapshot, SnapshotError> {
        let bodies = (0..self.bodies.len()).map(|slot| self.body_snapshot(slot)).collect::<Result<Vec<_>, _>>()?;
        Ok(Snapshot {
            version: SNAPSHOT_VERSION,
            settings: self.settings.clone(),
            time: self.time,
            accumulator: self.accumulator,
            next_spawn: self.next_spawn,
            bodies,
            excluded_pairs: self.excluded.clone(),
            touching_pairs: self.touching.clone(),
            needs_detection: self.stale,
            step: StepMemory::of(&self.buffers, self.stale),
        })
    }

    fn body_snapshot(&self, slot: usize) -> Result<BodySnapshot, SnapshotError> {
        let record: &BodyRecord = &self.bodies[slot];
        let entity = record.entity;
        let state: RigidState = self.component(slot)?;
        if !state.is_finite() {
            let reason = format!("its state is not finite: {state:?}");
            return Err(SnapshotError::Broken { body: self.label(slot), reason });
        }
        // What the step needs of every body (it rebuilds the last two on restore).
        self.component::<AobbTree>(slot)?;
        self.component::<MassProperties>(slot)?;
        let world = &self.world;
        let kind = if world.satisfies::<&Kinematic>(entity) {
            BodyKind::Kinematic
        } else if world.satisfies::<&Static>(entity) {
            BodyKind::Static
        } else {
            BodyKind::Dynamic {
                motion: self.component(slot)?,
                sleep: self.component(slot)?,
                applied: self.component(slot)?,
            }
        };
        Ok(BodySnapshot {
            entity,
            spawn_order: self.component::<SpawnOrder>(slot)?.0,
            name: world.get::<&BodyName>(entity).ok().map(|name| name.0.clone()),
            spline: self.component(slot)?,
            rugosity: self.component(slot)?,
            material: self.component(slot)?,
            state,
            kind,
            groups: world.get::<&CollisionGroups>(entity).map_or(CollisionGroups::default(), |g| *g),
            sensor: world.satisfies::<&Sensor>(entity),
        })
    }

    /// A copy of the body's component `T`, or the error naming the body and `T`.
    fn component<T: hecs::Component + Clone>(&self, slot: usize) -> Result<T, SnapshotError> {
        match self.world.get::<&T>(self.bodies[slot].entity) {
            Ok(component) => Ok((*component).clone()),
            Err(_) => {
                let name = std::any::type_name::<T>().rsplit("::").next().unwrap_or("component");
                Err(SnapshotError::Broken { body: self.label(slot), reason: format!("it has no `{name}` component") })
            }
        }
    }
}

#[cfg(feature = "scene")]
impl Snapshot {
    /// The snapshot as RON text.
    ///
    /// # Errors
    /// [`SnapshotError::Text`] if serialization fails (it does not for a snapshot
    /// [`Simulation::snapshot`] took).
    pub fn to_ron(&self) -> Result<String, SnapshotError> {
        let config = ron::ser::PrettyConfig::default().depth_limit(3);
        ron::ser::to_string_pretty(self, config).map_err(|e| SnapshotError::Text(e.to_string()))
    }

    /// Reads a snapshot from RON text. The text is only parsed here:
    /// [`Simulation::from_snapshot`] checks the values.
    ///
    /// # Errors
    /// [`SnapshotError::Text`] with the parser's message (line and column).
    pub fn from_ron(text: &str) -> Result<Self, SnapshotError> {
        // As scenes are read: a material's fields are optional (`Material`'s serde form).
        let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        options.from_str(text).map_err(|e| SnapshotError::Text(e.to_string()))
    }
}
