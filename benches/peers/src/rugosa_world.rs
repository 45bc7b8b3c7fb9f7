//! A scene in rugosa: the splines themselves.

use glam::DVec2;
use hecs::Entity;
use rugosa::{Simulation, SimulationSettings, SleepSettings};

use crate::engine::{Engine, Reading, Setup};
use crate::scenes::SceneSpec;

/// rugosa's simulation of a scene, with its entities in scene order.
pub struct RugosaWorld {
    /// The simulation.
    pub sim: Simulation,
    entities: Vec<Entity>,
    dt: f64,
}

/// The scene's settings with the run's step, threads and sleeping.
#[must_use]
pub fn settings(spec: &SceneSpec, setup: Setup) -> SimulationSettings {
    let sleep = if setup.sleep { SleepSettings::default() } else { SleepSettings::off() };
    SimulationSettings { threads: setup.threads, time_step: setup.dt, sleep, ..spec.settings.clone() }
}

/// Builds the scene.
///
/// # Panics
/// If a scene's body or setting is invalid (the scenes are the program's own).
#[must_use]
pub fn build(spec: &SceneSpec, setup: Setup) -> RugosaWorld {
    let mut sim = Simulation::new(settings(spec, setup)).expect("valid settings");
    let entities = spec.bodies.iter().map(|b| sim.add_body(b.clone()).expect("valid body")).collect();
    RugosaWorld { sim, entities, dt: setup.dt }
}

impl Engine for RugosaWorld {
    fn step(&mut self) {
        self.sim.step(self.dt);
    }

    fn reading(&mut self, index: usize) -> Reading {
        let s = self.sim.state(self.entities[index]).expect("the scene's body");
        Reading { position: s.position, angle: s.angle, velocity: s.linear_velocity }
    }

    fn set_velocity(&mut self, index: usize, linear: DVec2, angular: f64) {
        self.sim.set_velocity(self.entities[index], linear, angular).expect("a kinematic body");
    }

    fn take_profile(&mut self) -> Option<rugosa::Profile> {
        Some(self.sim.take_profile())
    }
}
