//! Validation against mechanics (MODEL §9). Each test states the tolerance it uses and why.

mod common;

use common::{box_spline, disc, frictionless, ground, material, simulation};
use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Rugosity, Simulation};

const G: f64 = 9.81;

fn run(sim: &mut Simulation, seconds: f64) {
    let steps = (seconds / sim.settings().time_step).round() as usize;
    for _ in 0..steps {
        sim.step(sim.settings().time_step);
    }
}

#[test]
fn free_flight_is_an_exact_parabola_with_constant_spin() {
    // The integrator is exact for constant gravity, so only rounding remains: ~1e-13 relative
    // after 240 steps of O(1) values.
    let mut sim = simulation(DVec2::new(0.0, -G));
    let blob = Generator::Blob { radius: 0.3, roughness: 0.5, seed: 9 }.build(24).unwrap();
    let body = sim
        .add_body(BodyDesc::new(blob, Rugosity::constant(24, 0.002).unwrap()).with_velocity(DVec2::new(3.0, 4.0), 5.0))
        .unwrap();
    let start = sim.state(body).unwrap();
    run(&mut sim, 2.0);
    let t = sim.time();
    let end = sim.state(body).unwrap();
    let expected = start.position + DVec2::new(3.0, 4.0) * t + 0.5 * DVec2::new(0.0, -G) * t * t;
    assert!((end.position - expected).length() < 1e-11, "{} vs {expected}", end.position);
    assert!((end.angle - (start.angle + 5.0 * t)).abs() < 1e-12);
    assert_eq!(end.angular_velocity, 5.0);
    assert!((end.linear_velocity - DVec2::new(3.0, 4.0 - G * t)).length() < 1e-12);
}

#[test]
fn bounce_apex_heights_fall_as_e_to_the_2k() {
    // Frictionless disc dropped from 1 m onto flat ground, e = 0.8. The impact happens somewhere
    // inside the combined band (depth ≤ band = 2 × 0.002 m), which shifts each apex by at most
    // the band; sampling the apex at 1/120 s steps adds ≤ g h²/8 ≈ 9e-5 m. Tolerance per bounce
    // k: 2 × band × k.
    let e = 0.8;
    let radius = 0.2;
    let band = 0.002;
    let mut sim = simulation(DVec2::new(0.0, -G));
    sim.add_body(ground(band, material(e, frictionless()))).unwrap();
    let drop = 1.0;
    let contact_height = radius + 2.0 * band;
    let ball = sim
        .add_body(disc(radius, 64, band, material(e, frictionless())).at(DVec2::new(0.0, contact_height + drop), 0.0))
        .unwrap();
    let mut apexes = Vec::new();
    let mut previous_vy = 0.0;
    for _ in 0..(4.0 / sim.settings().time_step) as usize {
        sim.step(sim.settings().time_step);
        let s = sim.state(ball).unwrap();
        if previous_vy > 0.0 && s.linear_velocity.y <= 0.0 {
            apexes.push(s.position.y - contact_height);
        }
        previous_vy = s.linear_velocity.y;
    }
    assert!(apexes.len() >= 3, "only {} apexes: {apexes:?}", apexes.len());
    for (k, apex) in apexes.iter().take(3).enumerate() {
        let expected = drop * e.powi(2 * (k as i32 + 1));
        let tolerance = 2.0 * 2.0 * band * (k + 1) as f64;
        assert!((apex - expected).abs() < tolerance, "apex {}: {apex} vs {expected} (±{tolerance})", k + 1);
    }
}

/// A 0.4 × 0.2 m flat-bottomed box at rest on the ground with rugosity `band` on both.
fn block_on_ground(gravity: DVec2, band: f64, friction: FrictionLaw, speed: f64) -> (Simulation, hecs::Entity) {
    let mut sim = simulation(gravity);
    sim.add_body(ground(band, material(0.0, friction))).unwrap();
    let spline = box_spline(0.4, 0.2, 0.05);
    let rugosity = Rugosity::constant(spline.segment_count(), band).unwrap();
    let mut mat = material(0.0, friction);
    mat.restitution_max = 0.5;
    let block = BodyDesc::new(spline, rugosity)
        .with_material(mat)
        .at(DVec2::new(0.0, 0.1 + 1.5 * band), 0.0)
        .with_velocity(DVec2::new(speed, 0.0), 0.0);
    let entity = sim.add_body(block).unwrap();
    (sim, entity)
}

#[test]
fn sliding_block_stops_after_v0_squared_over_2_mu_g() {
    // μ from rugosity: λ = 0.004 on both, λ_min = 0.002, μ_max = 1 → μ = 0.5.
    let friction = FrictionLaw { lambda_min: 0.002, mu_max: 1.0 };
    let mu = friction.coefficient(0.004);
    assert!((mu - 0.5).abs() < 1e-15);
    let v0 = 2.0;
    let (mut sim, block) = block_on_ground(DVec2::new(0.0, -G), 0.004, friction, v0);
    let x0 = sim.state(block).unwrap().position.x;
    run(&mut sim, 0.6);
    let x_stopped = sim.state(block).unwrap().position.x;
    run(&mut sim, 0.4);
    let x_end = sim.state(block).unwrap().position.x;
    let expected = v0 * v0 / (2.0 * mu * G);
    // Friction acts through the micro-collision impulses, whose normal part averages m g per
    // unit time only over a hop cycle of a few steps: 3% on the stopping distance.
    let distance = x_end - x0;
    assert!((distance - expected).abs() < 0.03 * expected, "stopped after {distance} m, expected {expected}");
    // After the stop (t* = v0/(μg) = 0.41 s) the block only rocks in the band: its angle swings
    // by ~0.02 rad (2 mm at the half-height) and hops shift it by ~0.15 m/s × 1/60 s (2.5 mm).
    // Twice their sum: 1 cm between t = 0.6 s and 1 s.
    assert!((x_end - x_stopped).abs() < 0.01, "moved {} m after stopping", x_end - x_stopped);
}

/// Mean velocity along x over `[t0, t1]` (from positions), and the position at `t1`.
fn window_velocity(sim: &mut Simulation, body: hecs::Entity, t0: f64, t1: f64) -> f64 {
    run(sim, t0 - sim.time());
    let x0 = sim.state(body).unwrap().position.x;
    run(sim, t1 - sim.time());
    (sim.state(body).unwrap().position.x - x0) / (t1 - t0)
}

#[test]
fn block_on_incline_sticks_below_the_friction_angle_and_slides_above() {
    let friction = FrictionLaw { lambda_min: 0.002, mu_max: 1.0 };
    let mu = 0.5;
    let tilted = |tan: f64| {
        let theta = tan.atan();
        G * DVec2::new(theta.sin(), -theta.cos())
    };
    // Micro-collisions make a resting body hop, so it creeps at about v_r tan θ (MODEL §7),
    // with micro-bounce speed at most v_r = (1 + e_max)√(2gλ), λ = 0.008 m the combined band:
    // 0.59 m/s. Creep is a constant speed; sliding is an acceleration.
    let creep_speed = |tan: f64| (1.0 + 0.5) * (2.0 * G * 0.008f64).sqrt() * tan;
    // Below: tan θ = 0.4 < μ. No acceleration: the mean speeds over [0.25, 0.5] s and
    // [0.75, 1] s (each window ≥ 5 hops) agree within 0.1 m/s, and stay below the creep bound.
    let (mut sim, block) = block_on_ground(tilted(0.4), 0.004, friction, 0.0);
    let early = window_velocity(&mut sim, block, 0.25, 0.5);
    let late = window_velocity(&mut sim, block, 0.75, 1.0);
    eprintln!("tan 0.4: speeds {early:.3} → {late:.3} m/s");
    assert!((late - early).abs() < 0.1, "accelerated below the friction angle: {early} → {late} m/s");
    assert!(late.abs() < creep_speed(0.4), "creeps at {late} m/s, bound {}", creep_speed(0.4));
    // Above: tan θ = 0.7 → a = g (sin θ − μ cos θ): the speed gain over 0.5 s is a·Δt (creep
    // only offsets the speed, it does not accelerate).
    let (mut sim, block) = block_on_ground(tilted(0.7), 0.004, friction, 0.0);
    let theta = 0.7f64.atan();
    let accel = G * (theta.sin() - mu * theta.cos());
    let early = window_velocity(&mut sim, block, 0.25, 0.5);
    let late = window_velocity(&mut sim, block, 0.75, 1.0);
    let gain = late - early;
    eprintln!("tan 0.7: speeds {early:.3} → {late:.3} m/s, gain {gain:.3} (Coulomb {:.3})", accel * 0.5);
    // Each window averages ≥ 5 hops, leaving ~0.04 m/s of hop jitter per window: 10% of a·Δt.
    let coulomb = accel * 0.5;
    assert!((gain - coulomb).abs() < 0.1 * coulomb, "speed gained {gain} m/s over 0.5 s, Coulomb gives {coulomb}");
}

#[test]
fn disc_rolls_down_an_incline_at_two_thirds_g_sin_theta() {
    // tan θ = 0.5 ≤ 3μ = 1.5: rolling without slip, a = (2/3) g sin θ for a uniform disc (the
    // spline circle's inertia is m r²/2 to 1e-6). Distance after 1 s within 3%.
    let friction = FrictionLaw { lambda_min: 0.002, mu_max: 1.0 };
    let theta = 0.5f64.atan();
    let mut sim = simulation(G * DVec2::new(theta.sin(), -theta.cos()));
    sim.add_body(ground(0.004, material(0.0, friction))).unwrap();
    let mut mat = material(0.0, friction);
    mat.restitution_max = 0.5;
    let wheel = sim.add_body(disc(0.2, 64, 0.004, mat).at(DVec2::new(0.0, 0.2 + 0.006), 0.0)).unwrap();
    let x0 = sim.state(wheel).unwrap().position.x;
    run(&mut sim, 1.0);
    let rolled = sim.state(wheel).unwrap().position.x - x0;
    let expected = 0.5 * (2.0 / 3.0) * G * theta.sin() * sim.time() * sim.time();
    assert!((rolled - expected).abs() < 0.03 * expected, "rolled {rolled} m, expected {expected}");
}

fn two_discs(offset: DVec2, velocity: DVec2) -> (Simulation, hecs::Entity, hecs::Entity) {
    let mut sim = simulation(DVec2::ZERO);
    let mat = material(1.0, frictionless());
    let a = sim.add_body(disc(0.25, 64, 0.001, mat).at(DVec2::ZERO, 0.0).with_velocity(velocity, 0.0)).unwrap();
    let b = sim.add_body(disc(0.25, 64, 0.001, mat).at(offset, 0.0)).unwrap();
    (sim, a, b)
}

#[test]
fn frictionless_elastic_impact_conserves_momentum_and_energy() {
    // Impulses are equal and opposite and Newton's law with e = 1, μ = 0 is exactly elastic:
    // only rounding remains (1e-12 relative).
    let (mut sim, a, b) = two_discs(DVec2::new(1.0, 0.3), DVec2::new(2.0, 0.0));
    let mass = |e| {
        let m: rugosa::MassProperties = *sim.world().get::<&rugosa::MassProperties>(e).unwrap();
        m.mass
    };
    let (ma, mb) = (mass(a), mass(b));
    let momentum =
        |sim: &Simulation| ma * sim.state(a).unwrap().linear_velocity + mb * sim.state(b).unwrap().linear_velocity;
    let (p0, k0) = (momentum(&sim), sim.kinetic_energy());
    run(&mut sim, 1.0);
    let events = sim.drain_events().count();
    assert!(events >= 1, "the discs never collided");
    assert!((momentum(&sim) - p0).length() < 1e-12 * p0.length());
    assert!((sim.kinetic_energy() - k0).abs() < 1e-12 * k0, "{} vs {k0}", sim.kinetic_energy());
}

#[test]
fn equal_discs_swap_velocities_head_on() {
    // The contact normal of the symmetric spline circle is exactly horizontal (a joint lies on
    // the axis), so the swap is exact up to rounding.
    let (mut sim, a, b) = two_discs(DVec2::new(1.0, 0.0), DVec2::new(2.0, 0.0));
    run(&mut sim, 0.5);
    let (va, vb) = (sim.state(a).unwrap().linear_velocity, sim.state(b).unwrap().linear_velocity);
    assert!(va.length() < 1e-9, "A kept {va}");
    assert!((vb - DVec2::new(2.0, 0.0)).length() < 1e-9, "B got {vb}");
}
