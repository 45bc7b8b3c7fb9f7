//! Runs a RON scene and writes its event log, states, plots and animation frames.
//!
//! Run: `cargo run --release --example simulate -- [SCENE] [--steps N | --time T] [--out DIR]`
//! (default scene `assets/scenes/default.ron`, default output `out/<scene name>`). The files
//! and their columns are described in `docs/scenes.md`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};
use rugosa::report::plot::{FrameStyle, write_plots};
use rugosa::report::{Recording, ReportError};
use rugosa::{Profile, Scene, SceneError, Simulation};
use thiserror::Error;

/// Run a rugosa scene and write events.csv, states.csv, friction.png, velocity.png and frames.
#[derive(Parser, Debug)]
#[command(version)]
struct Args {
    /// Scene file (RON).
    #[arg(default_value = "assets/scenes/default.ron")]
    scene: PathBuf,
    /// Number of steps of `settings.time_step` to run.
    #[arg(long, conflicts_with = "time")]
    steps: Option<usize>,
    /// Simulated time to run (s); default: the scene's `duration`.
    #[arg(long)]
    time: Option<f64>,
    /// Output directory; default `out/<scene file stem>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0: as many as cores); default: the scene's `settings.threads`.
    #[arg(long)]
    threads: Option<usize>,
    /// Record the body states every K-th step.
    #[arg(long, default_value_t = 1, value_name = "K")]
    state_every: usize,
    /// Number of animation frames to draw.
    #[arg(long, default_value_t = 30)]
    frames: usize,
}

/// Why a run failed.
#[derive(Debug, Error)]
enum RunError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Report(#[from] ReportError),
    #[error("--time {0} must be finite and > 0")]
    Time(f64),
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &Args) -> Result<(), RunError> {
    let mut scene = Scene::load(&args.scene)?;
    if let Some(threads) = args.threads {
        scene.settings.threads = threads;
    }
    let mut sim = scene.build()?;
    let steps = step_count(args, &scene)?;
    let out = args.out.clone().unwrap_or_else(|| default_out_dir(&args.scene));
    println!("{}: {} bodies, {steps} steps of {} s", args.scene.display(), sim.body_count(), scene.settings.time_step);

    let start = Instant::now();
    let (recording, profile) = simulate(&mut sim, steps, args.state_every);
    let simulated = start.elapsed();
    recording.write_csv_files(&out)?;
    let frames = write_plots(&recording, &out, args.frames, &FrameStyle::default())?;
    print_summary(&recording, &profile, simulated, start.elapsed());
    println!("wrote {}: events.csv, states.csv, friction.png, velocity.png, {frames} frames", out.display());
    Ok(())
}

fn step_count(args: &Args, scene: &Scene) -> Result<usize, RunError> {
    if let Some(steps) = args.steps {
        return Ok(steps);
    }
    let time = args.time.unwrap_or(scene.duration);
    if !(time.is_finite() && time > 0.0) {
        return Err(RunError::Time(time));
    }
    Ok((time / scene.settings.time_step).round().max(1.0) as usize)
}

fn default_out_dir(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    Path::new("out").join(stem)
}

/// Steps the simulation with a progress bar (hidden when stderr is not a terminal).
fn simulate(sim: &mut Simulation, steps: usize, state_every: usize) -> (Recording, Profile) {
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(steps as u64) } else { ProgressBar::hidden() };
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} (eta {eta})") {
        bar.set_style(style);
    }
    let mut recording = Recording::new(sim, state_every);
    for _ in 0..steps {
        sim.step(sim.settings().time_step);
        recording.record_step(sim);
        bar.inc(1);
    }
    bar.finish_and_clear();
    (recording, sim.take_profile())
}

fn print_summary(recording: &Recording, profile: &Profile, simulated: Duration, total: Duration) {
    println!("\nevents: {}", recording.events.len());
    for (kind, count) in recording.events_by_kind() {
        println!("  {:<16} {count}", kind.name());
    }
    let c = &profile.counters;
    println!(
        "\nsub-steps {}, retries {}, retry-limit hits {}, contacts {}, impulse cap hits {}",
        c.substeps, c.retries, c.retry_limit_hits, c.contacts, c.impulse_cap_hits
    );
    println!("\n{profile}\n");
    println!("wall time: simulation {:.2} s, total with output {:.2} s", simulated.as_secs_f64(), total.as_secs_f64());
}
