//! Step times of every engine on the throughput scenes.

use std::time::{Duration, Instant};

use rugosa::{Stage, StepCounters};

use crate::engine::{self, Setup, Variant};
use crate::scenes::SceneSpec;
use crate::shapes::ShapeStats;

/// Median of durations (`rugosa::report::median`: the upper median for an even count).
fn median(samples: Vec<Duration>) -> Duration {
    rugosa::report::median(samples).unwrap_or_default()
}

/// How long to run before and while measuring.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    /// Steps taken before measuring.
    pub warmup: usize,
    /// Steps measured.
    pub steps: usize,
}

/// One engine's step time on one scene with one setup.
#[derive(Clone, Debug)]
pub struct Timing {
    /// Median step time.
    pub step: Duration,
    /// rugosa only: median time of each stage, in `Stage::ALL` order.
    pub stages: Vec<Duration>,
    /// rugosa only: counters summed over the measured steps.
    pub counters: StepCounters,
    /// How each body's shape was built (peers), scene order.
    pub shapes: Vec<ShapeStats>,
}

/// Times `variant` on `spec`: `run.warmup` steps, then the median of `run.steps` timed steps.
#[must_use]
pub fn time(variant: Variant, spec: &SceneSpec, setup: Setup, run: Run) -> Timing {
    let (mut world, shapes) = engine::build(variant, spec, setup);
    let started = Instant::now();
    for k in 0..run.warmup {
        engine::advance(world.as_mut(), spec);
        if k % 30 == 29 && started.elapsed() > Duration::from_secs(5) {
            eprintln!("    {} warm-up step {} ({:.1} s)", variant.label(), k + 1, started.elapsed().as_secs_f64());
        }
    }
    world.take_profile();
    let mut per_stage: Vec<Vec<Duration>> = vec![Vec::new(); Stage::ALL.len()];
    let mut per_step = Vec::with_capacity(run.steps);
    let mut counters = StepCounters::default();
    for _ in 0..run.steps {
        let start = Instant::now();
        engine::advance(world.as_mut(), spec);
        per_step.push(start.elapsed());
        if let Some(profile) = world.take_profile() {
            for (k, stage) in Stage::ALL.iter().enumerate() {
                per_stage[k].push(profile.time(*stage));
            }
            counters.accumulate(&profile.counters);
        }
    }
    let stages = if per_stage[0].is_empty() { Vec::new() } else { per_stage.into_iter().map(median).collect() };
    Timing { step: median(per_step), stages, counters, shapes }
}
