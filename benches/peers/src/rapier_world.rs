//! A scene in rapier2d, written once for both precisions: `rapier_f32.rs` and `rapier_f64.rs`
//! include this file with `rapier` naming `rapier2d` or `rapier2d_f64`. glam 0.34 `DVec2` is
//! converted to rapier's `Vector` here and nowhere else.
// One source for both precisions: a cast to `Real` or `f64::from` is a no-op in the f64 build.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use glam::DVec2;
use rapier::math::Real;
use rapier::prelude::*;

use super::rapier;
use crate::engine::{Engine, Reading, Setup};
use crate::scenes::SceneSpec;
use crate::shapes::{Geometry, Limits, ShapeChoice, ShapeStats, peer_shape};

/// rapier's world of a scene, with the handles of its bodies in scene order and the rayon pool
/// its `parallel` feature steps in.
pub struct RapierWorld {
    world: PhysicsWorld,
    handles: Vec<RigidBodyHandle>,
    pool: rayon::ThreadPool,
}

fn vector(v: DVec2) -> Vector {
    Vector::new(v.x as Real, v.y as Real)
}

/// Builds the scene with every curve given as `choice` asks, polygons within `tolerance` (m).
///
/// # Panics
/// If the rayon pool cannot be built.
#[must_use]
pub fn build(spec: &SceneSpec, choice: ShapeChoice, tolerance: f64, setup: Setup) -> (RapierWorld, Vec<ShapeStats>) {
    let mut world = PhysicsWorld::new();
    world.gravity = vector(spec.settings.gravity);
    world.integration_parameters.dt = setup.dt as Real;
    let mut handles = Vec::with_capacity(spec.bodies.len());
    let mut stats = Vec::with_capacity(spec.bodies.len());
    for (desc, natural) in spec.bodies.iter().zip(&spec.natural) {
        let shape = peer_shape(desc, *natural, choice, tolerance, Limits::NONE);
        let (collider_shape, pieces) = shared_shape(&shape.geometry);
        let builder = if desc.is_static {
            RigidBodyBuilder::fixed()
        } else if desc.is_kinematic {
            RigidBodyBuilder::kinematic_velocity_based()
        } else {
            RigidBodyBuilder::dynamic()
        };
        let centre = desc.position + DVec2::from_angle(desc.angle).rotate(shape.centroid);
        let body = builder
            .translation(vector(centre))
            .rotation(desc.angle as Real)
            .linvel(vector(desc.linear_velocity))
            .angvel(desc.angular_velocity as Real)
            .can_sleep(setup.sleep);
        let collider = ColliderBuilder::new(collider_shape)
            .density(desc.material.density as Real)
            .friction(spec.friction_of(desc) as Real)
            .friction_combine_rule(CoefficientCombineRule::Max)
            .restitution(desc.material.restitution as Real)
            .restitution_combine_rule(CoefficientCombineRule::Max);
        let (handle, _) = world.insert(body, collider);
        handles.push(handle);
        stats.push(ShapeStats { pieces: pieces.max(shape.stats.pieces), ..shape.stats });
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(setup.threads).build().expect("rayon pool");
    (RapierWorld { world, handles, pool }, stats)
}

/// The collider shape, and its number of convex pieces when parry decomposed it.
fn shared_shape(geometry: &Geometry) -> (SharedShape, usize) {
    let points = |vertices: &[DVec2]| vertices.iter().map(|&v| vector(v)).collect::<Vec<_>>();
    match geometry {
        Geometry::Circle(radius) => (SharedShape::ball(*radius as Real), 1),
        Geometry::RoundedBox { inner, radius } => {
            (SharedShape::round_cuboid(inner.x as Real, inner.y as Real, *radius as Real), 1)
        }
        Geometry::Loop(vertices) => {
            let mut closed = points(vertices);
            closed.push(closed[0]);
            (SharedShape::polyline(closed, None), 1)
        }
        Geometry::Pieces(pieces) if pieces.len() == 1 => {
            (SharedShape::convex_polyline(points(&pieces[0])).expect("a convex piece"), 1)
        }
        Geometry::Pieces(pieces) => {
            let parts: Vec<(Pose, SharedShape)> = pieces
                .iter()
                .map(|p| (Pose::IDENTITY, SharedShape::convex_polyline(points(p)).expect("a convex piece")))
                .collect();
            (SharedShape::compound(parts), 0)
        }
        Geometry::Decompose(vertices) => {
            let n = vertices.len() as u32;
            let indices: Vec<[u32; 2]> = (0..n).map(|i| [i, (i + 1) % n]).collect();
            let shape = SharedShape::convex_decomposition(&points(vertices), &indices);
            let count = shape.as_compound().map_or(1, |c| c.shapes().len());
            (shape, count)
        }
    }
}

impl Engine for RapierWorld {
    fn step(&mut self) {
        let world = &mut self.world;
        self.pool.install(|| world.step());
    }

    fn reading(&mut self, index: usize) -> Reading {
        let body = &self.world.bodies[self.handles[index]];
        let (t, v) = (body.translation(), body.linvel());
        Reading {
            position: DVec2::new(f64::from(t.x), f64::from(t.y)),
            angle: f64::from(body.rotation().angle()),
            velocity: DVec2::new(f64::from(v.x), f64::from(v.y)),
        }
    }

    fn set_velocity(&mut self, index: usize, linear: DVec2, angular: f64) {
        let body = &mut self.world.bodies[self.handles[index]];
        body.set_linvel(vector(linear), true);
        body.set_angvel(angular as Real, true);
    }
}
