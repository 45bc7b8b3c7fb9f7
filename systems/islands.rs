//! Islands: union-find over the pairs in contact (static bodies do not join islands), and each
//! body's level — its distance from a static body in the contact graph — which orders the
//! contact solver from the ground up and tells shock propagation which body is below.

use super::{BodyRecord, StepContext, find, union};

/// Level of a body that touches no chain of contacts down to a static body.
pub const UNGROUNDED: u32 = u32::MAX;

/// Fills `island_of` (a representative body slot per body) and `levels`; kept as they are
/// where the colliding pairs and the static bodies are those they were found from (a still
/// structure's every step). The sleep stage writes its own islands over `island_of` and forgets
/// the inputs, so they are found again after it.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let count = ctx.bodies.len();
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let touching = || live.iter().filter(|slot| slot.colliding()).map(|slot| slot.bodies);
    let (pairs, statics, islands) = &mut buffers.island_inputs;
    let unchanged = buffers.island_of.len() == count
        && statics.len() == count
        && ctx.bodies.iter().zip(statics.iter()).all(|(body, &was)| body.is_static == was)
        && touching().eq(pairs.iter().copied());
    if unchanged {
        ctx.profile.counters.islands += *islands;
        return;
    }
    pairs.clear();
    pairs.extend(touching());
    statics.clear();
    statics.extend(ctx.bodies.iter().map(|body| body.is_static));
    *islands = find_islands(ctx.bodies, pairs, &mut buffers.island_of, &mut buffers.levels);
    ctx.profile.counters.islands += *islands;
}

/// Fills `island_of` and `levels` from the colliding `pairs`; returns the count of islands
/// (of bodies that are not static).
pub(crate) fn find_islands(
    bodies: &[BodyRecord],
    pairs: &[(u32, u32)],
    island_of: &mut Vec<u32>,
    levels: &mut Vec<u32>,
) -> u64 {
    let count = bodies.len();
    island_of.clear();
    island_of.extend(0..count as u32);
    levels.clear();
    levels.extend(bodies.iter().map(|b| if b.is_static { 0 } else { UNGROUNDED }));
    for &(a, b) in pairs {
        if !bodies[a as usize].is_static && !bodies[b as usize].is_static {
            union(island_of, a, b);
        }
    }
    for i in 0..count as u32 {
        let root = find(island_of, i);
        island_of[i as usize] = root;
    }
    // Levels by relaxation (Bellman–Ford on unit edges): a stack of k bodies settles in k sweeps.
    loop {
        let mut changed = false;
        for &(a, b) in pairs {
            let (la, lb) = (levels[a as usize], levels[b as usize]);
            if la.saturating_add(1) < lb {
                levels[b as usize] = la + 1;
                changed = true;
            } else if lb.saturating_add(1) < la {
                levels[a as usize] = lb + 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    (0..count).filter(|&i| !bodies[i].is_static && island_of[i] == i as u32).count() as u64
}
