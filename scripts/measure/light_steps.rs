//! Light scenes on one and two threads (`scripts/measure/light-steps.sh` copies it into a
//! worktree's examples and runs it): each scene of `assets/scenes` named below, `copies` times
//! side by side 20 m apart, stepped 60 steps and then measured over 200, sleeping off, on one
//! thread, on two with every step on the pool (`min_parallel_work` 0) and on two with the default
//! (light steps on the caller's thread). `ROUNDS` rounds (default 9), the three runs of a round
//! one after the other; a time is the median over the rounds of each run's median step. Prints a
//! markdown table: the scene's work a step (candidate pairs, leaf pairs and contacts, as
//! `SimulationSettings::min_parallel_work` counts it) and the three times with their ratios to
//! one thread.

use std::time::Instant;

use glam::DVec2;
use rugosa::{Scene, Simulation, SimulationSettings, SleepSettings};

const CASES: &[(&str, usize)] = &[
    ("fig8-type3-type3", 1),
    ("fig8-type3-type3", 8),
    ("fig8-type3-type3", 16),
    ("fig8-type3-type3", 24),
    ("fig8-type3-type3", 32),
    ("fig12-irregular", 1),
    ("fig12-irregular", 4),
    ("fig12-irregular", 6),
    ("fig12-irregular", 8),
    ("fig12-irregular", 12),
    ("default", 1),
    ("default", 3),
    ("default", 6),
    ("default", 12),
];

fn main() {
    let rounds: usize = std::env::var("ROUNDS").ok().and_then(|v| v.parse().ok()).unwrap_or(9);
    println!("| scene | copies | bodies | work a step | one thread (ms) | two, every step on the pool | two, default | pool / one | default / one |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for &(name, copies) in CASES {
        let path = format!("{}/assets/scenes/{name}.ron", env!("CARGO_MANIFEST_DIR"));
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let runs = [(1, None), (2, Some(0)), (2, None)];
        let mut medians = [Vec::new(), Vec::new(), Vec::new()];
        let (mut work, mut bodies) = (0.0, 0);
        for _ in 0..rounds {
            for (k, &(threads, min_parallel_work)) in runs.iter().enumerate() {
                let defaults = SimulationSettings::default().min_parallel_work;
                let settings = SimulationSettings {
                    threads,
                    sleep: SleepSettings::off(),
                    record_events: false,
                    min_parallel_work: min_parallel_work.unwrap_or(defaults),
                    ..scene.settings.clone()
                };
                let mut sim = Simulation::new(settings.clone()).unwrap();
                for copy in 0..copies {
                    for desc in scene.body_descs().unwrap() {
                        let (position, angle) = (desc.position, desc.angle);
                        sim.add_body(desc.at(position + DVec2::new(20.0 * copy as f64, 0.0), angle)).unwrap();
                    }
                }
                for _ in 0..60 {
                    sim.step(settings.time_step);
                }
                let _ = sim.take_profile();
                let mut times: Vec<f64> = (0..200)
                    .map(|_| {
                        let start = Instant::now();
                        sim.step(settings.time_step);
                        start.elapsed().as_secs_f64() * 1e3
                    })
                    .collect();
                times.sort_by(f64::total_cmp);
                medians[k].push(times[times.len() / 2]);
                if k == 0 {
                    let c = sim.take_profile().counters;
                    work = c.work() as f64 / 200.0;
                    bodies = sim.body_count();
                }
            }
        }
        let [one, pool, default] = medians.map(|mut m| {
            m.sort_by(f64::total_cmp);
            m[m.len() / 2]
        });
        println!(
            "| {name} | {copies} | {bodies} | {work:.0} | {one:.4} | {pool:.4} | {default:.4} | {:.2} | {:.2} |",
            pool / one,
            default / one
        );
    }
}
