//! No allocation per step in steady state: once the step's buffers have grown to the scene,
//! stepping allocates nothing with one thread; with two, the only allocations are rayon's
//! job-queue blocks (one per 63 jobs handed to the pool, one job per step).
//!
//! The only test in this file, so the process-wide count sees no other test's allocations.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

#[path = "common/pile.rs"]
mod pile;

use rugosa::{Simulation, SimulationSettings};

// ---------------------------------------------------------------------------------------------
// Allocation counting over every thread (the narrow phase runs on the rayon pool's threads).

struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Twelve blobs of the benchmark pile dropped into their box: collisions, resting contact and
/// micro-collisions.
fn settling_pile(threads: usize) -> Simulation {
    let settings = SimulationSettings { threads, record_events: true, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    for body in pile::blob_pile(12, 4) {
        sim.add_body(body).unwrap();
    }
    sim
}

/// Entries of a block of the pool's job queue (crossbeam-deque's `Injector`, which rayon uses
/// for jobs handed in from outside the pool): the queue allocates one block per this many jobs.
const JOB_QUEUE_BLOCK: u64 = 63;

#[test]
fn stepping_allocates_nothing_once_warm() {
    for threads in [1, 2] {
        let mut sim = settling_pile(threads);
        let dt = sim.settings().time_step;
        // Warm-up: the pile lands and settles, so every buffer reaches the size it needs.
        for _ in 0..480 {
            sim.step(dt);
            sim.drain_events().for_each(drop);
        }
        let before = sim.take_profile().counters;
        let allocated_before = ALLOCATIONS.load(Ordering::Relaxed);
        for _ in 0..240 {
            sim.step(dt);
            sim.drain_events().for_each(drop);
        }
        let allocations = ALLOCATIONS.load(Ordering::Relaxed) - allocated_before;
        let counters = sim.profile().counters;
        assert!(counters.contacts > 0 && before.contacts > 0, "{threads} threads: the pile is not in contact");
        // The engine's own buffers never grow once warm. With more than one thread the only
        // allocations are the job queue's blocks: at most one per JOB_QUEUE_BLOCK jobs, plus one
        // for a block boundary inside the window.
        let queue_blocks = counters.pool_jobs.div_ceil(JOB_QUEUE_BLOCK) + u64::from(counters.pool_jobs > 0);
        assert!(
            allocations as u64 <= queue_blocks,
            "{threads} threads: {allocations} allocations in 240 steady steps ({} pool jobs)",
            counters.pool_jobs
        );
        if threads == 1 {
            assert_eq!(allocations, 0, "one thread: {allocations} allocations in 240 steady steps");
        }
    }
}
