//! Collide: the first stage of a sub-step's solve. The impulse law of MODEL §6 (energy-safe by
//! default) acts at every contact approaching faster than the resting threshold
//! `v_rest + 2 |g| h` — a contact at rest approaches at most at `|g| h` after one sub-step of
//! gravity, so twice that separates collisions from resting contacts. It runs on the velocities
//! the bodies arrived with, before this sub-step's gravity, so an elastic bounce returns the
//! arrival speed and gains nothing. Swept in contact order until nothing approaches that fast;
//! after the cap, one inelastic sweep stops what still approaches (Guendelman et al. 2003).
//! It also clears the sub-step's pseudo-velocities and per-body contact flags.

use super::{StepContext, pair_velocities, store_velocities};
use crate::dynamics::impulse::{
    BodyVelocity, ContactMassInput, ImpactContact, ImpulseKind, collision_matrix, resolve_impact,
};
use crate::dynamics::solver::{SolverContact, arms_along};

/// Applies collision impulses; skipped when there is no contact.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    buffers.bias.clear();
    buffers.bias.resize(ctx.bodies.len(), BodyVelocity::ZERO);
    buffers.touched.clear();
    buffers.touched.resize(ctx.bodies.len(), false);
    if buffers.solver_contacts.is_empty() {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    // A resting contact approaches at most at what one sub-step of its bodies' relative
    // acceleration gives (gravity, or a stronger applied force); twice that is a collision.
    let gravity = ctx.settings.gravity.length();
    let threshold = |contact: &crate::dynamics::solver::SolverContact| {
        let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
        let driven = (buffers.accelerations[a].linear - buffers.accelerations[b].linear).length();
        ctx.settings.resting_speed + 2.0 * gravity.max(driven) * buffers.substep
    };
    let states = &mut buffers.states;
    // Whether any contact approaches faster than its threshold (or is not a number): the test
    // of the first sweep, which applies nothing where none does (a still structure's every
    // sub-step), so it is not run.
    let mut approaching = false;
    for contact in &mut buffers.solver_contacts {
        let (va, vb) = pair_velocities(states, contact.key.bodies);
        contact.normal_velocity_before = contact.relative_velocity(va, vb).dot(contact.normal);
        let slow = contact.normal_velocity_before.partial_cmp(&-threshold(contact)).is_some_and(|order| order.is_ge());
        approaching |= !slow;
        contact.collision_impulse = glam::DVec2::ZERO;
        contact.collided = false;
        contact.collision_kind = None;
    }
    let law = ctx.settings.impulse_law;
    let counters = &mut ctx.profile.counters;
    if !approaching {
        // The counts of the sweep that would have found nothing.
        counters.impulse_iterations += 1;
        counters.impulse_cap_hits += u64::from(ctx.settings.max_impulse_iterations == 0);
        return;
    }
    for sweep in 0..=ctx.settings.max_impulse_iterations {
        let inelastic = sweep == ctx.settings.max_impulse_iterations;
        if inelastic {
            counters.impulse_cap_hits += 1;
        }
        counters.impulse_iterations += 1;
        let mut applied = 0;
        let contacts = &mut buffers.solver_contacts;
        let mut k = 0;
        while k < contacts.len() {
            // A flat patch whose two ends both strike collides once, at its centre: the ends
            // struck one after the other would spin the body (a box pushed flat-on by a wall came
            // away turning and faster than the wall; tests/kinematic.rs). A patch landing on one
            // end (a turning body) is struck end by end.
            let patch = contacts[k].patch_with_next
                && k + 1 < contacts.len()
                && contacts[k..k + 2].iter().all(|end| {
                    let (va, vb) = pair_velocities(states, end.key.bodies);
                    end.relative_velocity(va, vb).dot(end.normal) < -threshold(end)
                });
            let outcome = if patch {
                let mut centre = patch_centre(&contacts[k], &contacts[k + 1]);
                let before = centre.collision_impulse;
                let threshold = threshold(&centre);
                let outcome = collide(&mut centre, states, threshold, law, inelastic);
                // Each end records half of the centre's impulse (events and the warm start).
                let share = 0.5 * (centre.collision_impulse - before);
                for end in &mut contacts[k..k + 2] {
                    end.collision_impulse += share;
                    end.collided |= centre.collided;
                    end.collision_kind = centre.collision_kind.or(end.collision_kind);
                }
                outcome
            } else {
                // In place: a contact is large, and most are not struck.
                let threshold = threshold(&contacts[k]);
                collide(&mut contacts[k], states, threshold, law, inelastic)
            };
            match outcome {
                Ok(true) => applied += 1,
                Ok(false) => {}
                Err(()) => counters.impulse_errors += 1,
            }
            k += if patch { 2 } else { 1 };
        }
        if applied == 0 {
            break;
        }
    }
    for contact in &buffers.solver_contacts {
        if contact.collided {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// The contact at the centre of a two-point patch: lever arms and point averaged, the rest of
/// `first` (normal, masses' inverses, friction, restitution); its collision impulse is the sum
/// of both ends' so far.
fn patch_centre(first: &SolverContact, second: &SolverContact) -> SolverContact {
    let (r_a, r_b) = (0.5 * (first.r_a + second.r_a), 0.5 * (first.r_b + second.r_b));
    SolverContact {
        point: 0.5 * (first.point + second.point),
        r_a,
        r_b,
        normal_arms: arms_along(r_a, r_b, first.normal),
        tangent_arms: arms_along(r_a, r_b, first.tangent()),
        collision_impulse: first.collision_impulse + second.collision_impulse,
        collided: first.collided || second.collided,
        ..*first
    }
}

/// One contact of a sweep: `Ok(true)` if an impulse was applied, `Err` if the law failed.
fn collide(
    contact: &mut SolverContact,
    states: &mut [crate::components::RigidState],
    threshold: f64,
    law: crate::dynamics::impulse::ImpulseLaw,
    inelastic: bool,
) -> Result<bool, ()> {
    let (va, vb) = pair_velocities(states, contact.key.bodies);
    let u = contact.relative_velocity(va, vb);
    if u.dot(contact.normal) >= -threshold {
        return Ok(false);
    }
    let input = ContactMassInput {
        inverse_mass_a: contact.inverse[0],
        inverse_inertia_a: contact.inverse[1],
        r_a: contact.r_a,
        inverse_mass_b: contact.inverse[2],
        inverse_inertia_b: contact.inverse[3],
        r_b: contact.r_b,
    };
    let e = if inelastic { 0.0 } else { contact.restitution };
    let impact = ImpactContact {
        matrix: collision_matrix(&input),
        normal: contact.normal,
        velocity: u,
        restitution: e,
        friction: contact.friction,
    };
    let outcome = resolve_impact(law, &impact).map_err(|_| ())?;
    if outcome.kind == ImpulseKind::Separating {
        return Ok(false);
    }
    let (mut va, mut vb) = (va, vb);
    crate::dynamics::solver::apply(contact.inverse, contact.r_a, contact.r_b, outcome.impulse, &mut va, &mut vb);
    store_velocities(states, contact.key.bodies, va, vb);
    contact.collision_impulse += outcome.impulse;
    contact.collided = true;
    contact.collision_kind = Some(outcome.kind);
    Ok(true)
}
