//! Work in two halves, on two threads when the pool has them and the caller asks for a helper:
//! the subspace solve's passes (`subspace.rs`), each split into a fixed half 0 and half 1
//! whatever the thread count.
//!
//! One thread, the *leader*, runs the solve and posts each pass; a *helper*, offered to the
//! pool beside it, spins until a pass is posted and claims its half 1. The leader does half 0,
//! then claims half 1 itself unless the helper has, and waits only for a half the helper has
//! claimed and is running. So the leader never waits for a thread that has not come: where no
//! worker takes the helper (one thread, or the pool's other workers busy with other islands),
//! the leader does both halves, one after the other, and the results are the same bit for bit,
//! since each half's work is the same whoever does it.
//!
//! A thread already waiting beside the leader may be lent instead ([`Lent`]): the wavefront's
//! helper, which waits between an island's stretches of sweeps while the leader does the
//! subspace solve (`wavefront.rs`). It then serves the passes where a helper offered to the pool would
//! find no worker free.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicPtr, AtomicU32, AtomicU64, Ordering};

/// A pass, run once for each half (0 and 1).
pub(super) type Pass<'a> = &'a (dyn Fn(usize) + Sync + 'a);

/// The leader's and the helper's meeting point (see the module documentation).
pub(super) struct Halves {
    /// The number of the last pass posted (passes count from 1), [`QUIT`] once the leader is done.
    posted: AtomicU64,
    /// The number of the last pass whose half 1 a thread has claimed.
    claimed: AtomicU64,
    /// The number of the last pass whose half 1 the helper has done, [`FAILED`] if it panicked.
    done: AtomicU64,
    /// The last pass posted, written by the leader before it posts it (its lifetime erased: it
    /// is read only while [`Halves::run`] waits for it, see there).
    pass: UnsafeCell<Option<Pass<'static>>>,
}

// SAFETY: `pass` is written only by the leader, before it posts the pass's number (a release
// store that the helper's acquire load of `posted` pairs with), and read by the helper only once
// it has claimed the pass's half 1, while the leader waits for that half and writes nothing.
#[allow(unsafe_code)]
unsafe impl Sync for Halves {}

/// `posted` once the leader is done: the helper returns.
const QUIT: u64 = u64::MAX;

/// `done` when the helper's half panicked: the leader stops waiting and panics too.
const FAILED: u64 = u64::MAX;

/// Spins of a waiting thread before it yields its core (the host may have given it to another
/// process); the wavefront's threads wait the same way.
const SPINS: u32 = 1 << 12;

impl Halves {
    pub(super) fn new() -> Self {
        Self {
            posted: AtomicU64::new(0),
            claimed: AtomicU64::new(0),
            done: AtomicU64::new(0),
            pass: UnsafeCell::new(None),
        }
    }

    /// Runs `lead` on this thread with a helper beside it when `two` and the pool has more than
    /// one thread: the `lent` one if given (which may or may not come), else one offered to the
    /// pool; `lead` runs its passes through [`Leader::run`].
    pub(super) fn lead<R: Send>(two: bool, lent: Option<&Lent>, lead: impl FnOnce(&Leader<'_>) -> R + Send) -> R {
        let halves = Halves::new();
        let leader = |halves| Leader { halves, only_here: PhantomData };
        if !two || rayon::current_num_threads() < 2 || rayon::current_thread_index().is_none() {
            return lead(&leader(&halves));
        }
        if let Some(lent) = lent {
            debug_assert_eq!(lent.state.load(Ordering::Relaxed), EMPTY, "one leader at a time");
            lent.halves.store(std::ptr::from_ref(&halves).cast_mut(), Ordering::Relaxed);
            lent.state.store(POSTED, Ordering::Release);
            let _back = Retract { lent, halves: &halves };
            return lead(&leader(&halves));
        }
        let (result, ()) = rayon::join(
            || {
                let _quit = Quit(&halves);
                lead(&leader(&halves))
            },
            || halves.help(),
        );
        result
    }

    /// Runs `pass` on both halves: half 0 on this thread, half 1 on the helper if it claims it
    /// first; returns once both are done. Only through [`Leader::run`]: one thread, and not
    /// from within a pass.
    fn run(&self, pass: Pass<'_>) {
        let number = self.posted.load(Ordering::Relaxed) + 1;
        // SAFETY: the helper reads the cell only after claiming a posted pass, and every pass
        // posted before this one has had its half 1 done (the leader waited for it), so no read
        // is under way. The lifetime is erased: the helper calls the pass only between its claim
        // and its `done`, and this function returns (or unwinds, see `Unwinding`) only after the
        // helper's `done` or once no claim of it can succeed, so `pass` outlives every call.
        #[allow(unsafe_code)]
        unsafe {
            *self.pass.get() = Some(std::mem::transmute::<Pass<'_>, Pass<'static>>(pass));
        }
        self.posted.store(number, Ordering::Release);
        let unwinding = Unwinding { halves: self, number };
        pass(0);
        std::mem::forget(unwinding);
        if self.claim(number) {
            pass(1);
            return;
        }
        assert!(self.helper_done(number), "the subspace solve's helper panicked");
    }

    /// Waits until the helper, which claimed half 1 of pass `number`, has done it: `false` if it
    /// panicked instead.
    fn helper_done(&self, number: u64) -> bool {
        let mut spins = 0;
        loop {
            match self.done.load(Ordering::Acquire) {
                FAILED => return false,
                done if done == number => return true,
                _ => pause(&mut spins),
            }
        }
    }

    /// Claims half 1 of pass `number`: whether this thread got it.
    fn claim(&self, number: u64) -> bool {
        self.claimed.compare_exchange(number - 1, number, Ordering::AcqRel, Ordering::Acquire).is_ok()
    }

    /// The helper: claims the half 1 of each pass posted until the leader is done.
    fn help(&self) {
        let _failed = Failed(&self.done);
        let mut seen = 0;
        let mut spins = 0;
        loop {
            let number = self.posted.load(Ordering::Acquire);
            if number == QUIT {
                return;
            }
            if number == seen {
                pause(&mut spins);
                continue;
            }
            (seen, spins) = (number, 0);
            if self.claim(number) {
                // SAFETY: the claim succeeded, so the leader posted `number` and is waiting for
                // its half 1: the cell holds that pass and nothing writes it until it is done.
                #[allow(unsafe_code)]
                let pass = unsafe { *self.pass.get() };
                if let Some(pass) = pass {
                    pass(1);
                }
                self.done.store(number, Ordering::Release);
            }
        }
    }
}

/// A thread waiting beside a leader, lent to its [`Halves`] (see the module documentation): the
/// leader posts its halves here, and the thread, while it waits, [`serve`](Lent::serve)s them.
pub(super) struct Lent {
    /// The posted halves (on the leader's stack).
    halves: AtomicPtr<Halves>,
    /// [`EMPTY`], [`POSTED`] or [`SERVING`].
    state: AtomicU32,
}

/// [`Lent::state`] with no halves posted, ...
const EMPTY: u32 = 0;
/// ... with halves posted and not yet taken, ...
const POSTED: u32 = 1;
/// ... and while the lent thread helps them.
const SERVING: u32 = 2;

impl Lent {
    pub(super) fn new() -> Self {
        Self { halves: AtomicPtr::new(std::ptr::null_mut()), state: AtomicU32::new(EMPTY) }
    }

    /// Helps the halves posted, if any, until their leader is done: whether there were any.
    pub(super) fn serve(&self) -> bool {
        if self.state.compare_exchange(POSTED, SERVING, Ordering::AcqRel, Ordering::Relaxed).is_err() {
            return false;
        }
        let _back = Served(&self.state);
        // SAFETY: the leader stored the pointer before posting it (the release store this
        // exchange read) and keeps the halves alive until the state is back to `EMPTY`
        // ([`Retract`]), which `Served` stores only once this is done with them.
        #[allow(unsafe_code)]
        let halves = unsafe { &*self.halves.load(Ordering::Relaxed) };
        halves.help();
        true
    }
}

/// Takes back the halves posted to a lent thread when their leader is done (or unwinds): tells
/// a thread helping them to return and waits until it has, or withdraws them if none took them.
struct Retract<'h> {
    lent: &'h Lent,
    halves: &'h Halves,
}

impl Drop for Retract<'_> {
    fn drop(&mut self) {
        self.halves.posted.store(QUIT, Ordering::Release);
        let state = &self.lent.state;
        if state.compare_exchange(POSTED, EMPTY, Ordering::AcqRel, Ordering::Acquire).is_err() {
            let mut spins = 0;
            while state.load(Ordering::Acquire) != EMPTY {
                pause(&mut spins);
            }
        }
    }
}

/// Tells the leader the lent thread is done with its halves, however it leaves them.
struct Served<'a>(&'a AtomicU32);

impl Drop for Served<'_> {
    fn drop(&mut self) {
        self.0.store(EMPTY, Ordering::Release);
    }
}

/// The leader's handle on its [`Halves`]: the one way to run a pass. Neither `Send` nor `Sync`,
/// so it stays on the leader's thread and no pass (which must be `Sync`) can hold it: passes
/// are posted one at a time, never from within one.
pub(super) struct Leader<'h> {
    halves: &'h Halves,
    only_here: PhantomData<*const ()>,
}

impl Leader<'_> {
    /// Runs `pass` on both halves: half 0 on this thread, half 1 on the helper if it claims it
    /// first; returns once both are done.
    pub(super) fn run(&self, pass: Pass<'_>) {
        self.halves.run(pass);
    }
}

/// Pauses a waiting thread: a spin hint, and past [`SPINS`] a yield of its core.
pub(super) fn pause(spins: &mut u32) {
    *spins += 1;
    if *spins < SPINS {
        std::hint::spin_loop();
    } else {
        std::thread::yield_now();
    }
}

/// Pass `number` while the leader runs its half 0: if that unwinds, the helper must not start
/// half 1 (or must have finished it) before the pass's borrows go.
struct Unwinding<'h> {
    halves: &'h Halves,
    number: u64,
}

impl Drop for Unwinding<'_> {
    /// Only on unwinding (`run` forgets it otherwise).
    fn drop(&mut self) {
        if !self.halves.claim(self.number) {
            self.halves.helper_done(self.number);
        }
    }
}

/// Tells the helper the leader is done, when the leader returns or unwinds.
struct Quit<'h>(&'h Halves);

impl Drop for Quit<'_> {
    fn drop(&mut self) {
        self.0.posted.store(QUIT, Ordering::Release);
    }
}

/// Tells the leader the helper's half panicked, so that it does not wait for it.
struct Failed<'h>(&'h AtomicU64);

impl Drop for Failed<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(FAILED, Ordering::Release);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, AtomicUsize};

    use super::*;

    /// Every pass runs each half exactly once, on any pool, in order: a pass's halves both see
    /// the passes before them done.
    #[test]
    fn every_half_runs_once_in_order() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let counts: Vec<AtomicUsize> = (0..2000).map(|_| AtomicUsize::new(0)).collect();
            pool.install(|| {
                Halves::lead(true, None, |leader| {
                    for pass in 0..1000 {
                        leader.run(&|half| {
                            if pass > 0 {
                                assert_eq!(counts[2 * pass - 2].load(Ordering::Relaxed), 1, "pass {pass}");
                                assert_eq!(counts[2 * pass - 1].load(Ordering::Relaxed), 1, "pass {pass}");
                            }
                            counts[2 * pass + half].fetch_add(1, Ordering::Relaxed);
                        });
                    }
                });
            });
            assert!(counts.iter().all(|count| count.load(Ordering::Relaxed) == 1), "{threads} threads");
        }
    }

    /// Halves lent to a thread waiting beside the leader run every half exactly once, in order,
    /// whether that thread serves them (and then runs some) or never does (the leader then does
    /// both and takes them back).
    #[test]
    fn lent_halves_run_every_half_once_in_order() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for serving in [true, false] {
            let counts: Vec<AtomicUsize> = (0..2000).map(|_| AtomicUsize::new(0)).collect();
            let lent_ran = AtomicUsize::new(0);
            let lent = beside_a_lent_thread(&pool, serving, |lent, lent_thread| {
                for round in 0..10 {
                    Halves::lead(true, Some(lent), |leader| {
                        for pass in 100 * round..100 * round + 100 {
                            leader.run(&|half| {
                                if pass > 0 {
                                    assert_eq!(counts[2 * pass - 1].load(Ordering::Relaxed), 1, "{pass}");
                                }
                                counts[2 * pass + half].fetch_add(1, Ordering::Relaxed);
                                // Half 0 gives a serving thread time to claim half 1 (a pass
                                // this short is otherwise over before it looks).
                                let mut spins = 0;
                                while serving && half == 0 && spins < 100_000 {
                                    if counts[2 * pass + 1].load(Ordering::Relaxed) == 1 {
                                        break;
                                    }
                                    spins += 1;
                                    std::hint::spin_loop();
                                }
                                if rayon::current_thread_index() == Some(lent_thread) {
                                    lent_ran.fetch_add(1, Ordering::Relaxed);
                                }
                            });
                        }
                    });
                }
            });
            assert!(counts.iter().all(|count| count.load(Ordering::Relaxed) == 1), "serving {serving}");
            assert_eq!(lent.state.load(Ordering::Relaxed), EMPTY);
            let ran = lent_ran.load(Ordering::Relaxed);
            assert!(if serving { ran > 0 } else { ran == 0 }, "serving {serving}: the lent thread ran {ran} halves");
        }
    }

    /// A panic in either half of lent halves reaches the caller instead of a hang.
    #[test]
    fn a_panicking_lent_half_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for failing in [0, 1] {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                beside_a_lent_thread(&pool, true, |lent, _| {
                    Halves::lead(true, Some(lent), |leader| {
                        for pass in 0..100 {
                            leader.run(&|half| assert!(!(pass == 50 && half == failing), "half {half} fails"));
                        }
                    });
                })
            }));
            assert!(result.is_err(), "half {failing}");
        }
    }

    /// Runs `lead` on `pool` beside a second thread that, once it has come (`lead` is given its
    /// index), serves a [`Lent`] when `serving` until `lead` is done; returns the `Lent`.
    fn beside_a_lent_thread(pool: &rayon::ThreadPool, serving: bool, lead: impl FnOnce(&Lent, usize) + Send) -> Lent {
        let (lent, over, thread) = (Lent::new(), AtomicBool::new(false), AtomicUsize::new(usize::MAX));
        pool.install(|| {
            rayon::join(
                || {
                    // Set however `lead` leaves, so that the other thread stops.
                    struct Over<'a>(&'a AtomicBool);
                    impl Drop for Over<'_> {
                        fn drop(&mut self) {
                            self.0.store(true, Ordering::Release);
                        }
                    }
                    let _over = Over(&over);
                    // The pool's other worker is idle: it takes the second closure.
                    while thread.load(Ordering::Acquire) == usize::MAX {
                        std::hint::spin_loop();
                    }
                    lead(&lent, thread.load(Ordering::Acquire));
                },
                || {
                    thread.store(rayon::current_thread_index().unwrap(), Ordering::Release);
                    while !over.load(Ordering::Acquire) {
                        if !(serving && lent.serve()) {
                            std::hint::spin_loop();
                        }
                    }
                },
            )
        });
        lent
    }

    /// A panic in either half reaches the caller instead of a hang.
    #[test]
    fn a_panicking_half_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for failing in [0, 1] {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| {
                    Halves::lead(true, None, |leader| {
                        for pass in 0..100 {
                            leader.run(&|half| assert!(!(pass == 50 && half == failing), "half {half} fails"));
                        }
                    });
                });
            }));
            assert!(result.is_err(), "half {failing}");
        }
    }
}
