//! Contact solver: sequential impulses over the resting contacts (MODEL §7a), warm-started
//! with last sub-step's forces, in order from the ground up; then shock propagation
//! (Guendelman, Bridson and Fedkiw 2003): level by level from the ground up, a few sweeps over
//! the contacts of that level with their lower body held, so the levels above cannot push it
//! down and tall stacks stand. The shock pass changes velocities only: the impulses kept for
//! the warm start and the events are the relaxation's, which act on both bodies alike (the
//! shock pass's do not, and warm-starting from them would push the lower body down).

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
        shock_propagation(&mut buffers.solver_contacts, states);
        ctx.profile.counters.solver_iterations += u64::from(SHOCK_SWEEPS);
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

/// Sweeps over the contacts of one level in the shock pass: a body resting on two others (a
/// pyramid) needs its two contacts to agree, which one sweep in a fixed order does not give.
const SHOCK_SWEEPS: u32 = 4;

/// Shock propagation over contacts sorted by level: each level's contacts swept
/// [`SHOCK_SWEEPS`] times with the lower body held; the relaxation's impulses are restored after.
fn shock_propagation(contacts: &mut [SolverContact], states: &mut [crate::components::RigidState]) {
    for contact in contacts.iter_mut() {
        contact.relaxed_impulse = (contact.normal_impulse, contact.tangent_impulse);
    }
    let mut start = 0;
    while start < contacts.len() {
        let level = contacts[start].level;
        let end = start + contacts[start..].iter().take_while(|c| c.level == level).count();
        for _ in 0..SHOCK_SWEEPS {
            sweep(&mut contacts[start..end], states, Pass::Shock);
        }
        start = end;
    }
    for contact in contacts.iter_mut() {
        (contact.normal_impulse, contact.tangent_impulse) = contact.relaxed_impulse;
    }
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
