//! Mass properties, friction and restitution laws, and impulses.

pub mod impulse;
pub mod laws;
pub mod mass;
pub mod solver;
