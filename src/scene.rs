//! Scenes in RON: the settings and a list of bodies, each with its shape, rugosity, material
//! and initial state. The format, every default and every error message are in
//! `docs/scenes.md`.
//!
//! ```
//! use rugosa::Scene;
//!
//! let text = r#"(
//!     bodies: [
//!         (name: "block", shape: Generator(generator: RoundedRectangle(width: 4.0, height: 0.4,
//!             corner_radius: 0.05), segments: 32), static: true),
//!         (name: "ball", shape: Generator(generator: Circle(radius: 0.2), segments: 16),
//!             rugosity: Pattern(Constant(value: 0.004)), position: (0.0, 0.5), velocity: (1.0, 0.0)),
//!     ],
//! )"#;
//! let scene = Scene::from_ron_str(text, "inline")?;
//! let mut sim = scene.build()?;
//! sim.step(sim.settings().time_step);
//! assert_eq!(sim.body_count(), 2);
//! # Ok::<(), rugosa::SceneError>(())
//! ```

use std::path::{Path, PathBuf};

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::components::{CollisionGroups, Material, Motion};
use crate::error::{BodyLabel, SettingsError, ShapeError};
use crate::geometry::construct::Generator;
use crate::geometry::multiresolution::NoiseEstimator;
use crate::geometry::patterns::{RugosityPattern, ToleranceRule, rugosity_from_outline};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::self_intersection::find_self_intersection;
use crate::geometry::spline::Spline;
use crate::simulation::{BodyDesc, Simulation, SimulationSettings};

/// A scene: the simulation settings, how long to run it, and its bodies in spawn order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Settings of the dynamics (every field defaults, see [`SimulationSettings`]).
    #[serde(default)]
    pub settings: SimulationSettings,
    /// Suggested run length (s) for tools such as the `simulate` example (default 3).
    #[serde(default = "default_duration")]
    pub duration: f64,
    /// The bodies, spawned in this order.
    pub bodies: Vec<BodyScene>,
    /// Where the scene came from (a path or a label), used in error messages.
    #[serde(skip)]
    pub origin: String,
}

fn default_duration() -> f64 {
    3.0
}

/// One body of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyScene {
    /// Optional name, used in errors, events and plots.
    #[serde(default)]
    pub name: Option<String>,
    /// The boundary curve.
    pub shape: ShapeScene,
    /// The per-segment tolerances (default: smooth, `Pattern(Constant(value: 0.0))`).
    #[serde(default)]
    pub rugosity: RugosityScene,
    /// Density, restitution and friction law (every field defaults, see [`Material`]).
    #[serde(default)]
    pub material: Material,
    /// A static body never moves (default `false`).
    #[serde(default, rename = "static")]
    pub is_static: bool,
    /// World position of the shape's frame origin (m, default `(0, 0)`).
    #[serde(default)]
    pub position: DVec2,
    /// Orientation (rad, default 0).
    #[serde(default)]
    pub angle: f64,
    /// Initial velocity of the centre of mass (m/s, default `(0, 0)`).
    #[serde(default)]
    pub velocity: DVec2,
    /// Initial angular velocity (rad/s, default 0).
    #[serde(default)]
    pub angular_velocity: f64,
    /// Gravity scale, damping and fixed rotation (every field defaults, see [`Motion`]).
    #[serde(default)]
    pub motion: Motion,
    /// Which bodies it collides with (default: every group, see [`CollisionGroups`]).
    #[serde(default)]
    pub groups: CollisionGroups,
    /// A sensor reports what it touches and never collides (default `false`).
    #[serde(default)]
    pub sensor: bool,
    /// A kinematic body moves at its velocity with infinite mass (default `false`).
    #[serde(default)]
    pub kinematic: bool,
}

/// How a body's boundary curve is given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeScene {
    /// Control points of the closed B-spline (the curve does not pass through them).
    ControlPoints(Vec<DVec2>),
    /// Points the closed curve passes through, one per segment joint.
    Interpolate(Vec<DVec2>),
    /// A shape generator with exactly `segments` segments: sampled at `segments` points and
    /// interpolated, or, for the rounded rectangle and polygon, control points on the sides.
    Generator {
        /// The parametric shape.
        generator: Generator,
        /// Number of segments (≥ 4; ≥ 6 per corner for a rounded rectangle or polygon).
        segments: usize,
    },
    /// A dense closed outline, interpolated and decomposed `levels` times; the coarse curve
    /// becomes the boundary and, with rugosity `FromOutline`, the details give the rugosity.
    Outline {
        /// The outline's points, closed (the last joins the first), either orientation.
        points: Vec<DVec2>,
        /// Halvings down to the explicit level: `points.len()` must divide by `2^levels`.
        levels: usize,
        /// Noise rule for `FromOutline` (default `ToleranceInterval(k: 3.0)`).
        #[serde(default)]
        rule: ToleranceRule,
        /// Noise estimator for `FromOutline` (default `MedianAbsolute`).
        #[serde(default)]
        estimator: NoiseEstimator,
    },
}

/// How a body's per-segment tolerances are given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum RugosityScene {
    /// One of the seed's four pattern types.
    Pattern(RugosityPattern),
    /// One tolerance per segment (m).
    Values(Vec<f64>),
    /// The same noise level `S` on every segment, turned into a tolerance by `rule`; the
    /// universal threshold counts one detail coefficient per segment.
    Sigma {
        /// Noise level `S` (m), ≥ 0.
        sigma: f64,
        /// Rule from `S` to `R` (default `ToleranceInterval(k: 3.0)`).
        #[serde(default)]
        rule: ToleranceRule,
    },
    /// Measured from the body's `Outline` shape.
    FromOutline,
}

impl Default for RugosityScene {
    fn default() -> Self {
        Self::Pattern(RugosityPattern::Constant { value: 0.0 })
    }
}

/// Why a scene could not be read or built.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene {}: {source}", path.display())]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not RON, or does not match the format (unknown field, missing field, …).
    #[error("{origin}:{line}:{column}: {message}")]
    Parse {
        /// Path or label of the scene.
        origin: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// A setting is outside its domain.
    #[error("{origin}: settings: {source}")]
    Settings {
        /// Path or label of the scene.
        origin: String,
        /// The refused setting.
        #[source]
        source: SettingsError,
    },
    /// The scene-level `duration` is not finite and positive.
    #[error("{origin}: duration: {value} must be finite and > 0")]
    Duration {
        /// Path or label of the scene.
        origin: String,
        /// The refused value.
        value: f64,
    },
    /// A body is invalid; `field` names the part of its description at fault.
    #[error("{origin}: {body}: {field}: {reason}")]
    Body {
        /// Path or label of the scene.
        origin: String,
        /// The body's index in the scene and its name.
        body: BodyLabel,
        /// `shape`, `rugosity`, `material`, `position`, … (the scene field at fault).
        field: String,
        /// Why it is refused.
        reason: String,
    },
}

/// A body error before the scene's origin is attached: `(field, reason)`.
type FieldError = (String, String);

fn field_error(field: &str, reason: impl ToString) -> FieldError {
    (field.to_owned(), reason.to_string())
}

impl Scene {
    /// Parses a scene from RON text; `origin` (a path or a label) prefixes error messages.
    ///
    /// `Option` fields may be written bare (`name: "wheel"`), the `implicit_some` extension.
    ///
    /// # Errors
    /// [`SceneError::Parse`] with the line and column of the first error.
    pub fn from_ron_str(text: &str, origin: impl Into<String>) -> Result<Self, SceneError> {
        let origin = origin.into();
        let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        match options.from_str::<Scene>(text) {
            Ok(scene) => Ok(Self { origin, ..scene }),
            Err(e) => Err(SceneError::Parse {
                origin,
                line: e.span.start.line,
                column: e.span.start.col,
                message: e.code.to_string(),
            }),
        }
    }

    /// Reads and parses a scene file.
    ///
    /// # Errors
    /// [`SceneError::Io`] naming the path, or as [`Scene::from_ron_str`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_owned(), source })?;
        Self::from_ron_str(&text, path.display().to_string())
    }

    /// Checks the settings and every body and returns them as descriptions, in scene order.
    ///
    /// # Errors
    /// [`SceneError::Settings`], [`SceneError::Duration`], or [`SceneError::Body`] for the
    /// first invalid body, naming it and the field at fault.
    pub fn body_descs(&self) -> Result<Vec<BodyDesc>, SceneError> {
        self.check_settings()?;
        self.bodies
            .iter()
            .enumerate()
            .map(|(index, body)| body.desc().map_err(|e| self.body_error(index, body, e)))
            .collect()
    }

    /// Builds the simulation: validates everything, then spawns the bodies in order.
    ///
    /// # Errors
    /// As [`Scene::body_descs`]; [`SceneError::Settings`] if the thread pool cannot be built.
    pub fn build(&self) -> Result<Simulation, SceneError> {
        let descs = self.body_descs()?;
        let mut sim = Simulation::new(self.settings.clone()).map_err(|e| self.settings_error(e))?;
        for (index, desc) in descs.into_iter().enumerate() {
            sim.add_body(desc)
                .map_err(|e| self.body_error(index, &self.bodies[index], field_error("body", e.reason)))?;
        }
        Ok(sim)
    }

    fn check_settings(&self) -> Result<(), SceneError> {
        self.settings.validate().map_err(|e| self.settings_error(e))?;
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(SceneError::Duration { origin: self.origin.clone(), value: self.duration });
        }
        Ok(())
    }

    fn settings_error(&self, source: SettingsError) -> SceneError {
        SceneError::Settings { origin: self.origin.clone(), source }
    }

    fn body_error(&self, index: usize, body: &BodyScene, (field, reason): FieldError) -> SceneError {
        SceneError::Body {
            origin: self.origin.clone(),
            body: BodyLabel::new(index, body.name.as_deref()),
            field,
            reason,
        }
    }
}

impl BodyScene {
    /// The body description: shape, rugosity, material and initial state, each checked.
    ///
    /// # Errors
    /// `(field, reason)`: the scene field at fault and why.
    fn desc(&self) -> Result<BodyDesc, FieldError> {
        let (spline, outline_rugosity) = self.shape.build().map_err(|e| field_error("shape", e))?;
        if let Some((first, second)) = find_self_intersection(&spline) {
            return Err(field_error("shape", ShapeError::SelfIntersecting { first, second }));
        }
        let rugosity = self.rugosity.build(spline.segment_count(), outline_rugosity)?;
        self.material.validate().map_err(|e| field_error(&e.field, format!("{} {}", e.value, e.reason)))?;
        self.check_initial_state()?;
        let mut desc = BodyDesc::new(spline, rugosity)
            .with_material(self.material)
            .at(self.position, self.angle)
            .with_velocity(self.velocity, self.angular_velocity);
        self.motion.validate().map_err(|e| field_error(&e.field, format!("{} {}", e.value, e.reason)))?;
        if self.motion.fixed_rotation && !self.is_static && self.angular_velocity != 0.0 {
            return Err(field_error("angular_velocity", "a body with fixed rotation does not turn: it must be 0"));
        }
        desc.is_static = self.is_static;
        desc.motion = self.motion;
        desc.groups = self.groups;
        desc.sensor = self.sensor;
        desc.is_kinematic = self.kinematic;
        desc.name.clone_from(&self.name);
        Ok(desc)
    }

    fn check_initial_state(&self) -> Result<(), FieldError> {
        let fields = [
            ("position", self.position.is_finite()),
            ("angle", self.angle.is_finite()),
            ("velocity", self.velocity.is_finite()),
            ("angular_velocity", self.angular_velocity.is_finite()),
        ];
        match fields.iter().find(|(_, finite)| !finite) {
            Some((field, _)) => Err(field_error(field, "must be finite")),
            None => Ok(()),
        }
    }
}

impl ShapeScene {
    /// The curve, and the rugosity measured from an outline (`None` for other shapes).
    ///
    /// # Errors
    /// The [`ShapeError`] of the constructor.
    pub fn build(&self) -> Result<(Spline, Option<Rugosity>), ShapeError> {
        match self {
            Self::ControlPoints(points) => Ok((Spline::from_control_points(points.clone())?, None)),
            Self::Interpolate(points) => Ok((Spline::interpolating(points)?, None)),
            Self::Generator { generator, segments } => Ok((generator.build(*segments)?, None)),
            Self::Outline { points, levels, rule, estimator } => {
                let (spline, rugosity) = rugosity_from_outline(points, *levels, *rule, *estimator)?;
                Ok((spline, Some(rugosity)))
            }
        }
    }
}

impl RugosityScene {
    /// The tolerances for a curve of `segments` segments; `outline` is the rugosity measured
    /// from an `Outline` shape, if the shape was one.
    ///
    /// # Errors
    /// `(field, reason)` with field `rugosity`.
    fn build(&self, segments: usize, outline: Option<Rugosity>) -> Result<Rugosity, FieldError> {
        let fail = |e: ShapeError| field_error("rugosity", e);
        match self {
            Self::Pattern(pattern) => pattern.rugosity(segments).map_err(fail),
            Self::Values(values) if values.len() != segments => {
                Err(field_error("rugosity", format!("{} values for {segments} segments", values.len())))
            }
            Self::Values(values) => Rugosity::new(values.clone()).map_err(fail),
            Self::Sigma { sigma, rule } => {
                let tolerance = rule.tolerance(*sigma, segments).map_err(fail)?;
                Rugosity::constant(segments, tolerance).map_err(fail)
            }
            Self::FromOutline => outline.ok_or_else(|| {
                field_error("rugosity", "FromOutline needs an Outline shape to measure the rugosity from")
            }),
        }
    }
}
