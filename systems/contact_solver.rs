//! Contact solver: sequential impulses over the resting contacts (MODEL §7a), warm-started
//! with last sub-step's forces, in order from the ground up; then one shock-propagation sweep
//! in the same order in which the lower body of each contact is held (Guendelman, Bridson and
//! Fedkiw 2003), so the levels above cannot push it down and tall stacks stand.

use super::{StepContext, pair_velocities, store_velocities};
use crate::dynamics::solver::{Pass, SolverContact, apply, solve_contact, solve_patch};

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
    for _ in 0..settings.iterations {
        sweep(&mut buffers.solver_contacts, states, Pass::Relax);
    }
    ctx.profile.counters.solver_iterations += u64::from(settings.iterations);
    if settings.shock_propagation {
        sweep(&mut buffers.solver_contacts, states, Pass::Shock);
        ctx.profile.counters.solver_iterations += 1;
    }
    for contact in &buffers.solver_contacts {
        if contact.normal_impulse > 0.0 {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// Applies last sub-step's impulses, scaled to this sub-step (forces × h); a contact that just
/// collided starts from zero.
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

/// One sweep over the contacts in order; a patch's two ends are solved together.
fn sweep(contacts: &mut [SolverContact], states: &mut [crate::components::RigidState], pass: Pass) {
    let mut k = 0;
    while k < contacts.len() {
        let bodies = contacts[k].key.bodies;
        let (mut va, mut vb) = pair_velocities(states, bodies);
        if contacts[k].patch_with_next {
            let (first, rest) = contacts[k..].split_at_mut(1);
            solve_patch(&mut first[0], &mut rest[0], &mut va, &mut vb, pass);
            k += 2;
        } else {
            solve_contact(&mut contacts[k], &mut va, &mut vb, pass);
            k += 1;
        }
        store_velocities(states, bodies, va, vb);
    }
}
