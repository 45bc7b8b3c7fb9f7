//! Collision impulses at one contact point (MODEL §6) and micro-collisions (MODEL §7).
//!
//! Conventions: `u = (v_A + ω_A × r_A) − (v_B + ω_B × r_B)` is the relative velocity of the
//! contact point, `n` the unit outward normal of B (from B towards A), `t = n.perp()` the
//! tangent (`n` turned +90°). An impulse `j` acts on A and `−j` on B, and changes the contact
//! velocity by `Δu = K j` ([`collision_matrix`]). `u_n = u·n < 0` means approaching.
//!
//! Two laws are offered ([`ImpulseLaw`]). `Seed` is the paper's algebraic law, kept for
//! comparison; it gains kinetic energy in a small fraction of frictional impacts.
//! `EnergySafe` (the default) integrates the impact over the normal impulse with Stronge's
//! energetic restitution, and never gains energy.

use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::dynamics::laws::{contact_restitution, micro_collision_speed};
use crate::dynamics::mass::MassProperties;

// The energy-safe law's integration and the micro-collisions live beside this file.
mod energy_safe;
mod micro;

use energy_safe::*;
pub use micro::{BandPenetration, MicroCollisionSettings, resolve_micro_collision};

/// Inverse mass properties of two bodies and the contact point's lever arms.
///
/// A static body has `inverse_mass = inverse_inertia = 0`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactMassInput {
    /// `1/m_A`, 0 for a static body.
    pub inverse_mass_a: f64,
    /// `1/I_A` about A's centre of mass, 0 for a static body.
    pub inverse_inertia_a: f64,
    /// Contact point relative to A's centre of mass, world axes.
    pub r_a: DVec2,
    /// `1/m_B`, 0 for a static body.
    pub inverse_mass_b: f64,
    /// `1/I_B` about B's centre of mass, 0 for a static body.
    pub inverse_inertia_b: f64,
    /// Contact point relative to B's centre of mass, world axes.
    pub r_b: DVec2,
}

impl ContactMassInput {
    /// Builds the input from two bodies' mass properties and lever arms.
    #[must_use]
    pub fn new(a: &MassProperties, r_a: DVec2, b: &MassProperties, r_b: DVec2) -> Self {
        Self {
            inverse_mass_a: a.inverse_mass(),
            inverse_inertia_a: a.inverse_inertia(),
            r_a,
            inverse_mass_b: b.inverse_mass(),
            inverse_inertia_b: b.inverse_inertia(),
            r_b,
        }
    }
}

/// Linear and angular velocity of one body.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyVelocity {
    /// Velocity of the centre of mass.
    pub linear: DVec2,
    /// Angular velocity, counter-clockwise positive.
    pub angular: f64,
}

impl BodyVelocity {
    /// At rest.
    pub const ZERO: Self = Self { linear: DVec2::ZERO, angular: 0.0 };

    /// Velocity of the material point at `r` from the centre of mass: `v + ω × r`.
    #[must_use]
    pub fn point_velocity(self, r: DVec2) -> DVec2 {
        self.linear + self.angular * r.perp()
    }

    /// Kinetic energy `½ m |v|² + ½ I ω²` from inverse mass and inertia.
    ///
    /// A zero inverse (static body) contributes nothing: static bodies exchange no energy.
    #[must_use]
    pub fn kinetic_energy(self, inverse_mass: f64, inverse_inertia: f64) -> f64 {
        let linear = if inverse_mass > 0.0 { self.linear.length_squared() / inverse_mass } else { 0.0 };
        let angular = if inverse_inertia > 0.0 { self.angular * self.angular / inverse_inertia } else { 0.0 };
        0.5 * (linear + angular)
    }
}

/// Collision matrix `K` with `Δu = K j` (MODEL §6); symmetric positive semi-definite.
#[must_use]
pub fn collision_matrix(input: &ContactMassInput) -> DMat2 {
    let arm = |inverse_inertia: f64, r: DVec2| {
        // (1/I) [[r_y², −r_x r_y], [−r_x r_y, r_x²]] = (1/I) r⊥ r⊥ᵀ with r⊥ = (−r_y, r_x).
        let p = r.perp();
        DMat2::from_cols(p * p.x, p * p.y) * inverse_inertia
    };
    DMat2::from_diagonal(DVec2::splat(input.inverse_mass_a + input.inverse_mass_b))
        + arm(input.inverse_inertia_a, input.r_a)
        + arm(input.inverse_inertia_b, input.r_b)
}

/// Relative velocity of the contact point, `u = (v_A + ω_A × r_A) − (v_B + ω_B × r_B)`.
#[must_use]
pub fn relative_velocity(input: &ContactMassInput, a: BodyVelocity, b: BodyVelocity) -> DVec2 {
    a.point_velocity(input.r_a) - b.point_velocity(input.r_b)
}

/// Applies `impulse` to A and its opposite to B; returns the new velocities `(A, B)`.
#[must_use]
pub fn apply_impulse(
    input: &ContactMassInput,
    a: BodyVelocity,
    b: BodyVelocity,
    impulse: DVec2,
) -> (BodyVelocity, BodyVelocity) {
    let a = BodyVelocity {
        linear: a.linear + impulse * input.inverse_mass_a,
        angular: a.angular + input.r_a.perp_dot(impulse) * input.inverse_inertia_a,
    };
    let b = BodyVelocity {
        linear: b.linear - impulse * input.inverse_mass_b,
        angular: b.angular - input.r_b.perp_dot(impulse) * input.inverse_inertia_b,
    };
    (a, b)
}

/// Kinetic energy of both bodies (static bodies contribute nothing).
#[must_use]
pub fn kinetic_energy(input: &ContactMassInput, a: BodyVelocity, b: BodyVelocity) -> f64 {
    a.kinetic_energy(input.inverse_mass_a, input.inverse_inertia_a)
        + b.kinetic_energy(input.inverse_mass_b, input.inverse_inertia_b)
}

/// Tangent of the contact frame: the normal turned +90°, `t = (−n_y, n_x)`.
#[must_use]
pub fn contact_tangent(normal: DVec2) -> DVec2 {
    normal.perp()
}

/// Which impact law computes the impulse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ImpulseLaw {
    /// The seed paper's law as written: Newton restitution `u_n' = −e u_n`, sticking if the
    /// sticking impulse lies in the friction cone, else sliding along `−u_t`. Can gain energy.
    Seed,
    /// Stronge's energetic restitution integrated over the normal impulse, with slide, stick
    /// and reverse-slip phases. Never gains kinetic energy; equals Newton's law when `μ = 0`.
    #[default]
    EnergySafe,
}

/// One impact: collision matrix, normal, relative velocity, restitution and friction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactContact {
    /// Collision matrix `K` of the contact ([`collision_matrix`]).
    pub matrix: DMat2,
    /// Unit outward normal of B at the contact, pointing towards A.
    pub normal: DVec2,
    /// Relative contact velocity `u` before the impact ([`relative_velocity`]).
    pub velocity: DVec2,
    /// Coefficient of restitution `e ∈ [0, 1]` (Newton's for `Seed`, energetic for `EnergySafe`).
    pub restitution: f64,
    /// Friction coefficient `μ ≥ 0`.
    pub friction: f64,
}

impl ImpactContact {
    /// Builds the impact from the bodies' mass input and velocities.
    #[must_use]
    pub fn new(
        input: &ContactMassInput,
        a: BodyVelocity,
        b: BodyVelocity,
        normal: DVec2,
        restitution: f64,
        friction: f64,
    ) -> Self {
        Self {
            matrix: collision_matrix(input),
            normal,
            velocity: relative_velocity(input, a, b),
            restitution,
            friction,
        }
    }
}

/// How the contact behaved during the impact.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ImpulseKind {
    /// `u_n ≥ 0`: not approaching, no impulse.
    Separating,
    /// `μ = 0`: the impulse is along the normal.
    Frictionless,
    /// The contact ends the impact with zero tangential velocity.
    Sticking,
    /// The contact ends the impact sliding (friction on the cone's edge).
    Sliding,
}

/// Result of an impact law.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpulseOutcome {
    /// Impulse on A (B receives its opposite).
    pub impulse: DVec2,
    /// Sticking, sliding, frictionless or separating.
    pub kind: ImpulseKind,
    /// `u_n` before the impact.
    pub normal_velocity_before: f64,
    /// `u_n` after the impact, from `u + K j`.
    pub normal_velocity_after: f64,
    /// `u_t = u·t` before the impact ([`contact_tangent`]).
    pub tangential_velocity_before: f64,
    /// `u_t` after the impact.
    pub tangential_velocity_after: f64,
    /// Whether the slip stopped and restarted the other way during the impact (`EnergySafe`).
    pub slip_reversed: bool,
    /// Change of the two bodies' kinetic energy, `u·j + ½ jᵀ K j`; `≤ 0` for `EnergySafe`.
    pub energy_change: f64,
}

/// Why an impulse could not be computed. No law ever returns NaN: bad input is one of these.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ImpulseError {
    /// An input is NaN or infinite.
    #[error("impact input `{field}` is not finite")]
    NonFinite {
        /// Which input.
        field: &'static str,
    },
    /// An input is finite but outside its domain.
    #[error("impact input `{field}` = {value}: {reason}")]
    OutOfRange {
        /// Which input.
        field: &'static str,
        /// The refused value.
        value: f64,
        /// Why it is refused.
        reason: &'static str,
    },
    /// No finite impulse can stop the approach (both bodies immovable along the normal).
    #[error("no finite impulse stops the approach: normal stiffness nᵀ K n = {normal_stiffness:e}")]
    Unresolvable {
        /// `nᵀ K n`, or the normal rate of the phase that cannot end.
        normal_stiffness: f64,
    },
    /// Seed law only: the sliding impulse would need a pulling normal impulse (Painlevé).
    #[error("seed law: nᵀ K (n − μ t̂) = {denominator:e} ≤ 0, sliding needs a pulling normal impulse")]
    Jam {
        /// The seed's denominator `nᵀ K (n − μ t̂)`.
        denominator: f64,
    },
}

/// Tolerance on `|n|` being 1: a narrow phase that normalizes is exact to ~1e-16.
const UNIT_NORMAL_TOLERANCE: f64 = 1e-9;

/// Relative rounding allowed on the energy check before `EnergySafe` falls back.
const ENERGY_ROUNDING: f64 = 1e-12;

/// Computes the impulse of one impact with the chosen law.
///
/// Returns a zero impulse of kind [`ImpulseKind::Separating`] when `u_n ≥ 0`.
///
/// # Errors
/// [`ImpulseError::NonFinite`] for NaN or infinite input, [`ImpulseError::OutOfRange`] for
/// `e ∉ [0, 1]`, `μ < 0`, a normal that is not unit or a `K` that is not positive
/// semi-definite, [`ImpulseError::NonFinite`] also if the result overflows,
/// [`ImpulseError::Unresolvable`] when `nᵀ K n = 0` (no impulse moves the
/// contact along the normal), and for the seed law [`ImpulseError::Jam`].
pub fn resolve_impact(law: ImpulseLaw, contact: &ImpactContact) -> Result<ImpulseOutcome, ImpulseError> {
    let frame = ContactFrame::new(contact)?;
    if frame.u_n >= 0.0 {
        return Ok(frame.outcome(DVec2::ZERO, ImpulseKind::Separating, false));
    }
    let outcome = match law {
        ImpulseLaw::Seed => seed_impulse(&frame)?,
        ImpulseLaw::EnergySafe => energy_safe_impulse(&frame),
    };
    // Finite inputs near f64::MAX can still overflow; report that rather than return NaN.
    if !(outcome.impulse.is_finite() && outcome.energy_change.is_finite()) {
        return Err(ImpulseError::NonFinite { field: "impulse (overflow)" });
    }
    Ok(outcome)
}

/// The impact in the contact frame `(t, n)`, validated.
#[derive(Clone, Copy, Debug)]
struct ContactFrame {
    matrix: DMat2,
    normal: DVec2,
    tangent: DVec2,
    velocity: DVec2,
    k_tt: f64,
    k_tn: f64,
    k_nn: f64,
    u_t: f64,
    u_n: f64,
    restitution: f64,
    friction: f64,
}

impl ContactFrame {
    fn new(contact: &ImpactContact) -> Result<Self, ImpulseError> {
        validate(contact)?;
        let (normal, matrix) = (contact.normal, contact.matrix);
        let tangent = contact_tangent(normal);
        let k_nn = normal.dot(matrix * normal);
        if k_nn <= 0.0 {
            return Err(ImpulseError::Unresolvable { normal_stiffness: k_nn });
        }
        Ok(Self {
            matrix,
            normal,
            tangent,
            velocity: contact.velocity,
            k_tt: tangent.dot(matrix * tangent),
            // K is symmetric, so tᵀ K n = nᵀ K t; average to absorb input asymmetry rounding.
            k_tn: 0.5 * (tangent.dot(matrix * normal) + normal.dot(matrix * tangent)),
            k_nn,
            u_t: contact.velocity.dot(tangent),
            u_n: contact.velocity.dot(normal),
            restitution: contact.restitution,
            friction: contact.friction,
        })
    }

    /// Sticking is stable when the friction cone holds the impulse that keeps `u_t = 0`.
    fn stick_is_stable(&self) -> bool {
        self.k_tn.abs() <= self.friction * self.k_tt
    }

    /// Direction (±1) slip takes when starting from rest and sticking is unstable.
    fn slip_direction_from_rest(&self) -> f64 {
        // With u_t = 0 and p_t = −μ s p, u_t grows as (K_tn − μ s K_tt) p; this is consistent
        // (s u_t > 0) only for s = sign(K_tn) when |K_tn| > μ K_tt.
        if self.k_tn > 0.0 {
            1.0
        } else if self.k_tn < 0.0 {
            -1.0
        } else {
            0.0
        }
    }

    fn impulse(&self, normal_impulse: f64, tangential_impulse: f64) -> DVec2 {
        self.normal * normal_impulse + self.tangent * tangential_impulse
    }

    fn energy_change(&self, impulse: DVec2) -> f64 {
        self.velocity.dot(impulse) + 0.5 * impulse.dot(self.matrix * impulse)
    }

    fn outcome(&self, impulse: DVec2, kind: ImpulseKind, slip_reversed: bool) -> ImpulseOutcome {
        let after = self.velocity + self.matrix * impulse;
        let kind =
            if kind != ImpulseKind::Separating && self.friction == 0.0 { ImpulseKind::Frictionless } else { kind };
        ImpulseOutcome {
            impulse,
            kind,
            normal_velocity_before: self.u_n,
            normal_velocity_after: after.dot(self.normal),
            tangential_velocity_before: self.u_t,
            tangential_velocity_after: after.dot(self.tangent),
            slip_reversed,
            energy_change: self.energy_change(impulse),
        }
    }
}

fn validate(contact: &ImpactContact) -> Result<(), ImpulseError> {
    let finite = |field, ok: bool| if ok { Ok(()) } else { Err(ImpulseError::NonFinite { field }) };
    finite("matrix", contact.matrix.is_finite())?;
    finite("normal", contact.normal.is_finite())?;
    finite("velocity", contact.velocity.is_finite())?;
    finite("restitution", contact.restitution.is_finite())?;
    finite("friction", contact.friction.is_finite())?;
    let out = |field, value, reason| Err(ImpulseError::OutOfRange { field, value, reason });
    if !(0.0..=1.0).contains(&contact.restitution) {
        return out("restitution", contact.restitution, "must lie in [0, 1]");
    }
    if contact.friction < 0.0 {
        return out("friction", contact.friction, "must be >= 0");
    }
    let length = contact.normal.length();
    if (length - 1.0).abs() > UNIT_NORMAL_TOLERANCE {
        return out("normal", length, "length must be 1");
    }
    let m = contact.matrix;
    // Relative 1e-12: [`collision_matrix`] is symmetric and PSD up to a few roundings.
    let scale = m.x_axis.x.abs() + m.y_axis.y.abs();
    let asymmetric = (m.x_axis.y - m.y_axis.x).abs() > 1e-12 * scale;
    if asymmetric || m.x_axis.x < 0.0 || m.y_axis.y < 0.0 || m.determinant() < -1e-12 * scale * scale {
        return out("matrix", m.determinant(), "must be symmetric positive semi-definite");
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Seed law (MODEL §6), as written.
// ---------------------------------------------------------------------------------------

/// The seed's law: try sticking `j = −K⁻¹(u + e u_n n)`, accept iff `|j·t| ≤ μ j·n`, else
/// slide with `j = j_n (n − μ t̂)`, `j_n = −(1+e) u_n / nᵀK(n − μ t̂)`.
///
/// Where the seed is silent: a singular `K` skips the sticking trial; with `u_t = 0` and
/// unstable sticking, `t̂` is the direction slip starts in, `sign(K_tn) t` (as `EnergySafe`).
fn seed_impulse(frame: &ContactFrame) -> Result<ImpulseOutcome, ImpulseError> {
    if let Some(impulse) = seed_sticking_impulse(frame) {
        return Ok(frame.outcome(impulse, ImpulseKind::Sticking, false));
    }
    let slip = if frame.u_t > 0.0 {
        1.0
    } else if frame.u_t < 0.0 {
        -1.0
    } else {
        frame.slip_direction_from_rest()
    };
    let denominator = frame.k_nn - frame.friction * slip * frame.k_tn;
    if denominator <= 0.0 {
        return Err(ImpulseError::Jam { denominator });
    }
    let normal_impulse = -(1.0 + frame.restitution) * frame.u_n / denominator;
    let impulse = frame.impulse(normal_impulse, -frame.friction * slip * normal_impulse);
    Ok(frame.outcome(impulse, ImpulseKind::Sliding, false))
}

fn seed_sticking_impulse(frame: &ContactFrame) -> Option<DVec2> {
    let det = frame.matrix.determinant();
    // Below this K⁻¹ amplifies rounding by more than ~1e12; treat K as singular.
    if det <= 1e-12 * frame.k_tt * frame.k_nn {
        return None;
    }
    let target = frame.velocity + frame.restitution * frame.u_n * frame.normal;
    let impulse = -(frame.matrix.inverse() * target);
    let (j_t, j_n) = (impulse.dot(frame.tangent), impulse.dot(frame.normal));
    (j_t.abs() <= frame.friction * j_n).then_some(impulse)
}
