//! The pool's other workers kept at hand through a step (`SimulationSettings::worker_spin`).
//!
//! A step on more than one thread runs on one worker of the pool and hands its parallel stages
//! to the others. Between those stages it runs serial work (a sub-step's bound, the collision
//! sweeps, the islands), and a rayon worker with nothing to do falls asleep within a few
//! microseconds; the next parallel stage then waits for the kernel to wake it, tens of
//! microseconds on this project's host, a dozen times a sub-step (docs/performance.md). So
//! while a step runs, each other worker runs a *spinner*: a job that takes any of the step's
//! work offered to the pool (`rayon::yield_now`) and otherwise pauses and looks again, until the
//! step ends or it has found nothing for `worker_spin` seconds.
//! Which thread does which part of the work never changes a result (every parallel stage
//! gives the same bits on any number of threads), so the spinners change only the time.
//!
//! Spinners never hold up the step. They are pushed before any of its work, so a worker that
//! takes one from the step's thread takes it first; a thread already at work in the step, or
//! in a spinner, that comes upon a spinner (stealing while it waits) returns from it at once;
//! and a spinner that finds no work for `worker_spin` returns, so even a worker that took part
//! of the step before its spinner (possible with more than two threads) is back within that
//! time. The step's thread waits for its spinners only after the step's work is done.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

thread_local! {
    /// Whether this thread is running a step's work or a spinner (the spinner it comes upon
    /// then returns at once).
    static AT_WORK: Cell<bool> = const { Cell::new(false) };
}

/// Runs `work` on the current worker while every other worker of the current pool spins for
/// up to `spin` seconds idle (see the module documentation); with `spin` 0, one thread, or off
/// the pool, just runs `work`.
pub(crate) fn with_workers_at_hand<R: Send>(spin: f64, work: impl FnOnce() -> R + Send) -> R {
    let helpers = rayon::current_thread_index().map_or(0, |_| rayon::current_num_threads().saturating_sub(1));
    if helpers == 0 || spin <= 0.0 {
        return work();
    }
    let idle_limit = Duration::from_secs_f64(spin);
    let done = AtomicBool::new(false);
    let (result, ()) = rayon::join(
        || {
            let _ending = StepEnd { done: &done, was: AT_WORK.with(|at_work| at_work.replace(true)) };
            work()
        },
        || spinners(&done, idle_limit, helpers),
    );
    result
}

/// Ends the step for its spinners when its work returns or unwinds: the thread's flag as it
/// was, and `done` set (so a panicking step releases its spinners at once, not after their idle
/// limit, and leaves no worker marked at work).
struct StepEnd<'a> {
    done: &'a AtomicBool,
    was: bool,
}

impl Drop for StepEnd<'_> {
    fn drop(&mut self) {
        AT_WORK.with(|at_work| at_work.set(self.was));
        self.done.store(true, Ordering::Release);
    }
}

/// `count` spinners: this thread's, and the rest offered to the pool meanwhile.
fn spinners(done: &AtomicBool, idle_limit: Duration, count: usize) {
    if count <= 1 {
        spin(done, idle_limit);
    } else {
        rayon::join(|| spin(done, idle_limit), || spinners(done, idle_limit, count - 1));
    }
}

/// Takes the pool's pending work until `done`, or until none has come for `idle_limit`; returns
/// at once on a thread already at work.
fn spin(done: &AtomicBool, idle_limit: Duration) {
    if done.load(Ordering::Acquire) || AT_WORK.with(|at_work| at_work.replace(true)) {
        return;
    }
    let mut idle_since: Option<Instant> = None;
    while !done.load(Ordering::Acquire) {
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            idle_since = None;
            continue;
        }
        let since = *idle_since.get_or_insert_with(Instant::now);
        if since.elapsed() >= idle_limit {
            break;
        }
        // A pause, not `std::thread::yield_now`: yielding to the system between looks made
        // the landing pile's steps no faster than not spinning at all (docs/performance.md).
        std::hint::spin_loop();
    }
    AT_WORK.with(|at_work| at_work.set(false));
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
    }

    /// Nested parallel work inside the step, with serial gaps between, on 2, 3 and 4 threads:
    /// it completes with the serial result (a spinner never holds up the work it sits on).
    #[test]
    fn nested_parallel_work_completes_with_spinners() {
        let serial: usize = (0..20_000usize).map(|k| k * k % 7).sum::<usize>() * 10;
        for threads in [2, 3, 4] {
            let pool = pool(threads);
            for spin in [1e-3, 1e-5] {
                let total = pool.install(|| {
                    with_workers_at_hand(spin, || {
                        (0..10)
                            .map(|_| {
                                std::thread::sleep(Duration::from_micros(50));
                                (0..20_000usize).into_par_iter().with_max_len(64).map(|k| k * k % 7).sum::<usize>()
                            })
                            .sum::<usize>()
                    })
                });
                assert_eq!(total, serial, "{threads} threads, spin {spin}");
            }
        }
    }

    /// Off the pool, with one thread or with no spin, the work runs as it is.
    #[test]
    fn without_helpers_the_work_runs_alone() {
        assert_eq!(with_workers_at_hand(1e-3, || 7), 7);
        assert_eq!(pool(1).install(|| with_workers_at_hand(1e-3, rayon::current_num_threads)), 1);
        assert_eq!(pool(2).install(|| with_workers_at_hand(0.0, || 8)), 8);
    }

    /// A step whose work panics passes the panic on, and leaves no worker marked at work.
    #[test]
    fn a_panicking_step_releases_its_spinners() {
        let pool = pool(2);
        let caught = pool
            .install(|| std::panic::catch_unwind(|| with_workers_at_hand(1.0, || -> u32 { panic!("in the step") })));
        assert!(caught.is_err());
        pool.broadcast(|_| assert!(!AT_WORK.with(Cell::get), "a worker is still marked at work"));
    }

    /// The spinners are gone once the step returns: a later step on the same pool runs, and
    /// the flags are reset on every worker.
    #[test]
    fn spinners_end_with_the_step() {
        let pool = pool(2);
        for _ in 0..50 {
            let sum = pool.install(|| with_workers_at_hand(1.0, || (0..1000u64).into_par_iter().sum::<u64>()));
            assert_eq!(sum, 499_500);
        }
        pool.broadcast(|_| assert!(!AT_WORK.with(Cell::get), "a worker is still marked at work"));
    }
}
