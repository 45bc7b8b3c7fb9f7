//! Contact solver: sequential impulses over the resting contacts (MODEL §7a), warm-started
//! with last sub-step's forces, `iterations` sweeps in order from the ground up. Tall
//! structures are held up by the warm start (the forces converge over the sub-steps) and by
//! the push-out pass's shock propagation (`position_correction.rs`). Where a body rests on one
//! at least ten times lighter, the sweeps cannot converge; the island of such a contact then
//! gets shock propagation here too (Guendelman, Bridson and Fedkiw 2003): level by level from
//! the ground up, each lower body held while the contacts above it are solved.

use super::islands::UNGROUNDED;
use super::{StepContext, contact_island, pair_velocities, store_velocities};
use crate::dynamics::solver::{
    Accumulator, Pass, SHOCK_SWEEPS, SolverContact, apply, for_each_level, for_each_run, sweep,
};

/// Solves the resting contacts; skipped when there is none.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    if buffers.solver_contacts.is_empty() {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let h = buffers.substep;
    let states = &mut buffers.states;
    for contact in &mut buffers.solver_contacts {
        warm_start(contact, states, h);
    }
    let settings = &ctx.settings.solver;
    // Island by island (no dynamic body is in two, so the order between them changes nothing),
    // sweep until converged: the last sweep's largest change would move no contact by more than
    // `tolerance` of its band over the sub-step — and never fewer sweeps than the island has
    // levels. A sweep passes a change of load one level down (the contacts run from the ground
    // up), so until then a change at the top has not reached the ground; the small changes a
    // still structure sees at every sub-step stay below the tolerance, and left unresolved they
    // let a tall stack bend a little more each sub-step (a stack of 20 boxes tilted
    // exponentially with one sweep per sub-step: tests/resting.rs). An island that converges
    // stops there, whatever the others still need.
    let (mut most_sweeps, mut unconverged) = (0, 0);
    for_each_run(
        &mut buffers.solver_contacts,
        |c| c.island,
        |island| {
            let grounded = island.iter().map(|c| c.level).filter(|&level| level != UNGROUNDED);
            let min_sweeps = grounded.max().map_or(1, |level| level + 1).min(settings.iterations);
            let mut converged = false;
            let mut sweeps = 0;
            while sweeps < settings.iterations {
                let change = sweep(island, states.as_mut_slice(), Accumulator::Velocity, Pass::Relax);
                sweeps += 1;
                if change * h <= settings.tolerance && sweeps >= min_sweeps {
                    converged = true;
                    break;
                }
            }
            most_sweeps = most_sweeps.max(sweeps);
            unconverged += u64::from(!converged);
        },
    );
    ctx.profile.counters.solver_iterations += u64::from(most_sweeps);
    ctx.profile.counters.solver_unconverged += u64::from(unconverged > 0);
    if settings.shock_propagation && buffers.solver_contacts.iter().any(|c| c.heavy_on_light) {
        mark_shock_islands(ctx.bodies, &buffers.island_of, &mut buffers.shock_islands, &mut buffers.solver_contacts);
        heavy_on_light_shock(&mut buffers.solver_contacts, states);
        ctx.profile.counters.solver_iterations += u64::from(SHOCK_SWEEPS);
    }
    for contact in &buffers.solver_contacts {
        if contact.normal_impulse > 0.0 {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// Applies last sub-step's forces over this sub-step (`F h`); a contact that just collided
/// starts from zero.
fn warm_start(contact: &mut SolverContact, states: &mut [crate::components::RigidState], h: f64) {
    let (normal, tangent) = if contact.collided { (0.0, 0.0) } else { (contact.warm.0 * h, contact.warm.1 * h) };
    let limit = contact.friction * normal;
    contact.normal_impulse = normal.max(0.0);
    contact.tangent_impulse = tangent.clamp(-limit, limit);
    if contact.normal_impulse == 0.0 {
        return;
    }
    let (mut va, mut vb) = pair_velocities(states, contact.key.bodies);
    let j = contact.normal * contact.normal_impulse + contact.tangent() * contact.tangent_impulse;
    apply(contact.inverse, contact.r_a, contact.r_b, j, &mut va, &mut vb);
    store_velocities(states, contact.key.bodies, va, vb);
}

/// Marks for the velocity shock pass every contact of an island that has a heavy-on-light
/// contact: the light body must itself be held by what is below it.
fn mark_shock_islands(
    bodies: &[super::BodyRecord],
    island_of: &[u32],
    flags: &mut Vec<bool>,
    contacts: &mut [SolverContact],
) {
    let island = |c: &SolverContact| contact_island(bodies, island_of, c.key.bodies);
    flags.clear();
    flags.resize(bodies.len(), false);
    for contact in contacts.iter().filter(|c| c.heavy_on_light) {
        flags[island(contact)] = true;
    }
    for contact in contacts.iter_mut() {
        contact.velocity_shock = flags[island(contact)];
    }
}

/// Shock propagation over the islands with a heavy-on-light contact, level by level
/// ([`SHOCK_SWEEPS`] sweeps each, the lower body held). Their impulses are kept for the warm
/// start: they carry the heavy body's weight, which the light body passes on to its support.
fn heavy_on_light_shock(contacts: &mut [SolverContact], states: &mut [crate::components::RigidState]) {
    for_each_level(contacts, |level| {
        for _ in 0..SHOCK_SWEEPS {
            sweep(level, states, Accumulator::Velocity, Pass::Shock);
        }
    });
}
