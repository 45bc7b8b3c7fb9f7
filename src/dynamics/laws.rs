//! Friction from rugosity (MODEL §5) and the contact restitution of micro-collisions (MODEL §7).

use serde::{Deserialize, Serialize};

/// Parameters of the friction law `μ(λ) = μ_max (λ − λ_min)/λ` for `λ > λ_min`, else 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionLaw {
    /// Tolerance below which a surface is frictionless, `λ_min ≥ 0`.
    pub lambda_min: f64,
    /// Friction coefficient approached for very rough surfaces, `μ_max ≥ 0`.
    pub mu_max: f64,
}

impl Default for FrictionLaw {
    fn default() -> Self {
        Self { lambda_min: 0.0, mu_max: 1.0 }
    }
}

impl FrictionLaw {
    /// Friction coefficient of one surface with local tolerance `lambda`.
    #[must_use]
    pub fn coefficient(&self, lambda: f64) -> f64 {
        if lambda > self.lambda_min { self.mu_max * (lambda - self.lambda_min) / lambda } else { 0.0 }
    }
}

/// Friction coefficient of a contact: the max rule `μ = max(μ_A(λ_A), μ_B(λ_B))` (seed 4.2).
#[must_use]
pub fn contact_friction(law_a: &FrictionLaw, lambda_a: f64, law_b: &FrictionLaw, lambda_b: f64) -> f64 {
    law_a.coefficient(lambda_a).max(law_b.coefficient(lambda_b))
}

/// Contact restitution `e_c(δ) = e + (e_max − e)(δ/λ)²`, with `δ/λ` clamped to `[0, 1]`.
///
/// A zero tolerance `λ` gives `e_max` when `δ > 0` (fully inside a band of no width), else `e`.
#[must_use]
pub fn contact_restitution(restitution: f64, restitution_max: f64, penetration: f64, tolerance: f64) -> f64 {
    let depth = if tolerance > 0.0 {
        (penetration / tolerance).clamp(0.0, 1.0)
    } else if penetration > 0.0 {
        1.0
    } else {
        0.0
    };
    restitution + (restitution_max - restitution) * depth * depth
}

/// Normal approach speed given to a resting contact, `u_n = −√(2 g δ)` (MODEL §7).
#[must_use]
pub fn micro_collision_speed(gravity: f64, penetration: f64) -> f64 {
    -(2.0 * gravity.abs() * penetration.max(0.0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_is_zero_below_lambda_min_and_rises_to_mu_max() {
        let law = FrictionLaw { lambda_min: 0.01, mu_max: 0.8 };
        assert_eq!(law.coefficient(0.005), 0.0);
        assert_eq!(law.coefficient(0.01), 0.0);
        assert!((law.coefficient(0.02) - 0.4).abs() < 1e-15);
        assert!(law.coefficient(1e6) < 0.8 && law.coefficient(1e6) > 0.7999);
    }

    #[test]
    fn contact_uses_the_larger_coefficient() {
        let smooth = FrictionLaw { lambda_min: 1.0, mu_max: 1.0 };
        let rough = FrictionLaw::default();
        assert!((contact_friction(&smooth, 0.5, &rough, 0.5) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn restitution_rises_quadratically_to_e_max() {
        assert_eq!(contact_restitution(0.2, 0.6, 0.0, 0.1), 0.2);
        assert!((contact_restitution(0.2, 0.6, 0.05, 0.1) - 0.3).abs() < 1e-15);
        assert!((contact_restitution(0.2, 0.6, 0.1, 0.1) - 0.6).abs() < 1e-15);
        assert!((contact_restitution(0.2, 0.6, 0.5, 0.1) - 0.6).abs() < 1e-15);
    }

    #[test]
    fn micro_collision_speed_follows_free_fall() {
        assert!((micro_collision_speed(9.81, 0.002) + (2.0f64 * 9.81 * 0.002).sqrt()).abs() < 1e-15);
    }
}
