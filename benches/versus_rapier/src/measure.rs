//! Step times of both engines and their accuracy against a fine-step run of their own.

use std::time::{Duration, Instant};

use glam::DVec2;
use hecs::Entity;
use rugosa::report::median;
use rugosa::{Simulation, SimulationSettings, Stage, StepCounters};

use crate::rapier_world::{self, ShapeStats};
use crate::scenes::SceneSpec;

/// How long to run before and while measuring.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    /// Steps taken before measuring.
    pub warmup: usize,
    /// Steps measured.
    pub steps: usize,
}

/// rugosa's step time and per-stage medians.
#[derive(Clone, Debug)]
pub struct RugosaTiming {
    /// Median step time.
    pub step: Duration,
    /// Median time of each stage, in `Stage::ALL` order.
    pub stages: Vec<Duration>,
    /// Counters summed over the measured steps.
    pub counters: StepCounters,
}

/// rapier's step time and how the shapes were built.
#[derive(Clone, Debug)]
pub struct RapierTiming {
    /// Median step time.
    pub step: Duration,
    /// Shape of every body, in scene order.
    pub shapes: Vec<ShapeStats>,
}

/// The scene in rugosa with `threads` workers and time step `dt`; entities in scene order.
#[must_use]
pub fn rugosa_scene(spec: &SceneSpec, threads: usize, dt: f64) -> (Simulation, Vec<Entity>) {
    let settings = SimulationSettings { threads, time_step: dt, ..spec.settings.clone() };
    let mut sim = Simulation::new(settings).expect("valid settings");
    let entities = spec.bodies.iter().map(|b| sim.add_body(b.clone()).expect("valid body")).collect();
    (sim, entities)
}

/// Step time of rugosa on `spec`, per stage.
#[must_use]
pub fn time_rugosa(spec: &SceneSpec, threads: usize, run: Run) -> RugosaTiming {
    let dt = spec.settings.time_step;
    let (mut sim, _) = rugosa_scene(spec, threads, dt);
    let started = Instant::now();
    for k in 0..run.warmup {
        sim.step(dt);
        if k % 30 == 29 {
            eprintln!("  rugosa {} × {threads}: warm-up step {} ({:.1} s)", spec.name, k + 1, secs(started));
        }
    }
    sim.take_profile();
    let mut per_stage: Vec<Vec<Duration>> = vec![Vec::new(); Stage::ALL.len()];
    let mut per_step = Vec::with_capacity(run.steps);
    let mut counters = StepCounters::default();
    for _ in 0..run.steps {
        let start = Instant::now();
        sim.step(dt);
        per_step.push(start.elapsed());
        let profile = sim.take_profile();
        for (k, stage) in Stage::ALL.iter().enumerate() {
            per_stage[k].push(profile.time(*stage));
        }
        counters.accumulate(&profile.counters);
    }
    let stages = per_stage.into_iter().map(|samples| median(samples).unwrap_or_default()).collect();
    RugosaTiming { step: median(per_step).unwrap_or_default(), stages, counters }
}

/// A rayon pool of `threads` workers for rapier's `parallel` feature.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("rayon pool")
}

/// Step time of rapier on `spec` with every spline sampled to `tolerance` (m).
#[must_use]
pub fn time_rapier(spec: &SceneSpec, tolerance: f64, threads: usize, run: Run) -> RapierTiming {
    let mut scene = rapier_world::build(spec, tolerance, spec.settings.time_step);
    let pool = pool(threads);
    pool.install(|| {
        for _ in 0..run.warmup {
            scene.world.step();
        }
        let per_step: Vec<Duration> = (0..run.steps)
            .map(|_| {
                let start = Instant::now();
                scene.world.step();
                start.elapsed()
            })
            .collect();
        RapierTiming { step: median(per_step).unwrap_or_default(), shapes: scene.shapes.clone() }
    })
}

fn secs(since: Instant) -> f64 {
    since.elapsed().as_secs_f64()
}

/// One point of error against cost.
#[derive(Clone, Copy, Debug)]
pub struct AccuracyPoint {
    /// Time step (s).
    pub dt: f64,
    /// Wall time of the whole horizon at this step (one thread).
    pub wall: Duration,
    /// RMS over dynamic bodies of |position − reference position| / body size, at the horizon.
    pub error: f64,
}

/// Positions of the dynamic bodies after `horizon` seconds at step `dt`, and the wall time.
type Final = (Vec<DVec2>, Duration);

/// rugosa on `spec` for `horizon` seconds at step `dt` (one thread).
#[must_use]
pub fn run_rugosa(spec: &SceneSpec, dt: f64, horizon: f64) -> Final {
    let (mut sim, entities) = rugosa_scene(spec, 1, dt);
    let steps = (horizon / dt).round() as usize;
    let start = Instant::now();
    for _ in 0..steps {
        sim.step(dt);
    }
    let wall = start.elapsed();
    let positions = dynamic(spec, &entities).map(|e| sim.state(*e).expect("body").position).collect();
    (positions, wall)
}

/// rapier on `spec` (splines sampled to `tolerance`) for `horizon` seconds at step `dt`.
#[must_use]
pub fn run_rapier(spec: &SceneSpec, tolerance: f64, dt: f64, horizon: f64) -> Final {
    let mut scene = rapier_world::build(spec, tolerance, dt);
    let steps = (horizon / dt).round() as usize;
    let wall = pool(1).install(|| {
        let start = Instant::now();
        for _ in 0..steps {
            scene.world.step();
        }
        start.elapsed()
    });
    let positions = (0..spec.bodies.len())
        .filter(|&i| !spec.bodies[i].is_static)
        .map(|i| rapier_world::position(&scene, i))
        .collect();
    (positions, wall)
}

fn dynamic<'a, T>(spec: &'a SceneSpec, items: &'a [T]) -> impl Iterator<Item = &'a T> + 'a {
    items.iter().zip(&spec.bodies).filter(|(_, b)| !b.is_static).map(|(item, _)| item)
}

/// Error against cost: `run(dt)` for each of `steps`, against `run(reference_dt)`.
pub fn accuracy(spec: &SceneSpec, steps: &[f64], reference_dt: f64, run: impl Fn(f64) -> Final) -> Vec<AccuracyPoint> {
    let (reference, _) = run(reference_dt);
    steps
        .iter()
        .map(|&dt| {
            let (positions, wall) = run(dt);
            let squares: f64 = positions.iter().zip(&reference).map(|(p, r)| p.distance_squared(*r)).sum();
            let error = (squares / positions.len().max(1) as f64).sqrt() / spec.body_size;
            AccuracyPoint { dt, wall, error }
        })
        .collect()
}
