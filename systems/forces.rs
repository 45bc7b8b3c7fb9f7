//! Forces: gravity acts on every free body's velocity over the sub-step, `v += g h`, after the
//! collisions and before the resting contacts are solved (so a resting contact cancels it and
//! the body does not move).

use super::StepContext;

/// Adds `g h` to the velocity of every dynamic body.
pub fn run(ctx: &mut StepContext<'_>) {
    let h = ctx.buffers.substep;
    let gravity = ctx.settings.gravity;
    for (body, state) in ctx.bodies.iter().zip(ctx.buffers.states.iter_mut()) {
        if !body.is_static {
            state.linear_velocity += gravity * h;
        }
    }
}
