//! Contact resolution shared by the impulse and micro-collision systems (not a system itself):
//! impulses are applied serially, contact by contact in pair order, so the result does not
//! depend on the thread count.

use glam::DVec2;

use super::{BodyRecord, PairSlot, StepContext};
use crate::components::RigidState;
use crate::dynamics::impulse::{
    BandPenetration, BodyVelocity, ContactMassInput, ImpactContact, ImpulseKind, ImpulseLaw, ImpulseOutcome,
    MicroCollisionSettings, resolve_impact, resolve_micro_collision,
};
use crate::dynamics::laws::{combine_restitution, contact_friction};
use crate::events::{ContactEvent, EventKind, EventLog};
use crate::geometry::query::BodyContact;
use crate::profile::StepCounters;

/// Everything contact resolution reads or writes, split out of the step context.
pub(super) struct Resolver<'a> {
    bodies: &'a [BodyRecord],
    states: &'a mut [RigidState],
    events: &'a mut EventLog<ContactEvent>,
    counters: &'a mut StepCounters,
    law: ImpulseLaw,
    record_events: bool,
    time: f64,
    /// Normal speed below which a contact is resting (m/s).
    resting_speed: f64,
    /// Magnitude of gravity (m/s²).
    gravity: f64,
    /// Collision sweeps before the final inelastic one.
    max_sweeps: u32,
}

/// Runs `f` with a resolver over the live pairs, unless no pair has a contact (then the stage
/// is counted as skipped).
pub(super) fn with_resolver(ctx: &mut StepContext<'_>, f: impl FnOnce(&mut Resolver<'_>, &[PairSlot])) {
    let buffers = &mut *ctx.buffers;
    let slots = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    if slots.iter().all(|s| s.sensor || s.manifold().contacts.is_empty()) {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let gravity = ctx.settings.gravity.length();
    let mut resolver = Resolver {
        bodies: ctx.bodies,
        states: &mut buffers.states,
        events: ctx.events,
        counters: &mut ctx.profile.counters,
        law: ctx.settings.impulse_law,
        record_events: ctx.settings.record_events,
        time: buffers.substep_time + buffers.substep,
        resting_speed: ctx.settings.resting_speed + 2.0 * gravity * buffers.substep,
        gravity,
        max_sweeps: ctx.settings.max_impulse_iterations,
    };
    f(&mut resolver, slots);
}

/// How a contact is to be resolved.
#[derive(Clone, Copy)]
pub(super) enum Treatment {
    /// A collision with the materials' restitution, or with `e = 0` for the final sweep.
    Collision { inelastic: bool },
    /// A micro-collision of a resting contact (MODEL §7).
    Micro,
}

/// Friction and restitution of a contact from the two materials and the local tolerances.
struct SurfaceLaw {
    mu_a: f64,
    mu_b: f64,
    restitution: f64,
    restitution_max: f64,
}

impl Resolver<'_> {
    /// One sweep over all contacts; returns how many impulses it applied.
    pub fn sweep(&mut self, slots: &[PairSlot], treatment: Treatment) -> usize {
        let mut applied = 0;
        for slot in slots.iter().filter(|slot| slot.solvable(self.bodies)) {
            for contact in &slot.manifold().contacts {
                if self.resolve(slot.bodies, contact, treatment) {
                    applied += 1;
                }
            }
        }
        applied
    }

    /// Collision sweeps until no contact approaches; after `cap` sweeps one inelastic sweep
    /// stops what still approaches (Guendelman et al. 2003), and the cap hit is counted.
    pub fn collide_until_separating(&mut self, slots: &[PairSlot]) {
        for _ in 0..self.max_sweeps {
            self.counters.impulse_iterations += 1;
            if self.sweep(slots, Treatment::Collision { inelastic: false }) == 0 {
                return;
            }
        }
        self.counters.impulse_cap_hits += 1;
        self.sweep(slots, Treatment::Collision { inelastic: true });
    }

    fn surface_law(&self, (a, b): (usize, usize), contact: &BodyContact) -> SurfaceLaw {
        let (ma, mb) = (&self.bodies[a].material, &self.bodies[b].material);
        SurfaceLaw {
            mu_a: ma.friction.coefficient(contact.contact.raw_lambda_a),
            mu_b: mb.friction.coefficient(contact.contact.raw_lambda_b),
            restitution: combine_restitution(ma.restitution, mb.restitution),
            restitution_max: combine_restitution(ma.restitution_max, mb.restitution_max),
        }
    }

    fn resolve(&mut self, (a, b): (u32, u32), contact: &BodyContact, treatment: Treatment) -> bool {
        let (a, b) = (a as usize, b as usize);
        let point = contact.contact.point;
        let input = ContactMassInput {
            inverse_mass_a: self.bodies[a].inverse_mass,
            inverse_inertia_a: self.bodies[a].inverse_inertia,
            r_a: point - self.states[a].position,
            inverse_mass_b: self.bodies[b].inverse_mass,
            inverse_inertia_b: self.bodies[b].inverse_inertia,
            r_b: point - self.states[b].position,
        };
        let (va, vb) = (velocity(&self.states[a]), velocity(&self.states[b]));
        let law = self.surface_law((a, b), contact);
        let normal = contact.contact.normal;
        let u_n = (va.point_velocity(input.r_a) - vb.point_velocity(input.r_b)).dot(normal);
        let mu = contact_friction(
            &self.bodies[a].material.friction,
            contact.contact.raw_lambda_a,
            &self.bodies[b].material.friction,
            contact.contact.raw_lambda_b,
        );
        let outcome = match treatment {
            Treatment::Collision { inelastic } => {
                if u_n >= -self.resting_speed {
                    return false;
                }
                let e = if inelastic { 0.0 } else { law.restitution };
                let resolved = resolve_impact(self.law, &ImpactContact::new(&input, va, vb, normal, e, mu));
                self.counters.impulse_errors += u64::from(resolved.is_err());
                resolved.ok()
            }
            Treatment::Micro => {
                let band = BandPenetration {
                    penetration: contact.contact.penetration.max(0.0),
                    tolerance: contact.contact.lambda_a + contact.contact.lambda_b,
                };
                let settings =
                    MicroCollisionSettings { resting_speed: self.resting_speed, restitution_max: law.restitution_max };
                let impact = ImpactContact::new(&input, va, vb, normal, law.restitution, mu);
                let resolved = resolve_micro_collision(self.law, &impact, band, self.gravity, &settings);
                self.counters.impulse_errors += u64::from(resolved.is_err());
                resolved.ok().flatten()
            }
        };
        let Some(outcome) = outcome.filter(|o| o.kind != ImpulseKind::Separating && o.impulse.is_finite()) else {
            return false;
        };
        self.apply(a, b, &input, outcome.impulse);
        let after = (velocity(&self.states[a]).point_velocity(input.r_a)
            - velocity(&self.states[b]).point_velocity(input.r_b))
        .dot(normal);
        let kind = match (treatment, outcome.kind) {
            (Treatment::Micro, _) => EventKind::MicroCollision,
            (_, ImpulseKind::Sticking) => EventKind::Sticking,
            (_, ImpulseKind::Sliding) => EventKind::Sliding,
            _ => EventKind::Collision,
        };
        match treatment {
            Treatment::Micro => self.counters.micro_collisions += 1,
            Treatment::Collision { .. } => self.counters.impulses += 1,
        }
        if self.record_events {
            self.record((a, b), contact, &law, mu, kind, u_n, after, &outcome);
        }
        true
    }

    fn apply(&mut self, a: usize, b: usize, input: &ContactMassInput, impulse: DVec2) {
        let sa = &mut self.states[a];
        sa.linear_velocity += input.inverse_mass_a * impulse;
        sa.angular_velocity += input.inverse_inertia_a * input.r_a.perp_dot(impulse);
        let sb = &mut self.states[b];
        sb.linear_velocity -= input.inverse_mass_b * impulse;
        sb.angular_velocity -= input.inverse_inertia_b * input.r_b.perp_dot(impulse);
    }

    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        (a, b): (usize, usize),
        contact: &BodyContact,
        law: &SurfaceLaw,
        mu: f64,
        kind: EventKind,
        before: f64,
        after: f64,
        outcome: &ImpulseOutcome,
    ) {
        let event = ContactEvent {
            time: self.time,
            body_a: self.bodies[a].entity,
            body_b: self.bodies[b].entity,
            segment_a: contact.segment_a as usize,
            parameter_a: contact.u_a,
            segment_b: contact.segment_b as usize,
            parameter_b: contact.u_b,
            point: contact.contact.point,
            normal: contact.contact.normal,
            lambda_a: contact.contact.raw_lambda_a,
            lambda_b: contact.contact.raw_lambda_b,
            mu_a: law.mu_a,
            mu_b: law.mu_b,
            mu,
            kind,
            normal_velocity_before: before,
            normal_velocity_after: after,
            impulse: outcome.impulse,
        };
        self.events.push(event, self.counters);
    }
}

fn velocity(state: &RigidState) -> BodyVelocity {
    BodyVelocity { linear: state.linear_velocity, angular: state.angular_velocity }
}
