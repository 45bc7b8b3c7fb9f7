//! Islands: union-find over the pairs in contact (static bodies do not join islands), and each
//! body's level — its distance from a static body in the contact graph — which orders the
//! contact solver from the ground up and tells shock propagation which body is below.

use super::{StepContext, find, union};

/// Level of a body that touches no chain of contacts down to a static body.
pub const UNGROUNDED: u32 = u32::MAX;

/// Fills `island_of` (a representative body slot per body) and `levels`.
pub fn run(ctx: &mut StepContext<'_>) {
    let buffers = &mut *ctx.buffers;
    let count = ctx.bodies.len();
    buffers.island_of.clear();
    buffers.island_of.extend(0..count as u32);
    buffers.levels.clear();
    buffers.levels.extend(ctx.bodies.iter().map(|b| if b.is_static { 0 } else { UNGROUNDED }));
    let live = &buffers.pair_slots[..buffers.candidate_pairs.len()];
    let touching = || live.iter().filter(|slot| slot.colliding()).map(|slot| slot.bodies);
    for (a, b) in touching() {
        if !ctx.bodies[a as usize].is_static && !ctx.bodies[b as usize].is_static {
            union(&mut buffers.island_of, a, b);
        }
    }
    for i in 0..count as u32 {
        let root = find(&mut buffers.island_of, i);
        buffers.island_of[i as usize] = root;
    }
    // Levels by relaxation (Bellman–Ford on unit edges): a stack of k bodies settles in k sweeps.
    loop {
        let mut changed = false;
        for (a, b) in touching() {
            let (la, lb) = (buffers.levels[a as usize], buffers.levels[b as usize]);
            if la.saturating_add(1) < lb {
                buffers.levels[b as usize] = la + 1;
                changed = true;
            } else if lb.saturating_add(1) < la {
                buffers.levels[a as usize] = lb + 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let islands = (0..count).filter(|&i| !ctx.bodies[i].is_static && buffers.island_of[i] == i as u32).count();
    ctx.profile.counters.islands += islands as u64;
}
