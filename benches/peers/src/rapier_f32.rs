//! rapier2d in single precision.

use rapier2d as rapier;

// Included once per precision on purpose (`rapier` differs).
#[allow(clippy::duplicate_mod)]
#[path = "rapier_world.rs"]
mod world;

pub use world::build;
