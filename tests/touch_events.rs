//! Begin and end of touching per pair (Box2D's contact begin/end events): one begin when a pair
//! starts touching, one end when it stops or a body is removed, nothing while it rests — asleep
//! or awake.

mod common;

use common::{disc, ground, material};
use glam::DVec2;
use rugosa::{FrictionLaw, Simulation, SimulationSettings, SleepSettings, TouchEvent, TouchKind};

const DT: f64 = 1.0 / 120.0;
const BAND: f64 = 0.002;

fn drop_ball(restitution: f64, sleep: SleepSettings) -> (Simulation, hecs::Entity, hecs::Entity) {
    let settings = SimulationSettings { threads: 1, sleep, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    let friction = FrictionLaw { lambda_min: 0.0, mu_max: 0.5 };
    let floor = sim.add_body(ground(BAND, material(restitution, friction))).unwrap();
    let ball = disc(0.1, 32, BAND, material(restitution, friction)).at(DVec2::new(0.0, 0.6), 0.0);
    let ball = sim.add_body(ball).unwrap();
    (sim, floor, ball)
}

fn events(sim: &mut Simulation, steps: usize) -> Vec<TouchEvent> {
    let mut all = Vec::new();
    for _ in 0..steps {
        sim.step(DT);
        all.extend(sim.drain_touch_events());
    }
    all
}

#[test]
fn a_ball_that_lands_and_rests_begins_once_and_ends_when_removed() {
    for sleep in [SleepSettings::off(), SleepSettings::default()] {
        let (mut sim, floor, ball) = drop_ball(0.0, sleep);
        let seen = events(&mut sim, 240);
        // Falls 0.5 m (0.32 s), lands inelastically, rests 1.7 s (asleep after 0.5 s with sleep on).
        assert_eq!(seen.len(), 1, "{sleep:?}: {seen:?}");
        let begin = seen[0];
        assert_eq!(
            (begin.kind, begin.body_a.min(begin.body_b), begin.body_a.max(begin.body_b)),
            (TouchKind::Begin, floor.min(ball), floor.max(ball))
        );
        let landing = (2.0 * 0.5 / 9.81_f64).sqrt();
        assert!((begin.time - landing).abs() < 0.03, "began at {} s, lands at {landing} s", begin.time);
        assert_eq!(sim.touching_pairs().len(), 1);
        assert!(sim.remove_body(ball));
        let ended: Vec<_> = sim.drain_touch_events().collect();
        assert_eq!(ended.len(), 1);
        assert_eq!(ended[0].kind, TouchKind::End);
        assert!(sim.touching_pairs().is_empty());
        assert!(events(&mut sim, 10).is_empty());
    }
}

#[test]
fn a_bouncing_ball_begins_and_ends_with_every_bounce() {
    let (mut sim, _, _) = drop_ball(0.8, SleepSettings::off());
    let seen = events(&mut sim, 120);
    // Mechanics: falls 0.5 m to the band (impact at t₁ = 0.319 s), bounces to 0.8² × 0.5 m, lands
    // again at t₂ = t₁ + 2√(2 · 0.32 / g) = 0.830 s; the third impact (1.24 s) is after 1 s.
    // Each impact lasts less than a step, so each gives a begin and an end in the same step.
    let kinds: Vec<TouchKind> = seen.iter().map(|e| e.kind).collect();
    use TouchKind::{Begin, End};
    assert_eq!(kinds, [Begin, End, Begin, End], "{seen:?}");
    let t1 = (2.0 * 0.5 / 9.81_f64).sqrt();
    let t2 = t1 + 2.0 * (2.0 * 0.32 / 9.81_f64).sqrt();
    for (event, expected) in seen.iter().zip([t1, t1, t2, t2]) {
        assert!((event.time - expected).abs() < 0.03, "{:?} at {} s, expected {expected} s", event.kind, event.time);
    }
}

#[test]
fn a_ball_falls_through_a_sensor_unhindered_and_the_sensor_reports_it_all_the_way() {
    let (mut sim, floor, _) = drop_ball(0.0, SleepSettings::off());
    let friction = FrictionLaw { lambda_min: 0.0, mu_max: 0.5 };
    let ball = sim.add_body(disc(0.1, 32, BAND, material(0.0, friction)).at(DVec2::new(2.0, 1.6), 0.0)).unwrap();
    // A static sensor box from 0.6 m to 1.2 m under the ball (lowest point at 1.5 m): the ball
    // enters it at 0.30 s, is wholly inside from 0.36 s, leaves it at 0.48 s and lands at 0.53 s.
    let spline = common::box_spline(1.0, 0.6, 0.1);
    let rugosity = rugosa::Rugosity::constant(spline.segment_count(), 0.0).unwrap();
    let zone = rugosa::BodyDesc::new(spline, rugosity).at(DVec2::new(2.0, 0.9), 0.0).fixed().sensor();
    let zone = sim.add_body(zone).unwrap();
    let pair = (zone.min(ball), zone.max(ball));
    let mut seen = Vec::new();
    let mut inside = Vec::new();
    for _ in 0..90 {
        sim.step(DT);
        seen.extend(sim.drain_touch_events().filter(|e| (e.body_a.min(e.body_b), e.body_a.max(e.body_b)) == pair));
        inside.push(sim.touching_pairs().contains(&pair));
        // Mechanics: free fall, untouched by the sensor, until the ball reaches the floor.
        let (t, y) = (sim.time(), sim.state(ball).unwrap().position.y);
        if t < 0.5 {
            assert!((y - (1.6 - 4.905 * t * t)).abs() < 1e-9, "the sensor touched the ball at t = {t}: y = {y}");
        }
    }
    let kinds: Vec<TouchKind> = seen.iter().map(|e| e.kind).collect();
    assert_eq!(kinds, [TouchKind::Begin, TouchKind::End], "{seen:?}");
    // In touch from entering to leaving, wholly inside included; the times as free fall gives.
    let enter = ((2.0 * 0.3) / 9.81_f64).sqrt();
    let leave = ((2.0 * (0.3 + 0.6 + 0.2)) / 9.81_f64).sqrt();
    assert!((seen[0].time - enter).abs() < 2.0 * DT && (seen[1].time - leave).abs() < 2.0 * DT, "{seen:?}");
    let touching_steps = inside.iter().filter(|&&t| t).count();
    assert!(inside.iter().skip_while(|&&t| !t).take_while(|&&t| t).count() == touching_steps, "{inside:?}");
    // The floor still stops the ball, which then rests below the zone.
    assert!(sim.touching_pairs().contains(&(floor.min(ball), floor.max(ball))));
}
