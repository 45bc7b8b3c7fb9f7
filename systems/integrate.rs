//! Integrate: moves every free body over the sub-step, exactly for constant gravity where no
//! contact acted, and chooses the sub-step by conservative advancement (MODEL §7b).

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec2;
use rayon::prelude::*;

use super::forces::damp;
use super::{
    BodyAcceleration, BodyMotion, BodyRecord, BoundFloor, Drift, PairSlot, StepContext, body_motions, closing_bound,
    fastest, motion_bound,
};
use crate::components::RigidState;
use crate::simulation::ContactModel;

/// Moves bodies by `buffers.substep`. Static and frozen bodies stay where they are.
///
/// - Seed model (velocities not yet changed this sub-step): `x += v h + ½ g h²`, `v += g h`.
/// - Solver (gravity and contact impulses already in `v`; `v₀` is the velocity after the
///   collisions, before gravity): a body moves at the mean of `v₀` and `v` plus its
///   split-impulse pseudo-velocity, `x += ((v₀ + v)/2 + v_bias) h` (the trapezoidal rule). A body
///   no contact touched follows the exact parabola, `x += (v − ½ g h) h`; a body decelerated by
///   friction at a constant rate covers the exact distance (the semi-implicit `x += v h` falls
///   `v h / 2` short of it); a resting body whose contact cancelled gravity does not move.
pub fn run(ctx: &mut StepContext<'_>) {
    let h = ctx.buffers.substep;
    let seed = ctx.settings.contact_model == ContactModel::SeedMicroCollisions;
    let buffers = &mut *ctx.buffers;
    for (i, (body, state)) in ctx.bodies.iter().zip(buffers.states.iter_mut()).enumerate() {
        if body.kinematic && !buffers.frozen[i] {
            // Moved by its own velocity alone.
            state.position += state.linear_velocity * h;
            state.angle += state.angular_velocity * h;
            continue;
        }
        if body.is_static || buffers.frozen[i] {
            continue;
        }
        let BodyAcceleration { linear: a, angular: alpha } = buffers.accelerations[i];
        if seed {
            state.position += state.linear_velocity * h + 0.5 * a * h * h;
            state.linear_velocity += a * h;
            state.angle += state.angular_velocity * h + 0.5 * alpha * h * h;
            state.angular_velocity += alpha * h;
            damp(state, &body.motion, h);
        } else if buffers.touched.get(i).copied().unwrap_or(false) {
            let (start, bias) = (buffers.start_velocities[i], buffers.bias[i]);
            state.position += (0.5 * (start.linear + state.linear_velocity) + bias.linear) * h;
            state.angle += (0.5 * (start.angular + state.angular_velocity) + bias.angular) * h;
        } else {
            state.position += (state.linear_velocity - 0.5 * a * h) * h;
            state.angle += (state.angular_velocity - 0.5 * alpha * h) * h;
        }
    }
}

/// The longest sub-step (at most `remaining`) over which no two bodies can come closer than
/// `(1 − approach_depth)` of their combined band from outside it, given the distance bounds of
/// the last narrow phase and the current velocities. There is no lower limit, so no speed tunnels; a bound
/// below `retry_floor` (the shortest retried sub-step) is counted as a floor hit, and once a
/// step has taken `max_substeps` sub-steps the rest of it is taken at once (counted).
#[must_use]
pub fn choose_substep(ctx: &mut StepContext<'_>, remaining: f64, retry_floor: f64, substeps_taken: u32) -> f64 {
    if substeps_taken >= ctx.settings.max_substeps {
        ctx.profile.counters.substep_cap_hits += 1;
        return remaining;
    }
    let buffers = &mut *ctx.buffers;
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let (states, accelerations, margins) = (&buffers.states, &buffers.accelerations, &buffers.margins);
    let h = substep_bound(
        ctx.pool,
        ctx.bodies,
        (states, accelerations, &mut buffers.motions),
        margins,
        (live, &buffers.bound_floors, buffers.nearest_gap),
        remaining,
    );
    if h < retry_floor {
        ctx.profile.counters.advancement_floor_hits += 1;
    }
    // A sub-step the bound cuts short is taken a little shorter still, for the solve to come.
    let h = if h < remaining { h * (1.0 - ANTICIPATION) } else { h };
    // A zero bound (a pair already at its approach depth and approaching) still moves a little:
    // the impulses of this sub-step have made it separate, and the retry guards the rest.
    h.max(MIN_SUBSTEP_FRACTION * remaining).min(remaining)
}

/// How much shorter than the bound of the velocities before the solve a sub-step that bound cuts
/// short is taken. The solve's impulses push bodies towards their other neighbours, so the
/// bound of the solved velocities is usually a little shorter (by 0.02 % to 2 % in 10 of the 17
/// shortenings of 15 steps of the fixed pile, a scratch count), and each shortening redoes the
/// whole solve. At 5 % the fixed pile redoes a quarter as many solves as without (14 against 56
/// in 60 steps), for 5 % fewer instructions over 120 steps than the shortening margin alone
/// (11 % fewer than neither; docs/performance.md).
const ANTICIPATION: f64 = 0.05;

/// Pairs per parallel task of [`substep_bound`].
const PAIRS_PER_TASK: usize = 128;

/// Fewer pairs than this are bounded on the caller's thread: most pairs cost a comparison with
/// their floor (about 30 ns each in a landing pile), so below it the split and join cost more
/// than the second thread saves (the pile of 100 blobs, about 600 pairs a sub-step, bounded
/// 0.54–0.62 ms a step on the caller's thread against 0.59–0.68 ms split, docs/performance.md).
const PARALLEL_PAIRS: usize = 8 * PAIRS_PER_TASK;

/// The conservative-advancement bound of [`choose_substep`] (at most `limit`) for bodies moving
/// with the velocities of `states`: each body within its refit margin, and no separate leaf
/// pair closing its gap. The pairs are bounded in parallel, each task from the least bound the
/// tasks before it have found (at first `limit`); the least of their bounds is the same, to the
/// bit, as one pass's, since a pair's bound only skips leaf pairs, or all of them where the
/// whole bodies' bound [`clears`] the nearest gap, whose bounds are at least the bound already
/// found (`clears` leaves room for the rounding of [`time_to_travel`]). Starting from what the
/// others found, a task clears as many pairs as one pass would: from `limit` each, the pile of
/// 2000 blobs' bound took 8.7–9.3 ms a step on two threads against 6.5 on one, and 5.5–6.1 now
/// (docs/performance.md).
#[must_use]
pub fn substep_bound(
    pool: Option<&rayon::ThreadPool>,
    bodies: &[BodyRecord],
    (states, accelerations, motions): (&[RigidState], &[BodyAcceleration], &mut Vec<BodyMotion>),
    margins: &[f64],
    (pairs, floors, nearest): (&[PairSlot], &[BoundFloor], Option<f64>),
    limit: f64,
) -> f64 {
    body_motions(bodies, states, accelerations, motions);
    let motions = &motions[..];
    let mut h = limit;
    for ((body, acceleration), (state, margin)) in bodies.iter().zip(accelerations).zip(states.iter().zip(margins)) {
        let speed = body_speed(body, state);
        let acceleration = acceleration.bound(body);
        // A body that does not move (at rest, no force) stays within any margin, even none.
        if (!body.is_static || body.kinematic) && (speed > 0.0 || acceleration > 0.0) {
            h = h.min(time_to_travel(speed, 0.5 * acceleration, *margin));
        }
    }
    // While no two bodies can close the least gap of the last narrow phase, no pair bounds the
    // sub-step (a still structure's every bound).
    if let Some(nearest) = nearest {
        let (speed, growth) = fastest(motions);
        if clears(speed, growth, nearest, h) {
            return h;
        }
    }
    // Each pair's floor first, where the narrow phase listed these slots (not yet for a restored
    // snapshot's): where the bodies' closing bound clears it, the pair bounds nothing and its
    // slot is not read (see `BoundFloor`).
    let listed = (floors.len() == pairs.len()).then_some(floors);
    #[cfg(debug_assertions)]
    if let Some(floors) = listed {
        check_floors(pairs, floors);
    }
    // A listed pair's closing bound, worked out for its floor, is the one its slot is bounded
    // with (the floor's bodies are the slot's): passed on, not worked out again.
    let read = |slot: &PairSlot, closing: (f64, f64), h: f64| {
        if slot.sensor { h } else { h.min(pair_substep(states, slot, closing, h)) }
    };
    let bound_from = |range: std::ops::Range<usize>, h: f64| match listed {
        Some(floors) => pairs[range.clone()].iter().zip(&floors[range]).fold(h, |h, (slot, floor)| {
            let (closing, accel) = closing_bound(motions, (floor.bodies.0 as usize, floor.bodies.1 as usize));
            if clears(closing, accel, floor.floor, h) { h } else { read(slot, (closing, accel), h) }
        }),
        None => pairs[range].iter().fold(h, |h, slot| read(slot, closing_bound(motions, slot.body_indices()), h)),
    };
    let Some(pool) = pool.filter(|_| pairs.len() >= PARALLEL_PAIRS) else {
        return bound_from(0..pairs.len(), h);
    };
    // Each task starts from the least bound the tasks before it have published (a bound of
    // some pair, so at least the least of all): a pair it clears bounds nothing below it either
    // way, and a task that starts lower reads fewer pairs, as one pass does once its bound has
    // come down. Only positive bounds are published (their bits order as they do).
    let tasks = pairs.len().div_ceil(PAIRS_PER_TASK);
    let published = AtomicU64::new(h.to_bits());
    pool.install(|| {
        (0..tasks)
            .into_par_iter()
            .map(|task| {
                let start = f64::from_bits(published.load(Ordering::Relaxed));
                let range = task * PAIRS_PER_TASK..((task + 1) * PAIRS_PER_TASK).min(pairs.len());
                let found = bound_from(range, start);
                if found > 0.0 && found < start {
                    published.fetch_min(found.to_bits(), Ordering::Relaxed);
                }
                found
            })
            .reduce(|| h, f64::min)
    })
}

/// Debug builds: the sub-step bound's list is the narrow phase's for these slots (a pair the
/// contact hook turned into a sensor pair since bounds nothing either way).
#[cfg(debug_assertions)]
fn check_floors(pairs: &[PairSlot], floors: &[BoundFloor]) {
    for (slot, floor) in pairs.iter().zip(floors) {
        let now = slot.bound_floor(slot.bounding_gap());
        assert!(
            now.bodies == floor.bodies && (slot.sensor || now.floor.to_bits() == floor.floor.to_bits()),
            "pair {:?}: the sub-step bound's floor {floor:?} is not its slot's, {now:?}",
            slot.bodies
        );
    }
}

/// Smallest sub-step as a fraction of what remains of the step: keeps a step finite.
const MIN_SUBSTEP_FRACTION: f64 = 1e-9;

/// Longest sub-step (at most `limit`) before any separate leaf pair of `slot` can close its
/// gap. For pieces held by discs (centre `c`, radius `r`) of bodies A and B, the pieces close
/// at most at `|u(c_A) − u(c_B)| + |ω_A| r_A + |ω_B| r_B`, where `u(c)` is the velocity of the
/// body point at `c`; over time this grows by at most `ω²ρ + |Δa| + |α_A| ρ_A + |α_B| ρ_B` (a
/// point's velocity turns at `ω²|r|`; `Δa` the difference of the bodies' accelerations, zero
/// between two bodies under gravity alone, `α` their angular accelerations). Near a rolling or resting contact the relative velocity of the pieces is much
/// smaller than that of the bodies, which keeps the sub-steps long.
///
/// Where the pieces are apart along a fixed axis `n`, their gap along `n` closes only at
/// `|(u(c_A) − u(c_B))·n| + |ω_A| r_A + |ω_B| r_B`, with the same growth bound: pieces sliding
/// past each other (a body falling along a wall) do not shorten the sub-step. Every one of
/// these bounds holds, so the longest is safe.
///
/// The whole bodies' closing bound `closing` ([`closing_bound`], speed and growth: any point of
/// A against any point of B) holds for every leaf pair too, against the smallest of their gaps.
/// For a pair with several leaf pairs it is tried first: where it already allows `limit` they
/// are not bounded one by one, and otherwise each one's bound is taken at least as long as it.
/// A pair's bound is then the same whatever `limit` it starts from, as long as that is above
/// it, which keeps the parallel bound equal to the serial one.
fn pair_substep(states: &[RigidState], slot: &PairSlot, (closing, accel): (f64, f64), limit: f64) -> f64 {
    let manifold = slot.manifold();
    let (a, b) = slot.body_indices();
    let (sa, sb) = (&states[a], &states[b]);
    let mut h = limit;
    // A pair carried from an earlier query (§3b): its pieces have moved in the world by up to
    // `δ_A`, `δ_B` since, so each disc is that much wider about its old centre, and every gap
    // has closed by at most the drift of the distances.
    let Drift { a: drift_a, b: drift_b, gap: drift } = slot.drift;
    // The whole bodies' bound first, where there are several leaf pairs: while it clears the
    // nearest gap, none of them bounds.
    let (leaves, whole) = match manifold.gaps.as_slice() {
        several @ [_, _, ..] => {
            let nearest = several.iter().fold(f64::INFINITY, |nearest, leaf| nearest.min(leaf.gap)) - drift;
            if clears(closing, accel, nearest, h) {
                (&[][..], h)
            } else {
                (several, time_to_travel(closing, accel, nearest))
            }
        }
        one => (one, 0.0),
    };
    for leaf in leaves {
        let relative = sa.velocity_at(leaf.centre_a) - sb.velocity_at(leaf.centre_b);
        let turning = sa.angular_velocity.abs() * (leaf.radius_a + drift_a)
            + sb.angular_velocity.abs() * (leaf.radius_b + drift_b);
        let any_direction = time_to_travel(relative.length() + turning, accel, leaf.gap - drift).max(whole);
        if any_direction >= h {
            continue;
        }
        // Along an axis (oriented from A's side to B's) only A's motion towards B closes the gap;
        // moving apart, only the turning and the acceleration can.
        let along =
            |(axis, gap): (DVec2, f64)| time_to_travel(relative.dot(axis).max(0.0) + turning, accel, gap - drift);
        // The hull's axes one by one, until one allows `h` (the longest of all then cannot
        // shorten it, so the rest are not worked out: the same bound), then the axis towards
        // the nearest points, which costs four Newton steps.
        let mut along_axes: f64 = 0.0;
        for axis in leaf.hull_axis_gaps() {
            along_axes = along_axes.max(along(axis));
            if along_axes >= h {
                break;
            }
        }
        if any_direction.max(along_axes) < h {
            along_axes = along_axes.max(along(leaf.nearest_axis_gap()));
        }
        h = h.min(any_direction.max(along_axes));
    }
    // Leaf pairs left out of the gaps were farther apart than the query's margin: the pair's
    // relative motion (narrower than the bodies' own margins, which cover it only while it
    // moves as it did), less the drift of a carried pair. Points that do not close at all bound
    // nothing, even with no margin (bodies at rest without gravity).
    if let Some(solved_at) = slot.solved_at
        && (closing > 0.0 || accel > 0.0)
        && !clears(closing, accel, solved_at.margin - drift, h)
    {
        h = h.min(time_to_travel(closing, accel, solved_at.margin - drift));
    }
    h
}

fn body_speed(body: &BodyRecord, state: &RigidState) -> f64 {
    motion_bound(body, state, 0.0, 1.0)
}

/// Whether points closing at most `speed·h + accel·h²` over `h` surely stay short of
/// `distance`: with room for rounding, so that [`time_to_travel`] of the same numbers is at
/// least `h` as computed. Never for a distance that is not positive; a NaN clears nothing.
fn clears(speed: f64, accel: f64, distance: f64, h: f64) -> bool {
    distance > 0.0 && speed * h + accel * h * h <= distance * (1.0 - CLEARING_ROOM)
}

/// Relative room [`clears`] leaves for the rounding of [`time_to_travel`] (a few units in
/// the last place).
const CLEARING_ROOM: f64 = 1e-9;

/// Largest `h ≥ 0` with `speed·h + accel·h² ≤ distance` (∞ when nothing moves).
#[must_use]
pub fn time_to_travel(speed: f64, accel: f64, distance: f64) -> f64 {
    if distance <= 0.0 {
        return 0.0;
    }
    if speed <= 0.0 && accel <= 0.0 {
        return f64::INFINITY;
    }
    // Stable root of accel h² + speed h − distance = 0.
    2.0 * distance / (speed + (speed * speed + 4.0 * accel * distance).sqrt())
}

#[cfg(test)]
mod tests {
    use super::{clears, time_to_travel};

    /// What `clears` lets pass, `time_to_travel` computes at least as long: the bound of a
    /// pair skipped on it is never shorter than the sub-step it was skipped for. (Up to 1e100:
    /// past about 1e154 `time_to_travel`'s square overflows and it returns 0, a bound shorter
    /// than need be.)
    #[test]
    fn a_cleared_distance_takes_at_least_the_sub_step() {
        let values = [0.0, 1e-300, 1e-12, 3e-7, 0.1, 1.0 / 3.0, 1.0, 7.5, 1e6, 1e100];
        let mut cleared = 0;
        for speed in values {
            for accel in values {
                for distance in values.iter().flat_map(|&d| [d, -d, d * (1.0 + 1e-12)]) {
                    for h in values.iter().flat_map(|&h| [h, h * (1.0 - 1e-12), h * (1.0 + 1e-9)]) {
                        if clears(speed, accel, distance, h) {
                            cleared += 1;
                            let t = time_to_travel(speed, accel, distance);
                            assert!(t >= h, "speed {speed} accel {accel} distance {distance}: {t} < {h}");
                        }
                    }
                }
            }
        }
        assert!(cleared > 1000, "the grid clears some cases ({cleared})");
        assert!(!clears(0.0, 0.0, 0.0, 1.0), "no distance is cleared, even standing still");
        assert!(!clears(f64::NAN, 0.0, 1.0, 1.0) && !clears(0.0, 0.0, f64::NAN, 1.0), "a NaN clears nothing");
    }

    /// The bound over the pairs on the pool, each task starting from the least bound the
    /// tasks before it published, is the one pass's to the bit: a packed grid of 900 blobs
    /// closing on each other gives well over `PARALLEL_PAIRS` pairs, bounded on pools of one,
    /// two and four threads from several limits.
    #[test]
    fn the_bound_on_the_pool_is_the_one_pass_bound() {
        use glam::DVec2;

        use super::{PARALLEL_PAIRS, substep_bound};
        use crate::{BodyDesc, Generator, Rugosity, Simulation, SimulationSettings, SleepSettings};

        let settings = SimulationSettings {
            threads: 1,
            sleep: SleepSettings::off(),
            gravity: DVec2::ZERO,
            ..SimulationSettings::default()
        };
        let mut sim = Simulation::new(settings).unwrap();
        for k in 0..900u64 {
            let (i, j) = ((k % 30) as f64, (k / 30) as f64);
            let spline = Generator::Blob { radius: 0.1, roughness: 0.2, seed: k }.build(16).unwrap();
            let speed = if k % 2 == 0 { 0.6 } else { -0.6 };
            let body = BodyDesc::new(spline, Rugosity::constant(16, 0.002).unwrap())
                .at(DVec2::new(0.23 * i, 0.23 * j), 0.3 * k as f64)
                .with_velocity(DVec2::new(speed, 0.1 * speed), 0.5 * speed);
            sim.add_body(body).unwrap();
        }
        for _ in 0..2 {
            sim.step(sim.settings().time_step);
        }
        let buffers = &sim.buffers;
        let pairs = &buffers.pair_slots[..buffers.candidate_pairs.len()];
        assert!(pairs.len() >= PARALLEL_PAIRS, "{} pairs", pairs.len());
        let mut motions = Vec::new();
        let mut bound = |threads: usize, limit: f64| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let inputs = (&buffers.states[..], &buffers.accelerations[..], &mut motions);
            let floors = (pairs, &buffers.bound_floors[..], None);
            substep_bound((threads > 1).then_some(&pool), &sim.bodies, inputs, &buffers.margins, floors, limit)
        };
        let mut cut = 0;
        for limit in [1.0 / 60.0, 4e-3, 1e-3, 1e-5] {
            let one = bound(1, limit);
            cut += usize::from(one < limit);
            for threads in [2, 4] {
                assert_eq!(bound(threads, limit).to_bits(), one.to_bits(), "{threads} threads, limit {limit}");
            }
        }
        assert!(cut >= 2, "the pairs cut the sub-step at {cut} limits");
    }

    #[test]
    fn travel_time_solves_the_quadratic() {
        let h = time_to_travel(2.0, 4.9, 1.0);
        assert!((2.0 * h + 4.9 * h * h - 1.0).abs() < 1e-14);
        assert_eq!(time_to_travel(0.0, 0.0, 1.0), f64::INFINITY);
        assert_eq!(time_to_travel(0.0, 0.0, 0.0), 0.0, "no distance: not even a still body may travel");
        assert_eq!(time_to_travel(3.0, 0.0, 0.0), 0.0);
        assert!((time_to_travel(4.0, 0.0, 2.0) - 0.5).abs() < 1e-15);
    }
}
