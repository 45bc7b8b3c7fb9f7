//! The event logs: one record per impulse applied, and one per begin or end of contact of a
//! pair, each drained by the user after a step.

use glam::DVec2;
use hecs::Entity;
use serde::{Deserialize, Serialize};

/// What an impulse did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EventKind {
    /// A collision with no friction at the contact (μ = 0).
    Collision,
    /// A collision in which friction stopped the tangential slip.
    Sticking,
    /// A collision in which the contact kept sliding.
    Sliding,
    /// A resting contact treated as a micro-collision (MODEL §7, the seed's contact model).
    MicroCollision,
    /// A resting contact held by the iterated solver (MODEL §7a): its impulse over one sub-step.
    Resting,
}

impl EventKind {
    /// Every kind, in the order of the summaries.
    pub const ALL: [EventKind; 5] =
        [EventKind::Collision, EventKind::Sticking, EventKind::Sliding, EventKind::MicroCollision, EventKind::Resting];

    /// Lower-case name used in CSV files and summaries.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Collision => "collision",
            Self::Sticking => "sticking",
            Self::Sliding => "sliding",
            Self::MicroCollision => "micro-collision",
            Self::Resting => "resting",
        }
    }
}

/// One impulse applied between two bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactEvent {
    /// Simulation time at which the impulse was applied (s).
    pub time: f64,
    /// Body that received `+impulse`.
    pub body_a: Entity,
    /// Body that received `−impulse`; the normal is its outward normal.
    pub body_b: Entity,
    /// Segment index on A.
    pub segment_a: usize,
    /// Global curve parameter on A.
    pub parameter_a: f64,
    /// Segment index on B.
    pub segment_b: usize,
    /// Global curve parameter on B.
    pub parameter_b: f64,
    /// Contact point in the world (m).
    pub point: DVec2,
    /// Unit outward normal of B at the contact.
    pub normal: DVec2,
    /// Tolerance of A at the contact (m).
    pub lambda_a: f64,
    /// Tolerance of B at the contact (m).
    pub lambda_b: f64,
    /// Friction coefficient of A's surface there.
    pub mu_a: f64,
    /// Friction coefficient of B's surface there.
    pub mu_b: f64,
    /// Coefficient used: `max(μ_A, μ_B)`.
    pub mu: f64,
    /// Collision, sticking, sliding or micro-collision.
    pub kind: EventKind,
    /// Normal relative velocity before the impulse (m/s).
    pub normal_velocity_before: f64,
    /// Normal relative velocity after the impulse (m/s).
    pub normal_velocity_after: f64,
    /// The impulse on A (N·s).
    pub impulse: DVec2,
}

/// Whether a pair of bodies started or stopped touching.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TouchKind {
    /// The pair touches (contacts in the band, or crossing curves) and did not at the end of
    /// the last step.
    Begin,
    /// The pair touched at the end of the last step and does not any more (or one of its
    /// bodies was removed).
    End,
}

/// A pair of bodies that began or ended touching (Box2D's contact begin and end events), judged
/// at the end of each step. A pair of sleeping bodies keeps touching while it sleeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TouchEvent {
    /// Simulation time at the end of the step, or of the removal (s).
    pub time: f64,
    /// Begin or end.
    pub kind: TouchKind,
    /// One body of the pair (the earlier spawned one for a begin).
    pub body_a: Entity,
    /// The other body.
    pub body_b: Entity,
}

/// An event log of a simulation: the events since the last drain, at most `capacity` of them;
/// any beyond are dropped and counted (`StepCounters::dropped_events`), so a program that never
/// drains the log uses bounded memory.
#[derive(Debug, Default)]
pub(crate) struct EventLog<E> {
    events: Vec<E>,
    capacity: usize,
}

impl<E> EventLog<E> {
    /// An empty log that keeps at most `capacity` events between drains.
    pub(crate) fn new(capacity: usize) -> Self {
        Self { events: Vec::new(), capacity }
    }

    /// Appends `event`, or counts it as dropped when the log is full.
    pub(crate) fn push(&mut self, event: E, counters: &mut crate::profile::StepCounters) {
        if self.events.len() < self.capacity {
            self.events.push(event);
        } else {
            counters.dropped_events += 1;
        }
    }

    /// Takes every event (in application order), keeping the memory.
    pub(crate) fn drain(&mut self) -> std::vec::Drain<'_, E> {
        self.events.drain(..)
    }
}
