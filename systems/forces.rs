//! Forces: gravity (times the body's scale) and the user's applied force and torque act on every
//! free body's velocity over the sub-step, `v += a h`, `ω += α h`, then damping,
//! `v ← v / (1 + c h)` (Box2D's); after the collisions and before the resting contacts are
//! solved (so a resting contact cancels them and the body does not move). It first keeps every
//! body's velocity as the sub-step's continuous part begins (after the collisions): the
//! integrator moves bodies at the mean of that velocity and the solved one.

use super::StepContext;
use crate::dynamics::impulse::BodyVelocity;

/// Records the start velocities, then accelerates and damps every dynamic body.
pub fn run(ctx: &mut StepContext<'_>) {
    let h = ctx.buffers.substep;
    let buffers = &mut *ctx.buffers;
    buffers.start_velocities.clear();
    for ((body, state), acceleration) in ctx.bodies.iter().zip(buffers.states.iter_mut()).zip(&buffers.accelerations) {
        buffers.start_velocities.push(BodyVelocity { linear: state.linear_velocity, angular: state.angular_velocity });
        if !body.is_static {
            state.linear_velocity += acceleration.linear * h;
            state.angular_velocity += acceleration.angular * h;
            damp(state, &body.motion, h);
        }
    }
}

/// Box2D's damping over a sub-step: `v ← v / (1 + c h)` (never reverses a velocity).
pub(crate) fn damp(state: &mut crate::components::RigidState, motion: &crate::components::Motion, h: f64) {
    if motion.linear_damping > 0.0 {
        state.linear_velocity /= 1.0 + motion.linear_damping * h;
    }
    if motion.angular_damping > 0.0 {
        state.angular_velocity /= 1.0 + motion.angular_damping * h;
    }
}
