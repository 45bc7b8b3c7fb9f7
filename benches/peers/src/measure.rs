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

/// The ratios that can be read: positive and finite (a ratio of two step times).
pub fn readable(ratios: &[f64]) -> impl Iterator<Item = f64> + '_ {
    ratios.iter().copied().filter(|r| r.is_finite() && *r > 0.0)
}

/// Median of the readable ratios (`rugosa::report::median`, on their bits, which order as the
/// values of positive finite numbers), NaN for none.
#[must_use]
pub fn median_ratio(ratios: &[f64]) -> f64 {
    rugosa::report::median(readable(ratios).map(f64::to_bits)).map_or(f64::NAN, f64::from_bits)
}

/// How long to run before and while measuring.
#[derive(Clone, Copy, Debug)]
pub struct Run {
    /// Steps taken before measuring.
    pub warmup: usize,
    /// Steps measured.
    pub steps: usize,
    /// Rounds of the sleeping-off runs: each round runs every engine once, one after the other,
    /// so that a ratio can be taken between runs that lie close together in time.
    pub rounds: usize,
}

/// One run of one engine on one scene: the warm-up, then the measured steps.
#[derive(Clone, Debug)]
pub struct Round {
    /// Each measured step's wall time.
    per_step: Vec<Duration>,
    /// rugosa only: each stage's time in each measured step, in `Stage::ALL` order.
    per_stage: Vec<Vec<Duration>>,
    /// rugosa only: counters summed over the measured steps.
    counters: StepCounters,
    /// How each body's shape was built (peers), scene order.
    shapes: Vec<ShapeStats>,
}

impl Round {
    /// The median step time in milliseconds.
    #[must_use]
    pub fn step_ms(&self) -> f64 {
        median(self.per_step.clone()).as_secs_f64() * 1e3
    }
}

/// One engine's step time on one scene with one setup, over one or more rounds.
#[derive(Clone, Debug)]
pub struct Timing {
    /// Median over the rounds of each round's median step time.
    pub step: Duration,
    /// Each round's median step time, in round order.
    pub rounds: Vec<Duration>,
    /// rugosa only: median time of each stage over every measured step of every round, in
    /// `Stage::ALL` order.
    pub stages: Vec<Duration>,
    /// rugosa only: counters summed over the measured steps of the first round.
    pub counters: StepCounters,
    /// Whether every round took the same sub-steps and found the same pairs and contacts (a rugosa
    /// run is deterministic, so it must; counters of the threads' scheduling may differ).
    pub counters_agree: bool,
    /// How each body's shape was built (peers), scene order.
    pub shapes: Vec<ShapeStats>,
}

impl Timing {
    /// The timing of `rounds` (at least one) of the same engine, scene and setup.
    #[must_use]
    pub fn of(rounds: Vec<Round>) -> Timing {
        let first = rounds.first().expect("at least one round");
        let physics = |c: &StepCounters| (c.substeps, c.candidate_pairs, c.contacts, c.leaf_pairs, c.newton_iterations);
        let counters_agree = rounds.iter().all(|r| physics(&r.counters) == physics(&first.counters));
        let (counters, shapes) = (first.counters, first.shapes.clone());
        let round_steps: Vec<Duration> = rounds.iter().map(|r| median(r.per_step.clone())).collect();
        let mut per_stage: Vec<Vec<Duration>> = vec![Vec::new(); first.per_stage.len()];
        for round in &rounds {
            for (all, samples) in per_stage.iter_mut().zip(&round.per_stage) {
                all.extend_from_slice(samples);
            }
        }
        let stages =
            if per_stage.iter().all(Vec::is_empty) { Vec::new() } else { per_stage.into_iter().map(median).collect() };
        Timing { step: median(round_steps.clone()), rounds: round_steps, stages, counters, counters_agree, shapes }
    }

    /// The ratios of this timing's rounds to `other`'s, round by round (each pair ran close
    /// together in time).
    #[must_use]
    pub fn round_ratios(&self, other: &Timing) -> Vec<f64> {
        self.rounds.iter().zip(&other.rounds).map(|(a, b)| a.as_secs_f64() / b.as_secs_f64()).collect()
    }
}

/// Runs `variant` on `spec` once: `run.warmup` steps, then `run.steps` timed steps.
#[must_use]
pub fn round(variant: Variant, spec: &SceneSpec, setup: Setup, run: Run) -> Round {
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
    Round { per_step, per_stage, counters, shapes }
}
