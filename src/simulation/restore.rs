//! Restoring a simulation from a [`Snapshot`]: every field is checked first (a snapshot read
//! from a file may be corrupt), by the checks `add_body` and the settings already make where
//! they apply, each failure a typed error naming the field and the reason; then the bodies are
//! spawned with their own handles, their mass properties and trees rebuilt, and the step's
//! memory put back.

use std::fmt::Debug;
use std::sync::Arc;

use glam::DVec2;
use hecs::{Entity, EntityBuilder};

use super::snapshot::{BodyKind, BodySnapshot, PairMemory, SNAPSHOT_VERSION, Snapshot, StepMemory};
use super::{BodyDesc, Simulation};
use crate::components::{BodyName, Kinematic, Sensor, SpawnOrder, Static};
use crate::dynamics::mass::{MassProperties, mass_properties};
use crate::error::{BodyLabel, SnapshotError, check_range};
use crate::geometry::aobb_tree::AobbTree;
use crate::geometry::octagon::Octagon;
use crate::geometry::rugosity::Rugosity;

/// Largest slot index of a body's handle that a snapshot may hold: restoring a body allocates
/// hecs's entity table up to its slot (16 bytes a slot, so at most 64 MiB), and a corrupt index
/// near 2³² would exhaust memory.
pub const MAX_ENTITY_INDEX: u32 = (1 << 22) - 1;

impl Simulation {
    /// A simulation restored from `snapshot`, with its own rayon pool of
    /// `snapshot.settings.threads` workers (results are the same for any count). It continues
    /// bit-identically; the contact hook is not restored ([`Snapshot`]: what is saved and what
    /// is not).
    ///
    /// # Errors
    /// As [`Snapshot::validate`], or [`SnapshotError::Settings`] naming `threads` if the pool
    /// cannot be built.
    pub fn from_snapshot(snapshot: Snapshot) -> Result<Self, SnapshotError> {
        snapshot.validate()?;
        let pool = super::build_pool(snapshot.settings.threads).map_err(SnapshotError::Settings)?;
        Ok(Self::restore(snapshot, Arc::new(pool)))
    }

    /// As [`Simulation::from_snapshot`], running the parallel stages on a pool the caller owns.
    ///
    /// # Errors
    /// As [`Snapshot::validate`].
    pub fn from_snapshot_with_pool(snapshot: Snapshot, pool: Arc<rayon::ThreadPool>) -> Result<Self, SnapshotError> {
        snapshot.validate()?;
        Ok(Self::restore(snapshot, pool))
    }

    /// Builds the simulation of a checked snapshot.
    fn restore(snapshot: Snapshot, pool: Arc<rayon::ThreadPool>) -> Self {
        let mut sim = Self::with_pool(snapshot.settings, pool);
        for body in snapshot.bodies {
            sim.spawn_restored(body);
        }
        sim.excluded = snapshot.excluded_pairs;
        sim.rebuild_body_table();
        sim.time = snapshot.time;
        sim.accumulator = snapshot.accumulator;
        sim.next_spawn = snapshot.next_spawn;
        sim.touching = snapshot.touching_pairs;
        sim.stale = snapshot.needs_detection;
        let mut step = snapshot.step;
        if sim.stale {
            // The next step detects everything afresh: only the swept bounds (read by the sleep
            // stage before) and the interpolation states are kept.
            step = StepMemory {
                swept_bounds: step.swept_bounds,
                previous_states: step.previous_states,
                ..StepMemory::default()
            };
        }
        step.into_buffers(&mut sim.buffers);
        sim
    }

    /// Spawns a checked body with its own handle, as `add_body` builds a body.
    fn spawn_restored(&mut self, body: BodySnapshot) {
        let mut builder = EntityBuilder::new();
        let mass = match body.kind {
            BodyKind::Dynamic { .. } => mass_properties(&body.spline, body.material.density),
            BodyKind::Static | BodyKind::Kinematic => MassProperties::STATIC,
        };
        let tree = AobbTree::build(&body.spline, &body.rugosity, self.settings.min_band);
        let octagon = Octagon::of_body(&body.spline, &body.rugosity, self.settings.min_band);
        builder.add_bundle((body.spline, body.rugosity, tree, octagon, body.state, body.material, mass));
        builder.add_bundle((SpawnOrder(body.spawn_order), body.groups));
        match body.kind {
            BodyKind::Static => {
                builder.add(Static);
            }
            BodyKind::Kinematic => {
                builder.add_bundle((Static, Kinematic));
            }
            BodyKind::Dynamic { motion, sleep, applied } => {
                builder.add_bundle((sleep, motion, applied));
            }
        }
        if body.sensor {
            builder.add(Sensor);
        }
        if let Some(name) = body.name {
            builder.add(BodyName(name));
        }
        self.world.spawn_at(body.entity, builder.build());
    }
}

impl Snapshot {
    /// Checks every field as [`Simulation::from_snapshot`] does, without restoring: the
    /// version, the settings, the clock, every body (as [`Simulation::add_body`] checks a body,
    /// and its state, sleep and applied force), the handles (distinct) and spawn orders
    /// (increasing, below `next_spawn`), the excluded and touching pairs (of the snapshot's
    /// bodies), and the step's memory (body slots in range, pairs in order, finite numbers,
    /// unit normals, non-negative warm-start forces).
    ///
    /// # Errors
    /// [`SnapshotError::Settings`], [`SnapshotError::Body`] (the body's index in `bodies`), or
    /// [`SnapshotError::Field`] naming the field's path and the reason.
    pub fn validate(&self) -> Result<(), SnapshotError> {
        let version = self.version;
        require(version == SNAPSHOT_VERSION, || "version".into(), version, "this build reads version 1 only")?;
        self.settings.validate().map_err(SnapshotError::Settings)?;
        check_range("time", self.time, 0.0, f64::MAX).map_err(|e| SnapshotError::at("", e))?;
        let accumulator = self.accumulator;
        let stepped = (0.0..self.settings.time_step).contains(&accumulator);
        require(stepped, || "accumulator".into(), accumulator, "must lie in [0, settings.time_step)")?;
        for (i, body) in self.bodies.iter().enumerate() {
            self.check_body(i, body)?;
        }
        let handles = self.check_handles()?;
        check_pairs("excluded_pairs", &self.excluded_pairs, &handles, false)?;
        check_pairs("touching_pairs", &self.touching_pairs, &handles, true)?;
        let segments: Vec<usize> = self.bodies.iter().map(|b| b.spline.segment_count()).collect();
        check_step(&self.step, &segments, self.needs_detection)
    }

    /// One body: its state finite, then `add_body`'s checks, then its dynamic state.
    fn check_body(&self, i: usize, body: &BodySnapshot) -> Result<(), SnapshotError> {
        let state = &body.state;
        let fields = [
            ("position", state.position.is_finite()),
            ("angle", state.angle.is_finite()),
            ("linear_velocity", state.linear_velocity.is_finite()),
            ("angular_velocity", state.angular_velocity.is_finite()),
        ];
        for (name, finite) in fields {
            require(finite, || format!("bodies[{i}].state.{name}"), state, "must be finite")?;
        }
        let label = BodyLabel::new(i, body.name.as_deref());
        let desc = body.desc();
        desc.validate(&label).map_err(SnapshotError::Body)?;
        desc.check_band(self.settings.min_band, &label).map_err(SnapshotError::Body)?;
        // `constant` must be what the tolerances give (it replaces the interpolation).
        let rebuilt = Rugosity::new(body.rugosity.tolerances().to_vec()).ok();
        let constant = body.rugosity.constant_value();
        require(
            rebuilt.as_ref() == Some(&body.rugosity),
            || format!("bodies[{i}].rugosity.constant"),
            constant,
            "must be Some(R) exactly when every tolerance is R",
        )?;
        if let BodyKind::Dynamic { motion, sleep, applied } = &body.kind {
            let at = format!("bodies[{i}].kind.sleep.");
            check_range("still_for", sleep.still_for, 0.0, f64::MAX).map_err(|e| SnapshotError::at(&at, e))?;
            let pose = sleep.pose;
            require(pose.0.is_finite() && pose.1.is_finite(), || format!("{at}pose"), pose, "must be finite")?;
            let finite = applied.force.is_finite() && applied.torque.is_finite();
            require(finite, || format!("bodies[{i}].kind.applied"), applied, "must be finite")?;
            let mass = mass_properties(&body.spline, body.material.density);
            let inverse_inertia = crate::systems::inverse_inertia(&mass, motion);
            super::actions::check_acceleration(applied, mass.inverse_mass(), inverse_inertia)
                .map_err(|e| SnapshotError::at(&format!("bodies[{i}].kind.applied."), e))?;
        }
        Ok(())
    }

    /// Handles distinct (by slot index: two handles of one slot cannot both live) with slot
    /// indices up to [`MAX_ENTITY_INDEX`], spawn orders increasing and below `next_spawn`;
    /// returns the handles, sorted.
    fn check_handles(&self) -> Result<Vec<Entity>, SnapshotError> {
        let mut previous: Option<u64> = None;
        for (i, body) in self.bodies.iter().enumerate() {
            let entity = body.entity;
            let reason = format!("its slot index must be at most {MAX_ENTITY_INDEX}");
            require(entity.id() <= MAX_ENTITY_INDEX, || format!("bodies[{i}].entity"), entity, &reason)?;
            let order = body.spawn_order;
            let increasing = previous.is_none_or(|p| p < order) && order < self.next_spawn;
            let reason = "must increase along `bodies` and stay below `next_spawn`";
            require(increasing, || format!("bodies[{i}].spawn_order"), order, reason)?;
            previous = Some(order);
        }
        let mut handles: Vec<(u32, usize)> = self.bodies.iter().enumerate().map(|(i, b)| (b.entity.id(), i)).collect();
        handles.sort_unstable();
        for pair in handles.windows(2) {
            let ((id, _), (next, i)) = (pair[0], pair[1]);
            let entity = self.bodies[i].entity;
            require(id != next, || format!("bodies[{i}].entity"), entity, "its slot index is another body's")?;
        }
        let mut entities: Vec<Entity> = self.bodies.iter().map(|b| b.entity).collect();
        entities.sort_unstable();
        Ok(entities)
    }
}

impl BodySnapshot {
    /// The body as a [`BodyDesc`] (its frame at the centre of mass), for `add_body`'s checks.
    fn desc(&self) -> BodyDesc {
        let motion = match &self.kind {
            BodyKind::Dynamic { motion, .. } => *motion,
            BodyKind::Static | BodyKind::Kinematic => crate::components::Motion::default(),
        };
        BodyDesc {
            spline: self.spline.clone(),
            rugosity: self.rugosity.clone(),
            material: self.material,
            position: self.state.position,
            angle: self.state.angle,
            linear_velocity: self.state.linear_velocity,
            angular_velocity: self.state.angular_velocity,
            is_static: self.kind == BodyKind::Static,
            is_kinematic: self.kind == BodyKind::Kinematic,
            motion,
            groups: self.groups,
            sensor: self.sensor,
            name: self.name.clone(),
        }
    }
}

/// `Ok` if `ok`, else a [`SnapshotError::Field`] (the path is built only on failure).
fn require(ok: bool, field: impl FnOnce() -> String, value: impl Debug, reason: &str) -> Result<(), SnapshotError> {
    if ok { Ok(()) } else { Err(SnapshotError::field(field(), value, reason)) }
}

/// Pairs of bodies of the snapshot (`handles`, sorted), `(a, b)` with `a < b`, each once;
/// with `sorted`, in increasing order.
fn check_pairs(name: &str, pairs: &[(Entity, Entity)], handles: &[Entity], sorted: bool) -> Result<(), SnapshotError> {
    let known = |e: Entity| handles.binary_search(&e).is_ok();
    for (k, &(a, b)) in pairs.iter().enumerate() {
        let field = || format!("{name}[{k}]");
        require(known(a) && known(b), field, (a, b), "both must be bodies of the snapshot")?;
        require(a < b, field, (a, b), "must be ordered, a < b")?;
        if sorted {
            require(k == 0 || pairs[k - 1] < (a, b), field, (a, b), "must be sorted, each pair once")?;
        } else {
            require(!pairs[..k].contains(&(a, b)), field, (a, b), "must be listed once")?;
        }
    }
    Ok(())
}

/// The step's memory against the bodies (`segments`: each body's segment count, in slot order).
fn check_step(step: &StepMemory, segments: &[usize], needs_detection: bool) -> Result<(), SnapshotError> {
    for (k, bounds) in step.swept_bounds.iter().enumerate() {
        let (low, high) = *bounds;
        let ordered = low.is_finite() && high.is_finite() && low.cmple(high).all();
        require(ordered, || format!("step.swept_bounds[{k}]"), bounds, "must be finite, min <= max")?;
    }
    for (k, state) in step.previous_states.iter().enumerate() {
        require(state.is_finite(), || format!("step.previous_states[{k}]"), state, "must be finite")?;
    }
    if needs_detection {
        return Ok(()); // the rest is dropped
    }
    let n = segments.len();
    let one_per_body = format!("must hold one entry per body ({n})");
    require(step.margins.len() == n, || "step.margins".into(), step.margins.len(), &one_per_body)?;
    require(step.swept_bounds.len() == n, || "step.swept_bounds".into(), step.swept_bounds.len(), &one_per_body)?;
    let poses = step.phase_poses.len();
    require(poses == 0 || poses == n, || "step.phase_poses".into(), poses, "must be empty or hold one entry per body")?;
    for (k, &(position, angle)) in step.phase_poses.iter().enumerate() {
        let finite = position.is_finite() && angle.is_finite();
        require(finite, || format!("step.phase_poses[{k}]"), (position, angle), "must be finite")?;
    }
    for (k, &margin) in step.margins.iter().enumerate() {
        let sound = margin.is_finite() && margin >= 0.0;
        require(sound, || format!("step.margins[{k}]"), margin, "must be finite and >= 0")?;
    }
    let slots = |(a, b): (u32, u32)| a < b && (b as usize) < n;
    let candidates = &step.candidate_pairs;
    for (k, &pair) in candidates.iter().enumerate() {
        let ordered = slots(pair) && (k == 0 || candidates[k - 1] < pair);
        let reason = "must be body slots a < b, sorted, each pair once";
        require(ordered, || format!("step.candidate_pairs[{k}]"), pair, reason)?;
    }
    let remembered = candidates.len().max(step.detected_pairs);
    let reason = "must hold max(candidate_pairs, detected_pairs) pairs";
    require(step.pairs.len() == remembered, || "step.pairs".into(), step.pairs.len(), reason)?;
    for (k, pair) in step.pairs.iter().enumerate() {
        let at = format!("step.pairs[{k}].");
        let ordered = slots(pair.bodies) && (k == 0 || step.pairs[k - 1].bodies < pair.bodies);
        let live = candidates.get(k).is_none_or(|&c| c == pair.bodies);
        let reason = "must be body slots a < b, sorted, the live ones those of candidate_pairs";
        require(ordered && live, || format!("{at}bodies"), pair.bodies, reason)?;
        let counts = (segments[pair.bodies.0 as usize], segments[pair.bodies.1 as usize]);
        check_pair(&at, pair, counts)?;
    }
    for (k, cached) in step.contact_cache.iter().enumerate() {
        let field = || format!("step.contact_cache[{k}]");
        let ordered = slots(cached.key.bodies) && (k == 0 || step.contact_cache[k - 1].key <= cached.key);
        require(ordered, field, cached.key, "must be of body slots a < b, sorted by key")?;
        let sound = cached.normal_force.is_finite() && cached.normal_force >= 0.0 && cached.tangent_force.is_finite();
        require(sound, field, cached, "forces must be finite, the normal one >= 0")?;
    }
    Ok(())
}

/// One pair's contacts, intersections, gaps, leaf memory, recovery contact and hook values.
fn check_pair(at: &str, pair: &PairMemory, (na, nb): (usize, usize)) -> Result<(), SnapshotError> {
    let segments = |a: u32, b: u32| (a as usize) < na && (b as usize) < nb;
    let manifold = &pair.manifold;
    for (j, contact) in manifold.contacts.iter().enumerate() {
        let c = &contact.contact;
        let finite = [c.t, c.s, c.distance, c.penetration, c.lambda_a, c.lambda_b, c.raw_lambda_a, c.raw_lambda_b]
            .iter()
            .all(|v| v.is_finite())
            && [c.point_a, c.point_b, c.point].iter().all(|p| p.is_finite())
            && contact.u_a.is_finite()
            && contact.u_b.is_finite();
        let unit = (c.normal.length() - 1.0).abs() < 1e-9;
        let sound = finite && unit && segments(contact.segment_a, contact.segment_b);
        let reason = "must have segments of the bodies, finite numbers and a unit normal";
        require(sound, || format!("{at}manifold.contacts[{j}]"), contact, reason)?;
    }
    for (j, crossing) in manifold.intersections.iter().enumerate() {
        let sound =
            segments(crossing.segment_a, crossing.segment_b) && crossing.t.is_finite() && crossing.s.is_finite();
        let reason = "must have segments of the bodies and finite parameters";
        require(sound, || format!("{at}manifold.intersections[{j}]"), crossing, reason)?;
    }
    for (j, gap) in manifold.gaps.iter().enumerate() {
        let points = [gap.centre_a, gap.centre_b].into_iter().chain(gap.piece_a.bezier).chain(gap.piece_b.bezier);
        // A band that is NaN comes from an older snapshot: the pair's clearance is unknown and it
        // is queried again before it is carried.
        let sound = !gap.gap.is_nan()
            && [gap.radius_a, gap.radius_b, gap.approach].iter().all(|v| v.is_finite())
            && (gap.band.is_nan() || (gap.band.is_finite() && (0.0..=gap.band).contains(&gap.approach)))
            && points.into_iter().all(DVec2::is_finite);
        let reason = "must have a gap that is a number, an approach within a finite or unknown band and finite pieces";
        require(sound, || format!("{at}manifold.gaps[{j}]"), gap, reason)?;
    }
    for (j, leaf) in pair.leaves.iter().enumerate() {
        let key = (leaf.segment_a, leaf.segment_b);
        let ordered = j == 0 || (pair.leaves[j - 1].segment_a, pair.leaves[j - 1].segment_b) <= key;
        let sound = leaf.relative.position.is_finite()
            && leaf.relative.rotation.is_finite()
            && !leaf.lower_bound.is_nan()
            && leaf.seed.is_none_or(|[t, s]| t.is_finite() && s.is_finite());
        let reason = "must be sorted by segments, with finite numbers";
        require(ordered && sound, || format!("{at}leaves[{j}]"), leaf, reason)?;
    }
    if let Some(recovery) = &pair.recovery {
        let (la, lb) = recovery.raw_lambda;
        let sound = segments(recovery.segment_a, recovery.segment_b)
            && recovery.point.is_finite()
            && (recovery.normal.length() - 1.0).abs() < 1e-9
            && [recovery.depth, recovery.u_a, recovery.u_b].iter().all(|v| v.is_finite())
            && la.is_finite()
            && lb.is_finite()
            && la >= 0.0
            && lb >= 0.0;
        let reason = "must have segments of the bodies, finite numbers and a unit normal";
        require(sound, || format!("{at}recovery"), recovery, reason)?;
    }
    if let Some(solved_at) = &pair.solved_at {
        let reason = "must have finite poses and a margin >= 0";
        require(solved_at.is_sound(), || format!("{at}solved_at"), solved_at, reason)?;
    }
    require(pair.drift.is_sound(), || format!("{at}drift"), pair.drift, "must be finite and >= 0")?;
    let angle = pair.evaluated_angle_b;
    require(angle.is_none_or(f64::is_finite), || format!("{at}evaluated_angle_b"), angle, "must be finite")?;
    let reused_at = pair.reused_at;
    let sound = reused_at.is_none_or(|states| states.iter().all(|(p, angle)| p.is_finite() && angle.is_finite()));
    require(sound, || format!("{at}reused_at"), reused_at, "must be finite")?;
    let (friction, restitution) = pair.modified;
    let sound =
        friction.is_none_or(|mu| mu.is_finite() && mu >= 0.0) && restitution.is_none_or(|e| (0.0..=1.0).contains(&e));
    let reason = "friction must be finite and >= 0, restitution in [0, 1]";
    require(sound, || format!("{at}modified"), pair.modified, reason)
}
