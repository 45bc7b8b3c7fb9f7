//! The contact hook (as rapier's contact-modification hooks): after every narrow phase, a
//! function of the user's sees each pair in contact or crossing, in pair order on the step's
//! thread, and may let it collide, ignore it for that sub-step (one-way platforms: the bodies
//! pass through each other as through a sensor), or change its friction and restitution.
//!
//! ```
//! use std::sync::Arc;
//! use rugosa::{PairAction, Simulation, SimulationSettings};
//!
//! let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
//! // Nothing collides while it moves upwards.
//! sim.set_contact_hook(Some(Arc::new(|pair: &rugosa::PairContacts<'_>| {
//!     let rising = |s: &rugosa::RigidState| s.linear_velocity.y > 0.0;
//!     if rising(pair.state_a) || rising(pair.state_b) { PairAction::Ignore } else { PairAction::Keep }
//! })));
//! ```

use std::sync::Arc;

use hecs::Entity;

use super::Simulation;
use crate::components::RigidState;
use crate::geometry::query::BodyContact;

/// What the contact hook sees of a pair: its bodies (A the earlier spawned), their states, and
/// its contacts (normals outward of B), or that their curves cross.
#[derive(Clone, Copy, Debug)]
pub struct PairContacts<'a> {
    /// Body A.
    pub body_a: Entity,
    /// Body B.
    pub body_b: Entity,
    /// A's state at the detection.
    pub state_a: &'a RigidState,
    /// B's state at the detection.
    pub state_b: &'a RigidState,
    /// The contacts within the band (may be empty when the curves cross).
    pub contacts: &'a [BodyContact],
    /// Whether the curves cross.
    pub crossing: bool,
}

/// What the contact hook decides for a pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum PairAction {
    /// Collide as the materials say.
    #[default]
    Keep,
    /// Pass through each other for this sub-step: no impulse, no retry, and no bound on the
    /// sub-step from this pair, as for a sensor; the pair still touches (touch events).
    Ignore,
    /// Collide with this friction coefficient (finite, ≥ 0) and restitution (in [0, 1]) in
    /// place of the materials' (`None` keeps it). The solver's contacts take them (with
    /// `ContactModel::Solver`); a value outside its range is not used and is counted
    /// (`StepCounters::rejected_hook_values`).
    Modify {
        /// Friction coefficient μ.
        friction: Option<f64>,
        /// Restitution e (of collisions and of the push-out).
        restitution: Option<f64>,
    },
}

/// A contact hook: called on the step's thread, so it may capture anything `Send + Sync`.
pub type ContactHook = Arc<dyn Fn(&PairContacts<'_>) -> PairAction + Send + Sync>;

impl Simulation {
    /// Sets (or with `None` removes) the contact hook.
    pub fn set_contact_hook(&mut self, hook: Option<ContactHook>) {
        self.contact_hook = hook;
    }
}
