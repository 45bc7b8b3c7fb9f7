//! Begin and end of touching per pair of bodies (Box2D's contact begin and end events): the
//! pairs touching at the end of a step are compared with those of the step before. A pair that
//! was not tested in the step — both bodies asleep, or one asleep and one static — keeps
//! touching; a removed body ends every pair it was in.

use hecs::Entity;

use super::Simulation;
use crate::components::{Kinematic, Sleep};
use crate::events::{TouchEvent, TouchKind};

impl Simulation {
    /// Takes the begin and end events recorded since the last call (each step's in pair order).
    pub fn drain_touch_events(&mut self) -> std::vec::Drain<'_, TouchEvent> {
        self.touch_events.drain()
    }

    /// The pairs of bodies touching at the end of the last step, `(a, b)` sorted.
    #[must_use]
    pub fn touching_pairs(&self) -> &[(Entity, Entity)] {
        &self.touching
    }

    /// After a step that ran the narrow phase: records begin and end events. A pair that
    /// touched at the end of any sub-step but was not touching before begins; one that was
    /// touching before, or touched during the step, and does not touch at its end, ends (a
    /// bounce inside one step gives both). `stale`: the step began with contacts detected
    /// again (bodies may have been added or removed since the last record).
    pub(super) fn record_touches(&mut self, stale: bool) {
        // The slot pairs that touched during the step are those that touch at its end (no
        // bounce within it), and the same as at the last record, over the same table of bodies
        // (nothing added or removed; sleeping off, so no pair is kept untested): the same pairs
        // of bodies touch as before, and nothing began or ended. A still structure's every step,
        // without mapping its pairs to bodies and sorting them.
        let touching_live = self.buffers.live_pairs().iter().filter(|slot| slot.touching()).map(|slot| slot.bodies);
        let whole = self.buffers.touched_pairs.iter().copied().eq(touching_live);
        let known = self.touched_slots.1 && !stale && !self.settings.sleep.enabled;
        if whole && known && self.touched_slots.0 == self.buffers.touched_pairs {
            return;
        }
        // What the next record compares with: this step's slot pairs, where they are the
        // pairs touching at its end.
        self.touched_slots.0.clear();
        self.touched_slots.0.extend_from_slice(&self.buffers.touched_pairs);
        self.touched_slots.1 = whole;
        let table = if self.settings.sleep.enabled { &self.step_bodies } else { &self.bodies };
        let entities = |(a, b): (u32, u32)| {
            let (a, b) = (table[a as usize].entity, table[b as usize].entity);
            (a.min(b), a.max(b))
        };
        let now = &mut self.touching_now;
        now.clear();
        // Room for every live pair and every pair touching before, which bound what it holds
        // below: grown once to the scene's pairs while everything is awake, not pair by pair in
        // whichever later step first holds a few more (a wake and sleep cycle did: an allocation
        // in steady state, tests/allocation.rs).
        now.reserve(self.buffers.live_pairs().len() + self.touching.len());
        now.extend(self.buffers.live_pairs().iter().filter(|slot| slot.touching()).map(|slot| entities(slot.bodies)));
        // Pairs with no awake body were not tested: they keep touching (only with sleeping on;
        // without it every pair is tested). A kinematic body's pairs are always tested.
        if self.settings.sleep.enabled {
            let awake = |e: Entity| {
                self.world.get::<&Kinematic>(e).is_ok() || self.world.get::<&Sleep>(e).is_ok_and(|s| !s.is_asleep())
            };
            now.extend(self.touching.iter().filter(|&&(a, b)| !awake(a) && !awake(b)));
        }
        now.sort_unstable();
        now.dedup();
        // The same pairs touch as before, and every pair that touched during the step touches
        // still: nothing began or ended. A resting structure's every step: the searches below
        // cost the settled 210-box pyramid 0.30 M instructions a step, 6 % of its step.
        if *now == self.touching && whole {
            return;
        }
        let (time, counters) = (self.time, &mut self.profile.counters);
        let mut push = |kind, (body_a, body_b)| {
            self.touch_events.push(TouchEvent { time, kind, body_a, body_b }, counters);
        };
        // Begins: touched during the step (or touching at its end), not touching before.
        let during = self.buffers.touched_pairs.iter().map(|&pair| entities(pair));
        let mut begun = 0;
        for pair in during.chain(now.iter().copied()) {
            if self.touching.binary_search(&pair).is_err() && !self.touch_scratch[..begun].contains(&pair) {
                self.touch_scratch.truncate(begun);
                self.touch_scratch.push(pair);
                begun += 1;
                push(TouchKind::Begin, pair);
            }
        }
        // Ends: touching before or begun in the step, not touching at its end.
        for &pair in self.touching.iter().chain(&self.touch_scratch[..begun]) {
            if now.binary_search(&pair).is_err() {
                push(TouchKind::End, pair);
            }
        }
        std::mem::swap(&mut self.touching, &mut self.touching_now);
    }

    /// Before a body is removed: ends every pair it touches.
    pub(super) fn end_touches_of(&mut self, entity: Entity) {
        let (time, counters) = (self.time, &mut self.profile.counters);
        for &(a, b) in self.touching.iter().filter(|&&(a, b)| a == entity || b == entity) {
            self.touch_events.push(TouchEvent { time, kind: TouchKind::End, body_a: a, body_b: b }, counters);
        }
        self.touching.retain(|&(a, b)| a != entity && b != entity);
    }
}
