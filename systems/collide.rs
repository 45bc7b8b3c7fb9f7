//! Collide: the first stage of a sub-step's solve. The impulse law of MODEL §6 (energy-safe by
//! default) acts at every contact approaching faster than the resting threshold
//! `v_rest + 2 |g| h` — a contact at rest approaches at most at `|g| h` after one sub-step of
//! gravity, so twice that separates collisions from resting contacts. It runs on the velocities
//! the bodies arrived with, before this sub-step's gravity, so an elastic bounce returns the
//! arrival speed and gains nothing. Swept in contact order until nothing approaches that fast;
//! after the cap, one inelastic sweep stops what still approaches (Guendelman et al. 2003).
//! A sweep after the first tests again only the contacts a body of which an impulse has moved
//! since their last test ([`SweepMarks`]): the others would find what they found then.
//! It also clears the sub-step's pseudo-velocities and per-body contact flags.

use super::{StepContext, pair_velocities, store_velocities};
use crate::dynamics::impulse::{
    BodyVelocity, ContactMassInput, ImpactContact, ImpulseKind, collision_matrix, resolve_impact,
};
use crate::dynamics::solver::{SolverContact, arms_along};

/// Applies collision impulses; skipped when there is no contact.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    buffers.bias.clear();
    buffers.bias.resize(ctx.bodies.len(), BodyVelocity::ZERO);
    buffers.touched.clear();
    buffers.touched.resize(ctx.bodies.len(), false);
    if buffers.solver_contacts.is_empty() {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    // A resting contact approaches at most at what one sub-step of its bodies' relative
    // acceleration gives (gravity, or a stronger applied force); twice that is a collision.
    let gravity = ctx.settings.gravity.length();
    let threshold = |contact: &crate::dynamics::solver::SolverContact| {
        let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
        let driven = (buffers.accelerations[a].linear - buffers.accelerations[b].linear).length();
        ctx.settings.resting_speed + 2.0 * gravity.max(driven) * buffers.substep
    };
    let states = &mut buffers.states;
    // Whether any contact approaches faster than its threshold (or is not a number): the test
    // of the first sweep, which applies nothing where none does (a still structure's every
    // sub-step), so it is not run. It is the first test of every contact: one it finds slow
    // the first sweep passes over until an impulse moves one of its bodies ([`SweepMarks`]).
    let marks = &mut buffers.collide_marks;
    marks.first_tests(buffers.solver_contacts.len());
    let mut approaching = false;
    for (contact, passed) in buffers.solver_contacts.iter_mut().zip(&mut marks.passed) {
        let (va, vb) = pair_velocities(states, contact.key.bodies);
        contact.normal_velocity_before = contact.relative_velocity(va, vb).dot(contact.normal);
        let slow = contact.normal_velocity_before.partial_cmp(&-threshold(contact)).is_some_and(|order| order.is_ge());
        approaching |= !slow;
        *passed = u64::from(slow);
        contact.collision_impulse = glam::DVec2::ZERO;
        contact.collided = false;
        contact.collision_kind = None;
    }
    let law = ctx.settings.impulse_law;
    let counters = &mut ctx.profile.counters;
    if !approaching {
        // The counts of the sweep that would have found nothing.
        counters.impulse_iterations += 1;
        counters.impulse_cap_hits += u64::from(ctx.settings.max_impulse_iterations == 0);
        return;
    }
    marks.start(ctx.bodies.len());
    for sweep in 0..=ctx.settings.max_impulse_iterations {
        let inelastic = sweep == ctx.settings.max_impulse_iterations;
        if inelastic {
            counters.impulse_cap_hits += 1;
        }
        counters.impulse_iterations += 1;
        let mut applied = 0;
        let contacts = &mut buffers.solver_contacts;
        let mut k = 0;
        while k < contacts.len() {
            // The inelastic sweep tests everything: a contact the law let go (`Separating`) at
            // its restitution may be struck at none.
            if !inelastic && marks.passes_again(contacts, k) {
                k += 1;
                continue;
            }
            // A flat patch whose two ends both strike collides once, at its centre: the ends
            // struck one after the other would spin the body (a box pushed flat-on by a wall came
            // away turning and faster than the wall; tests/kinematic.rs). A patch landing on one
            // end (a turning body) is struck end by end.
            let patch = contacts[k].patch_with_next
                && k + 1 < contacts.len()
                && contacts[k..k + 2].iter().all(|end| {
                    let (va, vb) = pair_velocities(states, end.key.bodies);
                    end.relative_velocity(va, vb).dot(end.normal) < -threshold(end)
                });
            let outcome = if patch {
                let mut centre = patch_centre(&contacts[k], &contacts[k + 1]);
                let before = centre.collision_impulse;
                let threshold = threshold(&centre);
                let outcome = collide(&mut centre, states, threshold, law, inelastic);
                // Each end records half of the centre's impulse (events and the warm start).
                let share = 0.5 * (centre.collision_impulse - before);
                for end in &mut contacts[k..k + 2] {
                    end.collision_impulse += share;
                    end.collided |= centre.collided;
                    end.collision_kind = centre.collision_kind.or(end.collision_kind);
                }
                outcome
            } else {
                // In place: a contact is large, and most are not struck.
                let threshold = threshold(&contacts[k]);
                collide(&mut contacts[k], states, threshold, law, inelastic)
            };
            let unit = if patch { 2 } else { 1 };
            match outcome {
                Ok(Some(moved)) => {
                    applied += 1;
                    marks.struck(contacts[k].key.bodies, moved);
                }
                Ok(None) => marks.passed(k..k + unit),
                Err(()) => counters.impulse_errors += 1,
            }
            k += unit;
        }
        if applied == 0 {
            break;
        }
    }
    for contact in &buffers.solver_contacts {
        if contact.collided {
            buffers.touched[contact.key.bodies.0 as usize] = true;
            buffers.touched[contact.key.bodies.1 as usize] = true;
        }
    }
}

/// The contact at the centre of a two-point patch: lever arms and point averaged, the rest of
/// `first` (normal, masses' inverses, friction, restitution); its collision impulse is the sum
/// of both ends' so far.
fn patch_centre(first: &SolverContact, second: &SolverContact) -> SolverContact {
    let (r_a, r_b) = (0.5 * (first.r_a + second.r_a), 0.5 * (first.r_b + second.r_b));
    SolverContact {
        point: 0.5 * (first.point + second.point),
        r_a,
        r_b,
        normal_arms: arms_along(r_a, r_b, first.normal),
        tangent_arms: arms_along(r_a, r_b, first.tangent()),
        collision_impulse: first.collision_impulse + second.collision_impulse,
        collided: first.collided || second.collided,
        ..*first
    }
}

/// One contact of a sweep: `Ok(Some(moved))` if an impulse was applied (`moved`: whether it
/// changed the velocity of A and of B; a static or kinematic body's never changes), `Ok(None)`
/// if not, `Err` if the law failed.
fn collide(
    contact: &mut SolverContact,
    states: &mut [crate::components::RigidState],
    threshold: f64,
    law: crate::dynamics::impulse::ImpulseLaw,
    inelastic: bool,
) -> Result<Option<[bool; 2]>, ()> {
    let (va, vb) = pair_velocities(states, contact.key.bodies);
    let u = contact.relative_velocity(va, vb);
    if u.dot(contact.normal) >= -threshold {
        return Ok(None);
    }
    let input = ContactMassInput {
        inverse_mass_a: contact.inverse[0],
        inverse_inertia_a: contact.inverse[1],
        r_a: contact.r_a,
        inverse_mass_b: contact.inverse[2],
        inverse_inertia_b: contact.inverse[3],
        r_b: contact.r_b,
    };
    let e = if inelastic { 0.0 } else { contact.restitution };
    let impact = ImpactContact {
        matrix: collision_matrix(&input),
        normal: contact.normal,
        velocity: u,
        restitution: e,
        friction: contact.friction,
    };
    let outcome = resolve_impact(law, &impact).map_err(|_| ())?;
    if outcome.kind == ImpulseKind::Separating {
        return Ok(None);
    }
    let (mut new_a, mut new_b) = (va, vb);
    crate::dynamics::solver::apply(contact.inverse, contact.r_a, contact.r_b, outcome.impulse, &mut new_a, &mut new_b);
    store_velocities(states, contact.key.bodies, new_a, new_b);
    contact.collision_impulse += outcome.impulse;
    contact.collided = true;
    contact.collision_kind = Some(outcome.kind);
    Ok(Some([new_a != va, new_b != vb]))
}

/// Which contacts a collision sweep need not test again: those that struck nothing when last
/// tested and neither of whose bodies has changed velocity since. A test reads only the
/// contact's own (fixed) data and its bodies' velocities, so it would strike nothing again, and
/// leaving it out changes no bit. Each impulse applied is a tick of a clock (from 1); each body
/// keeps the tick of its last change (by value: `-0.0` for `0.0` is no change, as no test can
/// tell them apart), each contact the tick of its last test that struck nothing. The stage's
/// first pass over the contacts is every contact's first test (tick 1 where it found the
/// contact slow), so the first sweep tests only the contacts that approach and those an impulse
/// of that sweep has reached.
#[derive(Debug, Default)]
pub(crate) struct SweepMarks {
    /// Per body slot: the tick of its last change of velocity (0: none in this stage).
    changed: Vec<u64>,
    /// Per contact (`solver_contacts` order): the tick of its last test that struck nothing
    /// (0: none, and it is tested).
    passed: Vec<u64>,
    /// One more than the impulses applied so far in this stage.
    clock: u64,
}

impl SweepMarks {
    /// Room for the first tests of `contacts` contacts, each of which the first pass writes.
    fn first_tests(&mut self, contacts: usize) {
        self.passed.resize(contacts, 0);
    }

    /// The sweeps start, for `bodies` body slots: no body has changed, the clock at 1.
    fn start(&mut self, bodies: usize) {
        self.changed.clear();
        self.changed.resize(bodies, 0);
        self.clock = 1;
    }

    /// Every mark cleared, for `bodies` body slots and `contacts` contacts.
    #[cfg(test)]
    fn reset(&mut self, bodies: usize, contacts: usize) {
        self.passed.clear();
        self.first_tests(contacts);
        self.start(bodies);
    }

    /// Whether the sweep's unit at `k` (the contact, with the next one where it may be the other
    /// end of a patch) struck nothing when last tested and none of its bodies has changed
    /// since: it would strike nothing again.
    ///
    /// Patches are pairs of contacts (the first `patch_with_next`), so a sweep's unit at `k`
    /// that is passed over leaves the next unit at `k + 1` either way.
    fn passes_again(&self, contacts: &[SolverContact], k: usize) -> bool {
        debug_assert!(
            k == 0 || !(contacts[k - 1].patch_with_next && contacts[k].patch_with_next),
            "a patch's second end begins no patch"
        );
        let tick = self.passed[k];
        let still = |(a, b): (u32, u32)| self.changed[a as usize] <= tick && self.changed[b as usize] <= tick;
        tick > 0
            && still(contacts[k].key.bodies)
            && (!contacts[k].patch_with_next || contacts.get(k + 1).is_none_or(|next| still(next.key.bodies)))
    }

    /// The contacts of `unit` were tested and struck nothing.
    fn passed(&mut self, unit: std::ops::Range<usize>) {
        let tick = self.clock;
        self.passed[unit].fill(tick);
    }

    /// An impulse was applied between `bodies`, changing the velocities `moved` says.
    fn struck(&mut self, (a, b): (u32, u32), moved: [bool; 2]) {
        self.clock += 1;
        for (slot, moved) in [(a, moved[0]), (b, moved[1])] {
            if moved {
                self.changed[slot as usize] = self.clock;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::SweepMarks;
    use crate::dynamics::solver::{ContactKey, SolverContact};

    fn contact(bodies: (u32, u32), patch_with_next: bool) -> SolverContact {
        SolverContact {
            key: ContactKey { bodies, ..ContactKey::default() },
            patch_with_next,
            ..SolverContact::default()
        }
    }

    /// A contact is passed over only while it struck nothing at its last test and neither of its
    /// bodies has changed since (a body an impulse did not move, as a static one, never counts).
    #[test]
    fn marks_pass_over_only_contacts_whose_bodies_have_not_changed() {
        // Bodies 0–3; 3 is static (an impulse never changes it).
        let contacts = [contact((0, 1), false), contact((1, 2), false), contact((2, 3), true), contact((2, 3), false)];
        let mut marks = SweepMarks::default();
        marks.reset(4, contacts.len());
        assert!((0..4).all(|k| !marks.passes_again(&contacts, k)), "untested contacts are tested");
        marks.passed(0..1);
        marks.passed(1..2);
        marks.passed(2..4);
        assert!((0..4).all(|k| marks.passes_again(&contacts, k)), "nothing has changed since");
        // Contact 1 strikes, moving body 1 only (say body 2 is kinematic).
        marks.struck((1, 2), [true, false]);
        assert!(!marks.passes_again(&contacts, 0), "body 1 moved since contact 0's test");
        assert!(!marks.passes_again(&contacts, 1), "contact 1 struck: it is tested again");
        assert!(marks.passes_again(&contacts, 2) && marks.passes_again(&contacts, 3), "bodies 2 and 3 kept still");
        marks.passed(0..1);
        assert!(marks.passes_again(&contacts, 0), "tested again after the change");
        // An impulse on the static body's pair that moves only body 2 reaches the patch's ends.
        marks.struck((2, 3), [true, false]);
        assert!(!marks.passes_again(&contacts, 2) && !marks.passes_again(&contacts, 3));
        assert!(marks.passes_again(&contacts, 0), "body 2 is not contact 0's");
    }
}
