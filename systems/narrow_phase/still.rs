//! The narrow phase of a still structure (docs/model.md §3b): where the pairs are the last
//! phase's, every body has barely moved since, and that phase carried every pair and recorded
//! its budget of drift, each pair is carried again by comparing its grown drift with its
//! budget, and the closing speed of the fastest bodies with its margin; nothing else about a
//! pair changes. Where any pair's budget does not cover it, the pass over the slots decides
//! every pair one by one. A budget is a sufficient condition for the same decision the pass
//! would take (checked in debug builds), so the results are the pass's to the bit.

use super::carry::{Carry, apart_limit};
use super::{PairJob, Pass, Tally, least};
use crate::systems::{Drift, PairSlot};

/// Room for rounding, relative to the threshold, of a budget's bound on the motion at which a
/// pair's contacts are evaluated again ([`PairJob::stale_limit`]).
const STALE_ROUNDING: f64 = 1e-6;

/// Room for rounding of the closing bound over every pair at once (`systems::fastest`), relative
/// to it: the pass's bound of each pair is never larger.
pub(super) const COVER_ROUNDING: f64 = 1e-9;

/// The largest drift gap at which `slot`, carried in this phase with its bodies barely moved,
/// is carried again as it is (`PairSlot::drift_budget`): the carry's own bound (half the
/// clearance, a quarter of the query margin) and, for a pair in contact, each contact's reuse
/// bound, the crossing check from its record ([`Carry::crossing_limit`]) and the motion at which
/// its contacts are evaluated again ([`PairJob::stale_limit`]). The closing speed over the
/// horizon is checked at each phase for every pair at once. `None` for a pair not carried, or
/// whose budget is spent (NaN refuses).
pub(super) fn budget(carry: &Carry<'_>, job: &PairJob<'_>, slot: &PairSlot) -> Option<f64> {
    let solved_at = slot.solved_at.filter(|_| slot.carried)?;
    let manifold = slot.manifold();
    let mut limit = apart_limit(manifold.clearance(), solved_at.margin);
    if !manifold.contacts.is_empty() {
        let reuse =
            manifold.contacts.iter().map(|found| carry.reuse * (found.contact.lambda_a + found.contact.lambda_b));
        limit = reuse.fold(limit, least);
        limit = least(limit, carry.crossing_limit(slot)?);
        limit = least(limit, job.stale_limit(slot)?);
    }
    (slot.drift.gap <= limit).then_some(limit)
}

impl PairJob<'_> {
    /// The largest drift gap at which the contacts of `slot` (carried, in contact) are still
    /// not evaluated again ([`PairJob::unmoved`]), `None` where they were never evaluated again
    /// (a reuse evaluates them first): the motion since they were grows by at most the drift
    /// gap's growth.
    fn stale_limit(&self, slot: &PairSlot) -> Option<f64> {
        let then = slot.reused_at?;
        let threshold = self.stale_motion(slot);
        let spare = threshold - self.moved_since(slot, then, self.states_now(slot));
        Some(slot.drift.gap + spare - STALE_ROUNDING * threshold)
    }
}

impl Pass<'_> {
    /// Carries every pair of `slots` (the last phase's, every one with a budget, in a phase
    /// where every body is still and no contact hook is set) by its budget, and counts them;
    /// `None`, nothing changed, where some pair's grown drift passes its budget or the bodies'
    /// closing over the horizon, `cover` (with room for rounding), does not fit in its margin.
    pub(super) fn carry_all(&self, slots: &mut [PairSlot], cover: f64) -> Option<Tally> {
        let moved = self.carry.moved;
        // As `Carry::drift` grows a still pair's drift.
        let grown = |slot: &PairSlot| {
            let (last, moved_a, moved_b) = (slot.drift, moved[slot.bodies.0 as usize], moved[slot.bodies.1 as usize]);
            Drift { a: last.a + moved_a, b: last.b + moved_b, gap: last.gap + moved_a + moved_b }
        };
        let covered = slots.iter().all(|slot| {
            let gap = grown(slot).gap;
            slot.drift_budget.is_some_and(|limit| gap <= limit)
                && slot.solved_at.is_some_and(|solved_at| cover <= solved_at.margin - gap)
        });
        if !covered {
            return None;
        }
        #[cfg(debug_assertions)]
        self.check_budgets(slots, grown);
        let mut tally = Tally::default();
        for slot in slots {
            slot.drift = grown(slot);
            tally.add(slot, Some(slot.bounding_gap()));
        }
        Some(tally)
    }

    /// Debug builds: every pair a budget carries is carried by the pass over the slots, with the
    /// same drift and crossing record, and its contacts are not evaluated again.
    #[cfg(debug_assertions)]
    fn check_budgets(&self, slots: &[PairSlot], grown: impl Fn(&PairSlot) -> Drift) {
        let bodies = self.carry.bodies;
        for slot in slots {
            let sensor = bodies[slot.bodies.0 as usize].sensor || bodies[slot.bodies.1 as usize].sensor;
            let carried = self.carry.drift(slot.bodies, sensor, slot);
            assert!(
                carried.is_some_and(|carried| carried.drift == grown(slot) && carried.crossing == slot.crossing),
                "pair {:?}: its budget carries it where the pass would not, or otherwise",
                slot.bodies
            );
            let now = self.job.states_now(slot);
            assert!(
                slot.manifold().contacts.is_empty()
                    || slot.reused_at.is_some_and(|then| self.job.unmoved(slot, then, now)),
                "pair {:?}: its budget keeps contacts the pass would evaluate again",
                slot.bodies
            );
        }
    }
}
