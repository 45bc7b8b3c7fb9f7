//! Sleeping (docs/model.md §8), with the semantics users know from Box2D and rapier: an island at rest
//! sleeps and costs nothing; it wakes when an awake body touches it, when its state is
//! changed, when a body it rests on is removed, or on request; a sleeping body never moves.

mod common;

use common::{box_spline, ground, material};
use glam::DVec2;
use hecs::Entity;
use rugosa::{BodyDesc, FrictionLaw, RigidState, Rugosity, Simulation, SimulationSettings, SleepSettings, Stage};

const DT: f64 = 1.0 / 120.0;
const BAND: f64 = 0.002;

fn rough() -> FrictionLaw {
    FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }
}

fn sleepy(sleep: SleepSettings) -> Simulation {
    let settings = SimulationSettings { threads: 1, sleep, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    sim.add_body(ground(BAND, material(0.0, rough()))).unwrap();
    sim
}

/// A 0.4 × 0.2 m box with its centre at `(x, y)`.
fn add_box(sim: &mut Simulation, x: f64, y: f64) -> Entity {
    let spline = box_spline(0.4, 0.2, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    let desc = BodyDesc::new(spline, rugosity).with_material(material(0.0, rough())).at(DVec2::new(x, y), 0.0);
    sim.add_body(desc).unwrap()
}

/// Height of a box's centre resting at the rest depth on the ground (level 0) or on `level`
/// boxes of the same size.
fn resting(level: usize) -> f64 {
    (level as f64 + 0.5) * 0.2 + (level + 1) as f64 * BAND
}

fn steps(sim: &mut Simulation, n: usize) {
    for _ in 0..n {
        sim.step(DT);
    }
}

#[test]
fn a_box_at_rest_falls_asleep_and_then_costs_nothing() {
    let mut sim = sleepy(SleepSettings::default());
    let body = add_box(&mut sim, 0.0, resting(0));
    // Still from the start: asleep once it has been still for `time` (0.5 s = 60 steps).
    steps(&mut sim, 59);
    assert!(!sim.is_sleeping(body), "asleep before it was still for 0.5 s");
    steps(&mut sim, 2);
    assert!(sim.is_sleeping(body), "not asleep after 0.5 s at rest");
    let state = sim.state(body).unwrap();
    assert_eq!((state.linear_velocity, state.angular_velocity), (DVec2::ZERO, 0.0), "a sleeping body has no velocity");
    let narrow = sim.take_profile().runs(Stage::NarrowPhase);
    assert!(narrow > 0);
    steps(&mut sim, 100);
    let profile = sim.take_profile();
    assert_eq!(profile.runs(Stage::NarrowPhase), 0, "a scene that sleeps still ran the narrow phase");
    assert_eq!(profile.counters.sleeping_bodies, 100);
    assert_eq!(sim.state(body).unwrap(), state, "a sleeping body moved");
    assert!((sim.time() - 161.0 * DT).abs() < 1e-12, "time does not advance while everything sleeps");
}

#[test]
fn with_sleeping_off_nothing_sleeps() {
    let mut sim = sleepy(SleepSettings::off());
    let body = add_box(&mut sim, 0.0, resting(0));
    steps(&mut sim, 200);
    assert!(!sim.is_sleeping(body));
    assert_eq!(sim.profile().counters.sleeping_bodies, 0);
}

#[test]
fn a_body_dropped_on_a_sleeping_one_wakes_it_and_lands_on_it() {
    let mut sim = sleepy(SleepSettings::default());
    let below = add_box(&mut sim, 0.0, resting(0));
    steps(&mut sim, 70);
    assert!(sim.is_sleeping(below));
    // Dropped from 5 cm above its resting place on the sleeping box.
    let above = add_box(&mut sim, 0.05, resting(1) + 0.05);
    let mut woke = false;
    for _ in 0..240 {
        sim.step(DT);
        woke |= !sim.is_sleeping(below);
    }
    assert!(woke, "the box below never woke");
    // Mechanics: the upper box lands on the lower one and both rest there (within the band).
    let (a, b) = (sim.state(above).unwrap(), sim.state(below).unwrap());
    assert!((b.position.y - resting(0)).abs() < 2.0 * BAND, "box below at {:?}", b.position);
    assert!((a.position.y - resting(1)).abs() < 3.0 * BAND, "box above at {:?}", a.position);
    assert!(a.position.y > b.position.y + 0.2, "the box above passed into the one below");
    // And the pair goes back to sleep together.
    steps(&mut sim, 120);
    assert!(sim.is_sleeping(above) && sim.is_sleeping(below));
}

#[test]
fn changing_a_sleeping_body_wakes_it() {
    let mut sim = sleepy(SleepSettings::default());
    let body = add_box(&mut sim, 0.0, resting(0));
    steps(&mut sim, 70);
    assert!(sim.is_sleeping(body));
    // A kick through the world: the next step must move the body.
    sim.world_mut().get::<&mut RigidState>(body).unwrap().linear_velocity = DVec2::new(1.0, 0.0);
    let before = sim.state(body).unwrap().position;
    sim.step(DT);
    assert!(!sim.is_sleeping(body));
    let moved = sim.state(body).unwrap().position.x - before.x;
    assert!(moved > 0.5 * DT, "a kicked sleeping body moved only {moved:e} m");
    assert!(sim.profile().counters.woken_bodies >= 1);
}

#[test]
fn removing_the_support_of_a_sleeping_stack_wakes_it_and_it_falls() {
    let mut sim = sleepy(SleepSettings::default());
    let bottom = add_box(&mut sim, 0.0, resting(0));
    let top = add_box(&mut sim, 0.0, resting(1));
    steps(&mut sim, 70);
    assert!(sim.is_sleeping(bottom) && sim.is_sleeping(top));
    assert!(sim.remove_body(bottom));
    assert!(!sim.is_sleeping(top), "the box on the removed one still sleeps");
    steps(&mut sim, 120);
    // Mechanics: it falls 0.2 m onto the ground and rests there.
    let y = sim.state(top).unwrap().position.y;
    assert!((y - resting(0)).abs() < 2.0 * BAND, "top box at y = {y}");
}

#[test]
fn wake_on_request_wakes_the_whole_island() {
    let mut sim = sleepy(SleepSettings::default());
    let bottom = add_box(&mut sim, 0.0, resting(0));
    let top = add_box(&mut sim, 0.0, resting(1));
    let apart = add_box(&mut sim, 3.0, resting(0));
    steps(&mut sim, 70);
    assert!(sim.is_sleeping(bottom) && sim.is_sleeping(top) && sim.is_sleeping(apart));
    assert!(sim.wake(top));
    assert!(!sim.is_sleeping(bottom) && !sim.is_sleeping(top), "its island must wake with it");
    assert!(sim.is_sleeping(apart), "another island woke");
    // Woken bodies at rest stay at rest.
    let before = sim.state(top).unwrap().position;
    steps(&mut sim, 30);
    assert!(sim.state(top).unwrap().position.distance(before) < 1e-6);
}

#[test]
fn switching_sleeping_off_wakes_everything() {
    let mut sim = sleepy(SleepSettings::default());
    let body = add_box(&mut sim, 0.0, resting(0));
    steps(&mut sim, 70);
    assert!(sim.is_sleeping(body));
    let bad = SleepSettings { speed: f64::NAN, ..SleepSettings::default() };
    assert!(sim.set_sleep(bad).unwrap_err().to_string().contains("sleep.speed"));
    assert!(sim.is_sleeping(body), "a refused setting changed something");
    sim.set_sleep(SleepSettings::off()).unwrap();
    assert!(!sim.is_sleeping(body));
    steps(&mut sim, 120);
    assert!(!sim.is_sleeping(body));
    assert!(sim.take_profile().runs(Stage::NarrowPhase) > 0);
}

#[test]
fn a_body_at_the_top_of_its_flight_does_not_fall_asleep() {
    let mut sim = sleepy(SleepSettings::default());
    let body = add_box(&mut sim, 0.0, 2.0);
    sim.world_mut().get::<&mut RigidState>(body).unwrap().linear_velocity = DVec2::new(0.0, 3.0);
    // Apex at 0.31 s: still (|v| < 0.05 m/s) for about 10 ms around it, far from 0.5 s.
    for _ in 0..60 {
        sim.step(DT);
        assert!(!sim.is_sleeping(body), "asleep in flight at t = {}", sim.time());
    }
}

#[test]
fn sleeping_gives_the_same_result_for_any_thread_count() {
    let run = |threads: usize| {
        let settings = SimulationSettings { threads, min_parallel_work: 0, ..SimulationSettings::default() };
        let mut sim = Simulation::new(settings).unwrap();
        sim.add_body(ground(BAND, material(0.0, rough()))).unwrap();
        for k in 0..6 {
            add_box(&mut sim, -1.5 + 0.5 * k as f64, resting(0) + 0.1 * k as f64);
        }
        let late = add_box(&mut sim, -1.5, 1.5);
        steps(&mut sim, 240);
        (sim.state_hash(), sim.is_sleeping(late), sim.profile().counters.sleeping_bodies)
    };
    let one = run(1);
    assert!(one.2 > 0, "nothing slept");
    assert_eq!(one, run(2));
}
