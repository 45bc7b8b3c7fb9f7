//! Regenerates the README's figures in `docs/img/` from real runs of the seed's experiments:
//! the friction coefficient per collision event (Figure 8), the velocities of an irregular
//! object against time (Figures 10–11, which plot them against time reparametrized to [0, 1])
//! and animation frames (Figure 12).
//! Figures 8, 10 and 11 run under both contact models: the iterated solver (default; files
//! `*-friction.png`, `*-velocity.png`) and the seed's micro-collisions (`*-seed.png`).
//!
//! Run: `cargo run --release --example figures [-- --out DIR]` (default `docs/img`).

use std::path::{Path, PathBuf};

use clap::Parser;
use rugosa::report::Recording;
use rugosa::report::plot::{FrameStyle, plot_friction, plot_velocity, render_frames};
use rugosa::{ContactModel, Scene, Simulation};

const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes");
const OUT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/img");

/// Regenerate the README's figures (seed Figures 8, 10–12) from real runs of the scenes.
#[derive(Parser, Debug)]
struct Args {
    /// Directory the PNG files are written to.
    #[arg(long, value_name = "DIR", default_value = OUT)]
    out: PathBuf,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let out = args.out.as_path();
    std::fs::create_dir_all(out)?;
    for (model, suffix) in [(ContactModel::Solver, ""), (ContactModel::SeedMicroCollisions, "-seed")] {
        for name in ["fig8-type1-type1", "fig8-type2-type3", "fig8-type3-type3", "fig8-type1-type4"] {
            let recording = run(name, model)?;
            plot_friction(&recording, &out.join(format!("{name}-friction{suffix}.png")))?;
        }
        for name in ["fig10-blob-constant", "fig11-blob-smooth", "fig11-blob-random"] {
            let recording = run(name, model)?;
            plot_velocity(&recording, &out.join(format!("{name}-velocity{suffix}.png")))?;
        }
    }
    let recording = run("fig12-irregular", ContactModel::Solver)?;
    let frames = out.join("fig12-frames");
    render_frames(&recording, &frames, 4, &FrameStyle { width: 800, ..FrameStyle::default() })?;
    println!("wrote figures to {}", out.display());
    Ok(())
}

/// Runs a scene of `assets/scenes` for its duration under `model`, recording every step.
fn run(name: &str, model: ContactModel) -> Result<Recording, Box<dyn std::error::Error>> {
    let path: PathBuf = Path::new(SCENES).join(format!("{name}.ron"));
    let mut scene = Scene::load(&path)?;
    scene.settings.contact_model = model;
    let mut sim: Simulation = scene.build()?;
    let steps = (scene.duration / scene.settings.time_step).round() as usize;
    let mut recording = Recording::new(&sim, 1);
    for _ in 0..steps {
        sim.step(scene.settings.time_step);
        recording.record_step(&mut sim);
    }
    println!(
        "{name} ({model:?}): {steps} steps, {} events",
        recording.events_by_kind().iter().map(|(_, n)| n).sum::<usize>()
    );
    Ok(recording)
}
