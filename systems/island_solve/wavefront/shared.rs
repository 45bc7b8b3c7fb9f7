//! The two threads' protocol on one island's sweeps ([`Shared`]): the stretches of sweeps, the
//! hand-over of the upper runs to a helper, and what each thread copies to put back (the
//! module documentation of `wavefront`).

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};

use super::super::halves::{Lent, pause};
use super::super::{Outcome, Settled, StopRule, Sweeper, relax};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{Accumulator, SolverContact};
use runs::Saved;

mod runs;

/// The solve's own thread on a wavefront island: each stretch's lower runs (and every run until
/// a helper has come), and the island between stretches.
pub(in crate::systems::island_solve) struct Lower<'s, 'a> {
    shared: &'s Shared<'a>,
    saved: Saved<'s>,
}

impl<'s, 'a> Lower<'s, 'a> {
    /// The lower thread of `shared`, its copies kept in the run's buffers.
    pub(super) fn new(
        shared: &'s Shared<'a>,
        impulses: &'s mut [[f64; 2]],
        velocities: &'s mut [BodyVelocity],
        runs: &'s mut Vec<u32>,
    ) -> Self {
        Self { shared, saved: Saved { impulses, velocities, runs } }
    }
}

impl Sweeper for Lower<'_, '_> {
    /// Opens a stretch of sweeps under `rule`, sweeps it with the helper if one has come (until
    /// converged, capped, or at a block's end that needs a subspace solve), and returns once the
    /// helper, if it took part, is done with it.
    fn sweep(&mut self, rule: StopRule) -> Outcome {
        let shared = self.shared;
        shared.open(rule);
        shared.lower(&mut self.saved, &rule);
        shared.close();
        let stop = shared.stop.load(Ordering::Acquire);
        let unconverged = shared.unconverged.load(Ordering::Acquire);
        // The sweeps whose upper runs the helper did: from the one it joined at to the last.
        let from = shared.shared_from.load(Ordering::Acquire);
        let shared_sweeps = if from <= stop { u64::from(stop + 1 - from) } else { 0 };
        Outcome { most_sweeps: stop + 1, unconverged, wavefront_shared_sweeps: shared_sweeps, ..Outcome::default() }
    }

    fn island(&mut self) -> (&mut [SolverContact], &mut [BodyVelocity], Option<&Lent>) {
        let (contacts, bodies) = self.shared.starts[self.shared.starts.len() - 1];
        // SAFETY: the pointers and counts are the island's, borrowed mutably by `solve` for as
        // long as `self.shared` lives. Between stretches the helper touches none of the island's
        // runs: `close` waited for a helper that had taken a seat to finish the stretch, and one
        // that has not takes a seat only at the next `open` (`Shared::help`). It may work on
        // the island only for the subspace solve these slices are lent to, as its `Halves`
        // helper (`halves::Lent`), which it leaves before that solve returns.
        #[allow(unsafe_code)]
        unsafe {
            (
                std::slice::from_raw_parts_mut(self.shared.contacts, contacts as usize),
                std::slice::from_raw_parts_mut(self.shared.velocities, bodies as usize),
                Some(&self.shared.lent),
            )
        }
    }
}

/// The first run of the upper part: the runs before it hold about half the island's contacts
/// (at least one run on each side).
fn split_run(starts: &[(u32, u32)]) -> usize {
    let runs = starts.len() - 1;
    let half = starts[runs].0 / 2;
    let split = starts[..runs].iter().position(|&(first, _)| first >= half).unwrap_or(runs);
    split.clamp(1, runs - 1)
}

/// [`Shared::shared_from`] while the lower thread sweeps every run itself, ...
const NOT_SHARED: u32 = u32::MAX;
/// ... and once it has returned without handing any sweep over.
const LEFT_ALONE: u32 = u32::MAX - 1;

/// [`Shared::seat`] while a helper that has not come may not take one (between `close` and
/// the next `open`, and before the first), ...
const CLOSED: u32 = 0;
/// ... while it may (from an `open` to its `close`), ...
const OPEN: u32 = 1;
/// ... once the helper has taken it: it takes part in every stretch from then on, ...
const TAKEN: u32 = 2;
/// ... and once the helper has panicked: the lower thread sweeps alone and waits for it no more.
const GONE: u32 = 3;

/// [`Shared::opened`] once the stretches are over: the helper returns.
const ENDED: u32 = u32::MAX;

/// What the two threads share: the island's contacts and velocities (each run's taken by one
/// thread at a time, by the wavefront's order), the runs, the stretches of sweeps, where each
/// sweep of the stretch is, and the hand-over of the upper runs (the module documentation).
///
/// A *stretch* is the sweeps between two subspace solves (one block of `SUBSPACE_PERIOD` or
/// more: a block's end whose island no subspace solve would change does not end it; fewer
/// where the sweeps converge or reach their cap). The lower
/// thread `open`s each (its rule and a fresh state), `close`s it once its sweeps are decided,
/// then does the subspace solve until it opens the next. A helper that comes takes the seat of
/// the stretch open then, if any, and from then on takes part in every stretch, serving the
/// subspace solves' halves in between (`halves::Lent`); it tells the lower thread when it is
/// done with each stretch (`finished`), and the lower thread waits for that before it touches
/// the island or the stretch's state again. A helper that comes while no stretch is open serves
/// the subspace solve's halves until the next.
pub(super) struct Shared<'a> {
    contacts: *mut SolverContact,
    velocities: *mut BodyVelocity,
    starts: &'a [(u32, u32)],
    /// The first run of the upper part.
    split: usize,
    /// The whole solve's rule; each stretch's cap and sweeps before it in `cap` and `before`
    /// ([`StopRule::after`]).
    rule: StopRule,
    cap: AtomicU32,
    before: AtomicU32,
    /// The number of stretches opened; [`ENDED`] once the stretches are over.
    pub(super) opened: AtomicU32,
    /// Whether a helper that has not come may take part in the open stretch ([`CLOSED`], [`OPEN`],
    /// [`TAKEN`], [`GONE`]).
    seat: AtomicU32,
    /// The number of the last stretch (as `opened` counts them) the helper is done with.
    finished: AtomicU32,
    /// The helper, lent to the subspace solves between stretches while it waits (`halves.rs`).
    lent: Lent,
    /// Whether the helper takes part in the open stretch (set by the lower thread when it opens a
    /// stretch with the seat taken, by the helper when it comes): the lower thread then hands it
    /// the upper runs at the next split it reaches.
    arrived: AtomicBool,
    /// The first sweep of the stretch whose upper part the lower thread handed to the helper;
    /// [`NOT_SHARED`] until then, [`LEFT_ALONE`] once the lower thread has returned without
    /// handing one over.
    shared_from: AtomicU32,
    /// The sweep of each stretch at which the lower thread waits for the helper and hands it the
    /// upper runs ([`solve_joined_at`](super::solve_joined_at)); `None` in the engine.
    join_at: Option<u32>,
    /// Per sweep `k` of the stretch, slot `k % 4` (sweeps four apart are never both running),
    /// each slot on cache lines of its own ([`SweepSlot`]).
    slots: [SweepSlot; 4],
    /// The sweep of the stretch that ended it, `u32::MAX` until one does.
    stop: AtomicU32,
    /// 1 when the stretch's last sweep stopped it unconverged: at its cap, or at a block's end
    /// for a subspace solve.
    unconverged: AtomicU32,
}

/// One sweep's record in [`Shared`]: the threads write it after every run they sweep and read
/// it before every run they start. Packed with the other sweeps' records and the rest of
/// `Shared` on a few cache lines, each such store took the line from the other core, whose next
/// read took it back, two transfers a run a thread; alone on its lines (128 bytes: the
/// adjacent-line prefetcher pairs lines), a slot moves between the cores when the sweep's
/// work does (docs/performance.md).
#[derive(Debug, Default)]
#[repr(align(128))]
struct SweepSlot {
    /// `(k + 1) << 32` and the runs sweep `k` has done (all of them once it is decided).
    progress: AtomicU64,
    /// The largest change of its runs done so far (`f64` bits).
    partial: AtomicU64,
    /// `k + 1` once the lower part of sweep `k` is done.
    handed: AtomicU32,
    /// At a block's end: whether the test of some run done so far found that a subspace solve
    /// would change it (`StopRule::checks_after`).
    unsettled: AtomicBool,
    /// At a block's end: whether the test of some run done so far found a unit that pushes
    /// sliding (`Settled::Sliding`).
    sliding: AtomicBool,
}

// SAFETY: the raw pointers are the island's contacts and velocities, borrowed mutably by
// `solve` for as long as `Shared` lives. The threads touch them only through `run_slices`, for
// runs the wavefront gives one thread at a time (see `Shared::lower`), and the lower thread
// through `Lower::island` between stretches, when the helper touches none but as the subspace
// solve's lent helper (`halves.rs` synchronises that).
#[allow(unsafe_code)]
unsafe impl Sync for Shared<'_> {}

impl<'a> Shared<'a> {
    /// The shared state of a solve of the island at `island` (its contacts and velocities,
    /// borrowed mutably by the caller for as long as this lives) in the runs `starts`, under
    /// `rule`; `join_at` as [`super::solve_joined_at`] takes it.
    pub(super) fn new(
        island: (*mut SolverContact, *mut BodyVelocity),
        starts: &'a [(u32, u32)],
        (rule, join_at): (StopRule, Option<u32>),
    ) -> Self {
        Self {
            contacts: island.0,
            velocities: island.1,
            starts,
            split: split_run(starts),
            rule,
            cap: AtomicU32::new(rule.cap),
            before: AtomicU32::new(rule.before),
            opened: AtomicU32::new(0),
            seat: AtomicU32::new(CLOSED),
            finished: AtomicU32::new(0),
            lent: Lent::new(),
            arrived: AtomicBool::new(false),
            shared_from: AtomicU32::new(NOT_SHARED),
            join_at,
            slots: Default::default(),
            stop: AtomicU32::new(u32::MAX),
            unconverged: AtomicU32::new(0),
        }
    }

    /// The rule of the open stretch.
    fn stretch_rule(&self) -> StopRule {
        let (cap, before) = (self.cap.load(Ordering::Relaxed), self.before.load(Ordering::Relaxed));
        StopRule { cap, before, ..self.rule }
    }

    /// Opens the stretch of sweeps under `rule` (the lower thread, while the helper touches no
    /// stretch state: see [`Shared`]).
    fn open(&self, rule: StopRule) {
        debug_assert_eq!(StopRule { cap: 0, before: 0, ..rule }, StopRule { cap: 0, before: 0, ..self.rule });
        self.cap.store(rule.cap, Ordering::Relaxed);
        self.before.store(rule.before, Ordering::Relaxed);
        // Sweep numbers start again at 0: no sweep of the stretch before may be taken for one of
        // this.
        for slot in 0..4 {
            self.slots[slot].progress.store(0, Ordering::Relaxed);
            self.slots[slot].partial.store(0, Ordering::Relaxed);
            self.slots[slot].handed.store(0, Ordering::Relaxed);
            self.slots[slot].unsettled.store(false, Ordering::Relaxed);
            self.slots[slot].sliding.store(false, Ordering::Relaxed);
        }
        self.stop.store(u32::MAX, Ordering::Relaxed);
        self.unconverged.store(0, Ordering::Relaxed);
        self.shared_from.store(NOT_SHARED, Ordering::Relaxed);
        self.arrived.store(self.seat.load(Ordering::Acquire) == TAKEN, Ordering::Relaxed);
        // Published to a helper that has a seat by the stretch's number, to one that takes it
        // now by the seat (opened first, so that it reads this stretch's number).
        self.opened.store(self.opened.load(Ordering::Relaxed) + 1, Ordering::Release);
        let _ = self.seat.compare_exchange(CLOSED, OPEN, Ordering::AcqRel, Ordering::Relaxed);
    }

    /// Closes the open stretch once the lower thread's sweeps are done: no helper may take a seat
    /// in it any more, and one that has is done with it.
    fn close(&self) {
        if self.seat.compare_exchange(OPEN, CLOSED, Ordering::AcqRel, Ordering::Acquire).is_ok() {
            return;
        }
        let stretch = self.opened.load(Ordering::Relaxed);
        let mut spins = 0u32;
        while self.finished.load(Ordering::Acquire) != stretch && self.seat.load(Ordering::Acquire) != GONE {
            pause(&mut spins);
        }
    }

    /// The helper: takes a seat in the first stretch open after it came, if any, and the upper
    /// part of it and of every stretch after, serving the subspace solves' halves in between;
    /// returns once the stretches are over.
    pub(super) fn help(&self) {
        let _gone = Gone(&self.seat);
        let mut spins = 0u32;
        loop {
            if self.opened.load(Ordering::Acquire) == ENDED {
                return;
            }
            if self.seat.compare_exchange(OPEN, TAKEN, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                break;
            }
            if self.lent.serve() {
                spins = 0;
            } else {
                pause(&mut spins);
            }
        }
        // The stretch open when the seat was taken: the lower thread opens no other before this
        // one is finished here.
        let mut stretch = self.opened.load(Ordering::Acquire);
        loop {
            self.upper(&self.stretch_rule());
            self.finished.store(stretch, Ordering::Release);
            spins = 0;
            loop {
                match self.opened.load(Ordering::Acquire) {
                    ENDED => return,
                    next if next != stretch => {
                        stretch = next;
                        break;
                    }
                    _ if self.lent.serve() => spins = 0,
                    _ => pause(&mut spins),
                }
            }
        }
    }

    /// The lower thread (the solve's own): every run of each sweep until the helper has come,
    /// then the lower part of each sweep from the next split it reaches on.
    fn lower(&self, saved: &mut Saved<'_>, rule: &StopRule) {
        let _unwinding = EndOnPanic(&self.stop);
        let _leaving = LeaveAlone(&self.shared_from);
        let runs = self.starts.len() - 1;
        let mut shared = false;
        for k in 0.. {
            // Whether sweep `k − 2` ended the solve is known only once its upper part is done;
            // until then the copies of sweep `k − 1` are kept. (Sweeps before the first one
            // handed over were decided here, and one that ended the solve ended the loop.)
            if shared && k >= 2 && self.wait(k - 2, runs, k - 1).is_none() {
                return self.put_back(saved);
            }
            if k >= rule.cap || self.stop.load(Ordering::Acquire) < k {
                return;
            }
            if self.join_at == Some(k) {
                let mut spins = 0u32;
                while !self.arrived.load(Ordering::Acquire) && self.seat.load(Ordering::Acquire) != GONE {
                    pause(&mut spins);
                }
            }
            let slot = (k % 4) as usize;
            self.slots[slot].partial.store(0f64.to_bits(), Ordering::Relaxed);
            self.slots[slot].unsettled.store(false, Ordering::Relaxed);
            self.slots[slot].sliding.store(false, Ordering::Relaxed);
            self.slots[slot].progress.store(u64::from(k + 1) << 32, Ordering::Release);
            saved.runs.clear();
            let mut change: f64 = 0.0;
            let may_join = self.join_at.is_none_or(|join| k >= join);
            for run in 0..runs {
                if run == self.split && (shared || (may_join && self.arrived.load(Ordering::Acquire))) {
                    if !shared {
                        self.shared_from.store(k, Ordering::Release);
                        shared = true;
                    }
                    self.slots[slot].handed.store(k + 1, Ordering::Release);
                    break;
                }
                if !self.sweep_run(rule, (k, run), &mut change, Some(&mut *saved)) {
                    return self.put_back(saved);
                }
            }
            if !shared {
                self.decide(rule, k, change);
            }
        }
    }

    /// The helper: once the lower thread hands it a sweep, the upper part of that sweep and
    /// of every sweep after, each once the lower thread has handed it over, and the decision
    /// whether it ends the solve. Returns at once where the lower thread has returned alone.
    fn upper(&self, rule: &StopRule) {
        let _unwinding = EndOnPanic(&self.stop);
        self.arrived.store(true, Ordering::Release);
        let mut spins = 0u32;
        let first = loop {
            match self.shared_from.load(Ordering::Acquire) {
                LEFT_ALONE => return,
                NOT_SHARED => pause(&mut spins),
                first => break first,
            }
        };
        let runs = self.starts.len() - 1;
        for k in first.. {
            if k >= rule.cap || self.stop.load(Ordering::Acquire) < k {
                return;
            }
            let slot = (k % 4) as usize;
            spins = 0;
            while self.slots[slot].handed.load(Ordering::Acquire) != k + 1 {
                // Only a panic of the lower thread ends the solve before this sweep is decided.
                if self.stop.load(Ordering::Acquire) <= k {
                    return;
                }
                pause(&mut spins);
            }
            let mut change = f64::from_bits(self.slots[slot].partial.load(Ordering::Relaxed));
            for run in self.split..runs {
                // The sweep before was decided here (or, for the first one handed over, by the
                // lower thread before it went on): it did not end the solve, so nothing here
                // needs a copy to put back.
                if !self.sweep_run(rule, (k, run), &mut change, None) {
                    return;
                }
            }
            self.decide(rule, k, change);
        }
    }

    /// Sweeps `run` of sweep `k` once the sweep before has done the runs this one's reach,
    /// copying it first into `saved` where the sweep before may still end the solve, and
    /// records the sweep's progress; `false` where a sweep before `k` has ended the solve.
    fn sweep_run(
        &self,
        rule: &StopRule,
        (k, run): (u32, usize),
        change: &mut f64,
        saved: Option<&mut Saved<'_>>,
    ) -> bool {
        let runs = self.starts.len() - 1;
        let slot = (k % 4) as usize;
        // The sweep before has done the runs up to `run + 1`: those this one's reach.
        let may_end = match k.checked_sub(1) {
            Some(before) => match self.wait(before, (run + 2).min(runs), k) {
                Some(partial) => rule.converged(before + 1, partial) || rule.checks_after(before + 1),
                None => return false,
            },
            None => false,
        };
        if may_end && let Some(saved) = saved {
            self.save(run, saved);
        }
        // SAFETY: the wait above gave this thread the run (see `run_slices`).
        #[allow(unsafe_code)]
        let (contacts, mut velocities) = unsafe { self.run_slices(run) };
        let relaxed = relax(contacts, &mut velocities, self.rule.accumulator);
        *change = match self.rule.accumulator {
            Accumulator::Velocity => change.max(relaxed),
            // What the run before leaves undone, which no later run of this sweep changes.
            Accumulator::Split if run > 0 => change.max(self.shortfall(run - 1)),
            Accumulator::Split => *change,
        };
        self.slots[slot].partial.store(change.to_bits(), Ordering::Relaxed);
        // At a block's end, whether a subspace solve would change the run before, which no
        // later run of this sweep changes either, and whether its pushing contacts are at rest.
        // (Once some run is found unsettled, the sweep ends the stretch: no other is tested.)
        let checks = rule.checks_after(k + 1);
        if checks && run > 0 && !self.slots[slot].unsettled.load(Ordering::Relaxed) {
            self.record_settled(slot, self.settled(rule, run - 1));
        }
        // The runs done: for the push-out and at a block's end, those whose shortfall or test is
        // known too, one fewer (the sweep after may not touch the bodies they read before).
        let done = match self.rule.accumulator {
            Accumulator::Velocity if !checks => run + 1,
            Accumulator::Velocity | Accumulator::Split => run,
        };
        if done < runs {
            self.slots[slot].progress.store(u64::from(k + 1) << 32 | done as u64, Ordering::Release);
        }
        true
    }

    /// Ends sweep `k`, whose largest change was `change`: records whether it ends the solve,
    /// then that it is done.
    fn decide(&self, rule: &StopRule, k: u32, mut change: f64) {
        let runs = self.starts.len() - 1;
        if self.rule.accumulator == Accumulator::Split {
            change = change.max(self.shortfall(runs - 1));
        }
        let sweeps = k + 1;
        let slot = (k % 4) as usize;
        // At a block's end, whether a subspace solve would change the island: some run's test
        // found so (`sweep_run`), or the last run's.
        let settled = if rule.checks_after(sweeps) && !self.slots[slot].unsettled.load(Ordering::Relaxed) {
            self.record_settled(slot, self.settled(rule, runs - 1))
        } else {
            Settled::No
        };
        let unsettled = rule.checks_after(sweeps) && settled == Settled::No;
        let converged = rule.converged(sweeps, change) || rule.ends_at_rest(settled, change);
        if converged || sweeps >= rule.cap || unsettled {
            self.unconverged.store(u32::from(!converged), Ordering::Relaxed);
            self.stop.store(k, Ordering::Release);
        }
        self.slots[slot].progress.store(u64::from(k + 1) << 32 | runs as u64, Ordering::Release);
    }

    /// Waits until sweep `before` has done `runs` runs and returns the largest change of its
    /// runs done by then; `None` when a sweep before `own` has ended the solve (or a thread
    /// has panicked: [`EndOnPanic`]).
    fn wait(&self, before: u32, runs: usize, own: u32) -> Option<f64> {
        let slot = (before % 4) as usize;
        let mut spins = 0u32;
        loop {
            let progress = self.slots[slot].progress.load(Ordering::Acquire);
            if self.stop.load(Ordering::Acquire) < own {
                return None;
            }
            if progress >> 32 == u64::from(before + 1) && (progress & u64::from(u32::MAX)) as usize >= runs {
                return Some(f64::from_bits(self.slots[slot].partial.load(Ordering::Relaxed)));
            }
            pause(&mut spins);
        }
    }
}

/// Ends the solve if its thread panics, so that the other thread stops waiting for it and the
/// panic reaches the caller instead of a hang.
struct EndOnPanic<'a>(&'a AtomicU32);

impl Drop for EndOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(0, Ordering::Release);
        }
    }
}

/// Ends the stretches when the lower thread leaves them (a panic included): the helper returns.
pub(super) struct EndBlocks<'a>(pub(super) &'a AtomicU32);

impl Drop for EndBlocks<'_> {
    fn drop(&mut self) {
        self.0.store(ENDED, Ordering::Release);
    }
}

/// Tells the lower thread that the helper has panicked, so that it waits for it no more (the
/// panic reaches the caller once the lower thread is done).
struct Gone<'a>(&'a AtomicU32);

impl Drop for Gone<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(GONE, Ordering::Release);
        }
    }
}

/// Tells a helper still waiting for a sweep that none will come, however the lower thread
/// leaves (a panic included).
struct LeaveAlone<'a>(&'a AtomicU32);

impl Drop for LeaveAlone<'_> {
    fn drop(&mut self) {
        let _ = self.0.compare_exchange(NOT_SHARED, LEFT_ALONE, Ordering::AcqRel, Ordering::Acquire);
    }
}
