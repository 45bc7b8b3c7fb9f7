//! Scene queries, exact on the curves (docs/model.md §10): ray casts, point queries and box
//! queries. Each body's world bounds (its bounding octagon at its pose, band included; a ray
//! its tree's root box) are tested first; a ray then descends the body's AOBB tree in the
//! body's frame, and the pieces of the leaves it reaches are solved exactly (`geometry::ray`). Queries read the bodies as they are between steps.
//!
//! ```
//! use rugosa::{BodyDesc, Generator, QueryFilter, Rugosity, Simulation, SimulationSettings};
//! use rugosa::glam::DVec2;
//!
//! let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
//! let disc = Generator::Circle { radius: 0.5 }.build(16).unwrap();
//! let body = sim.add_body(BodyDesc::new(disc, Rugosity::constant(16, 0.0).unwrap()).at(DVec2::new(3.0, 0.0), 0.0)).unwrap();
//! let hit = sim.cast_ray(DVec2::ZERO, DVec2::X, 10.0, &QueryFilter::default()).unwrap();
//! assert_eq!(hit.body, body);
//! assert!((hit.distance - 2.5).abs() < 1e-3); // the 16-segment circle is within 1e-3 of r = 0.5
//! assert!(hit.entering && (hit.normal + DVec2::X).length() < 1e-2);
//! assert_eq!(sim.bodies_containing(DVec2::new(3.1, 0.0), &QueryFilter::default()), vec![body]);
//! ```

use glam::DVec2;
use hecs::Entity;

use super::Simulation;
use crate::components::{CollisionGroups, RigidState};
use crate::geometry::aobb_tree::{AobbNodeKind, AobbTree};
use crate::geometry::pose::Pose;
use crate::geometry::ray::{Ray, ray_crossings};
use crate::geometry::spline::Spline;
use crate::systems::BodyRecord;

/// Which bodies a query sees. `Default` sees every body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QueryFilter {
    /// A body to leave out (say, the one casting the ray).
    pub exclude: Option<Entity>,
    /// Leave out sensors.
    pub exclude_sensors: bool,
    /// Leave out static and kinematic bodies.
    pub exclude_fixed: bool,
    /// Only bodies whose collision groups interact with these (rapier's rule).
    pub groups: Option<CollisionGroups>,
}

impl QueryFilter {
    pub(super) fn admits(&self, body: &BodyRecord) -> bool {
        self.exclude != Some(body.entity)
            && !(self.exclude_sensors && body.sensor)
            && !(self.exclude_fixed && body.is_static)
            && self.groups.is_none_or(|groups| groups.interact(body.groups))
    }
}

/// Where a ray meets a body's boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The body.
    pub body: Entity,
    /// Distance from the ray's origin (m).
    pub distance: f64,
    /// The point on the boundary, in the world.
    pub point: DVec2,
    /// The boundary's outward unit normal there, in the world.
    pub normal: DVec2,
    /// Segment of the boundary.
    pub segment: usize,
    /// Parameter within the segment, in `[0, 1]`.
    pub parameter: f64,
    /// Whether the ray enters the body there (`false`: it leaves it, having started inside).
    pub entering: bool,
}

/// The nearest boundary point of a body to a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointProjection {
    /// The body.
    pub body: Entity,
    /// The nearest point of its boundary, in the world.
    pub point: DVec2,
    /// Distance to it (m).
    pub distance: f64,
    /// Segment of the boundary.
    pub segment: usize,
    /// Parameter within the segment.
    pub parameter: f64,
}

/// A body's boundary, tree and pose, read from the world.
pub(super) struct Placed<'w> {
    pub(super) spline: hecs::Ref<'w, Spline>,
    pub(super) tree: hecs::Ref<'w, AobbTree>,
    pub(super) pose: Pose,
}

impl Simulation {
    pub(super) fn placed(&self, body: &BodyRecord) -> Option<Placed<'_>> {
        let entity = self.world.entity(body.entity).ok()?;
        let pose = entity.get::<&RigidState>()?.pose();
        Some(Placed { spline: entity.get::<&Spline>()?, tree: entity.get::<&AobbTree>()?, pose })
    }

    /// The first boundary a ray from `origin` along `direction` meets within `max_distance`,
    /// exactly on the curves (a band is a contact tolerance, not part of the boundary). `None`
    /// when it meets none, or for a zero or non-finite direction or a negative distance. A ray
    /// that starts inside a body first meets that body's boundary from inside
    /// (`entering == false`).
    #[must_use]
    pub fn cast_ray(&self, origin: DVec2, direction: DVec2, max_distance: f64, filter: &QueryFilter) -> Option<RayHit> {
        let mut first: Option<RayHit> = None;
        self.ray_hits(origin, direction, max_distance, filter, |hit| {
            if first.is_none_or(|f| hit.distance < f.distance) {
                first = Some(hit);
            }
        });
        first
    }

    /// Every boundary crossing of the ray within `max_distance`, nearest first, into `out`
    /// (cleared first).
    pub fn cast_ray_all(
        &self,
        origin: DVec2,
        direction: DVec2,
        max_distance: f64,
        filter: &QueryFilter,
        out: &mut Vec<RayHit>,
    ) {
        out.clear();
        self.ray_hits(origin, direction, max_distance, filter, |hit| out.push(hit));
        out.sort_by(|a, b| a.distance.total_cmp(&b.distance));
    }

    fn ray_hits(
        &self,
        origin: DVec2,
        direction: DVec2,
        max_distance: f64,
        filter: &QueryFilter,
        mut found: impl FnMut(RayHit),
    ) {
        let Some(ray) = Ray::new(origin, direction, max_distance) else { return };
        let mut stack = Vec::new();
        for body in self.bodies.iter().filter(|b| filter.admits(b)) {
            let Some(placed) = self.placed(body) else { continue };
            let root = body.root_box.transformed(&placed.pose);
            if ray.box_interval(root.centre, root.axis, root.half_extents).is_none() {
                continue;
            }
            // The ray in the body's frame: the tree's boxes and the pieces stay where they are.
            let local = Ray {
                origin: placed.pose.inverse_transform_point(ray.origin),
                direction: placed.pose.inverse_rotate(ray.direction),
                max_distance: ray.max_distance,
            };
            stack.clear();
            stack.push(placed.tree.root_index());
            while let Some(index) = stack.pop() {
                let node = &placed.tree.nodes()[index as usize];
                let obb = &node.obb;
                if local.box_interval(obb.centre, obb.axis, obb.half_extents).is_none() {
                    continue;
                }
                match node.kind {
                    AobbNodeKind::Branch { children } => stack.extend(children),
                    AobbNodeKind::Leaf { segment } => {
                        let piece = placed.spline.segment(segment as usize);
                        for crossing in ray_crossings(&local, &piece) {
                            let normal = outward(piece.derivative(crossing.s));
                            found(RayHit {
                                body: body.entity,
                                distance: crossing.distance,
                                point: ray.at(crossing.distance),
                                normal: placed.pose.rotate(normal),
                                segment: segment as usize,
                                parameter: crossing.s,
                                entering: crossing.side < 0.0,
                            });
                        }
                    }
                }
            }
        }
    }

    /// The bodies whose boundary encloses `point`, in spawn order: the winding number of each
    /// boundary about the point, counted exactly from a ray's crossings (a point on a boundary
    /// may fall either way).
    #[must_use]
    pub fn bodies_containing(&self, point: DVec2, filter: &QueryFilter) -> Vec<Entity> {
        let mut inside = Vec::new();
        for (body, octagon) in self.bodies.iter().zip(&self.octagons).filter(|(b, _)| filter.admits(b)) {
            let Some(placed) = self.placed(body) else { continue };
            let (low, high) = octagon.world_bounds(&placed.pose);
            if point.cmplt(low).any() || point.cmpgt(high).any() {
                continue;
            }
            if placed.spline.winding_number(placed.pose.inverse_transform_point(point)) != 0 {
                inside.push(body.entity);
            }
        }
        inside
    }

    /// The nearest boundary point to `point` of any body within `max_distance` of it (exact:
    /// the 1-D nearest point on each piece whose control box could hold a nearer one).
    #[must_use]
    pub fn project_point(&self, point: DVec2, max_distance: f64, filter: &QueryFilter) -> Option<PointProjection> {
        let mut best: Option<PointProjection> = None;
        for (body, octagon) in self.bodies.iter().zip(&self.octagons).filter(|(b, _)| filter.admits(b)) {
            let Some(placed) = self.placed(body) else { continue };
            let (low, high) = octagon.world_bounds(&placed.pose);
            let reach = best.map_or(max_distance, |b| b.distance.min(max_distance));
            if point.clamp(low, high).distance(point) > reach {
                continue;
            }
            let nearest = placed.spline.nearest_point(placed.pose.inverse_transform_point(point));
            if nearest.distance <= reach && best.is_none_or(|b| nearest.distance < b.distance) {
                let (segment, parameter) = placed.spline.split_parameter(nearest.parameter);
                best = Some(PointProjection {
                    body: body.entity,
                    point: placed.pose.transform_point(nearest.position),
                    distance: nearest.distance,
                    segment,
                    parameter,
                });
            }
        }
        best
    }

    /// The bodies whose world bounds (their bounding octagon at their pose, band included)
    /// overlaps the box `[min, max]`, in spawn order (as rapier's
    /// `colliders_with_aabb_intersecting_aabb`: a candidate list, not an exact overlap).
    #[must_use]
    pub fn bodies_in_aabb(&self, min: DVec2, max: DVec2, filter: &QueryFilter) -> Vec<Entity> {
        let mut found = Vec::new();
        for (body, octagon) in self.bodies.iter().zip(&self.octagons).filter(|(b, _)| filter.admits(b)) {
            let Some(placed) = self.placed(body) else { continue };
            let (low, high) = octagon.world_bounds(&placed.pose);
            if low.cmple(max).all() && high.cmpge(min).all() {
                found.push(body.entity);
            }
        }
        found
    }
}

/// The outward unit normal of a counter-clockwise boundary whose tangent is `tangent`.
fn outward(tangent: DVec2) -> DVec2 {
    DVec2::new(tangent.y, -tangent.x).try_normalize().unwrap_or(DVec2::ZERO)
}
