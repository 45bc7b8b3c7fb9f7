//! Overlap recovery: a contact for two bodies whose curves cross (overlapping input, a teleport,
//! or a sub-step accepted at the retry limit), so the contact solver can push them apart.
//!
//! Crossing curves have no nearest points, only crossing points. The recovery contact takes
//! the normal from both curves' outward normals at the crossings (`Σ (n_B − n_A)`, normalised:
//! B's outward normal and the inward normal of A both point from B towards A) and the depth
//! from the deepest sample of either curve on the wrong side of the crossings' chord, within
//! the chord's span: 8 samples per segment, so the depth is approximate (exact for straight
//! pieces at the samples). It only drives the split-impulse push-out; once the curves no longer
//! cross, the exact contacts of the narrow phase take over.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::pose::Pose;
use crate::geometry::query::{BodyShape, SegmentIntersection};

/// Samples per segment when looking for the deepest point.
const SAMPLES_PER_SEGMENT: usize = 8;

/// The contact that pushes two crossing bodies apart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecoveryContact {
    /// Where the push acts: halfway between the deepest point and the chord.
    pub point: DVec2,
    /// Unit normal, outward of B (towards A).
    pub normal: DVec2,
    /// How far the deepest point lies past the chord (m), `≥ 0`.
    pub depth: f64,
    /// Segment of A at the deepest point (or at the first crossing).
    pub segment_a: u32,
    /// Segment of B at the first crossing.
    pub segment_b: u32,
    /// Global parameter on A of that point.
    pub u_a: f64,
    /// Global parameter on B of the first crossing.
    pub u_b: f64,
    /// Unfloored tolerances `(λ_A(u_A), λ_B(u_B))`, for friction.
    pub raw_lambda: (f64, f64),
}

/// The recovery contact of two bodies whose curves cross at `crossings` (A's and B's segment
/// parameters), or `None` if the crossings give no normal (their normals cancel).
#[must_use]
pub fn overlap_recovery(
    a: &BodyShape<'_>,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    pose_b: &Pose,
    crossings: &[SegmentIntersection],
) -> Option<RecoveryContact> {
    let first = crossings.first()?;
    let point_of =
        |c: &SegmentIntersection| pose_a.transform_point(a.spline.segment(c.segment_a as usize).position(c.t));
    let normal_sum = crossings.iter().fold(DVec2::ZERO, |sum, c| {
        let n_b = pose_b.rotate(b.spline.outward_normal(f64::from(c.segment_b) + c.s));
        let n_a = pose_a.rotate(a.spline.outward_normal(f64::from(c.segment_a) + c.t));
        sum + n_b - n_a
    });
    let normal = normal_sum.try_normalize()?;
    let tangent = normal.perp();
    let centre = crossings.iter().map(point_of).fold(DVec2::ZERO, |s, p| s + p) / crossings.len() as f64;
    let (low, high) = crossings.iter().map(point_of).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let x = (p - centre).dot(tangent);
        (lo.min(x), hi.max(x))
    });
    let deep_a = deepest(a, pose_a, centre, -normal, tangent, (low, high));
    let deep_b = deepest(b, pose_b, centre, normal, tangent, (low, high));
    let (depth, point, u_a) = match (deep_a, deep_b) {
        (Some((da, pa, ua)), Some((db, _, _))) if da >= db => (da, pa + 0.5 * da * normal, ua),
        (Some((da, pa, ua)), None) => (da, pa + 0.5 * da * normal, ua),
        (_, Some((db, pb, _))) => (db, pb - 0.5 * db * normal, f64::from(first.segment_a) + first.t),
        (None, None) => (0.0, centre, f64::from(first.segment_a) + first.t),
    };
    Some(RecoveryContact {
        point,
        normal,
        depth,
        segment_a: (u_a.floor() as u32).min(a.spline.segment_count() as u32 - 1),
        segment_b: first.segment_b,
        u_a,
        u_b: f64::from(first.segment_b) + first.s,
        raw_lambda: (a.rugosity.tolerance_at(u_a), b.rugosity.tolerance_at(f64::from(first.segment_b) + first.s)),
    })
}

/// The sample of a body's curve farthest along `inward` from `centre` (with its depth, point and
/// global parameter), among those within the span `(low, high)` along `tangent`; `None` if no
/// sample lies past the chord.
fn deepest(
    shape: &BodyShape<'_>,
    pose: &Pose,
    centre: DVec2,
    inward: DVec2,
    tangent: DVec2,
    (low, high): (f64, f64),
) -> Option<(f64, DVec2, f64)> {
    let mut best: Option<(f64, DVec2, f64)> = None;
    for (i, segment) in shape.spline.segments().enumerate() {
        for k in 0..SAMPLES_PER_SEGMENT {
            let t = (k as f64 + 0.5) / SAMPLES_PER_SEGMENT as f64;
            let p = pose.transform_point(segment.position(t));
            let along = (p - centre).dot(tangent);
            let depth = (p - centre).dot(inward);
            if along < low || along > high || depth <= 0.0 {
                continue;
            }
            if best.is_none_or(|(d, _, _)| depth > d) {
                best = Some((depth, p, i as f64 + t));
            }
        }
    }
    best
}

/// Which of two bodies lies inside the other, with no curves meeting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    /// A lies inside B.
    AInB,
    /// B lies inside A.
    BInA,
}

/// The contact that pushes a body lying wholly inside another out of it: out through the
/// outer boundary's point nearest the inner body's centre of mass, along the outer's outward
/// normal there, as deep as the inner body's deepest sample lies behind the tangent there. A
/// body inside another has no crossing points for [`overlap_recovery`]; this is its
/// counterpart. `None` when no sample lies behind the tangent (not contained after all).
#[must_use]
pub fn containment_recovery(
    a: &BodyShape<'_>,
    pose_a: &Pose,
    b: &BodyShape<'_>,
    pose_b: &Pose,
    containment: Containment,
) -> Option<RecoveryContact> {
    let (inner, inner_pose, outer, outer_pose) = match containment {
        Containment::AInB => (a, pose_a, b, pose_b),
        Containment::BInA => (b, pose_b, a, pose_a),
    };
    // The body frame's origin is the centre of mass.
    let nearest = outer.spline.nearest_point(outer_pose.inverse_transform_point(inner_pose.position));
    let on_outer = outer_pose.transform_point(nearest.position);
    let outward = outer_pose.rotate(outer.spline.outward_normal(nearest.parameter));
    let tangent = outward.perp();
    let (depth, point, u_inner) =
        deepest(inner, inner_pose, on_outer, -outward, tangent, (f64::NEG_INFINITY, f64::INFINITY))?;
    let u_outer = nearest.parameter;
    let segment = |shape: &BodyShape<'_>, u: f64| (u.floor() as u32).min(shape.spline.segment_count() as u32 - 1);
    // The normal points from B towards A: A moves along it, B against it.
    let (normal, u_a, u_b) = match containment {
        Containment::AInB => (outward, u_inner, u_outer),
        Containment::BInA => (-outward, u_outer, u_inner),
    };
    Some(RecoveryContact {
        point: point + 0.5 * depth * outward,
        normal,
        depth,
        segment_a: segment(a, u_a),
        segment_b: segment(b, u_b),
        u_a,
        u_b,
        raw_lambda: (a.rugosity.tolerance_at(u_a), b.rugosity.tolerance_at(u_b)),
    })
}
