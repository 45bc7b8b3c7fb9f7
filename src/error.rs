//! Typed errors: every failure names the place (body, segment, field) and the reason.

use std::fmt;

use thiserror::Error;

/// Names a body in an error message: its index (in a scene or a world) and its optional name.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BodyLabel {
    /// Position of the body in its scene or spawn order, if known.
    pub index: Option<usize>,
    /// The user's name for the body, if any.
    pub name: Option<String>,
}

impl BodyLabel {
    /// A label with an index and an optional name.
    #[must_use]
    pub fn new(index: usize, name: Option<&str>) -> Self {
        Self { index: Some(index), name: name.map(str::to_owned) }
    }
}

impl fmt::Display for BodyLabel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.index, &self.name) {
            (Some(i), Some(n)) => write!(f, "body {i} ('{n}')"),
            (Some(i), None) => write!(f, "body {i}"),
            (None, Some(n)) => write!(f, "body '{n}'"),
            (None, None) => write!(f, "body"),
        }
    }
}

/// Why a boundary curve, its rugosity or a shape parameter is invalid.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ShapeError {
    /// A closed cubic B-spline needs at least four control points.
    #[error("a closed cubic B-spline needs at least 4 control points, got {count}")]
    TooFewControlPoints {
        /// How many were given.
        count: usize,
    },
    /// A control point has a NaN or infinite coordinate.
    #[error("control point {index} is not finite: ({x}, {y})")]
    NonFiniteControlPoint {
        /// Index of the control point.
        index: usize,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
    },
    /// The enclosed area is zero or negligible relative to the size of the curve.
    #[error("enclosed area {area:.3e} is near zero for a boundary of extent {extent:.3e} (degenerate shape)")]
    DegenerateArea {
        /// Signed area enclosed by the curve.
        area: f64,
        /// Diagonal of the curve's bounding box.
        extent: f64,
    },
    /// The curve runs clockwise (negative enclosed area) where counter-clockwise is required.
    #[error(
        "enclosed area {area:.3e} is negative: the control points run clockwise; list them counter-clockwise (reverse the list)"
    )]
    NegativeArea {
        /// Signed area enclosed by the curve.
        area: f64,
    },
    /// Two non-adjacent segments of the boundary intersect.
    #[error("the boundary intersects itself: segments {first} and {second} cross")]
    SelfIntersecting {
        /// The lower-numbered segment.
        first: usize,
        /// The other segment.
        second: usize,
    },
    /// A rugosity tolerance is negative or not finite.
    #[error("rugosity of segment {segment} is {value}: it must be finite and >= 0")]
    InvalidRugosity {
        /// Index of the segment.
        segment: usize,
        /// The offending value.
        value: f64,
    },
    /// The rugosity does not have one value per segment.
    #[error("rugosity has {got} values but the curve has {expected} segments")]
    RugosityLength {
        /// Number of segments of the curve.
        expected: usize,
        /// Number of tolerances given.
        got: usize,
    },
    /// A constructor or pattern parameter is out of its domain.
    #[error("{what}: {reason}")]
    InvalidParameter {
        /// Which constructor and parameter, e.g. `ellipse.semi_axes`.
        what: String,
        /// Why the value is refused.
        reason: String,
    },
}

impl ShapeError {
    /// Shorthand for [`ShapeError::InvalidParameter`].
    #[must_use]
    pub fn parameter(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::InvalidParameter { what: what.into(), reason: reason.into() }
    }

    /// Attaches the body this error belongs to.
    #[must_use]
    pub fn for_body(self, body: BodyLabel) -> BodyError {
        BodyError { body, reason: self }
    }
}

/// A shape error together with the body it belongs to.
#[derive(Clone, Debug, PartialEq, Error)]
#[error("{body}: {reason}")]
pub struct BodyError {
    /// The body at fault.
    pub body: BodyLabel,
    /// Why it is invalid.
    #[source]
    pub reason: ShapeError,
}

/// A setting outside its domain.
#[derive(Clone, Debug, PartialEq, Error)]
#[error("setting `{field}` = {value}: {reason}")]
pub struct SettingsError {
    /// The setting's field path, e.g. `rugosity.k`.
    pub field: String,
    /// The refused value, as text.
    pub value: String,
    /// Why it is refused.
    pub reason: String,
}

impl SettingsError {
    /// Builds a settings error for `field` holding `value`.
    #[must_use]
    pub fn new(field: impl Into<String>, value: impl fmt::Display, reason: impl Into<String>) -> Self {
        Self { field: field.into(), value: value.to_string(), reason: reason.into() }
    }
}

/// Checks that a setting is finite and within `[low, high]`.
///
/// # Errors
/// [`SettingsError`] naming `field` when the value is NaN, infinite or out of range.
pub fn check_range(field: &str, value: f64, low: f64, high: f64) -> Result<(), SettingsError> {
    if !value.is_finite() {
        return Err(SettingsError::new(field, value, "must be finite"));
    }
    if value < low || value > high {
        return Err(SettingsError::new(field, value, range_text(low, high)));
    }
    Ok(())
}

/// `must lie in [low, high]`, or the one-sided form when a bound is the extreme `f64`.
fn range_text(low: f64, high: f64) -> String {
    match (low, high) {
        (f64::MIN_POSITIVE, f64::MAX) => "must be > 0".to_owned(),
        (low, f64::MAX) => format!("must be >= {low}"),
        (low, high) => format!("must lie in [{low}, {high}]"),
    }
}

/// Why an action on a body ([`Simulation::apply_force`](crate::Simulation::apply_force), …)
/// was refused; nothing was changed.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum BodyActionError {
    /// The entity is not a body of this simulation (never spawned here, or removed).
    #[error("{action}: entity {entity:?} is not a body of this simulation")]
    NotABody {
        /// What was asked.
        action: &'static str,
        /// The entity given.
        entity: hecs::Entity,
    },
    /// Static bodies do not move: a force, impulse or velocity given to one is an error.
    #[error("{action}: {body} is static; static bodies do not move")]
    Static {
        /// What was asked.
        action: &'static str,
        /// The body.
        body: BodyLabel,
    },
    /// A kinematic body moves only at the velocity it is given (`set_velocity`): forces,
    /// impulses and motion settings do not act on it.
    #[error("{action}: {body} is kinematic; it moves only at the velocity set_velocity gives it")]
    Kinematic {
        /// What was asked.
        action: &'static str,
        /// The body.
        body: BodyLabel,
    },
    /// An argument is NaN or infinite, or outside its domain.
    #[error("{action}: {body}: {source}")]
    Argument {
        /// What was asked.
        action: &'static str,
        /// The body.
        body: BodyLabel,
        /// Which argument, its value and the rule.
        source: Box<SettingsError>,
    },
}

/// Why a [`Snapshot`](crate::Snapshot) could not be taken, read or restored; nothing was changed.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum SnapshotError {
    /// The RON text is not a snapshot (syntax, a missing or unknown field, a value of the wrong
    /// type, an entity handle of 0): the parser's message, with the line and column.
    #[error("snapshot text: {0}")]
    Text(String),
    /// A setting is outside its domain ([`SimulationSettings::validate`](crate::SimulationSettings::validate)),
    /// or the thread pool could not be built.
    #[error("snapshot settings: {0}")]
    Settings(SettingsError),
    /// A body's curve, rugosity, material, motion or state is invalid, as
    /// [`Simulation::add_body`](crate::Simulation::add_body) would refuse it; the label is the
    /// body's index in [`Snapshot::bodies`](crate::Snapshot::bodies).
    #[error("snapshot {0}")]
    Body(BodyError),
    /// Any other field: its path in the snapshot (e.g. `bodies[3].state.linear_velocity`,
    /// `excluded_pairs[0]`, `step.pairs[2].manifold.contacts[1]`), the value and the rule.
    #[error("snapshot field `{field}` = {value}: {reason}")]
    Field {
        /// Path of the field in the snapshot.
        field: String,
        /// The refused value, as text.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// A body of the simulation cannot be saved: it lacks a component it needs, or its state is
    /// not finite (both only through [`Simulation::world_mut`](crate::Simulation::world_mut)).
    #[error("cannot save {body}: {reason}")]
    Broken {
        /// The body (spawn index and name).
        body: BodyLabel,
        /// What is wrong with it.
        reason: String,
    },
}

impl SnapshotError {
    /// A [`SnapshotError::Field`] for `field` holding `value`.
    pub(crate) fn field(field: impl Into<String>, value: impl fmt::Debug, reason: impl Into<String>) -> Self {
        Self::Field { field: field.into(), value: format!("{value:?}"), reason: reason.into() }
    }

    /// A [`SettingsError`] about a field below `prefix` (the check's own field name appended).
    pub(crate) fn at(prefix: &str, error: SettingsError) -> Self {
        Self::Field { field: format!("{prefix}{}", error.field), value: error.value, reason: error.reason }
    }
}
