//! Narrow phase: for every candidate pair, in parallel, descend both AOBB trees and classify
//! the leaf pairs with the curve-pair solver. Each pair writes only its own slot.

use super::{
    BodyRecord, BoundFloor, Drift, PairSlot, StepBuffers, StepContext, body_motions, fastest, least, margin_horizon,
};
use crate::geometry::query::{PairState, QueryCapacity, QuerySettings};
use crate::profile::StepCounters;
use crate::simulation::{PairAction, PairContacts};

mod carry;
mod detect;
mod still;

use carry::{Carry, STILL_MOTION};
use detect::PairJob;

/// Fills one [`PairSlot`] per candidate pair, then adds the slots' counters in pair order.
pub fn run(ctx: &mut StepContext<'_>) {
    let count = ctx.buffers.candidate_pairs.len();
    // Every entry is written by the pass below.
    ctx.buffers.bound_floors.resize(count, BoundFloor::default());
    if count == 0 {
        ctx.buffers.nearest_gap = Some(f64::INFINITY);
        ctx.buffers.intersecting_pairs = Some(0);
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    // The poses the refit placed the bodies at, at these states (the stage before this one).
    debug_assert!(
        ctx.buffers.poses.len() == ctx.buffers.states.len()
            && ctx.buffers.poses.iter().zip(&ctx.buffers.states).all(|(pose, state)| *pose == state.pose()),
        "the narrow phase runs after the refit, at the same states"
    );
    let in_place = link_slots(ctx.buffers);
    record_motion(ctx.bodies, ctx.buffers);
    let horizon = query_horizon(ctx);
    let (tally, still) = detect_pairs(ctx, in_place, horizon);
    finish_phase(ctx, &tally, still);
}

/// Readies this phase's slots and returns whether they are the last phase's, in place. The
/// same pairs as the last phase's (a resting structure's every step; 55 of the first 256 narrow
/// phases of the landing pile of 100): each slot is its own slot of the last phase (see
/// `Pass::run_in_place`). Otherwise the last phase's slots become the memory this one answers
/// from (temporal coherence): they are read in place, never copied, and their buffers serve the
/// phase after.
fn link_slots(buffers: &mut StepBuffers) -> bool {
    let count = buffers.candidate_pairs.len();
    let in_place = buffers.detected_pairs == count
        && buffers.pair_slots.len().min(buffers.previous_slots.len()) >= count
        && buffers.pair_slots[..count].iter().zip(&buffers.candidate_pairs).all(|(slot, &pair)| slot.bodies == pair);
    if !in_place {
        std::mem::swap(&mut buffers.pair_slots, &mut buffers.previous_slots);
    }
    if buffers.pair_slots.len() < count {
        // New slots hold what every slot holds (see `share_capacity`), while all of them together
        // stay within the budget; beyond it they start empty and grow as their pairs need.
        let slots = count + buffers.previous_slots.len();
        let capacity =
            Some(buffers.slot_capacity).filter(|capacity| within_budget(*capacity, slots)).unwrap_or_default();
        buffers.pair_slots.resize_with(count, || PairSlot::with_capacity(capacity));
    }
    in_place
}

/// How far each body has moved since the last phase (its still pairs' drift grows by it), and
/// what the margins and the carry read of its motion now ([`body_motions`]).
fn record_motion(bodies: &[BodyRecord], buffers: &mut StepBuffers) {
    buffers.phase_motion.clear();
    if buffers.phase_poses.len() == bodies.len() {
        let moved = bodies.iter().zip(&buffers.states).zip(&buffers.phase_poses);
        buffers.phase_motion.extend(moved.map(|((body, state), &(position, angle))| {
            state.position.distance(position) + (state.angle - angle).abs() * body.radius
        }));
    }
    body_motions(bodies, &buffers.states, &buffers.accelerations, &mut buffers.motions);
}

/// The time a carried pair's margin and a query's must cover ([`margin_horizon`]). The next
/// sub-step ends the step at the latest: while the step lasts, a margin need only cover what is
/// left of it (a tenth fewer queries per sub-step in a landing pile; docs/performance.md), and
/// so need a query's (a third fewer leaf pairs). The step's loop ends within 1e-12 of the step;
/// its last narrow phase covers the next step.
fn query_horizon(ctx: &StepContext<'_>) -> f64 {
    let buffers = &*ctx.buffers;
    let horizon = margin_horizon(ctx.settings, buffers.substep);
    let left = buffers.step_left;
    if left > 1e-12 * buffers.step_length { horizon.min(left) } else { horizon }
}

/// The pass over the slots: each slot finds its slot of the last phase (in place: is it),
/// decides whether it is carried and, if so, holds that slot's buffers (by a swap, or where they
/// are), then is detected and counted. One pass, in parallel over stretches of slots, each with
/// its own stretch of the last phase's (both lists are sorted by pair), so a slot is linked,
/// queried and counted on one thread while its data are in that core's cache. A still
/// structure's pairs are all carried by their budgets where they cover them, without the pass.
/// Returns the tally and whether every body is still.
fn detect_pairs(ctx: &mut StepContext<'_>, in_place: bool, horizon: f64) -> (Tally, bool) {
    let buffers = &mut *ctx.buffers;
    let count = buffers.candidate_pairs.len();
    let remembered = buffers.detected_pairs;
    let carry = Carry {
        bodies: ctx.bodies,
        states: &buffers.states,
        motions: &buffers.motions,
        horizon,
        poses: &buffers.poses,
        moved: &buffers.phase_motion,
        broken: &buffers.broken,
        tolerance: ctx.settings.coherence,
        reuse: ctx.settings.contact_reuse,
        intersection_tolerance: ctx.settings.curve_pair.intersection_tolerance,
    };
    let query = QuerySettings {
        min_band: ctx.settings.min_band,
        curve_pair: ctx.settings.curve_pair,
        approach_depth: ctx.settings.approach_depth,
        ..QuerySettings::default()
    };
    // The bodies' geometry stays borrowed for the pair tasks, and only for them.
    let mut geometry = buffers.geometry.0.query(ctx.world);
    let job = PairJob {
        geometry: geometry.view(),
        bodies: ctx.bodies,
        states: &buffers.states,
        poses: &buffers.poses,
        motions: &buffers.motions,
        margins: &buffers.margins,
        horizon,
        tolerance: ctx.settings.coherence,
        solver_tolerance: ctx.settings.solver.tolerance,
        query,
    };
    let still = buffers.phase_motion.len() == ctx.bodies.len()
        && ctx.bodies.iter().zip(&buffers.phase_motion).all(|(body, &moved)| moved <= STILL_MOTION * body.radius);
    let pass = Pass { carry: &carry, job: &job, still };
    let slots = &mut buffers.pair_slots[..count];
    let floors = &mut buffers.bound_floors[..];
    let budgeted = in_place && still && buffers.still_budgets && ctx.contact_hook.is_none();
    let quick = if budgeted && !buffers.broken.contains(&true) {
        let (speed, growth) = fastest(&buffers.motions);
        let h = carry.horizon;
        pass.carry_all(slots, (speed * h + growth * h * h) * (1.0 + still::COVER_ROUNDING))
    } else {
        None
    };
    ctx.profile.counters.still_phases += u64::from(quick.is_some());
    let tally = quick.unwrap_or_else(|| {
        let pairs = &buffers.candidate_pairs[..];
        // Without a pool the step runs on the caller's thread; with one, on a worker of it
        // already, so no job is queued.
        let splitter = ctx.pool.map(|pool| (Splitter::new(pool.current_num_threads()), false));
        let mut run = || {
            if in_place {
                pass.run_in_place((slots, floors), &mut buffers.previous_slots[..count], splitter)
            } else {
                pass.run((slots, floors), pairs, &mut buffers.previous_slots[..remembered], splitter)
            }
        };
        match ctx.pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
    });
    drop(geometry);
    if quick.is_some() {
        // Carried by their budgets, the pairs wrote no list: the sub-step bound, which the
        // fastest bodies' closing seldom lets reach the pairs here, reads the slots.
        buffers.bound_floors.clear();
    }
    buffers.still_budgets = still && (quick.is_some() || tally.budgets == count as u64);
    (tally, still)
}

/// What the phase leaves for the stages after it and the next phase: the poses it ran at, the
/// contact hook's word, the counters, the least gap (still) and the crossings, and every slot's
/// capacity grown to the largest any slot has needed ([`share_capacity`]).
fn finish_phase(ctx: &mut StepContext<'_>, tally: &Tally, still: bool) {
    let buffers = &mut *ctx.buffers;
    buffers.detected_pairs = buffers.candidate_pairs.len();
    buffers.phase_poses.clear();
    buffers.phase_poses.extend(buffers.states.iter().map(|state| (state.position, state.angle)));
    if let Some(hook) = ctx.contact_hook {
        ask_hook(hook, ctx.bodies, buffers, &mut ctx.profile.counters);
    }
    ctx.profile.counters.accumulate(&tally.counters());
    buffers.nearest_gap = still.then_some(tally.nearest);
    buffers.intersecting_pairs = Some(tally.intersecting as usize);
    let largest = tally.largest.max(buffers.largest_slot);
    if largest != buffers.largest_slot {
        buffers.largest_slot = largest;
        share_capacity(buffers, largest);
    }
}

/// What the pass over the slots adds up: the profile's narrow-phase counters (in the order of
/// [`Tally::counters`]), and the largest capacity any slot needed. Sums of integers and maxima:
/// the same in any order of adding.
#[derive(Clone, Copy, Debug)]
struct Tally {
    counts: [u64; 7],
    largest: QueryCapacity,
    /// The least gap, less its drift, of the separate leaf pairs that bound the sub-step (their
    /// listed gaps and query margins; NaN if any is).
    nearest: f64,
    /// How many slots hold a drift budget (`PairSlot::drift_budget`).
    budgets: u64,
    /// How many slots intersect ([`PairSlot::intersecting`]).
    intersecting: u64,
}

impl Default for Tally {
    fn default() -> Self {
        Self { counts: [0; 7], largest: QueryCapacity::default(), nearest: f64::INFINITY, budgets: 0, intersecting: 0 }
    }
}

impl Tally {
    /// Counts `slot`, the capacity its query needed and, where given, the least gap `nearest`
    /// it bounds the sub-step by ([`PairSlot::bounding_gap`]): only a query grows a slot's
    /// buffers (a carried slot holds its last query's, which every slot held).
    fn add(&mut self, slot: &PairSlot, nearest: Option<f64>) {
        let manifold = slot.manifold();
        let counts = [
            slot.query.counters.box_tests as u64,
            slot.query.counters.leaf_pairs as u64,
            manifold.recalled_leaf_pairs,
            u64::from(slot.carried),
            u64::from(slot.carried && !manifold.contacts.is_empty()),
            manifold.newton_iterations,
            manifold.contacts.len() as u64,
        ];
        for (count, add) in self.counts.iter_mut().zip(counts) {
            *count += add;
        }
        self.intersecting += u64::from(slot.intersecting());
        if !slot.carried {
            self.largest = self.largest.max(slot.query.capacity());
        }
        // What the slot bounds the sub-step by (`integrate::pair_substep`): its listed gaps and
        // its query margin, less its drift. A sensor pair bounds nothing.
        if let Some(nearest) = nearest {
            self.nearest = least(self.nearest, nearest);
        }
    }

    fn join(mut self, other: &Self) -> Self {
        for (count, other) in self.counts.iter_mut().zip(&other.counts) {
            *count += other;
        }
        self.largest = self.largest.max(other.largest);
        self.nearest = least(self.nearest, other.nearest);
        self.budgets += other.budgets;
        self.intersecting += other.intersecting;
        self
    }

    /// The profile's counters these counts are.
    fn counters(&self) -> StepCounters {
        let [box_tests, leaf_pairs, recalled_leaf_pairs, carried_pairs, reused_pairs, newton_iterations, contacts] =
            self.counts;
        StepCounters {
            box_tests,
            leaf_pairs,
            recalled_leaf_pairs,
            carried_pairs,
            reused_pairs,
            newton_iterations,
            contacts,
            ..StepCounters::default()
        }
    }
}

/// The contact hook's word on every pair in contact or crossing, in pair order: ignored pairs
/// pass through this sub-step as sensor pairs do; modified ones keep the hook's friction and
/// restitution for the solver (values outside their ranges are counted and not used).
fn ask_hook(
    hook: &(dyn Fn(&PairContacts<'_>) -> PairAction + Send + Sync),
    bodies: &[BodyRecord],
    buffers: &mut StepBuffers,
    counters: &mut StepCounters,
) {
    let count = buffers.candidate_pairs.len();
    for slot in &mut buffers.pair_slots[..count] {
        let manifold = &slot.query.manifold;
        let crossing = manifold.state == PairState::Intersecting;
        if slot.sensor || (manifold.contacts.is_empty() && !crossing) {
            continue;
        }
        let (a, b) = slot.body_indices();
        let pair = PairContacts {
            body_a: bodies[a].entity,
            body_b: bodies[b].entity,
            state_a: &buffers.states[a],
            state_b: &buffers.states[b],
            contacts: &manifold.contacts,
            crossing,
        };
        match hook(&pair) {
            PairAction::Keep => {}
            PairAction::Ignore => slot.sensor = true,
            PairAction::Modify { friction, restitution } => {
                let friction = friction.filter(|&mu| {
                    let valid = mu.is_finite() && mu >= 0.0;
                    counters.rejected_hook_values += u64::from(!valid);
                    valid
                });
                let restitution = restitution.filter(|&e| {
                    let valid = (0.0..=1.0).contains(&e);
                    counters.rejected_hook_values += u64::from(!valid);
                    valid
                });
                slot.modified = (friction, restitution);
            }
        }
    }
}

/// Grows every pair slot's buffers, this phase's and the last one's, to `largest`, the largest
/// any slot has needed (a pair lands in another slot from one sub-step to the next, the
/// carried ones swap buffers with the last phase's slots, and in place the queried ones swap
/// their leaf memory's and front's with their spares'), if all of them together stay within
/// [`SHARED_SLOT_BYTES`]. Every slot holds `StepBuffers::slot_capacity`, so this runs only when
/// a slot has grown past the largest any slot had needed: steady stepping neither allocates nor
/// walks the slots for it. Beyond the budget the slots are left as they are, and a slot whose
/// pair needs more grows on its own (and keeps what it grew to).
fn share_capacity(buffers: &mut StepBuffers, largest: QueryCapacity) {
    if !within_budget(largest, buffers.pair_slots.len() + buffers.previous_slots.len()) {
        return;
    }
    buffers.slot_capacity = largest;
    for slot in buffers.pair_slots.iter_mut().chain(buffers.previous_slots.iter_mut()) {
        slot.query.reserve(largest); // exact, and nothing where the slot already holds it
    }
}

/// Whether `slots` pair slots may each hold `capacity`: their buffers together within
/// [`SHARED_SLOT_BYTES`].
fn within_budget(capacity: QueryCapacity, slots: usize) -> bool {
    capacity.bytes().saturating_mul(slots) <= SHARED_SLOT_BYTES
}

/// The most heap the pair slots' shared buffers may take (64 MiB; *our choice*). Sharing the
/// largest buffers any slot needed with every slot keeps steady stepping free of allocation, but
/// costs the slot count times the largest need (a leaf gap takes 200 bytes): a pyramid of 820
/// boxes whose bodies an unstable solver prototype had thrown at 1e13 m/s gave all 336,299 of
/// its pairs a slot, and sharing the 30 KiB a few pairs had needed with all of them, this
/// phase's slots and the last one's, asked for about 20 GB (the machine's 24 GB ran out; at
/// that speed the pairs' own searches still take more than 8 GB within the budget). The landing
/// pile of 500 blobs shared 29 KiB (128 leaf gaps) with 8,800 slots, 248 MiB; within this budget
/// its peak resident memory fell from 212 to 132 MB at the same step time (docs/performance.md).
pub(crate) const SHARED_SLOT_BYTES: usize = 64 << 20;

/// Splits a parallel pass starts with, per thread (rayon's splitter starts with one): each
/// halves a stretch, so 8 give about 16 stretches a thread where rayon's gives about 2. The
/// pairs are in body order, and a landing pile's costly pairs (its bodies in contact) lie
/// together among the cheap ones of its falling bodies: with about two stretches a thread, a
/// thread that had finished found nothing left to take while the other was still in the
/// stretch that held them. Since the broad phase's bounds are tight (`geometry/octagon.rs`) the
/// cheap far pairs no longer dilute them, and the landing pile of 500 blobs' narrow phase took
/// 22–25 ms a step on two threads with one split a thread against 14–17 with eight
/// (docs/performance.md).
const SPLITS_PER_THREAD: usize = 8;

/// How a parallel pass splits its stretch of slots: as rayon's adaptive splitter does, but into
/// about [`SPLITS_PER_THREAD`] times as many stretches as threads, and a stolen stretch into as
/// many again as there are threads. Pairs are handed out one by one if need be: a few cost a
/// hundred times the median (with at least four to a task a landing pile's narrow phase ran
/// 1.5× faster on two threads than on one; split to single pairs, 1.62×: docs/performance.md).
#[derive(Clone, Copy, Debug)]
struct Splitter {
    threads: usize,
    splits: usize,
}

impl Splitter {
    fn new(threads: usize) -> Self {
        Self { threads, splits: threads * SPLITS_PER_THREAD }
    }

    /// Whether to split again, for a stretch that was (`stolen`) or was not taken by another
    /// thread.
    fn split(&mut self, stolen: bool) -> bool {
        if stolen {
            self.splits = self.threads.max(self.splits / 2);
            true
        } else if self.splits > 0 {
            self.splits /= 2;
            true
        } else {
            false
        }
    }
}

/// Where a stretch of `len` slots is split (its middle), and the splitter its halves go on
/// with; `None` where it is run on this thread.
fn halve(splitter: Option<(Splitter, bool)>, len: usize) -> Option<(Splitter, usize)> {
    let (mut splitter, stolen) = splitter?;
    (len > 1 && splitter.split(stolen)).then_some((splitter, len / 2))
}

/// Runs `run` on the two halves of a stretch on the pool, each with `splitter` and whether its
/// half was taken by another thread, and adds up their tallies.
fn join_halves<T: Send>(
    splitter: Splitter,
    (left, right): (T, T),
    run: impl Fn(T, Option<(Splitter, bool)>) -> Tally + Sync,
) -> Tally {
    let (left, right) = rayon::join_context(
        |context| run(left, Some((splitter, context.migrated()))),
        |context| run(right, Some((splitter, context.migrated()))),
    );
    left.join(&right)
}

/// The narrow phase's pass over a stretch of slots: link each to the last phase, decide its
/// carry, detect it and count it.
struct Pass<'a> {
    carry: &'a Carry<'a>,
    job: &'a PairJob<'a>,
    /// Whether every body has barely moved since the last phase: only then is the least gap
    /// gathered for the sub-step bound (a moving scene's bound seldom clears it).
    still: bool,
}

impl Pass<'_> {
    /// For each of `slots` (the candidate pairs `pairs`, sorted): its pair and sensor flag, its
    /// slot among `previous` (a stretch of the last phase's slots, sorted, holding every slot
    /// of these pairs), whether it is carried ([`Carry::drift`]: it reads only its
    /// own slot of the last phase) and, if so, that slot's buffers by a swap (no copy, no
    /// search); then its detection ([`PairJob::detect`], from its own slot of the last phase)
    /// and its tally. With a `splitter` (more than one thread), halves of the stretch run on
    /// the pool, each with the part of `previous` its pairs can be in: no slot of the last
    /// phase is touched by two tasks, and the result is the same in any order.
    fn run(
        &self,
        (slots, floors): (&mut [PairSlot], &mut [BoundFloor]),
        pairs: &[(u32, u32)],
        previous: &mut [PairSlot],
        splitter: Option<(Splitter, bool)>,
    ) -> Tally {
        if let Some((splitter, middle)) = halve(splitter, slots.len()) {
            let split = previous.partition_point(|slot| slot.bodies < pairs[middle]);
            let (slots_left, slots_right) = slots.split_at_mut(middle);
            let (floors_left, floors_right) = floors.split_at_mut(middle);
            let (pairs_left, pairs_right) = pairs.split_at(middle);
            let (previous_left, previous_right) = previous.split_at_mut(split);
            let halves = (
                ((slots_left, floors_left), pairs_left, previous_left),
                ((slots_right, floors_right), pairs_right, previous_right),
            );
            return join_halves(splitter, halves, |(slots, pairs, previous), splitter| {
                self.run(slots, pairs, previous, splitter)
            });
        }
        let bodies = self.carry.bodies;
        let mut tally = Tally::default();
        let mut j = 0;
        for ((slot, floor), &pair) in slots.iter_mut().zip(floors).zip(pairs) {
            slot.bodies = pair;
            slot.sensor = bodies[pair.0 as usize].sensor || bodies[pair.1 as usize].sensor;
            slot.modified = (None, None);
            while j < previous.len() && previous[j].bodies < pair {
                j += 1;
            }
            let found = (j < previous.len() && previous[j].bodies == pair).then_some(j);
            let carried = found.and_then(|j| self.carry.drift(pair, slot.sensor, &previous[j]));
            (slot.carried, slot.drift) = (carried.is_some(), carried.map_or_else(Drift::default, |c| c.drift));
            slot.crossing = None;
            if let (Some(j), Some(carried)) = (found, carried) {
                slot.take_carried(&mut previous[j], carried.drift);
                slot.crossing = carried.crossing;
            }
            // A carried slot holds its last query's buffers now; any other reads its memory
            // from its slot of the last phase.
            self.job.detect(slot, found.map(|j| &previous[j]));
            *floor = self.count(slot, &mut tally);
        }
        tally
    }

    /// Adds `slot`, detected, to `tally`, with its drift budget where every body is still;
    /// returns its entry of the sub-step bound's list.
    fn count(&self, slot: &mut PairSlot, tally: &mut Tally) -> BoundFloor {
        slot.drift_budget = if self.still { still::budget(self.carry, self.job, slot) } else { None };
        tally.budgets += u64::from(slot.drift_budget.is_some());
        let gap = slot.bounding_gap();
        tally.add(slot, self.still.then_some(gap));
        slot.bound_floor(gap)
    }

    /// As [`Pass::run`] where the candidate pairs are the last phase's, in the same slots: each
    /// slot is its own slot of the last phase. A carried one keeps its buffers where they are;
    /// one that is queried first hands its leaf memory and front to its `spare` (its slot of the
    /// phase before, which nothing reads), swapping their buffers
    /// ([`BodyQuery::take_memory_from`](crate::geometry::query::BodyQuery::take_memory_from)),
    /// and answers from them; its answer is written over where it is. The same result as
    /// `run`.
    fn run_in_place(
        &self,
        (slots, floors): (&mut [PairSlot], &mut [BoundFloor]),
        spare: &mut [PairSlot],
        splitter: Option<(Splitter, bool)>,
    ) -> Tally {
        if let Some((splitter, middle)) = halve(splitter, slots.len()) {
            let (slots_left, slots_right) = slots.split_at_mut(middle);
            let (floors_left, floors_right) = floors.split_at_mut(middle);
            let (spare_left, spare_right) = spare.split_at_mut(middle);
            let halves = (((slots_left, floors_left), spare_left), ((slots_right, floors_right), spare_right));
            return join_halves(splitter, halves, |(slots, spare), splitter| self.run_in_place(slots, spare, splitter));
        }
        let bodies = self.carry.bodies;
        let mut tally = Tally::default();
        for ((slot, floor), spare) in slots.iter_mut().zip(floors).zip(spare) {
            let pair = slot.bodies;
            let sensor = bodies[pair.0 as usize].sensor || bodies[pair.1 as usize].sensor;
            let carried = self.carry.drift(pair, sensor, slot);
            (slot.sensor, slot.modified) = (sensor, (None, None));
            if let Some(carried) = carried {
                slot.keep_carried(carried.drift);
                slot.crossing = carried.crossing;
                self.job.detect(slot, None);
            } else {
                (slot.carried, slot.drift, slot.crossing) = (false, Drift::default(), None);
                spare.query.take_memory_from(&mut slot.query);
                self.job.detect(slot, Some(spare));
            }
            *floor = self.count(slot, &mut tally);
        }
        tally
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A capacity of `gaps` leaf gaps (200 bytes each) and nothing else.
    fn gaps(gaps: usize) -> QueryCapacity {
        QueryCapacity { gaps, ..QueryCapacity::default() }
    }

    #[test]
    fn shared_slot_buffers_stay_within_their_budget() {
        let slots = 1000;
        let mut buffers = StepBuffers::default();
        buffers.pair_slots.resize_with(slots, PairSlot::default);
        // Within the budget: every slot is grown to the largest need.
        share_capacity(&mut buffers, gaps(16));
        assert_eq!(buffers.slot_capacity, gaps(16));
        assert!(buffers.pair_slots.iter().all(|slot| slot.query.capacity().gaps >= 16));
        // A need that, given to every slot, would pass the budget: no slot is grown to it.
        let beyond = SHARED_SLOT_BYTES / slots / gaps(1).bytes() + 1;
        assert!(!within_budget(gaps(beyond), slots) && within_budget(gaps(beyond - 1), slots));
        share_capacity(&mut buffers, gaps(beyond));
        assert_eq!(buffers.slot_capacity, gaps(16));
        assert!(buffers.pair_slots.iter().all(|slot| slot.query.capacity().gaps < beyond));
        // The heap the slots' buffers hold stays within the budget.
        let held: usize = buffers.pair_slots.iter().map(|slot| slot.query.capacity().bytes()).sum();
        assert!(held <= SHARED_SLOT_BYTES, "{held} bytes");
    }
}
