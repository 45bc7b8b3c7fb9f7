//! Shape cast: the time at which a body, moved from its pose at a constant velocity, first
//! comes within a distance of another body's boundary (docs/model.md §10), by conservative
//! advancement on the exact curve distance — as rapier's `cast_shape` and Box2D's
//! `b2World_CastShape`, on the splines.
//!
//! ```
//! use rugosa::{BodyDesc, Generator, QueryFilter, Rugosity, ShapeCast, Simulation, SimulationSettings};
//! use rugosa::glam::DVec2;
//!
//! let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
//! let disc = |x: f64| {
//!     let spline = Generator::Circle { radius: 0.5 }.build(16).unwrap();
//!     BodyDesc::new(spline, Rugosity::constant(16, 0.0).unwrap()).at(DVec2::new(x, 0.0), 0.0)
//! };
//! let mover = sim.add_body(disc(0.0)).unwrap();
//! let wall = sim.add_body(disc(3.0).fixed()).unwrap();
//! let cast = ShapeCast { linear_velocity: DVec2::new(2.0, 0.0), ..ShapeCast::default() };
//! let hit = sim.cast_shape(mover, &cast, &QueryFilter::default()).unwrap().unwrap();
//! assert_eq!(hit.body, wall);
//! assert!((hit.time - 1.0).abs() < 1e-3); // 2 m of gap at 2 m/s (the circles within 1e-3 of r)
//! ```

use glam::DVec2;
use hecs::Entity;

use super::Simulation;
use super::queries::{Placed, QueryFilter};
use crate::error::{BodyActionError, SettingsError};
use crate::geometry::aobb_tree::TraversalWorkspace;
use crate::geometry::curve_pair::{CurvePairSettings, closest_points_segment_segment};
use crate::geometry::pose::Pose;

/// A motion to cast a body along: constant velocity from its present pose, up to `max_time`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeCast {
    /// Velocity of the centre of mass (m/s).
    pub linear_velocity: DVec2,
    /// Angular velocity about the centre of mass (rad/s).
    pub angular_velocity: f64,
    /// Longest time to look ahead (s), `> 0`.
    pub max_time: f64,
    /// The cast stops where the curves come this close (m), `≥ 0`: 0 for touching curves, a
    /// band's width to stop at its outer edge.
    pub target_distance: f64,
}

impl Default for ShapeCast {
    /// At rest, one second ahead, stopping where the curves touch.
    fn default() -> Self {
        Self { linear_velocity: DVec2::ZERO, angular_velocity: 0.0, max_time: 1.0, target_distance: 0.0 }
    }
}

/// Where a cast body first meets another.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeHit {
    /// The body met.
    pub body: Entity,
    /// When (s from now, in `[0, max_time]`); 0 if they are already that close.
    pub time: f64,
    /// The nearest point of the body met, in the world, at that time.
    pub point: DVec2,
    /// The outward unit normal of the body met there (pointing towards the cast body).
    pub normal: DVec2,
    /// The distance between the curves then (m): `target_distance` to within
    /// [`SHAPE_CAST_TOLERANCE`] of the pair's size, less if they started closer.
    pub distance: f64,
    /// Segment of the body met, and the parameter within it.
    pub segment: usize,
    /// Parameter within that segment, in `[0, 1]`.
    pub parameter: f64,
}

/// Relative accuracy of a cast's stopping distance (of the larger body's radius).
pub const SHAPE_CAST_TOLERANCE: f64 = 1e-9;
/// Conservative-advancement iterations per body pair before the cast gives up on that pair.
const MAX_ADVANCES: usize = 1000;

impl Simulation {
    /// The first body that body `entity`, moved from its pose by `cast` (the others held where
    /// they are), comes within `cast.target_distance` of, exactly on the curves. `None` when it
    /// meets none within `cast.max_time`. The cast body itself and the filter's exclusions are
    /// left out; it is not moved.
    ///
    /// Conservative advancement: at each time the exact distance `d` between the curves bounds
    /// how long the cast body may move before they can be `target_distance` apart —
    /// `(d − target) / (|v| + |ω| R)`, `R` the reach of its curve from its centre of mass — and
    /// time advances by that until the distance is within [`SHAPE_CAST_TOLERANCE`] of the target.
    /// A fast spin grazing another body takes many small advances; a pair that needs more than 1000
    /// is reported at the time reached, which is never past the true one (its `distance` says how short).
    ///
    /// # Errors
    /// [`BodyActionError`]: not a body of this simulation, or a non-finite velocity, a
    /// `max_time` that is not positive or a negative `target_distance`.
    pub fn cast_shape(
        &self,
        entity: Entity,
        cast: &ShapeCast,
        filter: &QueryFilter,
    ) -> Result<Option<ShapeHit>, BodyActionError> {
        const ACTION: &str = "cast_shape";
        let slot = self.body_slot(ACTION, entity)?;
        let v = cast.linear_velocity;
        self.check_finite(ACTION, slot, &[("linear_velocity", v.x), ("linear_velocity", v.y)])?;
        self.check_finite(ACTION, slot, &[("angular_velocity", cast.angular_velocity)])?;
        let domain = |name: &str, value: f64, ok: bool, rule: &str| {
            if ok {
                Ok(())
            } else {
                Err(BodyActionError::Argument {
                    action: ACTION,
                    body: self.label(slot),
                    source: Box::new(SettingsError::new(name, value, rule)),
                })
            }
        };
        domain(
            "max_time",
            cast.max_time,
            cast.max_time > 0.0 && cast.max_time.is_finite(),
            "must be positive and finite",
        )?;
        let target = cast.target_distance;
        domain("target_distance", target, target >= 0.0 && target.is_finite(), "must be non-negative and finite")?;
        let Some(caster) = self.placed(&self.bodies[slot]) else { return Ok(None) };
        let reach = caster.spline.control_points().iter().map(|p| p.length()).fold(0.0, f64::max);
        let speed = v.length() + cast.angular_velocity.abs() * reach;
        let sweep = speed * cast.max_time;
        let pose_at = |t: f64| Pose::new(caster.pose.position + v * t, caster.pose.angle() + cast.angular_velocity * t);
        let (start_low, start_high) = self.octagons[slot].world_bounds(&caster.pose);
        let (low, high) = (start_low - DVec2::splat(sweep + target), start_high + DVec2::splat(sweep + target));
        let mut best: Option<ShapeHit> = None;
        let mut workspace = TraversalWorkspace::new();
        let mut pairs = Vec::new();
        let others = self.bodies.iter().zip(&self.octagons);
        for (other, octagon) in others.filter(|(b, _)| b.entity != entity && filter.admits(b)) {
            let Some(shape) = self.placed(other) else { continue };
            let (other_low, other_high) = octagon.world_bounds(&shape.pose);
            if other_low.cmpgt(high).any() || other_high.cmplt(low).any() {
                continue;
            }
            let horizon = best.map_or(cast.max_time, |b| b.time);
            let size = reach.max(other.radius);
            let mut t = 0.0;
            for advance in 0..MAX_ADVANCES {
                let pose = pose_at(t);
                // Leaf pairs farther apart than the rest of the sweep cannot come within the
                // target before the horizon: the distance is at least that.
                let margin = speed * (horizon - t) + target;
                let Some(nearest) = nearest_points(&caster, &pose, &shape, margin, &mut workspace, &mut pairs) else {
                    break; // farther apart than the rest of the sweep can close
                };
                let excess = nearest.distance - target;
                if excess <= SHAPE_CAST_TOLERANCE * size || advance + 1 == MAX_ADVANCES {
                    let (segment, parameter) = (nearest.segment_b, nearest.s);
                    let normal = shape.pose.rotate(shape.spline.outward_normal(segment as f64 + parameter));
                    let hit = ShapeHit {
                        body: other.entity,
                        time: t,
                        point: nearest.point_b,
                        normal,
                        distance: nearest.distance,
                        segment,
                        parameter,
                    };
                    if best.is_none_or(|b| t < b.time) {
                        best = Some(hit);
                    }
                    break;
                }
                if speed == 0.0 {
                    break; // at rest and not within the target: never
                }
                t += excess / speed;
                if t > horizon {
                    break;
                }
            }
        }
        Ok(best)
    }
}

/// The nearest points of the caster at `pose` and `other`, over the leaf pairs within `margin`
/// (`None` when there are none: the curves are farther apart than `margin`).
fn nearest_points(
    caster: &Placed<'_>,
    pose: &Pose,
    other: &Placed<'_>,
    margin: f64,
    workspace: &mut TraversalWorkspace,
    pairs: &mut Vec<(u32, u32)>,
) -> Option<Nearest> {
    caster.tree.overlapping_leaves_within(pose, &other.tree, &other.pose, margin, workspace, pairs);
    let settings = CurvePairSettings::default();
    let mut best: Option<Nearest> = None;
    for &(i, j) in pairs.iter() {
        let a = caster.spline.segment(i as usize).transformed(pose);
        let b = other.spline.segment(j as usize).transformed(&other.pose);
        let found = closest_points_segment_segment(&a, &b, &settings);
        if best.is_none_or(|n| found.distance < n.distance) {
            best =
                Some(Nearest { distance: found.distance, point_b: found.point_b, segment_b: j as usize, s: found.s });
        }
    }
    best
}

/// The nearest points of a body pair, on the second body.
#[derive(Clone, Copy, Debug)]
struct Nearest {
    distance: f64,
    point_b: DVec2,
    segment_b: usize,
    s: f64,
}
