//! A scene in Box2D v3 (boxdd 0.6, f32), at its default length unit (1 m) and 4 sub-steps (its
//! samples' default).
//!
//! Box2D keeps polygons coarse on purpose: its hull welds vertices closer than 4 linear slops
//! (2 cm), merges a vertex within 2 slops (1 cm) of its neighbours' line, and takes at most 8
//! vertices per polygon; chain segments must be longer than a slop (5 mm). A polygon is thinned
//! to those limits first (its bound recomputed and reported), then cut into pieces Box2D keeps
//! whole ([`crate::shapes::Limits`]). Static bodies are closed chains (one-sided, outward).

use boxdd::prelude::*;
use glam::DVec2;

use crate::engine::{Engine, Reading, Setup};
use crate::scenes::SceneSpec;
use crate::shapes::{Geometry, Limits, ShapeChoice, ShapeStats, peer_shape};

/// Box2D's linear slop at the default length unit (m): `B2_LINEAR_SLOP`.
const LINEAR_SLOP: f64 = 0.005;
/// Sub-steps per step (Box2D's samples and benchmarks use 4).
pub const SUB_STEPS: i32 = 4;

/// Box2D's limits on a polygon, with 1 % to spare.
pub const LIMITS: Limits = Limits {
    min_edge: 4.04 * LINEAR_SLOP,
    min_loop_edge: 1.01 * LINEAR_SLOP,
    max_vertices: MAX_POLYGON_VERTICES,
    min_bulge: 2.02 * LINEAR_SLOP,
};

/// Box2D's world of a scene, with its bodies in scene order.
pub struct Box2dWorld {
    world: World,
    bodies: Vec<BodyId>,
    dt: f32,
}

fn vec2(v: DVec2) -> Vec2 {
    Vec2::new(v.x as f32, v.y as f32)
}

/// Builds the scene with every curve given as `choice` asks, polygons within `tolerance` (m) or
/// Box2D's own limits, whichever is coarser.
///
/// # Panics
/// If Box2D refuses a body or shape (the shapes are cut to its limits first).
#[must_use]
pub fn build(spec: &SceneSpec, choice: ShapeChoice, tolerance: f64, setup: Setup) -> (Box2dWorld, Vec<ShapeStats>) {
    let foundation = Foundation::initialize_default().expect("Box2D foundation");
    let workers = WorkerCount::new(setup.threads as u32).expect("a worker count");
    let def = WorldBuilder::from(foundation.world_def())
        .gravity(vec2(spec.settings.gravity))
        .enable_sleep(setup.sleep)
        .worker_count(workers)
        .build()
        .expect("a world definition");
    let mut world = foundation.create_world(def).expect("a world");
    // rugosa and the rapier runs take the larger friction of two bodies; Box2D's default is the
    // geometric mean. Restitution is the larger in all three.
    world
        .set_friction_callback(MixerId::from_bytes(*b"rugosa-peers-friction-max-rule.."), |a, b| {
            a.coefficient.max(b.coefficient)
        })
        .expect("a friction rule");
    let mut bodies = Vec::with_capacity(spec.bodies.len());
    let mut stats = Vec::with_capacity(spec.bodies.len());
    for (desc, natural) in spec.bodies.iter().zip(&spec.natural) {
        let shape = peer_shape(desc, *natural, choice, tolerance, LIMITS);
        let kind = if desc.is_static {
            BodyType::Static
        } else if desc.is_kinematic {
            BodyType::Kinematic
        } else {
            BodyType::Dynamic
        };
        let centre = desc.position + DVec2::from_angle(desc.angle).rotate(shape.centroid);
        let body_def = BodyBuilder::from(foundation.body_def())
            .body_type(kind)
            .position(Position::new(centre.x as WorldScalar, centre.y as WorldScalar))
            .angle(desc.angle as f32)
            .linear_velocity(vec2(desc.linear_velocity))
            .angular_velocity(desc.angular_velocity as f32)
            .enable_sleep(setup.sleep)
            .build()
            .expect("a body definition");
        let id = world.create_body(body_def).expect("a body");
        let material = SurfaceMaterial::new()
            .with_friction(spec.friction_of(desc) as f32)
            .and_then(|m| m.with_restitution(desc.material.restitution as f32))
            .expect("a material");
        let shape_def = ShapeDef::builder()
            .density(desc.material.density as f32)
            .material(material)
            .build()
            .expect("a shape definition");
        let mut body = world.body(id).expect("the body");
        let count = match &shape.geometry {
            Geometry::Circle(radius) => {
                let circle = shapes::circle(Vec2::new(0.0, 0.0), *radius as f32).expect("a circle");
                body.create_circle(&shape_def, &circle).expect("a circle shape");
                1
            }
            Geometry::RoundedBox { inner, radius } => {
                let polygon =
                    shapes::rounded_box_polygon(inner.x as f32, inner.y as f32, *radius as f32).expect("a rounded box");
                body.create_polygon(&shape_def, &polygon).expect("a rounded box shape");
                1
            }
            Geometry::Pieces(pieces) => {
                for piece in pieces {
                    let polygon = shapes::polygon_from_points(piece.iter().map(|&v| vec2(v)), 0.0)
                        .unwrap_or_else(|e| panic!("{}: a piece of {} vertices: {e}", spec.name, piece.len()));
                    assert_eq!(polygon.count(), piece.len(), "{}: Box2D merged vertices of a piece", spec.name);
                    body.create_polygon(&shape_def, &polygon).expect("a polygon shape");
                }
                pieces.len()
            }
            Geometry::Loop(vertices) => {
                let chain = ChainDef::builder()
                    .points(vertices.iter().map(|&v| vec2(v)))
                    .is_loop(true)
                    .single_material(&material)
                    .build()
                    .expect("a chain definition");
                body.create_chain(&chain).expect("a chain");
                1
            }
            Geometry::Decompose(_) => {
                panic!("{}: a body that is not star-shaped has no Box2D decomposition here", spec.name)
            }
        };
        bodies.push(id);
        stats.push(ShapeStats { pieces: count, ..shape.stats });
    }
    (Box2dWorld { world, bodies, dt: setup.dt as f32 }, stats)
}

impl Engine for Box2dWorld {
    fn step(&mut self) {
        let completed = self.world.step(self.dt, SUB_STEPS).expect("a Box2D step");
        drop(completed);
    }

    fn reading(&mut self, index: usize) -> Reading {
        let body = self.world.body(self.bodies[index]).expect("the body");
        let p = body.world_center_of_mass().expect("a centre");
        let v = body.linear_velocity().expect("a velocity");
        Reading {
            position: DVec2::new(f64::from(p.x), f64::from(p.y)),
            angle: f64::from(body.rotation().expect("a rotation").angle()),
            velocity: DVec2::new(f64::from(v.x), f64::from(v.y)),
        }
    }

    fn set_velocity(&mut self, index: usize, linear: DVec2, angular: f64) {
        let mut body = self.world.body(self.bodies[index]).expect("the body");
        body.set_linear_velocity(vec2(linear)).expect("a velocity");
        body.set_angular_velocity(angular as f32).expect("an angular velocity");
    }
}
