//! The step driver: one step as sub-steps chosen by conservative advancement, each running
//! the tables of `systems/mod.rs` (and redone shorter on intersection), then gathering the
//! bodies' states before and scattering them after. It calls the systems only through the
//! tables.

use std::time::Instant;

use super::*;

/// Runs one step of length `dt`; `stale` forces detection at the current poses first.
pub fn run_step(ctx: &mut StepContext<'_>, dt: f64, stale: bool) {
    timed(ctx, Stage::GatherScatter, |ctx| gather_states(ctx, stale));
    ctx.buffers.step_length = dt;
    ctx.buffers.woke_in_step = false;
    ctx.buffers.previous_states.clone_from(&ctx.buffers.states);
    ctx.buffers.substep_time = ctx.time;
    let seed = ctx.settings.contact_model == ContactModel::SeedMicroCollisions;
    if stale {
        ctx.buffers.substep = dt;
        ctx.buffers.frozen.clear();
        ctx.buffers.frozen.resize(ctx.bodies.len(), true); // detect without moving
        ctx.buffers.detected_pairs = 0; // body slots may have changed: search everything
        ctx.buffers.phase_poses.clear(); // and measure no motion from the last phase
        ctx.buffers.enlarged_bounds.clear(); // and sweep again
        ctx.buffers.step_left = dt; // the step's first sub-step may take all of it
        run_table(ctx, &ADVANCE);
        if seed {
            run_table(ctx, &RESOLVE);
        }
        ctx.buffers.contact_cache.clear(); // slots may have changed: nothing to warm-start from
    }
    ctx.buffers.touched_pairs.clear();
    let floor = dt / f64::from(1u32 << ctx.settings.max_retry_depth.min(30));
    let mut remaining = dt;
    let mut substeps = 0;
    let quiet = std::mem::take(&mut ctx.buffers.quiet) && !stale;
    ctx.profile.counters.quiet_starts += u64::from(quiet && !seed);
    while remaining > 1e-12 * dt {
        let h = if seed {
            let h = advance_with_retry(ctx, remaining, floor, substeps);
            run_table(ctx, &RESOLVE);
            h
        } else {
            solve_and_advance(ctx, remaining, floor, substeps, quiet && substeps == 0)
        };
        substeps += 1;
        remaining -= h;
        timed(ctx, Stage::Commit, |ctx| record_touching(ctx.buffers));
        ctx.buffers.substep_time += h;
        ctx.profile.counters.substeps += 1;
    }
    timed(ctx, Stage::Commit, |ctx| {
        ctx.buffers.touched_pairs.sort_unstable();
        ctx.buffers.touched_pairs.dedup();
    });
    // Quiet: one sub-step, the whole step, no collision, and every moving body held by a
    // resting contact (`touched`: a body in flight may be about to strike something, which the
    // bound before the solve anticipates).
    let buffers = &*ctx.buffers;
    ctx.buffers.quiet = substeps == 1
        && !buffers.solver_contacts.iter().any(|contact| contact.collided)
        && buffers.touched.len() == ctx.bodies.len()
        && ctx.bodies.iter().zip(&buffers.touched).all(|(body, &touched)| touched || body.is_static);
    run_table(ctx, &FINISH);
    timed(ctx, Stage::GatherScatter, scatter_states);
}

/// Adds the pairs touching at the end of a sub-step to `touched_pairs`: from the narrow phase's
/// dense list where it wrote one for these slots (a pass over every slot is a cache miss or two a
/// pair: about 0.5 ms a step in the landing pile of 500), else from the slots.
fn record_touching(buffers: &mut StepBuffers) {
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let floors = &buffers.bound_floors;
    if floors.len() == live.len() {
        debug_assert!(
            live.iter()
                .zip(floors)
                .all(|(slot, floor)| slot.bodies == floor.bodies && slot.touching() == floor.touching),
            "the narrow phase's list says which pairs touch"
        );
        buffers.touched_pairs.extend(floors.iter().filter(|floor| floor.touching).map(|floor| floor.bodies));
    } else {
        buffers.touched_pairs.extend(live.iter().filter(|slot| slot.touching()).map(|slot| slot.bodies));
    }
}

/// Runs `block` on `ctx`, its time recorded as `stage`'s (the step's own blocks between the
/// systems' tables: every part of the step is in the profile).
fn timed<T>(ctx: &mut StepContext<'_>, stage: Stage, block: impl FnOnce(&mut StepContext<'_>) -> T) -> T {
    let start = Instant::now();
    let out = block(ctx);
    ctx.profile.record(stage, start.elapsed());
    out
}

/// Keeps what a retried sub-step starts from: the pairs already crossing, the states, and no
/// body held.
fn save_for_retry(ctx: &mut StepContext<'_>) {
    remember_overlaps(ctx);
    ctx.buffers.saved_states.clone_from(&ctx.buffers.states);
    ctx.buffers.frozen.clear();
    ctx.buffers.frozen.resize(ctx.bodies.len(), false);
}

/// Rounds of shortening a sub-step because the solved velocities move faster than the ones it
/// was chosen for; after them the retry guards the rest.
const MAX_BOUND_ROUNDS: u32 = 4;

/// Solver: one sub-step of solving, motion and detection, shortened when the solved velocities
/// would outrun the conservative bound and halved on intersection; returns its length. At the
/// retry limit the sub-step is accepted as it is (counted): the pair then overlaps, and its
/// recovery contact pushes it apart — no body is ever held with a velocity its position ignores.
///
/// The bound of the velocities before the solve ([`integrate::choose_substep`]) only anticipates
/// the bound of the solved ones, which is what keeps bodies apart. It is left out at a `quiet`
/// start, the first sub-step after a quiet step (one whole sub-step, no collision, every body
/// that can move held by a resting contact, and no action on a body since: a still structure's
/// every step, where it takes the whole step): the solve then takes what remains, and the solved
/// velocities' bound shortens it if anything has changed, a first time without counting against
/// [`MAX_BOUND_ROUNDS`] (docs/model.md §7).
fn solve_and_advance(ctx: &mut StepContext<'_>, remaining: f64, floor: f64, substeps: u32, quiet: bool) -> f64 {
    let mut h = if quiet {
        remaining
    } else {
        timed(ctx, Stage::SubstepBound, |ctx| integrate::choose_substep(ctx, remaining, floor, substeps))
    };
    ctx.buffers.substep = h;
    // PREPARE only reads the states: they may be saved before it.
    timed(ctx, Stage::Retry, save_for_retry);
    run_table(ctx, &PREPARE);
    // A quiet start's first shortening is not counted: it stands for the bound it left out.
    let mut bound_rounds = 0;
    let mut uncounted = quiet;
    // The first solve starts from the states just saved (PREPARE only reads them); a shortened
    // or retried one from what was saved.
    let mut first = true;
    loop {
        if !std::mem::take(&mut first) {
            timed(ctx, Stage::Retry, |ctx| ctx.buffers.states.clone_from(&ctx.buffers.saved_states));
        }
        ctx.buffers.substep = h;
        run_table(ctx, &SOLVE);
        // Once the step has used its sub-step budget the rest is taken at once (as in
        // `choose_substep`), so a step always ends.
        if bound_rounds < MAX_BOUND_ROUNDS && substeps < ctx.settings.max_substeps {
            let bound = timed(ctx, Stage::SubstepBound, |ctx| solved_motion_bound(ctx, h));
            if bound < h * (1.0 - 1e-9) {
                if !std::mem::take(&mut uncounted) {
                    bound_rounds += 1;
                }
                h = (bound * (1.0 - SHORTENING_MARGIN)).max(MIN_SUBSTEP_FRACTION * remaining);
                ctx.profile.counters.bound_shrinks += 1;
                continue;
            }
        }
        ctx.buffers.step_left = remaining - h;
        run_table(ctx, &ADVANCE);
        if !timed(ctx, Stage::Retry, |ctx| moving_pair_intersects(ctx)) {
            break;
        }
        if h > floor {
            h = (0.5 * h).max(floor);
            ctx.profile.counters.retries += 1;
        } else {
            ctx.profile.counters.retry_limit_hits += 1;
            break;
        }
    }
    timed(ctx, Stage::Commit, |ctx| commit_contacts(ctx, h));
    h
}

/// How much shorter than the bound of its solved velocities a shortened sub-step is taken. That
/// bound moves with the sub-step (the solve's impulses do), by about 3e-3 of the change in a
/// landing pile, so a sub-step shortened exactly to it failed its own test again by a hair, and
/// the solve ran up to [`MAX_BOUND_ROUNDS`] times for changes of 1e-5 to 1e-8 of `h`.
const SHORTENING_MARGIN: f64 = 1e-3;

/// Smallest sub-step as a fraction of what remains of the step.
const MIN_SUBSTEP_FRACTION: f64 = 1e-9;

/// The conservative bound for bodies moving as the integrator will move them after the solve:
/// touched bodies at `(v₀ + v)/2 + v_bias`, free ones along their parabola from `v₀`.
fn solved_motion_bound(ctx: &mut StepContext<'_>, h: f64) -> f64 {
    let buffers = &mut *ctx.buffers;
    buffers.motion_states.clone_from(&buffers.states);
    for (i, state) in buffers.motion_states.iter_mut().enumerate() {
        if buffers.touched[i] {
            let (start, bias) = (buffers.start_velocities[i], buffers.bias[i]);
            state.linear_velocity = 0.5 * (start.linear + state.linear_velocity) + bias.linear;
            state.angular_velocity = 0.5 * (start.angular + state.angular_velocity) + bias.angular;
        } else if !ctx.bodies[i].is_static {
            let acceleration = buffers.accelerations[i];
            state.linear_velocity -= acceleration.linear * h;
            state.angular_velocity -= acceleration.angular * h;
        }
    }
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let (motion, accelerations, margins) = (&buffers.motion_states, &buffers.accelerations, &buffers.margins);
    let pairs = (live, &buffers.bound_floors[..], buffers.nearest_gap);
    integrate::substep_bound(ctx.pool, ctx.bodies, (motion, accelerations, &mut buffers.motions), margins, pairs, h)
}

/// After a sub-step is accepted: counts its impulses, records its events, and keeps its
/// contacts' forces for the next sub-step's warm start.
fn commit_contacts(ctx: &mut StepContext<'_>, h: f64) {
    let buffers = &mut *ctx.buffers;
    buffers.contact_cache.clear();
    let time = buffers.substep_time + h;
    // In sorted order, not solving order (`OrderScratch::sorted_places`).
    let places = buffers.order_scratch.sorted_places();
    debug_assert_eq!(places.len(), buffers.solver_contacts.len(), "every prepared contact has its place");
    for contact in places.iter().map(|&k| &buffers.solver_contacts[k as usize]) {
        if contact.collided {
            ctx.profile.counters.impulses += 1;
        } else if contact.normal_impulse > 0.0 {
            ctx.profile.counters.resting_contacts += 1;
        }
        if contact.normal_impulse > 0.0 {
            buffers.contact_cache.push(cached_force(contact, h, ctx.settings.time_step));
        }
        if ctx.settings.record_events && (contact.collided || contact.normal_impulse > 0.0) {
            ctx.events.push(contact_event(ctx.bodies, &buffers.states, contact, time), &mut ctx.profile.counters);
        }
    }
    buffers.contact_cache.sort_unstable_by_key(|c| c.key);
}

/// The force a contact carried over a sub-step of length `h`, for the next warm start: `P / h`,
/// except where the contact collided in the sub-step, when its resting impulse is spread over at
/// least a whole `time_step`. Right after a collision that impulse is mostly a velocity
/// correction, not a lasting force; as `P / h` over a short sub-step it would be large, and the
/// next, longer sub-step's warm start would throw the bodies apart (a stack settling from its
/// bands' outer edge was kicked up at 0.3 m/s and fell 5 m away).
fn cached_force(contact: &SolverContact, h: f64, time_step: f64) -> CachedImpulse {
    let span = if contact.collided { h.max(time_step) } else { h };
    CachedImpulse {
        key: contact.key,
        normal_force: contact.normal_impulse / span,
        tangent_force: contact.tangent_impulse / span,
    }
}

/// The event of one solved contact: its impulse over the sub-step and what it did.
fn contact_event(bodies: &[BodyRecord], states: &[RigidState], contact: &SolverContact, time: f64) -> ContactEvent {
    let (a, b) = (contact.key.bodies.0 as usize, contact.key.bodies.1 as usize);
    let after = (states[a].velocity_at(contact.point) - states[b].velocity_at(contact.point)).dot(contact.normal);
    let kind = match contact.collision_kind {
        Some(ImpulseKind::Sticking) => EventKind::Sticking,
        Some(ImpulseKind::Sliding) => EventKind::Sliding,
        Some(_) => EventKind::Collision,
        None => EventKind::Resting,
    };
    ContactEvent {
        time,
        body_a: bodies[a].entity,
        body_b: bodies[b].entity,
        segment_a: contact.segments.0 as usize,
        parameter_a: contact.parameters.0,
        segment_b: contact.segments.1 as usize,
        parameter_b: contact.parameters.1,
        point: contact.point,
        normal: contact.normal,
        lambda_a: contact.raw_lambda.0,
        lambda_b: contact.raw_lambda.1,
        mu_a: contact.mu.0,
        mu_b: contact.mu.1,
        mu: contact.friction,
        kind,
        normal_velocity_before: contact.normal_velocity_before,
        normal_velocity_after: after,
        impulse: contact.total_impulse(),
    }
}

fn run_table(ctx: &mut StepContext<'_>, table: &[(Stage, System)]) {
    for &(stage, system) in table {
        let start = Instant::now();
        system(ctx);
        ctx.profile.record(stage, start.elapsed());
        #[cfg(debug_assertions)]
        validate::after(ctx, stage);
    }
}

/// One sub-step of motion and detection, halved on intersection; returns its length.
fn advance_with_retry(ctx: &mut StepContext<'_>, remaining: f64, floor: f64, substeps: u32) -> f64 {
    let mut h = timed(ctx, Stage::SubstepBound, |ctx| integrate::choose_substep(ctx, remaining, floor, substeps));
    timed(ctx, Stage::Retry, save_for_retry);
    loop {
        ctx.buffers.substep = h;
        ctx.buffers.step_left = remaining - h;
        run_table(ctx, &ADVANCE);
        if !timed(ctx, Stage::Retry, |ctx| moving_pair_intersects(ctx)) {
            return h;
        }
        timed(ctx, Stage::Retry, |ctx| ctx.buffers.states.clone_from(&ctx.buffers.saved_states));
        if h > floor {
            h = (0.5 * h).max(floor);
            ctx.profile.counters.retries += 1;
        } else {
            ctx.profile.counters.retry_limit_hits += 1;
            // An intersecting pair that did not overlap at the start has a moving body, so
            // there is always one to hold; each round holds at least one more, so this ends.
            let held_one = freeze_intersecting(ctx);
            debug_assert!(held_one, "an intersecting pair with a moving body had no body to hold");
            if !held_one {
                return h;
            }
        }
    }
}

/// Records the pairs that intersect at the start of the sub-step (overlapping input or a
/// teleport): retrying cannot separate them, so they do not trigger retries; counted.
fn remember_overlaps(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    buffers.overlapping_pairs.clear();
    if no_pair_intersects(buffers) {
        return;
    }
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    buffers.overlapping_pairs.extend(live.iter().filter(|slot| slot.intersecting()).map(|slot| slot.bodies));
    ctx.profile.counters.persistent_overlaps += buffers.overlapping_pairs.len() as u64;
}

/// Whether a pair that did not overlap at the start of the sub-step now intersects, with at
/// least one of its bodies moving.
fn moving_pair_intersects(ctx: &StepContext<'_>) -> bool {
    if no_pair_intersects(ctx.buffers) {
        return false;
    }
    let overlapping = &ctx.buffers.overlapping_pairs;
    ctx.buffers.live_pairs().iter().any(|slot| {
        slot.intersecting() && pair_moves(ctx, slot.bodies) && overlapping.binary_search(&slot.bodies).is_err()
    })
}

/// Whether the last narrow phase found no pair intersecting (its count; checked against the
/// slots in debug builds): the retry's checks then read no slot (their two passes over them, a
/// cache miss or two a pair, took 0.2 ms a step in the base-40 pyramid's 9,700 pairs).
fn no_pair_intersects(buffers: &StepBuffers) -> bool {
    let none = buffers.intersecting_pairs == Some(0);
    debug_assert!(!none || !buffers.live_pairs().iter().any(PairSlot::intersecting), "a pair intersects uncounted");
    none
}

fn pair_moves(ctx: &StepContext<'_>, (a, b): (u32, u32)) -> bool {
    let moves = |i: u32| !ctx.bodies[i as usize].is_static && !ctx.buffers.frozen[i as usize];
    moves(a) || moves(b)
}

/// Holds the moving bodies of intersecting pairs at their saved states; `false` if none was new.
fn freeze_intersecting(ctx: &mut StepContext<'_>) -> bool {
    let mut any = false;
    for k in 0..ctx.buffers.candidate_pairs.len() {
        let slot = &ctx.buffers.pair_slots[k];
        if !slot.intersecting() || ctx.buffers.overlapping_pairs.binary_search(&slot.bodies).is_ok() {
            continue;
        }
        for i in [slot.bodies.0, slot.bodies.1] {
            let i = i as usize;
            if !ctx.bodies[i].is_static && !ctx.buffers.frozen[i] {
                ctx.buffers.frozen[i] = true;
                any = true;
            }
        }
    }
    any
}

/// Reads every body's state and applied force. A body broken through `world_mut` — its state
/// or geometry removed, or its state made non-finite — is counted (`broken_bodies`), never
/// passed on quietly: a missing or non-finite state is replaced by the body's last good one
/// (from the step before, when the body table has not changed since), else by rest at the
/// origin.
fn gather_states(ctx: &mut StepContext<'_>, stale: bool) {
    let gravity = ctx.settings.gravity;
    let buffers = &mut *ctx.buffers;
    let (states, accelerations, applied_any, broken) =
        (&mut buffers.states, &mut buffers.accelerations, &mut buffers.applied, &mut buffers.broken);
    let world: &hecs::World = ctx.world;
    let (mut state_query, mut force_query) = (buffers.state_query.0.query(world), buffers.force_query.0.query(world));
    let mut geometry_query = buffers.geometry.0.query(world);
    let (mut state_view, mut force_view) = (state_query.view(), force_query.view());
    let geometry = geometry_query.view();
    let last_good = if stale { 0 } else { states.len() };
    states.resize(ctx.bodies.len(), RigidState::default());
    accelerations.clear();
    applied_any.clear();
    broken.clear();
    for (i, body) in ctx.bodies.iter().enumerate() {
        let read = state_view.get_mut(body.entity).map(|s| *s).filter(RigidState::is_finite);
        let whole = geometry.contains(body.entity);
        match read {
            Some(state) => states[i] = state,
            None if i < last_good => {} // the last good state stays
            None => states[i] = RigidState::default(),
        }
        broken.push(read.is_none() || !whole);
        ctx.profile.counters.broken_bodies += u64::from(read.is_none() || !whole);
        accelerations.push(if body.is_static {
            applied_any.push(false);
            BodyAcceleration::default()
        } else {
            let applied = force_view.get_mut(body.entity).map(|a| *a).unwrap_or_default();
            applied_any.push(applied != AppliedForce::default());
            BodyAcceleration {
                linear: gravity * body.motion.gravity_scale + applied.force * body.inverse_mass,
                angular: applied.torque * body.inverse_inertia,
            }
        });
    }
}

/// Writes the states back and clears the applied forces (they acted over this step).
fn scatter_states(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let mut targets = buffers.state_query.0.view_mut(ctx.world);
    for (body, state) in ctx.bodies.iter().zip(&buffers.states) {
        if let Some(target) = targets.get_mut(body.entity) {
            *target = *state;
        }
    }
    if buffers.applied.contains(&true) {
        let mut forces = buffers.force_query.0.view_mut(ctx.world);
        for (body, _) in ctx.bodies.iter().zip(&buffers.applied).filter(|(_, applied)| **applied) {
            if let Some(force) = forces.get_mut(body.entity) {
                *force = AppliedForce::default();
            }
        }
    }
}
