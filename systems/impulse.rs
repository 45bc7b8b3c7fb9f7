//! Impulse: collision impulses (MODEL §6) at every approaching contact, swept in pair order
//! until no contact approaches or the iteration cap is hit.

use super::StepContext;
use super::contacts::with_resolver;

/// Resolves approaching contacts of the live pairs; skipped when no pair has a contact.
pub fn run(ctx: &mut StepContext<'_>) {
    with_resolver(ctx, |resolver, slots| resolver.collide_until_separating(slots));
}
