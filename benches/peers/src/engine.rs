//! One interface over the engines compared: build a scene, step it, read a body.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::DVec2;

use crate::box2d_world;
use crate::rapier_f32;
use crate::rapier_f64;
use crate::rugosa_world;
use crate::scenes::SceneSpec;
use crate::shapes::{ShapeChoice, ShapeStats};

/// A body's state as an engine reports it (its centre of mass, angle and velocities).
#[derive(Clone, Copy, Debug, Default)]
pub struct Reading {
    /// Centre of mass (m).
    pub position: DVec2,
    /// Angle (rad).
    pub angle: f64,
    /// Velocity of the centre of mass (m/s).
    pub velocity: DVec2,
}

/// A scene built in one engine.
pub trait Engine {
    /// One step of the length the scene was built with.
    fn step(&mut self);
    /// Body `index` (scene order).
    fn reading(&mut self, index: usize) -> Reading;
    /// Sets the velocity of a kinematic body (scene order).
    fn set_velocity(&mut self, index: usize, linear: DVec2, angular: f64);
    /// rugosa's profile since the last call (per stage and its counters); `None` for a peer.
    fn take_profile(&mut self) -> Option<rugosa::Profile> {
        None
    }
}

/// The engines compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Peer {
    /// This crate.
    Rugosa,
    /// rapier2d 0.36, f32.
    RapierF32,
    /// rapier2d-f64 0.36.
    RapierF64,
    /// Box2D v3 (the 3.2 snapshot pinned by boxdd 0.6), f32.
    Box2d,
}

impl Peer {
    /// Name in tables.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Rugosa => "rugosa",
            Self::RapierF32 => "rapier f32",
            Self::RapierF64 => "rapier f64",
            Self::Box2d => "Box2D v3",
        }
    }
}

/// An engine with the shapes it is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    /// The engine.
    pub peer: Peer,
    /// Its shapes (ignored by rugosa, which has the splines).
    pub shapes: ShapeChoice,
}

impl Variant {
    /// rugosa on its splines.
    pub const RUGOSA: Self = Self { peer: Peer::Rugosa, shapes: ShapeChoice::polygon(0.0) };

    /// Label: "rugosa", "Box2D v3, polygon 1e-4", "rapier f64, exact circle".
    #[must_use]
    pub fn label(self) -> String {
        match self.peer {
            Peer::Rugosa => "rugosa".to_owned(),
            peer => format!("{}, {}", peer.name(), self.shapes.label()),
        }
    }
}

/// How a run steps.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Step (s).
    pub dt: f64,
    /// Worker threads.
    pub threads: usize,
    /// Whether bodies may sleep.
    pub sleep: bool,
}

/// The scene in the variant's engine, with how each body's shape was built (scene order).
#[must_use]
pub fn build(variant: Variant, spec: &SceneSpec, setup: Setup) -> (Box<dyn Engine>, Vec<ShapeStats>) {
    let tolerance = variant.shapes.relative * spec.body_size;
    match variant.peer {
        Peer::Rugosa => (Box::new(rugosa_world::build(spec, setup)), Vec::new()),
        Peer::RapierF32 => {
            let (world, stats) = rapier_f32::build(spec, variant.shapes, tolerance, setup);
            (Box::new(world), stats)
        }
        Peer::RapierF64 => {
            let (world, stats) = rapier_f64::build(spec, variant.shapes, tolerance, setup);
            (Box::new(world), stats)
        }
        Peer::Box2d => {
            let (world, stats) = box2d_world::build(spec, variant.shapes, tolerance, setup);
            (Box::new(world), stats)
        }
    }
}

/// One step of `engine`, the scene's driven bodies first set to turn rigidly about the pivot
/// (velocity ω × (x − pivot) at their current centres).
pub fn advance(engine: &mut dyn Engine, spec: &SceneSpec) {
    if let Some(drive) = &spec.drive {
        for &index in &drive.bodies {
            let x = engine.reading(index).position;
            let r = x - drive.pivot;
            engine.set_velocity(index, drive.omega * r.perp(), drive.omega);
        }
    }
    engine.step();
    STEPS_TAKEN.fetch_add(1, Ordering::Relaxed);
}

/// Steps any engine has finished ([`advance`]): what the [`watchdog`] watches.
static STEPS_TAKEN: AtomicU64 = AtomicU64::new(0);

/// Ends the run with a message when no engine has finished a step for `limit`. rapier2d 0.36's
/// step can wait forever on two threads for the tree optimisation it handed to the pool
/// (`PhysicsPipeline::join_deferred_bvh_optimize`, dimforge/rapier#1008): seen once here, every
/// thread asleep ten minutes into a partial run. Without this, such a run would hold
/// `scripts/regenerate-docs.sh` forever; with it, the run fails and can be started again.
pub fn watchdog(limit: Duration) {
    std::thread::spawn(move || {
        let (mut seen, mut since) = (STEPS_TAKEN.load(Ordering::Relaxed), Instant::now());
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let now = STEPS_TAKEN.load(Ordering::Relaxed);
            if now != seen {
                (seen, since) = (now, Instant::now());
            } else if since.elapsed() >= limit {
                eprintln!(
                    "peers: no engine has finished a step for {} s (after {now} steps); rapier2d's step can hang on \
                     two threads (dimforge/rapier#1008): run it again",
                    limit.as_secs()
                );
                std::process::exit(3);
            }
        }
    });
}
