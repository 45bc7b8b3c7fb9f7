//! Deciding a carry: whether a pair's last result still holds at the current poses
//! (docs/model.md §3b).

use super::{Drift, PairSlot, PairState, least};
use crate::components::RigidState;
use crate::geometry::pose::Pose;
use crate::systems::{BodyMotion, BodyRecord, closing_bound};

/// What deciding a carry reads (docs/model.md §3b).
pub(super) struct Carry<'a> {
    pub(super) bodies: &'a [BodyRecord],
    pub(super) states: &'a [RigidState],
    /// Per body: what the closing bound reads ([`crate::systems::body_motions`]).
    pub(super) motions: &'a [BodyMotion],
    /// The time a carried pair's margin must cover: what is left of the step, or after the
    /// step's last sub-step the time the margins cover ([`crate::systems::margin_horizon`]).
    pub(super) horizon: f64,
    pub(super) poses: &'a [Pose],
    /// Per body: how far any of its points has moved since the last phase (empty where that
    /// is not known).
    pub(super) moved: &'a [f64],
    /// Per body: whether `world_mut` broke it (gathered with the states).
    pub(super) broken: &'a [bool],
    /// `SimulationSettings::coherence`.
    pub(super) tolerance: f64,
    /// `SimulationSettings::contact_reuse`.
    pub(super) reuse: f64,
    /// `CurvePairSettings::intersection_tolerance`.
    pub(super) intersection_tolerance: f64,
}

impl Carry<'_> {
    /// The drift of a separate pair that may be carried from its last query (docs/model.md
    /// §3b): every leaf pair then had clearance `c` (its distance less the combined band) and
    /// every leaf pair not listed was farther apart than the query margin `m`; after the
    /// distances have changed by at most `δ ≤ min(½ c, ¼ m)`, no piece can be within the band or
    /// crossing, so the pair is still separate, and its gaps less that drift still bound
    /// conservative advancement (the quarter keeps the leaf pairs not listed, `¾ m` apart, from
    /// shortening a sub-step that the bodies' own margins allow). The rest of the margin must
    /// also cover, at the pair's present relative motion, the time to the next query that could
    /// be needed (what is left of the step, which the next sub-step ends at the latest, or the
    /// horizon after the step's last sub-step), or the leaf pairs not listed would cut the next
    /// sub-step short where a query, with a margin for that motion, would not.
    /// `None` (a query is needed) for any other pair, and always with `coherence = 0`.
    ///
    /// A pair in contact is carried the same way while the drift is also at most
    /// `contact_reuse` of each contact's combined band and each contact leaf pair is still
    /// proven apart by more than the intersection tolerance: then no leaf pair has come into
    /// the band or crossed, and its contacts, evaluated again at their last parameters
    /// ([`PairJob::detect`](super::detect::PairJob::detect)), are within the drift of the nearest points' distances (the ends
    /// of an overlap lie on the band's edge, so such an end may now lie up to the drift
    /// outside it; contacts not evaluated again while the bodies barely moved are off by at
    /// most that motion more, [`PairJob::unmoved`](super::detect::PairJob::unmoved)). Moved with the bodies by `coherence` of
    /// the band, such contacts kept a pyramid creeping (docs/model.md §3b). Never for a body
    /// broken through `world_mut` (its geometry or state gone).
    pub(super) fn drift(&self, (a, b): (u32, u32), sensor: bool, previous: &PairSlot) -> Option<Carried> {
        let solved_at = previous.solved_at?;
        let manifold = previous.manifold();
        let (a, b) = (a as usize, b as usize);
        // Separate and no sensor on either side: then it had no recovery contact (those come
        // with an intersecting pair) and no containment (only a sensor pair records one).
        let separate = manifold.state == PairState::Separate && manifold.contacts.is_empty();
        let in_contact = manifold.state == PairState::Contact && previous.recovery.is_none() && !previous.contained;
        let sensor = sensor || previous.sensor;
        let whole = !self.broken.get(a).copied().unwrap_or(true) && !self.broken.get(b).copied().unwrap_or(true);
        if self.tolerance <= 0.0 || !(separate || (in_contact && self.reuse > 0.0)) || sensor || !whole {
            return None;
        }
        let radii = (self.bodies[a].radius, self.bodies[b].radius);
        let (pose_a, pose_b) = (&self.poses[a], &self.poses[b]);
        // Bodies that have barely moved since the last phase (a still structure's every pair):
        // the last phase's drift grown by their motions is a bound as sound as the drift worked
        // out from the query's poses, and larger only by rounding-sized motions. Where it does
        // not carry the pair (bodies that move as one keep a drift of zero in each other's
        // frames), the drift is worked out.
        if let (Some(&moved_a), Some(&moved_b)) = (self.moved.get(a), self.moved.get(b))
            && moved_a + moved_b <= STILL_MOTION * (radii.0 + radii.1)
        {
            let last = previous.drift;
            let grown = Drift { a: last.a + moved_a, b: last.b + moved_b, gap: last.gap + moved_a + moved_b };
            if let Some(carried) = self.carries(previous, (a, b, separate), None, grown) {
                return Some(carried);
            }
        }
        let now = pose_b.relative(pose_a);
        let drift = solved_at.drift((&self.states[a], &self.states[b]), (pose_a, pose_b), &now, radii);
        self.carries(previous, (a, b, separate), Some(&now), drift)
    }

    /// Whether `previous` (`separate`, or in contact with contacts that may be reused, and
    /// queried) is carried with its bodies moved by `drift` since its query; `now` is A's pose in
    /// B's frame where the caller has it (see [`Carry::drift`]).
    fn carries(
        &self,
        previous: &PairSlot,
        (a, b, separate): (usize, usize, bool),
        now: Option<&Pose>,
        drift: Drift,
    ) -> Option<Carried> {
        let solved_at = previous.solved_at?;
        let manifold = previous.manifold();
        let covers = || {
            let (speed, growth) = closing_bound(self.motions, (a, b));
            let h = self.horizon;
            speed * h + growth * h * h <= solved_at.margin - drift.gap
        };
        // Written so that a NaN refuses the carry.
        let kept_apart = drift.gap <= apart_limit(manifold.clearance(), solved_at.margin) && covers();
        if separate || !kept_apart {
            return kept_apart.then_some(Carried { drift, crossing: None });
        }
        let in_band = manifold
            .contacts
            .iter()
            .all(|found| drift.gap <= self.reuse * (found.contact.lambda_a + found.contact.lambda_b));
        let evaluated = previous.evaluated_angle_b.is_some_and(f64::is_finite);
        if !(in_band && evaluated) {
            return None;
        }
        let now = now.copied().unwrap_or_else(|| self.poses[b].relative(&self.poses[a]));
        let crossing = self.uncrossed(previous, (a, b), &now, drift.gap)?;
        Some(Carried { drift, crossing: Some(crossing) })
    }

    /// Whether every leaf pair of `previous` last seen in contact is still proven apart by more
    /// than the intersection tolerance, `drift` after its query: each leaf memory's bound, less
    /// the motion since its search (from its pose of A in B's frame to `now`, turns times A's
    /// radius), less the drift. The tolerance is taken at its largest for the bodies' sizes.
    /// `Some` record of the pass that proved it (`PairSlot::crossing`) where it is.
    fn uncrossed(&self, previous: &PairSlot, (a, b): (usize, usize), now: &Pose, drift: f64) -> Option<(Pose, f64)> {
        let radius = self.bodies[a].radius;
        let touch = self.touch((a, b));
        let moved = |from: &Pose| relative_motion(from, now, radius);
        // Each memory's motion is at most its motion at the last pass plus A's motion in B's
        // frame since (both are distances of poses): the least room then, less that motion, is
        // a lower bound of every memory's (with room for rounding, so that it never passes
        // where the pass over the memories would not).
        if let Some((then, room)) = previous.crossing
            && room - moved(&then) - drift > touch + CROSSING_ROUNDING * radius
        {
            return Some((then, room));
        }
        // The least room, NaN if any is (then nothing passes, as `all` would refuse it).
        let memories = previous.query.memory.iter().filter(|memory| memory.seed.is_some());
        let room =
            memories.fold(f64::INFINITY, |room, memory| least(room, memory.lower_bound - moved(&memory.relative)));
        (room - drift > touch).then_some((*now, room))
    }

    /// The intersection tolerance at its largest for the sizes of bodies `a` and `b`.
    fn touch(&self, (a, b): (usize, usize)) -> f64 {
        self.intersection_tolerance * 2.0 * self.bodies[a].radius.max(self.bodies[b].radius)
    }

    /// The largest drift gap at which the crossing check of `slot` (carried, in contact) still
    /// passes from the record of its last pass ([`Carry::uncrossed`]) as its bodies move on,
    /// `None` where it has no record. While the drift gap grows from `g` to `g'`, the bodies'
    /// points move in the world by `m_A + m_B ≤ g' − g`, and A's pose in B's frame by at most
    /// `m_A + k m_B`: B's turn `Δθ_B ≤ m_B / ρ_B` moves A's position in B's frame by
    /// `Δθ_B |x_A − x_B|` and turns A's points by `Δθ_B ρ_A` more, so
    /// `k = (|x_A − x_B| + 2 ρ_A + ρ_B) / ρ_B` (room for the bodies' distance to change by
    /// `ρ_A + ρ_B`, far more than the drift can: `contact_reuse ≤ 1e-3` of the band). The check
    /// `room − moved − g' > touch` then holds while `g' − g < spare / (1 + k)`, `spare` its
    /// margin now less as much room for rounding again.
    pub(super) fn crossing_limit(&self, slot: &PairSlot) -> Option<f64> {
        let (then, room) = slot.crossing?;
        let (a, b) = slot.body_indices();
        let (radius, radius_b) = (self.bodies[a].radius, self.bodies[b].radius);
        let (pose_a, pose_b) = (&self.poses[a], &self.poses[b]);
        let moved = relative_motion(&then, &pose_b.relative(pose_a), radius);
        let lever = (pose_a.position.distance(pose_b.position) + 2.0 * radius + radius_b) / radius_b;
        let gap = slot.drift.gap;
        let spare = room - moved - gap - self.touch((a, b)) - 2.0 * CROSSING_ROUNDING * radius;
        Some(gap + spare / (1.0 + lever))
    }
}

/// The most drift a pair may be carried with by its separate leaf pairs (docs/model.md §3b):
/// half the smallest clearance `c`, a quarter of the query margin `m`; NaN where either is (a
/// leaf gap from an older snapshot has no band, so its clearance is unknown), which refuses.
pub(super) fn apart_limit(clearance: f64, margin: f64) -> f64 {
    least(0.5 * clearance, 0.25 * margin)
}

/// How far A's pose in B's frame has moved from `from` to `now`: its position's distance plus
/// its rotation's times A's radius (a turn by `Δ` moves a point at `ρ` by exactly `ρ |Δr|`).
fn relative_motion(from: &Pose, now: &Pose, radius: f64) -> f64 {
    from.position.distance(now.position) + from.rotation.distance(now.rotation) * radius
}

/// What a carried pair takes to its slot: its drift, and where its crossing check last went
/// over its leaf memory (for a pair in contact).
#[derive(Clone, Copy)]
pub(super) struct Carried {
    pub(super) drift: Drift,
    pub(super) crossing: Option<(Pose, f64)>,
}

/// Room for rounding, relative to A's radius, of the crossing check from its last pass
/// ([`Carry::uncrossed`]).
const CROSSING_ROUNDING: f64 = 1e-12;

/// Motion since the last phase, as a fraction of the bodies' radii, below which a carried
/// pair's drift is the last phase's grown by it ([`Carry::drift`]): a settled structure moves
/// by rounding errors, 1e-16 m a step.
pub(super) const STILL_MOTION: f64 = 1e-12;

#[cfg(test)]
mod tests {
    use super::apart_limit;

    #[test]
    fn an_unknown_clearance_refuses_the_carry() {
        assert_eq!(apart_limit(2.0, 4.0), 1.0);
        assert_eq!(apart_limit(4.0, 4.0), 1.0);
        // NaN, so that `drift ≤ limit` fails for any drift (`f64::min` would give the margin's).
        assert!(apart_limit(f64::NAN, 4.0).is_nan());
        assert!(apart_limit(2.0, f64::NAN).is_nan());
    }
}
