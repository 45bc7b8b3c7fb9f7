//! The peers' pyramid (`benches/peers`, base `BASE` boxes, 4 mm gaps, 5 mm bands), built through
//! the public API and stepped `STEPS` times on `THREADS` threads; every `EVERY` steps it prints
//! the mean step time, the counters and the stages' times per step since the last print
//! (`scripts/measure/pyramid-stages.sh` copies it into a worktree's examples and runs it).
//! Steps after `FROM` run through `measure_steps`, for `valgrind --toggle-collect`.
//! `REUSE` sets `contact_reuse`; `SUB` the resting solve's `subspace_iterations`, `PI`, `PT` and
//! `PS` the push-out's `position_iterations`, `position_tolerance` and `position_shortfall`
//! (read as RON, so that the program still builds at commits before a setting; there, it is
//! refused). Each print also gives the sub-steps whose resting solve stopped unconverged, the
//! fastest box, the most any box moved a step since the last print with the top box's
//! height, and the most any box has moved since the first print at or after step `ORIGIN`
//! (default 100; a creep grows there, a jitter does not). At the end it prints the state hash
//! (the same bits on any number of threads; a change meant to keep them checks it).

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity, Simulation, SimulationSettings, SleepSettings, Stage};

/// The environment variables that set solver settings, and the settings they set.
const SOLVER_VARIABLES: [(&str, &str); 4] = [
    ("SUB", "subspace_iterations"),
    ("PI", "position_iterations"),
    ("PT", "position_tolerance"),
    ("PS", "position_shortfall"),
];

fn var<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn main() {
    let (base, steps, threads): (usize, usize, usize) = (var("BASE", 40), var("STEPS", 80), var("THREADS", 1));
    let (from, every): (usize, usize) = (var("FROM", usize::MAX), var("EVERY", 20));
    let (band, gap) = (0.005, 0.004);
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.75 }, ..Material::default() };
    let pitch = 1.0 + gap;
    let ground_width = base as f64 * pitch + 12.0;
    let mut settings =
        SimulationSettings { record_events: false, sleep: SleepSettings::off(), threads, ..SimulationSettings::default() };
    settings.contact_reuse = var("REUSE", settings.contact_reuse);
    // The solver's settings given, as RON over the defaults (fields an older commit lacks are
    // refused there, not misread).
    let given: Vec<String> = SOLVER_VARIABLES
        .iter()
        .filter_map(|(var, field)| std::env::var(var).ok().map(|value| format!("{field}: {value}")))
        .collect();
    if !given.is_empty() {
        let text = format!("(iterations: {}, {})", settings.solver.iterations, given.join(", "));
        settings.solver = ron::from_str(&text).expect("SUB, PI, PT, PS: a commit with these solver settings");
    }
    let mut sim = Simulation::new(settings.clone()).unwrap();
    let ground = Generator::RoundedRectangle { width: ground_width, height: 1.0, corner_radius: 0.1 }.build(32).unwrap();
    let ground = BodyDesc::new(ground, Rugosity::constant(32, band).unwrap()).with_material(material);
    sim.add_body(ground.at(DVec2::new(0.0, -0.5), 0.0).fixed()).unwrap();
    for row in 0..base {
        let width = base - row;
        for column in 0..width {
            let x = (column as f64 - 0.5 * (width as f64 - 1.0)) * pitch;
            let y = 0.5 + gap + row as f64 * pitch;
            let spline = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
            let rugosity = Rugosity::constant(24, band).unwrap();
            sim.add_body(BodyDesc::new(spline, rugosity).with_material(material).at(DVec2::new(x, y), 0.0)).unwrap();
        }
    }
    let mut profile = rugosa::Profile::default();
    let boxes: Vec<_> = sim.bodies().collect();
    let positions = |sim: &Simulation| -> Vec<DVec2> { boxes.iter().map(|&e| sim.state(e).unwrap().position).collect() };
    let mut last = positions(&sim);
    let origin_step: usize = var("ORIGIN", 100);
    let mut origin: Option<(usize, Vec<DVec2>)> = None;
    for step in 1..=steps {
        if step > from { measure_steps(&mut sim, settings.time_step) } else { sim.step(settings.time_step) };
        profile.accumulate(&sim.take_profile());
        if step % every == 0 {
            let (c, n) = (&profile.counters, profile.steps as f64);
            println!(
                "step {step:4} mean {:.2} ms | sub-steps {:.2} sweeps/sub-step {:.1} pairs {:.0} carried {:.0} leaf pairs {:.0} newton {:.0} unconverged {} fastest {:.1e} m/s",
                profile.total().as_secs_f64() * 1e3 / n,
                c.substeps as f64 / n,
                c.solver_iterations as f64 / c.substeps.max(1) as f64,
                c.candidate_pairs as f64 / n,
                c.carried_pairs as f64 / n,
                c.leaf_pairs as f64 / n,
                c.newton_iterations as f64 / n,
                c.solver_unconverged,
                sim.bodies().filter_map(|e| sim.state(e)).map(|s| s.linear_velocity.length()).fold(0.0, f64::max),
            );
            let stages: Vec<String> = Stage::ALL
                .iter()
                .map(|&stage| format!("{} {:.2}", stage.name(), profile.time(stage).as_secs_f64() * 1e3 / n))
                .filter(|s| !s.ends_with(" 0.00"))
                .collect();
            println!("   {}", stages.join(" | "));
            let now = positions(&sim);
            let moved = now.iter().zip(&last).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max) / every as f64;
            let top = now.iter().map(|p| p.y).fold(f64::MIN, f64::max);
            if step >= origin_step && origin.is_none() {
                origin = Some((step, now.clone()));
            }
            let since = |origin: &[DVec2]| now.iter().zip(origin).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
            let since = origin.as_ref().map_or(String::new(), |(at, o)| format!(", {:.2e} m since step {at}", since(o)));
            println!("   moved {moved:.2e} m a step at most{since}, top box at {top:.7} m");
            last = now;
            profile = rugosa::Profile::default();
        }
    }
    println!("hash {:016x}", sim.state_hash());
}

#[inline(never)]
fn measure_steps(sim: &mut Simulation, dt: f64) {
    sim.step(dt);
}
