//! Solver contacts built from touches (lever arms, effective masses, laws), warm-started from
//! the cache of last sub-step's forces, and the statics estimate of islands that start cold.

use glam::DVec2;

use super::Touch;
use super::order::OrderKey;
use crate::components::RigidState;
use crate::dynamics::laws::{combine_restitution, contact_friction, contact_restitution};
use crate::dynamics::solver::{CachedImpulse, HEAVY_ON_LIGHT, SolverContact, arms_along, effective_mass};
use crate::simulation::{SimulationSettings, SolverSettings};
use crate::systems::BodyRecord;

/// A cold start's estimate of the forces that hold bodies up: each body's weight plus the load
/// from above, shared equally by the contacts it rests on and passed down level by level.
pub(super) struct Statics<'a> {
    pub(super) bodies: &'a [BodyRecord],
    pub(super) levels: &'a [u32],
    pub(super) island_of: &'a [u32],
    pub(super) gravity: DVec2,
}

impl Statics<'_> {
    /// The body a contact holds up (the one further from the ground) and the one below, with the
    /// normal oriented from the lower to the upper; `None` for a contact within one level or
    /// off the ground.
    fn support(&self, contact: &SolverContact) -> Option<(usize, usize, DVec2)> {
        let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
        let (la, lb) = (self.levels[a], self.levels[b]);
        if la == lb || la.max(lb) == crate::systems::islands::UNGROUNDED {
            return None;
        }
        Some(if la > lb { (a, b, contact.normal) } else { (b, a, -contact.normal) })
    }

    /// The island of a contact.
    fn island(&self, contact: &SolverContact) -> usize {
        crate::systems::contact_island(self.bodies, self.island_of, contact.key.bodies)
    }

    /// Sets the warm-start force of the contacts of every island whose contacts are all cold
    /// (a structure spawned at rest: otherwise the first sub-steps' sweeps, starting from
    /// nothing, let a tall one sink, and what they push back adds up) from the loads. An island
    /// with any force cached is left to its warm start. Contacts come sorted from the ground
    /// up, so walking them backwards finishes each level's loads before they are passed down.
    pub(super) fn estimate(&self, contacts: &mut [SolverContact], loads: &mut Vec<f64>, supports: &mut Vec<u32>) {
        let up = -self.gravity.normalize_or_zero();
        // `supports` first marks the islands with a warm contact (1), then counts supports.
        supports.clear();
        supports.resize(self.bodies.len(), 0);
        for contact in contacts.iter().filter(|c| !c.cold) {
            supports[self.island(contact)] = 1;
        }
        for contact in contacts.iter_mut() {
            contact.cold &= supports[self.island(contact)] == 0;
        }
        supports.fill(0);
        for contact in contacts.iter() {
            if let Some((upper, _, n)) = self.support(contact)
                && n.dot(up) > 0.0
            {
                supports[upper] += 1;
            }
        }
        loads.clear();
        loads.extend(self.bodies.iter().map(
            |b| {
                if b.is_static { 0.0 } else { self.gravity.length() / b.inverse_mass }
            },
        ));
        for contact in contacts.iter_mut().rev() {
            let Some((upper, lower, n)) = self.support(contact) else { continue };
            let lift = n.dot(up);
            if lift <= 0.0 || supports[upper] == 0 {
                continue;
            }
            let share = loads[upper] / f64::from(supports[upper]);
            if contact.cold {
                contact.warm = (share / lift.max(0.5), 0.0);
            }
            if !self.bodies[lower].is_static {
                loads[lower] += share;
            }
        }
    }
}

/// Copies last sub-step's forces into the contacts whose identity persists; `true` if some
/// contact found none (it is then *cold*). The cache is sorted by key, pair first;
/// the contacts come mostly pair by pair in pair order (the narrow phase's, within a level of
/// the solving order, where a pair that shares a body with the one before it may wait a few
/// places, [`sort_keys`](super::order::sort_keys)): each pair's cached forces are found by walking the cache forward
/// or a few entries back, then among them its contacts' (a pair further behind, or far ahead,
/// is searched for).
pub(super) fn warm_start(contacts: &mut [SolverContact], cache: &[CachedImpulse]) -> bool {
    let mut any_cold = false;
    let mut start = 0;
    for contact in contacts {
        let bodies = contact.key.bodies;
        // Back over the entries of later pairs (what is left is the first not before `bodies`).
        let mut back = 0;
        while start > 0 && back < WALK && cache[start - 1].key.bodies >= bodies {
            start -= 1;
            back += 1;
        }
        let behind = start > 0 && cache[start - 1].key.bodies >= bodies;
        let far = cache.get(start + WALK).is_some_and(|cached| cached.key.bodies < bodies);
        if behind || far {
            start = cache.partition_point(|cached| cached.key.bodies < bodies);
        }
        while start < cache.len() && cache[start].key.bodies < bodies {
            start += 1;
        }
        let mut pair = cache[start..].iter().take_while(|cached| cached.key.bodies == bodies);
        (contact.warm, contact.cold) = match pair.find(|cached| cached.key == contact.key) {
            Some(cached) => ((cached.normal_force, cached.tangent_force), false),
            None => ((0.0, 0.0), true),
        };
        any_cold |= contact.cold;
    }
    any_cold
}

/// Cached forces the warm start walks past at most before it searches instead.
const WALK: usize = 8;

/// A contact's lever arms and effective masses ([`Builder::arms`]).
struct Arms {
    r_a: DVec2,
    r_b: DVec2,
    normal_arms: (f64, f64),
    tangent_arms: (f64, f64),
    normal_mass: f64,
    tangent_mass: f64,
    shock_masses: (f64, f64),
}

/// Read-only inputs of contact preparation.
pub(super) struct Builder<'a> {
    bodies: &'a [BodyRecord],
    states: &'a [RigidState],
    levels: &'a [u32],
    settings: &'a SolverSettings,
}

impl<'a> Builder<'a> {
    /// The inputs of preparing the contacts of `bodies` at `states`, with their `levels`.
    pub(super) fn new(
        bodies: &'a [BodyRecord],
        (states, levels): (&'a [RigidState], &'a [u32]),
        settings: &'a SimulationSettings,
    ) -> Self {
        Self { bodies, states, levels, settings: &settings.solver }
    }

    /// The solver contact of `touch` at the bodies' positions now, at its place in solving
    /// order (`key`), with the friction and restitution the contact hook set for its pair
    /// (`hook`; `None`: the materials').
    #[inline(always)]
    pub(super) fn contact(&self, touch: &Touch, key: &OrderKey, hook: (Option<f64>, Option<f64>)) -> SolverContact {
        let (a, b) = (touch.key.bodies.0 as usize, touch.key.bodies.1 as usize);
        let (body_a, body_b) = (&self.bodies[a], &self.bodies[b]);
        let inverse = [body_a.inverse_mass, body_a.inverse_inertia, body_b.inverse_mass, body_b.inverse_inertia];
        let (level_a, level_b) = (self.levels[a], self.levels[b]);
        let shock_hold = match level_a.cmp(&level_b) {
            std::cmp::Ordering::Less => 1,
            std::cmp::Ordering::Greater => 2,
            std::cmp::Ordering::Equal => 0,
        };
        let (ma, mb) = (&body_a.material, &body_b.material);
        let restitution = combine_restitution(ma.restitution, mb.restitution);
        let restitution_max = combine_restitution(ma.restitution_max, mb.restitution_max);
        let arms = self.arms(touch.key.bodies, touch.point, touch.normal, inverse, shock_hold);
        SolverContact {
            key: touch.key,
            r_a: arms.r_a,
            r_b: arms.r_b,
            normal_arms: arms.normal_arms,
            tangent_arms: arms.tangent_arms,
            normal_mass: arms.normal_mass,
            tangent_mass: arms.tangent_mass,
            shock_masses: arms.shock_masses,
            normal: touch.normal,
            inverse,
            shock_hold,
            heavy_on_light: match shock_hold {
                // The held body's inverse mass is at least HEAVY_ON_LIGHT times the other's.
                1 => inverse[0] >= HEAVY_ON_LIGHT * inverse[2],
                2 => inverse[2] >= HEAVY_ON_LIGHT * inverse[0],
                _ => false,
            },
            friction: match hook.0 {
                Some(mu) => mu,
                None => contact_friction(&ma.friction, touch.raw_lambda.0, &mb.friction, touch.raw_lambda.1),
            },
            mu: (ma.friction.coefficient(touch.raw_lambda.0), mb.friction.coefficient(touch.raw_lambda.1)),
            restitution: hook.1.unwrap_or(restitution),
            push_restitution: match hook.1 {
                Some(e) => e,
                None => contact_restitution(restitution, restitution_max, touch.penetration, touch.band),
            },
            excess_depth: touch.penetration - self.settings.rest_depth * touch.band,
            band: touch.band,
            point: touch.point,
            parameters: touch.parameters,
            raw_lambda: touch.raw_lambda,
            level: level_a.min(level_b),
            segments: touch.segments,
            patch_with_next: touch.patch_with_next,
            sequence: key.sequence,
            island: key.island,
            ..SolverContact::default()
        }
    }

    /// Writes [`Builder::contact`] over `out`. Not inlined, so that the contact is built where
    /// it is returned, in `out` (built and then moved into the vector, each contact's 472 bytes
    /// were copied by a call to memcpy).
    #[inline(never)]
    pub(super) fn write(
        &self,
        out: &mut SolverContact,
        touch: &Touch,
        key: &OrderKey,
        hook: (Option<f64>, Option<f64>),
    ) {
        *out = self.contact(touch, key, hook);
    }

    /// The lever arms and effective masses of a contact of `bodies` at `point` with normal `n`,
    /// at the bodies' positions now (the shock pass's with the body `shock_hold` names held).
    #[inline(always)]
    fn arms(&self, bodies: (u32, u32), point: DVec2, n: DVec2, inverse: [f64; 4], shock_hold: u8) -> Arms {
        let r_a = point - self.states[bodies.0 as usize].position;
        let r_b = point - self.states[bodies.1 as usize].position;
        let mut held = inverse;
        match shock_hold {
            1 => held[..2].fill(0.0),
            2 => held[2..].fill(0.0),
            _ => {}
        }
        let t = n.perp();
        Arms {
            r_a,
            r_b,
            normal_arms: arms_along(r_a, r_b, n),
            tangent_arms: arms_along(r_a, r_b, t),
            normal_mass: effective_mass(inverse, r_a, r_b, n),
            tangent_mass: effective_mass(inverse, r_a, r_b, t),
            shock_masses: (effective_mass(held, r_a, r_b, n), effective_mass(held, r_a, r_b, t)),
        }
    }

    /// `contact` at the bodies' positions now: its lever arms and effective masses worked out,
    /// what its touch, its bodies and its place in solving order gave it kept, and what a solve
    /// wrote cleared. Of a contact prepared from the same touch with the bodies' masses,
    /// materials, levels and islands unchanged, the same as [`Builder::contact`] of its touch
    /// (checked in debug builds, `validate::after`).
    pub(super) fn refresh(&self, contact: &SolverContact) -> SolverContact {
        let arms = self.arms(contact.key.bodies, contact.point, contact.normal, contact.inverse, contact.shock_hold);
        SolverContact {
            r_a: arms.r_a,
            r_b: arms.r_b,
            normal_arms: arms.normal_arms,
            tangent_arms: arms.tangent_arms,
            normal_mass: arms.normal_mass,
            tangent_mass: arms.tangent_mass,
            shock_masses: arms.shock_masses,
            key: contact.key,
            segments: contact.segments,
            point: contact.point,
            parameters: contact.parameters,
            raw_lambda: contact.raw_lambda,
            mu: contact.mu,
            normal: contact.normal,
            inverse: contact.inverse,
            shock_hold: contact.shock_hold,
            heavy_on_light: contact.heavy_on_light,
            friction: contact.friction,
            restitution: contact.restitution,
            push_restitution: contact.push_restitution,
            excess_depth: contact.excess_depth,
            band: contact.band,
            level: contact.level,
            patch_with_next: contact.patch_with_next,
            sequence: contact.sequence,
            island: contact.island,
            ..SolverContact::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::warm_start;
    use crate::dynamics::solver::{CachedImpulse, ContactKey, SolverContact};

    /// The warm start finds every contact's cached force that a scan of the whole cache finds,
    /// in pair order (several contacts a pair, some not cached, pairs with nothing cached) and
    /// out of it.
    #[test]
    fn the_warm_start_finds_each_contacts_cached_force() {
        let mut rng = crate::random::seeded(14);
        let key = |rng: &mut crate::random::SeededRng| {
            let a = rng.random_range(0..6);
            ContactKey {
                bodies: (a, a + rng.random_range(1..4)),
                segment_a: rng.random_range(0..3),
                segment_b: 0,
                ordinal: rng.random_range(0..2),
            }
        };
        for round in 0..200 {
            let mut cache: Vec<CachedImpulse> = (0..rng.random_range(0..20))
                .map(|k| CachedImpulse { key: key(&mut rng), normal_force: k as f64 + 1.0, tangent_force: -(k as f64) })
                .collect();
            cache.sort_by_key(|c| c.key);
            cache.dedup_by_key(|c| c.key);
            let mut contacts: Vec<SolverContact> = (0..rng.random_range(0..30))
                .map(|_| SolverContact { key: key(&mut rng), ..SolverContact::default() })
                .collect();
            if round % 2 == 0 {
                contacts.sort_by_key(|c| c.key.bodies);
            }
            let cold = warm_start(&mut contacts, &cache);
            for contact in &contacts {
                let searched = cache.iter().find(|c| c.key == contact.key);
                let expected = searched.map_or(((0.0, 0.0), true), |c| ((c.normal_force, c.tangent_force), false));
                assert_eq!((contact.warm, contact.cold), expected, "round {round}: {:?}", contact.key);
            }
            assert_eq!(cold, contacts.iter().any(|c| c.cold));
        }
    }
}
