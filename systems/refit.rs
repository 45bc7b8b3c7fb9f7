//! Refit: places every body's bounding octagon in the world and sweeps its bounds by the body's
//! motion margin.

use glam::DVec2;

use super::{StepContext, margin_horizon, motion_bound};
use crate::components::RigidState;

/// Margins cover this many nominal steps of motion, so velocity changes from impulses rarely
/// force a shorter sub-step.
const MARGIN_FACTOR: f64 = 2.0;

/// Computes `poses`, `swept_bounds` and `margins` for every body at the current states (the
/// narrow phase, which follows at the same states, reads the poses).
pub fn run(ctx: &mut StepContext<'_>) {
    let horizon = margin_horizon(ctx.settings, ctx.buffers.substep);
    let buffers = &mut *ctx.buffers;
    buffers.swept_bounds.clear();
    buffers.margins.clear();
    buffers.poses.clear();
    buffers.poses.extend(buffers.states.iter().map(RigidState::pose));
    let placed =
        ctx.bodies.iter().zip(ctx.octagons).zip(&buffers.states).zip(&buffers.accelerations).zip(&buffers.poses);
    for ((((body, octagon), state), acceleration), pose) in placed {
        let margin = MARGIN_FACTOR * motion_bound(body, state, acceleration.bound(body), horizon);
        let (low, high) = octagon.world_bounds(pose);
        buffers.swept_bounds.push((low - DVec2::splat(margin), high + DVec2::splat(margin)));
        buffers.margins.push(margin);
    }
}
