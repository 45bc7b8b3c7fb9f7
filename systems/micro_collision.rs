//! Micro-collision: every resting contact inside the band gets the impulse of a collision at
//! `u_n = −√(2gδ)` with restitution `e_c(δ)` (MODEL §7); then collisions are swept again
//! until no contact approaches.

use super::StepContext;
use super::contacts::{Treatment, with_resolver};

/// Applies micro-collisions; skipped when no pair has a contact.
pub fn run(ctx: &mut StepContext<'_>) {
    with_resolver(ctx, |resolver, slots| {
        if resolver.sweep(slots, Treatment::Micro) > 0 {
            resolver.collide_until_separating(slots);
        }
    });
}
