//! Position correction: split impulses on pseudo-velocities that move positions in this
//! sub-step and are then discarded, so removing position error never adds kinetic energy
//! (MODEL §7a). A contact deeper in its band than the rest depth is pushed out at the seed's
//! micro-collision speed for the excess depth scaled by `e_c(δ)` (`push_out_speed`), which is
//! how the seed's contact restitution lives in the solver: the deeper, the harder — but a body
//! resting at a steady depth gets no kick. Crossing curves (overlap recovery) come apart the
//! same way.

use super::StepContext;
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::laws::push_out_speed;
use crate::dynamics::solver::{Pass, SHOCK_SWEEPS, SolverContact, for_each_level, solve_bias, solve_bias_patch};

/// Solves the split impulses; skipped when no contact is too deep.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    if !buffers.solver_contacts.iter().any(|c| c.excess_depth > 0.0) {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let h = buffers.substep;
    let gravity = ctx.settings.gravity.length();
    let beta = ctx.settings.solver.position_correction;
    for contact in &mut buffers.solver_contacts {
        contact.bias_speed = push_out_speed(contact.push_restitution, contact.excess_depth, gravity, beta, h);
        contact.bias_impulse = 0.0;
        contact.bias_tangent_impulse = 0.0;
    }
    let bias = &mut buffers.bias;
    let contacts = &mut buffers.solver_contacts;
    for _ in 0..ctx.settings.solver.position_iterations {
        sweep(contacts, bias, Pass::Relax);
    }
    // Shock propagation of the push-out: level by level with the lower body held, so a level
    // pushed out carries the levels above instead of being held down by them.
    if ctx.settings.solver.shock_propagation {
        for_each_level(contacts, |level| {
            for _ in 0..SHOCK_SWEEPS {
                sweep(level, bias, Pass::Shock);
            }
        });
        ctx.profile.counters.solver_iterations += u64::from(SHOCK_SWEEPS);
    }
    ctx.profile.counters.solver_iterations += u64::from(ctx.settings.solver.position_iterations);
    for contact in &buffers.solver_contacts {
        if contact.bias_impulse > 0.0 {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// One sweep of split impulses over the contacts in order; a patch's two ends together.
fn sweep(contacts: &mut [SolverContact], bias: &mut [BodyVelocity], pass: Pass) {
    let mut k = 0;
    while k < contacts.len() {
        let (a, b) = (contacts[k].key.bodies.0 as usize, contacts[k].key.bodies.1 as usize);
        let (mut va, mut vb) = (bias[a], bias[b]);
        if contacts[k].patch_with_next {
            let (first, rest) = contacts[k..].split_at_mut(1);
            solve_bias_patch(&mut first[0], &mut rest[0], &mut va, &mut vb, pass);
            k += 2;
        } else {
            solve_bias(&mut contacts[k], &mut va, &mut vb, pass);
            k += 1;
        }
        (bias[a], bias[b]) = (va, vb);
    }
}
