//! Island by island solves of the solver contacts' sweeps, shared by the contact solver (the
//! resting solve, until converged) and the push-out (the split impulses' sweeps, until every
//! contact is pushed out to within its allowance): the islands in parallel, each on its own copy
//! of its bodies' velocities, and the largest on two threads as a wavefront; the resting
//! solve's sweeps in blocks, each island that has not converged by the end of a block solving
//! the contacts that stick by conjugate gradients in between (`subspace.rs`). Not a system: the
//! two systems that sweep call it.

use super::SolverIsland;
use super::islands::UNGROUNDED;
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{
    Accumulator, IslandVelocities, PairVelocities, Pass, SolverContact, row_velocity, sweep,
};
use crate::simulation::SolverSettings;
use halves::Lent;
use subspace::Settled;
pub(crate) use subspace::{Scratch, ScratchBuffers};
pub(crate) use wavefront::Runs;

mod halves;
mod subspace;
mod wavefront;

/// What the islands' solves came to: the most sweeps any took (a subspace solve's iterations
/// counted as sweeps), how many stopped at the cap, and the subspace solves' iterations and the
/// units they held at their cones, in all.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Outcome {
    pub(crate) most_sweeps: u32,
    pub(crate) unconverged: u32,
    pub(crate) subspace_iterations: u64,
    pub(crate) subspace_holds: u64,
    pub(crate) subspace_halves: u64,
    /// Sweeps whose upper runs a wavefront's helper swept (`wavefront.rs`).
    pub(crate) wavefront_shared_sweeps: u64,
}

/// Solves `islands`, whose contacts and velocities are exactly `contacts` and `velocities`, by
/// halves (of their contacts) joined on the pool when `parallel`: no allocation, and each
/// island's own solve the same whichever thread runs it.
pub(crate) fn solve_islands(lanes: Lanes<'_>, islands: &[SolverIsland], sweeps: Sweeps<'_>, parallel: bool) -> Outcome {
    match islands {
        [] => Outcome::default(),
        [_] => {
            let rule = sweeps.rule(lanes.contacts);
            solve_blocks(lanes, rule)
        }
        [first, .., last] => {
            let middle = (first.contacts.0 + last.contacts.1) / 2;
            let half = islands.partition_point(|island| island.contacts.0 < middle).clamp(1, islands.len() - 1);
            let (left, right) = islands.split_at(half);
            let (left_lanes, right_lanes) = lanes.split(*first, right[0]);
            let solve_left = move || solve_islands(left_lanes, left, sweeps, parallel);
            let solve_right = move || solve_islands(right_lanes, right, sweeps, parallel);
            let (a, b) = if parallel && contacts_len(islands) >= PARALLEL_CONTACTS {
                rayon::join(solve_left, solve_right)
            } else {
                (solve_left(), solve_right())
            };
            Outcome {
                most_sweeps: a.most_sweeps.max(b.most_sweeps),
                unconverged: a.unconverged + b.unconverged,
                subspace_iterations: a.subspace_iterations + b.subspace_iterations,
                subspace_holds: a.subspace_holds + b.subspace_holds,
                subspace_halves: a.subspace_halves + b.subspace_halves,
                wavefront_shared_sweeps: a.wavefront_shared_sweeps + b.wavefront_shared_sweeps,
            }
        }
    }
}

/// What an island's sweeps solve and when they stop ([`StopRule`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Sweeps<'a> {
    /// The resting solve at these settings, over a sub-step `h`: until converged or capped.
    Resting(&'a SolverSettings, f64),
    /// The push-out at these settings, over a sub-step `h`: its split impulses' sweeps until
    /// every contact is within its allowance of its push (`position_tolerance`,
    /// `position_shortfall`) or `position_iterations` of them.
    PushOut(&'a SolverSettings, f64),
}

impl Sweeps<'_> {
    /// The rule of the island of `contacts`.
    fn rule(self, contacts: &[SolverContact]) -> StopRule {
        match self {
            Self::Resting(settings, h) => StopRule::new(contacts, settings, h),
            Self::PushOut(settings, h) => StopRule::push_out(contacts, settings, h),
        }
    }
}

/// Fewer contacts than this are not split between threads (a join costs more than they do).
const PARALLEL_CONTACTS: usize = 64;

/// What a part of the islands' solve owns: their contacts and velocities, if the wavefront
/// island is among them, its first contact (in `solver_contacts`) and runs, and the subspace
/// solves' scratch (none for the push-out).
pub(crate) struct Lanes<'a> {
    pub(crate) contacts: &'a mut [SolverContact],
    pub(crate) velocities: &'a mut [BodyVelocity],
    pub(crate) wavefront: Option<(usize, &'a mut Runs)>,
    pub(crate) scratch: Option<Scratch<'a>>,
}

impl<'a> Lanes<'a> {
    /// The lanes of the islands before `right` (which start at `first`'s contacts and bodies)
    /// and of those from `right` on.
    fn split(self, first: SolverIsland, right: SolverIsland) -> (Self, Self) {
        let (left_contacts, right_contacts) = self.contacts.split_at_mut(right.contacts.0 - first.contacts.0);
        let (left_velocities, right_velocities) = self.velocities.split_at_mut(right.bodies.0 - first.bodies.0);
        let (left_wavefront, right_wavefront) = match self.wavefront {
            Some((start, runs)) if start >= right.contacts.0 => (None, Some((start, runs))),
            other => (other, None),
        };
        let (left_scratch, right_scratch) = match self.scratch {
            Some(scratch) => {
                let (left, right) = scratch.split(right.contacts.0 - first.contacts.0, right.bodies.0 - first.bodies.0);
                (Some(left), Some(right))
            }
            None => (None, None),
        };
        (
            Self {
                contacts: left_contacts,
                velocities: left_velocities,
                wavefront: left_wavefront,
                scratch: left_scratch,
            },
            Self {
                contacts: right_contacts,
                velocities: right_velocities,
                wavefront: right_wavefront,
                scratch: right_scratch,
            },
        )
    }
}

/// The largest island, with its runs built, if it is to be solved as a wavefront
/// ([`wavefront::Runs::build`]).
pub(crate) fn wavefront_island<'a>(
    islands: &[SolverIsland],
    contacts: &[SolverContact],
    runs: &'a mut Runs,
) -> Option<(usize, &'a mut Runs)> {
    let largest = islands.iter().max_by_key(|island| island.contacts.1 - island.contacts.0)?;
    let (start, end) = largest.contacts;
    runs.build(&contacts[start..end], largest.bodies.1 - largest.bodies.0).then_some((start, runs))
}

fn contacts_len(islands: &[SolverIsland]) -> usize {
    islands.last().map_or(0, |last| last.contacts.1) - islands.first().map_or(0, |first| first.contacts.0)
}

/// One island's solve: its sweeps (on two threads for the wavefront island) until converged or
/// capped, in blocks of [`SUBSPACE_PERIOD`] when the rule has subspace iterations and scratch
/// is given, an island that has not converged by the end of a block then solving the contacts
/// that stick by conjugate gradients (`subspace.rs`) before the next, if the cap leaves room for
/// its iterations. The blocks and what is done between them are the same whichever thread, and
/// however many, runs the sweeps. A block's end where the subspace solve would take no
/// iteration (`subspace::settled`) changes nothing, so the sweeps test for it themselves and
/// go on ([`StopRule::checks_after`]): the wavefront island's threads then keep their pipeline
/// full across it, and meet once for all its blocks, the helper serving the subspace solves'
/// halves while the solve's thread does them (`halves::Lent`).
fn solve_blocks(lanes: Lanes<'_>, rule: StopRule) -> Outcome {
    let Lanes { contacts, velocities, wavefront, scratch } = lanes;
    let scratch = scratch.filter(|_| rule.subspace > 0);
    let rule = StopRule { period: if scratch.is_some() { SUBSPACE_PERIOD } else { 0 }, ..rule };
    match wavefront {
        Some((_, runs)) => wavefront::solve(contacts, velocities, runs, rule, |island| blocks(island, rule, scratch)),
        None => blocks(&mut OneThread { contacts, velocities }, rule, scratch),
    }
}

/// An island's sweeps, by one thread ([`OneThread`]) or two (`wavefront::Lower`), and the
/// island itself between them.
trait Sweeper {
    /// The island's sweeps under `rule` (a stretch's: [`StopRule::after`]), until converged,
    /// capped, or at a block's end where a subspace solve would change the island
    /// ([`StopRule::checks_after`]).
    fn sweep(&mut self, rule: StopRule) -> Outcome;
    /// The island's contacts and velocities, between the sweeps, and the thread waiting beside
    /// this one, if any, to help its subspace solves.
    fn island(&mut self) -> (&mut [SolverContact], &mut [BodyVelocity], Option<&Lent>);
}

/// An island swept by one thread ([`solve_island`]).
struct OneThread<'a> {
    contacts: &'a mut [SolverContact],
    velocities: &'a mut [BodyVelocity],
}

impl Sweeper for OneThread<'_> {
    fn sweep(&mut self, rule: StopRule) -> Outcome {
        solve_island(self.contacts, self.velocities, rule)
    }

    fn island(&mut self) -> (&mut [SolverContact], &mut [BodyVelocity], Option<&Lent>) {
        (self.contacts, self.velocities, None)
    }
}

/// The blocks of [`solve_blocks`] by `island`'s sweeps: sweeps until converged, capped, or the
/// end of a block whose island a subspace solve would change, then that subspace solve, and
/// again; one run of sweeps under the whole `rule` without `scratch`.
fn blocks(island: &mut impl Sweeper, rule: StopRule, scratch: Option<Scratch<'_>>) -> Outcome {
    let Some(mut scratch) = scratch else {
        return island.sweep(rule);
    };
    let mut done = Outcome::default();
    // Whether a subspace solve has left the island at rest (`Solved::at_rest`).
    let mut at_rest = false;
    loop {
        let swept = island.sweep(rule.after(done.most_sweeps, at_rest));
        done.most_sweeps += swept.most_sweeps;
        done.wavefront_shared_sweeps += swept.wavefront_shared_sweeps;
        if swept.unconverged == 0 {
            return done;
        }
        if done.most_sweeps >= rule.cap {
            done.unconverged = 1;
            return done;
        }
        // The sweeps stopped at the end of a block whose island a subspace solve changes: the
        // cap leaves room for its iterations (`StopRule::checks_after`).
        debug_assert!(done.most_sweeps + rule.subspace < rule.cap, "{done:?} of {rule:?}");
        let (contacts, velocities, lent) = island.island();
        let solved = subspace::solve(
            contacts,
            velocities,
            &mut scratch,
            (rule.subspace, rule.accumulator),
            (rule.tolerance, rule.h),
            lent,
        );
        done.most_sweeps += solved.iterations;
        at_rest |= solved.at_rest;
        done.subspace_iterations += u64::from(solved.iterations);
        done.subspace_holds += u64::from(solved.held);
        if solved.halves {
            done.subspace_halves += u64::from(solved.iterations);
        }
    }
}

/// One island's sweeps until converged: the last sweep's largest change would move no contact
/// by more than `tolerance` of its band over the sub-step — and never fewer sweeps than the
/// island has levels. A sweep passes a change of load one level down (the contacts run from
/// the ground up), so until then a change at the top has not reached the ground; the small
/// changes a still structure sees at every sub-step stay below the tolerance, and left
/// unresolved they let a tall stack bend a little more each sub-step (a stack of 20 boxes
/// tilted exponentially with one sweep per sub-step: tests/resting.rs). A sweep whose change
/// times the levels plus one stays within [`STILL_FRACTION`] of the tolerance ends the solve
/// before that: what it leaves to pass down is far below what the solver resolves (a body
/// holding up several others, or a lighter one, can pass on a larger change than it got, but
/// not by the 1e5 this leaves). An island that converges stops there, whatever the others
/// still need; one that does not stops at its cap ([`SHALLOW_SWEEPS`]) and is counted
/// unconverged, as it is where it stops at the end of a block for a subspace solve
/// ([`StopRule::checks_after`]). The push-out's sweeps test what they leave undone instead of
/// their change ([`StopRule::push_out`]).
fn solve_island(contacts: &mut [SolverContact], velocities: &mut [BodyVelocity], rule: StopRule) -> Outcome {
    let mut velocities = IslandVelocities(velocities);
    let mut sweeps = 0;
    while sweeps < rule.cap {
        let change = match rule.accumulator {
            Accumulator::Velocity => relax(contacts, &mut velocities, Accumulator::Velocity),
            Accumulator::Split => {
                relax(contacts, &mut velocities, Accumulator::Split);
                shortfall(contacts, &velocities, rule.slack)
            }
        };
        sweeps += 1;
        if rule.converged(sweeps, change) {
            return Outcome { most_sweeps: sweeps, unconverged: 0, ..Outcome::default() };
        }
        if rule.checks_after(sweeps) {
            let settled = rule.settled(contacts, (velocities.0, 0));
            if rule.ends_at_rest(settled, change) {
                return Outcome { most_sweeps: sweeps, unconverged: 0, ..Outcome::default() };
            }
            if settled == Settled::No {
                break;
            }
        }
    }
    Outcome { most_sweeps: sweeps, unconverged: 1, ..Outcome::default() }
}

/// What the push-out's sweeps leave undone at `contacts`, in the units of a sweep's change (a
/// relative velocity per metre of band): the largest of each contact's shortfall of its push
/// less `slack`, `(v* − u_n − slack) / (λ_A + λ_B)`, with `u_n` its relative pseudo-velocity
/// along the normal now and `v*` its push-out speed. Within the push-out's tolerance, every
/// contact moves apart at its push-out speed less at most `slack`, to within the tolerance.
pub(super) fn shortfall<V: PairVelocities + ?Sized>(contacts: &[SolverContact], velocities: &V, slack: f64) -> f64 {
    contacts.iter().filter(|c| c.band > 0.0).fold(0.0, |most, c| {
        let (a, b) = velocities.pair(c);
        let u_n = row_velocity(c.normal, c.normal_arms, &a, &b);
        most.max((c.bias_speed - u_n - slack) / c.band)
    })
}

/// One relaxing sweep of `which`'s impulses. Each arm passes its accumulator as a constant, so
/// the sweep inlined there is specialised to it: with the accumulator read at run time, the
/// resting solve of the settling base-20 pyramid took 4 % more instructions.
#[inline(always)]
pub(super) fn relax<V: PairVelocities + ?Sized>(
    contacts: &mut [SolverContact],
    velocities: &mut V,
    which: Accumulator,
) -> f64 {
    match which {
        Accumulator::Velocity => sweep(contacts, velocities, Accumulator::Velocity, Pass::Relax),
        Accumulator::Split => sweep(contacts, velocities, Accumulator::Split, Pass::Relax),
    }
}

/// Which impulses an island's sweeps solve and when they stop (see [`solve_island`]): the level
/// count, the cap and the tolerance (the push-out's: no level minimum, its own cap, tolerance
/// and slack, and its test on what the sweeps leave undone rather than on their change). One
/// home for the serial solve and the wavefront's.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StopRule {
    /// Sweeps an island needs before a change within the tolerance ends it: its levels plus one.
    min_sweeps: u32,
    /// Sweeps after which it stops unconverged.
    cap: u32,
    /// `SolverSettings::tolerance`.
    tolerance: f64,
    /// The sub-step (s).
    h: f64,
    /// Which impulses the sweeps solve: the resting solve's or the push-out's.
    accumulator: Accumulator,
    /// Sweeps (and subspace iterations) done before this rule's first sweep: a block's rule
    /// counts on from them ([`StopRule::after`]).
    before: u32,
    /// Conjugate-gradient iterations of each subspace solve (`SolverSettings::subspace_iterations`;
    /// 0 for the push-out).
    subspace: u32,
    /// Sweeps between the subspace solves ([`SUBSPACE_PERIOD`]); 0 where there are none.
    period: u32,
    /// The push-out's slack (m/s): `position_shortfall` of the island's largest push-out speed,
    /// the most a contact's pseudo-velocity may fall short of its own when the sweeps stop (0
    /// for the resting solve).
    slack: f64,
}

impl StopRule {
    fn new(contacts: &[SolverContact], settings: &SolverSettings, h: f64) -> Self {
        let grounded = contacts.iter().map(|c| c.level).filter(|&level| level != UNGROUNDED);
        let min_sweeps = grounded.max().map_or(1, |level| level + 1).min(settings.iterations);
        let cap = settings.iterations.min(SHALLOW_SWEEPS.max(SWEEPS_PER_LEVEL * min_sweeps));
        let (tolerance, subspace) = (settings.tolerance, settings.subspace_iterations);
        let accumulator = Accumulator::Velocity;
        Self { min_sweeps, cap, tolerance, h, accumulator, before: 0, subspace, period: 0, slack: 0.0 }
    }

    /// The rule of the sweeps after `before` sweeps and subspace iterations: up to the cap, and
    /// converged as the whole solve would be; blocks of [`period`](Self::period) from here. Where
    /// a subspace solve has left the island `at_rest` ([`Settled::AtRest`]), its level minimum
    /// counts as met: the next sweep within the tolerance ends the solve.
    fn after(self, before: u32, at_rest: bool) -> Self {
        let counted = if at_rest { before.max(self.min_sweeps) } else { before };
        Self { cap: self.cap - before, before: counted, ..self }
    }

    /// Whether the sweeps stop after their `sweeps`-th (not converged, and short of the cap)
    /// where a subspace solve would change the island then ([`StopRule::settled`]): at the end
    /// of each block of [`period`](Self::period) sweeps where the cap leaves room for the subspace
    /// solve's iterations.
    fn checks_after(&self, sweeps: u32) -> bool {
        self.period > 0 && sweeps.is_multiple_of(self.period) && sweeps + self.subspace < self.cap
    }

    /// Whether a subspace solve would leave `contacts` (all or some runs of an island, whose
    /// bodies from the island-relative index `base` on are `velocities`) as they are, and whether
    /// their pushing contacts are at rest ([`Settled`]).
    fn settled(&self, contacts: &[SolverContact], velocities: (&[BodyVelocity], u32)) -> Settled {
        subspace::settled(contacts, velocities, self.accumulator, (self.tolerance, self.h))
    }

    /// The push-out's split impulses of the island of `contacts`: sweeps until the first after
    /// which every contact moves apart at its push-out speed less at most the slack (a share
    /// `position_shortfall` of the island's largest push-out speed), to within
    /// `position_tolerance` of its band over the sub-step ([`shortfall`]); at most
    /// `position_iterations`, no level minimum and no subspace solve. What the sweeps leave
    /// undone leaves a contact a little too deep, gives no body a velocity, and is pushed at the
    /// next sub-step; the slack lets them stop where a pile is jammed, pushing one contact out
    /// into the others (a slow mode of the sweeps, docs/model.md §6 step 6), and a test on what
    /// is left undone rather than on a sweep's change keeps them going where a slow mode leaves
    /// much undone with little change (a row of boxes set down too deep).
    fn push_out(contacts: &[SolverContact], settings: &SolverSettings, h: f64) -> Self {
        let (cap, tolerance) = (settings.position_iterations, settings.position_tolerance);
        let fastest = contacts.iter().map(|c| c.bias_speed).fold(0.0, f64::max);
        let slack = settings.position_shortfall * fastest;
        let accumulator = Accumulator::Split;
        Self { min_sweeps: 1, cap, tolerance, h, accumulator, before: 0, subspace: 0, period: 0, slack }
    }

    /// Whether the solve ends converged after its `sweeps`-th sweep, which changed `change` (the
    /// push-out: left `change` undone, [`shortfall`]). Also whether the `sweeps`-th sweep may end
    /// it when `change` is only the largest of the part of it done so far: no sweep with a
    /// larger one ends it.
    fn converged(&self, sweeps: u32, change: f64) -> bool {
        let still = f64::from(self.min_sweeps) * change * self.h <= STILL_FRACTION * self.tolerance;
        self.within_tolerance(change) && (self.before + sweeps >= self.min_sweeps || still)
    }

    /// Whether a sweep at a block's end whose test found `settled` and whose largest change is
    /// `change` ends the solve before the level minimum: the island's pushing contacts are at
    /// rest ([`Settled::AtRest`]) and the change is within the tolerance.
    fn ends_at_rest(&self, settled: Settled, change: f64) -> bool {
        settled == Settled::AtRest && self.within_tolerance(change)
    }

    /// Whether a sweep whose largest change is `change` is within the tolerance.
    fn within_tolerance(&self, change: f64) -> bool {
        change * self.h <= self.tolerance
    }
}

/// An island with `L` levels resting on the ground sweeps at most `max(30, 3 (L + 1))` times
/// a sub-step, one with no contact on the ground (bodies colliding in the air, or without
/// gravity) at most 30, and never more than `SolverSettings::iterations`: its sweeps pass load
/// one level down, so a tall structure needs several passes over its height, while a wide, shallow
/// heap of bodies converges slowly whatever the count (docs/model.md §7a, our choice). A
/// landing pile of 100 blobs (levels 1–4) still changed 1e2–4e4 times the tolerance at its
/// 100th sweep, and at 30 sweeps the fixed pile takes 25 % fewer instructions a step; the
/// stability report's pyramid (20 levels, 63 sweeps) settles with its top 5.3e-5 m from where
/// it started (2.5e-5 m with 100, 1.35e-4 m with 30 for every island).
const SHALLOW_SWEEPS: u32 = 30;

/// See [`SHALLOW_SWEEPS`].
const SWEEPS_PER_LEVEL: u32 = 3;

/// Sweeps of the resting solve between an island's subspace solves (docs/model.md §6 step 5,
/// our choice): enough for the sweeps to find which contacts push and which frictions stick, and
/// to settle what the last subspace solve held. On the settling pyramids of 20 and 40 levels
/// (steps 21–100), 5, 10 and 20 gave the same convergence within the run-to-run differences of
/// their trajectories; 10 took the fewest sweeps a sub-step.
const SUBSPACE_PERIOD: u32 = 10;

/// A sweep of an island with `L` levels that changed no contact by more than this fraction of
/// the tolerance over `L + 1` (`(L + 1) |Δu| h ≤ 1e-5 tolerance (λ_A + λ_B)`) ends its solve
/// before the level count (docs/model.md §7a, our choice). A structure settled to round-off
/// (the 210-box pyramid's sweeps change 3e-8 of the tolerance) then takes one sweep where it
/// took 21. A heuristic, measured rather than proven: the stability report's stack of ten
/// creeps at 1.2e-15 m/s with it (2.3e-15 without; 2.3e-11 m/s with a fraction of 1e-3).
const STILL_FRACTION: f64 = 1e-5;
