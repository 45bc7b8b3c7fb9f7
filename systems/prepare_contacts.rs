//! Prepare contacts: one solver contact per contact of the last narrow phase (and one
//! overlap-recovery contact per pair whose curves cross), with lever arms, effective masses,
//! μ by the max rule, the seed's contact restitution at its depth, and the impulses it carried
//! last sub-step (warm start); sorted from the ground up. Runs once per sub-step, before the
//! retry loop, so a retried sub-step solves the same contacts.

use glam::DVec2;
use rayon::prelude::*;

use super::{BodyRecord, PairSlot, StepContext, TouchRange};
use crate::components::Material;
use crate::components::RigidState;
use crate::dynamics::laws::{combine_restitution, contact_friction, contact_restitution};
use crate::dynamics::solver::{
    CachedImpulse, ContactKey, HEAVY_ON_LIGHT, PATCH_END, RECOVERY_ORDINAL, SolverContact, arms_along, effective_mass,
    prepare_patches,
};
use crate::simulation::{SimulationSettings, SolverSettings};

/// Where a contact touches: point, normal, depth into the band and the two tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    key: ContactKey,
    /// The segments `(A, B)` it lies on.
    segments: (u32, u32),
    point: DVec2,
    normal: DVec2,
    /// Penetration into the combined band, `δ = λ_A + λ_B − d` (beyond the band for crossings).
    penetration: f64,
    /// Combined band `λ_A + λ_B` (floored).
    band: f64,
    /// Unfloored tolerances `(λ_A, λ_B)`, for friction.
    raw_lambda: (f64, f64),
    /// Global parameters `(u_A, u_B)`, for events.
    parameters: (f64, f64),
    /// Whether the next touch is the other end of this one's flat patch (set by
    /// [`reduce_manifold`]).
    patch_with_next: bool,
}

/// Fills `solver_contacts` from the live pair slots. A slot reduces its manifold only when the
/// manifold changed since its last reduction (a query, or its contacts evaluated again) or it
/// was not prepared last time: a carried pair copies its touches from the last preparation's
/// store (a still structure's every pair, every sub-step). The touches are written pair after
/// pair into one store, kept until the next preparation. Where the store is kept as it is and
/// nothing but the bodies' positions has changed since the last preparation, its contacts are
/// refreshed where they lie ([`Builder::refresh`]).
///
/// The slots' touches and solving-order keys are gathered stretch by stretch ([`TouchChunk`])
/// on the pool and written into the store there ([`Placed`]), the keys sorted on one thread,
/// and the contacts built from the sorted keys on the pool again. Every stretch and contact is
/// the same whichever thread does it, so the results are the same bit for bit for any thread
/// count.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let pool = ctx.pool.filter(|_| buffers.candidate_pairs.len() >= PARALLEL_SLOTS);
    let builder = Builder::new(ctx.bodies, (&buffers.states, &buffers.levels), ctx.settings);
    let generation = buffers.touch_store.1;
    let now = generation + 1;
    let live = &mut buffers.pair_slots[..buffers.candidate_pairs.len()];
    // Where every pair keeps its touches where they lie, one after the other (a still
    // structure's every preparation), the store is the one this preparation would write: it is
    // kept as it is instead of copied.
    let mut end = 0;
    let in_place = live.iter().filter(|slot| slot.solvable(ctx.bodies)).all(|slot| {
        let kept = slot.touches.filter(|kept| kept.generation == generation && kept.start == end);
        end += kept.map_or(0, |kept| kept.len);
        kept.is_some()
    }) && end as usize == buffers.touch_store.0.len();
    // The bodies' masses, materials, levels and islands as the last preparation read them (only
    // a store kept in place is refreshed: another preparation forgets them).
    let same_bodies = if in_place {
        remember_bodies(ctx.bodies, &buffers.levels, &buffers.island_of, &mut buffers.prepared_bodies)
    } else {
        buffers.prepared_bodies.clear();
        false
    };
    // The last preparation's contacts, in solving order, are those of this store then.
    let refresh = in_place
        && same_bodies
        && ctx.contact_hook.is_none()
        && buffers.solver_contacts.len() == buffers.touch_store.0.len()
        && buffers.prepared_generation == generation;
    ctx.profile.counters.refreshed_preparations += u64::from(refresh);
    if refresh {
        for slot in live.iter_mut().filter(|slot| slot.solvable(ctx.bodies)) {
            ctx.profile.counters.recovery_contacts += u64::from(slot.recovery.is_some());
            if let Some(kept) = slot.touches.as_mut() {
                kept.generation = now;
            }
        }
        let refresh = |contact: &mut SolverContact| *contact = builder.refresh(contact);
        if let Some(pool) = pool.filter(|_| buffers.solver_contacts.len() > BUILD_CONTACTS) {
            let contacts = &mut buffers.solver_contacts;
            pool.install(|| contacts.par_iter_mut().with_min_len(BUILD_CONTACTS).for_each(refresh));
        } else {
            buffers.solver_contacts.iter_mut().for_each(refresh);
        }
    } else {
        let gather = Gather {
            bodies: ctx.bodies,
            levels: &buffers.levels,
            island_of: &buffers.island_of,
            store: &buffers.touch_store.0,
            generation,
            in_place,
            min_band: ctx.settings.min_band,
            place: None,
        };
        // Each stretch of slots gathers its touches (copied, reduced, or where they lie) and
        // their keys, then the stretches are joined in slot order. On one thread the slots are
        // one stretch.
        let per_chunk = if pool.is_some() { SLOTS_PER_CHUNK } else { live.len().max(1) };
        let count = live.len().div_ceil(per_chunk);
        let chunks = &mut buffers.touch_chunks;
        if chunks.len() < count {
            chunks.resize_with(count, TouchChunk::default);
        }
        let chunks = &mut chunks[..count];
        // One stretch places its slots' touches as it goes (they start the store).
        let gather = Gather { place: (count == 1).then_some(now), ..gather };
        if let Some(pool) = pool.filter(|_| count > 1) {
            pool.install(|| {
                live.par_chunks_mut(per_chunk).zip(chunks.par_iter_mut()).enumerate().for_each(
                    |(c, (slots, chunk))| {
                        gather.chunk(c * per_chunk, slots, chunk);
                    },
                );
            });
        } else {
            for (c, (slots, chunk)) in live.chunks_mut(per_chunk).zip(chunks.iter_mut()).enumerate() {
                gather.chunk(c * per_chunk, slots, chunk);
            }
        }
        let (next, keys) = (&mut buffers.next_touch_store, &mut buffers.contact_keys);
        let mut modified = false;
        if let [chunk] = chunks {
            // Its touches and keys are the store's and the order's as they are: swapped, not
            // copied.
            next.clear();
            if !in_place {
                std::mem::swap(next, &mut chunk.touches);
            }
            keys.clear();
            std::mem::swap(keys, &mut chunk.keys);
            ctx.profile.counters.recovery_contacts += chunk.recoveries;
            modified = chunk.modified;
        } else {
            // Each stretch's place in the store, then its touches, keys and slots' ranges
            // written there on the pool (the buffers keep their length, the store's from the
            // preparation before last and the keys' from the last, so only what they lack is
            // filled first).
            let mut total = 0;
            for chunk in chunks.iter_mut() {
                chunk.offset = total;
                total += chunk.keys.len() as u32;
                ctx.profile.counters.recovery_contacts += chunk.recoveries;
                modified |= chunk.modified;
            }
            fit(keys, total as usize, OrderKey::default());
            match chunks.iter().find_map(|chunk| chunk.touches.first()) {
                Some(&filler) if !in_place => fit(next, total as usize, filler),
                _ => next.clear(),
            }
            let placed = Placed { bodies: ctx.bodies, now, per_chunk };
            if let Some(pool) = pool {
                pool.install(|| placed.write(live, chunks, (next, keys), true));
            } else {
                placed.write(live, chunks, (next, keys), false);
            }
        }
        if !in_place {
            std::mem::swap(&mut buffers.touch_store.0, &mut buffers.next_touch_store);
        }
        sort_keys(&mut buffers.contact_keys, &buffers.touch_store.0, &mut buffers.order_scratch);
        let slots = &buffers.pair_slots[..];
        let touches = &buffers.touch_store.0;
        let build = |key: &OrderKey| {
            let mut contact = builder.contact(&touches[key.sequence as usize], key);
            // The contact hook's friction and restitution, where it set them.
            if modified {
                let (friction, restitution) = slots[key.slot as usize].modified;
                if let Some(mu) = friction {
                    contact.friction = mu;
                }
                if let Some(e) = restitution {
                    (contact.restitution, contact.push_restitution) = (e, e);
                }
            }
            contact
        };
        let (keys, contacts) = (&buffers.contact_keys, &mut buffers.solver_contacts);
        if let Some(pool) = pool.filter(|_| keys.len() > BUILD_CONTACTS) {
            pool.install(|| keys.par_iter().with_min_len(BUILD_CONTACTS).map(build).collect_into_vec(contacts));
        } else {
            contacts.clear();
            contacts.extend(keys.iter().map(build));
        }
    }
    buffers.touch_store.1 = now;
    buffers.prepared_generation = now;
    let statics = Statics {
        bodies: ctx.bodies,
        levels: &buffers.levels,
        island_of: &buffers.island_of,
        gravity: ctx.settings.gravity,
    };
    let scratch = (&mut buffers.loads, &mut buffers.supports);
    finish(&mut buffers.solver_contacts, &buffers.contact_cache, &statics, scratch, pool);
}

/// `buffer` at `len` entries: cut, or grown with `filler` (every entry is then written).
fn fit<T: Copy>(buffer: &mut Vec<T>, len: usize, filler: T) {
    buffer.truncate(len);
    buffer.resize(len, filler);
}

/// Where the stretches of a gather go in the new store: each slot's range, its touches (unless
/// the store is kept in place) and its keys, the keys' sequences made the store's.
struct Placed<'a> {
    bodies: &'a [BodyRecord],
    now: u64,
    per_chunk: usize,
}

impl Placed<'_> {
    /// Writes `chunks` (whose offsets are set), the stretches of `slots`, into `touches` and
    /// `keys` (theirs from the first chunk's offset on; `touches` empty where kept in place),
    /// halves joined on the current pool where `parallel`.
    fn write(
        &self,
        slots: &mut [PairSlot],
        chunks: &[TouchChunk],
        (touches, keys): (&mut [Touch], &mut [OrderKey]),
        parallel: bool,
    ) {
        if parallel && chunks.len() > 1 {
            let middle = chunks.len() / 2;
            let at = (chunks[middle].offset - chunks[0].offset) as usize;
            let (slots_first, slots_second) = slots.split_at_mut((middle * self.per_chunk).min(slots.len()));
            let (keys_first, keys_second) = keys.split_at_mut(at);
            let (touches_first, touches_second) = touches.split_at_mut(at.min(touches.len()));
            let (first, second) = chunks.split_at(middle);
            rayon::join(
                || self.write(slots_first, first, (touches_first, keys_first), true),
                || self.write(slots_second, second, (touches_second, keys_second), true),
            );
            return;
        }
        let base = chunks.first().map_or(0, |chunk| chunk.offset);
        for (slots, chunk) in slots.chunks_mut(self.per_chunk).zip(chunks) {
            let from = (chunk.offset - base) as usize;
            let to = from + chunk.keys.len();
            if !touches.is_empty() {
                touches[from..to].copy_from_slice(&chunk.touches);
            }
            for (key, gathered) in keys[from..to].iter_mut().zip(&chunk.keys) {
                *key = OrderKey { sequence: gathered.sequence + chunk.offset, ..*gathered };
            }
            for (slot, &(start, len)) in slots.iter_mut().zip(&chunk.ranges) {
                if slot.solvable(self.bodies) {
                    slot.touches = Some(TouchRange { start: chunk.offset + start, len, generation: self.now });
                }
            }
        }
    }
}

/// Slots a stretch of the gather holds on more than one thread (not tuned: the landing pile of
/// 500 blobs has about 27 stretches a sub-step, the base-40 pyramid about 37).
const SLOTS_PER_CHUNK: usize = 64;

/// Fewer live pair slots than this are prepared on the step's thread alone: the landing pile of
/// 100 blobs (about 280 slots a sub-step) prepared in 0.20–0.23 ms a step on the step's thread
/// against 0.24–0.29 on two (steps 61–80, three alternating rounds), the pile of 500 (about
/// 1,700) in 0.90–0.96 either way, and the base-40 pyramid (2,380 slots with six contacts
/// each) in 0.52 ms on two threads against 0.72 on one (docs/performance.md).
const PARALLEL_SLOTS: usize = 512;

/// Contacts are built or refreshed on the pool in stretches of at least this many.
const BUILD_CONTACTS: usize = 64;

/// Where a contact stands in solving order: island by island, each from the ground up, pair by
/// pair (a patch's two ends together); the `sequence` is its touch's place in the store (the
/// narrow phase's order), unique, so the order is deterministic. `slot` is its pair's slot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct OrderKey {
    island: u32,
    level: u32,
    sequence: u32,
    slot: u32,
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
fn sort_keys(keys: &mut Vec<OrderKey>, touches: &[Touch], scratch: &mut OrderScratch) {
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

/// What one stretch of [`SLOTS_PER_CHUNK`] slots gathered for the preparation: the touches it
/// adds to the store, their keys, each slot's `(start, len)` among them, and after the join its
/// offset in the store. Kept in the step's buffers (no allocation once grown).
#[derive(Debug, Default)]
pub(crate) struct TouchChunk {
    touches: Vec<Touch>,
    keys: Vec<OrderKey>,
    ranges: Vec<(u32, u32)>,
    offset: u32,
    /// Recovery contacts among its slots (for the profile).
    recoveries: u64,
    /// Whether the contact hook changed the friction or restitution of any of its slots.
    modified: bool,
}

/// Read-only inputs of the gather ([`Gather::chunk`]).
struct Gather<'a> {
    bodies: &'a [BodyRecord],
    levels: &'a [u32],
    island_of: &'a [u32],
    /// The last preparation's store and its generation.
    store: &'a [Touch],
    generation: u64,
    /// Whether every pair keeps its touches where they lie in `store`.
    in_place: bool,
    min_band: f64,
    /// The new store's generation, where the stretch is the only one and so places its slots'
    /// touches as it goes (its starts are theirs in the new store).
    place: Option<u64>,
}

impl Gather<'_> {
    /// Gathers the touches and keys of `slots`, the slots from `first` on: each solvable slot's
    /// kept touches where they lie (in place), copied from the last store (kept from its
    /// generation), or its manifold reduced.
    fn chunk(&self, first: usize, slots: &mut [PairSlot], chunk: &mut TouchChunk) {
        chunk.touches.clear();
        chunk.keys.clear();
        chunk.ranges.clear();
        (chunk.recoveries, chunk.modified) = (0, false);
        let mut start = 0;
        for (k, slot) in slots.iter_mut().enumerate() {
            if !slot.solvable(self.bodies) {
                chunk.ranges.push((start, 0));
                continue;
            }
            chunk.recoveries += u64::from(slot.recovery.is_some());
            chunk.modified |= slot.modified != (None, None);
            let len = match slot.touches {
                Some(kept) if self.in_place => kept.len,
                Some(kept) if kept.generation == self.generation => {
                    chunk.touches.extend_from_slice(&self.store[kept.start as usize..(kept.start + kept.len) as usize]);
                    kept.len
                }
                _ => {
                    let from = chunk.touches.len();
                    reduced_touches(slot, self.min_band, &mut chunk.touches);
                    (chunk.touches.len() - from) as u32
                }
            };
            let key = OrderKey {
                slot: (first + k) as u32,
                ..order_key(self.bodies, (self.levels, self.island_of), slot.bodies)
            };
            chunk.keys.extend((start..start + len).map(|sequence| OrderKey { sequence, ..key }));
            chunk.ranges.push((start, len));
            if let Some(generation) = self.place {
                slot.touches = Some(TouchRange { start, len, generation });
            }
            start += len;
        }
    }
}

/// The island and level of a contact between `bodies` (its key's `sequence` and `slot` left 0).
fn order_key(bodies: &[BodyRecord], (levels, island_of): (&[u32], &[u32]), pair: (u32, u32)) -> OrderKey {
    OrderKey {
        island: super::contact_island(bodies, island_of, pair) as u32,
        level: levels[pair.0 as usize].min(levels[pair.1 as usize]),
        ..OrderKey::default()
    }
}

/// Warm-starts `contacts` (in solving order) from `cache`, works out their patches' blocks and,
/// where a contact found nothing cached, the statics estimate of the islands that are all cold.
/// Each contact's warm start and block depend on it and its patch's other end alone, so stretches
/// of the contacts that split no patch are finished on the pool when `parallel`, the same bit for
/// bit whatever the thread count; the estimate, rare, is serial.
fn finish(
    contacts: &mut [SolverContact],
    cache: &[CachedImpulse],
    statics: &Statics<'_>,
    (loads, supports): (&mut Vec<f64>, &mut Vec<u32>),
    parallel: Option<&rayon::ThreadPool>,
) {
    debug_assert!(cache.windows(2).all(|pair| pair[0].key <= pair[1].key), "the cache is sorted by key");
    let stretch = |contacts: &mut [SolverContact]| {
        let cold = warm_start(contacts, cache);
        prepare_patches(contacts);
        cold
    };
    let cold = match parallel {
        Some(pool) if contacts.len() > 2 * BUILD_CONTACTS => pool.install(|| by_patches(contacts, &stretch)),
        _ => stretch(contacts),
    };
    if cold {
        statics.estimate(contacts, loads, supports);
    }
}

/// `work` on stretches of `contacts` (in solving order, a patch's two ends adjacent) of at least
/// [`BUILD_CONTACTS`] that split no patch, joined on the pool; whether any returned `true`.
fn by_patches(contacts: &mut [SolverContact], work: &(impl Fn(&mut [SolverContact]) -> bool + Sync)) -> bool {
    if contacts.len() < 2 * BUILD_CONTACTS {
        return work(contacts);
    }
    let mut middle = contacts.len() / 2;
    while middle < contacts.len() && contacts[middle - 1].patch_with_next {
        middle += 1;
    }
    let (first, second) = contacts.split_at_mut(middle);
    let (a, b) = rayon::join(|| by_patches(first, work), || by_patches(second, work));
    a | b
}

/// What a body gives its contacts besides its position: its inverse mass and inertia, whether
/// it is fixed, its level and island, and its material. A preparation that finds every body's
/// as the last one left them may refresh its contacts where they lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PreparedBody {
    inverse: (f64, f64),
    is_static: bool,
    level: u32,
    island: u32,
    material: Material,
}

/// Whether every body's [`PreparedBody`] is as `prepared` holds it (NaN never is); `prepared`
/// is then what it is now.
fn remember_bodies(bodies: &[BodyRecord], levels: &[u32], island_of: &[u32], prepared: &mut Vec<PreparedBody>) -> bool {
    let now = bodies.iter().zip(levels).zip(island_of).map(|((body, &level), &island)| PreparedBody {
        inverse: (body.inverse_mass, body.inverse_inertia),
        is_static: body.is_static,
        level,
        island,
        material: body.material,
    });
    let same = prepared.len() == bodies.len() && levels.len() == bodies.len() && island_of.len() == bodies.len();
    if same && prepared.iter().zip(now.clone()).all(|(then, now)| *then == now) {
        return true;
    }
    prepared.clear();
    prepared.extend(now);
    false
}

/// Debug builds: the solver contacts of a still structure's preparation, built afresh from the
/// kept store in `out` (scratch `keys`, `loads` and `supports`), for the check that
/// refreshing them gave the same (`validate::after`).
#[cfg(debug_assertions)]
pub(crate) fn afresh(
    ctx: &StepContext<'_>,
    (out, keys, order): (&mut Vec<SolverContact>, &mut Vec<OrderKey>, &mut OrderScratch),
    scratch: (&mut Vec<f64>, &mut Vec<u32>),
) {
    let buffers = &*ctx.buffers;
    let builder = Builder::new(ctx.bodies, (&buffers.states, &buffers.levels), ctx.settings);
    keys.clear();
    keys.extend((0..).zip(&buffers.touch_store.0).map(|(sequence, touch)| OrderKey {
        sequence,
        ..order_key(ctx.bodies, (&buffers.levels, &buffers.island_of), touch.key.bodies)
    }));
    sort_keys(keys, &buffers.touch_store.0, order);
    out.clear();
    out.extend(keys.iter().map(|key| builder.contact(&buffers.touch_store.0[key.sequence as usize], key)));
    let statics = Statics {
        bodies: ctx.bodies,
        levels: &buffers.levels,
        island_of: &buffers.island_of,
        gravity: ctx.settings.gravity,
    };
    finish(out, &buffers.contact_cache, &statics, scratch, None);
}

/// Appends to `touches` the solver's touches of `slot`: its manifold's contacts and its recovery
/// contact (bands floored at `min_band`), reduced to each flat patch's two ends
/// ([`reduce_manifold`]). They depend on the manifold, the recovery contact, the pair's bodies
/// (the keys) and `min_band`, so a slot keeps them while those are unchanged
/// (`PairSlot::touches`; checked in debug builds, `validate::after`).
pub(crate) fn reduced_touches(slot: &PairSlot, min_band: f64, touches: &mut Vec<Touch>) {
    let from = touches.len();
    let mut last_pair = None;
    let mut ordinal = 0;
    for contact in &slot.manifold().contacts {
        let segments = (contact.segment_a, contact.segment_b);
        ordinal = if last_pair == Some(segments) { ordinal + 1 } else { 0 };
        last_pair = Some(segments);
        let c = &contact.contact;
        touches.push(Touch {
            key: ContactKey { bodies: slot.bodies, segment_a: segments.0, segment_b: segments.1, ordinal },
            segments,
            point: c.point,
            normal: c.normal,
            penetration: c.penetration,
            band: c.lambda_a + c.lambda_b,
            raw_lambda: (c.raw_lambda_a, c.raw_lambda_b),
            parameters: (contact.u_a, contact.u_b),
            patch_with_next: false,
        });
    }
    if let Some(recovery) = slot.recovery {
        let raw_lambda = recovery.raw_lambda;
        let band = raw_lambda.0.max(min_band) + raw_lambda.1.max(min_band);
        touches.push(Touch {
            key: ContactKey {
                bodies: slot.bodies,
                segment_a: recovery.segment_a,
                segment_b: recovery.segment_b,
                ordinal: RECOVERY_ORDINAL,
            },
            segments: (recovery.segment_a, recovery.segment_b),
            point: recovery.point,
            normal: recovery.normal,
            penetration: band + recovery.depth,
            band,
            raw_lambda,
            parameters: (recovery.u_a, recovery.u_b),
            patch_with_next: false,
        });
    }
    // Reduced before the solver contacts are built: a flat overlap's inner points cost nothing
    // more.
    reduce_manifold(touches, from);
}

/// A cold start's estimate of the forces that hold bodies up: each body's weight plus the load
/// from above, shared equally by the contacts it rests on and passed down level by level.
struct Statics<'a> {
    bodies: &'a [BodyRecord],
    levels: &'a [u32],
    island_of: &'a [u32],
    gravity: DVec2,
}

impl Statics<'_> {
    /// The body a contact holds up (the one further from the ground) and the one below, with the
    /// normal oriented from the lower to the upper; `None` for a contact within one level or
    /// off the ground.
    fn support(&self, contact: &SolverContact) -> Option<(usize, usize, DVec2)> {
        let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
        let (la, lb) = (self.levels[a], self.levels[b]);
        if la == lb || la.max(lb) == super::islands::UNGROUNDED {
            return None;
        }
        Some(if la > lb { (a, b, contact.normal) } else { (b, a, -contact.normal) })
    }

    /// The island of a contact.
    fn island(&self, contact: &SolverContact) -> usize {
        super::contact_island(self.bodies, self.island_of, contact.key.bodies)
    }

    /// Sets the warm-start force of the contacts of every island whose contacts are all cold
    /// (a structure spawned at rest: otherwise the first sub-steps' sweeps, starting from
    /// nothing, let a tall one sink, and what they push back adds up) from the loads. An island
    /// with any force cached is left to its warm start. Contacts come sorted from the ground
    /// up, so walking them backwards finishes each level's loads before they are passed down.
    fn estimate(&self, contacts: &mut [SolverContact], loads: &mut Vec<f64>, supports: &mut Vec<u32>) {
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

/// Normals closer than this (cosine; 1.8°) belong to one flat patch of contact.
const SAME_NORMAL_COS: f64 = 0.9995;

/// Reduces the touches of one pair to the two ends of each group of nearly parallel normals (a
/// flat-on-flat overlap is reported by every leaf pair along it, several times at shared
/// joints): for a rigid body in 2-D the two extreme points of a flat patch carry any load its
/// inner points could, and two points per patch let the solver converge as a two-point
/// manifold does. Order is kept deterministic (first occurrence of each group). Each patch's
/// ends are keyed as the pair's `k`-th patch's low and high end ([`ContactKey`]), whichever
/// leaf pairs found them.
///
/// The pair's touches are `touches[from..]`.
fn reduce_manifold(touches: &mut Vec<Touch>, from: usize) {
    // The touches not yet grouped are `touches[read..]`; those kept so far, `touches[from..kept]`
    // (never past `read`: a group keeps at most as many touches as it has).
    let (mut read, mut kept, mut patches) = (from, from, 0);
    while read < touches.len() {
        let normal = touches[read].normal;
        // Gather the group behind its first member.
        let mut group_end = read + 1;
        for j in read + 1..touches.len() {
            if touches[j].normal.dot(normal) >= SAME_NORMAL_COS {
                touches.swap(group_end, j);
                group_end += 1;
            }
        }
        let across = normal.perp();
        let (mut low, mut high) = (read, read);
        let (mut lowest, mut highest) = (touches[read].point.dot(across), touches[read].point.dot(across));
        for (k, touch) in touches.iter().enumerate().take(group_end).skip(read + 1) {
            let along = touch.point.dot(across);
            if along < lowest {
                (low, lowest) = (k, along);
            }
            if along > highest {
                (high, highest) = (k, along);
            }
        }
        let (mut keep_low, mut keep_high) = (touches[low], touches[high]);
        keep_low.patch_with_next = high != low;
        touches[kept] = keep_low;
        kept += 1;
        if high != low {
            let end = |ordinal| ContactKey { segment_a: PATCH_END, segment_b: patches, ordinal, ..keep_low.key };
            (touches[kept - 1].key, keep_high.key) = (end(0), end(1));
            touches[kept] = keep_high;
            kept += 1;
            patches += 1;
        }
        read = group_end;
    }
    touches.truncate(kept);
}

/// Copies last sub-step's forces into the contacts whose identity persists; `true` if some
/// contact found none (it is then *cold*). The cache is sorted by key, pair first;
/// the contacts come mostly pair by pair in pair order (the narrow phase's, within a level of
/// the solving order, where a pair that shares a body with the one before it may wait a few
/// places, [`sort_keys`]): each pair's cached forces are found by walking the cache forward
/// or a few entries back, then among them its contacts' (a pair further behind, or far ahead,
/// is searched for).
fn warm_start(contacts: &mut [SolverContact], cache: &[CachedImpulse]) -> bool {
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
struct Builder<'a> {
    bodies: &'a [BodyRecord],
    states: &'a [RigidState],
    levels: &'a [u32],
    settings: &'a SolverSettings,
}

impl<'a> Builder<'a> {
    /// The inputs of preparing the contacts of `bodies` at `states`, with their `levels`.
    fn new(
        bodies: &'a [BodyRecord],
        (states, levels): (&'a [RigidState], &'a [u32]),
        settings: &'a SimulationSettings,
    ) -> Self {
        Self { bodies, states, levels, settings: &settings.solver }
    }

    /// The solver contact of `touch` at the bodies' positions now, at its place in solving
    /// order (`key`).
    fn contact(&self, touch: &Touch, key: &OrderKey) -> SolverContact {
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
            friction: contact_friction(&ma.friction, touch.raw_lambda.0, &mb.friction, touch.raw_lambda.1),
            mu: (ma.friction.coefficient(touch.raw_lambda.0), mb.friction.coefficient(touch.raw_lambda.1)),
            restitution,
            push_restitution: contact_restitution(restitution, restitution_max, touch.penetration, touch.band),
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
    fn refresh(&self, contact: &SolverContact) -> SolverContact {
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

    use super::{OrderKey, OrderScratch, Touch, sort_keys, warm_start};
    use crate::dynamics::solver::{CachedImpulse, ContactKey, SolverContact};
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
