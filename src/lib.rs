//! # rugosa
//!
//! Collision dynamics of 2-D rigid bodies of arbitrary shape and rough surfaces.
//!
//! Bodies are bounded by closed periodic cubic B-spline curves ([`Spline`]). Every boundary
//! segment carries a *rugosity* tolerance ([`Rugosity`]): a band that stands for surface
//! detail too fine to model explicitly. The friction coefficient at a contact follows from
//! the local tolerance, and resting contact is a stream of micro-collisions.
//!
//! The model, with every formula, is written out in `MODEL.md` of the project's shared spec.
//!
//! ```
//! use rugosa::{Generator, mass_properties};
//!
//! let disc = Generator::Circle { radius: 0.5 }.build(32)?;
//! let props = mass_properties(&disc, 1000.0);
//! let exact = 1000.0 * std::f64::consts::PI * 0.25;
//! assert!((props.mass - exact).abs() / exact < 1e-4);
//! # Ok::<(), rugosa::ShapeError>(())
//! ```
#![warn(missing_docs)]

pub mod dynamics;
pub mod error;
pub mod geometry;

pub use dynamics::laws::{FrictionLaw, contact_friction, contact_restitution, micro_collision_speed};
pub use dynamics::mass::{AreaMoments, MassProperties, area_moments, mass_properties, recentre};
pub use error::{BodyError, BodyLabel, SettingsError, ShapeError};
pub use geometry::construct::{Generator, interpolating_control_points};
pub use geometry::pose::Pose;
pub use geometry::rugosity::{Rugosity, SegmentTolerance};
pub use geometry::segment::CubicSegment;
pub use geometry::spline::{CurvePoint, Spline};
