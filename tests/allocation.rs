//! No allocation per step in steady state: once the step's buffers have grown to the scene,
//! stepping allocates nothing with one thread; with two, the only allocations are rayon's
//! job-queue blocks (one per 63 jobs handed to the pool, one job per step).
//!
//! The only test in this file, so the process-wide count sees no other test's allocations.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity, Simulation, SimulationSettings};

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

/// Twelve blobs dropped into a box: collisions, resting contact and micro-collisions.
fn settling_pile(threads: usize) -> Simulation {
    let settings = SimulationSettings { threads, record_events: true, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.6 }, ..Material::default() };
    let wall = |size: DVec2, at: DVec2| {
        let spline =
            Generator::RoundedRectangle { width: size.x, height: size.y, corner_radius: 0.05 }.build(32).unwrap();
        BodyDesc::new(spline, Rugosity::constant(32, 0.002).unwrap()).with_material(material).at(at, 0.0).fixed()
    };
    sim.add_body(wall(DVec2::new(2.0, 0.4), DVec2::new(0.0, -0.2))).unwrap();
    sim.add_body(wall(DVec2::new(0.4, 4.0), DVec2::new(-0.9, 2.0))).unwrap();
    sim.add_body(wall(DVec2::new(0.4, 4.0), DVec2::new(0.9, 2.0))).unwrap();
    for k in 0..12 {
        let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: k }.build(16).unwrap();
        let at = DVec2::new(-0.45 + 0.3 * (k % 4) as f64, 0.2 + 0.3 * (k / 4) as f64);
        let body = BodyDesc::new(spline, Rugosity::constant(16, 0.002).unwrap()).with_material(material);
        sim.add_body(body.at(at, 0.3 * k as f64)).unwrap();
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
