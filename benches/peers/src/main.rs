//! rugosa, Box2D v3 (boxdd) and rapier2d (f32 and f64) side by side: error against cost on cases
//! with an analytic answer, and step time on throughput scenes. Writes `docs/comparison.md`,
//! its figures in `docs/img/peers-*.png`, and the `peers` section of `docs/performance.md`.
//!
//! Run: `cargo run --release -p peers` (`-- --quick` for a short run that only prints; `-- --help`
//! for the options).

mod box2d_world;
mod cases;
mod engine;
mod measure;
mod plot;
mod polygon;
mod rapier_f32;
mod rapier_f64;
mod report;
mod rugosa_world;
mod scenes;
mod shapes;

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Parser;

use engine::{Peer, Setup, Variant};
use measure::{Run, Timing};
use scenes::SceneSpec;
use shapes::ShapeChoice;

/// Thread counts of the throughput runs.
pub const THREADS: [usize; 2] = [1, 2];

/// The engines of the throughput tables: rugosa, and each peer with polygons at 1e-3 and 1e-4
/// of the body size (rounded boxes exact), rapier in double precision at 1e-4 only.
pub const THROUGHPUT: [Variant; 6] = [
    Variant::RUGOSA,
    Variant { peer: Peer::Box2d, shapes: ShapeChoice::polygon(1e-3) },
    Variant { peer: Peer::Box2d, shapes: ShapeChoice::polygon(1e-4) },
    Variant { peer: Peer::RapierF32, shapes: ShapeChoice::polygon(1e-3) },
    Variant { peer: Peer::RapierF32, shapes: ShapeChoice::polygon(1e-4) },
    Variant { peer: Peer::RapierF64, shapes: ShapeChoice::polygon(1e-4) },
];

/// rugosa against Box2D v3 and rapier2d: error against cost, step time per scene.
#[derive(Parser, Debug)]
pub struct Args {
    /// Small scenes, few steps and steps swept; prints without writing any file.
    #[arg(long)]
    pub quick: bool,
    /// Pile sizes (number of blobs).
    #[arg(long, value_delimiter = ',', default_value = "100,500")]
    pub sizes: Vec<usize>,
    /// Measured steps per throughput run.
    #[arg(long, default_value_t = 20)]
    pub steps: usize,
    /// Steps run before measuring (the same for every engine).
    #[arg(long, default_value_t = 60)]
    pub warmup: usize,
    /// Rounds of the sleeping-off throughput runs: each round runs every engine once on a scene,
    /// one after the other (each round starting with the next engine), and a ratio is the median of
    /// the rounds' ratios. The sleeping-on runs take one round.
    #[arg(long, default_value_t = 3)]
    pub rounds: usize,
    /// Boxes in the base of the pyramid.
    #[arg(long, default_value_t = 20)]
    pub pyramid_base: usize,
    /// Boxes in the base of the larger pyramid.
    #[arg(long, default_value_t = 40)]
    pub large_pyramid_base: usize,
    /// Blobs in the tumbler.
    #[arg(long, default_value_t = 150)]
    pub tumbler: usize,
    /// Blobs of the rain.
    #[arg(long, default_value_t = 300)]
    pub rain: usize,
    /// Leave out the analytic cases (a partial run: writes nothing).
    #[arg(long)]
    pub no_cases: bool,
    /// Leave out the throughput scenes (a partial run: writes nothing).
    #[arg(long)]
    pub no_throughput: bool,
}

impl Args {
    fn apply_quick(&mut self) {
        if self.quick {
            self.sizes = vec![20];
            self.steps = 3;
            self.warmup = 5;
            self.rounds = 3;
            self.pyramid_base = 4;
            self.large_pyramid_base = 6;
            self.tumbler = 20;
            self.rain = 20;
        }
    }

    /// The command that reproduces this run.
    #[must_use]
    pub fn command(&self) -> String {
        let defaults = Args::parse_from(["peers"]);
        let mut flags = String::new();
        if self.sizes != defaults.sizes {
            let sizes: Vec<String> = self.sizes.iter().map(ToString::to_string).collect();
            flags.push_str(&format!(" --sizes {}", sizes.join(",")));
        }
        for (name, value, default) in [
            ("steps", self.steps, defaults.steps),
            ("warmup", self.warmup, defaults.warmup),
            ("rounds", self.rounds, defaults.rounds),
            ("pyramid-base", self.pyramid_base, defaults.pyramid_base),
            ("large-pyramid-base", self.large_pyramid_base, defaults.large_pyramid_base),
            ("tumbler", self.tumbler, defaults.tumbler),
            ("rain", self.rain, defaults.rain),
        ] {
            if value != default {
                flags.push_str(&format!(" --{name} {value}"));
            }
        }
        if flags.is_empty() {
            "cargo run --release -p peers".to_owned()
        } else {
            format!("cargo run --release -p peers --{flags}")
        }
    }
}

/// One case's sweep per engine variant.
pub struct CaseResult {
    /// The case.
    pub case: cases::Case,
    /// Each variant's points, in the case's variant order.
    pub rows: Vec<(Variant, Vec<cases::Point>)>,
}

/// One throughput scene: every variant at each thread count, sleeping off and on.
pub struct SceneResult {
    /// The scene.
    pub spec: SceneSpec,
    /// Warm-up and measured steps.
    pub run: Run,
    /// `[sleep off, sleep on]` → per variant of [`THROUGHPUT`] → per thread count of [`THREADS`].
    pub timings: [Vec<Vec<Timing>>; 2],
}

fn main() {
    let mut args = Args::parse();
    args.apply_quick();
    engine::watchdog(WATCHDOG_LIMIT);
    let started = Instant::now();
    let case_results = if args.no_cases { Vec::new() } else { run_cases(args.quick) };
    let scene_results = if args.no_throughput { Vec::new() } else { run_scenes(&args) };
    let elapsed = started.elapsed();
    let context = report::Context { args: &args, cases: &case_results, scenes: &scene_results, elapsed };
    let comparison = report::comparison(&context);
    let section = report::performance_section(&context);
    println!("{comparison}");
    if !(args.quick || args.no_cases || args.no_throughput) {
        write_outputs(&comparison, &section, &case_results, &scene_results);
    }
    eprintln!("total run time {:.0} s", elapsed.as_secs_f64());
}

/// How long the run may go without any engine finishing a step (the slowest step, a rugosa pile
/// of 2000 blobs landing, takes well under a second; building the largest scene a few).
const WATCHDOG_LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

fn run_cases(quick: bool) -> Vec<CaseResult> {
    cases::all()
        .into_iter()
        .map(|case| {
            eprintln!("case {}: {} variants × {} steps", case.name, case.variants.len(), cases::STEPS.len());
            let rows = case
                .variants
                .iter()
                .filter(|v| !quick || v.shapes.relative != 1e-3)
                .map(|&variant| (variant, case.sweep(variant)))
                .collect();
            CaseResult { case, rows }
        })
        .collect()
}

fn run_scenes(args: &Args) -> Vec<SceneResult> {
    let mut specs: Vec<SceneSpec> = args.sizes.iter().map(|&n| scenes::pile(n)).collect();
    specs.push(scenes::rain(args.rain));
    specs.push(scenes::tumbler(args.tumbler));
    specs.push(scenes::fig12().unwrap_or_else(|e| panic!("fig12 scene: {e}")));
    specs.push(scenes::pyramid(args.pyramid_base));
    specs.push(scenes::pyramid(args.large_pyramid_base));
    specs.push(scenes::pyramids(8, args.pyramid_base.min(6)));
    let run = Run { warmup: args.warmup, steps: args.steps, rounds: args.rounds.max(1) };
    specs
        .into_iter()
        .map(|spec| {
            eprintln!(
                "{}: {} bodies, {} + {} steps, {} round(s)",
                spec.name,
                spec.dynamic_count(),
                run.warmup,
                run.steps,
                run.rounds
            );
            let timings = [false, true].map(|sleep| time_scene(&spec, run, sleep));
            SceneResult { spec, run, timings }
        })
        .collect()
}

/// Every variant of [`THROUGHPUT`] at each thread count of [`THREADS`] on `spec`, in rounds (one
/// with sleeping on): within a round the engines run one after the other at one thread count,
/// then at the next, each round starting with the next engine, so that the runs a ratio compares
/// lie close together in time and no engine always runs first.
fn time_scene(spec: &SceneSpec, run: Run, sleep: bool) -> Vec<Vec<Timing>> {
    let rounds = if sleep { 1 } else { run.rounds };
    let mut runs: Vec<Vec<Vec<measure::Round>>> = vec![vec![Vec::new(); THREADS.len()]; THROUGHPUT.len()];
    for r in 0..rounds {
        for (t, &threads) in THREADS.iter().enumerate() {
            for j in 0..THROUGHPUT.len() {
                let k = (j + r) % THROUGHPUT.len();
                let variant = THROUGHPUT[k];
                let setup = Setup { dt: spec.settings.time_step, threads, sleep };
                let round = measure::round(variant, spec, setup, run);
                eprintln!(
                    "  round {}: {} × {threads}, sleep {}: {:.3} ms",
                    r + 1,
                    variant.label(),
                    if sleep { "on" } else { "off" },
                    round.step_ms()
                );
                runs[k][t].push(round);
            }
        }
    }
    runs.into_iter()
        .map(|per_thread| {
            per_thread
                .into_iter()
                .map(|rounds| {
                    let timing = Timing::of(rounds);
                    if !timing.counters_agree {
                        eprintln!("  warning: {}'s rounds counted different sub-steps or pairs", spec.name);
                    }
                    timing
                })
                .collect()
        })
        .collect()
}

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

fn write_outputs(comparison: &str, section: &str, cases: &[CaseResult], scenes: &[SceneResult]) {
    let root = root();
    let write = |path: &Path, text: &str| {
        std::fs::write(path, text).unwrap_or_else(|e| panic!("write {}: {e}", path.display()));
        eprintln!("wrote {}", path.display());
    };
    write(&root.join("docs/comparison.md"), comparison);
    let perf = root.join("docs/performance.md");
    let existing = std::fs::read_to_string(&perf).unwrap_or_default();
    write(&perf, &report::replace_section(&existing, section));
    for result in cases {
        let path = root.join(format!("docs/img/peers-{}.png", result.case.name));
        let axes = plot::Axes {
            title: &format!("{}: error against cost", result.case.name),
            x: "wall time of the run, stepping only (ms)",
            y: "error (relative)",
        };
        plot::write(&path, &axes, &report::case_series(result))
            .unwrap_or_else(|e| panic!("plot {}: {e}", path.display()));
        eprintln!("wrote {}", path.display());
    }
    let path = root.join("docs/img/peers-piles.png");
    let axes = plot::Axes { title: "Piles of blobs: step time (sleeping off)", x: "blobs", y: "median step time (ms)" };
    plot::write(&path, &axes, &report::pile_series(scenes)).unwrap_or_else(|e| panic!("plot {}: {e}", path.display()));
    eprintln!("wrote {}", path.display());
}
