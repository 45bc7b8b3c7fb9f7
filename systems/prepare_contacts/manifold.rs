//! A pair's touches for the solver: its manifold's contacts and its recovery contact, each flat
//! patch reduced to its two ends ([`reduced_touches`]).

use super::Touch;
use crate::dynamics::solver::{ContactKey, PATCH_END, RECOVERY_ORDINAL};
use crate::systems::PairSlot;

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
pub(super) fn reduce_manifold(touches: &mut Vec<Touch>, from: usize) {
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
