//! Acting on bodies between steps, as in Box2D and rapier: forces and torques accumulated over
//! the next step, impulses and velocities applied at once, and the motion settings (gravity
//! scale, damping, fixed rotation). Every action checks that the entity is a body of this
//! simulation, that it is dynamic, and that its arguments are finite; it wakes the body (and
//! the island it sleeps in). A refused action changes nothing.

use glam::DVec2;
use hecs::Entity;

use super::Simulation;
use crate::components::{AppliedForce, CollisionGroups, Motion, RigidState, Sleep};
use crate::error::{BodyActionError, BodyLabel, SettingsError};
use crate::systems;

impl Simulation {
    /// Adds `force` (N) acting at the world point `point` over the next step: a force on the
    /// centre of mass and the torque `(point − c) × force`.
    ///
    /// # Errors
    /// [`BodyActionError`]: not a body of this simulation, a static body, or a non-finite
    /// argument.
    pub fn apply_force(&mut self, entity: Entity, force: DVec2, point: DVec2) -> Result<(), BodyActionError> {
        const ACTION: &str = "apply_force";
        let slot = self.dynamic_slot(ACTION, entity)?;
        self.check_finite(
            ACTION,
            slot,
            &[("force", force.x), ("force", force.y), ("point", point.x), ("point", point.y)],
        )?;
        let centre = self.state(entity).map_or(point, |s| s.position);
        self.accumulate(ACTION, slot, force, (point - centre).perp_dot(force))
    }

    /// Adds `force` (N) on the centre of mass over the next step.
    ///
    /// # Errors
    /// As [`Simulation::apply_force`].
    pub fn apply_force_to_centre(&mut self, entity: Entity, force: DVec2) -> Result<(), BodyActionError> {
        const ACTION: &str = "apply_force_to_centre";
        let slot = self.dynamic_slot(ACTION, entity)?;
        self.check_finite(ACTION, slot, &[("force", force.x), ("force", force.y)])?;
        self.accumulate(ACTION, slot, force, 0.0)
    }

    /// Adds `torque` (N·m, counter-clockwise positive) over the next step.
    ///
    /// # Errors
    /// As [`Simulation::apply_force`].
    pub fn apply_torque(&mut self, entity: Entity, torque: f64) -> Result<(), BodyActionError> {
        const ACTION: &str = "apply_torque";
        let slot = self.dynamic_slot(ACTION, entity)?;
        self.check_finite(ACTION, slot, &[("torque", torque)])?;
        self.accumulate(ACTION, slot, DVec2::ZERO, torque)
    }

    /// Applies `impulse` (N·s) at the world point `point` at once:
    /// `v += J / m`, `ω += ((point − c) × J) / I`.
    ///
    /// # Errors
    /// As [`Simulation::apply_force`].
    pub fn apply_impulse(&mut self, entity: Entity, impulse: DVec2, point: DVec2) -> Result<(), BodyActionError> {
        const ACTION: &str = "apply_impulse";
        let slot = self.dynamic_slot(ACTION, entity)?;
        let values = [("impulse", impulse.x), ("impulse", impulse.y), ("point", point.x), ("point", point.y)];
        self.check_finite(ACTION, slot, &values)?;
        let (inverse_mass, inverse_inertia) = (self.bodies[slot].inverse_mass, self.bodies[slot].inverse_inertia);
        let Some(state) = self.state(entity) else { return Err(BodyActionError::NotABody { action: ACTION, entity }) };
        let linear = state.linear_velocity + impulse * inverse_mass;
        let angular = state.angular_velocity + (point - state.position).perp_dot(impulse) * inverse_inertia;
        self.check_domain(ACTION, slot, state.position, linear, angular)?;
        self.change_state(slot, |state| {
            state.linear_velocity = linear;
            state.angular_velocity = angular;
        });
        Ok(())
    }

    /// Sets a body's velocities at once (the angular one must be 0 for a body with fixed
    /// rotation); a kinematic body moves at them from the next step on.
    ///
    /// # Errors
    /// As [`Simulation::apply_force`], and an angular velocity given to a body with fixed
    /// rotation.
    pub fn set_velocity(&mut self, entity: Entity, linear: DVec2, angular: f64) -> Result<(), BodyActionError> {
        const ACTION: &str = "set_velocity";
        let slot = self.body_slot(ACTION, entity)?;
        if self.bodies[slot].is_static && !self.bodies[slot].kinematic {
            return Err(BodyActionError::Static { action: ACTION, body: self.label(slot) });
        }
        self.check_finite(ACTION, slot, &[("linear", linear.x), ("linear", linear.y), ("angular", angular)])?;
        if self.bodies[slot].motion.fixed_rotation && angular != 0.0 {
            let source = SettingsError::new("angular", angular, "must be 0 for a body with fixed rotation");
            return Err(BodyActionError::Argument { action: ACTION, body: self.label(slot), source: Box::new(source) });
        }
        let position = self.state(entity).map_or(DVec2::ZERO, |s| s.position);
        self.check_domain(ACTION, slot, position, linear, angular)?;
        self.change_state(slot, |state| {
            state.linear_velocity = linear;
            state.angular_velocity = angular;
        });
        Ok(())
    }

    /// Drives a kinematic body to a pose over the next step of `settings.time_step` (rapier's
    /// `set_next_kinematic_position`): its velocities become the displacement over that step
    /// (the angle is taken as given, not wrapped), and it moves on at them until told otherwise.
    ///
    /// # Errors
    /// [`BodyActionError::NotABody`]; [`BodyActionError::Static`] for a body that is not
    /// kinematic; [`BodyActionError::Argument`] for a non-finite pose or one that needs a speed
    /// beyond the domain.
    pub fn set_kinematic_target(&mut self, entity: Entity, position: DVec2, angle: f64) -> Result<(), BodyActionError> {
        const ACTION: &str = "set_kinematic_target";
        let slot = self.body_slot(ACTION, entity)?;
        if !self.bodies[slot].kinematic {
            return Err(BodyActionError::Static { action: ACTION, body: self.label(slot) });
        }
        self.check_finite(ACTION, slot, &[("position", position.x), ("position", position.y), ("angle", angle)])?;
        let Some(state) = self.state(entity) else { return Err(BodyActionError::NotABody { action: ACTION, entity }) };
        let h = self.settings.time_step;
        let (linear, angular) = ((position - state.position) / h, (angle - state.angle) / h);
        self.check_domain(ACTION, slot, position, linear, angular)?;
        self.change_state(slot, |state| {
            state.linear_velocity = linear;
            state.angular_velocity = angular;
        });
        Ok(())
    }

    /// Changes a body's gravity scale, damping and fixed rotation (fixing the rotation stops
    /// the body turning).
    ///
    /// # Errors
    /// As [`Simulation::apply_force`], and a [`Motion`] field outside its domain.
    pub fn set_motion(&mut self, entity: Entity, motion: Motion) -> Result<(), BodyActionError> {
        const ACTION: &str = "set_motion";
        let slot = self.dynamic_slot(ACTION, entity)?;
        motion.validate().map_err(|e| BodyActionError::Argument {
            action: ACTION,
            body: self.label(slot),
            source: Box::new(e),
        })?;
        if let Ok(mut current) = self.world.get::<&mut Motion>(entity) {
            *current = motion;
        }
        if motion.fixed_rotation {
            self.change_state(slot, |state| state.angular_velocity = 0.0);
        }
        let inverse_inertia = self
            .world
            .get::<&crate::dynamics::mass::MassProperties>(entity)
            .map_or(0.0, |mass| systems::inverse_inertia(&mass, &motion));
        let record = &mut self.bodies[slot];
        record.motion = motion;
        record.inverse_inertia = inverse_inertia;
        self.wake_slot(slot);
        Ok(())
    }

    /// Changes which bodies a body collides with (static bodies included); contacts are redone
    /// before the next step.
    ///
    /// # Errors
    /// [`BodyActionError::NotABody`].
    pub fn set_collision_groups(&mut self, entity: Entity, groups: CollisionGroups) -> Result<(), BodyActionError> {
        let slot = self.body_slot("set_collision_groups", entity)?;
        if let Ok(mut current) = self.world.get::<&mut CollisionGroups>(entity) {
            *current = groups;
        }
        self.bodies[slot].groups = groups;
        self.wake_slot(slot);
        self.stale = true;
        Ok(())
    }

    /// Keeps two bodies from ever colliding (Box2D's joint `collideConnected = false`, rapier's
    /// pair filter): the pair is never tested, so they pass through each other.
    ///
    /// # Errors
    /// [`BodyActionError::NotABody`] for either, or [`BodyActionError::Argument`] if they are
    /// the same body.
    pub fn exclude_pair(&mut self, a: Entity, b: Entity) -> Result<(), BodyActionError> {
        const ACTION: &str = "exclude_pair";
        let (slot_a, slot_b) = (self.body_slot(ACTION, a)?, self.body_slot(ACTION, b)?);
        if slot_a == slot_b {
            let source = Box::new(SettingsError::new("b", format!("{b:?}"), "must differ from a"));
            return Err(BodyActionError::Argument { action: ACTION, body: self.label(slot_a), source });
        }
        let pair = (a.min(b), a.max(b));
        if !self.excluded.contains(&pair) {
            self.excluded.push(pair);
            self.map_excluded_pairs();
        }
        self.wake_slot(slot_a);
        self.wake_slot(slot_b);
        Ok(())
    }

    /// Lets two bodies collide again after [`Simulation::exclude_pair`]; contacts are redone
    /// before the next step. Nothing happens for a pair that was not excluded.
    ///
    /// # Errors
    /// [`BodyActionError::NotABody`] for either.
    pub fn include_pair(&mut self, a: Entity, b: Entity) -> Result<(), BodyActionError> {
        const ACTION: &str = "include_pair";
        let (slot_a, slot_b) = (self.body_slot(ACTION, a)?, self.body_slot(ACTION, b)?);
        let pair = (a.min(b), a.max(b));
        if let Some(k) = self.excluded.iter().position(|&p| p == pair) {
            self.excluded.swap_remove(k);
            self.map_excluded_pairs();
            self.wake_slot(slot_a);
            self.wake_slot(slot_b);
            self.stale = true;
        }
        Ok(())
    }

    /// The body's slot if it is a body (static or dynamic) of this simulation.
    pub(super) fn body_slot(&self, action: &'static str, entity: Entity) -> Result<usize, BodyActionError> {
        self.bodies.iter().position(|b| b.entity == entity).ok_or(BodyActionError::NotABody { action, entity })
    }

    /// The body's slot if it is a dynamic body of this simulation.
    fn dynamic_slot(&self, action: &'static str, entity: Entity) -> Result<usize, BodyActionError> {
        let slot = self.body_slot(action, entity)?;
        if self.bodies[slot].kinematic {
            return Err(BodyActionError::Kinematic { action, body: self.label(slot) });
        }
        if self.bodies[slot].is_static {
            return Err(BodyActionError::Static { action, body: self.label(slot) });
        }
        Ok(slot)
    }

    fn check_domain(
        &self,
        action: &'static str,
        slot: usize,
        position: DVec2,
        linear: DVec2,
        angular: f64,
    ) -> Result<(), BodyActionError> {
        super::body_desc::check_state_domain(position, linear, angular).map_err(|e| BodyActionError::Argument {
            action,
            body: self.label(slot),
            source: Box::new(e),
        })
    }

    pub(super) fn check_finite(
        &self,
        action: &'static str,
        slot: usize,
        values: &[(&str, f64)],
    ) -> Result<(), BodyActionError> {
        match values.iter().find(|(_, v)| !v.is_finite()) {
            None => Ok(()),
            Some(&(name, value)) => Err(BodyActionError::Argument {
                action,
                body: self.label(slot),
                source: Box::new(SettingsError::new(name, value, "must be finite")),
            }),
        }
    }

    /// The label of the body in `slot` for errors: its spawn index and name.
    pub(super) fn label(&self, slot: usize) -> BodyLabel {
        let entity = self.bodies[slot].entity;
        let name = self.world.get::<&crate::components::BodyName>(entity).ok().map(|n| n.0.clone());
        let index = self.world.get::<&crate::components::SpawnOrder>(entity).ok().map(|o| o.0 as usize);
        BodyLabel { index, name }
    }

    /// Adds to the body's applied force and torque, refusing a total whose acceleration would
    /// exceed [`MAX_ACCELERATION`](super::settings::MAX_ACCELERATION).
    fn accumulate(
        &mut self,
        action: &'static str,
        slot: usize,
        force: DVec2,
        torque: f64,
    ) -> Result<(), BodyActionError> {
        let body = &self.bodies[slot];
        let current = self.world.get::<&AppliedForce>(body.entity).map(|a| *a).unwrap_or_default();
        let total = AppliedForce { force: current.force + force, torque: current.torque + torque };
        if let Err(source) = check_acceleration(&total, body.inverse_mass, body.inverse_inertia) {
            return Err(BodyActionError::Argument { action, body: self.label(slot), source: Box::new(source) });
        }
        let (total, turning) = (total.force, total.torque);
        if let Ok(mut applied) = self.world.get::<&mut AppliedForce>(self.bodies[slot].entity) {
            applied.force = total;
            applied.torque = turning;
        }
        self.wake_slot(slot);
        Ok(())
    }

    /// Changes the state of the body in `slot` and wakes it; the step that follows sees the
    /// new velocities.
    fn change_state(&mut self, slot: usize, change: impl FnOnce(&mut RigidState)) {
        self.wake_slot(slot);
        if let Ok(mut state) = self.world.get::<&mut RigidState>(self.bodies[slot].entity) {
            change(&mut state);
        }
    }

    /// Wakes the island the body in `slot` sleeps in, if it sleeps. Every action on a body's
    /// motion passes here: the next step is not a quiet start (its sub-step is bounded before
    /// its solve as well as after, model §7).
    fn wake_slot(&mut self, slot: usize) {
        self.buffers.quiet = false;
        let tag = self.world.get::<&Sleep>(self.bodies[slot].entity).ok().and_then(|s| s.island);
        if let Some(tag) = tag {
            let woken = systems::sleep::wake_island(&mut self.world, &self.bodies, tag);
            self.profile.counters.woken_bodies += woken as u64;
            self.stale = true;
        }
    }
}

/// Checks that an applied force and torque accelerate a body of these inverse mass and inertia
/// by at most [`MAX_ACCELERATION`](super::settings::MAX_ACCELERATION).
///
/// # Errors
/// A [`SettingsError`] naming `force`.
pub(super) fn check_acceleration(
    applied: &AppliedForce,
    inverse_mass: f64,
    inverse_inertia: f64,
) -> Result<(), SettingsError> {
    let limit = super::settings::MAX_ACCELERATION;
    if (applied.force * inverse_mass).length() > limit || (applied.torque * inverse_inertia).abs() > limit {
        let reason = format!("would accelerate the body beyond {limit:e} m/s² or rad/s²");
        return Err(SettingsError::new("force", applied.force, reason));
    }
    Ok(())
}
