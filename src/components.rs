//! Components carried by body entities: plain data, no behaviour beyond small accessors.
//!
//! A body is a hecs entity with [`Spline`](crate::Spline), [`Rugosity`](crate::Rugosity),
//! [`AobbTree`](crate::geometry::aobb_tree::AobbTree), [`RigidState`], [`Material`],
//! [`MassProperties`](crate::MassProperties) and [`SpawnOrder`], and the engine's own bounding
//! octagon of its boundary (the broad phase's bounds, worked out when it is added); static
//! bodies also carry [`Static`], dynamic ones [`Sleep`], [`Motion`] and [`AppliedForce`], named
//! ones [`BodyName`]. Other components the user adds are left alone.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::dynamics::laws::FrictionLaw;
use crate::error::SettingsError;
use crate::geometry::pose::Pose;

/// Position, orientation and velocities of a body's centre of mass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RigidState {
    /// World position of the centre of mass (m).
    pub position: DVec2,
    /// Orientation angle (rad), unwrapped so that `ω t` accumulates exactly.
    pub angle: f64,
    /// Velocity of the centre of mass (m/s).
    pub linear_velocity: DVec2,
    /// Angular velocity (rad/s, counter-clockwise positive).
    pub angular_velocity: f64,
}

impl RigidState {
    /// A body at rest at `position` with orientation `angle`.
    #[must_use]
    pub fn at_rest(position: DVec2, angle: f64) -> Self {
        Self { position, angle, ..Self::default() }
    }

    /// The body-frame-to-world transform.
    #[must_use]
    pub fn pose(&self) -> Pose {
        Pose::new(self.position, self.angle)
    }

    /// Velocity of the material point at world position `point`: `v + ω × r`.
    #[must_use]
    pub fn velocity_at(&self, point: DVec2) -> DVec2 {
        let r = point - self.position;
        self.linear_velocity + self.angular_velocity * r.perp()
    }

    /// Whether every field is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.position.is_finite()
            && self.angle.is_finite()
            && self.linear_velocity.is_finite()
            && self.angular_velocity.is_finite()
    }
}

/// Surface and bulk material of a body.
///
/// In a scene, every field may be left out. A left-out `restitution_max` is the larger of
/// `restitution` and the default 0.5, so setting only `restitution` (say 0.8) is valid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "MaterialDef")]
pub struct Material {
    /// Areal density (kg/m²).
    pub density: f64,
    /// Newton restitution `e ∈ [0, 1]` of collisions.
    pub restitution: f64,
    /// Contact restitution `e_max ∈ [e, 1]` reached at full penetration of the band (MODEL §7).
    pub restitution_max: f64,
    /// Friction from rugosity: `λ_min` and `μ_max` (MODEL §5).
    pub friction: FrictionLaw,
}

impl Default for Material {
    fn default() -> Self {
        Self { density: 1000.0, restitution: 0.3, restitution_max: 0.5, friction: FrictionLaw::default() }
    }
}

/// A material as written in a scene: any field may be left out.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDef {
    density: Option<f64>,
    restitution: Option<f64>,
    restitution_max: Option<f64>,
    friction: Option<FrictionLaw>,
}

impl From<MaterialDef> for Material {
    /// Left-out fields take the defaults; a left-out `restitution_max` is at least the given
    /// `restitution` (its domain is `[e, 1]`).
    fn from(def: MaterialDef) -> Self {
        let defaults = Material::default();
        let restitution = def.restitution.unwrap_or(defaults.restitution);
        Self {
            density: def.density.unwrap_or(defaults.density),
            restitution,
            restitution_max: def.restitution_max.unwrap_or(defaults.restitution_max.max(restitution)),
            friction: def.friction.unwrap_or(defaults.friction),
        }
    }
}

impl Material {
    /// Checks every field against its domain.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field (`material.restitution`, …).
    pub fn validate(&self) -> Result<(), SettingsError> {
        use crate::error::check_range;
        // Masses and impulses stay far from overflow (f64::MAX made the mass infinite).
        check_range("material.density", self.density, 1e-6, 1e12)?;
        check_range("material.restitution", self.restitution, 0.0, 1.0)?;
        check_range("material.restitution_max", self.restitution_max, self.restitution, 1.0)?;
        check_range("material.friction.lambda_min", self.friction.lambda_min, 0.0, f64::MAX)?;
        check_range("material.friction.mu_max", self.friction.mu_max, 0.0, f64::MAX)
    }
}

/// How a dynamic body moves under gravity, damping and rotation (docs/model.md §9). Set with
/// [`BodyDesc::with_motion`](crate::BodyDesc::with_motion), changed with
/// [`Simulation::set_motion`](crate::Simulation::set_motion).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Motion {
    /// Multiplies the world's gravity for this body (0: it floats; finite).
    pub gravity_scale: f64,
    /// Linear damping `c` (1/s, ≥ 0): `v ← v / (1 + c h)` every sub-step, as in Box2D.
    pub linear_damping: f64,
    /// Angular damping (1/s, ≥ 0): `ω ← ω / (1 + c h)` every sub-step.
    pub angular_damping: f64,
    /// Whether the body never turns (infinite moment of inertia; its angular velocity is 0).
    pub fixed_rotation: bool,
}

impl Default for Motion {
    fn default() -> Self {
        Self { gravity_scale: 1.0, linear_damping: 0.0, angular_damping: 0.0, fixed_rotation: false }
    }
}

impl Motion {
    /// Checks every field against its domain.
    ///
    /// # Errors
    /// A [`SettingsError`] naming the field (`motion.gravity_scale`, …).
    pub fn validate(&self) -> Result<(), SettingsError> {
        crate::error::check_range("motion.gravity_scale", self.gravity_scale, -1e3, 1e3)?;
        crate::error::check_range("motion.linear_damping", self.linear_damping, 0.0, f64::MAX)?;
        crate::error::check_range("motion.angular_damping", self.angular_damping, 0.0, f64::MAX)
    }
}

/// Which bodies a body collides with (issue 13; rapier's `InteractionGroups`): two bodies
/// interact only if each one's `memberships` share a bit with the other's `filter`. Pairs
/// that do not interact are never tested: they pass through each other.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionGroups {
    /// The groups the body belongs to (bits).
    pub memberships: u32,
    /// The groups the body collides with (bits).
    pub filter: u32,
}

impl Default for CollisionGroups {
    /// Every group, colliding with every group.
    fn default() -> Self {
        Self::ALL
    }
}

impl CollisionGroups {
    /// Member of every group, colliding with every group (the default).
    pub const ALL: Self = Self { memberships: u32::MAX, filter: u32::MAX };

    /// Groups with these bits.
    #[must_use]
    pub const fn new(memberships: u32, filter: u32) -> Self {
        Self { memberships, filter }
    }

    /// Whether bodies with these groups interact: each one's memberships meet the other's filter.
    #[must_use]
    pub const fn interact(self, other: Self) -> bool {
        self.memberships & other.filter != 0 && other.memberships & self.filter != 0
    }
}

/// Force and torque the user applied to a body since the last step; they act over the whole
/// next step (every sub-step of it) and are then cleared, as in Box2D.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AppliedForce {
    /// Force on the centre of mass (N).
    pub force: DVec2,
    /// Torque (N·m, counter-clockwise positive).
    pub torque: f64,
}

/// Whether a dynamic body sleeps, and how long it has been still (docs/model.md §8, our choice). Every dynamic
/// body carries one; the step reads and writes it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sleep {
    /// How long the body has moved slower than `SleepSettings::speed` (s).
    pub still_for: f64,
    /// The island it sleeps in (the spawn order of the island's first body); `None` while it
    /// is awake.
    pub island: Option<u64>,
    /// Position and angle it fell asleep at: a change between steps wakes it.
    pub pose: (DVec2, f64),
}

impl Sleep {
    /// Whether the body sleeps.
    #[must_use]
    pub fn is_asleep(&self) -> bool {
        self.island.is_some()
    }
}

/// Marker: the body is a sensor — it reports the bodies it touches (touch events) and never
/// collides with anything.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Sensor;

/// Marker: the body moves only as the user says (its velocity, `Simulation::set_velocity`),
/// with infinite mass: contacts, gravity and forces do not change it, and it pushes dynamic
/// bodies (moving platforms, a rotating container). It carries `Static` too.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Kinematic;

/// Marker: the body does not move and has infinite mass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Static;

/// The user's name for a body, used in errors and events.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BodyName(pub String);

/// Spawn sequence number: bodies are always processed in this order, so results do not depend
/// on how hecs stores entities (or on components the user adds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct SpawnOrder(pub u64);
