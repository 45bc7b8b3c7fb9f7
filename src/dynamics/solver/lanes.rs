//! Two patches of a resting sweep at once, in the two lanes of 128-bit vectors (`wide`'s
//! `f64x2`: SSE2 on x86-64, the baseline, so no feature detection; NEON on aarch64; plain pairs
//! of scalars elsewhere, with the same results).
//!
//! A sweep updates its contacts one after the other, each update reading the velocities the
//! updates before it wrote. Two consecutive patches whose pairs share no body read and write
//! none of each other's velocities, so updating both at once, each in its own lane, reads and
//! writes exactly what updating them one after the other does. Each lane here does the very
//! operations of [`block_patch`](super::patch::block_patch), in the same order, on the same values
//! (IEEE addition, multiplication and division round each lane as they round a scalar; no
//! fused multiply-add; negation flips the sign bit; the block's cases and the friction's clamp
//! are chosen by the same comparisons), so the sweep's results are the same to the bit whether
//! a patch is updated here or alone: the golden hash and every thread count agree. The solving
//! order (`systems/prepare_contacts.rs`, `sort_keys`) places pairs that share no body one after
//! the other, so most patches of a resting structure pair up (docs/performance.md).

use wide::f64x2;

use super::{PairVelocities, SolverContact};
use crate::dynamics::impulse::BodyVelocity;

/// Whether the patches at `contacts[0..2]` and `contacts[2..4]` can be updated in lanes: both
/// are patches whose block was worked out for the sub-step with its normal matrix (the update
/// [`block_patch`](super::patch::block_patch) does for the resting sweep's free pass), and their pairs
/// share no body, neither by slot nor by index in the island.
#[inline(always)]
pub(super) fn pairable(contacts: &[SolverContact]) -> bool {
    let [first, _, second, _, ..] = contacts else { return false };
    let disjoint = |(a, b): (u32, u32), (c, d): (u32, u32)| a != c && a != d && b != c && b != d;
    first.patch_with_next
        && second.patch_with_next
        && first.patch.is_some_and(|block| block.matrix.is_some())
        && second.patch.is_some_and(|block| block.matrix.is_some())
        && disjoint(first.key.bodies, second.key.bodies)
        && disjoint(first.local, second.local)
}

/// One body's velocity in each lane.
#[derive(Clone, Copy)]
struct Velocities {
    x: f64x2,
    y: f64x2,
    angular: f64x2,
}

impl Velocities {
    #[inline(always)]
    fn of(one: &BodyVelocity, two: &BodyVelocity) -> Self {
        Self {
            x: f64x2::new([one.linear.x, two.linear.x]),
            y: f64x2::new([one.linear.y, two.linear.y]),
            angular: f64x2::new([one.angular, two.angular]),
        }
    }

    #[inline(always)]
    fn lane(&self, k: usize) -> BodyVelocity {
        let (x, y, angular) = (self.x.to_array(), self.y.to_array(), self.angular.to_array());
        BodyVelocity { linear: glam::DVec2::new(x[k], y[k]), angular: angular[k] }
    }
}

/// A direction in each lane.
#[derive(Clone, Copy)]
struct Direction {
    x: f64x2,
    y: f64x2,
}

/// `row_velocity` in lanes: `d·(v_A − v_B) + ω_A r_A − ω_B r_B`, as glam's dot product and
/// the scalar expression group it.
#[inline(always)]
fn row_velocity(d: Direction, (arm_a, arm_b): (f64x2, f64x2), a: &Velocities, b: &Velocities) -> f64x2 {
    (d.x * (a.x - b.x) + d.y * (a.y - b.y)) + a.angular * arm_a - b.angular * arm_b
}

/// `push_along` in lanes: `p d` on A, `−p d` on B, at the angular arms `arms`.
#[inline(always)]
fn push_along(
    inverse: [f64x2; 4],
    d: Direction,
    (arm_a, arm_b): (f64x2, f64x2),
    p: f64x2,
    (a, b): (&mut Velocities, &mut Velocities),
) {
    let along_a = inverse[0] * p;
    a.x += along_a * d.x;
    a.y += along_a * d.y;
    a.angular += inverse[1] * (p * arm_a);
    let minus = -p;
    let along_b = inverse[2] * minus;
    b.x += along_b * d.x;
    b.y += along_b * d.y;
    b.angular += inverse[3] * (minus * arm_b);
}

/// `block_impulses` in lanes: the four cases of which ends push, each lane taking the case the
/// scalar's `if` chain takes (its first whose test holds).
#[inline(always)]
fn block_impulses((k11, k22, k12): (f64x2, f64x2, f64x2), (b1, b2): (f64x2, f64x2)) -> (f64x2, f64x2) {
    let zero = f64x2::ZERO;
    let determinant = k11 * k22 - k12 * k12;
    let both = (((-k22) * b1 + k12 * b2) / determinant, (k12 * b1 - k11 * b2) / determinant);
    let only_first = (-b1) / k11;
    let only_second = (-b2) / k22;
    let take_both = both.0.simd_ge(zero) & both.1.simd_ge(zero);
    let take_first = only_first.simd_ge(zero) & (k12 * only_first + b2).simd_ge(zero);
    let take_second = only_second.simd_ge(zero) & (k12 * only_second + b1).simd_ge(zero);
    let first = take_both.select(both.0, take_first.select(only_first, zero));
    let second = take_both.select(both.1, take_first.select(zero, take_second.select(only_second, zero)));
    (first, second)
}

/// `f64::clamp(x, -limit, limit)` in lanes, by its two comparisons in its order.
#[inline(always)]
fn clamp(x: f64x2, limit: f64x2) -> f64x2 {
    let low = -limit;
    let raised = x.simd_lt(low).select(low, x);
    raised.simd_gt(limit).select(limit, raised)
}

/// The resting sweep's update of the two patches `contacts[0..2]` and `contacts[2..4]`
/// ([`pairable`]), each as [`block_patch`](super::patch::block_patch) updates it on the resting
/// impulses in the free pass; returns the larger change of each patch (see `sweep`).
#[inline(always)]
pub(super) fn solve_two_patches<V: PairVelocities + ?Sized>(
    contacts: &mut [SolverContact],
    velocities: &mut V,
) -> [f64; 2] {
    let [one, one_end, two, two_end, ..] = contacts else { return [0.0; 2] };
    let (Some(block_one), Some(block_two)) = (one.patch, two.patch) else { return [0.0; 2] };
    let (Some(matrix_one), Some(matrix_two)) = (block_one.matrix, block_two.matrix) else { return [0.0; 2] };
    let lanes = |first: f64, second: f64| f64x2::new([first, second]);
    let ((a_one, b_one), (a_two, b_two)) = (velocities.pair(one), velocities.pair(two));
    let (mut a, mut b) = (Velocities::of(&a_one, &a_two), Velocities::of(&b_one, &b_two));
    let inverse: [f64x2; 4] = std::array::from_fn(|k| lanes(one.inverse[k], two.inverse[k]));
    let n = Direction { x: lanes(one.normal.x, two.normal.x), y: lanes(one.normal.y, two.normal.y) };
    let arms = |first: &SolverContact, second: &SolverContact| {
        (lanes(first.normal_arms.0, second.normal_arms.0), lanes(first.normal_arms.1, second.normal_arms.1))
    };
    let (arms_first, arms_second) = (arms(one, two), arms(one_end, two_end));
    let w1 = row_velocity(n, arms_first, &a, &b);
    let w2 = row_velocity(n, arms_second, &a, &b);
    let old = (lanes(one.normal_impulse, two.normal_impulse), lanes(one_end.normal_impulse, two_end.normal_impulse));
    // The resting impulses' target is 0: `w − 0` is `w` to the bit, so `w` stands for it.
    let (b1, b2) = (w1, w2);
    let (k11, k22, k12) =
        (lanes(matrix_one.0, matrix_two.0), lanes(matrix_one.1, matrix_two.1), lanes(matrix_one.2, matrix_two.2));
    let new = block_impulses((k11, k22, k12), (b1 - (k11 * old.0 + k12 * old.1), b2 - (k12 * old.0 + k22 * old.1)));
    let tangent_old = lanes(one.tangent_impulse, two.tangent_impulse);
    let partner_tangent = lanes(one_end.tangent_impulse, two_end.tangent_impulse);
    let (dn1, dn2) = (new.0 - old.0, new.1 - old.1);
    push_along(inverse, n, arms_first, dn1, (&mut a, &mut b));
    push_along(inverse, n, arms_second, dn2, (&mut a, &mut b));
    let limit = lanes(one.friction, two.friction) * new.0 + lanes(one_end.friction, two_end.friction) * new.1;
    // The friction at the patch's centre, along `t = n.perp()`.
    let t = Direction { x: -n.y, y: n.x };
    let centre_arms = (
        lanes(block_one.centre_arms.0, block_two.centre_arms.0),
        lanes(block_one.centre_arms.1, block_two.centre_arms.1),
    );
    let u_t = row_velocity(t, centre_arms, &a, &b);
    let tangent_mass = lanes(block_one.tangent_mass, block_two.tangent_mass);
    let tangent = clamp(tangent_old - tangent_mass * u_t, limit);
    let dt = tangent - tangent_old;
    push_along(inverse, t, centre_arms, dt, (&mut a, &mut b));
    let weights = |first: &SolverContact, second: &SolverContact| {
        (lanes(first.change_weights.0, second.change_weights.0), lanes(first.change_weights.1, second.change_weights.1))
    };
    let ((normal_first, tangent_first), (normal_second, tangent_second)) =
        (weights(one, two), weights(one_end, two_end));
    // `|−x|` is `|x|` to the bit.
    let first_change = dn1.abs() * normal_first + dt.abs() * tangent_first;
    let second_change = dn2.abs() * normal_second + partner_tangent.abs() * tangent_second;
    let (new_first, new_second, tangent) = (new.0.to_array(), new.1.to_array(), tangent.to_array());
    (one.normal_impulse, one_end.normal_impulse, one.tangent_impulse, one_end.tangent_impulse) =
        (new_first[0], new_second[0], tangent[0], 0.0);
    (two.normal_impulse, two_end.normal_impulse, two.tangent_impulse, two_end.tangent_impulse) =
        (new_first[1], new_second[1], tangent[1], 0.0);
    velocities.set_pair(one, a.lane(0), b.lane(0));
    velocities.set_pair(two, a.lane(1), b.lane(1));
    let (first_change, second_change) = (first_change.to_array(), second_change.to_array());
    [first_change[0].max(second_change[0]), first_change[1].max(second_change[1])]
}

#[cfg(test)]
mod tests {
    use glam::DVec2;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::super::{Accumulator, Pass, SolverContact, prepare_patches, solve_unit};
    use super::*;

    /// Two patches of random bodies, arms, normals, frictions and impulses (some pushing, some
    /// pulled apart, some sliding), their pairs' bodies `(0, 1)` and `(2, 3)`.
    fn two_patches(rng: &mut StdRng) -> Vec<SolverContact> {
        let mut contacts = Vec::new();
        for pair in 0..2u32 {
            let inverse = [rng.random_range(0.1..2.0), rng.random_range(0.1..5.0), 0.0, 0.0];
            let inverse = if rng.random_bool(0.5) {
                [inverse[0], inverse[1], rng.random_range(0.1..2.0), rng.random_range(0.1..5.0)]
            } else {
                inverse
            };
            let normal = DVec2::from_angle(rng.random_range(0.0..std::f64::consts::TAU));
            let friction = rng.random_range(0.0..1.0);
            let centre = DVec2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            let half = normal.perp() * rng.random_range(0.05..0.5);
            for (end, offset) in [-half, half].into_iter().enumerate() {
                let arm_a = centre + offset;
                let arm_b = arm_a + DVec2::new(rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
                let mut contact = SolverContact::for_test(inverse, (arm_a, arm_b), normal, friction);
                contact.band = rng.random_range(0.001..0.01);
                contact.patch_with_next = end == 0;
                contact.key.bodies = (2 * pair, 2 * pair + 1);
                contact.local = contact.key.bodies;
                contact.normal_impulse = if rng.random_bool(0.3) { 0.0 } else { rng.random_range(0.0..1.0) };
                contact.tangent_impulse = rng.random_range(-0.5..0.5);
                contacts.push(contact);
            }
        }
        prepare_patches(&mut contacts);
        contacts
    }

    fn velocity(rng: &mut StdRng) -> BodyVelocity {
        let mut v = || rng.random_range(-1.0..1.0);
        BodyVelocity { linear: DVec2::new(v(), v()), angular: v() }
    }

    #[test]
    fn two_patches_in_lanes_give_the_bits_of_one_after_the_other() {
        let mut rng = StdRng::seed_from_u64(14);
        let mut cases = [0usize; 4];
        for _ in 0..4000 {
            let contacts = two_patches(&mut rng);
            assert!(pairable(&contacts));
            let bodies: Vec<BodyVelocity> = (0..4).map(|_| velocity(&mut rng)).collect();
            let (mut lane_contacts, mut lane_bodies) = (contacts.clone(), bodies.clone());
            let lane_changes = solve_two_patches(&mut lane_contacts, lane_bodies.as_mut_slice());
            let (mut one_contacts, mut one_bodies) = (contacts.clone(), bodies.clone());
            let mut one_changes = [0.0; 2];
            for (k, change) in one_changes.iter_mut().enumerate() {
                let unit = &mut one_contacts[2 * k..2 * k + 2];
                *change = solve_unit(unit, one_bodies.as_mut_slice(), Accumulator::Velocity, Pass::Relax);
            }
            let bits = |v: &[BodyVelocity]| {
                v.iter().flat_map(|v| [v.linear.x, v.linear.y, v.angular].map(f64::to_bits)).collect::<Vec<_>>()
            };
            assert_eq!(bits(&lane_bodies), bits(&one_bodies));
            assert_eq!(lane_changes.map(f64::to_bits), one_changes.map(f64::to_bits));
            for (lane, one) in lane_contacts.iter().zip(&one_contacts) {
                assert_eq!(lane.normal_impulse.to_bits(), one.normal_impulse.to_bits());
                assert_eq!(lane.tangent_impulse.to_bits(), one.tangent_impulse.to_bits());
            }
            // Which of the block's cases the first patch took.
            let (p1, p2) = (one_contacts[0].normal_impulse, one_contacts[1].normal_impulse);
            cases[usize::from(p1 > 0.0) + 2 * usize::from(p2 > 0.0)] += 1;
        }
        // Every case of which ends push came up.
        assert!(cases.iter().all(|&n| n > 100), "{cases:?}");
    }

    #[test]
    fn patches_that_share_a_body_are_not_paired() {
        let mut rng = StdRng::seed_from_u64(3);
        let mut contacts = two_patches(&mut rng);
        assert!(pairable(&contacts));
        for end in &mut contacts[2..4] {
            (end.key.bodies, end.local) = ((1, 3), (1, 3));
        }
        assert!(!pairable(&contacts));
        let mut contacts = two_patches(&mut rng);
        contacts[2].local = (5, 0);
        assert!(!pairable(&contacts), "the island's slots decide too");
        let mut contacts = two_patches(&mut rng);
        contacts[2].patch_with_next = false;
        assert!(!pairable(&contacts), "a lone contact is updated alone");
        assert!(!pairable(&contacts[..3]));
    }
}
