//! A subspace solve's passes in two halves (`subspace.rs`, `halves.rs`): where they split, and
//! what each half of a pass does.

use std::cell::UnsafeCell;
use std::marker::PhantomData;

use super::super::halves::Leader;
use super::{Solved, StepLimit, Stop, SubspaceRow, hold, release};
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{push_body, row_velocity};

/// A subspace solve of this many rows or more splits its passes into two halves, run on two
/// threads when the pool has them and the split gains ([`Split::gains`], `halves.rs`); the
/// halves' sums (`rᵀ z`, `pᵀ A p`) are then added half by half, whatever the thread count. Fewer
/// rows are one half, the same bits as a solve that does not split.
pub(super) const SPLIT_ROWS: usize = 1024;

/// Where a subspace solve's passes split: half 0's rows are `..row` (`row` a unit's first
/// row, so that each half's units are whole) and its bodies `..body`, every body up to the
/// highest its rows reach (the island's count when it does not split); half 1 has the rest.
/// The pass that applies the rows to the bodies splits by body instead, each half applying every
/// row that reaches one of its bodies to those bodies alone, so each body adds its rows in their
/// order, as one thread would: the rows before `shared` reach half 0's bodies only, those after
/// it half 1's only, and those of `shared` (a level's, in an island solved from the ground up)
/// reach both.
#[derive(Clone, Copy, Debug)]
pub(super) struct Split {
    len: usize,
    row: usize,
    body: usize,
    shared: (usize, usize),
}

impl Split {
    pub(super) fn new(rows: &[SubspaceRow], bodies: usize) -> Self {
        let len = rows.len();
        if len < SPLIT_ROWS {
            return Self { len, row: len, body: bodies, shared: (len, len) };
        }
        let mut row = len / 2;
        while row < len && rows[row].unit == rows[row - 1].unit {
            row += 1;
        }
        let body = rows[..row].iter().map(|r| r.bodies.0.max(r.bodies.1) as usize + 1).max().unwrap_or(0);
        // The last row that reaches half 0's bodies, and the first that reaches half 1's (no
        // row before `row` does): every row between reaches both, none outside does.
        let end = rows.iter().rposition(|r| (r.bodies.0.min(r.bodies.1) as usize) < body).map_or(0, |k| k + 1);
        let start = rows.iter().position(|r| r.bodies.0.max(r.bodies.1) as usize >= body).unwrap_or(len);
        Self { len, row, body, shared: (start.min(end), end) }
    }

    /// Whether the passes split: half 1 has rows.
    pub(super) fn halves(&self) -> bool {
        self.row < self.len
    }

    /// Whether two threads would gain: the solve splits, and each half applies at most three
    /// quarters of the rows to its bodies (an island solved from the ground up reaches the
    /// bodies of half 0 from its first rows and a level more; others may reach them from all).
    pub(super) fn gains(&self) -> bool {
        let most = self.shared.1.max(self.len - self.shared.0);
        self.halves() && 4 * most <= 3 * self.len
    }
}

/// What a half of a pass sums: `rᵀ z` or `pᵀ A p` over its rows, the longest feasible step
/// along the search directions, the row that sets it and that row's step before it was
/// clamped at 0 (`longest_step`), and whether every free row of it is solved.
#[derive(Clone, Copy, Debug)]
struct Partial {
    sum: f64,
    longest: (f64, usize, f64),
    solved: bool,
}

/// A subspace solve's rows, `A p`'s bodies and the island's velocities, shared by the two halves
/// of its passes: each pass writes only its half's rows and bodies (see [`Split`]), and the
/// leader works on them alone between passes.
pub(super) struct Lanes<'a> {
    rows: *mut SubspaceRow,
    len: usize,
    bodies: *mut BodyVelocity,
    velocities: *mut BodyVelocity,
    body_count: usize,
    split: Split,
    stop: Stop,
    partials: [UnsafeCell<Partial>; 2],
    borrows: PhantomData<&'a mut [SubspaceRow]>,
}

// SAFETY: the pointers are slices `Lanes::new` borrows mutably for `'a`. A pass's half writes only
// its own rows, bodies, velocities and partial, and reads other rows and bodies only where no
// half of the same pass writes them (`Lanes::half`, `Lanes::scatter`); the leader touches them
// alone only between passes, when no half runs (`Halves::run` returns once both are done).
#[allow(unsafe_code)]
unsafe impl Sync for Lanes<'_> {}

impl<'a> Lanes<'a> {
    pub(super) fn new(
        rows: &'a mut [SubspaceRow],
        bodies: &'a mut [BodyVelocity],
        velocities: &'a mut [BodyVelocity],
        split: Split,
        stop: Stop,
    ) -> Self {
        // The passes' raw slices rely on these (`Lanes::ranges`).
        assert!(bodies.len() == velocities.len() && split.len == rows.len() && split.body <= bodies.len());
        assert!(split.row <= split.len && split.shared.0 <= split.shared.1 && split.shared.1 <= split.len);
        let partial = || {
            let longest = (f64::INFINITY, 0, f64::INFINITY);
            UnsafeCell::new(Partial { sum: 0.0, longest, solved: true })
        };
        Self {
            rows: rows.as_mut_ptr(),
            len: rows.len(),
            bodies: bodies.as_mut_ptr(),
            velocities: velocities.as_mut_ptr(),
            body_count: bodies.len(),
            split,
            stop,
            partials: [partial(), partial()],
            borrows: PhantomData,
        }
    }

    /// The iterations (see [`super::solve`]), each pass in two halves through `leader`; returns
    /// what they did, the rows left for `solve` to hold and write back.
    pub(super) fn iterate(&self, leader: &Leader<'_>, iterations: u32) -> Solved {
        let mut solved = Solved { halves: self.split.halves(), ..Solved::default() };
        // `rᵀ z` over the free rows, whether the search directions start afresh, and whether
        // every free row is solved (known after a restart, or an update that takes a full step).
        let (mut squared, mut restart, mut all_solved) = (0.0, true, false);
        // The `β` of the next search directions `p = z + β p` on the free rows, not yet taken:
        // the pass that applies them to the bodies takes them as it reads them, and the pass that
        // reads `A p` back writes them (one pass over the rows fewer an iteration).
        let mut pending = None;
        while solved.iterations < iterations {
            if restart {
                leader.run(&|half| self.restart(half));
                (squared, all_solved) = self.sum();
                (restart, pending) = (false, None);
            }
            if all_solved {
                // The free rows are solved: free the held ones that would move into their cones.
                // SAFETY: between passes (see `Lanes`).
                #[allow(unsafe_code)]
                let rows = unsafe { std::slice::from_raw_parts_mut(self.rows, self.len) };
                if !release(rows, |row| self.stop.within(row)) {
                    solved.complete = true;
                    break;
                }
                leader.run(&|half| self.restart(half));
                (squared, _) = self.sum();
                pending = None;
            }
            solved.iterations += 1;
            // `A p`: the search direction's impulses applied to bodies at rest, read back along the
            // rows (the held ones too, whose residuals are kept for their release).
            leader.run(&|half| self.scatter(half, pending));
            leader.run(&|half| self.product(half, pending));
            pending = None;
            let (curvature, (feasible, blocking)) = self.curvature();
            let minimum = squared / curvature;
            // The search direction moves nothing (the residual is 0 in `A`'s range, up to rounding).
            if !(curvature > 0.0 && minimum.is_finite() && minimum > 0.0) {
                break;
            }
            let alpha = minimum.min(feasible);
            let blocked = feasible < minimum;
            leader.run(&|half| self.update(half, alpha, !blocked));
            if blocked {
                // The step reached the cone at `blocking` (on it up to rounding, which `hold`
                // settles): a normal reaching 0 is held there; a friction reaching its bound is held
                // with its unit's normals, which its bound follows. The iterations start again on
                // the rest.
                self.hold_at(blocking);
                solved.held += 1;
                restart = true;
                continue;
            }
            let next;
            (next, all_solved) = self.sum();
            pending = Some(next / squared);
            squared = next;
        }
        solved
    }

    /// Holds the unit (or the normal) whose row `blocking` the step reached the cone at.
    fn hold_at(&self, blocking: usize) {
        // SAFETY: between passes (see `Lanes`).
        #[allow(unsafe_code)]
        let (rows, velocities) = unsafe {
            (
                std::slice::from_raw_parts_mut(self.rows, self.len),
                std::slice::from_raw_parts_mut(self.velocities, self.body_count),
            )
        };
        let blocked = rows[blocking];
        let held = |row: &SubspaceRow| {
            if blocked.tangent { row.unit == blocked.unit } else { row.contact == blocked.contact && !row.tangent }
        };
        // The blocked row's unit: the rows `hold` brings to its cone, and those whose normals set
        // its friction's bound.
        let first = rows[..blocking].iter().rposition(|row| row.unit != blocked.unit).map_or(0, |k| k + 1);
        let end = rows[blocking..].iter().position(|row| row.unit != blocked.unit).map_or(self.len, |k| blocking + k);
        hold(&mut rows[first..end], held, velocities);
    }

    /// The half's rows and bodies (and velocities): index ranges.
    fn ranges(&self, half: usize) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        if half == 0 {
            (0..self.split.row, 0..self.split.body)
        } else {
            (self.split.row..self.len, self.split.body..self.body_count)
        }
    }

    /// The half's rows, to write.
    ///
    /// # Safety
    ///
    /// Only within a pass, by the half the caller runs, and only in a pass in which the other
    /// half reads no row of it ([`Lanes::scatter`] reads every row and writes none).
    #[allow(unsafe_code, clippy::mut_from_ref)]
    unsafe fn rows_mut(&self, half: usize) -> &mut [SubspaceRow] {
        let (rows, _) = self.ranges(half);
        // SAFETY: the halves' ranges are disjoint and within the rows `new` borrowed (it checks
        // the split against them); the caller's half alone touches them (see above).
        unsafe { std::slice::from_raw_parts_mut(self.rows.add(rows.start), rows.len()) }
    }

    /// The half's bodies of `A p`, to write.
    ///
    /// # Safety
    ///
    /// As [`Lanes::rows_mut`], for the bodies ([`Lanes::product`] reads every body and writes
    /// none).
    #[allow(unsafe_code, clippy::mut_from_ref)]
    unsafe fn bodies_mut(&self, half: usize) -> &mut [BodyVelocity] {
        let (_, bodies) = self.ranges(half);
        // SAFETY: as in `rows_mut`.
        unsafe { std::slice::from_raw_parts_mut(self.bodies.add(bodies.start), bodies.len()) }
    }

    /// The half's bodies of `A p` and its velocities, to read the one and write the other.
    ///
    /// # Safety
    ///
    /// As [`Lanes::rows_mut`]: only [`Lanes::update`] takes them, in which no half writes the
    /// bodies of `A p` and each half its own velocities only.
    #[allow(unsafe_code, clippy::mut_from_ref)]
    unsafe fn velocities_mut(&self, half: usize) -> (&[BodyVelocity], &mut [BodyVelocity]) {
        let (_, bodies) = self.ranges(half);
        // SAFETY: as in `rows_mut`; the bodies of `A p` are read only here.
        unsafe {
            (
                std::slice::from_raw_parts(self.bodies.add(bodies.start), bodies.len()),
                std::slice::from_raw_parts_mut(self.velocities.add(bodies.start), bodies.len()),
            )
        }
    }

    /// The half's partial, to write.
    ///
    /// # Safety
    ///
    /// Only within a pass, by the half the caller runs.
    #[allow(unsafe_code, clippy::mut_from_ref)]
    unsafe fn partial_mut(&self, half: usize) -> &mut Partial {
        // SAFETY: each half writes its own cell; the leader reads them only between passes.
        unsafe { &mut *self.partials[half].get() }
    }

    /// Starts the search directions afresh: `z = D⁻¹ r` on the free rows (0 on the held ones)
    /// and `p = z`; sums `rᵀ z` and whether every free row is solved.
    fn restart(&self, half: usize) {
        // SAFETY: within a pass that reads no row of the other half, this half's.
        #[allow(unsafe_code)]
        let (rows, partial) = unsafe { (self.rows_mut(half), self.partial_mut(half)) };
        let (mut squared, mut solved) = (0.0, true);
        for row in rows.iter_mut() {
            row.preconditioned = if row.free { row.residual / row.diagonal } else { 0.0 };
            row.search = row.preconditioned;
            squared += row.residual * row.preconditioned;
            solved &= !row.free || self.stop.within(row);
        }
        (partial.sum, partial.solved) = (squared, solved);
    }

    /// `A p`'s first part: the free rows' search directions applied to this half's bodies, at
    /// rest before; with `pending`, the next directions `z + β p` ([`next_search`]), which this
    /// pass only reads (the rows of the other half too) and [`Lanes::product`] writes.
    fn scatter(&self, half: usize, pending: Option<f64>) {
        // Each arm passes its own direction, so that the loops are specialised to it.
        match pending {
            Some(beta) => self.scatter_along(half, |row| next_search(row, beta)),
            None => self.scatter_along(half, |row| row.search),
        }
    }

    /// [`Lanes::scatter`] with each free row's direction `search(row)`.
    #[inline(always)]
    fn scatter_along(&self, half: usize, search: impl Fn(&SubspaceRow) -> f64 + Copy) {
        let Split { len, body, shared, .. } = self.split;
        // Half 0's rows that reach its bodies alone, then those that reach both halves'; half 1's
        // the other way round (each body's rows in their order).
        let (alone, both) = if half == 0 { ((0, shared.0), shared) } else { ((shared.1, len), shared) };
        // SAFETY: within a pass, this half's, which reads no body of the other half; every row is
        // read only (no half of this pass writes rows).
        #[allow(unsafe_code)]
        let (bodies, rows) = unsafe { (self.bodies_mut(half), std::slice::from_raw_parts(self.rows, len)) };
        bodies.fill(BodyVelocity::ZERO);
        let first = if half == 0 { 0 } else { body as u32 };
        let push = |row: &SubspaceRow, bodies: &mut [BodyVelocity], (a, b): (bool, bool)| {
            let search = search(row);
            if a {
                let a = &mut bodies[(row.bodies.0 - first) as usize];
                push_body([row.inverse[0], row.inverse[1]], row.direction, row.arms.0, search, a);
            }
            if b {
                let b = &mut bodies[(row.bodies.1 - first) as usize];
                push_body([row.inverse[2], row.inverse[3]], row.direction, row.arms.1, -search, b);
            }
        };
        let free = |range: (usize, usize)| rows[range.0..range.1].iter().filter(|row| row.free);
        if half == 1 {
            let own = |index: u32| index as usize >= body;
            free(both).for_each(|row| push(row, bodies, (own(row.bodies.0), own(row.bodies.1))));
        }
        free(alone).for_each(|row| push(row, bodies, (true, true)));
        if half == 0 {
            let own = |index: u32| (index as usize) < body;
            free(both).for_each(|row| push(row, bodies, (own(row.bodies.0), own(row.bodies.1))));
        }
    }

    /// `A p`'s second part: the bodies' velocities read back along this half's rows (with
    /// `pending`, each free row's next direction written first, as [`Lanes::scatter`] took it);
    /// sums `pᵀ A p` and finds the half's longest feasible step.
    fn product(&self, half: usize, pending: Option<f64>) {
        // Each arm passes its own update of the directions, so that the loop is specialised to it.
        match pending {
            Some(beta) => self.product_after(half, |row| {
                if row.free {
                    row.search = next_search(row, beta);
                }
            }),
            None => self.product_after(half, |_| {}),
        }
    }

    /// [`Lanes::product`] with `direct` applied to each row first.
    #[inline(always)]
    fn product_after(&self, half: usize, direct: impl Fn(&mut SubspaceRow)) {
        // SAFETY: within a pass that reads no row of the other half, this half's; every body is
        // read only (no half of this pass writes bodies).
        #[allow(unsafe_code)]
        let (rows, partial, bodies) = unsafe {
            (self.rows_mut(half), self.partial_mut(half), std::slice::from_raw_parts(self.bodies, self.body_count))
        };
        let mut curvature = 0.0;
        let mut limit = StepLimit::new();
        for (index, row) in rows.iter_mut().enumerate() {
            direct(row);
            let (a, b) = (&bodies[row.bodies.0 as usize], &bodies[row.bodies.1 as usize]);
            row.product = row_velocity(row.direction, row.arms, a, b);
            curvature += row.search * row.product;
            limit.row(index, row);
        }
        let (step, blocking, raw) = limit.longest;
        let offset = if half == 0 { 0 } else { self.split.row };
        (partial.sum, partial.longest) = (curvature, (step, blocking + offset, raw));
    }

    /// The step `alpha` along the search directions: the impulses, residuals and velocities;
    /// where the step was not cut (`precondition`), also `z = D⁻¹ r`, the next `rᵀ z` and
    /// whether every free row is solved.
    fn update(&self, half: usize, alpha: f64, precondition: bool) {
        // SAFETY: within a pass that reads nothing of the other half's, this half's.
        #[allow(unsafe_code)]
        let (rows, (bodies, velocities), partial) =
            unsafe { (self.rows_mut(half), self.velocities_mut(half), self.partial_mut(half)) };
        let (mut next, mut solved) = (0.0, true);
        for row in rows.iter_mut() {
            row.impulse += alpha * row.search;
            row.residual -= alpha * row.product;
            if precondition && row.free {
                row.preconditioned = row.residual / row.diagonal;
                next += row.residual * row.preconditioned;
                solved &= self.stop.within(row);
            }
        }
        for (velocity, change) in velocities.iter_mut().zip(bodies.iter()) {
            velocity.linear += alpha * change.linear;
            velocity.angular += alpha * change.angular;
        }
        (partial.sum, partial.solved) = (next, solved);
    }

    /// The last pass's halves' sums, added half 0's first, and whether both found every free row
    /// solved.
    fn sum(&self) -> (f64, bool) {
        // SAFETY: between passes (see `Lanes`).
        #[allow(unsafe_code)]
        let [first, second] = unsafe { [*self.partials[0].get(), *self.partials[1].get()] };
        (first.sum + second.sum, first.solved && second.solved)
    }

    /// The last [`Lanes::product`]'s `pᵀ A p` and longest feasible step: half 1's where its last
    /// shorter step found, before clamping, is shorter than half 0's step, which is what one scan
    /// over both halves would keep (so the row held is the same as a single scan's, rounding's
    /// negative steps included).
    fn curvature(&self) -> (f64, (f64, usize)) {
        // SAFETY: between passes (see `Lanes`).
        #[allow(unsafe_code)]
        let [first, second] = unsafe { [*self.partials[0].get(), *self.partials[1].get()] };
        let (step, row, _) = if second.longest.2 < first.longest.0 { second.longest } else { first.longest };
        (first.sum + second.sum, (step, row))
    }
}

/// A free row's next search direction, `p = z + β p` (conjugate gradients' next direction).
#[inline(always)]
fn next_search(row: &SubspaceRow, beta: f64) -> f64 {
    row.preconditioned + beta * row.search
}
