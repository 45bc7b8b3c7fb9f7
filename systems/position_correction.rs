//! Position correction: split impulses on pseudo-velocities that move positions in this
//! sub-step and are then discarded, so removing position error never adds kinetic energy
//! (MODEL §7a). A contact deeper in its band than the rest depth is pushed out at the seed's
//! micro-collision speed for the excess depth scaled by `e_c(δ)` (`push_out_speed`), which is
//! how the seed's contact restitution lives in the solver: the deeper, the harder — but a body
//! resting at a steady depth gets no kick. A contact that collided in the sub-step and separates
//! is pushed only by what its separation leaves (`excess_left`), and one whose separation
//! carries it past the rest depth gets a negative target (`push_out_target`): a bounce is lifted
//! neither by its own push nor by a push of the body it bounces off.
//! Crossing curves (overlap recovery) come apart the same way.

use super::island_solve::{Lanes, Outcome, Sweeps, solve_islands, wavefront_island};
use super::{StepContext, body_velocity};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::laws::{excess_left, push_out_target};
use crate::dynamics::solver::{Accumulator, Pass, SHOCK_SWEEPS, SolverContact, for_each_level, sweep};

/// Solves the split impulses; skipped when no contact is left deeper than the rest depth by
/// more than `position_tolerance` of its band (after what a bounce's separation carries it out,
/// `excess_left`): pushing that out would move no contact by more than the push-out's sweeps
/// leave once converged.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let tolerance = ctx.settings.solver.position_tolerance;
    let h = buffers.substep;
    // What each contact still has to be pushed out of: a contact that collided and separates
    // (on the solved velocities) carries itself out by its separation over the sub-step.
    let states = &buffers.states;
    let collided = |contact: &SolverContact| {
        let velocity = |slot: u32| body_velocity(&states[slot as usize]);
        let (a, b) = contact.key.bodies;
        let separating = || contact.relative_velocity(velocity(a), velocity(b)).dot(contact.normal);
        contact.collided.then(separating)
    };
    if !buffers.solver_contacts.iter().any(|c| excess_left(c.excess_depth, collided(c), h) > tolerance * c.band) {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let gravity = ctx.settings.gravity.length();
    let beta = ctx.settings.solver.position_correction;
    for contact in &mut buffers.solver_contacts {
        let collided = collided(contact);
        contact.bias_speed =
            push_out_target(contact.push_restitution, contact.excess_depth, collided, gravity, beta, h);
        contact.bias_impulse = 0.0;
        contact.bias_tangent_impulse = 0.0;
    }
    // Island by island, in parallel (the contact solver's islands, gathered this sub-step), the
    // largest shared by two threads as a wavefront: each island's sweeps read and write only its
    // own copy of its bodies' pseudo-velocities, which start at rest, so the results are those of
    // sweeping every contact in turn, the same bit for bit for any thread count.
    let mut push_out = Outcome::default();
    if ctx.settings.solver.position_iterations > 0 {
        let parallel = ctx.pool.is_some();
        let (islands, contacts) = (&buffers.solver_islands, &mut buffers.solver_contacts);
        debug_assert!(
            islands.last().map_or(0, |island| island.contacts.1) == contacts.len()
                && islands.last().map_or(0, |island| island.bodies.1) == buffers.island_slots.len(),
            "the contact solver gathered this sub-step's islands"
        );
        let velocities = &mut buffers.island_velocities;
        velocities.fill(BodyVelocity::ZERO);
        let wavefront = if parallel { wavefront_island(islands, contacts, &mut buffers.island_runs) } else { None };
        let lanes = Lanes { contacts, velocities, wavefront, scratch: None };
        push_out = solve_islands(lanes, islands, Sweeps::PushOut(&ctx.settings.solver, h), parallel);
        for (&slot, velocity) in buffers.island_slots.iter().zip(&buffers.island_velocities) {
            if !ctx.bodies[slot as usize].is_static {
                buffers.bias[slot as usize] = *velocity;
            }
        }
    }
    let bias = &mut buffers.bias;
    let contacts = &mut buffers.solver_contacts;
    // Shock propagation of the push-out: level by level with the lower body held, so a level
    // pushed out carries the levels above instead of being held down by them.
    if ctx.settings.solver.shock_propagation {
        for_each_level(contacts, |level| {
            for _ in 0..SHOCK_SWEEPS {
                sweep(level, bias.as_mut_slice(), Accumulator::Split, Pass::Shock);
            }
        });
        ctx.profile.counters.solver_iterations += u64::from(SHOCK_SWEEPS);
    }
    ctx.profile.counters.solver_iterations += u64::from(push_out.most_sweeps);
    ctx.profile.counters.push_out_unconverged += u64::from(push_out.unconverged > 0);
    ctx.profile.counters.push_out_sweeps += u64::from(push_out.most_sweeps);
    for contact in &buffers.solver_contacts {
        if contact.bias_impulse > 0.0 {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}
