//! Broad phase: sweep-and-prune on the swept world bounds, giving sorted candidate pairs; pairs
//! whose collision groups do not interact, and excluded pairs, are left out.

use super::StepContext;

/// Fills `candidate_pairs` with every pair of bodies (not both static) whose swept bounds
/// overlap, as `(a, b)` slot pairs with `a < b`, sorted.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let bounds = &buffers.swept_bounds;
    buffers.sweep_order.clear();
    buffers.sweep_order.extend(0..bounds.len() as u32);
    buffers
        .sweep_order
        .sort_unstable_by(|&i, &j| bounds[i as usize].0.x.total_cmp(&bounds[j as usize].0.x).then(i.cmp(&j)));
    buffers.candidate_pairs.clear();
    for (k, &i) in buffers.sweep_order.iter().enumerate() {
        let (low_i, high_i) = bounds[i as usize];
        for &j in &buffers.sweep_order[k + 1..] {
            let (low_j, high_j) = bounds[j as usize];
            if low_j.x > high_i.x {
                break;
            }
            let (a, b) = (&ctx.bodies[i as usize], &ctx.bodies[j as usize]);
            let pair = (i.min(j), i.max(j));
            // Static and kinematic bodies never touch each other (as in Box2D); a kinematic
            // body is tested against sleeping ones, to wake them.
            let driven = (a.kinematic && b.asleep) || (b.kinematic && a.asleep);
            if (!(a.is_static && b.is_static) || driven)
                && low_j.y <= high_i.y
                && low_i.y <= high_j.y
                && a.groups.interact(b.groups)
                && buffers.excluded_pairs.binary_search(&pair).is_err()
            {
                buffers.candidate_pairs.push(pair);
            }
        }
    }
    buffers.candidate_pairs.sort_unstable();
    ctx.profile.counters.candidate_pairs += buffers.candidate_pairs.len() as u64;
}
