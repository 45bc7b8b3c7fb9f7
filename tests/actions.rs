//! Acting on bodies (forces, torques, impulses, velocities, gravity scale, damping, fixed
//! rotation), judged against Newton's laws, and the typed errors of refused actions.

mod common;

use common::{box_spline, disc, ground, material, simulation};
use glam::DVec2;
use rugosa::{
    BodyActionError, BodyDesc, FrictionLaw, MassProperties, Motion, RigidState, Rugosity, Simulation,
    SimulationSettings,
};

const DT: f64 = 1.0 / 120.0;
const G: f64 = 9.81;
const BAND: f64 = 0.002;

fn floating() -> Simulation {
    simulation(DVec2::ZERO)
}

fn boxed(width: f64, height: f64) -> BodyDesc {
    let spline = box_spline(width, height, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), BAND).unwrap();
    BodyDesc::new(spline, rugosity).with_material(material(0.0, FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }))
}

fn mass(sim: &Simulation, body: hecs::Entity) -> MassProperties {
    *sim.world().get::<&MassProperties>(body).unwrap()
}

fn state(sim: &Simulation, body: hecs::Entity) -> RigidState {
    sim.state(body).unwrap()
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance * b.abs().max(1.0)
}

#[test]
fn a_force_accelerates_over_one_step_then_is_cleared() {
    let mut sim = floating();
    let body = sim.add_body(boxed(0.4, 0.2)).unwrap();
    let m = mass(&sim, body).mass;
    sim.apply_force_to_centre(body, DVec2::new(3.0, -1.0)).unwrap();
    sim.apply_force_to_centre(body, DVec2::new(1.0, 0.0)).unwrap(); // forces add up
    sim.step(DT);
    // v = F t / m, x = F t² / (2m): exact for a constant force.
    let s = state(&sim, body);
    assert!(close(s.linear_velocity.x, 4.0 * DT / m, 1e-12) && close(s.linear_velocity.y, -DT / m, 1e-12), "{s:?}");
    assert!(close(s.position.x, 2.0 * DT * DT / m, 1e-9), "{s:?}");
    // Cleared after the step: the body now coasts.
    let v = s.linear_velocity;
    sim.step(DT);
    assert_eq!(state(&sim, body).linear_velocity, v, "the force acted again");
}

#[test]
fn a_force_off_the_centre_turns_the_body_and_a_torque_alone_does_not_move_it() {
    let mut sim = floating();
    let body = sim.add_body(boxed(0.4, 0.2)).unwrap();
    let props = mass(&sim, body);
    let centre = state(&sim, body).position;
    // Force (0, 2) at 0.1 m to the right of the centre: torque 0.2 N·m.
    sim.apply_force(body, DVec2::new(0.0, 2.0), centre + DVec2::new(0.1, 0.0)).unwrap();
    sim.step(DT);
    let s = state(&sim, body);
    assert!(close(s.angular_velocity, 0.2 * DT / props.inertia, 1e-12), "ω = {}", s.angular_velocity);
    assert!(close(s.linear_velocity.y, 2.0 * DT / props.mass, 1e-12));
    let mut sim = floating();
    let body = sim.add_body(boxed(0.4, 0.2)).unwrap();
    let start = state(&sim, body).position;
    sim.apply_torque(body, -0.5).unwrap();
    sim.step(DT);
    let s = state(&sim, body);
    assert!(close(s.angular_velocity, -0.5 * DT / props.inertia, 1e-12));
    assert!(close(s.angle, -0.25 * DT * DT / props.inertia, 1e-9), "θ = {}", s.angle);
    assert_eq!(s.position, start);
}

#[test]
fn an_impulse_changes_the_velocities_at_once() {
    let mut sim = floating();
    let body = sim.add_body(boxed(0.4, 0.2)).unwrap();
    let props = mass(&sim, body);
    let centre = state(&sim, body).position;
    sim.apply_impulse(body, DVec2::new(0.5, 0.0), centre + DVec2::new(0.0, 0.1)).unwrap();
    let s = state(&sim, body);
    assert!(close(s.linear_velocity.x, 0.5 / props.mass, 1e-14));
    // r × J = (0, 0.1) × (0.5, 0) = −0.05.
    assert!(close(s.angular_velocity, -0.05 / props.inertia, 1e-14));
    sim.set_velocity(body, DVec2::new(0.0, 2.0), 1.0).unwrap();
    sim.step(DT);
    let after = state(&sim, body);
    assert!(close(after.position.y - centre.y, 2.0 * DT, 1e-12) && close(after.angle, DT, 1e-12), "{after:?}");
}

#[test]
fn gravity_scale_sets_the_fall_and_zero_floats() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    let double = boxed(0.2, 0.2).with_motion(Motion { gravity_scale: 2.0, ..Motion::default() });
    let double = sim.add_body(double.at(DVec2::new(0.0, 10.0), 0.0)).unwrap();
    let float = boxed(0.2, 0.2).with_motion(Motion { gravity_scale: 0.0, ..Motion::default() });
    let float = sim.add_body(float.at(DVec2::new(1.0, 10.0), 0.0)).unwrap();
    let (y0, f0) = (state(&sim, double).position.y, state(&sim, float).position);
    for _ in 0..60 {
        sim.step(DT);
    }
    let t = 60.0 * DT;
    assert!(close(state(&sim, double).position.y, y0 - G * t * t, 1e-9), "fell to {}", state(&sim, double).position.y);
    assert_eq!(state(&sim, float).position, f0, "a body with gravity scale 0 moved");
}

#[test]
fn damping_slows_a_body_as_stated() {
    let mut sim = floating();
    let c = 2.0;
    let body = sim.add_body(boxed(0.2, 0.2).with_motion(Motion {
        linear_damping: c,
        angular_damping: c,
        ..Motion::default()
    }));
    let body = body.unwrap();
    sim.set_velocity(body, DVec2::new(1.0, 0.0), 3.0).unwrap();
    for _ in 0..120 {
        sim.step(DT);
    }
    // One sub-step per step (nothing to collide with): v = v0 / (1 + c h)^n, → v0 e^(−ct).
    let factor = (1.0 + c * DT).powi(-120);
    let s = state(&sim, body);
    assert!(close(s.linear_velocity.x, factor, 1e-12) && close(s.angular_velocity, 3.0 * factor, 1e-12), "{s:?}");
    assert!((factor - (-c).exp()).abs() < 0.01, "the damping is not the continuous one to 1 %");
}

#[test]
fn a_body_with_fixed_rotation_never_turns() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(BAND, material(0.0, FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }))).unwrap();
    let fixed = boxed(0.4, 0.2).with_motion(Motion { fixed_rotation: true, ..Motion::default() });
    // Dropped on a corner: it would tip over; with fixed rotation it lands flat... at its angle.
    let body = sim.add_body(fixed.at(DVec2::new(0.0, 0.5), 0.3)).unwrap();
    let centre = state(&sim, body).position;
    sim.apply_impulse(body, DVec2::new(1.0, 0.0), centre + DVec2::new(0.0, 0.3)).unwrap();
    for _ in 0..120 {
        sim.step(DT);
        let s = state(&sim, body);
        assert_eq!((s.angle, s.angular_velocity), (0.3, 0.0), "a body with fixed rotation turned");
    }
    let err = sim.set_velocity(body, DVec2::ZERO, 1.0).unwrap_err();
    assert!(err.to_string().contains("fixed rotation"), "{err}");
    assert!(sim.kinetic_energy().is_finite());
}

/// A box on flat ground (μ = 0.5) pushed sideways by a constant force `fraction × m g` for 1 s;
/// returns how far it moved.
fn pushed(fraction: f64) -> f64 {
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(BAND, material(0.0, FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }))).unwrap();
    let body = sim.add_body(boxed(0.4, 0.2).at(DVec2::new(0.0, 0.1 + BAND), 0.0)).unwrap();
    let weight = mass(&sim, body).mass * G;
    let start = state(&sim, body).position.x;
    for _ in 0..120 {
        sim.apply_force_to_centre(body, DVec2::new(fraction * weight, 0.0)).unwrap();
        sim.step(DT);
    }
    state(&sim, body).position.x - start
}

#[test]
fn a_push_below_the_friction_limit_holds_and_above_it_accelerates_as_newton_says() {
    // Mechanics: F < μ m g: static friction holds, no motion (allowance 1e-4 m, as for a box at
    // rest). F > μ m g: a = (F − μ m g)/m = 0.3 g; x(1 s) = ½ a t² = 1.4715 m (allowance 1e-3
    // relative: the sliding-stop case's error at this step is 3e-5).
    let held = pushed(0.3);
    assert!(held.abs() < 1e-4, "pushed below μ m g, the box moved {held:e} m");
    let slid = pushed(0.8);
    let expected = 0.5 * 0.3 * G;
    assert!((slid - expected).abs() < 1e-3 * expected, "slid {slid} m, Newton says {expected} m");
}

#[test]
fn a_huge_force_toward_a_thin_wall_does_not_push_through_it() {
    let mut sim = floating();
    let spline = box_spline(0.02, 2.0, 0.02);
    let rugosity = Rugosity::constant(spline.segment_count(), 0.0).unwrap();
    sim.add_body(BodyDesc::new(spline, rugosity).at(DVec2::new(1.0, 0.0), 0.0).fixed()).unwrap();
    let ball = sim.add_body(disc(0.05, 16, 0.0, material(0.5, FrictionLaw { lambda_min: 1.0, mu_max: 0.0 })));
    let ball = ball.unwrap();
    let m = mass(&sim, ball).mass;
    for _ in 0..10 {
        // 10⁶ g toward the wall: it reaches the wall within the first step at about 4 km/s,
        // then presses on it (every step then takes the most sub-steps, max_substeps).
        sim.apply_force_to_centre(ball, DVec2::new(1e6 * G * m, 0.0)).unwrap();
        sim.step(DT);
        assert!(state(&sim, ball).position.x < 1.0 - 0.01, "tunnelled to {:?}", state(&sim, ball).position);
    }
}

#[test]
fn refused_actions_name_the_reason_and_change_nothing() {
    let mut sim = simulation(DVec2::new(0.0, -G));
    let ground = sim.add_body(ground(BAND, material(0.0, FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }))).unwrap();
    let body = sim.add_body(boxed(0.4, 0.2).at(DVec2::new(0.0, 1.0), 0.0).named("crate")).unwrap();
    let before = state(&sim, body);
    let err = sim.apply_impulse(ground, DVec2::X, DVec2::ZERO).unwrap_err();
    assert!(matches!(err, BodyActionError::Static { .. }), "{err}");
    assert_eq!(err.to_string(), "apply_impulse: body 0 ('ground') is static; static bodies do not move");
    let err = sim.apply_force_to_centre(body, DVec2::new(f64::NAN, 0.0)).unwrap_err();
    assert_eq!(err.to_string(), "apply_force_to_centre: body 1 ('crate'): setting `force` = NaN: must be finite");
    let err = sim.set_motion(body, Motion { linear_damping: -1.0, ..Motion::default() }).unwrap_err();
    assert!(err.to_string().contains("motion.linear_damping"), "{err}");
    assert_eq!(state(&sim, body), before, "a refused action changed the body");
    assert!(sim.remove_body(body));
    let err = sim.set_velocity(body, DVec2::X, 0.0).unwrap_err();
    assert!(matches!(err, BodyActionError::NotABody { .. }), "{err}");
}

#[test]
fn acting_on_a_sleeping_body_wakes_it() {
    let settings = SimulationSettings { threads: 1, ..SimulationSettings::default() };
    let mut sim = Simulation::new(settings).unwrap();
    sim.add_body(ground(BAND, material(0.0, FrictionLaw { lambda_min: 0.0, mu_max: 0.5 }))).unwrap();
    let body = sim.add_body(boxed(0.4, 0.2).at(DVec2::new(0.0, 0.1 + BAND), 0.0)).unwrap();
    for _ in 0..70 {
        sim.step(DT);
    }
    assert!(sim.is_sleeping(body));
    // 2 m/s upward: 17 mm in the next step.
    let impulse = DVec2::new(0.0, 2.0 * mass(&sim, body).mass);
    sim.apply_impulse(body, impulse, state(&sim, body).position).unwrap();
    assert!(!sim.is_sleeping(body));
    let y = state(&sim, body).position.y;
    sim.step(DT);
    assert!(state(&sim, body).position.y > y + 0.01, "the woken body did not jump");
}

#[test]
fn a_body_of_another_simulation_is_never_one_of_ours() {
    let (mut a, mut b) = (floating(), floating());
    let body_a = a.add_body(boxed(0.2, 0.2)).unwrap();
    let body_b = b.add_body(boxed(0.2, 0.2)).unwrap();
    assert_ne!(body_a, body_b, "two simulations handed out the same handle");
    assert!(b.state(body_a).is_none());
    assert!(!b.remove_body(body_a), "removed a body of another simulation");
    assert_eq!(b.body_count(), 1);
    let err = b.apply_torque(body_a, 1.0).unwrap_err();
    assert!(matches!(err, BodyActionError::NotABody { .. }), "{err}");
    assert!(!b.wake(body_a) && !b.is_sleeping(body_a));
    // A removed body's handle does not name the body that takes its slot.
    assert!(a.remove_body(body_a));
    let again = a.add_body(boxed(0.2, 0.2)).unwrap();
    assert_eq!(again.id(), body_a.id(), "hecs reuses the freed slot");
    assert_ne!(again, body_a);
    assert!(a.state(body_a).is_none() && a.state(again).is_some());
    let _ = body_b;
}
