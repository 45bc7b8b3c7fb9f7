//! Sleeping (docs/model.md §8, our choice): islands at rest cost nothing until something disturbs them.
//!
//! Before a step, [`prepare`] wakes every sleeping island whose state was changed between
//! steps and gives the step a body table in which sleeping bodies are static: they neither move
//! nor take impulses, and pairs of them are never tested. After the step, [`run`] wakes the
//! sleeping islands an awake body touches, advances each awake body's still-time, and puts to
//! sleep every island whose bodies have all been still for `sleep.time`. Everything runs
//! serially in slot order, so results do not depend on the thread count.

use glam::DVec2;
use hecs::World;

use super::{BodyRecord, SleepQuery, StateQuery, StepContext, find, union};
use crate::components::{RigidState, Sleep, SpawnOrder};

/// What [`prepare`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Prepared {
    /// Dynamic bodies awake for this step.
    pub awake: usize,
    /// Dynamic bodies asleep for this step.
    pub asleep: usize,
    /// Bodies woken because their state changed between steps.
    pub woken: usize,
}

/// Before a step: wakes the islands of sleeping bodies whose state changed since they fell
/// asleep, then fills `step_bodies` with `bodies`, sleeping ones made static (no motion,
/// infinite mass). `tags` is scratch;
/// `states` and `sleeps` are the step's prepared queries, through which each body is read.
pub(crate) fn prepare(
    world: &mut World,
    bodies: &[BodyRecord],
    step_bodies: &mut Vec<BodyRecord>,
    (tags, states, sleeps): (&mut Vec<u64>, &mut StateQuery, &mut SleepQuery),
    last_bounds: &[(DVec2, DVec2)],
) -> Prepared {
    tags.clear();
    // A moving kinematic body wakes the sleeping bodies its last swept bounds reach before it
    // moves into them (to the step, a sleeping body is static, and two bodies of infinite mass
    // cannot push each other).
    if last_bounds.len() == bodies.len() {
        let overlap = |(l1, h1): (DVec2, DVec2), (l2, h2): (DVec2, DVec2)| {
            l1.x <= h2.x && l2.x <= h1.x && l1.y <= h2.y && l2.y <= h1.y
        };
        for (k, _) in bodies.iter().enumerate().filter(|(_, b)| b.kinematic && moving(world, b.entity)) {
            for (s, _) in bodies.iter().enumerate().filter(|(_, b)| !b.is_static) {
                if overlap(last_bounds[k], last_bounds[s])
                    && let Some(tag) = island(world, bodies[s].entity)
                {
                    tags.push(tag);
                }
            }
        }
    }
    // Each body's components through prepared views: no per-call lookup and borrow.
    {
        let (mut state_query, mut sleep_query) = (states.0.query(world), sleeps.0.query(world));
        let (mut state_view, mut sleep_view) = (state_query.view(), sleep_query.view());
        for body in bodies.iter().filter(|b| !b.is_static) {
            if let Some(sleep) = sleep_view.get_mut(body.entity)
                && let Some(tag) = sleep.island
                && let Some(state) = state_view.get_mut(body.entity)
                && changed(sleep, state)
            {
                tags.push(tag);
            }
        }
    }
    tags.sort_unstable();
    tags.dedup();
    let mut prepared = Prepared::default();
    for &tag in tags.iter() {
        prepared.woken += wake_island(world, bodies, tag);
    }
    step_bodies.clear();
    step_bodies.extend_from_slice(bodies);
    // A moving kinematic body keeps the step running (it wakes what it touches).
    prepared.awake += step_bodies.iter().filter(|b| b.kinematic && moving(world, b.entity)).count();
    let mut sleep_view = sleeps.0.view_mut(world);
    for record in step_bodies.iter_mut().filter(|b| !b.is_static) {
        if sleep_view.get_mut(record.entity).is_some_and(|sleep| sleep.is_asleep()) {
            record.is_static = true;
            record.asleep = true;
            record.inverse_mass = 0.0;
            record.inverse_inertia = 0.0;
            prepared.asleep += 1;
        } else {
            prepared.awake += 1;
        }
    }
    prepared
}

/// Whether a body has a velocity.
fn moving(world: &World, entity: hecs::Entity) -> bool {
    world.get::<&RigidState>(entity).is_ok_and(|s| s.linear_velocity != DVec2::ZERO || s.angular_velocity != 0.0)
}

/// Whether a sleeping body's state differs from the one it fell asleep with.
fn changed(sleep: &Sleep, state: &RigidState) -> bool {
    state.position != sleep.pose.0
        || state.angle != sleep.pose.1
        || state.linear_velocity != DVec2::ZERO
        || state.angular_velocity != 0.0
}

/// Wakes every body sleeping in island `tag`; returns how many.
pub(crate) fn wake_island(world: &mut World, bodies: &[BodyRecord], tag: u64) -> usize {
    let mut woken = 0;
    for body in bodies {
        if let Ok(mut sleep) = world.get::<&mut Sleep>(body.entity)
            && sleep.island == Some(tag)
        {
            *sleep = Sleep::default();
            woken += 1;
        }
    }
    woken
}

/// The island `entity` sleeps in, if it sleeps.
fn island(world: &World, entity: hecs::Entity) -> Option<u64> {
    world.get::<&Sleep>(entity).ok().and_then(|s| s.island)
}

/// After a step (its last narrow phase describes the final poses): wakes sleeping islands that
/// an awake body touches, advances the still-time of awake bodies, and puts to sleep the
/// islands that have been still long enough. `ctx.bodies` is the step's table (sleeping bodies
/// static); bodies woken here stay static until the step ends.
pub fn run(ctx: &mut StepContext<'_>) {
    let settings = ctx.settings.sleep;
    if !settings.enabled {
        ctx.profile.counters.skipped_stages += 1;
        return;
    }
    let buffers = &mut *ctx.buffers;
    let count = ctx.bodies.len();
    // Who is dynamic-and-awake this step, who sleeps (static in the step's table but dynamic).
    buffers.sleeping.clear();
    let mut sleeps = buffers.sleep_query.0.view_mut(ctx.world);
    buffers.sleeping.extend(ctx.bodies.iter().map(|b| sleeps.get_mut(b.entity).is_some_and(|sleep| sleep.is_asleep())));
    // Dynamic and awake; a moving kinematic body wakes what it touches too.
    let states = &buffers.states;
    let awake_or_driven = |i: usize| {
        let (body, state) = (&ctx.bodies[i], &states[i]);
        !body.is_static || (body.kinematic && (state.linear_velocity != DVec2::ZERO || state.angular_velocity != 0.0))
    };
    let awake = |i: usize| !ctx.bodies[i].is_static;
    // 1. Wake the sleeping islands an awake body touches.
    buffers.wake_tags.clear();
    for slot in buffers.pair_slots[..buffers.candidate_pairs.len()].iter().filter(|slot| slot.colliding()) {
        let (a, b) = slot.body_indices();
        for (sleeper, other) in [(a, b), (b, a)] {
            if buffers.sleeping[sleeper]
                && awake_or_driven(other)
                && let Some(tag) = island(ctx.world, ctx.bodies[sleeper].entity)
            {
                buffers.wake_tags.push(tag);
            }
        }
    }
    buffers.wake_tags.sort_unstable();
    buffers.wake_tags.dedup();
    for k in 0..buffers.wake_tags.len() {
        let woken = wake_island(ctx.world, ctx.bodies, buffers.wake_tags[k]);
        ctx.profile.counters.woken_bodies += woken as u64;
    }
    buffers.woke_in_step = !buffers.wake_tags.is_empty();
    // 2. Still-time of the awake bodies, from their velocities at the end of the step.
    let dt = buffers.step_length;
    for i in (0..count).filter(|&i| awake(i)) {
        let state = &buffers.states[i];
        let speed = state.linear_velocity.length() + ctx.bodies[i].radius * state.angular_velocity.abs();
        if let Ok(mut sleep) = ctx.world.get::<&mut Sleep>(ctx.bodies[i].entity) {
            sleep.still_for = if speed <= settings.speed { sleep.still_for + dt } else { 0.0 };
        }
    }
    // 3. Islands of the awake bodies over the touching pairs at the final poses; an island
    //    touching a body woken above stays awake (the two will sleep together later).
    // (Over the islands stage's own array: its kept islands are no longer what it found.)
    buffers.island_inputs.1.clear();
    let island_of = &mut buffers.island_of;
    island_of.clear();
    island_of.extend(0..count as u32);
    buffers.island_still.clear();
    buffers.island_still.resize(count, true);
    for slot in buffers.pair_slots[..buffers.candidate_pairs.len()].iter().filter(|slot| slot.colliding()) {
        let (a, b) = slot.bodies;
        if awake(a as usize) && awake(b as usize) {
            union(island_of, a, b);
        }
    }
    for slot in buffers.pair_slots[..buffers.candidate_pairs.len()].iter().filter(|slot| slot.colliding()) {
        let (a, b) = slot.body_indices();
        for (body, other) in [(a, b), (b, a)] {
            if awake(body) && buffers.sleeping[other] {
                // `other` was woken in part 1 (or sleeps in an island woken there).
                let root = find(island_of, body as u32) as usize;
                buffers.island_still[root] = false;
            }
        }
    }
    for i in (0..count).filter(|&i| awake(i)) {
        let root = find(island_of, i as u32) as usize;
        let still = ctx.world.get::<&Sleep>(ctx.bodies[i].entity).is_ok_and(|s| s.still_for >= settings.time);
        if !still {
            buffers.island_still[root] = false;
        }
    }
    // 4. Put the still islands to sleep: velocities zero, pose recorded, island tagged by the
    //    spawn order of its first body.
    for i in (0..count).filter(|&i| awake(i)) {
        let root = find(island_of, i as u32) as usize;
        if !buffers.island_still[root] {
            continue;
        }
        let tag = ctx.world.get::<&SpawnOrder>(ctx.bodies[root].entity).map_or(root as u64, |order| order.0);
        let state = &mut buffers.states[i];
        state.linear_velocity = DVec2::ZERO;
        state.angular_velocity = 0.0;
        if let Ok(mut sleep) = ctx.world.get::<&mut Sleep>(ctx.bodies[i].entity) {
            *sleep = Sleep { still_for: sleep.still_for, island: Some(tag), pose: (state.position, state.angle) };
        }
    }
}
