//! Mass properties, friction and restitution laws, and impulses.

pub mod laws;
pub mod mass;
