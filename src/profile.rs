//! Per-stage timing and machine-independent counters of a step.

use std::fmt;
use std::time::Duration;

/// How many stages there are (the profile's arrays are sized from it).
pub const STAGE_COUNT: usize = 17;

/// The stages of a step, in schedule order (see `systems/mod.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Read every body's state and applied force from the world before the step, and write
    /// the states back after it.
    GatherScatter,
    /// Conservative advancement: the sub-step's length from the pairs' gaps and the bodies'
    /// motion, and again for the solved velocities before the sub-step is taken.
    SubstepBound,
    /// Move bodies by the chosen sub-step.
    Integrate,
    /// Place every body's tree and swept bounds in the world.
    Refit,
    /// Candidate pairs from overlapping swept bounds.
    BroadPhase,
    /// Curve-pair contacts for each candidate pair.
    NarrowPhase,
    /// Collision impulses.
    Impulse,
    /// Micro-collisions of resting contacts (the seed's contact model).
    MicroCollision,
    /// Islands of touching bodies and each body's level above the static bodies.
    Islands,
    /// Solver contacts from the last narrow phase, warm-started from the manifold.
    PrepareContacts,
    /// The impulse law at contacts approaching faster than the resting threshold.
    Collide,
    /// Gravity acting on the velocities over the sub-step.
    Forces,
    /// Sequential impulses on resting contacts, then shock propagation.
    ContactSolver,
    /// Split impulses that push overdeep contacts out without kinetic energy.
    PositionCorrection,
    /// Keeping the states to redo a sub-step from, and testing after the motion whether a pair
    /// that was apart now crosses (the sub-step is then redone shorter).
    Retry,
    /// The accepted sub-step's contacts counted, their events recorded and their forces kept
    /// for the next warm start.
    Commit,
    /// Islands at rest fall asleep, sleeping ones touched or changed wake (once per step).
    Sleep,
}

impl Stage {
    /// Every stage, in schedule order.
    pub const ALL: [Stage; STAGE_COUNT] = [
        Stage::GatherScatter,
        Stage::SubstepBound,
        Stage::Integrate,
        Stage::Refit,
        Stage::BroadPhase,
        Stage::NarrowPhase,
        Stage::Impulse,
        Stage::MicroCollision,
        Stage::Islands,
        Stage::PrepareContacts,
        Stage::Collide,
        Stage::Forces,
        Stage::ContactSolver,
        Stage::PositionCorrection,
        Stage::Retry,
        Stage::Commit,
        Stage::Sleep,
    ];

    /// Snake-case name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Stage::GatherScatter => "gather_scatter",
            Stage::SubstepBound => "substep_bound",
            Stage::Integrate => "integrate",
            Stage::Refit => "refit",
            Stage::BroadPhase => "broad_phase",
            Stage::NarrowPhase => "narrow_phase",
            Stage::Impulse => "impulse",
            Stage::MicroCollision => "micro_collision",
            Stage::Islands => "islands",
            Stage::PrepareContacts => "prepare_contacts",
            Stage::Forces => "forces",
            Stage::Collide => "collide",
            Stage::ContactSolver => "contact_solver",
            Stage::PositionCorrection => "position_correction",
            Stage::Retry => "retry",
            Stage::Commit => "commit",
            Stage::Sleep => "sleep",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Counts that do not depend on the machine.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepCounters {
    /// Sub-steps taken (conservative advancement may split a step).
    pub substeps: u64,
    /// Sub-steps redone shorter because a pair intersected.
    pub retries: u64,
    /// Times the retry depth was exhausted and the intersecting bodies were held in place.
    pub retry_limit_hits: u64,
    /// Sub-steps that conservative advancement made shorter than the shortest retried sub-step.
    pub advancement_floor_hits: u64,
    /// Steps that reached `max_substeps` and took the rest of the step at once.
    pub substep_cap_hits: u64,
    /// Steps started without the sub-step bound of the velocities before the solve (the step
    /// before was quiet: one whole sub-step, no collision, every body that can move held by a
    /// resting contact): the solved velocities' bound alone chose their sub-steps.
    pub quiet_starts: u64,
    /// Narrow phases of a still structure that carried every pair by its drift budget (the
    /// pairs the last phase's, every body barely moved since); the others decided each pair.
    pub still_phases: u64,
    /// Contact preparations that refreshed the last one's contacts where they lie (the touch
    /// store kept, the bodies' masses, materials, levels and islands unchanged).
    pub refreshed_preparations: u64,
    /// Candidate pairs from the broad phase.
    pub candidate_pairs: u64,
    /// Broad phases that swept (a body's swept bounds had left its enlarged ones); the others
    /// filtered the pairs of the last sweep.
    pub broad_phase_sweeps: u64,
    /// Broad phases that kept the last filter's pairs: no swept bound had moved beyond the room
    /// of its decisions, and nothing its rules read had changed.
    pub broad_phase_kept: u64,
    /// OBB overlap tests in tree descent.
    pub box_tests: u64,
    /// Leaf pairs handed to the curve-pair solver.
    pub leaf_pairs: u64,
    /// Newton iterations of the curve-pair solver.
    pub newton_iterations: u64,
    /// Leaf pairs answered from the pair's memory instead of a search (temporal coherence,
    /// `SimulationSettings::coherence`).
    pub recalled_leaf_pairs: u64,
    /// Candidate pairs carried from their last query without one (a separate pair whose
    /// bodies have moved less than half its clearance and a quarter of its query margin,
    /// docs/model.md §3b).
    pub carried_pairs: u64,
    /// Of the carried pairs, those in contact whose contacts were reused: evaluated again at
    /// their last parameters, or kept as they were while their bodies had barely moved since
    /// (`SimulationSettings::contact_reuse`, docs/model.md §3b).
    pub reused_pairs: u64,
    /// Contacts found (within tolerance).
    pub contacts: u64,
    /// Collision impulses applied.
    pub impulses: u64,
    /// Micro-collision impulses applied.
    pub micro_collisions: u64,
    /// Sweeps of the collision loop.
    pub impulse_iterations: u64,
    /// Collision loops stopped by the iteration cap with a contact still approaching.
    pub impulse_cap_hits: u64,
    /// Stages skipped because they had nothing to do.
    pub skipped_stages: u64,
    /// Jobs handed to the worker pool: one per step run on it (more than one thread, and work
    /// enough in the step before, `SimulationSettings::min_parallel_work`), none on one thread.
    /// Rayon's job queue allocates a block of 63 entries about once per 63 jobs.
    pub pool_jobs: u64,
    /// Pairs found intersecting at the start of a sub-step (overlapping input or a teleport),
    /// counted once per sub-step; they are not retried.
    pub persistent_overlaps: u64,
    /// Resting contacts that carried an impulse of the iterated solver, per sub-step.
    pub resting_contacts: u64,
    /// Sweeps of the iterated solver (velocity and position passes).
    pub solver_iterations: u64,
    /// Sub-steps whose resting solve stopped at `solver.iterations` sweeps before meeting
    /// `solver.tolerance` (not converged: usual while bodies land, rare at rest).
    pub solver_unconverged: u64,
    /// Sub-steps whose push-out stopped at `solver.position_iterations` sweeps before every
    /// contact was within its allowance (`solver.position_tolerance` and
    /// `solver.position_shortfall`; what it left is pushed out at the next sub-step).
    pub push_out_unconverged: u64,
    /// Sweeps of the push-out (the most any island took, per sub-step that ran it), in all; also
    /// counted in `solver_iterations`.
    pub push_out_sweeps: u64,
    /// Conjugate-gradient iterations of the resting solve's subspace solves, over all islands
    /// (each is also counted as a sweep of its island in `solver_iterations`).
    pub subspace_iterations: u64,
    /// Contacts (or patches) a subspace solve's step reached the cone of, held there and left to
    /// the sweeps, over all islands.
    pub subspace_holds: u64,
    /// Of `subspace_iterations`, those of solves large enough to split every pass into two
    /// halves (on two threads when the pool has them and the split gains; docs/model.md §6
    /// step 5).
    pub subspace_halves: u64,
    /// Islands of touching dynamic bodies, per sub-step.
    pub islands: u64,
    /// Sub-steps whose largest island's sweeps two threads shared as a wavefront (only with
    /// more than one thread; the results are the same as one thread's).
    pub wavefront_solves: u64,
    /// Of those solves' sweeps, the ones whose upper runs the second thread swept (it joins
    /// at the first sweep it finds handed over; the rest the solve's thread sweeps alone).
    pub wavefront_shared_sweeps: u64,
    /// Overlap-recovery contacts of pairs whose curves cross at a sub-step start.
    pub recovery_contacts: u64,
    /// Sub-steps shortened after the solve because the solved velocities outran the bound the
    /// sub-step was chosen with (the solve is then redone; not a retry).
    pub bound_shrinks: u64,
    /// Impulse-law errors (a contact the law could not resolve); counted, never dropped silently.
    pub impulse_errors: u64,
    /// Bodies found broken at the start of a step, once per step they stay broken: a component
    /// removed or a non-finite state written through `Simulation::world_mut` (the state is then
    /// replaced by the body's last good one; a body without its geometry collides with nothing).
    pub broken_bodies: u64,
    /// Values the contact hook returned outside their ranges (a negative or non-finite
    /// friction, a restitution outside [0, 1]): not used, the materials' stand.
    pub rejected_hook_values: u64,
    /// Events not recorded because the log held `event_capacity` undrained events.
    pub dropped_events: u64,
    /// Calls of `Simulation::step` refused for a `dt` outside its range (nothing changed).
    pub refused_steps: u64,
    /// Steps `Simulation::advance` dropped from frames longer than `max_steps_per_advance`
    /// steps.
    pub dropped_steps: u64,
    /// Sleeping dynamic bodies, per step.
    pub sleeping_bodies: u64,
    /// Bodies woken (by touch, by a change of their state, by removal of a body they touched,
    /// or by `Simulation::wake`).
    pub woken_bodies: u64,
}

impl StepCounters {
    /// The work these counters count as [`SimulationSettings::min_parallel_work`] measures a
    /// step's: candidate pairs, leaf pairs and contacts, counted at each narrow phase (one a
    /// sub-step, and one more for a retried sub-step or a stale step's first detection).
    ///
    /// [`SimulationSettings::min_parallel_work`]: crate::SimulationSettings::min_parallel_work
    #[must_use]
    pub fn work(&self) -> u64 {
        self.candidate_pairs + self.leaf_pairs + self.contacts
    }

    /// Adds `other` into `self`.
    pub fn accumulate(&mut self, other: &StepCounters) {
        self.substeps += other.substeps;
        self.retries += other.retries;
        self.retry_limit_hits += other.retry_limit_hits;
        self.advancement_floor_hits += other.advancement_floor_hits;
        self.substep_cap_hits += other.substep_cap_hits;
        self.candidate_pairs += other.candidate_pairs;
        self.quiet_starts += other.quiet_starts;
        self.still_phases += other.still_phases;
        self.wavefront_solves += other.wavefront_solves;
        self.wavefront_shared_sweeps += other.wavefront_shared_sweeps;
        self.refreshed_preparations += other.refreshed_preparations;
        self.broad_phase_sweeps += other.broad_phase_sweeps;
        self.broad_phase_kept += other.broad_phase_kept;
        self.box_tests += other.box_tests;
        self.leaf_pairs += other.leaf_pairs;
        self.newton_iterations += other.newton_iterations;
        self.recalled_leaf_pairs += other.recalled_leaf_pairs;
        self.carried_pairs += other.carried_pairs;
        self.reused_pairs += other.reused_pairs;
        self.contacts += other.contacts;
        self.impulses += other.impulses;
        self.micro_collisions += other.micro_collisions;
        self.impulse_iterations += other.impulse_iterations;
        self.impulse_cap_hits += other.impulse_cap_hits;
        self.skipped_stages += other.skipped_stages;
        self.pool_jobs += other.pool_jobs;
        self.persistent_overlaps += other.persistent_overlaps;
        self.resting_contacts += other.resting_contacts;
        self.solver_iterations += other.solver_iterations;
        self.solver_unconverged += other.solver_unconverged;
        self.push_out_unconverged += other.push_out_unconverged;
        self.push_out_sweeps += other.push_out_sweeps;
        self.subspace_iterations += other.subspace_iterations;
        self.subspace_holds += other.subspace_holds;
        self.subspace_halves += other.subspace_halves;
        self.islands += other.islands;
        self.recovery_contacts += other.recovery_contacts;
        self.impulse_errors += other.impulse_errors;
        self.broken_bodies += other.broken_bodies;
        self.rejected_hook_values += other.rejected_hook_values;
        self.bound_shrinks += other.bound_shrinks;
        self.dropped_events += other.dropped_events;
        self.refused_steps += other.refused_steps;
        self.dropped_steps = self.dropped_steps.saturating_add(other.dropped_steps);
        self.sleeping_bodies += other.sleeping_bodies;
        self.woken_bodies += other.woken_bodies;
    }
}

/// Wall time per stage and counters, for one step or accumulated over many.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Profile {
    stage_time: [Duration; STAGE_COUNT],
    stage_runs: [u64; STAGE_COUNT],
    /// Machine-independent counts.
    pub counters: StepCounters,
    /// Steps covered by this profile.
    pub steps: u64,
}

impl Profile {
    /// Adds `elapsed` to `stage`.
    pub fn record(&mut self, stage: Stage, elapsed: Duration) {
        self.stage_time[stage.index()] += elapsed;
        self.stage_runs[stage.index()] += 1;
    }

    /// Total time spent in `stage`.
    #[must_use]
    pub fn time(&self, stage: Stage) -> Duration {
        self.stage_time[stage.index()]
    }

    /// How many times `stage` ran.
    #[must_use]
    pub fn runs(&self, stage: Stage) -> u64 {
        self.stage_runs[stage.index()]
    }

    /// Sum of all stage times.
    #[must_use]
    pub fn total(&self) -> Duration {
        self.stage_time.iter().sum()
    }

    /// Adds another profile into this one.
    pub fn accumulate(&mut self, other: &Profile) {
        for stage in Stage::ALL {
            self.stage_time[stage.index()] += other.stage_time[stage.index()];
            self.stage_runs[stage.index()] += other.stage_runs[stage.index()];
        }
        self.counters.accumulate(&other.counters);
        self.steps += other.steps;
    }
}

impl fmt::Display for Profile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let steps = self.steps.max(1) as f64;
        writeln!(f, "{:<16} {:>12} {:>8}", "stage", "µs/step", "share")?;
        let total = self.total().as_secs_f64().max(f64::MIN_POSITIVE);
        for stage in Stage::ALL.into_iter().filter(|&s| self.runs(s) > 0) {
            let t = self.time(stage).as_secs_f64();
            writeln!(f, "{:<16} {:>12.2} {:>7.1}%", stage.name(), 1e6 * t / steps, 100.0 * t / total)?;
        }
        write!(f, "{:<16} {:>12.2}", "total", 1e6 * total / steps)
    }
}
