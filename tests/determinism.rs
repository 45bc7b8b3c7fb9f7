//! Golden determinism test: the same scene gives bit-identical states for 1, 2 and 4 threads,
//! and the same states as when the golden value was recorded.
//!
//! The golden hash lives in `assets/golden/determinism.ron`. After an intended change of the
//! dynamics, regenerate it with `RUGOSA_BLESS=1 cargo test --test determinism`.

mod common;

use common::{ground, material};
use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Rugosity, Simulation, SimulationSettings, SleepSettings};

const GOLDEN_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/golden/determinism.ron");
const STEPS: usize = 240;

/// Every step of more than one thread on the pool, however light (`min_parallel_work` 0).
fn pile(threads: usize) -> Simulation {
    let settings = SimulationSettings { threads, min_parallel_work: 0, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    add_pile(&mut sim);
    sim
}

fn add_pile(sim: &mut Simulation) {
    let friction = FrictionLaw { lambda_min: 0.001, mu_max: 0.8 };
    sim.add_body(ground(0.003, material(0.2, friction))).unwrap();
    for k in 0..12u64 {
        let spline = Generator::Blob { radius: 0.15, roughness: 0.5, seed: k }.build(16).unwrap();
        let tolerances: Vec<f64> = (0..16).map(|i| 0.001 + 0.002 * (((i as u64 + k) % 5) as f64 / 4.0)).collect();
        let body = BodyDesc::new(spline, Rugosity::new(tolerances).unwrap())
            .with_material(material(0.3, friction))
            .at(DVec2::new(-0.9 + 0.35 * (k % 6) as f64, 0.3 + 0.4 * (k / 6) as f64), 0.3 * k as f64)
            .with_velocity(DVec2::new(0.0, -1.0), 0.5 - 0.1 * k as f64);
        sim.add_body(body).unwrap();
    }
}

fn final_hash(threads: usize) -> u64 {
    let mut sim = pile(threads);
    for _ in 0..STEPS {
        sim.step(sim.settings().time_step);
    }
    sim.validate().unwrap();
    sim.state_hash()
}

#[test]
fn golden_hash_is_the_same_for_1_2_and_4_threads() {
    let hashes: Vec<u64> = [1, 2, 4].iter().map(|&t| final_hash(t)).collect();
    assert!(hashes.iter().all(|&h| h == hashes[0]), "thread counts 1, 2, 4 disagree: {hashes:x?}");
    let text = format!("(state_hash: {}, steps: {STEPS})\n", hashes[0]);
    if std::env::var_os("RUGOSA_BLESS").is_some() {
        std::fs::write(GOLDEN_PATH, &text).unwrap();
        return;
    }
    let golden = std::fs::read_to_string(GOLDEN_PATH).unwrap_or_default();
    assert_eq!(
        golden.trim(),
        text.trim(),
        "state hash differs from the golden value in {GOLDEN_PATH}; if the change of dynamics is \
         intended, regenerate it with `RUGOSA_BLESS=1 cargo test --test determinism`"
    );
}

/// Two simulations on one shared pool of two workers, stepped at the same time from two
/// threads: each step's spinners (`SimulationSettings::worker_spin`) may then take the other
/// simulation's work too, even a whole step of it. Both finish, with the states of a simulation
/// stepped alone.
#[test]
fn simulations_sharing_a_pool_give_the_states_of_one_alone() {
    let alone = final_hash(1);
    let pool = std::sync::Arc::new(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap());
    let run = |pool: std::sync::Arc<rayon::ThreadPool>| {
        let settings = SimulationSettings { threads: 2, min_parallel_work: 0, ..SimulationSettings::default() };
        let mut sim = Simulation::with_pool(settings, pool);
        add_pile(&mut sim);
        for _ in 0..STEPS {
            sim.step(sim.settings().time_step);
        }
        sim.state_hash()
    };
    let hashes = std::thread::scope(|scope| {
        let first = scope.spawn(|| run(pool.clone()));
        let second = scope.spawn(|| run(pool.clone()));
        [first.join().unwrap(), second.join().unwrap()]
    });
    assert_eq!(hashes, [alone, alone], "shared pool: {hashes:x?}, alone: {alone:x}");
}

/// Eight separate stacks of six rounded boxes dropped on the ground: eight islands, solved in
/// parallel on more than one thread. The states after 120 steps are the same bit for bit on
/// 1, 2 and 4 threads, and the islands were there to be split (the solver saw at least eight
/// per sub-step, with more resting contacts than the 64 below which it does not split).
#[test]
fn islands_solved_in_parallel_give_the_same_bits_as_one_thread() {
    let run = |threads: usize| {
        // Sleeping off: the stacks would fall asleep, and the solver with them.
        let settings = SimulationSettings {
            threads,
            sleep: SleepSettings::off(),
            min_parallel_work: 0,
            ..SimulationSettings::default()
        };
        let mut sim = Simulation::new(settings).unwrap();
        let friction = FrictionLaw { lambda_min: 0.001, mu_max: 0.6 };
        sim.add_body(ground(0.002, material(0.1, friction))).unwrap();
        let spline = Generator::RoundedRectangle { width: 0.4, height: 0.2, corner_radius: 0.03 }.build(28).unwrap();
        let rugosity = Rugosity::constant(spline.segment_count(), 0.002).unwrap();
        for stack in 0..8 {
            for level in 0..6 {
                let at = DVec2::new(-7.0 + 2.0 * f64::from(stack), 0.11 + 0.21 * f64::from(level));
                let body = BodyDesc::new(spline.clone(), rugosity.clone())
                    .with_material(material(0.1, friction))
                    .at(at, 0.02 * f64::from(stack - level));
                sim.add_body(body).unwrap();
            }
        }
        // Counted over the last 20 steps, once the stacks have landed.
        let (mut islands, mut substeps, mut contacts) = (0, 0, 0);
        for step in 0..120 {
            sim.step(sim.settings().time_step);
            let counters = sim.take_profile().counters;
            if step >= 100 {
                (islands, substeps, contacts) =
                    (islands + counters.islands, substeps + counters.substeps, contacts + counters.resting_contacts);
            }
        }
        (sim.state_hash(), islands as f64 / substeps as f64, contacts as f64 / substeps as f64)
    };
    let one = run(1);
    assert!(one.1 >= 8.0 && one.2 >= 64.0, "islands and resting contacts per sub-step: {:.1}, {:.1}", one.1, one.2);
    for threads in [2, 4] {
        assert_eq!(run(threads).0, one.0, "{threads} threads against one");
    }
}

/// A pyramid of 136 rounded boxes set down a little apart: one island of 16 levels and more
/// than 400 resting contacts, whose sweeps two threads share as a wavefront while it settles,
/// with subspace solves between blocks of them, some of them large enough to split into two
/// halves (docs/model.md §6 step 5). The states after 30 steps are the same bit for bit on 1, 2
/// and 4 threads, the wavefront was taken in every solve with more than one thread, and the
/// subspace solves ran, split ones among them.
#[test]
fn one_island_shared_by_two_threads_gives_the_same_bits_as_one_thread() {
    let run = |threads: usize| {
        let settings = SimulationSettings {
            threads,
            sleep: SleepSettings::off(),
            min_parallel_work: 0,
            ..SimulationSettings::default()
        };
        let mut sim = Simulation::new(settings).unwrap();
        let friction = FrictionLaw { lambda_min: 0.001, mu_max: 0.75 };
        sim.add_body(ground(0.005, material(0.1, friction))).unwrap();
        let spline = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
        let rugosity = Rugosity::constant(spline.segment_count(), 0.005).unwrap();
        let base = 16;
        for row in 0..base {
            for column in 0..base - row {
                let x = (f64::from(column) - 0.5 * f64::from(base - row - 1)) * 1.004;
                let at = DVec2::new(x, 0.504 + 1.004 * f64::from(row));
                let body = BodyDesc::new(spline.clone(), rugosity.clone()).with_material(material(0.1, friction));
                sim.add_body(body.at(at, 0.0)).unwrap();
            }
        }
        let (mut substeps, mut wavefronts, mut contacts, mut subspace, mut halves) = (0, 0, 0, 0, 0);
        for _ in 0..30 {
            sim.step(sim.settings().time_step);
            let counters = sim.take_profile().counters;
            (substeps, wavefronts, contacts, subspace, halves) = (
                substeps + counters.substeps,
                wavefronts + counters.wavefront_solves,
                contacts + counters.resting_contacts,
                subspace + counters.subspace_iterations,
                halves + counters.subspace_halves,
            );
        }
        sim.validate().unwrap();
        (sim.state_hash(), substeps, wavefronts, contacts as f64 / substeps as f64, subspace, halves)
    };
    let one = run(1);
    assert_eq!(one.2, 0, "one thread takes no wavefront");
    assert!(one.3 >= 400.0, "resting contacts per sub-step: {:.1}", one.3);
    assert!(one.4 > 0, "no subspace solve ran");
    assert!(one.5 > 0, "no subspace solve split into halves");
    for threads in [2, 4] {
        let (hash, substeps, wavefronts, ..) = run(threads);
        assert_eq!(hash, one.0, "{threads} threads against one");
        // Every solve of every sub-step (a retried sub-step solves again).
        assert!(wavefronts >= substeps, "{threads} threads: {wavefronts} wavefronts in {substeps} sub-steps");
    }
}

/// A step runs on the pool only after a step off it with at least `min_parallel_work` of work
/// (its candidate pairs, leaf pairs and contacts), or after one on it with at least three
/// quarters of that (the first step always), and on the caller's thread otherwise, with the same
/// bits either way: the pile of twelve blobs lands, its steps lighter than 3/4 of a threshold set
/// in its range, between, and heavier, and falls asleep (a step with every body asleep runs no
/// stage), on two threads against one thread and against two that take every step on the pool.
/// The contact hook, called on the step's thread, sees a worker of the pool in the steps on the
/// pool and this test's thread in the others.
#[test]
fn light_steps_run_on_the_callers_thread_with_the_same_bits() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};

    let run = |threads: usize, min_parallel_work: u64| {
        let settings = SimulationSettings { threads, min_parallel_work, ..SimulationSettings::default() };
        let mut sim = Simulation::new(settings).unwrap();
        add_pile(&mut sim);
        // Hook calls on a worker of a pool, and on a thread of none.
        let calls = Arc::new([AtomicU64::new(0), AtomicU64::new(0)]);
        let seen = calls.clone();
        sim.set_contact_hook(Some(Arc::new(move |_: &rugosa::PairContacts<'_>| {
            seen[usize::from(rayon::current_thread_index().is_some())].fetch_add(1, Ordering::Relaxed);
            rugosa::PairAction::Keep
        })));
        let mut last = None::<(u64, bool)>;
        // Steps on the pool, awake steps off it, of those after a step on it (dropped), steps on
        // it after a step off it below the threshold (held), and steps with every body asleep.
        let (mut pooled, mut off, mut dropped, mut held, mut asleep_steps) = (0, 0, 0, 0, 0);
        let mut works = Vec::new();
        for step in 0..STEPS {
            let before = [calls[0].load(Ordering::Relaxed), calls[1].load(Ordering::Relaxed)];
            sim.step(sim.settings().time_step);
            let counters = sim.take_profile().counters;
            let asleep = counters.substeps == 0;
            let limit = |on_pool: bool| if on_pool { (3 * min_parallel_work).div_ceil(4) } else { min_parallel_work };
            let expected = threads > 1 && !asleep && last.is_none_or(|(work, on_pool)| work >= limit(on_pool));
            assert_eq!(counters.pool_jobs, u64::from(expected), "{threads} threads, step {step}: after {last:?}");
            let on_pool = usize::from(expected);
            let hooked = [calls[0].load(Ordering::Relaxed) - before[0], calls[1].load(Ordering::Relaxed) - before[1]];
            assert_eq!(hooked[1 - on_pool], 0, "{threads} threads, step {step}: the hook ran on the wrong thread");
            pooled += counters.pool_jobs;
            off += u64::from(!expected && !asleep);
            dropped += u64::from(!expected && !asleep && last.is_some_and(|(_, on_pool)| on_pool));
            held += u64::from(expected && last.is_some_and(|(work, _)| work < min_parallel_work));
            asleep_steps += u64::from(asleep);
            // The first step runs on the pool for want of a measure and does not hold it; nor
            // does a step of sleepers measure anything.
            let work = counters.work();
            last = (!asleep).then_some((work, expected && last.is_some()));
            works.extend((!asleep).then_some(work));
        }
        assert!(asleep_steps > 0, "{threads} threads: the pile did not fall asleep");
        assert!(calls[0].load(Ordering::Relaxed) + calls[1].load(Ordering::Relaxed) > 0, "the hook was never called");
        works.sort_unstable();
        (sim.state_hash(), [pooled, off, dropped, held, asleep_steps], works[works.len() / 2])
    };
    let one = run(1, 0);
    let every = run(2, 0);
    // A threshold that the pile's steps fall on both sides of: the median of their work.
    let some = run(2, one.2);
    assert_eq!((every.0, some.0), (one.0, one.0), "the same bits on one thread, on the pool and off it");
    let [pooled, off, dropped, held, asleep] = some.1;
    assert_eq!(every.1[0] + every.1[4], STEPS as u64, "every step awake on the pool with no threshold");
    assert!(
        pooled > held && off > dropped && dropped > 0 && held > 0,
        "the pile's steps did not fall on every side: {:?}",
        some.1
    );
    assert!(asleep > 0 && one.1[0] == 0, "one thread never enters the pool");
}

/// With a threshold no step reaches, only the steps that have nothing to measure from run on the
/// pool: the first, the first after a restore and the first after every body slept (which wakes
/// one), each followed by steps on the caller's thread.
#[test]
fn a_step_with_no_measure_runs_on_the_pool() {
    let settings = SimulationSettings { threads: 2, min_parallel_work: u64::MAX, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    add_pile(&mut sim);
    let step = |sim: &mut Simulation| {
        sim.step(sim.settings().time_step);
        let counters = sim.take_profile().counters;
        (counters.pool_jobs, counters.substeps == 0)
    };
    assert_eq!(step(&mut sim), (1, false), "the first step");
    assert_eq!(step(&mut sim), (0, false), "the second step");
    let mut restored = Simulation::from_snapshot(sim.snapshot().unwrap()).unwrap();
    assert_eq!(step(&mut restored), (1, false), "the first step after a restore");
    assert_eq!(step(&mut restored), (0, false), "the second step after a restore");
    let mut asleep = 0;
    while asleep < 5 {
        let (jobs, all_asleep) = step(&mut sim);
        assert_eq!(jobs, 0, "a step before every body slept, or while they sleep");
        asleep += u64::from(all_asleep);
        assert!(sim.time() < 10.0, "the pile did not fall asleep");
    }
    let body = sim.bodies().nth(5).unwrap();
    sim.apply_impulse(body, DVec2::new(0.0, 0.5), sim.state(body).unwrap().position).unwrap();
    assert_eq!(step(&mut sim), (1, false), "the step that wakes the pile");
    assert_eq!(step(&mut sim), (0, false), "the step after it");
}
