//! Kinematic bodies (moving platforms, pushers): moved by the user's velocity alone, with
//! infinite mass; they carry and push dynamic bodies as mechanics says.

mod common;

use common::{box_spline, frictionless, ground, material, simulation};
use glam::DVec2;
use hecs::Entity;
use rugosa::{BodyActionError, BodyDesc, FrictionLaw, Rugosity, Simulation, SimulationSettings};

const DT: f64 = 1.0 / 120.0;
const G: f64 = 9.81;
const BAND: f64 = 0.002;

fn slab(width: f64, height: f64, friction: FrictionLaw) -> BodyDesc {
    let spline = box_spline(width, height, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material(0.0, friction))
}

fn x(sim: &Simulation, body: Entity) -> f64 {
    sim.state(body).unwrap().position.x
}

#[test]
fn a_kinematic_body_moves_at_its_velocity_whatever_it_meets() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(BAND, material(0.0, frictionless()))).unwrap();
    let platform =
        slab(2.0, 0.2, frictionless()).at(DVec2::new(0.0, 0.5), 0.0).with_velocity(DVec2::new(0.3, -0.1), 0.2);
    let platform = sim.add_body(platform.kinematic()).unwrap();
    let start = sim.state(platform).unwrap();
    // A heavy box lands on it: it does not notice.
    sim.add_body(slab(0.3, 0.3, frictionless()).at(DVec2::new(0.0, 1.0), 0.0)).unwrap();
    for _ in 0..60 {
        sim.step(DT);
    }
    let s = sim.state(platform).unwrap();
    let t = 60.0 * DT;
    assert!((s.position - (start.position + DVec2::new(0.3, -0.1) * t)).length() < 1e-12, "{s:?}");
    assert!((s.angle - 0.2 * t).abs() < 1e-12);
    assert_eq!((s.linear_velocity, s.angular_velocity), (DVec2::new(0.3, -0.1), 0.2));
}

#[test]
fn a_moving_platform_carries_a_box_after_friction_catches_it_up() {
    // Mechanics: the box (at rest) slides on the platform (speed v) until friction μ g brings it
    // to v, slipping v²/(2 μ g) behind; then it rides along. Allowance 1 mm.
    let (v, mu) = (0.5, 0.5);
    let rough = FrictionLaw { lambda_min: 0.0, mu_max: mu };
    let mut sim = simulation(DVec2::new(0.0, -G));
    let platform = slab(3.0, 0.2, rough).at(DVec2::new(0.0, 0.0), 0.0).with_velocity(DVec2::new(v, 0.0), 0.0);
    let platform = sim.add_body(platform.kinematic()).unwrap();
    let body = sim.add_body(slab(0.4, 0.2, rough).at(DVec2::new(0.0, 0.2 + 2.0 * BAND), 0.0)).unwrap();
    let (p0, b0) = (x(&sim, platform), x(&sim, body));
    for _ in 0..240 {
        sim.step(DT);
    }
    let slip = (x(&sim, platform) - p0) - (x(&sim, body) - b0);
    let expected = v * v / (2.0 * mu * G);
    assert!((slip - expected).abs() < 1e-3, "slipped {slip} m, mechanics says {expected} m");
    let relative = sim.state(body).unwrap().linear_velocity.x - v;
    assert!(relative.abs() < 1e-3, "the box does not ride along: {relative} m/s behind");
}

#[test]
fn a_kinematic_pusher_pushes_a_box_along_frictionless_ground_and_never_passes_it() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(BAND, material(0.0, frictionless()))).unwrap();
    let pusher = slab(0.2, 0.4, frictionless()).at(DVec2::new(-1.0, 0.2 + BAND), 0.0).with_velocity(DVec2::X, 0.0);
    let pusher = sim.add_body(pusher.kinematic()).unwrap();
    let body = sim.add_body(slab(0.4, 0.2, frictionless()).at(DVec2::new(0.0, 0.1 + BAND), 0.0)).unwrap();
    for _ in 0..240 {
        sim.step(DT);
        // Mechanics: after the pusher reaches it (0.7 s) the box moves at least as fast.
        assert!(x(&sim, body) - x(&sim, pusher) > 0.3 - 2.0 * BAND, "the pusher passed into the box");
    }
    // Inelastic push (e = 0): the box moves at the pusher's speed, 1 m/s. The pusher (taller
    // than the box) strikes the whole side, a patch between the two corners' roundings,
    // centred on the box's centre of mass: no turn. Allowance: what the resting solve may leave,
    // its tolerance (1e-7) of the combined band over a step, 4.8e-8 m/s. (While the conformal
    // test saw only the curvature at the nearest points, the patch reached up one corner's
    // rounding and not the other's, its centre off the centre of mass, the push turned the box,
    // and it left 2.1e-3 m/s fast; with the curvature's change taken unsigned, 1.1e-2 m/s.)
    let v = sim.state(body).unwrap().linear_velocity.x;
    let allowance = SimulationSettings::default().solver.tolerance * 2.0 * BAND / DT;
    assert!((v - 1.0).abs() <= allowance, "box at {v} m/s, allowed 1 ± {allowance:e}");
}

#[test]
fn a_moving_kinematic_body_wakes_what_it_touches_and_only_set_velocity_moves_it() {
    let mut sim = Simulation::new(SimulationSettings { threads: 1, ..Default::default() }).unwrap();
    sim.add_body(ground(BAND, material(0.0, frictionless()))).unwrap();
    let body = sim.add_body(slab(0.4, 0.2, frictionless()).at(DVec2::new(0.0, 0.1 + BAND), 0.0)).unwrap();
    let pusher =
        sim.add_body(slab(0.2, 0.4, frictionless()).at(DVec2::new(-1.0, 0.2 + BAND), 0.0).kinematic()).unwrap();
    for _ in 0..70 {
        sim.step(DT);
    }
    assert!(sim.is_sleeping(body));
    let err = sim.apply_force_to_centre(pusher, DVec2::X).unwrap_err();
    assert!(matches!(err, BodyActionError::Kinematic { .. }), "{err}");
    sim.set_velocity(pusher, DVec2::new(2.0, 0.0), 0.0).unwrap();
    for _ in 0..60 {
        sim.step(DT);
    }
    assert!(!sim.is_sleeping(body) && x(&sim, body) > 0.2, "the pushed box did not move: {}", x(&sim, body));
    let ground = sim.bodies().next().unwrap();
    assert!(matches!(sim.set_velocity(ground, DVec2::X, 0.0), Err(BodyActionError::Static { .. })));
}

#[test]
fn a_kinematic_target_is_reached_in_one_step() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    let platform = sim.add_body(slab(1.0, 0.2, frictionless()).kinematic()).unwrap();
    let dt = sim.settings().time_step;
    // A circle of radius 1 m, one point per step, turning with it.
    for k in 1..=60 {
        let phase = 0.05 * f64::from(k);
        let target = DVec2::new(phase.cos() - 1.0, phase.sin());
        sim.set_kinematic_target(platform, target, phase).unwrap();
        sim.step(dt);
        let s = sim.state(platform).unwrap();
        assert!(s.position.distance(target) < 1e-12 && (s.angle - phase).abs() < 1e-12, "step {k}: {s:?}");
    }
    let ground = sim.add_body(ground(BAND, material(0.0, frictionless()))).unwrap();
    let err = sim.set_kinematic_target(ground, DVec2::ZERO, 0.0).unwrap_err();
    assert!(matches!(err, BodyActionError::Static { .. }), "{err}");
}
