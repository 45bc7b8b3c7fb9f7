//! The solving order of the prepared contacts: island by island, each from the ground up, pair
//! by pair, pairs that share a body kept apart within a level ([`sort_keys`]).

use super::Touch;
use crate::systems::BodyRecord;

/// Where a contact stands in solving order: island by island, each from the ground up, pair by
/// pair (a patch's two ends together); the `sequence` is its touch's place in the store (the
/// narrow phase's order), unique, so the order is deterministic. `slot` is its pair's slot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct OrderKey {
    pub(super) island: u32,
    pub(super) level: u32,
    pub(super) sequence: u32,
    pub(super) slot: u32,
}

/// Sorts `keys` (of the contacts of `touches`) into solving order: island by island, each
/// from the ground up, and within a level pair by pair in the narrow phase's order, except that
/// a pair sharing a body with the pair just placed waits until it no longer does (the first one
/// waiting goes at the first place where it shares no body with the pair before it; those left
/// go at the level's end, in order). Deterministic (the sort is on a unique key) and without
/// allocation once `scratch` has grown.
///
/// Why: a sweep updates a pair's two bodies from their velocities as the pair before left
/// them, so where consecutive pairs share a body (a row of boxes on a row below, in the
/// narrow phase's order, shares one in two pairs of three) each update waits on the last one's
/// stores and loads, and the core runs one update at a time. Consecutive pairs with no body in
/// common let it overlap them. Each update still reads the newest velocities (Gauss–Seidel in
/// another order within the level); the levels' order, on which the sweeps' minimum rests, is
/// unchanged. The base-40 pyramid's contact solver took 3.52 ms a step instead of 3.76 on one
/// thread and 2.40 instead of 2.71 on two (medians of alternating rounds, docs/performance.md).
pub(super) fn sort_keys(keys: &mut Vec<OrderKey>, touches: &[Touch], scratch: &mut OrderScratch) {
    keys.sort_unstable_by_key(|key| (key.island, key.level, key.sequence));
    let OrderScratch { keys: out, waiting, sorted_places } = scratch;
    out.clear();
    sorted_places.clear();
    sorted_places.resize(keys.len(), 0);
    // Places the sorted keys `from..to` next in the solving order.
    let mut place = |out: &mut Vec<OrderKey>, (from, to): (usize, usize)| {
        for (k, place) in (from..to).zip(out.len()..) {
            sorted_places[k] = place as u32;
        }
        out.extend_from_slice(&keys[from..to]);
    };
    let bodies = |key: &OrderKey| touches[key.sequence as usize].key.bodies;
    let shares =
        |(a, b): (u32, u32), last: Option<(u32, u32)>| last.is_some_and(|(c, d)| a == c || a == d || b == c || b == d);
    let mut start = 0;
    while start < keys.len() {
        let level = (keys[start].island, keys[start].level);
        let end = start + keys[start..].iter().take_while(|key| (key.island, key.level) == level).count();
        waiting.clear();
        let (mut first_waiting, mut last) = (0, None);
        let mut k = start;
        while k < end {
            let pair = bodies(&keys[k]);
            let pair_end = k + keys[k..end].iter().take_while(|key| bodies(key) == pair).count();
            if let Some(&(from, to)) = waiting.get(first_waiting)
                && !shares(bodies(&keys[from as usize]), last)
            {
                place(out, (from as usize, to as usize));
                last = Some(bodies(&keys[from as usize]));
                first_waiting += 1;
            }
            if shares(pair, last) {
                waiting.push((k as u32, pair_end as u32));
            } else {
                place(out, (k, pair_end));
                last = Some(pair);
            }
            k = pair_end;
        }
        for &(from, to) in &waiting[first_waiting..] {
            place(out, (from as usize, to as usize));
        }
        start = end;
    }
    debug_assert_eq!(out.len(), keys.len(), "the solving order keeps every contact");
    std::mem::swap(keys, out);
}

/// What [`sort_keys`] works in, and where it put each contact.
#[derive(Debug, Default)]
pub(crate) struct OrderScratch {
    /// The keys in their new order (swapped with the sorted ones).
    keys: Vec<OrderKey>,
    /// The pairs waiting in the level being placed, as ranges of the sorted keys.
    waiting: Vec<(u32, u32)>,
    /// The place in solving order of each contact, taken in the sorted order (island, level,
    /// the narrow phase's order): the commit walks the contacts in that order, so that the
    /// cached forces come nearly sorted by key (their sort, and the next warm start's walk
    /// through them, stay short) and the events keep the order they had.
    sorted_places: Vec<u32>,
}

impl OrderScratch {
    /// The place in solving order of each of the last prepared contacts, in sorted order.
    pub(crate) fn sorted_places(&self) -> &[u32] {
        &self.sorted_places
    }
}

/// The island and level of a contact between `bodies` (its key's `sequence` and `slot` left 0).
pub(super) fn order_key(bodies: &[BodyRecord], (levels, island_of): (&[u32], &[u32]), pair: (u32, u32)) -> OrderKey {
    OrderKey {
        island: crate::systems::contact_island(bodies, island_of, pair) as u32,
        level: levels[pair.0 as usize].min(levels[pair.1 as usize]),
        ..OrderKey::default()
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::{OrderKey, OrderScratch, sort_keys};
    use crate::dynamics::solver::ContactKey;
    use crate::systems::prepare_contacts::Touch;
    use glam::DVec2;

    /// The solving order keeps every contact, the islands and levels in order and each pair's
    /// contacts together; it moves pairs only within their level; `sorted_places` says where
    /// each sorted contact went; and where the narrow phase's order has a row of bodies resting
    /// on a row below (each pair sharing a body with the one before), consecutive pairs of the
    /// new order share no body except at a level's end, where the pairs still waiting go.
    #[test]
    fn the_solving_order_keeps_levels_and_parts_pairs_that_share_a_body() {
        let mut rng = crate::random::seeded(27);
        let touch = |bodies: (u32, u32)| Touch {
            key: ContactKey { bodies, ..ContactKey::default() },
            segments: (0, 0),
            point: DVec2::ZERO,
            normal: DVec2::Y,
            penetration: 0.0,
            band: 0.0,
            raw_lambda: (0.0, 0.0),
            parameters: (0.0, 0.0),
            patch_with_next: false,
        };
        let mut scratch = OrderScratch::default();
        let mut totals = (0, 0);
        for round in 0..100 {
            // Islands of rows: level ℓ's pairs join body (ℓ, i) above with (ℓ − 1, i) and
            // (ℓ − 1, i + 1) below, one or two contacts each; the touch store in pair order.
            let mut touches = Vec::new();
            let mut keys = Vec::new();
            for island in 0..rng.random_range(1..4u32) {
                for level in 0..rng.random_range(1..5u32) {
                    let body = |row: u32, i: u32| 10_000 * island + 100 * row + i;
                    for i in 0..rng.random_range(1..12u32) {
                        for below in [i, i + 1] {
                            for _ in 0..rng.random_range(1..3) {
                                let sequence = touches.len() as u32;
                                touches.push(touch((body(level, below), body(level + 1, i))));
                                keys.push(OrderKey { island, level, sequence, slot: 0 });
                            }
                        }
                    }
                }
            }
            let mut sorted = keys.clone();
            sorted.sort_unstable_by_key(|key| (key.island, key.level, key.sequence));
            // Shuffled, as the gather's stretches may give them.
            for k in (1..keys.len()).rev() {
                keys.swap(k, rng.random_range(0..=k));
            }
            sort_keys(&mut keys, &touches, &mut scratch);
            assert_eq!(keys.len(), sorted.len(), "round {round}: contacts lost or added");
            for (k, &place) in scratch.sorted_places().iter().enumerate() {
                assert_eq!(keys[place as usize], sorted[k], "round {round}: sorted contact {k} misplaced");
            }
            let level = |key: &OrderKey| (key.island, key.level);
            assert!(keys.windows(2).all(|w| level(&w[0]) <= level(&w[1])), "round {round}: levels out of order");
            let bodies = |key: &OrderKey| touches[key.sequence as usize].key.bodies;
            let mut seen = std::collections::HashSet::new();
            for (k, key) in keys.iter().enumerate() {
                let starts = k == 0 || bodies(&keys[k - 1]) != bodies(key);
                assert!(!starts || seen.insert(bodies(key)), "round {round}: a pair's contacts split");
            }
            // Pairs in order, one entry each, and where each level's waiting pairs start.
            let mut pairs: Vec<(OrderKey, (u32, u32))> = Vec::new();
            for key in &keys {
                if pairs.last().is_none_or(|(_, last)| *last != bodies(key)) {
                    pairs.push((*key, bodies(key)));
                }
            }
            let shares = |a: (u32, u32), b: (u32, u32)| a.0 == b.0 || a.0 == b.1 || a.1 == b.0 || a.1 == b.1;
            for w in pairs.windows(2) {
                if level(&w[0].0) != level(&w[1].0) || !shares(w[0].1, w[1].1) {
                    continue;
                }
                // Only the waiting pairs placed at the level's end may still share: from the
                // first such pair on, the rest of the level is in the narrow phase's order.
                let rest: Vec<u32> =
                    pairs.iter().filter(|(key, _)| level(key) == level(&w[1].0)).map(|(key, _)| key.sequence).collect();
                let from = rest.iter().position(|&s| s == w[1].0.sequence).unwrap();
                assert!(rest[from..].is_sorted(), "round {round}: pairs sharing a body placed together mid-level");
            }
            // And they are few: fewer than half as many as in the narrow phase's order.
            let shared = |pairs: &[(u32, u32)]| pairs.windows(2).filter(|w| shares(w[0], w[1])).count();
            let mut before: Vec<(u32, u32)> = sorted.iter().map(bodies).collect();
            before.dedup();
            let after: Vec<(u32, u32)> = pairs.iter().map(|(_, pair)| *pair).collect();
            totals.0 += shared(&before);
            totals.1 += shared(&after);
        }
        assert!(2 * totals.1 < totals.0, "consecutive pairs sharing a body: {} before, {} after", totals.0, totals.1);
    }
}
