//! # rugosa
//!
//! Collision dynamics of 2-D rigid bodies of arbitrary shape and rough surfaces.
//!
//! Bodies are bounded by closed periodic cubic B-spline curves ([`Spline`]). Every boundary
//! segment carries a *rugosity* tolerance ([`Rugosity`]): a band that stands for surface
//! detail too fine to model explicitly. The friction coefficient at a contact follows from
//! the local tolerance; resting contacts are solved together by an iterated contact solver
//! (the seed's stream of micro-collisions stays selectable), and islands at rest sleep.
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
#![deny(unsafe_code)]

/// The README's example, compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The vector type of the API (`DVec2`), re-exported so a user needs no glam of their own.
pub use glam;
/// The ECS the bodies live in (`Entity`, `World`), re-exported for `Simulation::world`.
pub use hecs;

// The modules are private: everything public is re-exported at the root, below (as hecs
// does), so a path inside the crate can move without breaking a user.
mod components;
mod dynamics;
mod error;
mod events;
mod geometry;
mod profile;
mod random;
#[cfg(feature = "report")]
pub mod report;
#[cfg(feature = "scene")]
mod scene;
mod simulation;
#[path = "../systems/mod.rs"]
pub(crate) mod systems;

pub use components::{
    AppliedForce, BodyName, CollisionGroups, Kinematic, Material, Motion, RigidState, Sensor, Sleep, SpawnOrder, Static,
};
pub use dynamics::impulse::{
    BandPenetration, BodyVelocity, ContactMassInput, ImpactContact, ImpulseError, ImpulseKind, ImpulseLaw,
    ImpulseOutcome, MicroCollisionSettings, apply_impulse, collision_matrix, contact_tangent, kinetic_energy,
    relative_velocity, resolve_impact, resolve_micro_collision,
};
pub use dynamics::laws::{FrictionLaw, contact_friction, contact_restitution, micro_collision_speed};
pub use dynamics::mass::{AreaMoments, MassProperties, area_moments, mass_properties, recentre};
pub use error::{BodyActionError, BodyError, BodyLabel, SettingsError, ShapeError, SnapshotError};
pub use events::{ContactEvent, EventKind, TouchEvent, TouchKind};
pub use geometry::aobb_tree::{AobbNode, AobbNodeKind, AobbTree, TraversalCounters, TraversalWorkspace};
pub use geometry::construct::{Generator, interpolating_control_points};
pub use geometry::curve_pair::{
    ClosestPoints, ContactPoints, CurvePairSettings, MAX_SUBDIVISION_DEPTH, Orientation, SegmentContact,
    SegmentPairQuery, SegmentPairState, TolerancedSegment, closest_points_segment_segment, intersect_segment_segment,
    query_segment_segment, separating_axes,
};
pub use geometry::multiresolution::{
    ANALYSIS_DETAIL_TAPS, DETAIL_NOISE_GAIN, Decomposition, NoiseEstimator, decompose, noise_level, reconstruct,
    reverse_subdivide, segment_noise_levels, subdivide, synthesize,
};
pub use geometry::obb::{COVARIANCE_SAMPLES, OVERLAP_RELATIVE_SLACK, Obb};
pub use geometry::patterns::{RugosityPattern, ToleranceRule, rugosity_from_outline};
pub use geometry::pose::Pose;
pub use geometry::query::{
    BodyContact, BodyQuery, BodyShape, Coherence, LeafFront, LeafGap, LeafMemory, Manifold, PairState, QueryCapacity,
    QuerySettings, SegmentIntersection, all_segment_pairs, query_bodies, query_bodies_within, query_leaf_pairs,
};
pub use geometry::ray::{Ray, RayCrossing, ray_crossings};
pub use geometry::rounded_polygon::{ControlPointBudget, ShapeFit, rounded_polygon};
pub use geometry::rugosity::{Rugosity, SegmentTolerance};
pub use geometry::segment::CubicSegment;
pub use geometry::self_intersection::{find_self_intersection, validate_boundary};
pub use geometry::spline::{CurvePoint, Spline};
pub use profile::{Profile, Stage, StepCounters};
pub use random::{SeededRng, seeded};
#[cfg(feature = "scene")]
pub use scene::{BodyScene, RugosityScene, Scene, SceneError, ShapeScene};
pub use simulation::{
    BodyDesc, BodyKind, BodySnapshot, ContactHook, ContactModel, MAX_ANGULAR_SPEED, MAX_COORDINATE, MAX_ENTITY_INDEX,
    MAX_GRAVITY, MAX_SPEED, MAX_STEP, MIN_STEP, PairAction, PairContacts, PointProjection, QueryFilter, RayHit,
    SHAPE_CAST_TOLERANCE, SNAPSHOT_VERSION, ShapeCast, ShapeHit, Simulation, SimulationSettings, SleepSettings,
    Snapshot, SolverSettings, StepMemory,
};
