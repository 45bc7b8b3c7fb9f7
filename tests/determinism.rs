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
/// quarters of that (the first step always), and on the caller's thread otherwise, with the same bits either way:
/// the pile of twelve blobs lands, its steps lighter than 3/4 of a threshold set in its range,
/// between, and heavier, and falls asleep (a step with every body asleep runs no stage and has
/// no work), on two threads against one thread and against two that take every step on the pool.
#[test]
fn light_steps_run_on_the_callers_thread_with_the_same_bits() {
    let run = |threads: usize, min_parallel_work: u64| {
        let settings = SimulationSettings { threads, min_parallel_work, ..SimulationSettings::default() };
        let mut sim = Simulation::new(settings).unwrap();
        add_pile(&mut sim);
        let (mut last, mut pooled, mut light, mut held, mut asleep_steps) = (None::<(u64, bool)>, 0, 0, 0, 0);
        let mut works = Vec::new();
        for step in 0..STEPS {
            sim.step(sim.settings().time_step);
            let counters = sim.take_profile().counters;
            let asleep = counters.substeps == 0;
            asleep_steps += u64::from(asleep);
            let limit = |on_pool: bool| if on_pool { (3 * min_parallel_work).div_ceil(4) } else { min_parallel_work };
            let expected = threads > 1 && !asleep && last.is_none_or(|(work, on_pool)| work >= limit(on_pool));
            assert_eq!(counters.pool_jobs, u64::from(expected), "{threads} threads, step {step}: after {last:?}");
            pooled += counters.pool_jobs;
            light += u64::from(last.is_some_and(|(work, _)| work < min_parallel_work));
            held += u64::from(expected && last.is_some_and(|(work, _)| work < min_parallel_work));
            // The first step runs on the pool for want of a measure, and does not hold it.
            last = Some((counters.candidate_pairs + counters.leaf_pairs + counters.contacts, expected && step > 0));
            works.extend(last.map(|(work, _)| work).filter(|&work| work > 0));
        }
        assert!(asleep_steps > 0, "{threads} threads: the pile did not fall asleep");
        works.sort_unstable();
        (sim.state_hash(), pooled, light, asleep_steps, held, works[works.len() / 2])
    };
    let one = run(1, 0);
    let every = run(2, 0);
    // A threshold that the pile's steps fall on both sides of: the median of their work.
    let some = run(2, one.5);
    assert_eq!((every.0, some.0), (one.0, one.0), "the same bits on one thread, on the pool and off it");
    assert_eq!(every.1 + every.3, STEPS as u64, "every step awake on the pool with no threshold");
    assert!(some.2 > some.4 && some.1 > some.4 && some.4 > 0, "the pile's steps did not fall on every side: {some:?}");
    assert_eq!(one.1, 0, "one thread never enters the pool");
}
