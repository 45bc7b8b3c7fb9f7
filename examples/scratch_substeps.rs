#[path = "../tests/common/pile.rs"]
mod pile;
use rugosa::{Simulation, SimulationSettings, SleepSettings};
fn main() {
    let n: usize = std::env::args().nth(1).map_or(100, |s| s.parse().unwrap());
    let settings = SimulationSettings { threads: 1, record_events: false, sleep: SleepSettings::off(), ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    for body in pile::blob_pile(n, pile::square_columns(n)) { sim.add_body(body).unwrap(); }
    let dt = sim.settings().time_step;
    for k in 0..120 {
        sim.step(dt);
        let p = sim.take_profile();
        let c = &p.counters;
        println!("step {k:3} sub {:3} retries {:3} shrink {:3} floor {:3} cap {:2} pairs {:5} leaf {:6} contacts {:5} newton {:6} impulses {:4} solver_it {:5} recov {} carried {}",
            c.substeps, c.retries, c.bound_shrinks, c.advancement_floor_hits, c.substep_cap_hits, c.candidate_pairs, c.leaf_pairs, c.contacts, c.newton_iterations, c.impulses, c.solver_iterations, c.recovery_contacts, c.carried_pairs);
    }
}
