//! The peers' landing pile of blobs (`tests/common/pile.rs`: `N` blobs, default 100, in a box),
//! built through the public API and stepped `STEPS` times (default 80) on `THREADS` threads;
//! after the steps up to `FROM` (default 60, the blobs falling) it prints the window's mean step
//! time, the counters and the stages' times a step, and the state hash
//! (`scripts/measure/pile-stages.sh` copies it into a worktree's examples and runs it). The
//! window's steps run through `measure_steps`, for `valgrind --toggle-collect`. `DEPTH` sets
//! `approach_depth` (read as RON, so that the program still builds at commits before the
//! setting; there, it is refused). `COUNTERS=1` prints every counter of the window, summed.

#[path = "../tests/common/pile.rs"]
mod pile;

use rugosa::{Simulation, SimulationSettings, SleepSettings, Stage};

fn var<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn main() {
    let (count, steps, from, threads): (usize, usize, usize, usize) =
        (var("N", 100), var("STEPS", 80), var("FROM", 60), var("THREADS", 1));
    let mut settings =
        SimulationSettings { record_events: false, sleep: SleepSettings::off(), threads, ..SimulationSettings::default() };
    if let Ok(depth) = std::env::var("DEPTH") {
        let given: SimulationSettings = ron::from_str(&format!("(approach_depth: {depth})")).expect("DEPTH: a commit with it");
        settings = SimulationSettings { record_events: false, sleep: SleepSettings::off(), threads, ..given };
    }
    let mut sim = Simulation::new(settings.clone()).unwrap();
    for body in pile::blob_pile(count, pile::square_columns(count)) {
        sim.add_body(body).unwrap();
    }
    for _ in 0..from.min(steps) {
        sim.step(settings.time_step);
    }
    let _ = sim.take_profile();
    measure_steps(&mut sim, steps.saturating_sub(from), settings.time_step);
    let profile = sim.take_profile();
    let (c, n) = (&profile.counters, profile.steps.max(1) as f64);
    println!(
        "pile {count}, steps {}-{steps}: mean {:.2} ms | sub-steps {:.2} leaf pairs {:.0} newton {:.0} contacts {:.0} | hash {:016x}",
        from + 1,
        profile.total().as_secs_f64() * 1e3 / n,
        c.substeps as f64 / n,
        c.leaf_pairs as f64 / n,
        c.newton_iterations as f64 / n,
        c.contacts as f64 / n,
        sim.state_hash(),
    );
    let stages: Vec<String> = Stage::ALL
        .iter()
        .map(|&stage| format!("{} {:.2}", stage.name(), profile.time(stage).as_secs_f64() * 1e3 / n))
        .filter(|s| !s.ends_with(" 0.00"))
        .collect();
    println!("   {}", stages.join(" | "));
    if std::env::var("COUNTERS").is_ok_and(|v| v == "1") {
        println!("   counters over the {} steps: {c:?}", profile.steps);
    }
}

#[inline(never)]
fn measure_steps(sim: &mut Simulation, steps: usize, dt: f64) {
    for _ in 0..steps {
        sim.step(dt);
    }
}
