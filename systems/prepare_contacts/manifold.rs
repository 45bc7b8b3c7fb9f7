//! A pair's touches for the solver: its manifold's contacts and its recovery contact, each flat
//! patch reduced to its two ends ([`reduced_touches`]).

use glam::DVec2;

use super::Touch;
use crate::dynamics::solver::{ContactKey, PATCH_END, RECOVERY_ORDINAL};
use crate::geometry::query::BodyContact;
use crate::systems::PairSlot;

/// Appends to `touches` the solver's touches of `slot`: its manifold's contacts and its recovery
/// contact (bands floored at `min_band`), reduced to each flat patch's two ends
/// ([`reduce`]). They depend on the manifold, the recovery contact, the pair's bodies
/// (the keys) and `min_band`, so a slot keeps them while those are unchanged
/// (`PairSlot::touches`; checked in debug builds, `validate::after`).
///
/// The reduction reads only the candidates' normals and points, so it is made on their indices
/// (the manifold's contacts, then the recovery contact) and only the touches it keeps are built
/// and pushed: a box on a box of the base-20 pyramid has about six contacts and keeps two, and
/// building, pushing and swapping all six took about 740 instructions a pair against about 510.
pub(crate) fn reduced_touches(slot: &PairSlot, min_band: f64, touches: &mut Vec<Touch>) {
    let contacts = &slot.manifold().contacts[..];
    let recovery = slot.recovery.as_ref();
    let count = contacts.len() + usize::from(recovery.is_some());
    let normal =
        |i: usize| contacts.get(i).map_or_else(|| recovery.map_or(DVec2::ZERO, |r| r.normal), |c| c.contact.normal);
    let point =
        |i: usize| contacts.get(i).map_or_else(|| recovery.map_or(DVec2::ZERO, |r| r.point), |c| c.contact.point);
    let keep = |i: usize, end: End| touches.push(touch(slot, min_band, i, end));
    // Reduced before the solver contacts are built: a flat overlap's inner points cost nothing
    // more.
    reduce_candidates(count, normal, point, keep);
}

/// [`reduce`] of candidates `0..count`: their indices on the stack up to [`SMALL`], in a buffer
/// each thread keeps beyond (grown once: no allocation per step); one candidate is kept alone.
#[inline(always)]
fn reduce_candidates(
    count: usize,
    normal: impl Fn(usize) -> DVec2,
    point: impl Fn(usize) -> DVec2,
    mut keep: impl FnMut(usize, End),
) {
    if count == 0 {
        // A pair near but not touching (most of a landing pile's): nothing to keep, and no
        // indices set out for it.
        return;
    }
    if count == 1 {
        // One candidate: a lone contact (a blob on a blob, mostly).
        keep(0, End::Lone);
    } else if count <= SMALL {
        let mut small = [0; SMALL];
        let order = &mut small[..count];
        for (k, place) in order.iter_mut().enumerate() {
            *place = k as u32;
        }
        reduce(order, normal, point, keep);
    } else {
        LARGE.with_borrow_mut(|order| {
            order.clear();
            order.extend(0..count as u32);
            reduce(order, normal, point, keep);
        });
    }
}

thread_local! {
    /// The indices of a pair with more than [`SMALL`] candidates, kept by each thread.
    static LARGE: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Candidates a pair reduces with their indices on the stack (more, rare, take a buffer each
/// thread keeps).
const SMALL: usize = 16;

/// The touch of candidate `i` of `slot` (its manifold's contacts, then its recovery contact),
/// kept by the reduction as `end`.
#[inline(always)]
fn touch(slot: &PairSlot, min_band: f64, i: usize, end: End) -> Touch {
    let (contacts, recovery) = (&slot.manifold().contacts[..], slot.recovery.as_ref());
    let mut touch = match (contacts.get(i), recovery) {
        (Some(contact), _) => {
            let segments = (contact.segment_a, contact.segment_b);
            let c = &contact.contact;
            Touch {
                key: ContactKey {
                    bodies: slot.bodies,
                    segment_a: segments.0,
                    segment_b: segments.1,
                    // Read only where it keeps its own key.
                    ordinal: if end == End::Lone { ordinal(contacts, i) } else { 0 },
                },
                segments,
                point: c.point,
                normal: c.normal,
                penetration: c.penetration,
                band: c.lambda_a + c.lambda_b,
                raw_lambda: (c.raw_lambda_a, c.raw_lambda_b),
                parameters: (contact.u_a, contact.u_b),
                patch_with_next: false,
            }
        }
        (None, Some(recovery)) => {
            let raw_lambda = recovery.raw_lambda;
            let band = raw_lambda.0.max(min_band) + raw_lambda.1.max(min_band);
            Touch {
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
            }
        }
        (None, None) => unreachable!("an index past the pair's candidates"),
    };
    if let End::Low(patch) | End::High(patch) = end {
        // The pair's `patch`-th patch's low or high end, whichever leaf pair found it.
        touch.patch_with_next = matches!(end, End::Low(_));
        let ordinal = u32::from(matches!(end, End::High(_)));
        touch.key = ContactKey { segment_a: PATCH_END, segment_b: patch, ordinal, ..touch.key };
    }
    touch
}

/// The ordinal of the manifold's contact `i`: how many contacts of its segment pair come just
/// before it.
fn ordinal(contacts: &[BodyContact], i: usize) -> u32 {
    let segments = |c: &BodyContact| (c.segment_a, c.segment_b);
    let own = segments(&contacts[i]);
    contacts[..i].iter().rev().take_while(|c| segments(c) == own).count() as u32
}

/// What a kept candidate is: a lone contact (its own key), or the low or high end of the pair's
/// `k`-th patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    Lone,
    Low(u32),
    High(u32),
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
/// The candidates are `order` (their indices, in the manifold's order; reordered as the groups
/// are gathered), each with its `normal` and `point`; `keep` is given each one kept, in order.
#[inline(always)]
fn reduce(
    order: &mut [u32],
    normal: impl Fn(usize) -> DVec2,
    point: impl Fn(usize) -> DVec2,
    mut keep: impl FnMut(usize, End),
) {
    // The candidates not yet grouped are `order[read..]`.
    let (mut read, mut patches) = (0, 0);
    while read < order.len() {
        let first = normal(order[read] as usize);
        // Gather the group behind its first member (a candidate already in its place stays).
        let mut group_end = read + 1;
        for j in read + 1..order.len() {
            if normal(order[j] as usize).dot(first) >= SAME_NORMAL_COS {
                if j != group_end {
                    (order[group_end], order[j]) = (order[j], order[group_end]);
                }
                group_end += 1;
            }
        }
        let across = first.perp();
        let (mut low, mut high) = (read, read);
        let (mut lowest, mut highest) =
            (point(order[read] as usize).dot(across), point(order[read] as usize).dot(across));
        for (k, &index) in (read + 1..).zip(&order[read + 1..group_end]) {
            let along = point(index as usize).dot(across);
            if along < lowest {
                (low, lowest) = (k, along);
            }
            if along > highest {
                (high, highest) = (k, along);
            }
        }
        if high != low {
            keep(order[low] as usize, End::Low(patches));
            keep(order[high] as usize, End::High(patches));
            patches += 1;
        } else {
            keep(order[low] as usize, End::Lone);
        }
        read = group_end;
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{End, SMALL, reduce_candidates};

    /// A flat patch of many candidates keeps its two extreme points, as its patch's low and high
    /// end, and a candidate of another normal stays alone, whether the indices fit on the stack
    /// or not; a single candidate is kept alone.
    #[test]
    fn a_patch_keeps_its_two_ends_and_a_lone_contact_itself() {
        for count in [3, SMALL, SMALL + 5, 3 * SMALL] {
            // Candidate 1 has its own normal; the others lie along x on one flat, shuffled (5 is prime
            // to every count, so no two share a point).
            let normal = |i: usize| if i == 1 { DVec2::new(1.0, 1.0).normalize() } else { DVec2::Y };
            let point = |i: usize| DVec2::new(((i * 5) % count) as f64, 0.0);
            let mut kept = Vec::new();
            reduce_candidates(count, normal, point, |i, end| kept.push((i, end)));
            let flat: Vec<usize> = (0..count).filter(|&i| i != 1).collect();
            // Ends along the patch's own direction, `normal.perp()` (−x here).
            let along = |i: &&usize| -(((**i * 5) % count) as i64);
            let lowest = *flat.iter().min_by_key(along).unwrap();
            let highest = *flat.iter().max_by_key(along).unwrap();
            assert_eq!(
                kept,
                vec![(lowest, End::Low(0)), (highest, End::High(0)), (1, End::Lone)],
                "{count} candidates"
            );
        }
        let mut kept = Vec::new();
        reduce_candidates(1, |_| DVec2::Y, |_| DVec2::ZERO, |i, end| kept.push((i, end)));
        assert_eq!(kept, vec![(0, End::Lone)]);
    }
}
