//! Micro-collisions of resting contacts (MODEL §7).

use super::*;

/// Settings of the micro-collision treatment of resting contacts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MicroCollisionSettings {
    /// A contact is *resting* when `|u_n| ≤ resting_speed` (m/s). Default 0.01 m/s, the speed
    /// of a 5 µm fall under 1 g: well below the approach speed of any visible bounce.
    pub resting_speed: f64,
    /// Restitution `e_max` reached at full penetration of the band, `δ = λ`. Default 0.5.
    pub restitution_max: f64,
}

impl Default for MicroCollisionSettings {
    fn default() -> Self {
        Self { resting_speed: 0.01, restitution_max: 0.5 }
    }
}

/// Where a resting contact sits in the rugosity band.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BandPenetration {
    /// Penetration into the band, `δ = λ_A + λ_B − d ≥ 0`.
    pub penetration: f64,
    /// Tolerance at the contact point, `λ = λ_A + λ_B`.
    pub tolerance: f64,
}

/// Micro-collision of a resting contact (MODEL §7), or `None` if the contact is not resting.
///
/// The approach speed is replaced by the free-fall speed from the penetration,
/// `u_n := −√(2 g δ)`, and the restitution by `e_c(δ) = e + (e_max − e)(δ/λ)²`. **(our
/// choice)** If the contact already approaches faster than that (still within
/// `resting_speed`), its own `u_n` is kept, so the impulse always stops the actual approach.
/// The tangential velocity is kept. `contact.restitution` is the base `e`; `gravity` is the
/// magnitude `g ≥ 0` (m/s²). With `δ = 0` a contact that is not approaching gets no impulse.
///
/// The outcome's velocities are the perturbed ones the law saw: the bodies' actual normal
/// velocity after the impulse is their `u_n` plus `normal_velocity_after −
/// normal_velocity_before`; likewise `energy_change` is that of the perturbed impact (a
/// micro-collision may add energy by design: it is what makes resting bodies hop).
///
/// # Errors
/// As [`resolve_impact`], plus [`ImpulseError::NonFinite`] / [`ImpulseError::OutOfRange`]
/// for bad `gravity`, band or settings.
pub fn resolve_micro_collision(
    law: ImpulseLaw,
    contact: &ImpactContact,
    band: BandPenetration,
    gravity: f64,
    settings: &MicroCollisionSettings,
) -> Result<Option<ImpulseOutcome>, ImpulseError> {
    validate_micro_collision(band, gravity, settings)?;
    let u_n = contact.velocity.dot(contact.normal);
    if !u_n.is_finite() {
        return Err(ImpulseError::NonFinite { field: "velocity" });
    }
    if u_n.abs() > settings.resting_speed {
        return Ok(None);
    }
    let perturbed_u_n = u_n.min(micro_collision_speed(gravity, band.penetration));
    let restitution =
        contact_restitution(contact.restitution, settings.restitution_max, band.penetration, band.tolerance);
    let micro = ImpactContact {
        velocity: contact.velocity + (perturbed_u_n - u_n) * contact.normal,
        restitution: restitution.clamp(0.0, 1.0),
        ..*contact
    };
    resolve_impact(law, &micro).map(Some)
}

fn validate_micro_collision(
    band: BandPenetration,
    gravity: f64,
    settings: &MicroCollisionSettings,
) -> Result<(), ImpulseError> {
    let values = [
        ("band.penetration", band.penetration),
        ("band.tolerance", band.tolerance),
        ("gravity", gravity),
        ("settings.resting_speed", settings.resting_speed),
        ("settings.restitution_max", settings.restitution_max),
    ];
    for (field, value) in values {
        if !value.is_finite() {
            return Err(ImpulseError::NonFinite { field });
        }
        if value < 0.0 {
            return Err(ImpulseError::OutOfRange { field, value, reason: "must be >= 0" });
        }
    }
    if settings.restitution_max > 1.0 {
        let value = settings.restitution_max;
        return Err(ImpulseError::OutOfRange { field: "settings.restitution_max", value, reason: "must be <= 1" });
    }
    Ok(())
}
