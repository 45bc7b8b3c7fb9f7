//! [`BodyDesc`]: a body to spawn, built up and checked before it enters the world.

use glam::DVec2;

use crate::components::{CollisionGroups, Material, Motion};
use crate::error::{BodyError, BodyLabel, SettingsError};
use crate::simulation::settings::{MAX_ANGULAR_SPEED, MAX_COORDINATE, MAX_SPEED};

/// Checks a body's position and velocities against the supported domain (docs/scenes.md).
///
/// # Errors
/// A [`SettingsError`] naming `position`, `velocity` or `angular_velocity`.
pub(crate) fn check_state_domain(position: DVec2, velocity: DVec2, angular: f64) -> Result<(), SettingsError> {
    if position.abs().max_element() > MAX_COORDINATE {
        let reason = format!("must lie within {MAX_COORDINATE:e} m of the origin in x and y");
        return Err(SettingsError::new("position", position, reason));
    }
    if velocity.length() > MAX_SPEED {
        return Err(SettingsError::new("velocity", velocity, format!("must be at most {MAX_SPEED:e} m/s")));
    }
    if angular.abs() > MAX_ANGULAR_SPEED {
        let reason = format!("must be at most {MAX_ANGULAR_SPEED:e} rad/s");
        return Err(SettingsError::new("angular_velocity", angular, reason));
    }
    Ok(())
}
use crate::geometry::rugosity::Rugosity;
use crate::geometry::self_intersection::find_self_intersection;
use crate::geometry::spline::Spline;

/// Description of a body to spawn. The curve is given in its own frame; `position` and
/// `angle` place that frame in the world (the body's centre of mass is computed from it).
#[derive(Clone, Debug, PartialEq)]
pub struct BodyDesc {
    /// Boundary curve in the body's own frame.
    pub spline: Spline,
    /// Per-segment tolerances.
    pub rugosity: Rugosity,
    /// Density, restitution and friction law.
    pub material: Material,
    /// World position of the curve's frame origin (m).
    pub position: DVec2,
    /// Orientation of the curve's frame (rad).
    pub angle: f64,
    /// Initial velocity of the centre of mass (m/s).
    pub linear_velocity: DVec2,
    /// Initial angular velocity (rad/s).
    pub angular_velocity: f64,
    /// A static body never moves.
    pub is_static: bool,
    /// A kinematic body moves at the velocity the user gives it, with infinite mass.
    pub is_kinematic: bool,
    /// Gravity scale, damping and fixed rotation (ignored for static bodies).
    pub motion: Motion,
    /// Which bodies it collides with (default: all).
    pub groups: CollisionGroups,
    /// A sensor reports what it touches (touch events) and never collides.
    pub sensor: bool,
    /// Optional name, used in errors and events.
    pub name: Option<String>,
}

impl BodyDesc {
    /// A dynamic body at rest at the origin with the default material.
    #[must_use]
    pub fn new(spline: Spline, rugosity: Rugosity) -> Self {
        Self {
            spline,
            rugosity,
            material: Material::default(),
            position: DVec2::ZERO,
            angle: 0.0,
            linear_velocity: DVec2::ZERO,
            angular_velocity: 0.0,
            is_static: false,
            is_kinematic: false,
            motion: Motion::default(),
            groups: CollisionGroups::ALL,
            sensor: false,
            name: None,
        }
    }

    /// Makes the body a sensor: it reports the bodies it touches and never collides.
    #[must_use]
    pub fn sensor(mut self) -> Self {
        self.sensor = true;
        self
    }

    /// Sets which bodies it collides with.
    #[must_use]
    pub fn with_groups(mut self, groups: CollisionGroups) -> Self {
        self.groups = groups;
        self
    }

    /// Sets the gravity scale, damping and fixed rotation.
    #[must_use]
    pub fn with_motion(mut self, motion: Motion) -> Self {
        self.motion = motion;
        self
    }

    /// Sets the material.
    #[must_use]
    pub fn with_material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// Places the curve's frame origin at `position`, rotated by `angle`.
    #[must_use]
    pub fn at(mut self, position: DVec2, angle: f64) -> Self {
        self.position = position;
        self.angle = angle;
        self
    }

    /// Sets the initial linear and angular velocity.
    #[must_use]
    pub fn with_velocity(mut self, linear: DVec2, angular: f64) -> Self {
        self.linear_velocity = linear;
        self.angular_velocity = angular;
        self
    }

    /// Makes the body kinematic: it moves at its velocity (the initial one, then what
    /// [`Simulation::set_velocity`](crate::Simulation::set_velocity) gives), with infinite mass.
    #[must_use]
    pub fn kinematic(mut self) -> Self {
        self.is_kinematic = true;
        self
    }

    /// Makes the body static.
    #[must_use]
    pub fn fixed(mut self) -> Self {
        self.is_static = true;
        self
    }

    /// Names the body.
    #[must_use]
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Checks the curve (including self-intersection), the rugosity and the material.
    ///
    /// # Errors
    /// A [`BodyError`] naming `label` and the reason.
    pub fn validate(&self, label: &BodyLabel) -> Result<(), BodyError> {
        let fail = |reason| BodyError { body: label.clone(), reason };
        self.spline.validate().map_err(fail)?;
        if let Some((first, second)) = find_self_intersection(&self.spline) {
            return Err(fail(crate::ShapeError::SelfIntersecting { first, second }));
        }
        self.rugosity.validate(self.spline.segment_count()).map_err(fail)?;
        self.material
            .validate()
            .map_err(|e| fail(crate::ShapeError::parameter(e.field.clone(), format!("{} ({})", e.reason, e.value))))?;
        let finite = [self.position.x, self.position.y, self.angle, self.linear_velocity.x, self.linear_velocity.y]
            .iter()
            .chain(std::iter::once(&self.angular_velocity))
            .all(|v| v.is_finite());
        if !finite {
            return Err(fail(crate::ShapeError::parameter(
                "initial state",
                "position, angle and velocities must be finite",
            )));
        }
        if let Err(e) = check_state_domain(self.position, self.linear_velocity, self.angular_velocity) {
            return Err(fail(crate::ShapeError::parameter(e.field.clone(), format!("{} ({})", e.reason, e.value))));
        }
        self.motion
            .validate()
            .map_err(|e| fail(crate::ShapeError::parameter(e.field.clone(), format!("{} ({})", e.reason, e.value))))?;
        if self.motion.fixed_rotation && !self.is_static && self.angular_velocity != 0.0 {
            return Err(fail(crate::ShapeError::parameter(
                "angular_velocity",
                "a body with fixed rotation does not turn: its angular velocity must be 0",
            )));
        }
        Ok(())
    }

    /// Checks that the band (the largest tolerance, or `min_band`) is no wider than the body:
    /// a wider band is not surface detail (a 1e300 m band gave NaN, 1–5 m bands on a 0.6 m body
    /// cost seconds per step).
    ///
    /// # Errors
    /// A [`BodyError`] naming `label` and the two widths.
    pub(crate) fn check_band(&self, min_band: f64, label: &BodyLabel) -> Result<(), BodyError> {
        let (low, high) = self.spline.bounds();
        let extent = (high - low).length();
        let band = self.rugosity.body_band(min_band);
        if band > extent {
            let reason = format!(
                "band {band:e} m (the largest tolerance or settings.min_band) is wider than the body ({extent:e} m across)"
            );
            return Err(BodyError { body: label.clone(), reason: crate::ShapeError::parameter("rugosity", reason) });
        }
        Ok(())
    }
}
