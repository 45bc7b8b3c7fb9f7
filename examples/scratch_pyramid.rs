use glam::DVec2;
use rugosa::*;
fn main() {
    let base: usize = std::env::args().nth(1).map_or(20, |s| s.parse().unwrap());
    let settings = SimulationSettings {
        threads: 1,
        record_events: false,
        sleep: SleepSettings::off(),
        coherence: std::env::var("COH").map_or(1e-3, |s| s.parse().unwrap()),
        ..SimulationSettings::default()
    };
    let mut sim = Simulation::new(settings).unwrap();
    let band = 0.005;
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.75 }, ..Material::default() };
    let pitch = 1.004;
    let ground = Generator::RoundedRectangle { width: base as f64 * pitch + 12.0, height: 1.0, corner_radius: 0.1 }
        .build(32)
        .unwrap();
    sim.add_body(
        BodyDesc::new(ground, Rugosity::constant(32, band).unwrap())
            .with_material(material)
            .at(DVec2::new(0.0, -0.5), 0.0)
            .fixed(),
    )
    .unwrap();
    for row in 0..base {
        let width = base - row;
        for column in 0..width {
            let x = (column as f64 - 0.5 * (width as f64 - 1.0)) * pitch;
            let y = 0.5 + 0.004 + row as f64 * pitch;
            let spline = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
            sim.add_body(
                BodyDesc::new(spline, Rugosity::constant(24, band).unwrap())
                    .with_material(material)
                    .at(DVec2::new(x, y), 0.0),
            )
            .unwrap();
        }
    }
    let dt = sim.settings().time_step;
    let t0 = std::time::Instant::now();
    for k in 0..80 {
        let t = std::time::Instant::now();
        sim.step(dt);
        let p = sim.take_profile();
        let c = &p.counters;
        if k % 5 == 4 {
            let st: Vec<String> = rugosa::Stage::ALL
                .iter()
                .filter(|s| p.time(**s).as_secs_f64() > 1e-4)
                .map(|s| format!("{}={:.2}", s.name(), p.time(*s).as_secs_f64() * 1e3))
                .collect();
            println!("   {}", st.join(" "));
            println!(
                "step {k:3} {:7.2} ms sub {:3} shrink {:3} retries {} pairs {:5} carried {:5} leaf {:6} contacts {:5} newton {:6} impulses {:4} solver_it {:5} unconv {} levels_hint {}",
                t.elapsed().as_secs_f64() * 1e3,
                c.substeps,
                c.bound_shrinks,
                c.retries,
                c.candidate_pairs,
                c.carried_pairs,
                c.leaf_pairs,
                c.contacts,
                c.newton_iterations,
                c.impulses,
                c.solver_iterations,
                c.solver_unconverged,
                c.islands
            );
        }
    }
    println!("total {:.2} s", t0.elapsed().as_secs_f64());
}
