//! Settings of the dynamics: the world's, the contact solver's and sleeping's, each with its
//! documented defaults (one home per default) and a `validate` naming the field at fault.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::dynamics::impulse::ImpulseLaw;
use crate::error::{SettingsError, check_range};
use crate::geometry::curve_pair::CurvePairSettings;
use crate::geometry::query::QuerySettings;

/// Everything a user can set about the dynamics. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulationSettings {
    /// Gravity (m/s²); its magnitude is the `g` of micro-collisions.
    pub gravity: DVec2,
    /// Fixed step of [`Simulation::advance`](crate::Simulation::advance) (s).
    pub time_step: f64,
    /// Minimum half-width of every tolerance band (m): smooth bodies (R = 0) still need a band.
    pub min_band: f64,
    /// How many times a step may be halved (retry on intersection, and the floor of
    /// conservative advancement, `time_step / 2^depth`).
    pub max_retry_depth: u32,
    /// Most sub-steps conservative advancement may split one step into; the rest of a step
    /// that reaches it is taken at once (counted in the profile).
    pub max_substeps: u32,
    /// How deep into its combined band `λ_A + λ_B` conservative advancement lets a separate
    /// pair come before the sub-step ends, as a fraction of the band (docs/model.md §7, our
    /// choice): a sub-step stops every separate leaf pair short of the distance
    /// `(1 − approach_depth)(λ_A + λ_B)`. The deeper, the more of the impacts that fall close
    /// together in time are caught in one sub-step (a landing pile takes a fifth fewer); the
    /// impacts land that much deeper in the band, and a contact that collided and separates is
    /// pushed out only by what its separation leaves (§6 step 6). 0.5 (the band's middle,
    /// where contacts rest) was the engine's value until session 42. In [0.05, 0.9]: a pair
    /// stopped short of the band's edge by a shallow approach takes sub-step after sub-step to
    /// come into its band (each closes what is left by about 20 times).
    pub approach_depth: f64,
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
    /// How long (s) the pool's other workers keep looking for a step's parallel work while it
    /// runs serial stages, before they sleep (our choice; `src/simulation/workers.rs`). A
    /// sleeping worker takes tens of microseconds to wake, a dozen times a sub-step; spinning
    /// keeps them at hand, and costs their cores' idle time during the step only. 0 lets them
    /// sleep at once (rayon's own short spin), as a pool shared with other work may want. In
    /// [0, 1]; no effect on one thread or on any result.
    pub worker_spin: f64,
    /// How much work a step must have had for the next one to run on the pool's threads (our
    /// choice; `Simulation::step`, docs/model.md §7a): the last step's candidate pairs, leaf
    /// pairs and contacts, counted at each of its narrow phases. A step after a lighter one runs
    /// on the caller's thread alone, as on one thread: entering the pool wakes its workers, and
    /// stages split into parts that cost more to hand over than they take (two blobs in contact
    /// stepped in 0.006–0.009 ms on one thread and 0.013–0.045 ms on two; docs/performance.md).
    /// Once on the pool, steps stay there while their work keeps three quarters of this. The
    /// first step, the first after a restore and the first after every body slept run on the
    /// pool. 0 runs every step on the pool. No effect on one thread or on any result (every
    /// stage gives the same bits on any number of threads).
    pub min_parallel_work: u64,
    /// Whether every impulse is recorded in the event log.
    pub record_events: bool,
    /// Most events the log keeps between two [`Simulation::drain_events`](crate::Simulation::drain_events); later ones are
    /// dropped and counted (`StepCounters::dropped_events`), so a program that never drains
    /// the log stays within about `event_capacity × 200` bytes.
    pub event_capacity: usize,
    /// Most steps one [`Simulation::advance`](crate::Simulation::advance) call takes; the
    /// rest of a long frame is dropped and counted (`StepCounters::dropped_steps`), so a game
    /// that stalls does not fall into a spiral of ever longer frames (Bevy clamps its fixed
    /// time step likewise). ≥ 1.
    pub max_steps_per_advance: u32,
    /// Settings of the curve-pair solver.
    pub curve_pair: CurvePairSettings,
    /// Temporal coherence of the narrow phase (docs/model.md §3a, our choice): a leaf pair
    /// whose pieces have moved relative to each other by at most this fraction of their
    /// combined band since its last full search is answered from that search — a contact by
    /// Newton from the last answer's parameters, at most twice the motion above the true
    /// distance; a pair proven apart stays apart (also beyond this fraction, while it keeps
    /// half its clearance); a pair that could meet is always searched. A whole
    /// separate pair is carried without a query while its bodies move less than half its
    /// clearance (§3b). In [0, 0.1]; 0 queries every pair and searches every leaf pair in every
    /// sub-step.
    pub coherence: f64,
    /// Reuse of contacts (docs/model.md §3b, our choice): a pair in contact whose bodies have
    /// moved relative to each other by at most this fraction of its smallest combined band
    /// since its last query keeps that query's contacts, each evaluated again at the same
    /// curve parameters at the new poses (as rapier and Box2D keep a manifold while bodies
    /// barely move). The points then differ from the nearest ones by at most that motion, their
    /// distances by at most twice it; at the default 1e-4, 0.5 µm for a 5 mm band. (While the
    /// bodies move less than a thousandth of what the solver resolves, 1e-12 m for 5 mm bands,
    /// the contacts are not evaluated again.) In [0, 1e-3]; 0 queries every pair in contact in
    /// every sub-step.
    pub contact_reuse: f64,
    /// When bodies at rest go to sleep (docs/model.md §8, our choice).
    pub sleep: SleepSettings,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        Self {
            gravity: DVec2::new(0.0, -9.81),
            time_step: 1.0 / 120.0,
            min_band: QuerySettings::default().min_band,
            max_retry_depth: 8,
            max_substeps: 256,
            approach_depth: QuerySettings::default().approach_depth,
            impulse_law: ImpulseLaw::default(),
            contact_model: ContactModel::default(),
            solver: SolverSettings::default(),
            max_impulse_iterations: 16,
            resting_speed: 1e-3,
            threads: 0,
            worker_spin: 1e-3,
            min_parallel_work: 256,
            record_events: true,
            event_capacity: 1 << 16,
            max_steps_per_advance: 30,
            curve_pair: CurvePairSettings::default(),
            coherence: 1e-3,
            contact_reuse: 1e-4,
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
        check_range("time_step", self.time_step, MIN_STEP, MAX_STEP)?;
        if self.max_steps_per_advance == 0 {
            return Err(SettingsError::new("max_steps_per_advance", 0, "must be at least 1"));
        }
        check_range("min_band", self.min_band, f64::MIN_POSITIVE, 1e3)?;
        if self.max_retry_depth > 30 {
            return Err(SettingsError::new("max_retry_depth", self.max_retry_depth, "must be at most 30"));
        }
        if self.max_substeps == 0 {
            return Err(SettingsError::new("max_substeps", 0, "must be at least 1"));
        }
        check_range("approach_depth", self.approach_depth, MIN_APPROACH_DEPTH, 0.9)?;
        if self.max_impulse_iterations == 0 {
            return Err(SettingsError::new("max_impulse_iterations", 0, "must be at least 1"));
        }
        check_range("resting_speed", self.resting_speed, 0.0, f64::MAX)?;
        check_range("worker_spin", self.worker_spin, 0.0, 1.0)?;
        check_range("coherence", self.coherence, 0.0, 0.1)?;
        check_range("contact_reuse", self.contact_reuse, 0.0, 1e-3)?;
        self.sleep.validate()?;
        self.curve_pair.validate()?;
        self.solver.validate()
    }
}

/// The shallowest [`SimulationSettings::approach_depth`].
const MIN_APPROACH_DEPTH: f64 = 0.05;

/// When bodies go to sleep (docs/model.md §8, our choice). `Default` gives the documented defaults.
///
/// A body is *still* while `|v| + ρ |ω| ≤ speed` at the end of a step (ρ its radius, band
/// included: the fastest point of the body moves slower than `speed`). An island of touching
/// bodies that have all been still for `time` sleeps: its velocities are set to zero and it
/// costs nothing in any stage — to the bodies around it, it is static. It wakes when an awake
/// body touches it, when its state is changed between steps (through
/// [`Simulation::world_mut`](crate::Simulation::world_mut)), when a body it touches is removed, or by
/// [`Simulation::wake`](crate::Simulation::wake). Like Box2D's `sleepThreshold` the speed is in m/s: scale it with the
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

/// Shortest step a simulation takes (s): `time_step` and `step`'s argument.
pub const MIN_STEP: f64 = 1e-9;

/// Longest step a simulation takes (s): `time_step` and `step`'s argument.
pub const MAX_STEP: f64 = 10.0;

/// Largest coordinate of a body's position (m): beyond it f64 resolves less than 1e-9 m, below
/// the bands' scale (at 1e15 m a ball froze).
pub const MAX_COORDINATE: f64 = 1e7;

/// Largest speed of a body (m/s): 100 times the 10 km/s the tunnelling tests fire; at 1e300 the
/// kinetic energy was infinite.
pub const MAX_SPEED: f64 = 1e6;

/// Largest acceleration applied forces may give a body (m/s² and rad/s²; 10⁸ g).
pub const MAX_ACCELERATION: f64 = 1e9;

/// Largest angular speed of a body (rad/s).
pub const MAX_ANGULAR_SPEED: f64 = 1e6;

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
    /// earlier once converged (see `tolerance`), and an island with `L` levels resting on the
    /// ground after at most `max(30, 3 (L + 1))` of them, one not on the ground after 30
    /// (docs/model.md §7a).
    pub iterations: u32,
    /// Convergence test of the resting solve: it stops after the first sweep whose largest
    /// change of a contact's relative velocity `|Δu|` would move that contact by at most
    /// `tolerance` times its combined band over the sub-step, `|Δu| h ≤ tolerance (λ_A + λ_B)`.
    /// Relative to the band, so a scene's scale does not change what converged means. They
    /// stop no sooner than the deepest level resting on the ground plus one (a sweep passes a
    /// change of load one level down), unless every contact that pushes is found at rest at a
    /// block's end or after a subspace solve (docs/model.md §6 step 5).
    pub tolerance: f64,
    /// Conjugate-gradient iterations of each subspace solve of the resting solve; 0 turns the
    /// subspace solves off (sweeps alone). An island whose sweeps have not converged after every
    /// ten of them solves its contacts that stick (normals that push, frictions inside their
    /// cones) as equalities by preconditioned conjugate gradients, each step cut where a contact
    /// would leave its cone, and sweeps on; the iterations count as sweeps against `iterations`
    /// and the levels-plus-one minimum (docs/model.md §6 step 5).
    pub subspace_iterations: u32,
    /// Most sweeps of the split-impulse (position) pass per sub-step; the sweeps stop earlier
    /// once every contact is pushed out to within its allowance (see `position_tolerance`).
    pub position_iterations: u32,
    /// Convergence test of the push-out: its sweeps over an island stop after the first that
    /// leaves every contact moving apart at its push-out speed `v*` less at most the slack
    /// `s` (see `position_shortfall`), to within `position_tolerance` times its combined band
    /// over the sub-step: `(v* − u_n − s) h ≤ position_tolerance (λ_A + λ_B)`, with `u_n` the
    /// contact's relative pseudo-velocity along its normal. With both 0 the sweeps stop early
    /// only where every contact is already moving apart at its push-out speed. The push-out is
    /// skipped where no contact is deeper than the rest depth by more than this fraction of its
    /// band (docs/model.md §6 step 6).
    pub position_tolerance: f64,
    /// The push-out's slack, as a share of the island's largest push-out speed: how far a
    /// contact's pseudo-velocity may fall short of its own push-out speed when the sweeps stop
    /// (see `position_tolerance`). What a sub-step leaves undone is pushed at the next: with a
    /// share `ρ`, where every contact's push-out speed is its excess depth over the sub-step
    /// (the seed's speed reaches it for small excesses), the deepest excess falls to at most `ρ`
    /// of itself (plus the tolerance) each sub-step, to first order. A pile jammed around a few deep contacts, which the sweeps
    /// push out only slowly, then stops after a few sweeps instead of at its cap (docs/model.md
    /// §6 step 6). In `[0, 1]`.
    pub position_shortfall: f64,
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
            tolerance: 1e-7,
            subspace_iterations: 25,
            position_iterations: 64,
            position_tolerance: 1e-6,
            position_shortfall: 0.5,
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
        if self.subspace_iterations > 1000 {
            return Err(SettingsError::new(
                "solver.subspace_iterations",
                self.subspace_iterations,
                "must be at most 1000",
            ));
        }
        if self.position_iterations > 1000 {
            return Err(SettingsError::new(
                "solver.position_iterations",
                self.position_iterations,
                "must be at most 1000",
            ));
        }
        check_range("solver.tolerance", self.tolerance, 0.0, 1.0)?;
        check_range("solver.position_tolerance", self.position_tolerance, 0.0, 1.0)?;
        check_range("solver.position_shortfall", self.position_shortfall, 0.0, 1.0)?;
        check_range("solver.rest_depth", self.rest_depth, 0.0, 1.0)?;
        check_range("solver.position_correction", self.position_correction, 0.0, 1.0)
    }
}
