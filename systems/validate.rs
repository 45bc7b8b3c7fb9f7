//! Debug invariants of the step (as Box2D's `b2Validate*`): not a system of the tables, but the
//! check `run_table` makes after every system when debug assertions are on. Every body state is
//! finite; every swept box is finite and ordered and every margin finite and ≥ 0; every live
//! contact has a finite point and penetration and a unit normal; every separate leaf pair's gap
//! is a number; every pair's kept solver touches are its manifold's reduction, and islands and
//! levels kept from before are those of the colliding pairs; every prepared solver contact is
//! the one built afresh from its touch; every solver contact's impulses are finite, the normal
//! one ≥ 0. A violation panics naming the stage and the body or pair, so a test finds the stage
//! that broke it. The release build has no such checks: there, bad input is refused at the
//! door with a typed error and what goes wrong inside a step is counted (`StepCounters`). The
//! trees are checked when a body is built (`AobbTree::validate`): nothing in a step changes
//! them.

use super::StepContext;
use super::islands::find_islands;
use super::prepare_contacts::{OrderKey, OrderScratch, Touch, afresh, reduced_touches};
use crate::dynamics::solver::SolverContact;
use crate::profile::Stage;

/// What the checks work in, kept in the step's buffers so that they allocate nothing once grown
/// (in thread-locals it grew again on whichever pool thread ran the step next, which
/// tests/allocation.rs counted in one run in about nine).
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    /// A slot's touches, reduced again.
    touches: Vec<Touch>,
    /// The colliding pairs, and the islands and levels found from them.
    pairs: Vec<(u32, u32)>,
    island_of: Vec<u32>,
    levels: Vec<u32>,
    /// The solver contacts built afresh, and what building them works in.
    contacts: Vec<SolverContact>,
    keys: Vec<OrderKey>,
    order: OrderScratch,
    loads: Vec<f64>,
    supports: Vec<u32>,
}

/// Checks the step's invariants after `stage`; panics on a violation.
pub(crate) fn after(ctx: &mut StepContext<'_>, stage: Stage) {
    let mut scratch = std::mem::take(&mut ctx.buffers.validation);
    check(ctx, stage, &mut scratch);
    ctx.buffers.validation = scratch;
}

fn check(ctx: &StepContext<'_>, stage: Stage, scratch: &mut Scratch) {
    let buffers = &*ctx.buffers;
    let name = stage.name();
    for (i, state) in buffers.states.iter().enumerate() {
        assert!(state.is_finite(), "after {name}: body slot {i} has a non-finite state {state:?}");
    }
    for (i, (low, high)) in buffers.swept_bounds.iter().enumerate() {
        let ordered = low.is_finite() && high.is_finite() && low.cmple(*high).all();
        assert!(ordered, "after {name}: body slot {i} has the swept box {low:?}..{high:?}");
    }
    for (i, margin) in buffers.margins.iter().enumerate() {
        assert!(margin.is_finite() && *margin >= 0.0, "after {name}: body slot {i} has the margin {margin}");
    }
    // Between the broad and the narrow phase the slots are last phase's: check what there is.
    for slot in buffers.pair_slots.iter().take(buffers.candidate_pairs.len()) {
        let manifold = slot.manifold();
        for contact in &manifold.contacts {
            let c = &contact.contact;
            let sound = c.point.is_finite() && c.penetration.is_finite() && (c.normal.length() - 1.0).abs() < 1e-9;
            assert!(sound, "after {name}: pair {:?} has the contact {contact:?}", slot.bodies);
        }
        for gap in &manifold.gaps {
            assert!(!gap.gap.is_nan(), "after {name}: pair {:?} has a leaf gap that is not a number", slot.bodies);
            // Its approach lies within its band (unknown, NaN, only from an older snapshot).
            let within = gap.approach >= 0.0 && (gap.band.is_nan() || gap.approach <= gap.band);
            assert!(within, "after {name}: pair {:?} has a leaf gap beyond its band: {gap:?}", slot.bodies);
        }
    }
    // A slot's kept touches are its manifold's reduction.
    let (store, generation) = &buffers.touch_store;
    for slot in buffers.pair_slots.iter().take(buffers.candidate_pairs.len()) {
        let Some(kept) = slot.touches.filter(|kept| kept.generation == *generation) else { continue };
        scratch.touches.clear();
        reduced_touches(slot, ctx.settings.min_band, &mut scratch.touches);
        let stored = &store[kept.start as usize..(kept.start + kept.len) as usize];
        assert!(scratch.touches == stored, "after {name}: pair {:?} kept touches of another manifold", slot.bodies);
    }
    // Islands kept from an earlier sub-step are those of the colliding pairs now.
    if stage == Stage::Islands {
        let Scratch { pairs, island_of, levels, .. } = scratch;
        let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
        pairs.clear();
        pairs.extend(live.iter().filter(|slot| slot.colliding()).map(|slot| slot.bodies));
        let count = find_islands(ctx.bodies, pairs, island_of, levels);
        let same = (island_of == &buffers.island_of, levels == &buffers.levels, count == buffers.island_inputs.2);
        assert!(same == (true, true, true), "after {name}: islands, levels, count kept stale: {same:?}");
    }
    // The prepared contacts, refreshed where they lie or built, are those built afresh from the
    // touches (the contact hook's values aside).
    if stage == Stage::PrepareContacts && ctx.contact_hook.is_none() {
        let Scratch { contacts, keys, order, loads, supports, .. } = scratch;
        afresh(ctx, (contacts, keys, order), (loads, supports));
        if let Some((k, (prepared, built))) =
            buffers.solver_contacts.iter().zip(contacts.iter()).enumerate().find(|(_, (p, b))| p != b)
        {
            panic!("after {name}: solver contact {k} was prepared as {prepared:?}, built afresh as {built:?}");
        }
        assert_eq!(buffers.solver_contacts.len(), contacts.len(), "after {name}: solver contacts lost or added");
    }
    for contact in &buffers.solver_contacts {
        let sound =
            contact.normal_impulse.is_finite() && contact.normal_impulse >= 0.0 && contact.tangent_impulse.is_finite();
        assert!(
            sound,
            "after {name}: solver contact {:?} has impulses {}, {}",
            contact.key, contact.normal_impulse, contact.tangent_impulse
        );
    }
}
