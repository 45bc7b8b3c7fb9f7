//! Prepare contacts: one solver contact per contact of the last narrow phase (and one
//! overlap-recovery contact per pair whose curves cross), with lever arms, effective masses,
//! μ by the max rule, the seed's contact restitution at its depth, and the impulses it carried
//! last sub-step (warm start); sorted from the ground up. Runs once per sub-step, before the
//! retry loop, so a retried sub-step solves the same contacts.

use glam::DVec2;
use rayon::prelude::*;

mod build;
mod manifold;
mod order;

use build::{Builder, Statics, warm_start};
pub(crate) use manifold::reduced_touches;
pub(crate) use order::{OrderKey, OrderScratch};
use order::{order_key, sort_keys};

use super::{BodyRecord, PairSlot, StepBuffers, StepContext, TouchRange};
use crate::components::Material;
use crate::dynamics::solver::{CachedImpulse, ContactKey, SolverContact, prepare_patches};

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
    /// [`reduced_touches`]).
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
    let pool = ctx.pool.filter(|_| ctx.buffers.candidate_pairs.len() >= PARALLEL_SLOTS);
    let now = ctx.buffers.touch_store.1 + 1;
    let in_place = store_in_place(ctx.bodies, ctx.buffers);
    // The bodies' masses, materials, levels and islands as the last preparation read them (only
    // a store kept in place is refreshed: another preparation forgets them).
    let buffers = &mut *ctx.buffers;
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
        && buffers.prepared_generation == buffers.touch_store.1;
    ctx.profile.counters.refreshed_preparations += u64::from(refresh);
    if refresh {
        refresh_contacts(ctx, pool, now);
    } else {
        let modified = gather_touches(ctx, pool, in_place, now);
        let buffers = &mut *ctx.buffers;
        sort_keys(&mut buffers.contact_keys, &buffers.touch_store.0, &mut buffers.order_scratch);
        build_contacts(ctx, pool, modified);
    }
    let buffers = &mut *ctx.buffers;
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

/// Whether every solvable slot keeps its touches where they lie in the store, one after the
/// other and all of it (a still structure's every preparation): the store is then the one this
/// preparation would write, and it is kept as it is instead of copied.
fn store_in_place(bodies: &[BodyRecord], buffers: &StepBuffers) -> bool {
    let generation = buffers.touch_store.1;
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let mut end = 0;
    live.iter().filter(|slot| slot.solvable(bodies)).all(|slot| {
        let kept = slot.touches.filter(|kept| kept.generation == generation && kept.start == end);
        end += kept.map_or(0, |kept| kept.len);
        kept.is_some()
    }) && end as usize == buffers.touch_store.0.len()
}

/// The last preparation's contacts refreshed where they lie ([`Builder::refresh`]): the store,
/// the bodies and the order are as it left them, only the positions moved. The slots' touches
/// move to generation `now`.
fn refresh_contacts(ctx: &mut StepContext<'_>, pool: Option<&rayon::ThreadPool>, now: u64) {
    let buffers = &mut *ctx.buffers;
    for slot in buffers.pair_slots[..buffers.candidate_pairs.len()].iter_mut().filter(|slot| slot.solvable(ctx.bodies))
    {
        ctx.profile.counters.recovery_contacts += u64::from(slot.recovery.is_some());
        if let Some(kept) = slot.touches.as_mut() {
            kept.generation = now;
        }
    }
    let builder = Builder::new(ctx.bodies, (&buffers.states, &buffers.levels), ctx.settings);
    let refresh = |contact: &mut SolverContact| *contact = builder.refresh(contact);
    let contacts = &mut buffers.solver_contacts;
    if let Some(pool) = pool.filter(|_| contacts.len() > BUILD_CONTACTS) {
        pool.install(|| contacts.par_iter_mut().with_min_len(BUILD_CONTACTS).for_each(refresh));
    } else {
        contacts.iter_mut().for_each(refresh);
    }
}

/// The new store and its solving-order keys (unsorted): each stretch of slots gathers its
/// touches (copied, reduced, or where they lie in a store kept `in_place`) and their keys, then
/// the stretches are joined in slot order. On one thread the slots are one stretch. Returns
/// whether the contact hook changed the friction or restitution of any slot.
fn gather_touches(ctx: &mut StepContext<'_>, pool: Option<&rayon::ThreadPool>, in_place: bool, now: u64) -> bool {
    let buffers = &mut *ctx.buffers;
    let gather = Gather {
        bodies: ctx.bodies,
        levels: &buffers.levels,
        island_of: &buffers.island_of,
        store: &buffers.touch_store.0,
        generation: buffers.touch_store.1,
        in_place,
        min_band: ctx.settings.min_band,
        place: None,
    };
    let live = &mut buffers.pair_slots[..buffers.candidate_pairs.len()];
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
            live.par_chunks_mut(per_chunk).zip(chunks.par_iter_mut()).enumerate().for_each(|(c, (slots, chunk))| {
                gather.chunk(c * per_chunk, slots, chunk);
            });
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
        // Each stretch's place in the store, then its touches, keys and slots' ranges written
        // there on the pool (the buffers keep their length, the store's from the preparation
        // before last and the keys' from the last, so only what they lack is filled first).
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
    modified
}

/// The solver contacts of the sorted keys: each written over one of the last preparation's (the
/// vector keeps its length; only what it lacks is filled first), with the contact hook's
/// friction and restitution where it set them (`modified`: it set some).
fn build_contacts(ctx: &mut StepContext<'_>, pool: Option<&rayon::ThreadPool>, modified: bool) {
    let buffers = &mut *ctx.buffers;
    let builder = Builder::new(ctx.bodies, (&buffers.states, &buffers.levels), ctx.settings);
    let slots = &buffers.pair_slots[..];
    let touches = &buffers.touch_store.0;
    let build = |(contact, key): (&mut SolverContact, &OrderKey)| {
        let hook = if modified { slots[key.slot as usize].modified } else { (None, None) };
        builder.write(contact, &touches[key.sequence as usize], key, hook);
    };
    let (keys, contacts) = (&buffers.contact_keys, &mut buffers.solver_contacts);
    fit(contacts, keys.len(), SolverContact::default());
    if let Some(pool) = pool.filter(|_| keys.len() > BUILD_CONTACTS) {
        pool.install(|| contacts.par_iter_mut().zip(keys.par_iter()).with_min_len(BUILD_CONTACTS).for_each(build));
    } else {
        contacts.iter_mut().zip(keys).for_each(build);
    }
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
                    // Most kept ranges of a pile are empty: nothing to copy.
                    if kept.len > 0 {
                        let range = kept.start as usize..(kept.start + kept.len) as usize;
                        chunk.touches.extend_from_slice(&self.store[range]);
                    }
                    kept.len
                }
                _ => {
                    let from = chunk.touches.len();
                    reduced_touches(slot, self.min_band, &mut chunk.touches);
                    (chunk.touches.len() - from) as u32
                }
            };
            // Most solvable pairs of a pile are near but not touching: their key is not worked out
            // (it would key no contact; in the landing pile of 500 that and the empty extensions
            // of the list of keys were 0.46 M instructions a step, 14 % of the preparation).
            if len > 0 {
                let key = OrderKey {
                    slot: (first + k) as u32,
                    ..order_key(self.bodies, (self.levels, self.island_of), slot.bodies)
                };
                chunk.keys.extend((start..start + len).map(|sequence| OrderKey { sequence, ..key }));
            }
            chunk.ranges.push((start, len));
            if let Some(generation) = self.place {
                slot.touches = Some(TouchRange { start, len, generation });
            }
            start += len;
        }
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
    out.extend(
        keys.iter().map(|key| builder.contact(&buffers.touch_store.0[key.sequence as usize], key, (None, None))),
    );
    let statics = Statics {
        bodies: ctx.bodies,
        levels: &buffers.levels,
        island_of: &buffers.island_of,
        gravity: ctx.settings.gravity,
    };
    finish(out, &buffers.contact_cache, &statics, scratch, None);
}
