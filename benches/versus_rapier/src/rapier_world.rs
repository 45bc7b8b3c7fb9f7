//! A scene in rapier2d (f32): each spline body becomes a convex polygon or a compound of convex
//! pieces at a verified geometric error; glam 0.34 `DVec2` is converted to rapier's `Vector`
//! (glam 0.33 `Vec2`, via glamx) here and nowhere else.

use glam::DVec2;
use rapier2d::prelude::*;
use rugosa::{BodyDesc, recentre};

use crate::polygon::{SplinePolygon, convex_hull, fan_decomposition, polygon_within};
use crate::scenes::SceneSpec;

/// How one body was given to rapier.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShapeStats {
    /// Polygon vertices.
    pub vertices: usize,
    /// Convex pieces (1 for a convex body).
    pub pieces: usize,
    /// Verified bound of the Hausdorff distance between polygon and spline (m).
    pub hausdorff: f64,
    /// Whether parry's approximate VHACD decomposition had to be used (polygon not star-shaped).
    pub vhacd: bool,
}

/// The rapier world of a scene, with the handles of its bodies in scene order.
pub struct RapierScene {
    /// All of rapier's state.
    pub world: PhysicsWorld,
    /// Handle of each body, in scene order.
    pub handles: Vec<RigidBodyHandle>,
    /// How each body's shape was built, in scene order.
    pub shapes: Vec<ShapeStats>,
}

fn vector(v: DVec2) -> Vector {
    Vector::new(v.x as f32, v.y as f32)
}

/// Position of a body's origin (its centre of mass in rugosa's frame).
#[must_use]
pub fn position(scene: &RapierScene, index: usize) -> DVec2 {
    let translation = scene.world.bodies[scene.handles[index]].translation();
    DVec2::new(f64::from(translation.x), f64::from(translation.y))
}

/// Builds the scene with every spline sampled to `tolerance` (m), stepping at `dt`.
#[must_use]
pub fn build(spec: &SceneSpec, tolerance: f64, dt: f64) -> RapierScene {
    let mut world = PhysicsWorld::new();
    world.gravity = vector(spec.settings.gravity);
    world.integration_parameters.dt = dt as f32;
    let mut handles = Vec::with_capacity(spec.bodies.len());
    let mut shapes = Vec::with_capacity(spec.bodies.len());
    for desc in &spec.bodies {
        let (centroid, shape, stats) = body_shape(desc, tolerance);
        let body = rigid_body(desc, centroid);
        let collider = ColliderBuilder::new(shape)
            .density(desc.material.density as f32)
            .friction(spec.friction_of(desc) as f32)
            .friction_combine_rule(CoefficientCombineRule::Max)
            .restitution(desc.material.restitution as f32)
            .restitution_combine_rule(CoefficientCombineRule::Max);
        let (handle, _) = world.insert(body, collider);
        handles.push(handle);
        shapes.push(stats);
    }
    RapierScene { world, handles, shapes }
}

/// A rigid body at rugosa's centre of mass and angle; sleeping off, as rugosa has none.
fn rigid_body(desc: &BodyDesc, centroid: DVec2) -> RigidBodyBuilder {
    let builder = if desc.is_static { RigidBodyBuilder::fixed() } else { RigidBodyBuilder::dynamic() };
    let centre = desc.position + DVec2::from_angle(desc.angle).rotate(centroid);
    builder
        .translation(vector(centre))
        .rotation(desc.angle as f32)
        .linvel(vector(desc.linear_velocity))
        .angvel(desc.angular_velocity as f32)
        .can_sleep(false)
}

/// The body's shape about its centroid: a closed polyline for a static body; else its convex hull when that is within `tolerance` of
/// the curve, else the fan decomposition about the curve's frame origin, else VHACD.
fn body_shape(desc: &BodyDesc, tolerance: f64) -> (DVec2, SharedShape, ShapeStats) {
    let (spline, centroid) = recentre(&desc.spline);
    let polygon = polygon_within(&spline, tolerance);
    if desc.is_static {
        // Static walls: the closed polygon as a polyline (exact, no decomposition needed).
        let mut vertices: Vec<Vector> = polygon.vertices.iter().map(|&v| vector(v)).collect();
        vertices.push(vertices[0]);
        return (centroid, SharedShape::polyline(vertices, None), stats(&polygon, 1, false));
    }
    if let Some(hull) = convex_hull(&spline, &polygon).filter(|h| h.hausdorff <= tolerance)
        && let Some(shape) = SharedShape::convex_polyline(hull.vertices.iter().map(|&v| vector(v)).collect())
    {
        return (centroid, shape, stats(&hull, 1, false));
    }
    // The curve's frame origin, where generators centre their shapes: blobs are star-shaped
    // about it.
    if let Some(pieces) = fan_decomposition(&polygon.vertices, -centroid) {
        let parts: Vec<(Pose, SharedShape)> = pieces
            .iter()
            .filter_map(|p| SharedShape::convex_polyline(p.iter().map(|&v| vector(v)).collect()))
            .map(|shape| (Pose::IDENTITY, shape))
            .collect();
        let count = parts.len();
        return (centroid, SharedShape::compound(parts), stats(&polygon, count, false));
    }
    let vertices: Vec<Vector> = polygon.vertices.iter().map(|&v| vector(v)).collect();
    let n = vertices.len() as u32;
    let indices: Vec<[u32; 2]> = (0..n).map(|i| [i, (i + 1) % n]).collect();
    let shape = SharedShape::convex_decomposition(&vertices, &indices);
    let count = shape.as_compound().map_or(1, |c| c.shapes().len());
    (centroid, shape, stats(&polygon, count, true))
}

fn stats(polygon: &SplinePolygon, pieces: usize, vhacd: bool) -> ShapeStats {
    ShapeStats { vertices: polygon.vertices.len(), pieces, hausdorff: polygon.hausdorff, vhacd }
}
