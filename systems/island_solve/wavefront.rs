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

mod shared;

pub(super) use shared::Lower;
use shared::{EndBlocks, Shared};

use super::StopRule;
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::SolverContact;

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
    let shared = Shared::new((contacts.as_mut_ptr(), velocities.as_mut_ptr()), &runs.starts, (rule, join_at));
    let mut lower = Lower::new(&shared, &mut runs.saved_impulses, &mut runs.saved_velocities, &mut runs.saved_runs);
    let (result, ()) = rayon::join(
        || {
            let _end = EndBlocks(&shared.opened);
            blocks(&mut lower)
        },
        || shared.help(),
    );
    result
}

#[cfg(test)]
pub(super) mod tests {
    use glam::DVec2;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::super::subspace::ScratchBuffers;
    use super::super::{OneThread, Outcome, StopRule, Sweeper, blocks, solve_island};
    use super::*;
    use crate::dynamics::solver::{Accumulator, prepare_patches};
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
