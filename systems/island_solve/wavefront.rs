//! Two threads on one island's sweeps, the same bit for bit as one thread (docs/model.md §6).
//!
//! An island's sweeps run its contacts from the ground up, in *runs* of one level each (or of
//! consecutive small levels, [`MERGED_RUN_CONTACTS`]). A contact of level `ℓ` joins bodies of
//! levels `ℓ` and `ℓ + 1`, so runs two apart share no body:
//! while one thread does sweep `k` at run `r + 2` or beyond, another may do sweep `k + 1` at run
//! `r`, and every contact's update then reads exactly the velocities and impulses it reads when
//! one thread does the sweeps one after the other. That is a wavefront over (sweep, run), as a
//! Gauss–Seidel pipeline; Box2D v3 colours its constraint graph instead, which changes the order
//! of the updates and with it the results.
//!
//! Each thread keeps its own runs in every sweep (`Shared::lower`, the solve's thread, the runs
//! before the split, about half the contacts; `Shared::upper`, a helper offered to the pool,
//! the rest), so each half of the contacts stays in one core's cache: the helper does sweep
//! `k`'s upper runs while the lower thread does sweep `k + 1`'s lower ones. (Threads that took
//! whole sweeps in turn moved every contact from one core to the other every sweep; the base-40
//! pyramid's window solves its contacts about 7 % faster on two threads with the split, within
//! the host's noise in some rounds, docs/performance.md.) The lower thread never waits for a
//! helper that has not come: until one has, it sweeps every run and decides every sweep itself,
//! and it hands the helper the upper runs from the first sweep whose split it reaches after the
//! helper came.
//!
//! Whether a sweep ends the solve is known only when its upper runs are done (the helper
//! decides it), and by then the lower thread may have done the next sweep's runs. Where the
//! part of a sweep already done changed some contact by more than the tolerance, or the sweep
//! is short of the levels-plus-one minimum and the part done changed too much for the still
//! test (`StopRule::converged`, which no larger change passes), the sweep cannot end the solve
//! and the next one goes on as it is; else the lower thread first copies what each of its runs
//! will change (the run's impulses and the velocities of the bodies it is first to touch), and
//! puts them back if the sweep before ended the solve. It learns that before it starts the
//! sweep after; the upper thread decides each sweep before it starts the next, so it never
//! needs a copy.
//!
//! The push-out's sweeps end on what they leave undone, not on their change: a sweep reads its
//! run's shortfall once it has swept the run after (no later run of it reaches the run's bodies),
//! and counts the run done only then, so the sweep after it runs one run further behind. The
//! resting solve's sweep that ends a block of `SUBSPACE_PERIOD` tests the same way, run by run,
//! whether a subspace solve would change the island (`StopRule::checks_after`); where none
//! would, the sweeps go on with the pipeline full, and the lower thread copies the runs of the
//! sweep after every such sweep, which may end the stretch of sweeps whatever its change.
//!
//! The runs' bodies need not be levels at all: [`Runs::build`] checks, contact by contact, that
//! no contact reaches a body an earlier run than the one before its own touched first, and
//! the island is solved by one thread where that fails.

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};

use super::halves::{Lent, pause};
use super::{Outcome, Settled, StopRule, Sweeper, relax, shortfall};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{Accumulator, PairVelocities, SolverContact};

/// Islands with fewer contacts than this are solved by one thread, as the contact solver does
/// not split fewer than this between threads either (`PARALLEL_CONTACTS`). The landing pile of
/// 100 blobs, whose largest island has about 100 contacts over 8–9 levels, solved its contacts
/// in 0.90–0.98 ms a step on two threads with this, 0.96–1.12 ms with 512 (a scratch program,
/// alternating; the same bits).
pub(super) const WAVEFRONT_CONTACTS: usize = 64;

/// An island with fewer runs than this gains nothing from two threads on its sweeps.
const WAVEFRONT_RUNS: usize = 4;

/// An island whose runs hold fewer contacts than this on average is swept by one thread: the
/// threads wait on each other's runs in every sweep, and a run of a few contacts costs less
/// than the hand-off (measured when the threads took whole sweeps in turn, each run then
/// handed from one to the other). The landing pile of 100 blobs (steps 61–80: its largest
/// island about 100 contacts over 8–9 levels) solved in 0.68–0.82 ms a step on two threads with this, against
/// 0.80–0.99 ms as a wavefront, once the pool's workers spun through the step; settled (steps
/// 121–150, more contacts a level) the same with and without (a scratch program, alternating,
/// docs/performance.md). The pyramids' levels hold a hundred and more.
const RUN_CONTACTS: usize = 16;

/// Consecutive levels are merged into runs of at least this many contacts: the threads wait on
/// each other's runs, and the top levels of a pyramid hold a few contacts each (measured when
/// the threads took whole sweeps in turn, each run then handed from one to the other). Merging
/// changes no update's order, so no bit. The base-40 pyramid's window
/// (steps 61–80) solved its contacts in 2.55–3.41 ms a step on two threads (median 2.80) with
/// this, 2.83–3.54 (3.02) without and 2.49–3.91 (3.01) with 128; the settling pile of 500's
/// (steps 121–150) in 8.0–9.2 ms (median 8.42) against 8.2–10.0 (8.89) without (a scratch
/// program, alternating rounds, docs/performance.md).
const MERGED_RUN_CONTACTS: u32 = 64;

/// Merges consecutive runs of `starts` (each run's first contact and body, then the end) until
/// each holds at least `least` contacts, the last one excepted (it joins the one before if
/// smaller). A contact of a merged run still reaches no body first touched before the merged run
/// ahead of its own: its level's run ahead lies within it or within the run ahead.
fn merge_small_runs(starts: &mut Vec<(u32, u32)>, least: u32) {
    let end = starts.len() - 1;
    let mut kept = 1;
    for k in 1..end {
        let run_start = starts[kept - 1].0;
        if starts[k].0 - run_start >= least {
            starts[kept] = starts[k];
            kept += 1;
        }
    }
    // The last kept run, if too small, joins the one before.
    if kept > 1 && starts[end].0 - starts[kept - 1].0 < least {
        kept -= 1;
    }
    starts[kept] = starts[end];
    starts.truncate(kept + 1);
}

/// The runs of one island: where each starts among its contacts and among its bodies (the
/// bodies a run is the first to touch), then one entry past the last run. Kept in the step's
/// buffers (no allocation once grown), with the copies the lower thread keeps to put a sweep
/// back (the upper thread never needs one: it decides each sweep itself before the next).
#[derive(Debug, Default)]
pub struct Runs {
    /// `(first contact, first body)` of each run, island-relative, and a last entry with the
    /// island's contact and body counts; empty when the island is not solved as a wavefront.
    starts: Vec<(u32, u32)>,
    /// The impulses `(P_n, P_t)` of the contacts of the runs copied.
    saved_impulses: Vec<[f64; 2]>,
    /// The velocities of the bodies of the runs copied.
    saved_velocities: Vec<BodyVelocity>,
    /// The runs copied in the current sweep.
    saved_runs: Vec<u32>,
}

impl Runs {
    /// Splits `contacts` (one island, in solving order, its bodies numbered in order of first
    /// touch by `local`) into runs of one level each, consecutive levels merged into runs of at
    /// least [`MERGED_RUN_CONTACTS`]; `false`, and no runs, where the island is too small, has
    /// too few levels or too few contacts a level ([`RUN_CONTACTS`]), too few runs once merged,
    /// or a contact reaches a body first touched before the run ahead of its own (runs two apart
    /// would then share a body) or a patch spans two runs.
    pub(super) fn build(&mut self, contacts: &[SolverContact], bodies: usize) -> bool {
        self.starts.clear();
        if contacts.len() < WAVEFRONT_CONTACTS {
            return false;
        }
        let mut next_body = 0u32;
        let mut level = None;
        for (k, contact) in contacts.iter().enumerate() {
            if level != Some(contact.level) {
                if k > 0 && contacts[k - 1].patch_with_next {
                    self.starts.clear();
                    return false;
                }
                level = Some(contact.level);
                self.starts.push((k as u32, next_body));
            }
            let run = self.starts.len() - 1;
            let floor = self.starts[run.saturating_sub(1)].1;
            let (a, b) = contact.local;
            if a.min(b) < floor {
                self.starts.clear();
                return false;
            }
            next_body = next_body.max(a + 1).max(b + 1);
        }
        let few = contacts.len() < RUN_CONTACTS * self.starts.len();
        if self.starts.len() < WAVEFRONT_RUNS || next_body as usize != bodies || few {
            self.starts.clear();
            return false;
        }
        self.starts.push((contacts.len() as u32, bodies as u32));
        merge_small_runs(&mut self.starts, MERGED_RUN_CONTACTS);
        if self.count() < WAVEFRONT_RUNS {
            self.starts.clear();
            return false;
        }
        let runs = self.count();
        self.saved_impulses.resize(contacts.len(), [0.0; 2]);
        self.saved_velocities.resize(bodies, BodyVelocity::ZERO);
        // Room for every run now: a sweep's copies grow nothing while the step runs.
        self.saved_runs.clear();
        self.saved_runs.reserve(runs);
        true
    }

    /// The number of runs (0 when the island is not solved as a wavefront).
    fn count(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }
}

/// Solves one island (`contacts` and its `velocities`, split into `runs` by [`Runs::build`])
/// with two threads on the pool when it has them: `blocks` runs on this thread and does the
/// island's sweeps through [`Lower`] (each stretch of them, up to a subspace solve, the same bit
/// for bit as `solve_island`'s), and does the subspace solves between them, lending them the
/// helper, if one came, while it waits (`halves::Lent`). One `rayon::join` for all the
/// stretches, and a block's end that needs no subspace solve tested within the sweeps: a join a
/// block of 10 sweeps, each with its pipeline's fill and drain, a helper that came late and a
/// serial test between blocks, cost the base-40 pyramid's window about a fifth of its contact
/// solve on two threads (docs/performance.md).
pub(super) fn solve<R: Send>(
    contacts: &mut [SolverContact],
    velocities: &mut [BodyVelocity],
    runs: &mut Runs,
    rule: StopRule,
    blocks: impl FnOnce(&mut Lower<'_, '_>) -> R + Send,
) -> R {
    solve_joined_at(contacts, velocities, runs, (rule, None), blocks)
}

/// [`solve`], where `join_at` is `Some(j)`: the lower thread waits for the helper before sweep
/// `j` of every stretch and hands it the upper runs from sweep `j` on, not before (so that tests see
/// the helper join at a sweep of their choice; never in the engine, where the lower thread must
/// not wait for a worker that may not come).
fn solve_joined_at<R: Send>(
    contacts: &mut [SolverContact],
    velocities: &mut [BodyVelocity],
    runs: &mut Runs,
    (rule, join_at): (StopRule, Option<u32>),
    blocks: impl FnOnce(&mut Lower<'_, '_>) -> R + Send,
) -> R {
    debug_assert!(runs.count() >= WAVEFRONT_RUNS && runs.starts.last().map(|s| s.0 as usize) == Some(contacts.len()));
    debug_assert_eq!(runs.starts.last().map(|s| s.1 as usize), Some(velocities.len()));
    let shared = Shared {
        contacts: contacts.as_mut_ptr(),
        velocities: velocities.as_mut_ptr(),
        starts: &runs.starts,
        split: split_run(&runs.starts),
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
    };
    let mut lower = Lower {
        shared: &shared,
        saved: Saved {
            impulses: &mut runs.saved_impulses,
            velocities: &mut runs.saved_velocities,
            runs: &mut runs.saved_runs,
        },
    };
    let (result, ()) = rayon::join(
        || {
            let _end = EndBlocks(&shared.opened);
            blocks(&mut lower)
        },
        || shared.help(),
    );
    result
}

/// The solve's own thread on a wavefront island: each stretch's lower runs (and every run until
/// a helper has come), and the island between stretches.
pub(super) struct Lower<'s, 'a> {
    shared: &'s Shared<'a>,
    saved: Saved<'s>,
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

/// One thread's copies of what its sweep changed, to put back.
struct Saved<'a> {
    impulses: &'a mut [[f64; 2]],
    velocities: &'a mut [BodyVelocity],
    runs: &'a mut Vec<u32>,
}

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
struct Shared<'a> {
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
    opened: AtomicU32,
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
    /// upper runs ([`solve_joined_at`]); `None` in the engine.
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

impl Shared<'_> {
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
    fn help(&self) {
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

    /// What the push-out's sweep this thread is on leaves undone at `run`'s contacts
    /// ([`shortfall`]), once it has swept `run + 1` (or `run` is the last): no later run of the
    /// sweep reaches their bodies, and the sweep after is not given `run − 1`, whose bodies they
    /// share, until this one says it has done `run` (for the push-out a run counts as done once
    /// its shortfall is known).
    fn shortfall(&self, run: usize) -> f64 {
        // SAFETY: this thread holds `run + 1` (or the last run) of its sweep, and the other
        // thread's sweep holds no run less than two away from `run` (see above and
        // `run_slices`); nothing is written.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        shortfall(contacts, &velocities, self.rule.slack)
    }

    /// Records a run's answer at a block's end ([`Shared::settled`]) in sweep slot `slot`, and
    /// returns the answer of the runs tested so far in that sweep: no if any said no, at rest if all
    /// did.
    fn record_settled(&self, slot: usize, answer: Settled) -> Settled {
        let record = &self.slots[slot];
        match answer {
            Settled::No => record.unsettled.store(true, Ordering::Relaxed),
            Settled::Sliding => record.sliding.store(true, Ordering::Relaxed),
            Settled::AtRest => {}
        }
        if record.unsettled.load(Ordering::Relaxed) {
            Settled::No
        } else if record.sliding.load(Ordering::Relaxed) {
            Settled::Sliding
        } else {
            Settled::AtRest
        }
    }

    /// Whether a subspace solve would leave `run`'s contacts as they are ([`StopRule::settled`]),
    /// at the end of a block: as for [`Shared::shortfall`], once this thread has swept `run + 1`
    /// (or `run` is the last), and the sweep after is not given `run − 1` before.
    fn settled(&self, rule: &StopRule, run: usize) -> Settled {
        // SAFETY: as for `shortfall`: nothing is written, and no other thread holds a run less
        // than two away from `run`.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        rule.settled(contacts, (velocities.slice, velocities.base))
    }

    /// Copies what `run` will change: its contacts' impulses and its own bodies' velocities.
    fn save(&self, run: usize, saved: &mut Saved<'_>) {
        // SAFETY: called by the thread the wait gave the run to, before it sweeps it.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        let (first_contact, first_body) = (self.starts[run].0 as usize, self.starts[run].1 as usize);
        for (copy, contact) in saved.impulses[first_contact..].iter_mut().zip(contacts.iter_mut()) {
            let (normal, tangent, _) = contact.accumulated(self.rule.accumulator);
            *copy = [*normal, *tangent];
        }
        let own = &velocities.slice[first_body - velocities.base as usize..];
        saved.velocities[first_body..first_body + own.len()].copy_from_slice(own);
        saved.runs.push(run as u32);
    }

    /// Puts back every run this thread copied in its current sweep, which a sweep before it
    /// ended the solve: the island is then as that sweep left it.
    fn put_back(&self, saved: &mut Saved<'_>) {
        for &run in saved.runs.iter() {
            let run = run as usize;
            // SAFETY: the sweep before this thread's has ended the solve, so the other thread has
            // returned or is about to, touching nothing more.
            #[allow(unsafe_code)]
            let (contacts, velocities) = unsafe { self.run_slices(run) };
            let (first_contact, first_body) = (self.starts[run].0 as usize, self.starts[run].1 as usize);
            for (contact, copy) in contacts.iter_mut().zip(&saved.impulses[first_contact..]) {
                let (normal, tangent, _) = contact.accumulated(self.rule.accumulator);
                [*normal, *tangent] = *copy;
            }
            let own = &mut velocities.slice[first_body - velocities.base as usize..];
            let count = own.len();
            own.copy_from_slice(&saved.velocities[first_body..first_body + count]);
        }
        saved.runs.clear();
    }

    /// The contacts of `run` and the velocities of the bodies they reach: those the run before
    /// and this one were first to touch.
    ///
    /// # Safety
    ///
    /// No other thread may hold the slices of a run less than two away from `run` (or of `run`
    /// itself) while these live. The wavefront gives run `r` of sweep `k + 1` only once sweep
    /// `k` has done run `r + 1`; each thread goes run by run through its part; the upper thread
    /// starts its part of sweep `k` only once the lower one has done all of its own; and the
    /// lower thread starts sweep `k + 2` only once sweep `k` is done, so it is at most one
    /// sweep ahead. So while one thread holds run `r` the other holds a run at least two ahead
    /// of it or behind it, or waits, or has returned (the lower thread puts back the runs of a
    /// sweep only once the sweep before it has ended the solve or a thread has panicked: the
    /// helper's last access to the runs comes before it stores the end). For the push-out a run
    /// counts as done only once its shortfall is read, which reads the run before it (see
    /// `Shared::shortfall`).
    /// Two runs apart, the contacts differ, and so do the bodies: those runs `r − 1` and `r`
    /// first touched against runs `r + 1` and later ([`Runs::build`] checks that no contact of
    /// run `r` reaches a body first touched before run `r − 1`).
    #[allow(unsafe_code, clippy::mut_from_ref)]
    unsafe fn run_slices(&self, run: usize) -> (&mut [SolverContact], RunVelocities<'_>) {
        let (first_contact, _) = self.starts[run];
        let (end_contact, end_body) = self.starts[run + 1];
        let first_body = self.starts[run.saturating_sub(1)].1;
        // SAFETY: the ranges lie within the island's contacts and velocities, whose pointers
        // `solve` took from slices it borrows mutably while `self` lives (`Runs::build` checks the
        // starts against the island's counts); the caller holds the run (see above).
        unsafe {
            let contacts = std::slice::from_raw_parts_mut(
                self.contacts.add(first_contact as usize),
                (end_contact - first_contact) as usize,
            );
            let velocities = std::slice::from_raw_parts_mut(
                self.velocities.add(first_body as usize),
                (end_body - first_body) as usize,
            );
            (contacts, RunVelocities { base: first_body, slice: velocities })
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
struct EndBlocks<'a>(&'a AtomicU32);

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

/// The velocities one run reaches, by the island-relative `local` index less `base`.
struct RunVelocities<'a> {
    base: u32,
    slice: &'a mut [BodyVelocity],
}

impl PairVelocities for RunVelocities<'_> {
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity) {
        let (a, b) = contact.local;
        (self.slice[(a - self.base) as usize], self.slice[(b - self.base) as usize])
    }

    fn set_pair(&mut self, contact: &SolverContact, va: BodyVelocity, vb: BodyVelocity) {
        let (a, b) = contact.local;
        (self.slice[(a - self.base) as usize], self.slice[(b - self.base) as usize]) = (va, vb);
    }
}

#[cfg(test)]
pub(super) mod tests {
    use glam::DVec2;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::super::subspace::ScratchBuffers;
    use super::super::{OneThread, StopRule, Sweeper, blocks, solve_island};
    use super::*;
    use crate::dynamics::solver::prepare_patches;
    use crate::simulation::SolverSettings;

    /// `columns` stacks of `levels` boxes on one ground, each box resting on the one below by a
    /// two-point patch, in solving order (level by level), the bodies numbered by first touch,
    /// with random velocities and warm impulses.
    pub(in crate::systems::island_solve) fn stacks(
        columns: u32,
        levels: u32,
        seed: u64,
    ) -> (Vec<SolverContact>, Vec<BodyVelocity>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut contacts = Vec::new();
        // Body (column, level ≥ 1) before numbering; the ground is (0, 0).
        let mut order = vec![(0, 0)];
        let number = |body: (u32, u32), order: &mut Vec<(u32, u32)>| {
            let body = if body.1 == 0 { (0, 0) } else { body };
            match order.iter().position(|&b| b == body) {
                Some(index) => index as u32,
                None => {
                    order.push(body);
                    order.len() as u32 - 1
                }
            }
        };
        for level in 0..levels {
            for column in 0..columns {
                let below = number((column, level), &mut order);
                let above = number((column, level + 1), &mut order);
                let lower_inverse = if level == 0 { [0.0, 0.0] } else { [1.0, 6.0] };
                let inverse = [1.0, 6.0, lower_inverse[0], lower_inverse[1]];
                for end in 0..2 {
                    let x = if end == 0 { -0.4 } else { 0.4 } + rng.random_range(-0.01..0.01);
                    let arms = (DVec2::new(x, -0.5), DVec2::new(x, 0.5));
                    let normal = DVec2::new(rng.random_range(-1e-3..1e-3), 1.0).normalize();
                    contacts.push(SolverContact {
                        band: 0.01,
                        level,
                        local: (above, below),
                        patch_with_next: end == 0,
                        normal_impulse: rng.random_range(0.0..0.1),
                        ..SolverContact::for_test(inverse, arms, normal, 0.5)
                    });
                }
            }
        }
        prepare_patches(&mut contacts);
        let velocities = (0..order.len())
            .map(|k| match k {
                0 => BodyVelocity::ZERO,
                _ => BodyVelocity {
                    linear: DVec2::new(rng.random_range(-1e-3..1e-3), rng.random_range(-0.09..-0.07)),
                    angular: rng.random_range(-1e-3..1e-3),
                },
            })
            .collect();
        (contacts, velocities)
    }

    /// The bits of the bodies' velocities.
    fn bits(velocities: &[BodyVelocity]) -> Vec<u64> {
        velocities.iter().flat_map(|v| [v.linear.x, v.linear.y, v.angular]).map(f64::to_bits).collect()
    }

    /// The bits of what `of` reads of each contact.
    fn contact_bits(contacts: &[SolverContact], of: impl Fn(&SolverContact) -> [f64; 2]) -> Vec<u64> {
        contacts.iter().flat_map(of).map(f64::to_bits).collect()
    }

    /// The wavefront on two threads gives the serial solve's impulses, velocities and sweep
    /// count bit for bit, whether the solve converges early (the lower thread's speculative
    /// runs put back), late or stops at its cap, with the helper joining at the first sweep, a
    /// later one, or whenever it comes.
    #[test]
    fn two_threads_give_the_serial_solve_bit_for_bit() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let mut stops = Vec::new();
        for (trial, tolerance) in [1.0, 1e-1, 1e-2, 1e-3, 1e-5, 0.0].into_iter().cycle().take(24).enumerate() {
            let settings = SolverSettings { tolerance, ..SolverSettings::default() };
            // The helper joins at the first sweep, the second, the fourth (the lower thread
            // sweeping alone until then), or whenever it comes.
            let join = [Some(0), Some(1), Some(3), None][trial % 4];
            let (one, runs, helped) = against_serial(&pool, stacks(60, 6, trial as u64), &settings, (trial, join));
            if let Some(join) = join {
                let expected = u64::from(one.most_sweeps.saturating_sub(join));
                assert_eq!(helped, expected, "trial {trial}: sweeps shared, joined at {join}");
            }
            assert_eq!(runs, 6);
            stops.push((one.most_sweeps, one.unconverged));
        }
        // The trials cover a solve that ends before the cap and one that stops at it.
        assert!(stops.iter().any(|&(_, unconverged)| unconverged == 0), "{stops:?}");
        assert!(stops.iter().any(|&(_, unconverged)| unconverged == 1), "{stops:?}");
    }

    /// Levels of fewer than [`MERGED_RUN_CONTACTS`] contacts merge into runs of at least that
    /// many (a last small one joining the run before), and islands whose levels merged give the
    /// serial solve's bits on two threads.
    #[test]
    fn small_levels_merge_into_runs_that_give_the_serial_bits() {
        let mut starts = vec![(0, 0), (40, 1), (80, 21), (150, 41), (170, 60), (190, 70), (200, 75)];
        merge_small_runs(&mut starts, 64);
        // Runs of 40, 40, 70, 20, 20 and 10 contacts: 80, 70, and the last 50 joining the 70.
        assert_eq!(starts, [(0, 0), (80, 21), (200, 75)]);
        let mut starts = vec![(0, 0), (100, 1), (200, 51)];
        merge_small_runs(&mut starts, 64);
        assert_eq!(starts, [(0, 0), (100, 1), (200, 51)]);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for (trial, tolerance) in [1e-1, 1e-3, 0.0].into_iter().enumerate() {
            // 40 contacts a level: two levels a run.
            let settings = SolverSettings { tolerance, ..SolverSettings::default() };
            let (_, runs, _) = against_serial(&pool, stacks(20, 16, 90 + trial as u64), &settings, (trial, Some(0)));
            assert_eq!(runs, 8);
        }
    }

    /// Solves the island `(contacts, velocities)` at `settings` by the serial sweeps and as a
    /// wavefront on `pool`, checks that both take the same sweeps and give the same bits, and
    /// returns the serial outcome and the runs the island split into.
    fn against_serial(
        pool: &rayon::ThreadPool,
        (mut serial, mut serial_velocities): (Vec<SolverContact>, Vec<BodyVelocity>),
        settings: &SolverSettings,
        (trial, join_at): (usize, Option<u32>),
    ) -> (Outcome, usize, u64) {
        let (mut shared, mut shared_velocities) = (serial.clone(), serial_velocities.clone());
        let rule = StopRule::new(&serial, settings, 1.0 / 120.0);
        let one = solve_island(&mut serial, &mut serial_velocities, rule);
        let mut runs = Runs::default();
        assert!(runs.build(&shared, shared_velocities.len()), "the stacks split into runs");
        let two = pool.install(|| {
            solve_joined_at(&mut shared, &mut shared_velocities, &mut runs, (rule, join_at), |lower| lower.sweep(rule))
        });
        assert_eq!((two.most_sweeps, two.unconverged), (one.most_sweeps, one.unconverged), "trial {trial}");
        assert_eq!(bits(&shared_velocities), bits(&serial_velocities), "trial {trial}: velocities differ");
        let impulses = |c: &SolverContact| [c.normal_impulse, c.tangent_impulse];
        assert_eq!(contact_bits(&shared, impulses), contact_bits(&serial, impulses), "trial {trial}: impulses");
        (one, runs.count(), two.wavefront_shared_sweeps)
    }

    /// The push-out's sweeps of the split impulses on two threads give the serial sweeps' split
    /// impulses and pseudo-velocities bit for bit, and leave the resting impulses alone: a fixed
    /// count (`position_tolerance` and `position_shortfall` 0) and sweeps that stop once every
    /// contact is within its allowance, before their cap, with and without the slack.
    #[test]
    fn push_out_sweeps_on_two_threads_give_the_serial_bits() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let trials = [
            (1, 0.0, 0.0),
            (2, 0.0, 0.0),
            (4, 0.0, 0.0),
            (7, 0.0, 0.0),
            (500, 1e-1, 0.0),
            (500, 5e-2, 0.0),
            (500, 1e-3, 0.25),
            (500, 1e-6, 0.5),
        ];
        for (trial, (sweeps, tolerance, shortfall)) in trials.into_iter().enumerate() {
            let (mut serial, _) = stacks(40, 8, 100 + trial as u64);
            let mut rng = StdRng::seed_from_u64(trial as u64);
            for contact in &mut serial {
                // Negative targets too: a bounce that leaves the band by itself.
                contact.bias_speed = rng.random_range(-0.2..0.2);
            }
            let resting: Vec<u64> = serial.iter().map(|c| c.normal_impulse.to_bits()).collect();
            let mut serial_velocities = vec![BodyVelocity::ZERO; 40 * 8 + 1];
            let (mut shared, mut shared_velocities) = (serial.clone(), serial_velocities.clone());
            let settings = SolverSettings {
                position_iterations: sweeps,
                position_tolerance: tolerance,
                position_shortfall: shortfall,
                ..SolverSettings::default()
            };
            let rule = StopRule::push_out(&serial, &settings, 1.0 / 120.0);
            let one = solve_island(&mut serial, &mut serial_velocities, rule);
            let mut runs = Runs::default();
            assert!(runs.build(&shared, shared_velocities.len()), "the stacks split into runs");
            let join = (trial % 3) as u32;
            let two = pool.install(|| {
                let at = (rule, Some(join));
                solve_joined_at(&mut shared, &mut shared_velocities, &mut runs, at, |lower| lower.sweep(rule))
            });
            assert_eq!((one.most_sweeps, one.unconverged), (two.most_sweeps, two.unconverged), "trial {trial}");
            let expected = u64::from(two.most_sweeps.saturating_sub(join));
            assert_eq!(two.wavefront_shared_sweeps, expected, "trial {trial}: sweeps shared, joined at {join}");
            if tolerance == 0.0 {
                assert_eq!((one.most_sweeps, one.unconverged), (sweeps, 1), "trial {trial}: a fixed count");
            } else {
                assert!(one.unconverged == 0 && one.most_sweeps > 7, "trial {trial}: converged after {one:?}");
            }
            assert_eq!(bits(&shared_velocities), bits(&serial_velocities), "trial {trial}: pseudo-velocities differ");
            let split = |c: &SolverContact| [c.bias_impulse, c.bias_tangent_impulse];
            assert_eq!(
                contact_bits(&shared, split),
                contact_bits(&serial, split),
                "trial {trial}: split impulses differ"
            );
            assert!(serial.iter().any(|c| c.bias_impulse > 0.0), "trial {trial}: nothing pushed");
            let kept: Vec<u64> = shared.iter().map(|c| c.normal_impulse.to_bits()).collect();
            assert_eq!(kept, resting, "trial {trial}: the resting impulses were touched");
        }
    }

    /// Where no second thread comes (a pool of one, as when the pool's other worker is busy),
    /// the one thread takes every sweep: the serial bits again, for solves that end early, late
    /// and at caps of one, two and three sweeps.
    #[test]
    fn one_thread_alone_takes_every_sweep() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let mut stops = Vec::new();
        for (trial, (tolerance, iterations)) in
            [(1.0, 100), (1e-2, 100), (1e-5, 100), (0.0, 100), (0.0, 1), (0.0, 2), (0.0, 3)].into_iter().enumerate()
        {
            let settings = SolverSettings { tolerance, iterations, ..SolverSettings::default() };
            let (one, _, helped) = against_serial(&pool, stacks(40, 7, 50 + trial as u64), &settings, (trial, None));
            stops.push(one.most_sweeps);
            assert_eq!(helped, 0, "trial {trial}: a pool of one has no second thread");
        }
        // Solves of one, two and three sweeps, and longer ones.
        assert!([1, 2, 3].iter().all(|n| stops.contains(n)) && stops.iter().any(|&n| n > 3), "{stops:?}");
    }

    /// The resting solve in blocks with subspace solves between them on two threads, the
    /// threads meeting once for all the blocks, gives the one-thread blocks' impulses,
    /// velocities and counts bit for bit, with the helper joining at the first sweep of every
    /// stretch of sweeps, a later one (a block's last among them), or whenever it comes; and a
    /// pool of one does every block alone. The trials cross blocks' ends that need no subspace
    /// solve and stop at ones that do, several in one solve.
    #[test]
    fn blocks_on_two_threads_give_the_serial_bits() {
        let period = super::super::SUBSPACE_PERIOD;
        let (mut several, mut halves, mut crossed, mut stopped) = (0, 0, 0, 0);
        // Wide and shallow with the default subspace iterations; narrow and tall with few, so
        // that the cap leaves room for many blocks' ends.
        for (columns, levels, subspace) in [(30, 12, 25), (10, 30, 3)] {
            for threads in [2, 1] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                for (trial, tolerance) in [1.0, 1e-1, 1e-3, 1e-5, 1e-7, 0.0].into_iter().cycle().take(12).enumerate() {
                    let trial = (levels, threads, trial);
                    let (mut serial, mut serial_velocities) = stacks(columns, levels, 200 + trial.2 as u64);
                    if trial.2 >= 6 {
                        // The second round of tolerances: the top level slides on slippery
                        // contacts, its units pushing without sticking, so a block's end where
                        // every row is solved does not end the solve before the level minimum
                        // (`Settled::Sliding`), and the sweeps go on past it.
                        for contact in serial.iter_mut().filter(|c| c.level == levels - 1) {
                            contact.friction = 1e-3;
                            serial_velocities[contact.local.0 as usize].linear.x += 0.3;
                        }
                    }
                    let (mut shared, mut shared_velocities) = (serial.clone(), serial_velocities.clone());
                    let settings = SolverSettings { tolerance, subspace_iterations: subspace, ..Default::default() };
                    let rule = StopRule { period, ..StopRule::new(&serial, &settings, 1.0 / 120.0) };
                    // The first stretch alone: past a block's end, or stopped at one.
                    let (mut first, mut first_velocities) = (serial.clone(), serial_velocities.clone());
                    let stretch = solve_island(&mut first, &mut first_velocities, rule.after(0, false));
                    crossed += u32::from(stretch.most_sweeps > period && rule.checks_after(period));
                    stopped += u32::from(stretch.unconverged == 1 && stretch.most_sweeps < rule.cap);
                    let mut buffers = ScratchBuffers::default();
                    let scratch = buffers.scratch(serial.len(), serial_velocities.len());
                    let island = &mut OneThread { contacts: &mut serial, velocities: &mut serial_velocities };
                    let one = blocks(island, rule, Some(scratch));
                    let mut runs = Runs::default();
                    assert!(runs.build(&shared, shared_velocities.len()), "the stacks split into runs");
                    let scratch = buffers.scratch(shared.len(), shared_velocities.len());
                    // (A pool of one has no helper to wait for.)
                    let join =
                        if threads == 1 { None } else { [Some(0), Some(4), Some(period - 1), None][trial.2 % 4] };
                    let two = pool.install(|| {
                        let at = (rule, join);
                        solve_joined_at(&mut shared, &mut shared_velocities, &mut runs, at, |lower| {
                            blocks(lower, rule, Some(scratch))
                        })
                    });
                    let counts = |o: &Outcome| {
                        (o.most_sweeps, o.unconverged, o.subspace_iterations, o.subspace_holds, o.subspace_halves)
                    };
                    assert_eq!(counts(&two), counts(&one), "trial {trial:?}");
                    assert_eq!(bits(&shared_velocities), bits(&serial_velocities), "trial {trial:?}: velocities");
                    let impulses = |c: &SolverContact| [c.normal_impulse, c.tangent_impulse];
                    assert_eq!(contact_bits(&shared, impulses), contact_bits(&serial, impulses), "trial {trial:?}");
                    let sweeps = u64::from(one.most_sweeps) - one.subspace_iterations;
                    match join {
                        // A pool of one has no second thread.
                        _ if threads == 1 => assert_eq!(two.wavefront_shared_sweeps, 0, "trial {trial:?}"),
                        // Handed over at the first sweep of every stretch: every sweep shared.
                        Some(0) => assert_eq!(two.wavefront_shared_sweeps, sweeps, "trial {trial:?}"),
                        Some(j) if one.most_sweeps > j => assert!(two.wavefront_shared_sweeps > 0, "trial {trial:?}"),
                        _ => {}
                    }
                    several += u32::from(one.subspace_iterations > 0 && one.most_sweeps > 2 * period);
                    halves += one.subspace_halves;
                }
            }
        }
        // Some trials went through several blocks with subspace solves between them, and some
        // of those split into halves (which the wavefront's helper, lent to them on two threads,
        // may or may not have served: the bits are the same); some went on past a block's end,
        // some stopped at one.
        assert!(several > 0 && halves > 0, "{several} trials of several blocks, {halves} iterations by halves");
        assert!(crossed > 0 && stopped > 0, "first stretches: {crossed} past a block's end, {stopped} stopped at one");
    }

    /// Ten columns of 16 boxes brought to rest (by a subspace solve, which says so) and solved
    /// again in blocks, as they are and with a box pushed at 1e-5 m/s: the end of the first block
    /// finds every pushing contact at rest and ends the solve there, converged, short of the 16
    /// sweeps of its level minimum, on one thread and two alike. The test itself: at rest; with a
    /// patch's friction at its bound (a unit that pushes without sticking, whose normals it does
    /// not test), sliding; with a box moving, a subspace solve would change the island.
    /// (`blocks_on_two_threads_give_the_serial_bits` crosses blocks' ends where a top level
    /// slides.)
    #[test]
    fn an_island_at_rest_ends_its_solve_before_the_level_minimum() {
        use super::super::subspace::{self, Settled};
        let (levels, h) = (16, 1.0 / 120.0);
        let settings = SolverSettings::default();
        let tolerance = (settings.tolerance, h);
        for seed in 0..5 {
            let (mut contacts, mut velocities) = stacks(10, levels, seed);
            for contact in &mut contacts {
                contact.normal_impulse = 0.5 * f64::from(levels - contact.level) * 9.81 * h;
            }
            let mut buffers = ScratchBuffers::default();
            let mut scratch = buffers.scratch(contacts.len(), velocities.len());
            let which = (60 * levels, Accumulator::Velocity);
            let solved = subspace::solve(&mut contacts, &mut velocities, &mut scratch, which, tolerance, None);
            assert!(solved.at_rest, "seed {seed}: {solved:?}");
            let at = |contacts: &[SolverContact], velocities: &[BodyVelocity]| {
                subspace::settled(contacts, (velocities, 0), Accumulator::Velocity, tolerance)
            };
            assert_eq!(at(&contacts, &velocities), Settled::AtRest, "seed {seed}");
            let mut moving = velocities.clone();
            moving[1].linear.x += 1e-3;
            assert_eq!(at(&contacts, &moving), Settled::No, "seed {seed}");
            let mut sliding = contacts.clone();
            assert!(sliding[0].patch_with_next);
            sliding[0].tangent_impulse = sliding[0].friction * (sliding[0].normal_impulse + sliding[1].normal_impulse);
            assert_eq!(at(&sliding, &velocities), Settled::Sliding, "seed {seed}");

            let rule = StopRule { period: super::super::SUBSPACE_PERIOD, ..StopRule::new(&contacts, &settings, h) };
            assert_eq!(rule.min_sweeps, levels);
            for push in [0.0, 1e-5] {
                let mut pushed = velocities.clone();
                pushed[1].linear.y += push;
                let (mut one, mut one_velocities) = (contacts.clone(), pushed.clone());
                let (mut two, mut two_velocities) = (contacts.clone(), pushed);
                let scratch = buffers.scratch(one.len(), one_velocities.len());
                let serial =
                    blocks(&mut OneThread { contacts: &mut one, velocities: &mut one_velocities }, rule, Some(scratch));
                assert_eq!((serial.most_sweeps, serial.unconverged), (rule.period, 0), "seed {seed}, push {push:e}");
                let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
                let mut runs = Runs::default();
                assert!(runs.build(&two, two_velocities.len()), "the columns split into runs");
                let scratch = buffers.scratch(two.len(), two_velocities.len());
                let shared = pool.install(|| {
                    solve_joined_at(&mut two, &mut two_velocities, &mut runs, (rule, Some(0)), |lower| {
                        blocks(lower, rule, Some(scratch))
                    })
                });
                assert_eq!((shared.most_sweeps, shared.unconverged), (rule.period, 0), "seed {seed}, push {push:e}");
                assert_eq!(bits(&two_velocities), bits(&one_velocities), "seed {seed}, push {push:e}");
            }
        }
    }

    /// After a subspace solve that left the island at rest, the level minimum counts as met: the
    /// next sweep within the tolerance ends the solve, where without it the sweeps go on to the
    /// minimum.
    #[test]
    fn a_subspace_solve_at_rest_meets_the_level_minimum() {
        let (contacts, _) = stacks(10, 40, 3);
        let settings = SolverSettings::default();
        let rule =
            StopRule { period: super::super::SUBSPACE_PERIOD, ..StopRule::new(&contacts, &settings, 1.0 / 120.0) };
        assert_eq!(rule.min_sweeps, 40);
        let within = settings.tolerance * 120.0 * 0.5;
        for before in [11, 20, 35] {
            assert!(rule.after(before, true).converged(1, within), "after {before}");
            assert!(!rule.after(before, false).converged(1, within), "after {before}");
            assert!(rule.after(before, false).converged(rule.min_sweeps - before, within), "after {before}");
            assert!(!rule.after(before, true).converged(1, 2.0 * settings.tolerance * 120.0), "after {before}");
        }
    }

    /// A panic between blocks reaches the caller, with the helper waiting for the next block,
    /// instead of a hang.
    #[test]
    fn a_panic_between_blocks_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let (mut contacts, mut velocities) = stacks(30, 8, 7);
        let settings = SolverSettings { tolerance: 0.0, ..SolverSettings::default() };
        let rule = StopRule::new(&contacts, &settings, 1.0 / 120.0);
        let mut runs = Runs::default();
        assert!(runs.build(&contacts, velocities.len()));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| {
                solve_joined_at(&mut contacts, &mut velocities, &mut runs, (rule, Some(0)), |lower| {
                    let block = lower.sweep(rule);
                    assert_eq!(block.wavefront_shared_sweeps, u64::from(block.most_sweeps));
                    panic!("between blocks");
                })
            })
        }));
        let message = result.expect_err("the panic reaches the caller");
        assert_eq!(message.downcast_ref::<&str>(), Some(&"between blocks"));
    }

    /// An island whose contacts reach bodies two runs back is left to one thread.
    #[test]
    fn runs_that_would_share_a_body_are_refused() {
        let (mut contacts, velocities) = stacks(60, 6, 1);
        let mut runs = Runs::default();
        assert!(runs.build(&contacts, velocities.len()));
        // A contact of the top run reaching the first box of the bottom run.
        let last = contacts.len() - 1;
        contacts[last].local.1 = 1;
        assert!(!runs.build(&contacts, velocities.len()));
        assert_eq!(runs.count(), 0);
    }
}
