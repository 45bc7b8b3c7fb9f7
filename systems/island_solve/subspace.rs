//! The subspace solve of an island's resting contacts (docs/model.md §6 step 5): between blocks
//! of Gauss–Seidel sweeps, preconditioned conjugate gradients on the contacts that stick, as
//! equalities, each step kept inside the contacts' cones (after Silcowitz, Niebe and Erleben's
//! projected Gauss–Seidel with subspace minimisation, 2010, with the feasible steps of Dostál's
//! MPRGP in place of their projection).
//!
//! The sweeps alone converge on a tall structure at Gauss–Seidel's slow rate: the settling
//! pyramid of 40 levels needed 13,000–18,000 of them a sub-step. Once the sweeps have found which
//! contacts push and which of their frictions stick, what is left on those rows is a linear
//! problem, `A x = −u` with `A = J M⁻¹ Jᵀ` (the rows' velocities `u` brought to 0). Conjugate
//! gradients solve it in the order of the square root of the sweeps' count: the rows are the
//! Jacobian's, so `A p` is one pass that applies `p` to a scratch copy of the bodies' velocities
//! and one that reads the rows' velocities back, about a sweep's work.
//!
//! Every step stays feasible: it is cut where the first row would leave its cone (a normal
//! impulse reach 0, a friction reach `μ P_n`), that row is then held where it is (a friction with
//! its unit's normals, which its bound follows), and the iterations start again on the rest; once
//! those are solved, a held row whose residual points back into its cone is freed again (the
//! proportioning of Dostál's MPRGP, simplified), and what is left held is the sweeps' to settle.
//! A step along a conjugate direction no longer than the direction's minimum lowers the island's
//! kinetic energy, which is what the sweeps minimise (`½ vᵀ M v` over the impulses in their
//! cones, each sweep's update the exact minimum along its row; for the push-out's split impulses
//! `½ vᵀ M v − Σ tₙ Pₙ`, `tₙ` the push-out speeds), so a subspace solve never undoes the sweeps'
//! work: it only takes them further down the same descent. (Projecting a whole unconstrained
//! result on the cones instead, as the paper does, raised the energy in most of the settling
//! pyramid's early solves, once by ten times what the iterations had lowered it, and had to be
//! put back.)
//!
//! The problem is consistent whatever the rows (its right side `−J u` lies in the range of `J`,
//! which is `A`'s), so conjugate gradients converge on it even where the structure is statically
//! indeterminate and `A` singular.
//!
//! A solve of many rows ([`lanes::SPLIT_ROWS`]) splits each pass of its iterations into two
//! fixed halves (`subspace/lanes.rs`), run on two threads when the pool has them and each
//! half's scatter reads at most three quarters of the rows (`Split::gains`; `halves.rs`): the
//! rows' passes by row, the pass that applies the rows to the bodies by body (each body adds its
//! rows in their order, as one thread would), and the sums of the two halves added half 0's
//! first. What a half computes does not depend on which thread runs it,
//! so the results do not depend on the thread count; a solve of fewer rows is a single half.

use std::ops::ControlFlow::{self, Break, Continue};

use glam::DVec2;

use super::halves::{Halves, Lent};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{Accumulator, SolverContact, inverse_mass_along, push_along, row_velocity};
#[cfg(test)]
use lanes::SPLIT_ROWS;
use lanes::{Lanes, Split};

mod lanes;

/// One row of the subspace problem: a normal that pushes, or a friction inside its cone.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SubspaceRow {
    /// The row's direction (the contact's normal or tangent) and angular arms ([`row_velocity`]).
    direction: DVec2,
    arms: (f64, f64),
    /// The contact's inverse masses and inertias.
    inverse: [f64; 4],
    /// The bodies' indices among the island's velocities.
    bodies: (u32, u32),
    /// The contact (island-relative) whose impulse this row is, and whether it is its friction.
    contact: u32,
    tangent: bool,
    /// The first contact of the row's unit (a lone contact, or a patch's first end): the rows
    /// held together when one of them reaches its cone.
    unit: u32,
    /// A normal row's friction coefficient: its share `μ P_n` of its unit's friction bound.
    friction: f64,
    /// The contact's combined band: the scale of the stop test.
    band: f64,
    /// `A`'s diagonal entry, the row's inverse effective mass: the preconditioner.
    diagonal: f64,
    /// The row's accumulated impulse (of the pass's [`Accumulator`]).
    impulse: f64,
    /// Whether the iterations move the row (else it is held where it reached its cone).
    free: bool,
    /// Conjugate gradients' vectors: residual, preconditioned residual, search direction and
    /// `A` times it.
    residual: f64,
    preconditioned: f64,
    search: f64,
    product: f64,
}

/// What an island's subspace solve works in: a row per normal and friction of its contacts
/// (two per contact at most) and a velocity per body (`A p`). Parts of the step's buffers
/// ([`ScratchBuffers`]), split island by island as the contacts are.
pub(crate) struct Scratch<'a> {
    rows: &'a mut [SubspaceRow],
    bodies: &'a mut [BodyVelocity],
    /// Whether a solve may offer half of its passes to the pool it runs on: only where the step
    /// runs on its own pool. A step on the caller's thread (one thread, or a light step) may be
    /// called from within another rayon pool, whose workers are not the simulation's to use.
    helped: bool,
}

impl Scratch<'_> {
    /// The scratch of the islands before `contacts` contacts and `bodies` bodies, and of the rest.
    pub(crate) fn split(self, contacts: usize, bodies: usize) -> (Self, Self) {
        let (left_rows, right_rows) = self.rows.split_at_mut(ROWS_PER_CONTACT * contacts);
        let (left_bodies, right_bodies) = self.bodies.split_at_mut(bodies);
        let helped = self.helped;
        (
            Scratch { rows: left_rows, bodies: left_bodies, helped },
            Scratch { rows: right_rows, bodies: right_bodies, helped },
        )
    }

    /// This scratch, its solves offering half their passes to the pool only where `helped`.
    pub(crate) fn helped(self, helped: bool) -> Self {
        Self { helped, ..self }
    }
}

/// The step's buffers behind [`Scratch`]: kept from step to step, so the subspace solves allocate
/// nothing once they have grown.
#[derive(Debug, Default)]
pub(crate) struct ScratchBuffers {
    rows: Vec<SubspaceRow>,
    bodies: Vec<BodyVelocity>,
}

impl ScratchBuffers {
    /// The scratch of islands with `contacts` contacts and `bodies` bodies in all.
    pub(crate) fn scratch(&mut self, contacts: usize, bodies: usize) -> Scratch<'_> {
        self.rows.resize(ROWS_PER_CONTACT * contacts, SubspaceRow::default());
        self.bodies.resize(bodies, BodyVelocity::ZERO);
        Scratch { rows: &mut self.rows, bodies: &mut self.bodies, helped: true }
    }
}

/// Rows a contact can add at most: its normal and its friction.
const ROWS_PER_CONTACT: usize = 2;

/// A subspace solve stops once no row's residual velocity would move its contact by more than
/// this fraction of the solver's tolerance over the sub-step (`|u| h ≤ 0.1 tolerance (λ_A + λ_B)`):
/// the sweep after it then changes no more than the tolerance allows, unless a contact the sweeps
/// had not yet settled changes (docs/model.md §6 step 5, our choice).
const STOP_FRACTION: f64 = 0.1;

/// What a subspace solve did: its iterations (`A p` products), how many units it held at their
/// cones on the way, and whether its passes split into two halves ([`lanes::SPLIT_ROWS`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Solved {
    pub(crate) iterations: u32,
    pub(crate) held: u32,
    pub(crate) halves: bool,
    /// The iterations ended with every free row solved and none to free ([`release`]).
    pub(crate) complete: bool,
    /// Whether the solve left the island at rest ([`Settled::AtRest`]): it was complete, no row
    /// was left held, and no unit that pushes slid.
    pub(crate) at_rest: bool,
}

/// At most `iterations` preconditioned conjugate-gradient iterations on the impulses of `which`
/// (the resting solve's; the push-out's split impulses work the same way, but the push-out does
/// not use it: docs/model.md §6 step 5) of the rows of `contacts` that
/// stick (a unit whose friction is strictly inside its bound, or frictionless: its normals that
/// push, and its friction), from the velocities and impulses the sweeps left. `tolerance` is the
/// solver's and `h` the sub-step. Each step is cut where a row would first leave its cone; that
/// row is then held there (a friction with its unit's normals) and the iterations start again on
/// the other rows; once those are solved, the held rows that would move back into their cones are
/// freed and the iterations start again on them all. Called where [`settled`] found a row to
/// solve (the sweeps test it at a block's end: on a settled island it would take no iteration
/// and change nothing, only at the cost of gathering the rows). Its passes split into halves on two
/// threads where they gain from it and the scratch is `helped` (the step runs on its pool): the
/// second is `lent`'s (the wavefront's helper) if given, else one offered to the pool
/// (`halves.rs`).
pub(crate) fn solve(
    contacts: &mut [SolverContact],
    velocities: &mut [BodyVelocity],
    scratch: &mut Scratch<'_>,
    (iterations, which): (u32, Accumulator),
    (tolerance, h): (f64, f64),
    lent: Option<&Lent>,
) -> Solved {
    let stop = Stop { tolerance, h };
    let mut count = 0;
    let mut sliding = 0;
    let _ = visit_rows(contacts, (velocities, 0), which, &mut sliding, |row| {
        scratch.rows[count] = row;
        count += 1;
        Continue(())
    });
    let rows = &mut scratch.rows[..count];
    let bodies = &mut scratch.bodies[..velocities.len()];
    let split = Split::new(rows, bodies.len());
    let lanes = Lanes::new(&mut *rows, bodies, &mut *velocities, split, stop);
    let mut solved = Halves::lead(split.gains() && scratch.helped, lent, |leader| lanes.iterate(leader, iterations));
    solved.at_rest = solved.complete && sliding == 0 && rows.iter().all(|row| row.free);
    hold(rows, |_| true, velocities);
    for row in rows.iter() {
        let (normal, tangent, _) = contacts[row.contact as usize].accumulated(which);
        *(if row.tangent { tangent } else { normal }) = row.impulse;
    }
    solved
}

/// What [`settled`] finds of an island's rows (or some runs of one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Settled {
    /// Some row a subspace solve would gather is not solved: the solve would change the island.
    No,
    /// Every row it would gather is solved, but some unit that pushes slides (its friction at
    /// its bound), so its normals were not among them.
    Sliding,
    /// Every row is solved and every unit that pushes sticks: every contact that pushes is at
    /// rest along its normal, and every sticking friction along its tangent, to within the
    /// stop fraction — what the sweeps' level minimum waits for (`StopRule::converged`).
    AtRest,
}

/// Whether a subspace solve of `contacts` (a whole island, or runs of one whose bodies from the
/// island-relative index `base` on are `velocities`) would take no iteration: every row it would
/// gather is solved already ([`Stop::within`]). `solve` then changes nothing. Where also no unit
/// that pushes slides, the island's pushing contacts are at rest ([`Settled::AtRest`]). A pure
/// test, so the runs of an island may be tested in any order, by any thread, and give the
/// island's answer together (`wavefront.rs`: no if any says no, at rest if all do): a unit's rows
/// lie within one run.
pub(super) fn settled(
    contacts: &[SolverContact],
    velocities: (&[BodyVelocity], u32),
    which: Accumulator,
    (tolerance, h): (f64, f64),
) -> Settled {
    let stop = Stop { tolerance, h };
    let mut sliding = 0;
    let within = |row: SubspaceRow| if stop.within(&row) { Continue(()) } else { Break(()) };
    let solved = visit_rows(contacts, velocities, which, &mut sliding, within);
    match (solved.is_continue(), sliding) {
        (false, _) => Settled::No,
        (true, 0) => Settled::AtRest,
        (true, _) => Settled::Sliding,
    }
}

/// The stop test's scale: `SolverSettings::tolerance` and the sub-step.
#[derive(Clone, Copy, Debug)]
struct Stop {
    tolerance: f64,
    h: f64,
}

impl Stop {
    /// Whether `row`'s residual velocity is solved ([`STOP_FRACTION`]).
    fn within(self, row: &SubspaceRow) -> bool {
        row.residual.abs() * self.h <= STOP_FRACTION * self.tolerance * row.band
    }
}

/// Frees the held rows that would move into their cones, and returns whether any was: a held
/// normal whose contact asks for more push (its residual, beyond `within`, is positive: more push
/// only widens its unit's friction bound), a friction held at its bound whose residual points
/// inside it or whose bound has since grown away from it, and with such a friction the normals of
/// its unit held with it.
fn release(rows: &mut [SubspaceRow], within: impl Fn(&SubspaceRow) -> bool) -> bool {
    let mut released = false;
    let (mut unit, mut bound) = (u32::MAX, 0.0);
    for row in rows.iter_mut() {
        if row.unit != unit {
            (unit, bound) = (row.unit, 0.0);
        }
        if !row.tangent {
            bound += row.friction * row.impulse;
        }
        if row.free {
            continue;
        }
        let free = if row.tangent {
            let inward = row.residual * row.impulse < 0.0 && !within(row);
            inward || row.impulse.abs() < (1.0 - RELEASE_MARGIN) * bound
        } else {
            row.residual > 0.0 && !within(row)
        };
        row.free = free;
        released |= free;
    }
    // Backwards, so each unit's friction comes before its normals.
    let mut freed_unit = u32::MAX;
    for row in rows.iter_mut().rev() {
        if row.tangent && row.free {
            freed_unit = row.unit;
        } else if !row.tangent && !row.free && row.unit == freed_unit && row.impulse > 0.0 {
            row.free = true;
            released = true;
        }
    }
    released
}

/// A friction held at its bound is freed once the bound has grown past it by this fraction (less
/// would free one that rounding left just inside, to be held again at the next step).
const RELEASE_MARGIN: f64 = 1e-9;

/// The longest step `α ≤ ∞` along the rows' search directions that keeps every unit inside its
/// cone (each normal impulse at least 0, each friction within its unit's `Σ μ P_n`), the row
/// whose constraint sets it, and that row's step before it is clamped at 0 (rounding can leave a
/// row just outside its cone; the halves' merge needs it, `Lanes::curvature`), found row by row
/// ([`StepLimit::row`]) in the pass that reads `A p` back along the rows. Rows run unit by unit,
/// each unit's normals before its friction.
#[derive(Clone, Copy, Debug)]
struct StepLimit {
    longest: (f64, usize, f64),
    /// The current unit, its friction bound and that bound's rate along the search directions.
    unit: u32,
    bound: f64,
    rate: f64,
}

impl StepLimit {
    fn new() -> Self {
        Self { longest: (f64::INFINITY, 0, f64::INFINITY), unit: u32::MAX, bound: 0.0, rate: 0.0 }
    }

    /// Takes in `row`, the `index`-th of the rows, with its search direction as the step takes it.
    #[inline(always)]
    fn row(&mut self, index: usize, row: &SubspaceRow) {
        if row.unit != self.unit {
            (self.unit, self.bound, self.rate) = (row.unit, 0.0, 0.0);
        }
        if row.tangent {
            // |t + α s| ≤ b + α r: both t + α s ≤ b + α r and −(t + α s) ≤ b + α r.
            let (t, s) = (row.impulse, row.search);
            if s - self.rate > 0.0 {
                self.limit((self.bound - t) / (s - self.rate), index);
            }
            if -s - self.rate > 0.0 {
                self.limit((self.bound + t) / (-s - self.rate), index);
            }
        } else {
            self.bound += row.friction * row.impulse;
            self.rate += row.friction * row.search;
            if row.search < 0.0 {
                self.limit(-row.impulse / row.search, index);
            }
        }
    }

    #[inline(always)]
    fn limit(&mut self, alpha: f64, row: usize) {
        if alpha < self.longest.0 {
            self.longest = (alpha.max(0.0), row, alpha);
        }
    }
}

/// Holds the rows `held` picks where they are, brought onto the cone where rounding left them
/// just outside it (and that change applied to `velocities`). A friction's bound is its unit's
/// normals' (rows run unit by unit, each unit's normals before its friction), whether held with
/// it or not.
fn hold(rows: &mut [SubspaceRow], held: impl Fn(&SubspaceRow) -> bool, velocities: &mut [BodyVelocity]) {
    let (mut unit, mut bound) = (u32::MAX, 0.0);
    for row in rows.iter_mut() {
        if row.unit != unit {
            (unit, bound) = (row.unit, 0.0);
        }
        let value = if row.tangent { row.impulse.clamp(-bound, bound) } else { row.impulse.max(0.0) };
        if !row.tangent {
            bound += row.friction * value;
        }
        if !held(row) {
            continue;
        }
        let change = value - row.impulse;
        if change != 0.0 {
            let (a, b) = pair_mut(velocities, row.bodies);
            push_along(row.inverse, row.direction, row.arms, change, (a, b));
            // The row's velocity moved by `change` times its diagonal entry of `A`.
            row.residual -= change * row.diagonal;
        }
        (row.impulse, row.free, row.search) = (value, false, 0.0);
    }
}

/// The friction row of the unit (a lone contact, or a patch's two ends) starting at `k` of
/// `contacts`: how many contacts the unit has, its friction's angular arms and its bound,
/// `μ P_n` or `μ₁ P₁ + μ₂ P₂` at the patch centre, of the impulses of `which`. The same rows and
/// bounds as the sweeps' (`dynamics::solver::sweep`).
fn friction_row(contacts: &[SolverContact], k: usize, which: Accumulator) -> (usize, (f64, f64), f64) {
    let first = &contacts[k];
    let block = first.patch.filter(|block| block.matrix.is_some());
    let bound = |contact: &SolverContact| contact.friction * contact.impulses(which).0;
    match block {
        Some(block) if first.patch_with_next && k + 1 < contacts.len() => {
            (2, block.centre_arms, bound(first) + bound(&contacts[k + 1]))
        }
        // A patch whose ends nearly coincide is swept as two lone contacts (`solve_patch`).
        _ => (1, first.tangent_arms, bound(first)),
    }
}

/// Passes `visit` the rows of the units that stick (a unit whose friction is strictly inside
/// its bound, or frictionless: its normals that push, then its friction if it has one) of the
/// impulses of `which`, in order, each free and with its residual, its target less its velocity,
/// until `visit` breaks, and counts in `sliding` the units passed over that push (their friction
/// at a bound above 0). `velocities` are the bodies' from the island-relative index `base` on.
fn visit_rows(
    contacts: &[SolverContact],
    velocities: (&[BodyVelocity], u32),
    which: Accumulator,
    sliding: &mut u32,
    mut visit: impl FnMut(SubspaceRow) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let mut k = 0;
    while k < contacts.len() {
        let (span, arms, bound) = friction_row(contacts, k, which);
        let first = &contacts[k];
        let frictionless = contacts[k..k + span].iter().all(|contact| contact.friction == 0.0);
        if frictionless || first.impulses(which).1.abs() < bound {
            let unit = k as u32;
            for (offset, contact) in contacts[k..k + span].iter().enumerate() {
                let (normal, _, target) = contact.impulses(which);
                if normal > 0.0 {
                    let index = (k + offset) as u32;
                    let row = SubspaceRow::new(contact, (index, unit), false, contact.normal, contact.normal_arms);
                    visit(row.with_residual((normal, target), velocities))?;
                }
            }
            if !frictionless {
                let row = SubspaceRow::new(first, (unit, unit), true, first.tangent(), arms);
                visit(row.with_residual((first.impulses(which).1, 0.0), velocities))?;
            }
        } else if bound > 0.0 {
            *sliding += 1;
        }
        k += span;
    }
    Continue(())
}

impl SubspaceRow {
    /// The row of `contact` (its index and its unit's first contact's) along `direction`.
    fn new(
        contact: &SolverContact,
        (index, unit): (u32, u32),
        tangent: bool,
        direction: DVec2,
        arms: (f64, f64),
    ) -> Self {
        let inverse = contact.inverse;
        Self {
            direction,
            arms,
            inverse,
            bodies: contact.local,
            contact: index,
            tangent,
            unit,
            friction: contact.friction,
            band: contact.band,
            diagonal: inverse_mass_along(inverse, arms),
            ..Self::default()
        }
    }

    /// The row with its accumulated impulse and target velocity, and its residual (the target
    /// less its velocity at `velocities`).
    fn with_residual(self, (impulse, target): (f64, f64), (velocities, base): (&[BodyVelocity], u32)) -> Self {
        let (a, b) = (&velocities[(self.bodies.0 - base) as usize], &velocities[(self.bodies.1 - base) as usize]);
        Self { impulse, free: true, residual: target - row_velocity(self.direction, self.arms, a, b), ..self }
    }
}

/// The two bodies `(a, b)` of `velocities`, `a ≠ b`.
fn pair_mut(velocities: &mut [BodyVelocity], (a, b): (u32, u32)) -> (&mut BodyVelocity, &mut BodyVelocity) {
    let (a, b) = (a as usize, b as usize);
    if a < b {
        let (low, high) = velocities.split_at_mut(b);
        (&mut low[a], &mut high[0])
    } else {
        let (low, high) = velocities.split_at_mut(a);
        (&mut high[0], &mut low[b])
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::super::wavefront::tests::stacks;
    use super::*;

    const H: f64 = 1.0 / 120.0;

    /// A solve's scratch for `contacts` and `velocities`.
    fn buffers(contacts: &[SolverContact], velocities: &[BodyVelocity]) -> ScratchBuffers {
        let mut buffers = ScratchBuffers::default();
        buffers.scratch(contacts.len(), velocities.len());
        buffers
    }

    /// What the solve of `which` minimises, up to a constant: the bodies' kinetic energy at
    /// `velocities` less the work of the impulses towards their targets, `½ vᵀ M v − Σ tₙ Pₙ`.
    fn merit(contacts: &[SolverContact], velocities: &[BodyVelocity], which: Accumulator) -> f64 {
        let inverse = |k: usize| {
            let contact = contacts.iter().find(|c| c.local.0 as usize == k || c.local.1 as usize == k);
            contact.map_or([0.0; 2], |c| {
                if c.local.0 as usize == k { [c.inverse[0], c.inverse[1]] } else { [c.inverse[2], c.inverse[3]] }
            })
        };
        let kinetic: f64 = velocities
            .iter()
            .enumerate()
            .map(|(k, v)| match inverse(k) {
                [m, i] if m > 0.0 => 0.5 * (v.linear.length_squared() / m + v.angular * v.angular / i),
                _ => 0.0,
            })
            .sum();
        kinetic - contacts.iter().map(|c| c.impulses(which).2 * c.impulses(which).0).sum::<f64>()
    }

    /// Each unit's `(span, friction arms, bound)` at the contacts' impulses of `which`.
    fn units(contacts: &[SolverContact], which: Accumulator) -> Vec<(usize, (f64, f64), f64)> {
        let mut units = Vec::new();
        let mut k = 0;
        while k < contacts.len() {
            let unit = friction_row(contacts, k, which);
            units.push(unit);
            k += unit.0;
        }
        units
    }

    /// The stacks with random frictions (some frictionless, some sliding), impulses in their cones
    /// (some normals 0) and velocities, the same for the split impulses with random targets.
    fn random_island(seed: u64) -> (Vec<SolverContact>, Vec<BodyVelocity>) {
        let mut rng = StdRng::seed_from_u64(seed);
        // Every tenth island large enough for its solve to split into halves ([`SPLIT_ROWS`]).
        let (columns, levels) = if seed % 10 == 9 {
            (rng.random_range(40..50), rng.random_range(16..24))
        } else {
            (rng.random_range(1..4), rng.random_range(1..8))
        };
        let (mut contacts, mut velocities) = stacks(columns, levels, seed);
        for velocity in velocities.iter_mut().skip(1) {
            velocity.linear.y = rng.random_range(-0.1..0.05);
        }
        let mut k = 0;
        while k < contacts.len() {
            let span = friction_row(&contacts, k, Accumulator::Velocity).0;
            let friction = [0.0, 0.05, 0.5, 1.0][rng.random_range(0..4)];
            for contact in &mut contacts[k..k + span] {
                contact.friction = friction;
                contact.normal_impulse = if rng.random_bool(0.2) { 0.0 } else { rng.random_range(0.0..0.1) };
                contact.bias_impulse = if rng.random_bool(0.2) { 0.0 } else { rng.random_range(0.0..0.1) };
                contact.bias_speed = rng.random_range(0.0..0.05);
            }
            for which in [Accumulator::Velocity, Accumulator::Split] {
                let bound = friction_row(&contacts, k, which).2;
                let tangent = if rng.random_bool(0.3) { bound } else { rng.random_range(-1.0..1.0) * bound };
                *contacts[k].accumulated(which).1 = tangent;
            }
            k += span;
        }
        (contacts, velocities)
    }

    /// A subspace solve never raises what the sweeps lower, leaves every impulse in its cone, and
    /// moves the velocities by exactly what it changed the impulses by, for the resting impulses
    /// and the split ones alike (random islands with frictionless, sticking and sliding contacts,
    /// normals that push and ones at 0, bodies landing and leaving).
    #[test]
    fn never_raises_the_energy_and_keeps_every_impulse_in_its_cone() {
        let (mut held, mut split) = (0, 0);
        for seed in 0..200 {
            for which in [Accumulator::Velocity, Accumulator::Split] {
                let (mut contacts, mut velocities) = random_island(seed);
                let (before, start) = (contacts.clone(), velocities.clone());
                let mut buffers = buffers(&contacts, &velocities);
                let mut scratch = buffers.scratch(contacts.len(), velocities.len());
                let solved = solve(&mut contacts, &mut velocities, &mut scratch, (40, which), (1e-7, H), None);
                held += solved.held;
                split += usize::from(solved.halves);
                let (old, new) = (merit(&before, &start, which), merit(&contacts, &velocities, which));
                assert!(new <= old + 1e-15 * old.abs(), "seed {seed}, {which:?}: merit {old:e} -> {new:e}");
                let mut expected = start.clone();
                let mut k = 0;
                for (span, arms, bound) in units(&contacts, which) {
                    for offset in 0..span {
                        let (contact, previous) = (&contacts[k + offset], &before[k + offset]);
                        let normal = contact.impulses(which).0;
                        assert!(normal >= 0.0, "seed {seed}, {which:?}: normal impulse {normal}");
                        let (a, b) = pair_mut(&mut expected, contact.local);
                        let change = normal - previous.impulses(which).0;
                        push_along(contact.inverse, contact.normal, contact.normal_arms, change, (a, b));
                    }
                    let (contact, previous) = (&contacts[k], &before[k]);
                    let tangent = contact.impulses(which).1;
                    assert!(tangent.abs() <= bound, "seed {seed}, {which:?}: friction {tangent} beyond {bound}");
                    let (a, b) = pair_mut(&mut expected, contact.local);
                    push_along(contact.inverse, contact.tangent(), arms, tangent - previous.impulses(which).1, (a, b));
                    k += span;
                }
                for (got, want) in velocities.iter().zip(&expected) {
                    let off = (got.linear - want.linear).length() + (got.angular - want.angular).abs();
                    assert!(off < 1e-12, "seed {seed}, {which:?}: velocities off by {off:e}");
                }
            }
        }
        // The cases include steps cut at a cone, and solves split into halves.
        assert!(held > 100, "{held} units held");
        assert!(split >= 20, "{split} solves split");
    }

    /// The rows a solve of `which` gathers from `contacts` at `velocities`.
    fn gathered(contacts: &[SolverContact], velocities: &[BodyVelocity], which: Accumulator) -> usize {
        let mut count = 0;
        let _ = visit_rows(contacts, (velocities, 0), which, &mut 0, |_| {
            count += 1;
            Continue(())
        });
        count
    }

    /// A solve split into halves gives the same bits on one thread as on two (where the helper
    /// takes what half 1s it claims first, whichever those are), on islands solved from the ground
    /// up, whose halves' bodies are reached from about half the rows each (so that two threads do
    /// take part).
    #[test]
    fn a_split_solve_gives_the_same_bits_on_one_thread_and_two() {
        for seed in [9, 19, 29, 39] {
            for which in [Accumulator::Velocity, Accumulator::Split] {
                let (contacts, velocities) = random_island(seed);
                assert!(
                    gathered(&contacts, &velocities, which) >= SPLIT_ROWS,
                    "seed {seed}: {} contacts, {} rows",
                    contacts.len(),
                    gathered(&contacts, &velocities, which)
                );
                let solved = |threads: usize| {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                    let (mut contacts, mut velocities) = (contacts.clone(), velocities.clone());
                    let mut buffers = buffers(&contacts, &velocities);
                    let mut scratch = buffers.scratch(contacts.len(), velocities.len());
                    let mut rows = Vec::new();
                    let _ = visit_rows(&contacts, (&velocities, 0), which, &mut 0, |row| {
                        rows.push(row);
                        Continue(())
                    });
                    let split = Split::new(&rows, velocities.len());
                    assert!(split.gains(), "seed {seed}: {split:?}");
                    let solved = pool.install(|| {
                        solve(&mut contacts, &mut velocities, &mut scratch, (40, which), (1e-7, H), None).iterations
                    });
                    let bits: Vec<u64> = contacts
                        .iter()
                        .flat_map(|c| [c.normal_impulse, c.tangent_impulse, c.bias_impulse, c.bias_tangent_impulse])
                        .chain(velocities.iter().flat_map(|v| [v.linear.x, v.linear.y, v.angular]))
                        .map(f64::to_bits)
                        .collect();
                    (solved, bits)
                };
                let (one, two) = (solved(1), solved(2));
                assert!(one.0 > 0, "seed {seed}");
                assert!(one == two, "seed {seed}, {which:?}: {} and {} iterations", one.0, two.0);
            }
        }
    }

    /// A column of boxes, each held by the one below at a two-point patch whose friction sticks,
    /// warm-started with its weight above (as the last sub-step's forces or the cold start's
    /// statics estimate start it), is rigid on the ground: the one solution
    /// leaves every box at rest. The subspace solve finds it to rounding, holding nothing, within
    /// twice as many iterations as it has rows (conjugate gradients take at most as many in exact
    /// arithmetic), where as many sweeps leave the column moving (a sweep passes a change of load
    /// one level down).
    #[test]
    fn a_column_that_sticks_comes_to_rest_within_twice_as_many_iterations_as_rows() {
        for seed in 0..20 {
            let levels = 12;
            let column = || {
                let (mut contacts, velocities) = stacks(1, levels, seed);
                for contact in &mut contacts {
                    contact.normal_impulse = 0.5 * f64::from(levels - contact.level) * 9.81 * H;
                }
                (contacts, velocities)
            };
            let (mut contacts, mut velocities) = column();
            let rows = 3 * levels;
            let mut buffers = buffers(&contacts, &velocities);
            let mut scratch = buffers.scratch(contacts.len(), velocities.len());
            let solved = solve(
                &mut contacts,
                &mut velocities,
                &mut scratch,
                (2 * rows, Accumulator::Velocity),
                (1e-12, H),
                None,
            );
            let fastest = |velocities: &[BodyVelocity]| {
                velocities.iter().map(|v| v.linear.length().max(v.angular.abs())).fold(0.0, f64::max)
            };
            assert_eq!(solved.held, 0, "seed {seed}");

            let at_rest = fastest(&velocities);
            assert!(at_rest < 1e-9, "seed {seed}: {at_rest:e} m/s after {} iterations", solved.iterations);
            let (mut swept, mut swept_velocities) = column();
            let mut island = crate::dynamics::solver::IslandVelocities(&mut swept_velocities);
            for _ in 0..2 * rows {
                super::super::relax(&mut swept, &mut island, Accumulator::Velocity);
            }
            let moving = fastest(&swept_velocities);
            assert!(moving > 1e3 * at_rest.max(1e-12), "seed {seed}: sweeps alone {moving:e} m/s");
        }
    }

    /// A box leaving the ground with an impulse left on its contact: the subspace step, which would
    /// pull it down, is cut where the impulse reaches 0, and the contact is held there.
    #[test]
    fn a_contact_that_separates_is_held_at_zero_not_pulled() {
        let arms = (DVec2::new(0.0, -0.5), DVec2::ZERO);
        let contact = SolverContact {
            band: 0.01,
            local: (1, 0),
            normal_impulse: 0.05,
            ..SolverContact::for_test([1.0, 6.0, 0.0, 0.0], arms, DVec2::Y, 0.5)
        };
        let mut contacts = vec![contact];
        let mut velocities = vec![BodyVelocity::ZERO, BodyVelocity { linear: DVec2::new(0.0, 1.0), angular: 0.0 }];
        let mut buffers = buffers(&contacts, &velocities);
        let mut scratch = buffers.scratch(contacts.len(), velocities.len());
        let solved = solve(&mut contacts, &mut velocities, &mut scratch, (10, Accumulator::Velocity), (1e-7, H), None);
        assert_eq!(solved.held, 1);
        assert_eq!((contacts[0].normal_impulse, contacts[0].tangent_impulse), (0.0, 0.0));
        assert!((velocities[1].linear - DVec2::new(0.0, 0.95)).length() < 1e-15, "{:?}", velocities[1]);
        assert!(velocities[1].angular.abs() < 1e-15);
    }
}
