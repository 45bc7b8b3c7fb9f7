//! Broad phase: sweep-and-prune on the swept world bounds, giving sorted candidate pairs; pairs
//! whose collision groups do not interact, and excluded pairs, are left out. The sweep runs on
//! bounds enlarged beyond the swept ones, and only when a body's swept bounds have left its
//! enlarged ones: until then the pairs it found are filtered again (as Box2D's fat boxes).

use glam::DVec2;
use rayon::prelude::*;

use super::{BodyRecord, StepBuffers, StepContext, SweepEntry};
use crate::components::CollisionGroups;

/// Fills `candidate_pairs` with every pair of bodies (not both static) whose swept bounds
/// overlap, as `(a, b)` slot pairs with `a < b`, sorted.
///
/// The pairs whose *enlarged* bounds overlap are kept from the last sweep while every body's
/// swept bounds lie within its enlarged ones (each swept box grown by [`ENLARGEMENT`] of its
/// larger side): every pair whose swept bounds overlap is then among them, and testing those
/// again gives the candidate pairs exactly as a new sweep would, in the same order. A still
/// structure sweeps once; its broad phase is one pass over its pairs.
pub fn run(ctx: &mut StepContext<'_>) {
    let bodies = ctx.bodies;
    // A static body (not kinematic) does not move: its box is not enlarged.
    let fixed = |slot: usize| bodies[slot].is_static && !bodies[slot].kinematic;
    let buffers = &mut *ctx.buffers;
    // Where the last narrow phase found every body still, the filter measures its room; the
    // rules are compared where it does, or where the last one did.
    let measure = buffers.nearest_gap.is_some();
    let compare = measure || buffers.filter.room > 0.0;
    let same_rules = compare && buffers.filter.same_rules(bodies, &buffers.excluded_pairs);
    let filter = Filter { same_rules, measure };
    let found = find_candidates(ctx.pool, buffers, fixed, filter, |excluded, pair| collides(bodies, excluded, pair));
    ctx.profile.counters.broad_phase_sweeps += u64::from(found == Found::Swept);
    ctx.profile.counters.broad_phase_kept += u64::from(found == Found::Kept);
    ctx.profile.counters.candidate_pairs += ctx.buffers.candidate_pairs.len() as u64;
}

/// How a filter of the pairs may go: whether what `may_collide` reads is as the last filter
/// read it, and whether to measure the filter's room ([`FilterRecord`]).
#[derive(Clone, Copy, Debug)]
struct Filter {
    same_rules: bool,
    measure: bool,
}

/// The last filter of the pairs: the swept bounds it tested, the least room any of its
/// decisions had (how far a bound could move before one changed; 0 where not measured), and
/// what the filter's rules read of each body and the excluded pairs.
#[derive(Debug, Default)]
pub struct FilterRecord {
    bounds: Vec<(DVec2, DVec2)>,
    room: f64,
    bodies: Vec<(bool, bool, bool, CollisionGroups)>,
    excluded: Vec<(u32, u32)>,
}

impl FilterRecord {
    /// Whether what [`collides`] reads (each body's fixedness, kinematic and sleeping flags and
    /// groups, and the excluded pairs) is as the last filter read it; records it where not.
    fn same_rules(&mut self, bodies: &[BodyRecord], excluded: &[(u32, u32)]) -> bool {
        let now = bodies.iter().map(|body| (body.is_static, body.kinematic, body.asleep, body.groups));
        if self.bodies.len() == bodies.len() && self.bodies.iter().copied().eq(now.clone()) && self.excluded == excluded
        {
            return true;
        }
        self.bodies.clear();
        self.bodies.extend(now);
        self.excluded.clear();
        self.excluded.extend_from_slice(excluded);
        self.room = 0.0; // filtered under other rules
        false
    }

    /// Whether the last filter's pairs are the ones a filter of `bounds` would give: every bound
    /// has moved by `δ` at most (in any coordinate) since, and `3δ` is less than the room (a
    /// decision compares two bounds, each moved by at most `δ`; the third `δ` is room for the
    /// rounding of the differences).
    fn keeps(&self, bounds: &[(DVec2, DVec2)]) -> bool {
        if self.bounds.len() != bounds.len() || self.room <= 0.0 {
            return false;
        }
        let moved = self.bounds.iter().zip(bounds).fold(0.0f64, |moved, ((low, high), (now_low, now_high))| {
            moved.max((*now_low - *low).abs().max_element()).max((*now_high - *high).abs().max_element())
        });
        3.0 * moved < self.room
    }
}

/// Fills `candidate_pairs` with the pairs whose swept bounds overlap and that `may_collide`
/// (given the excluded pairs) lets through, sweeping again only where the enlarged bounds no
/// longer hold the swept ones (the bounds of the bodies `fixed` says do not move are not
/// enlarged). Where it did not sweep, `may_collide`'s rules are the last filter's and no bound
/// has moved beyond the room its decisions had, the last filter's pairs are kept as they are (a
/// still structure's every broad phase).
fn find_candidates(
    pool: Option<&rayon::ThreadPool>,
    buffers: &mut StepBuffers,
    fixed: impl Fn(usize) -> bool,
    filter: Filter,
    may_collide: impl Fn(&[(u32, u32)], (u32, u32)) -> bool,
) -> Found {
    // A bound that is not finite (NaN, or infinite, whose enlargement may be NaN): swept as it
    // is, as the sweep always did.
    let finite = buffers.swept_bounds.iter().all(|(low, high)| low.is_finite() && high.is_finite());
    let held =
        finite
            && buffers.enlarged_bounds.len() == buffers.swept_bounds.len()
            && buffers.swept_bounds.iter().zip(&buffers.enlarged_bounds).all(
                |((low, high), (outer_low, outer_high))| low.cmpge(*outer_low).all() && high.cmple(*outer_high).all(),
            );
    if !held {
        buffers.enlarged_bounds.clear();
        if finite {
            buffers.enlarged_bounds.extend(buffers.swept_bounds.iter().enumerate().map(|(slot, &(low, high))| {
                let grow =
                    if fixed(slot) { DVec2::ZERO } else { DVec2::splat(ENLARGEMENT * (high - low).max_element()) };
                (low - grow, high + grow)
            }));
        } else {
            buffers.enlarged_bounds.extend_from_slice(&buffers.swept_bounds);
        }
        sweep(pool, buffers);
    }
    if held && finite && filter.same_rules && buffers.filter.keeps(&buffers.swept_bounds) {
        return Found::Kept;
    }
    let (bounds, candidates) = (&buffers.swept_bounds, &mut buffers.candidate_pairs);
    candidates.clear();
    // The least room of any decision: for an overlapping pair the least of its four overlaps,
    // for another its largest gap (NaN refuses).
    let mut room = f64::INFINITY;
    for &(a, b) in &buffers.enlarged_pairs {
        let ((low_a, high_a), (low_b, high_b)) = (bounds[a as usize], bounds[b as usize]);
        let overlap = low_b.x <= high_a.x && low_b.y <= high_a.y && low_a.x <= high_b.x && low_a.y <= high_b.y;
        if filter.measure {
            let overlaps = [high_a.x - low_b.x, high_a.y - low_b.y, high_b.x - low_a.x, high_b.y - low_a.y];
            let decided = if overlap {
                overlaps.into_iter().fold(f64::INFINITY, f64::min)
            } else {
                -overlaps.into_iter().fold(f64::INFINITY, f64::min)
            };
            room = if decided.is_nan() || decided < room { decided } else { room };
        }
        if (overlap || !finite) && may_collide(&buffers.excluded_pairs, (a, b)) {
            candidates.push((a, b));
        }
    }
    let record = &mut buffers.filter;
    record.room = if filter.measure && finite && filter.same_rules { room } else { 0.0 };
    if record.room > 0.0 {
        record.bounds.clone_from(bounds);
    }
    if held { Found::Filtered } else { Found::Swept }
}

/// How a broad phase found its pairs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Found {
    /// Swept the enlarged bounds, then filtered their pairs.
    Swept,
    /// Filtered the last sweep's pairs.
    Filtered,
    /// Kept the last filter's pairs.
    Kept,
}

/// Enlarged bounds are the swept ones grown by this fraction of their larger side on every
/// side (our choice; a static body's are not grown): a settled 210-box pyramid sweeps once, and
/// a body falling past others sweeps about as often as before.
const ENLARGEMENT: f64 = 0.1;

/// Whether the bodies of `pair` may collide: not both static (as in Box2D; a kinematic body is
/// tested against sleeping ones, to wake them), their collision groups interact, and the pair
/// is not excluded.
#[inline]
fn collides(bodies: &[BodyRecord], excluded: &[(u32, u32)], (i, j): (u32, u32)) -> bool {
    let (a, b) = (&bodies[i as usize], &bodies[j as usize]);
    let driven = (a.kinematic && b.asleep) || (b.kinematic && a.asleep);
    (!(a.is_static && b.is_static) || driven)
        && a.groups.interact(b.groups)
        && (excluded.is_empty() || excluded.binary_search(&(i, j)).is_err())
}

/// Sweep-and-prune on `enlarged_bounds` into `enlarged_pairs`, sorted.
///
/// The sweep runs along the axis on which the bounds' centres spread most: a body is tested
/// against every body whose bounds overlap its own along that axis, so sweeping a tall pile
/// along x tests each blob against its whole column. The pairs are the same along either axis
/// (those overlapping on both), and sorted, so the choice changes no result.
fn sweep(pool: Option<&rayon::ThreadPool>, buffers: &mut StepBuffers) {
    let bounds = &buffers.enlarged_bounds;
    let along_y = spread(bounds, |p| p.y) > spread(bounds, |p| p.x);
    let split = |p: DVec2| if along_y { (p.y, p.x) } else { (p.x, p.y) };
    // The last sweep's order, if it still holds every body once: bodies move little between
    // sweeps, so it is nearly sorted. The order found is the same whatever it starts from (no
    // two entries tie).
    let order = &mut buffers.sweep_order;
    if order.len() != bounds.len() {
        order.clear();
        order.extend((0..bounds.len() as u32).map(|slot| SweepEntry { slot, ..SweepEntry::default() }));
    }
    for entry in order.iter_mut() {
        let (low, high) = bounds[entry.slot as usize];
        let ((low_along, low_across), (high_along, high_across)) = (split(low), split(high));
        (entry.along, entry.across) = ((low_along, high_along), (low_across, high_across));
    }
    sort_nearly_sorted(order);
    let candidates = Candidates { order };
    if let Some(pool) = pool.filter(|_| order.len() >= PARALLEL_SWEEP) {
        // Each stretch of the sweep gathers its pairs into its own buffer, in parallel; joined in
        // stretch order they are the serial sweep's pairs (and are sorted below anyway).
        if buffers.sweep_pairs.len() < STRETCHES {
            buffers.sweep_pairs.resize_with(STRETCHES, Vec::new);
        }
        let length = order.len().div_ceil(STRETCHES);
        pool.install(|| {
            buffers.sweep_pairs.par_iter_mut().enumerate().for_each(|(k, pairs)| {
                let start = (k * length).min(order.len());
                candidates.gather(start, (start + length).min(order.len()), pairs);
            });
        });
        buffers.enlarged_pairs.clear();
        for pairs in &buffers.sweep_pairs {
            buffers.enlarged_pairs.extend_from_slice(pairs);
        }
    } else {
        candidates.gather(0, order.len(), &mut buffers.enlarged_pairs);
    }
    sort_pairs(&mut buffers.enlarged_pairs, &mut buffers.pair_sort, bounds.len());
}

/// Sorts `pairs` (distinct, each `(a, b)` with `a < b < bodies`): counted by first body into
/// the scratch `sorted` (stable), each body's run then sorted by the second by insertion (a
/// body has a few neighbours; a run of more than 16 by `sort_unstable` first), and the buffers
/// swapped. Linear where a comparison sort of the
/// pyramid's 1,287 pairs cost 0.22 M of its 4 M instructions a step; the order is the same
/// (distinct pairs have one sorted order). Neither allocates once the buffers have grown.
fn sort_pairs(pairs: &mut Vec<(u32, u32)>, (sorted, counts): &mut (Vec<(u32, u32)>, Vec<u32>), bodies: usize) {
    counts.clear();
    counts.resize(bodies + 1, 0);
    for &(a, _) in pairs.iter() {
        counts[a as usize + 1] += 1;
    }
    for k in 1..counts.len() {
        counts[k] += counts[k - 1];
    }
    sorted.clear();
    sorted.resize(pairs.len(), (0, 0));
    for &pair in pairs.iter() {
        let at = &mut counts[pair.0 as usize];
        sorted[*at as usize] = pair;
        *at += 1;
    }
    // `counts[a]` is now the end of body `a`'s run, which starts at the end of the one before.
    let mut start = 0;
    for &end in &counts[..bodies] {
        let run = &mut sorted[start..end as usize];
        if run.len() > 16 {
            // A ground or wall with many neighbours.
            run.sort_unstable();
        }
        for i in 1..run.len() {
            let mut k = i;
            while k > 0 && run[k].1 < run[k - 1].1 {
                run.swap(k, k - 1);
                k -= 1;
            }
        }
        start = end as usize;
    }
    std::mem::swap(pairs, sorted);
}

/// Fewer bodies than this are swept on one thread.
const PARALLEL_SWEEP: usize = 256;

/// Stretches of the sweep gathered in parallel: a few per thread, as their costs differ.
const STRETCHES: usize = 8;

/// What the sweep reads: the bodies in sweep order.
struct Candidates<'a> {
    order: &'a [SweepEntry],
}

impl Candidates<'_> {
    /// Into `pairs` (cleared first), every pair `(a, b)`, `a < b`, whose bounds overlap and
    /// whose first body in sweep order is one of `order[start..end]`: each such body is tested
    /// against the bodies after it until one starts past its end along the axis.
    fn gather(&self, start: usize, end: usize, pairs: &mut Vec<(u32, u32)>) {
        pairs.clear();
        for (k, p) in self.order.iter().enumerate().take(end).skip(start) {
            for q in &self.order[k + 1..] {
                if q.along.0 > p.along.1 {
                    break;
                }
                // Written so that a NaN bound overlaps nothing.
                if !(q.across.0 <= p.across.1 && p.across.0 <= q.across.1) {
                    continue;
                }
                let (i, j) = (p.slot, q.slot);
                pairs.push((i.min(j), i.max(j)));
            }
        }
    }
}

/// Sorts the sweep by the lower bound along the axis (ties by slot): by insertion, which costs
/// one pass over a nearly sorted order, until that has cost eight passes' worth of moves, then
/// by `sort_unstable_by`. Neither allocates (the standard stable sort would, for more than about
/// a hundred bodies: no allocation per step).
fn sort_nearly_sorted(order: &mut [SweepEntry]) {
    let before = |p: &SweepEntry, q: &SweepEntry| p.along.0.total_cmp(&q.along.0).then(p.slot.cmp(&q.slot));
    let mut budget = 8 * order.len();
    for i in 1..order.len() {
        let mut k = i;
        while k > 0 && before(&order[k], &order[k - 1]).is_lt() {
            order.swap(k, k - 1);
            k -= 1;
            budget = budget.saturating_sub(1);
            if budget == 0 {
                order.sort_unstable_by(before);
                return;
            }
        }
    }
}

/// How far the centres of `bounds` spread along an axis (`coordinate` picks it): the sum of
/// their squared deviations from their mean.
fn spread(bounds: &[(DVec2, DVec2)], coordinate: impl Fn(DVec2) -> f64) -> f64 {
    let centre = |&(low, high): &(DVec2, DVec2)| coordinate(0.5 * (low + high));
    let mean = bounds.iter().map(centre).sum::<f64>() / bounds.len().max(1) as f64;
    bounds.iter().map(|bound| (centre(bound) - mean).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use glam::DVec2;
    use rand::RngExt;

    use super::{find_candidates, sort_pairs};
    use crate::systems::StepBuffers;

    /// Over rounds of small moves (the enlarged bounds hold) and jumps (they do not), the
    /// candidate pairs are those of a test of every pair, in order, and a still scene sweeps
    /// once and keeps the pairs of the last filter.
    #[test]
    fn candidates_are_every_overlapping_pair_sweeping_only_when_bounds_leave() {
        let mut rng = crate::random::seeded(21);
        let mut buffers = StepBuffers::default();
        let bodies = 40;
        let mut centres: Vec<DVec2> =
            (0..bodies).map(|_| DVec2::new(rng.random_range(0.0..8.0), rng.random_range(0.0..8.0))).collect();
        let sizes: Vec<DVec2> =
            (0..bodies).map(|_| DVec2::new(rng.random_range(0.3..1.5), rng.random_range(0.3..1.5))).collect();
        buffers.excluded_pairs = vec![(0, 1), (2, 5)];
        let may_collide = |excluded: &[(u32, u32)], (a, b): (u32, u32)| (a + b) % 7 != 3 && !excluded.contains(&(a, b));
        let (mut sweeps, mut still_sweeps, mut still_kept) = (0, 0, 0);
        for round in 0..200 {
            let still = (100..120).contains(&round);
            if !still {
                // Body 0 is fixed (its box is not enlarged) and does not move.
                for centre in &mut centres[1..] {
                    *centre += DVec2::new(rng.random_range(-0.002..0.002), rng.random_range(-0.002..0.002));
                }
                if round % 10 == 0 {
                    let jumper = rng.random_range(1..bodies);
                    centres[jumper] += DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                }
            }
            buffers.swept_bounds = centres.iter().zip(&sizes).map(|(&c, &s)| (c - 0.5 * s, c + 0.5 * s)).collect();
            let filter = super::Filter { same_rules: true, measure: true };
            let found = find_candidates(None, &mut buffers, |slot| slot == 0, filter, may_collide);
            let swept = found == super::Found::Swept;
            sweeps += usize::from(swept);
            still_sweeps += usize::from(swept && still && round > 100);
            still_kept += usize::from(found == super::Found::Kept && still);
            let bounds = &buffers.swept_bounds;
            let expected: Vec<(u32, u32)> = (0..bodies as u32)
                .flat_map(|a| (a + 1..bodies as u32).map(move |b| (a, b)))
                .filter(|&(a, b)| {
                    let ((la, ha), (lb, hb)) = (bounds[a as usize], bounds[b as usize]);
                    lb.cmple(ha).all() && la.cmple(hb).all()
                })
                .filter(|&pair| may_collide(&buffers.excluded_pairs, pair))
                .collect();
            assert_eq!(buffers.candidate_pairs, expected, "round {round}");
        }
        // A jump every tenth round (18 outside the still rounds) sweeps unless it is short, the
        // drift now and then; most rounds do not.
        assert!((10..100).contains(&sweeps), "bounds that hold are not swept again ({sweeps} sweeps in 200 rounds)");
        assert_eq!(still_sweeps, 0, "a still scene does not sweep");
        assert_eq!(still_kept, 20, "a still scene keeps the pairs of the last filter in every round");
    }

    #[test]
    fn pairs_sort_as_a_comparison_sort_would() {
        // Every pair of 60 bodies in a scrambled order, less some; one body with 59 neighbours
        // (a ground) takes the long-run path, the others the insertion.
        let bodies = 60u32;
        let mut pairs: Vec<(u32, u32)> = (0..bodies)
            .flat_map(|a| (a + 1..bodies).map(move |b| (a, b)))
            .filter(|&(a, b)| (a * 7 + b * 3) % 5 != 0 || a == 0)
            .collect();
        let mut state = 12345u64;
        for i in (1..pairs.len()).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            pairs.swap(i, (state >> 33) as usize % (i + 1));
        }
        let mut expected = pairs.clone();
        expected.sort_unstable();
        let mut scratch = (Vec::new(), Vec::new());
        sort_pairs(&mut pairs, &mut scratch, bodies as usize);
        assert_eq!(pairs, expected);
        assert!(expected.iter().filter(|p| p.0 == 0).count() > 16);
        // Again on the grown buffers, and on none.
        pairs.reverse();
        sort_pairs(&mut pairs, &mut scratch, bodies as usize);
        assert_eq!(pairs, expected);
        let mut empty = Vec::new();
        sort_pairs(&mut empty, &mut scratch, 0);
        assert!(empty.is_empty());
    }
}
