//! Bounds on how fast bodies move and close on each other, read by the query margins and the
//! sub-step bound.

use glam::DVec2;

use super::{BodyAcceleration, BodyRecord};
use crate::components::RigidState;
use crate::simulation::SimulationSettings;

/// What [`closing_bound`] reads of one body, worked out once per pass over the pairs (the
/// bound is taken two to four times a pair a sub-step): its velocity, `|ω| ρ`, `ω² ρ`, its
/// acceleration and `|α| ρ`.
#[derive(Clone, Copy, Debug, Default)]
pub struct BodyMotion {
    velocity: DVec2,
    turning: f64,
    turning_growth: f64,
    acceleration: DVec2,
    angular_acceleration: f64,
}

/// Fills `motions` with every body's [`BodyMotion`] at `states` (no allocation once grown).
pub(crate) fn body_motions(
    bodies: &[BodyRecord],
    states: &[RigidState],
    accelerations: &[BodyAcceleration],
    motions: &mut Vec<BodyMotion>,
) {
    motions.clear();
    motions.extend(bodies.iter().zip(states).zip(accelerations).map(|((body, state), acceleration)| {
        let (omega, radius) = (state.angular_velocity, body.radius);
        BodyMotion {
            velocity: state.linear_velocity,
            turning: omega.abs() * radius,
            turning_growth: omega * omega * radius,
            acceleration: acceleration.linear,
            angular_acceleration: acceleration.angular.abs() * radius,
        }
    }));
}

/// What the sub-step bound reads of a live pair before the pair's slot: its bodies and the
/// least gap, less its drift, it bounds the sub-step by ([`PairSlot::nearest_gap`](super::PairSlot::nearest_gap)). Kept
/// apart from the slots, in pair order, so that the bound's pass over a few thousand pairs
/// reads a dense list: a pair whose bodies' closing bound clears its floor over the sub-step
/// bounds nothing (`integrate::pair_substep` would return the sub-step it is given), and only
/// the others' slots are read. A sensor pair's floor is ∞ (it bounds nothing); a pair with
/// exactly one listed gap has −∞ (its pieces are bounded by their own motion, never by the
/// bodies' closing bound, so it is always read); NaN never clears. The list also says whether
/// the pair touches ([`PairSlot::touching`](super::PairSlot::touching)), which the step's record of touching pairs reads
/// after every sub-step instead of the slots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BoundFloor {
    /// Body slots `(a, b)` of the pair.
    pub bodies: (u32, u32),
    /// The least gap less the drift, ±∞ as above.
    pub floor: f64,
    /// Whether the pair touches.
    pub touching: bool,
}

/// How fast any point of A (band included) can approach any point of B, and how fast that can
/// grow: `speed = |v_A − v_B| + |ω_A| ρ_A + |ω_B| ρ_B` and
/// `growth = ½ (ω_A² ρ_A + ω_B² ρ_B + |a_A − a_B| + |α_A| ρ_A + |α_B| ρ_B)`, so that they close
/// at most `speed·h + growth·h²` in time `h` (a point's velocity turns at `ω²|r|`; two bodies
/// under gravity alone have no difference of accelerations).
#[must_use]
pub(crate) fn closing_bound(motions: &[BodyMotion], (a, b): (usize, usize)) -> (f64, f64) {
    let (ma, mb) = (&motions[a], &motions[b]);
    let speed = (ma.velocity - mb.velocity).length() + ma.turning + mb.turning;
    let driven = (ma.acceleration - mb.acceleration).length() + ma.angular_acceleration + mb.angular_acceleration;
    let growth = 0.5 * (ma.turning_growth + mb.turning_growth + driven);
    (speed, growth)
}

/// A bound of [`closing_bound`] over every pair of bodies at once: twice the fastest body's
/// `|v| + |ω| ρ`, and the largest `ω² ρ` and `|α| ρ` with half the spread of the accelerations
/// (the diagonal of their bounding box), so that no two bodies close faster than
/// `speed·h + growth·h²`.
#[must_use]
pub(crate) fn fastest(motions: &[BodyMotion]) -> (f64, f64) {
    let (mut speed, mut turning_growth, mut angular) = (0.0f64, 0.0f64, 0.0f64);
    let (mut low, mut high) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for motion in motions {
        speed = speed.max(motion.velocity.length() + motion.turning);
        turning_growth = turning_growth.max(motion.turning_growth);
        angular = angular.max(motion.angular_acceleration);
        (low, high) = (low.min(motion.acceleration), high.max(motion.acceleration));
    }
    let spread = if motions.is_empty() { 0.0 } else { (high - low).length() };
    (2.0 * speed, turning_growth + 0.5 * spread + angular)
}

/// The time the margins cover: a nominal step, or the last sub-step if that was longer.
pub(crate) fn margin_horizon(settings: &SimulationSettings, substep: f64) -> f64 {
    settings.time_step.max(substep)
}

/// Bound on how far any point of a body (band included) moves in time `h` under an
/// acceleration bound `acceleration` ([`BodyAcceleration::bound`]):
/// `(|v| + |ω| ρ) h + ½ (|a| + |α| ρ) h²` (zero for static bodies).
#[must_use]
pub fn motion_bound(body: &BodyRecord, state: &RigidState, acceleration: f64, h: f64) -> f64 {
    if body.is_static && !body.kinematic {
        return 0.0;
    }
    (state.linear_velocity.length() + state.angular_velocity.abs() * body.radius) * h + 0.5 * acceleration * h * h
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{BodyMotion, closing_bound, fastest};

    /// The bound over every pair at once is at least each pair's closing bound, speed and growth
    /// (`integrate::substep_bound` skips the pairs while it clears the least gap).
    #[test]
    fn the_fastest_bodies_bound_every_pair() {
        let mut rng = crate::random::seeded(20);
        use rand::RngExt;
        for _ in 0..200 {
            let count = rng.random_range(1..8);
            let mut value = |scale: f64| scale * (2.0 * rng.random::<f64>() - 1.0);
            let motions: Vec<BodyMotion> = (0..count)
                .map(|_| {
                    let (omega, radius) = (value(5.0), value(1.0).abs());
                    BodyMotion {
                        velocity: DVec2::new(value(3.0), value(3.0)),
                        turning: omega.abs() * radius,
                        turning_growth: omega * omega * radius,
                        acceleration: DVec2::new(value(10.0), value(10.0)),
                        angular_acceleration: value(2.0).abs() * radius,
                    }
                })
                .collect();
            let (speed, growth) = fastest(&motions);
            for a in 0..count {
                for b in 0..count {
                    let (pair_speed, pair_growth) = closing_bound(&motions, (a, b));
                    assert!(pair_speed <= speed && pair_growth <= growth, "pair ({a}, {b}) outruns the bound");
                }
            }
        }
        assert_eq!(fastest(&[]), (0.0, 0.0), "no body closes on anything");
    }
}
