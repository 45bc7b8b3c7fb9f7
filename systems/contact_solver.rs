//! Contact solver: sequential impulses over the resting contacts (MODEL §7a), warm-started
//! with last sub-step's forces, island by island (in parallel), each swept from the ground up
//! until it converges. Tall
//! structures are held up by the warm start (the forces converge over the sub-steps) and by
//! the push-out pass's shock propagation (`position_correction.rs`). Where a body rests on one
//! at least ten times lighter, the sweeps cannot converge; the island of such a contact then
//! gets shock propagation here too (Guendelman, Bridson and Fedkiw 2003): level by level from
//! the ground up, each lower body held while the contacts above it are solved.

use super::islands::UNGROUNDED;
use super::{
    SolverIsland, StepContext, body_velocity, contact_island, pair_velocities, store_velocities, store_velocity,
};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{
    Accumulator, IslandVelocities, Pass, SHOCK_SWEEPS, SolverContact, apply, for_each_level, sweep,
};
use crate::simulation::SolverSettings;
pub(crate) use wavefront::Runs;

mod wavefront;

/// Solves the resting contacts; skipped when there is none.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    if buffers.solver_contacts.is_empty() {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let h = buffers.substep;
    let states = &mut buffers.states;
    for contact in &mut buffers.solver_contacts {
        warm_start(contact, states, h);
    }
    let settings = &ctx.settings.solver;
    // Island by island, in parallel (no dynamic body is in two islands, so what one island's
    // solve does cannot reach another's): each island's solve reads and writes only its own
    // copy of its bodies' velocities, gathered here and applied back after, so the results are
    // the same bit for bit for any thread count.
    gather_islands(ctx.bodies, buffers);
    let parallel = ctx.pool.current_num_threads() > 1;
    let islands = &buffers.solver_islands;
    let (contacts, velocities) = (&mut buffers.solver_contacts, &mut buffers.island_velocities);
    // With two threads, the largest island's sweeps may be shared between them as a wavefront.
    let wavefront = if parallel { wavefront_island(islands, contacts, &mut buffers.island_runs) } else { None };
    ctx.profile.counters.wavefront_solves += u64::from(wavefront.is_some());
    let lanes = Lanes { contacts, velocities, wavefront };
    let outcome = solve_islands(lanes, islands, (settings, h), parallel);
    // Back to the states: each moving body from its one island (static and kinematic bodies,
    // which several islands may read, are not moved by contacts).
    for (&slot, velocity) in buffers.island_slots.iter().zip(&buffers.island_velocities) {
        if !ctx.bodies[slot as usize].is_static {
            store_velocity(&mut buffers.states[slot as usize], *velocity);
        }
    }
    ctx.profile.counters.solver_iterations += u64::from(outcome.most_sweeps);
    ctx.profile.counters.solver_unconverged += u64::from(outcome.unconverged > 0);
    let states = &mut buffers.states;
    if settings.shock_propagation && buffers.solver_contacts.iter().any(|c| c.heavy_on_light) {
        mark_shock_islands(ctx.bodies, &buffers.island_of, &mut buffers.shock_islands, &mut buffers.solver_contacts);
        heavy_on_light_shock(&mut buffers.solver_contacts, states);
        ctx.profile.counters.solver_iterations += u64::from(SHOCK_SWEEPS);
    }
    for contact in &buffers.solver_contacts {
        if contact.normal_impulse > 0.0 {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// Sorts out the islands of `solver_contacts` (ordered island by island): each one's contact
/// range, its bodies' velocities copied into `island_velocities` (with their slots in
/// `island_slots`) and each contact's `local` indices among them.
fn gather_islands(bodies: &[super::BodyRecord], buffers: &mut super::StepBuffers) {
    let (contacts, islands) = (&mut buffers.solver_contacts, &mut buffers.solver_islands);
    let (velocities, slots, index) =
        (&mut buffers.island_velocities, &mut buffers.island_slots, &mut buffers.island_index);
    islands.clear();
    velocities.clear();
    slots.clear();
    index.resize(bodies.len(), u32::MAX);
    let mut start = 0;
    while start < contacts.len() {
        let island = contacts[start].island;
        let end = start + contacts[start..].iter().take_while(|c| c.island == island).count();
        let first_body = velocities.len();
        for contact in &mut contacts[start..end] {
            let (a, b) = contact.key.bodies;
            let mut local = |slot: u32| {
                if index[slot as usize] == u32::MAX {
                    index[slot as usize] = (velocities.len() - first_body) as u32;
                    velocities.push(body_velocity(&buffers.states[slot as usize]));
                    slots.push(slot);
                }
                index[slot as usize]
            };
            contact.local = (local(a), local(b));
        }
        for &slot in &slots[first_body..] {
            index[slot as usize] = u32::MAX;
        }
        islands.push(SolverIsland { contacts: (start, end), bodies: (first_body, velocities.len()) });
        start = end;
    }
}

/// What the islands' solves came to: the most sweeps any took, and how many stopped at the cap.
#[derive(Clone, Copy, Debug, Default)]
struct Outcome {
    most_sweeps: u32,
    unconverged: u32,
}

/// Solves `islands`, whose contacts and velocities are exactly `contacts` and `velocities`, by
/// halves (of their contacts) joined on the pool when `parallel`: no allocation, and each
/// island's own solve the same whichever thread runs it.
fn solve_islands(
    lanes: Lanes<'_>,
    islands: &[SolverIsland],
    (settings, h): (&SolverSettings, f64),
    parallel: bool,
) -> Outcome {
    match islands {
        [] => Outcome::default(),
        [_] => {
            let rule = StopRule::new(lanes.contacts, settings, h);
            match lanes.wavefront {
                Some((_, runs)) => wavefront::solve(lanes.contacts, lanes.velocities, runs, rule),
                None => solve_island(lanes.contacts, lanes.velocities, rule),
            }
        }
        [first, .., last] => {
            let middle = (first.contacts.0 + last.contacts.1) / 2;
            let half = islands.partition_point(|island| island.contacts.0 < middle).clamp(1, islands.len() - 1);
            let (left, right) = islands.split_at(half);
            let (left_lanes, right_lanes) = lanes.split(*first, right[0]);
            let solve_left = move || solve_islands(left_lanes, left, (settings, h), parallel);
            let solve_right = move || solve_islands(right_lanes, right, (settings, h), parallel);
            let (a, b) = if parallel && contacts_len(islands) >= PARALLEL_CONTACTS {
                rayon::join(solve_left, solve_right)
            } else {
                (solve_left(), solve_right())
            };
            Outcome { most_sweeps: a.most_sweeps.max(b.most_sweeps), unconverged: a.unconverged + b.unconverged }
        }
    }
}

/// Fewer contacts than this are not split between threads (a join costs more than they do).
const PARALLEL_CONTACTS: usize = 64;

/// What a part of the islands' solve owns: their contacts and velocities, and, if the wavefront
/// island is among them, its first contact (in `solver_contacts`) and runs.
struct Lanes<'a> {
    contacts: &'a mut [SolverContact],
    velocities: &'a mut [BodyVelocity],
    wavefront: Option<(usize, &'a mut Runs)>,
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
        (
            Self { contacts: left_contacts, velocities: left_velocities, wavefront: left_wavefront },
            Self { contacts: right_contacts, velocities: right_velocities, wavefront: right_wavefront },
        )
    }
}

/// The largest island, with its runs built, if it is to be solved as a wavefront
/// ([`wavefront::Runs::build`]).
fn wavefront_island<'a>(
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
/// unconverged.
fn solve_island(contacts: &mut [SolverContact], velocities: &mut [BodyVelocity], rule: StopRule) -> Outcome {
    let mut velocities = IslandVelocities(velocities);
    let mut sweeps = 0;
    while sweeps < rule.cap {
        let change = sweep(contacts, &mut velocities, Accumulator::Velocity, Pass::Relax);
        sweeps += 1;
        if rule.converged(sweeps, change) {
            return Outcome { most_sweeps: sweeps, unconverged: 0 };
        }
    }
    Outcome { most_sweeps: sweeps, unconverged: 1 }
}

/// When an island's sweeps stop (see [`solve_island`]): the level count, the cap and the
/// tolerance. One home for the serial solve and the wavefront's.
#[derive(Clone, Copy, Debug)]
struct StopRule {
    /// Sweeps an island needs before a change within the tolerance ends it: its levels plus one.
    min_sweeps: u32,
    /// Sweeps after which it stops unconverged.
    cap: u32,
    /// `SolverSettings::tolerance`.
    tolerance: f64,
    /// The sub-step (s).
    h: f64,
}

impl StopRule {
    fn new(contacts: &[SolverContact], settings: &SolverSettings, h: f64) -> Self {
        let grounded = contacts.iter().map(|c| c.level).filter(|&level| level != UNGROUNDED);
        let min_sweeps = grounded.max().map_or(1, |level| level + 1).min(settings.iterations);
        let cap = settings.iterations.min(SHALLOW_SWEEPS.max(SWEEPS_PER_LEVEL * min_sweeps));
        Self { min_sweeps, cap, tolerance: settings.tolerance, h }
    }

    /// Whether the solve ends converged after its `sweeps`-th sweep, which changed `change`.
    fn converged(&self, sweeps: u32, change: f64) -> bool {
        let still = f64::from(self.min_sweeps) * change * self.h <= STILL_FRACTION * self.tolerance;
        self.within_tolerance(change) && (sweeps >= self.min_sweeps || still)
    }

    /// Whether a sweep whose largest change is `change` (or at least `change`, for part of a
    /// sweep) may end the solve: no sweep with a larger change does.
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

/// A sweep of an island with `L` levels that changed no contact by more than this fraction of
/// the tolerance over `L + 1` (`(L + 1) |Δu| h ≤ 1e-5 tolerance (λ_A + λ_B)`) ends its solve
/// before the level count (docs/model.md §7a, our choice). A structure settled to round-off
/// (the 210-box pyramid's sweeps change 3e-8 of the tolerance) then takes one sweep where it
/// took 21. A heuristic, measured rather than proven: the stability report's stack of ten
/// creeps at 1.2e-15 m/s with it (2.3e-15 without; 2.3e-11 m/s with a fraction of 1e-3).
const STILL_FRACTION: f64 = 1e-5;

/// Applies last sub-step's forces over this sub-step (`F h`); a contact that just collided
/// starts from zero.
fn warm_start(contact: &mut SolverContact, states: &mut [crate::components::RigidState], h: f64) {
    let (normal, tangent) = if contact.collided { (0.0, 0.0) } else { (contact.warm.0 * h, contact.warm.1 * h) };
    let limit = contact.friction * normal;
    contact.normal_impulse = normal.max(0.0);
    contact.tangent_impulse = tangent.clamp(-limit, limit);
    if contact.normal_impulse == 0.0 {
        return;
    }
    let (mut va, mut vb) = pair_velocities(states, contact.key.bodies);
    let j = contact.normal * contact.normal_impulse + contact.tangent() * contact.tangent_impulse;
    apply(contact.inverse, contact.r_a, contact.r_b, j, &mut va, &mut vb);
    store_velocities(states, contact.key.bodies, va, vb);
}

/// Marks for the velocity shock pass every contact of an island that has a heavy-on-light
/// contact: the light body must itself be held by what is below it.
fn mark_shock_islands(
    bodies: &[super::BodyRecord],
    island_of: &[u32],
    flags: &mut Vec<bool>,
    contacts: &mut [SolverContact],
) {
    let island = |c: &SolverContact| contact_island(bodies, island_of, c.key.bodies);
    flags.clear();
    flags.resize(bodies.len(), false);
    for contact in contacts.iter().filter(|c| c.heavy_on_light) {
        flags[island(contact)] = true;
    }
    for contact in contacts.iter_mut() {
        contact.velocity_shock = flags[island(contact)];
    }
}

/// Shock propagation over the islands with a heavy-on-light contact, level by level
/// ([`SHOCK_SWEEPS`] sweeps each, the lower body held). Their impulses are kept for the warm
/// start: they carry the heavy body's weight, which the light body passes on to its support.
fn heavy_on_light_shock(contacts: &mut [SolverContact], states: &mut [crate::components::RigidState]) {
    for_each_level(contacts, |level| {
        for _ in 0..SHOCK_SWEEPS {
            sweep(level, states, Accumulator::Velocity, Pass::Shock);
        }
    });
}
