//! A run's share of the island: the slices one thread holds while it sweeps a run, what
//! it reads of them at a sweep's end, and the copies the lower thread keeps to put a sweep
//! back ([`Shared`]'s protocol is in `shared.rs`).

use super::super::super::{Settled, StopRule, shortfall};
use super::Shared;
use crate::dynamics::impulse::BodyVelocity;
use crate::dynamics::solver::{PairVelocities, SolverContact, Update, update_at};
use std::sync::atomic::Ordering;

/// One thread's copies of what its sweep changed, to put back.
pub(super) struct Saved<'a> {
    pub(super) impulses: &'a mut [[f64; 2]],
    pub(super) velocities: &'a mut [BodyVelocity],
    pub(super) runs: &'a mut Vec<u32>,
}

impl Shared<'_> {
    /// What the push-out's sweep this thread is on leaves undone at `run`'s contacts
    /// ([`shortfall`]), once it has swept `run + 1` (or `run` is the last): no later run of the
    /// sweep reaches their bodies, and the sweep after is not given `run − 1`, whose bodies they
    /// share, until this one says it has done `run` (for the push-out a run counts as done once
    /// its shortfall is known).
    pub(super) fn shortfall(&self, run: usize) -> f64 {
        // SAFETY: this thread holds `run + 1` (or the last run) of its sweep, and the other
        // thread's sweep holds no run less than two away from `run` (see above and
        // `run_slices`); nothing is written.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        shortfall(contacts, &velocities, self.rule.slack)
    }

    /// Records a run's answer at a block's end ([`Shared::settled`]) in sweep slot `slot`, and
    /// returns the answer of the runs tested so far in that sweep: no if any said no, at rest if all
    /// did.
    pub(super) fn record_settled(&self, slot: usize, answer: Settled) -> Settled {
        let record = &self.slots[slot];
        match answer {
            Settled::No => record.unsettled.store(true, Ordering::Relaxed),
            Settled::Sliding => record.sliding.store(true, Ordering::Relaxed),
            Settled::AtRest => {}
        }
        if record.unsettled.load(Ordering::Relaxed) {
            Settled::No
        } else if record.sliding.load(Ordering::Relaxed) {
            Settled::Sliding
        } else {
            Settled::AtRest
        }
    }

    /// Whether a subspace solve would leave `run`'s contacts as they are ([`StopRule::settled`]),
    /// at the end of a block: as for [`Shared::shortfall`], once this thread has swept `run + 1`
    /// (or `run` is the last), and the sweep after is not given `run − 1` before.
    pub(super) fn settled(&self, rule: &StopRule, run: usize) -> Settled {
        // SAFETY: as for `shortfall`: nothing is written, and no other thread holds a run less
        // than two away from `run`.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        rule.settled(contacts, (velocities.slice, velocities.base))
    }

    /// Copies what `run` will change: its contacts' impulses and its own bodies' velocities.
    pub(super) fn save(&self, run: usize, saved: &mut Saved<'_>) {
        // SAFETY: called by the thread the wait gave the run to, before it sweeps it.
        #[allow(unsafe_code)]
        let (contacts, velocities) = unsafe { self.run_slices(run) };
        let (first_contact, first_body) = (self.starts[run].0 as usize, self.starts[run].1 as usize);
        for (copy, contact) in saved.impulses[first_contact..].iter_mut().zip(contacts.iter_mut()) {
            let (normal, tangent, _) = contact.accumulated(self.rule.accumulator);
            *copy = [*normal, *tangent];
        }
        let own = &velocities.slice[first_body - velocities.base as usize..];
        saved.velocities[first_body..first_body + own.len()].copy_from_slice(own);
        saved.runs.push(run as u32);
    }

    /// Puts back every run this thread copied in its current sweep, which a sweep before it
    /// ended the solve: the island is then as that sweep left it.
    pub(super) fn put_back(&self, saved: &mut Saved<'_>) {
        for &run in saved.runs.iter() {
            let run = run as usize;
            // SAFETY: the sweep before this thread's has ended the solve, so the other thread has
            // returned or is about to, touching nothing more.
            #[allow(unsafe_code)]
            let (contacts, velocities) = unsafe { self.run_slices(run) };
            let (first_contact, first_body) = (self.starts[run].0 as usize, self.starts[run].1 as usize);
            for (contact, copy) in contacts.iter_mut().zip(&saved.impulses[first_contact..]) {
                let (normal, tangent, _) = contact.accumulated(self.rule.accumulator);
                [*normal, *tangent] = *copy;
            }
            let own = &mut velocities.slice[first_body - velocities.base as usize..];
            let count = own.len();
            own.copy_from_slice(&saved.velocities[first_body..first_body + count]);
        }
        saved.runs.clear();
    }

    /// The contacts of `run` and the velocities of the bodies they reach: those the run before
    /// and this one were first to touch.
    ///
    /// # Safety
    ///
    /// No other thread may hold the slices of a run less than two away from `run` (or of `run`
    /// itself) while these live. The wavefront gives run `r` of sweep `k + 1` only once sweep
    /// `k` has done run `r + 1`; each thread goes run by run through its part; the upper thread
    /// starts its part of sweep `k` only once the lower one has done all of its own; and the
    /// lower thread starts sweep `k + 2` only once sweep `k` is done, so it is at most one
    /// sweep ahead. So while one thread holds run `r` the other holds a run at least two ahead
    /// of it or behind it, or waits, or has returned (the lower thread puts back the runs of a
    /// sweep only once the sweep before it has ended the solve or a thread has panicked: the
    /// helper's last access to the runs comes before it stores the end). For the push-out a run
    /// counts as done only once its shortfall is read, which reads the run before it (see
    /// `Shared::shortfall`).
    /// Two runs apart, the contacts differ, and so do the bodies: those runs `r − 1` and `r`
    /// first touched against runs `r + 1` and later ([`Runs::build`](super::super::Runs::build) checks that no contact of
    /// run `r` reaches a body first touched before run `r − 1`).
    #[allow(unsafe_code, clippy::mut_from_ref)]
    pub(super) unsafe fn run_slices(&self, run: usize) -> (&mut [SolverContact], RunVelocities<'_>) {
        let (first_contact, _) = self.starts[run];
        let (end_contact, end_body) = self.starts[run + 1];
        let first_body = self.starts[run.saturating_sub(1)].1;
        // SAFETY: the ranges lie within the island's contacts and velocities, whose pointers
        // `solve` took from slices it borrows mutably while `self` lives (`Runs::build` checks the
        // starts against the island's counts); the caller holds the run (see above).
        unsafe {
            let contacts = std::slice::from_raw_parts_mut(
                self.contacts.add(first_contact as usize),
                (end_contact - first_contact) as usize,
            );
            let velocities = std::slice::from_raw_parts_mut(
                self.velocities.add(first_body as usize),
                (end_body - first_body) as usize,
            );
            (contacts, RunVelocities { base: first_body, slice: velocities })
        }
    }
}

/// The velocities one run reaches, by the island-relative `local` index less `base`.
pub(super) struct RunVelocities<'a> {
    base: u32,
    slice: &'a mut [BodyVelocity],
}

impl PairVelocities for RunVelocities<'_> {
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity) {
        let (a, b) = contact.local;
        (self.slice[(a - self.base) as usize], self.slice[(b - self.base) as usize])
    }

    fn set_pair(&mut self, contact: &SolverContact, va: BodyVelocity, vb: BodyVelocity) {
        let (a, b) = contact.local;
        (self.slice[(a - self.base) as usize], self.slice[(b - self.base) as usize]) = (va, vb);
    }

    #[inline(always)]
    fn update(&mut self, update: impl Update) -> f64 {
        let (a, b) = update.contact().local;
        update_at(self.slice, ((a - self.base) as usize, (b - self.base) as usize), update)
    }
}
