//! No allocation per step in steady state: once the step's buffers have grown to the scene,
//! stepping allocates nothing with one thread; with two, the only allocations are rayon's
//! job-queue blocks (one per 63 jobs handed to the pool, one job per step). The settled pile
//! reuses still pairs' contacts (docs/model.md §3b), so that path is covered as well, and the
//! settled pyramid of the benchmarks takes the paths of a still structure (drift budgets,
//! refreshed contacts, the broad phase's kept filter).
//!
//! The only test in this file, so the process-wide count sees no other test's allocations.

use std::alloc::System;

#[path = "common/pile.rs"]
mod pile;

use hecs::Entity;
use rugosa::{Simulation, SimulationSettings, SleepSettings, Snapshot, StepCounters};
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

/// Counts allocations over every thread (the narrow phase runs on the rayon pool's threads).
#[global_allocator]
static ALLOCATOR: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Twelve blobs of the benchmark pile dropped into their box: collisions, resting contact and
/// micro-collisions.
fn settling_pile(threads: usize, sleep: SleepSettings) -> Simulation {
    let settings = SimulationSettings { threads, record_events: true, sleep, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    for body in pile::blob_pile(12, 4) {
        sim.add_body(body).unwrap();
    }
    sim
}

/// Entries of a block of the pool's job queue (crossbeam-deque's `Injector`, which rayon uses
/// for jobs handed in from outside the pool): the queue allocates one block per this many jobs.
const JOB_QUEUE_BLOCK: u64 = 63;

/// Steps `sim` `steps` times, waking `wake` first if given; returns the allocations made.
fn count_allocations(sim: &mut Simulation, steps: usize, wake: Option<Entity>) -> usize {
    let dt = sim.settings().time_step;
    let region = Region::new(ALLOCATOR);
    if let Some(body) = wake {
        sim.wake(body);
    }
    for _ in 0..steps {
        sim.step(dt);
        sim.drain_events().for_each(drop);
        sim.drain_touch_events().for_each(drop);
    }
    // A reallocation may move the block: it counts as an allocation.
    let change = region.change();
    change.allocations + change.reallocations
}

/// The engine's own buffers never grow once warm. With more than one thread the only
/// allocations are the job queue's blocks: at most one per JOB_QUEUE_BLOCK jobs, plus one for a
/// block boundary inside the window.
fn check(allocations: usize, threads: usize, counters: &StepCounters, what: &str) {
    let queue_blocks = counters.pool_jobs.div_ceil(JOB_QUEUE_BLOCK) + u64::from(counters.pool_jobs > 0);
    assert!(
        allocations as u64 <= queue_blocks,
        "{threads} threads, {what}: {allocations} allocations ({} pool jobs)",
        counters.pool_jobs
    );
    if threads == 1 {
        assert_eq!(allocations, 0, "one thread, {what}: {allocations} allocations");
    }
}

#[test]
fn stepping_allocates_nothing_once_warm() {
    for threads in [1, 2] {
        // Sleeping off: the pile keeps its contacts awake.
        let mut sim = settling_pile(threads, SleepSettings::off());
        // Warm-up: the pile lands and settles, so every buffer reaches the size it needs.
        count_allocations(&mut sim, 480, None);
        let before = sim.take_profile().counters;
        let allocations = count_allocations(&mut sim, 240, None);
        let counters = sim.take_profile().counters;
        assert!(counters.contacts > 0 && before.contacts > 0, "{threads} threads: the pile is not in contact");
        // Settled, it keeps still pairs' contacts (docs/model.md §3b): that path is counted too.
        assert!(counters.reused_pairs > 0, "{threads} threads: no contact was reused");
        check(allocations, threads, &counters, "240 steady steps");

        // Sleeping on: the pile falls asleep; waking part of it and letting it fall asleep again
        // allocates nothing either, once one such cycle has sized the buffers.
        let mut sim = settling_pile(threads, SleepSettings::default());
        let blob = sim.bodies().last().unwrap();
        count_allocations(&mut sim, 480, None);
        count_allocations(&mut sim, 240, Some(blob));
        sim.take_profile();
        let allocations = count_allocations(&mut sim, 240, Some(blob));
        let counters = sim.take_profile().counters;
        assert!(counters.woken_bodies > 0, "{threads} threads: nothing woke");
        assert!(counters.sleeping_bodies > 0, "{threads} threads: nothing slept");
        check(allocations, threads, &counters, "a wake and sleep cycle of 240 steps");
    }
    // A larger scene, where a buffer sorted each sub-step outgrows what the standard library's
    // stable sort sorts on the stack (about a hundred broad-phase entries): with it, every step
    // allocated once. One thread, settled.
    let settings = SimulationSettings { threads: 1, record_events: true, ..SimulationSettings::default() };
    let mut sim = Simulation::new(SimulationSettings { sleep: SleepSettings::off(), ..settings }).unwrap();
    for body in pile::blob_pile(120, 12) {
        sim.add_body(body).unwrap();
    }
    count_allocations(&mut sim, 360, None);
    let allocations = count_allocations(&mut sim, 20, None);
    check(allocations, 1, &sim.take_profile().counters, "20 steady steps of 120 blobs");

    // A settled structure, awake: the benchmark's pyramid of 210 boxes takes the still paths
    // (every pair carried by its drift budget, its contacts refreshed where they lie, the broad
    // phase's last filter kept) and, on two threads, the wavefront solve; they allocate nothing
    // either.
    for threads in [1, 2] {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bench/pyramid-210-settled.ron"))
                .expect("the settled pyramid's snapshot");
        let mut snapshot = Snapshot::from_ron(&text).expect("a snapshot");
        snapshot.settings.threads = threads;
        let mut sim = Simulation::from_snapshot(snapshot).expect("it restores");
        count_allocations(&mut sim, 10, None);
        sim.take_profile();
        let allocations = count_allocations(&mut sim, 20, None);
        let counters = sim.take_profile().counters;
        assert_eq!(counters.substeps, 20, "{threads} threads: the settled pyramid takes one sub-step a step");
        assert_eq!(counters.still_phases, 20, "{threads} threads: a narrow phase decided its pairs one by one");
        assert_eq!(counters.broad_phase_kept, 20, "{threads} threads: a broad phase filtered its pairs again");
        assert_eq!(counters.refreshed_preparations, 20, "{threads} threads: a preparation built its contacts again");
        // With two threads, its one island's sweeps are shared as a wavefront.
        assert_eq!(counters.wavefront_solves, if threads == 1 { 0 } else { 20 }, "{threads} threads: wavefronts");
        check(allocations, threads, &counters, "20 steps of the settled pyramid");
    }
}
