//! Contact solver: sequential impulses over the resting contacts (MODEL §7a), warm-started
//! with last sub-step's forces, island by island (in parallel), each swept from the ground up
//! until it converges. Tall
//! structures are held up by the warm start (the forces converge over the sub-steps) and by
//! the push-out pass's shock propagation (`position_correction.rs`). Where a body rests on one
//! at least ten times lighter, the sweeps cannot converge; the island of such a contact then
//! gets shock propagation here too (Guendelman, Bridson and Fedkiw 2003): level by level from
//! the ground up, each lower body held while the contacts above it are solved.

use super::island_solve::{Lanes, Sweeps, solve_islands, wavefront_island};
use super::{
    SolverIsland, StepContext, body_velocity, contact_island, pair_velocities, store_velocities, store_velocity,
};
use crate::dynamics::solver::{Accumulator, Pass, SHOCK_SWEEPS, SolverContact, apply, for_each_level, sweep};

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
    // Island by island, in parallel (no dynamic body is in two islands, so what one island's
    // solve does cannot reach another's): each island's solve reads and writes only its own
    // copy of its bodies' velocities, gathered here and applied back after, so the results are
    // the same bit for bit for any thread count.
    gather_islands(ctx.bodies, buffers);
    let parallel = ctx.pool.is_some();
    let islands = &buffers.solver_islands;
    // The subspace solves' scratch: a row per normal and friction, a velocity per body.
    let (contact_count, body_count) = (buffers.solver_contacts.len(), buffers.island_velocities.len());
    let scratch = (settings.subspace_iterations > 0)
        .then(|| buffers.subspace_scratch.scratch(contact_count, body_count).helped(parallel));
    let (contacts, velocities) = (&mut buffers.solver_contacts, &mut buffers.island_velocities);
    // With two threads, the largest island's sweeps may be shared between them as a wavefront.
    let wavefront = if parallel { wavefront_island(islands, contacts, &mut buffers.island_runs) } else { None };
    ctx.profile.counters.wavefront_solves += u64::from(wavefront.is_some());
    let lanes = Lanes { contacts, velocities, wavefront, scratch };
    let outcome = solve_islands(lanes, islands, Sweeps::Resting(settings, h), parallel);
    // Back to the states: each moving body from its one island (static and kinematic bodies,
    // which several islands may read, are not moved by contacts).
    for (&slot, velocity) in buffers.island_slots.iter().zip(&buffers.island_velocities) {
        if !ctx.bodies[slot as usize].is_static {
            store_velocity(&mut buffers.states[slot as usize], *velocity);
        }
    }
    ctx.profile.counters.solver_iterations += u64::from(outcome.most_sweeps);
    ctx.profile.counters.solver_unconverged += u64::from(outcome.unconverged > 0);
    ctx.profile.counters.subspace_iterations += outcome.subspace_iterations;
    ctx.profile.counters.subspace_holds += outcome.subspace_holds;
    ctx.profile.counters.subspace_halves += outcome.subspace_halves;
    ctx.profile.counters.wavefront_shared_sweeps += outcome.wavefront_shared_sweeps;
    let states = &mut buffers.states;
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

/// Sorts out the islands of `solver_contacts` (ordered island by island): each one's contact
/// range, its bodies' velocities copied into `island_velocities` (with their slots in
/// `island_slots`) and each contact's `local` indices among them.
fn gather_islands(bodies: &[super::BodyRecord], buffers: &mut super::StepBuffers) {
    let (contacts, islands) = (&mut buffers.solver_contacts, &mut buffers.solver_islands);
    let (velocities, slots, index) =
        (&mut buffers.island_velocities, &mut buffers.island_slots, &mut buffers.island_index);
    islands.clear();
    velocities.clear();
    slots.clear();
    index.resize(bodies.len(), u32::MAX);
    let mut start = 0;
    while start < contacts.len() {
        let island = contacts[start].island;
        let end = start + contacts[start..].iter().take_while(|c| c.island == island).count();
        let first_body = velocities.len();
        for contact in &mut contacts[start..end] {
            let (a, b) = contact.key.bodies;
            let mut local = |slot: u32| {
                if index[slot as usize] == u32::MAX {
                    index[slot as usize] = (velocities.len() - first_body) as u32;
                    velocities.push(body_velocity(&buffers.states[slot as usize]));
                    slots.push(slot);
                }
                index[slot as usize]
            };
            contact.local = (local(a), local(b));
        }
        for &slot in &slots[first_body..] {
            index[slot as usize] = u32::MAX;
        }
        islands.push(SolverIsland { contacts: (start, end), bodies: (first_body, velocities.len()) });
        start = end;
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
