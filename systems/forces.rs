//! Forces: gravity acts on every free body's velocity over the sub-step, `v += g h`, after the
//! collisions and before the resting contacts are solved (so a resting contact cancels it and
//! the body does not move). It first keeps every body's velocity as the sub-step's continuous
//! part begins (after the collisions): the integrator moves bodies at the mean of that velocity
//! and the solved one.

use super::StepContext;
use crate::dynamics::impulse::BodyVelocity;

/// Records the start velocities, then adds `g h` to the velocity of every dynamic body.
pub fn run(ctx: &mut StepContext<'_>) {
    let h = ctx.buffers.substep;
    let gravity = ctx.settings.gravity;
    let buffers = &mut *ctx.buffers;
    buffers.start_velocities.clear();
    for (body, state) in ctx.bodies.iter().zip(buffers.states.iter_mut()) {
        buffers.start_velocities.push(BodyVelocity { linear: state.linear_velocity, angular: state.angular_velocity });
        if !body.is_static {
            state.linear_velocity += gravity * h;
        }
    }
}
