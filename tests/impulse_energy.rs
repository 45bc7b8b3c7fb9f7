//! Impact laws against mechanics: energy, momentum, Newton's law and classical results.
//!
//! Tolerances. Kinetic energy may grow only by rounding: `ΔKE ≤ 1e-12 · KE_before`. The
//! energies are sums of a few products of doubles (relative error ~1e-16 each), so 1e-12
//! leaves four decades of margin and still catches any real gain (the seed law's gains are
//! ~1e-3 and larger relative to KE). Velocities recomputed from the bodies are compared to
//! `1e-12 ·` the speed scale of the inputs (largest `|v| + |ω||r|` term) for the same reason.

use glam::DVec2;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rugosa::{
    BandPenetration, BodyVelocity, ContactMassInput, ImpactContact, ImpulseError, ImpulseKind, ImpulseLaw,
    ImpulseOutcome, MicroCollisionSettings, apply_impulse, collision_matrix, contact_tangent, kinetic_energy,
    relative_velocity, resolve_impact, resolve_micro_collision,
};

const RANDOM_IMPACTS: usize = 10_000;
const ENERGY_ROUNDING: f64 = 1e-12;
const VELOCITY_ROUNDING: f64 = 1e-12;

/// Two bodies about to collide at a contact point at the origin.
#[derive(Clone, Copy, Debug)]
struct Impact {
    input: ContactMassInput,
    a: BodyVelocity,
    b: BodyVelocity,
    normal: DVec2,
    restitution: f64,
    friction: f64,
}

impl Impact {
    fn contact(&self) -> ImpactContact {
        ImpactContact::new(&self.input, self.a, self.b, self.normal, self.restitution, self.friction)
    }

    fn resolve(&self, law: ImpulseLaw) -> Result<ImpulseOutcome, ImpulseError> {
        resolve_impact(law, &self.contact())
    }

    fn after(&self, impulse: DVec2) -> (BodyVelocity, BodyVelocity) {
        apply_impulse(&self.input, self.a, self.b, impulse)
    }

    fn energy(&self) -> f64 {
        kinetic_energy(&self.input, self.a, self.b)
    }

    fn speed_scale(&self) -> f64 {
        let term = |v: BodyVelocity, r: DVec2| v.linear.length() + v.angular.abs() * r.length();
        term(self.a, self.input.r_a) + term(self.b, self.input.r_b)
    }
}

fn log_uniform(rng: &mut StdRng, low_exp: f64, high_exp: f64) -> f64 {
    10f64.powf(rng.random_range(low_exp..high_exp))
}

fn unit(rng: &mut StdRng) -> DVec2 {
    DVec2::from_angle(rng.random_range(0.0..std::f64::consts::TAU))
}

/// Inverse mass and inertia over four decades of mass and three of radius of gyration ρ, plus
/// a lever arm in a random direction. Its length is 0.5ρ to 2ρ, as for boundary points of
/// real shapes (disc √2 ρ, rod end √3 ρ, square corner √3 ρ), and exactly 0 in 5% of cases.
fn random_body(rng: &mut StdRng) -> (f64, f64, DVec2, BodyVelocity) {
    let mass = log_uniform(rng, -2.0, 2.0);
    let gyration = log_uniform(rng, -2.0, 1.0);
    let arm = if rng.random_range(0.0..1.0) < 0.05 { 0.0 } else { gyration * rng.random_range(0.5..2.0) };
    let speed = log_uniform(rng, -1.0, 1.0);
    let velocity = BodyVelocity {
        linear: unit(rng) * speed * rng.random_range(0.0..1.0),
        angular: speed / gyration * rng.random_range(-1.0..1.0),
    };
    (1.0 / mass, 1.0 / (mass * gyration * gyration), unit(rng) * arm, velocity)
}

/// A random approaching impact; B is static in a quarter of them. The approach speed is set
/// explicitly and A gets an extra tangential velocity up to 10 times that speed.
fn random_impact(rng: &mut StdRng) -> Impact {
    let (inverse_mass_a, inverse_inertia_a, r_a, mut a) = random_body(rng);
    let (mut inverse_mass_b, mut inverse_inertia_b, r_b, mut b) = random_body(rng);
    if rng.random_range(0.0..1.0) < 0.25 {
        (inverse_mass_b, inverse_inertia_b, b) = (0.0, 0.0, BodyVelocity::ZERO);
    }
    let input = ContactMassInput { inverse_mass_a, inverse_inertia_a, r_a, inverse_mass_b, inverse_inertia_b, r_b };
    let normal = unit(rng);
    let u_n = relative_velocity(&input, a, b).dot(normal);
    let approach = log_uniform(rng, -2.0, 1.0);
    a.linear += normal * (-approach - u_n) + contact_tangent(normal) * approach * rng.random_range(-10.0..10.0);
    let restitution = pick_with_ends(rng, 1.0);
    let friction = pick_with_ends(rng, 2.0);
    Impact { input, a, b, normal, restitution, friction }
}

/// Uniform in `[0, high]`, but exactly 0 or `high` one time in ten each.
fn pick_with_ends(rng: &mut StdRng, high: f64) -> f64 {
    match rng.random_range(0..10) {
        0 => 0.0,
        1 => high,
        _ => rng.random_range(0.0..high),
    }
}

fn random_impacts(seed: u64) -> impl Iterator<Item = Impact> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..RANDOM_IMPACTS).map(move |_| random_impact(&mut rng))
}

/// Relative kinetic energy change when `impulse` is applied.
fn relative_energy_gain(impact: &Impact, impulse: DVec2) -> f64 {
    let (a, b) = impact.after(impulse);
    let before = impact.energy();
    (kinetic_energy(&impact.input, a, b) - before) / before
}

#[test]
fn energy_safe_never_gains_energy_and_never_leaves_approaching() {
    let mut worst_gain = f64::NEG_INFINITY;
    for (i, impact) in random_impacts(1).enumerate() {
        let outcome = impact.resolve(ImpulseLaw::EnergySafe).unwrap_or_else(|e| panic!("impact {i}: {e}"));
        let gain = relative_energy_gain(&impact, outcome.impulse);
        worst_gain = worst_gain.max(gain);
        assert!(gain <= ENERGY_ROUNDING, "impact {i} gains {gain:e} of its energy: {impact:?} {outcome:?}");
        assert!(outcome.energy_change <= ENERGY_ROUNDING * impact.energy(), "impact {i}: {outcome:?}");
        let (a, b) = impact.after(outcome.impulse);
        let u_n = relative_velocity(&impact.input, a, b).dot(impact.normal);
        let floor = -VELOCITY_ROUNDING * impact.speed_scale();
        assert!(u_n >= floor, "impact {i} still approaches at {u_n:e}: {impact:?} {outcome:?}");
        assert!(outcome.normal_velocity_after >= floor, "impact {i}: {outcome:?}");
    }
    println!("energy-safe law: largest relative energy change {worst_gain:e}");
}

#[test]
fn seed_law_gains_energy_in_some_frictional_impacts() {
    let (mut gains, mut jams, mut worst) = (0usize, 0usize, 0f64);
    for impact in random_impacts(2) {
        match impact.resolve(ImpulseLaw::Seed) {
            Ok(outcome) => {
                let gain = relative_energy_gain(&impact, outcome.impulse);
                if gain > ENERGY_ROUNDING {
                    gains += 1;
                    worst = worst.max(gain);
                }
            }
            Err(ImpulseError::Jam { .. }) => jams += 1,
            Err(e) => panic!("seed law failed on {impact:?}: {e}"),
        }
    }
    let percent = |n: usize| 100.0 * n as f64 / RANDOM_IMPACTS as f64;
    println!(
        "seed law: gains energy in {gains}/{RANDOM_IMPACTS} random impacts ({:.2}%), largest gain {:.1}% of KE; \
         {jams} ({:.2}%) need a pulling normal impulse (Jam)",
        percent(gains),
        100.0 * worst,
        percent(jams),
    );
    assert!(gains > 0, "the seed law's energy paradox did not show in {RANDOM_IMPACTS} impacts");
}

#[test]
fn frictionless_energy_safe_equals_the_seed_law() {
    for (i, mut impact) in random_impacts(3).enumerate() {
        impact.friction = 0.0;
        let safe = impact.resolve(ImpulseLaw::EnergySafe).unwrap();
        let seed = impact.resolve(ImpulseLaw::Seed).unwrap();
        let scale = safe.impulse.length();
        assert!((safe.impulse - seed.impulse).length() <= 1e-12 * scale, "impact {i}: {safe:?} vs {seed:?}");
        assert_eq!(safe.kind, ImpulseKind::Frictionless);
        let newton = -impact.restitution * safe.normal_velocity_before;
        let tolerance = VELOCITY_ROUNDING * impact.speed_scale();
        assert!((safe.normal_velocity_after - newton).abs() <= tolerance, "impact {i}: {safe:?}");
    }
}

/// Linear momentum of both bodies and each body's angular momentum about the contact point
/// (the origin), which an impulse applied at that point cannot change.
fn momenta(input: &ContactMassInput, a: BodyVelocity, b: BodyVelocity) -> (DVec2, f64, f64) {
    let angular = |v: BodyVelocity, inverse_mass: f64, inverse_inertia: f64, r: DVec2| {
        v.angular / inverse_inertia + (-r).perp_dot(v.linear) / inverse_mass
    };
    (
        a.linear / input.inverse_mass_a + b.linear / input.inverse_mass_b,
        angular(a, input.inverse_mass_a, input.inverse_inertia_a, input.r_a),
        angular(b, input.inverse_mass_b, input.inverse_inertia_b, input.r_b),
    )
}

#[test]
fn frictionless_elastic_impacts_conserve_momentum_and_energy() {
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        for (i, mut impact) in random_impacts(4).filter(|x| x.input.inverse_mass_b > 0.0).enumerate() {
            (impact.friction, impact.restitution) = (0.0, 1.0);
            let outcome = impact.resolve(law).unwrap();
            let gain = relative_energy_gain(&impact, outcome.impulse);
            assert!(gain.abs() <= ENERGY_ROUNDING, "{law:?} impact {i}: energy changes by {gain:e}");
            let (p0, la0, lb0) = momenta(&impact.input, impact.a, impact.b);
            let (a, b) = impact.after(outcome.impulse);
            let (p1, la1, lb1) = momenta(&impact.input, a, b);
            let scale = momentum_scale(&impact);
            assert!((p1 - p0).length() <= 1e-12 * scale, "{law:?} impact {i}: momentum {p0} -> {p1}");
            assert!((la1 - la0).abs() <= 1e-12 * scale * impact.input.r_a.length(), "{law:?} impact {i}");
            assert!((lb1 - lb0).abs() <= 1e-12 * scale * impact.input.r_b.length(), "{law:?} impact {i}");
        }
    }
}

/// `Σ m |v| + |j|`: the size of the momenta being summed and exchanged.
fn momentum_scale(impact: &Impact) -> f64 {
    let p = |v: BodyVelocity, inverse_mass: f64| v.linear.length() / inverse_mass;
    let j = impact.resolve(ImpulseLaw::EnergySafe).unwrap().impulse.length();
    p(impact.a, impact.input.inverse_mass_a) + p(impact.b, impact.input.inverse_mass_b) + j
}

/// Solid disc of radius `radius` and mass 1: `I = ½ m R²`.
fn disc_inverse(radius: f64) -> (f64, f64) {
    (1.0, 2.0 / (radius * radius))
}

#[test]
fn equal_discs_head_on_swap_velocities() {
    let (w, iw) = disc_inverse(0.5);
    let input = ContactMassInput {
        inverse_mass_a: w,
        inverse_inertia_a: iw,
        r_a: DVec2::new(-0.5, 0.0),
        inverse_mass_b: w,
        inverse_inertia_b: iw,
        r_b: DVec2::new(0.5, 0.0),
    };
    // A on the right moving left at 3, B on the left moving right at 1; n from B to A is +x.
    let a = BodyVelocity { linear: DVec2::new(-3.0, 0.0), angular: 0.0 };
    let b = BodyVelocity { linear: DVec2::new(1.0, 0.0), angular: 0.0 };
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        let contact = ImpactContact::new(&input, a, b, DVec2::X, 1.0, 0.0);
        let outcome = resolve_impact(law, &contact).unwrap();
        let (a1, b1) = apply_impulse(&input, a, b, outcome.impulse);
        assert!((a1.linear - b.linear).length() < 1e-14 && (b1.linear - a.linear).length() < 1e-14, "{law:?}");
        assert_eq!((a1.angular, b1.angular), (0.0, 0.0), "{law:?}");
    }
}

#[test]
fn central_impact_with_large_friction_sticks() {
    let mut rng = StdRng::seed_from_u64(5);
    for i in 0..1000 {
        let normal = unit(&mut rng);
        let (radius_a, radius_b) = (log_uniform(&mut rng, -1.0, 1.0), log_uniform(&mut rng, -1.0, 1.0));
        // Discs touching along the line of centres: r_A = −R_A n, r_B = R_B n, so K_tn = 0.
        let input = ContactMassInput {
            inverse_mass_a: log_uniform(&mut rng, -2.0, 2.0),
            inverse_inertia_a: log_uniform(&mut rng, -2.0, 2.0),
            r_a: -radius_a * normal,
            inverse_mass_b: log_uniform(&mut rng, -2.0, 2.0),
            inverse_inertia_b: log_uniform(&mut rng, -2.0, 2.0),
            r_b: radius_b * normal,
        };
        let mut a = BodyVelocity { linear: unit(&mut rng), angular: rng.random_range(-5.0..5.0) };
        let b = BodyVelocity { linear: unit(&mut rng) * 0.5, angular: rng.random_range(-5.0..5.0) };
        // Approach at 1 with slip |u_t| ≤ 10: stopping it needs μ ≥ 10 K_nn/((1+e) K_tt) ≤ 10.
        let u = relative_velocity(&input, a, b);
        let slip = rng.random_range(-10.0..10.0);
        a.linear += normal * (-1.0 - u.dot(normal)) + contact_tangent(normal) * (slip - u.dot(contact_tangent(normal)));
        let contact = ImpactContact::new(&input, a, b, normal, rng.random_range(0.0..1.0), 100.0);
        // Sticking means solving K j = −(u + e u_n n): rounding grows with K's condition number.
        let scale = contact.velocity.length() * condition_number(contact.matrix);
        for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
            let outcome = resolve_impact(law, &contact).unwrap();
            assert_eq!(outcome.kind, ImpulseKind::Sticking, "{law:?} impact {i}: {outcome:?}");
            assert!(outcome.tangential_velocity_after.abs() <= 1e-12 * scale, "{law:?} impact {i}: {outcome:?}");
            let (a1, b1) = apply_impulse(&input, a, b, outcome.impulse);
            let u_t = relative_velocity(&input, a1, b1).dot(contact_tangent(normal));
            assert!(u_t.abs() <= 1e-12 * scale, "{law:?} impact {i}: u_t' = {u_t:e}");
        }
    }
}

/// Ratio of the eigenvalues of a symmetric positive definite 2×2 matrix.
fn condition_number(k: glam::DMat2) -> f64 {
    let (mean, det) = (0.5 * (k.x_axis.x + k.y_axis.y), k.determinant());
    let spread = (mean * mean - det).max(0.0).sqrt();
    (mean + spread) / (mean - spread)
}

/// A solid disc (m = 1, R, I = ½R²) hits static ground (n = +y) at contact r = (0, −R).
///
/// Expectation (derived): K = diag(3/m, 1/m) in (x, y) = (t, n), so the normal and tangential
/// problems decouple. Normal: `v_y' = −e v_y`, normal impulse `P = (1+e) m |v_y|`. Tangential:
/// the slip `u_t = v_x + ωR` falls by `3μ/m` per unit of P. If `|u_t| ≤ 3μP/m` it stops and
/// stays stopped (K_tn = 0 makes sticking stable): the tangential impulse is `−m u_t/3`, so
/// `v_x' = (2 v_x − Rω)/3` and `ω' = −v_x'/R`: the disc leaves rolling (MODEL §9's
/// `(2v0 + rω0)/3` with clockwise-positive spin). Otherwise it slides through:
/// `v_x' = v_x − μ P sign(u_t)/m`, `ω' = ω − 2μP sign(u_t)/(mR)`.
fn disc_on_ground(v: DVec2, omega: f64, radius: f64, e: f64, mu: f64) -> (BodyVelocity, BodyVelocity, ImpactContact) {
    let (w, iw) = disc_inverse(radius);
    let input = ContactMassInput {
        inverse_mass_a: w,
        inverse_inertia_a: iw,
        r_a: DVec2::new(0.0, -radius),
        inverse_mass_b: 0.0,
        inverse_inertia_b: 0.0,
        r_b: DVec2::ZERO,
    };
    let a = BodyVelocity { linear: v, angular: omega };
    let contact = ImpactContact::new(&input, a, BodyVelocity::ZERO, DVec2::Y, e, mu);
    let outcome = resolve_impact(ImpulseLaw::EnergySafe, &contact).unwrap();
    let seed = resolve_impact(ImpulseLaw::Seed, &contact).unwrap();
    assert!((outcome.impulse - seed.impulse).length() < 1e-13, "{outcome:?} vs {seed:?}");
    let (a1, _) = apply_impulse(&input, a, BodyVelocity::ZERO, outcome.impulse);
    (a, a1, contact)
}

#[test]
fn spinning_disc_on_ground_leaves_rolling_with_enough_friction() {
    let (radius, e) = (0.5, 0.6);
    let (v, omega) = (DVec2::new(2.0, -3.0), 4.0); // slip u_t = 2 + 4·0.5 = 4 ≤ 3μ(1+e)3 for μ = 0.5
    let (_, after, _) = disc_on_ground(v, omega, radius, e, 0.5);
    let rolling = (2.0 * v.x - radius * omega) / 3.0;
    assert!((after.linear.x - rolling).abs() < 1e-14, "v_x' = {} expected {rolling}", after.linear.x);
    assert!((after.angular + rolling / radius).abs() < 1e-14, "ω' = {} expected {}", after.angular, -rolling / radius);
    assert!((after.linear.y - 3.0 * e).abs() < 1e-14, "v_y' = {}", after.linear.y);
}

#[test]
fn spinning_disc_on_ground_slides_through_with_little_friction() {
    let (radius, e, mu) = (0.5, 0.6, 0.1);
    let (v, omega) = (DVec2::new(2.0, -3.0), 4.0); // slip 4 > 3·0.1·(1.6·3) = 1.44
    let (_, after, _) = disc_on_ground(v, omega, radius, e, mu);
    let normal_impulse = (1.0 + e) * 3.0;
    assert!((after.linear.x - (v.x - mu * normal_impulse)).abs() < 1e-14, "v_x' = {}", after.linear.x);
    let spin = omega - 2.0 * mu * normal_impulse / radius;
    assert!((after.angular - spin).abs() < 1e-13, "ω' = {} expected {spin}", after.angular);
}

#[test]
fn impact_at_the_centre_of_mass_and_without_slip_is_well_defined() {
    let (w, iw) = disc_inverse(1.0);
    let input = ContactMassInput {
        inverse_mass_a: w,
        inverse_inertia_a: iw,
        r_a: DVec2::ZERO,
        inverse_mass_b: 0.0,
        inverse_inertia_b: 0.0,
        r_b: DVec2::ZERO,
    };
    let a = BodyVelocity { linear: DVec2::new(0.0, -2.0), angular: 1.0 };
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        let contact = ImpactContact::new(&input, a, BodyVelocity::ZERO, DVec2::Y, 0.5, 0.3);
        let outcome = resolve_impact(law, &contact).unwrap();
        assert_eq!(outcome.impulse, DVec2::new(0.0, 3.0), "{law:?}");
        assert_eq!(outcome.kind, ImpulseKind::Sticking, "{law:?}");
    }
}

#[test]
fn singular_collision_matrix_gives_finite_impulses_or_typed_errors() {
    // Both bodies pinned (inverse mass 0, free to rotate): K has rank ≤ 2 and may be singular.
    let input = ContactMassInput {
        inverse_mass_a: 0.0,
        inverse_inertia_a: 1.0,
        r_a: DVec2::new(1.0, 0.0),
        inverse_mass_b: 0.0,
        inverse_inertia_b: 0.0,
        r_b: DVec2::ZERO,
    };
    let k = collision_matrix(&input);
    assert!(k.determinant().abs() < 1e-15, "{k:?}");
    let a = BodyVelocity { linear: DVec2::ZERO, angular: -1.0 }; // contact point moves at (0, −1)
    for (normal, mu) in [(DVec2::Y, 0.0), (DVec2::Y, 1.0), (DVec2::new(0.6, 0.8), 0.5), (DVec2::X, 1.0)] {
        for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
            let contact = ImpactContact::new(&input, a, BodyVelocity::ZERO, normal, 0.5, mu);
            match resolve_impact(law, &contact) {
                Ok(outcome) => {
                    assert!(outcome.impulse.is_finite(), "{law:?} {normal} {mu}: {outcome:?}");
                    assert!(outcome.normal_velocity_after >= -1e-12, "{law:?} {normal} {mu}: {outcome:?}");
                }
                Err(error) => assert!(
                    matches!(error, ImpulseError::Unresolvable { .. } | ImpulseError::Jam { .. }),
                    "{law:?} {normal} {mu}: {error}"
                ),
            }
        }
    }
}

#[test]
fn non_finite_or_out_of_range_inputs_are_typed_errors() {
    let impact = random_impacts(6).next().unwrap();
    let good = impact.contact();
    let cases = [
        ImpactContact { velocity: DVec2::new(f64::NAN, 0.0), ..good },
        ImpactContact { normal: DVec2::new(f64::INFINITY, 0.0), ..good },
        ImpactContact { friction: f64::NAN, ..good },
        ImpactContact { restitution: 1.5, ..good },
        ImpactContact { friction: -0.1, ..good },
        ImpactContact { normal: DVec2::new(2.0, 0.0), ..good },
        ImpactContact { matrix: -good.matrix, ..good },
    ];
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        for (i, contact) in cases.iter().enumerate() {
            let result = resolve_impact(law, contact);
            assert!(
                matches!(result, Err(ImpulseError::NonFinite { .. } | ImpulseError::OutOfRange { .. })),
                "{law:?} case {i}: {result:?}"
            );
        }
    }
}

#[test]
fn separating_contacts_get_no_impulse() {
    let mut impact = random_impacts(7).next().unwrap();
    impact.a.linear += impact.normal * 100.0;
    let outcome = impact.resolve(ImpulseLaw::EnergySafe).unwrap();
    assert_eq!((outcome.impulse, outcome.kind), (DVec2::ZERO, ImpulseKind::Separating));
}

#[test]
fn resting_disc_micro_collides_with_band_restitution() {
    let (v, omega, radius) = (DVec2::new(0.3, -0.001), -0.6, 0.5); // rolling, barely approaching
    let (_, _, contact) = disc_on_ground(DVec2::new(0.3, -1.0), omega, radius, 0.2, 1.0);
    let contact = ImpactContact { velocity: contact.velocity + DVec2::new(0.0, 1.0 + v.y), ..contact };
    let settings = MicroCollisionSettings { resting_speed: 0.01, restitution_max: 0.8 };
    let band = BandPenetration { penetration: 0.002, tolerance: 0.004 };
    let outcome = resolve_micro_collision(ImpulseLaw::EnergySafe, &contact, band, 9.81, &settings).unwrap().unwrap();
    let speed = (2.0 * 9.81 * 0.002f64).sqrt();
    let e_c = 0.2 + (0.8 - 0.2) * 0.25;
    assert!((outcome.normal_velocity_before + speed).abs() < 1e-15, "{outcome:?}");
    assert!((outcome.normal_velocity_after - e_c * speed).abs() < 1e-14, "{outcome:?}");
    // A rolling disc (u_t = 0) with stable sticking keeps rolling.
    assert!(outcome.tangential_velocity_after.abs() < 1e-14, "{outcome:?}");

    let moving = ImpactContact { velocity: contact.velocity + DVec2::new(0.0, -0.5), ..contact };
    let none = resolve_micro_collision(ImpulseLaw::EnergySafe, &moving, band, 9.81, &settings).unwrap();
    assert!(none.is_none(), "an approach at 0.5 m/s is a collision, not a resting contact");
    let bad = BandPenetration { penetration: f64::NAN, ..band };
    let error = resolve_micro_collision(ImpulseLaw::EnergySafe, &contact, bad, 9.81, &settings);
    assert!(matches!(error, Err(ImpulseError::NonFinite { field: "band.penetration" })), "{error:?}");
}

/// Unit mass and inertia, lever arm (1, −1), static ground n = +y, t = (−1, 0): K = [[2, 1],
/// [1, 2]], so in the contact frame K_tt = K_nn = 2, K_tn = −1, and sticking is stable only
/// for μ ≥ |K_tn|/K_tt = ½.
fn coupled_body_on_ground(velocity: DVec2, e: f64, mu: f64) -> ImpactContact {
    let input = ContactMassInput {
        inverse_mass_a: 1.0,
        inverse_inertia_a: 1.0,
        r_a: DVec2::new(1.0, -1.0),
        inverse_mass_b: 0.0,
        inverse_inertia_b: 0.0,
        r_b: DVec2::ZERO,
    };
    let a = BodyVelocity { linear: velocity, angular: 0.0 };
    ImpactContact::new(&input, a, BodyVelocity::ZERO, DVec2::Y, e, mu)
}

/// u_t = 0.1, u_n = −1, e = 1, μ = 0.3. The seed law slides and gains energy (ΔKE = 0.1554).
/// Stronge, derived by hand: slide s = +1 (du_t/dp = −1.6, du_n/dp = 2.3) stops at p₁ = 1/16;
/// sticking is unstable so slip reverses, s = −1 (du_t/dp = −0.4, du_n/dp = 1.7); compression
/// ends at p₂ = p₁ + u_n(p₁)/1.7; restitution does the compression's work back,
/// Δp₃ = √(2|W_c|/1.7). ΔKE is then only the friction work, negative.
#[test]
fn reversing_slip_dissipates_where_the_seed_law_gains_energy() {
    let contact = coupled_body_on_ground(DVec2::new(-0.1, -1.0), 1.0, 0.3);
    let seed = resolve_impact(ImpulseLaw::Seed, &contact).unwrap();
    assert!(seed.energy_change > 0.15, "{seed:?}");

    let outcome = resolve_impact(ImpulseLaw::EnergySafe, &contact).unwrap();
    let p1: f64 = 0.1 / 1.6;
    let u_n1 = -1.0 + 2.3 * p1;
    let work_c = (-1.0 + 0.5 * 2.3 * p1) * p1 - u_n1 * u_n1 / (2.0 * 1.7);
    let p3 = (2.0 * -work_c / 1.7).sqrt();
    let (reverse, total) = (-u_n1 / 1.7 + p3, p1 - u_n1 / 1.7 + p3);
    let friction_work = -0.3 * 0.05 * p1 + 0.3 * (-0.4 * reverse / 2.0) * reverse;
    let expected = [total, -0.3 * p1 + 0.3 * reverse, 1.7 * p3, -0.4 * reverse, friction_work];
    let got = [
        outcome.impulse.y,
        outcome.impulse.dot(contact_tangent(DVec2::Y)),
        outcome.normal_velocity_after,
        outcome.tangential_velocity_after,
        outcome.energy_change,
    ];
    for (g, x) in got.iter().zip(expected) {
        assert!((g - x).abs() < 1e-14, "got {got:?}, expected {expected:?}");
    }
    assert!(outcome.slip_reversed && outcome.kind == ImpulseKind::Sliding, "{outcome:?}");
}

#[test]
fn slip_starts_from_rest_when_sticking_is_unstable() {
    // u_t = 0, μ = 0.3 < ½: both laws slide in the direction sign(K_tn) t = −t.
    let contact = coupled_body_on_ground(DVec2::new(0.0, -1.0), 0.5, 0.3);
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        let outcome = resolve_impact(law, &contact).unwrap();
        assert_eq!(outcome.kind, ImpulseKind::Sliding, "{law:?}");
        assert!(outcome.tangential_velocity_after < 0.0, "{law:?}: {outcome:?}");
        let friction = outcome.impulse.dot(contact_tangent(DVec2::Y));
        assert!((friction - 0.3 * outcome.impulse.y).abs() < 1e-15, "{law:?}: friction opposes the slip");
        assert!(outcome.energy_change < 0.0, "{law:?}: {outcome:?}");
    }
    // μ = 0.5 holds it: both stick.
    let contact = ImpactContact { friction: 0.5, ..contact };
    for law in [ImpulseLaw::Seed, ImpulseLaw::EnergySafe] {
        let outcome = resolve_impact(law, &contact).unwrap();
        assert_eq!(outcome.kind, ImpulseKind::Sticking, "{law:?}");
        assert!(outcome.tangential_velocity_after.abs() < 1e-15, "{law:?}: {outcome:?}");
    }
}
