//! The contact hook against mechanics: a one-way platform (a ball thrown up through it lands on
//! it and rests there; without the hook it bounces off its underside), friction taken away by
//! the hook (a block slides on at its speed, where the materials' friction stops it in
//! `v²/(2μg)`), and values out of range (counted, not used).

mod common;

use std::sync::Arc;

use common::{box_spline, disc, ground, material, simulation};
use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, PairAction, PairContacts, Rugosity, Simulation};

const G: f64 = 9.81;
const BAND: f64 = 0.002;
const RADIUS: f64 = 0.1;
/// Top of the platform (m).
const TOP: f64 = 1.05;

/// μ = 0.5 on every band.
const ROUGH: FrictionLaw = FrictionLaw { lambda_min: 0.0, mu_max: 0.5 };

/// A platform 2 m wide and 0.1 m thick with its top at `TOP`, and a ball below it thrown up at
/// 5 m/s (its apex, 1.27 m above, is far above the platform).
fn scene() -> (Simulation, hecs::Entity) {
    let mut sim = simulation(DVec2::new(0.0, -G));
    let spline = box_spline(2.0, 0.1, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    let platform =
        BodyDesc::new(spline, rugosity).with_material(material(0.0, ROUGH)).at(DVec2::new(0.0, TOP - 0.05), 0.0);
    sim.add_body(platform.fixed().named("platform")).unwrap();
    let ball = disc(RADIUS, 32, BAND, material(0.0, ROUGH))
        .at(DVec2::new(0.0, 0.5), 0.0)
        .with_velocity(DVec2::new(0.0, 5.0), 0.0);
    let ball = sim.add_body(ball.named("ball")).unwrap();
    (sim, ball)
}

/// Steps `seconds`; returns the ball's highest centre.
fn run(sim: &mut Simulation, ball: hecs::Entity, seconds: f64) -> f64 {
    let mut highest = f64::NEG_INFINITY;
    for _ in 0..(seconds / sim.settings().time_step).round() as usize {
        sim.step(sim.settings().time_step);
        highest = highest.max(sim.state(ball).unwrap().position.y);
    }
    highest
}

#[test]
fn a_one_way_platform_lets_a_ball_through_from_below_and_holds_it_from_above() {
    // Without the hook the platform's underside stops the ball: its top never passes the
    // platform's bottom (TOP − 0.1), beyond the combined band.
    let (mut sim, ball) = scene();
    let highest = run(&mut sim, ball, 1.0);
    assert!(highest + RADIUS <= TOP - 0.1 + 2.0 * BAND, "without the hook the ball reached {highest}");

    // With it: ignored while the ball rises or its centre is below the top, so it passes up,
    // falls back and rests on the top: its centre between TOP + r and TOP + r + the band.
    let (mut sim, ball) = scene();
    sim.set_contact_hook(Some(Arc::new(move |pair: &PairContacts<'_>| {
        let state = if pair.body_a == ball { pair.state_a } else { pair.state_b };
        if state.linear_velocity.y > 0.0 || state.position.y < TOP { PairAction::Ignore } else { PairAction::Keep }
    })));
    let highest = run(&mut sim, ball, 3.0);
    let expected_apex = 0.5 + 25.0 / (2.0 * G);
    assert!((highest - expected_apex).abs() < 0.01, "apex {highest}, free flight gives {expected_apex}");
    let state = sim.state(ball).unwrap();
    let (low, high) = (TOP + RADIUS - 1e-4, TOP + RADIUS + 2.0 * BAND + 1e-4);
    assert!((low..=high).contains(&state.position.y), "rests at {} (between {low} and {high})", state.position.y);
    assert!(state.linear_velocity.length() < 1e-3, "still moving: {:?}", state.linear_velocity);
}

/// A 0.4 × 0.2 m block sliding at 2 m/s on rough ground (μ = 0.5): its speed after one second.
fn slide(hook: Option<rugosa::ContactHook>) -> (f64, u64) {
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(BAND, material(0.0, ROUGH))).unwrap();
    let spline = box_spline(0.4, 0.2, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    let block = BodyDesc::new(spline, rugosity)
        .with_material(material(0.0, ROUGH))
        .at(DVec2::new(0.0, 0.1 + BAND), 0.0)
        .with_velocity(DVec2::new(2.0, 0.0), 0.0);
    let block = sim.add_body(block).unwrap();
    sim.set_contact_hook(hook);
    sim.take_profile();
    for _ in 0..120 {
        sim.step(sim.settings().time_step);
    }
    (sim.state(block).unwrap().linear_velocity.x, sim.take_profile().counters.rejected_hook_values)
}

#[test]
fn the_hook_can_take_friction_away() {
    // Materials: the block stops within v²/(2μg) = 0.41 m, well inside one second.
    let (speed, _) = slide(None);
    assert!(speed.abs() < 1e-6, "with friction: {speed}");
    // Friction 0 from the hook: nothing slows it.
    let frictionless = PairAction::Modify { friction: Some(0.0), restitution: None };
    let (speed, rejected) = slide(Some(Arc::new(move |_: &PairContacts<'_>| frictionless)));
    assert!((speed - 2.0).abs() < 1e-9, "without friction: {speed}");
    assert_eq!(rejected, 0);
}

#[test]
fn values_out_of_range_are_counted_and_not_used() {
    let invalid = PairAction::Modify { friction: Some(-1.0), restitution: Some(f64::NAN) };
    let (speed, rejected) = slide(Some(Arc::new(move |_: &PairContacts<'_>| invalid)));
    assert!(speed.abs() < 1e-6, "the materials' friction stands: {speed}");
    assert!(rejected >= 2 * 120, "{rejected}");
}
