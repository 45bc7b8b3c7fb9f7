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

/// Restitution of a contact between two materials: the larger of the two (our choice, as the
/// max rule of friction).
#[must_use]
pub fn combine_restitution(restitution_a: f64, restitution_b: f64) -> f64 {
    restitution_a.max(restitution_b)
}

/// Push-out speed of a contact deeper in its band than its rest depth (MODEL §7a, our choice).
///
/// The seed's micro-collision speed for the excess depth `x`, scaled by the contact
/// restitution `e_c(δ)` at the contact's depth δ: `e_c(δ) √(2 g x)` — a deeper penetration
/// pushes back harder, as the seed says. It is at least `β x / h` (so a scene without gravity
/// still comes apart) and at most `x / h` (one sub-step never pushes past the rest depth). It
/// drives pseudo-velocities only (split impulse), so it never becomes kinetic energy.
#[must_use]
pub fn push_out_speed(contact_restitution: f64, excess: f64, gravity: f64, beta: f64, h: f64) -> f64 {
    if excess.is_nan() || excess <= 0.0 || h <= 0.0 {
        return 0.0;
    }
    let seed = contact_restitution * (2.0 * gravity.abs() * excess).sqrt();
    seed.max(beta * excess / h).min(excess / h)
}

/// The excess depth `x` a contact still has to be pushed out of (MODEL §7a, our choice): all
/// of it, unless the contact collided in this sub-step (`collided` holds its normal velocity
/// `u_n` since) and now separates at `u_n > 0`, which carries it `u_n h` out of the band over
/// the sub-step by itself; then `x − u_n h`. A body that
/// bounces from deep in its band (conservative advancement lets impacts come `approach_depth`
/// into it, deeper than the rest depth) is not pushed as well: split impulses move positions
/// without kinetic energy, but lifting a body gives it potential energy, and a disc bouncing
/// with `e = 1` gained 4e-4 of its drop's energy in ten bounces (docs/stability.md).
#[must_use]
pub fn excess_left(excess: f64, collided: Option<f64>, h: f64) -> f64 {
    match collided {
        Some(separating) if separating > 0.0 => excess - separating * h,
        _ => excess,
    }
}

/// The push-out's target for a contact's relative pseudo-velocity along its normal (MODEL §7a,
/// our choice): [`push_out_speed`] of what [`excess_left`] leaves, except where a contact that
/// collided separates by more than its excess over the sub-step. Its target is then negative,
/// `(x⁺ − u_n h) / h` (`x⁺` the excess, or zero for a contact above the rest depth): the split
/// solve leaves it alone unless other contacts would close it by more than its separation
/// carries it past the rest depth (or past its depth now, if that is shallower). So a body that
/// bounces off one being pushed out below it is not lifted with it, as a target of zero would
/// (the pair would keep its relative pseudo-velocity at least zero, and the bounce would gain the
/// lift's potential energy). The target is continuous in `u_n`: zero at `u_n = 0`, as for a
/// contact that did not collide. `u_n` is the solved velocity's, as in [`excess_left`], where
/// the integrator moves a touched body at the mean of its velocity after the collisions and the
/// solved one: a separation that speeds up over the solve lets the contact end a little deeper
/// than this allows (by at most the change of `u_n` times `h / 2`), which the next sub-step
/// carries out.
#[must_use]
pub fn push_out_target(
    contact_restitution: f64,
    excess: f64,
    collided: Option<f64>,
    gravity: f64,
    beta: f64,
    h: f64,
) -> f64 {
    let left = excess_left(excess, collided, h);
    match collided {
        // `left < 0` is false for a NaN excess, which pushes nothing.
        Some(separating) if separating > 0.0 && left < 0.0 && h > 0.0 => (excess.max(0.0) - separating * h) / h,
        _ => push_out_speed(contact_restitution, left, gravity, beta, h),
    }
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
    fn push_out_follows_the_seed_law_between_its_bounds() {
        let h = 1.0 / 120.0;
        // e_c √(2 g x) for x = 1 mm: 0.5 · 0.14 = 0.070 m/s, between β x / h = 0.024 and x / h = 0.12.
        let v = push_out_speed(0.5, 1e-3, 9.81, 0.2, h);
        assert!((v - 0.5 * (2.0f64 * 9.81 * 1e-3).sqrt()).abs() < 1e-15);
        assert_eq!(push_out_speed(0.5, 0.0, 9.81, 0.2, h), 0.0);
        assert!((push_out_speed(0.0, 1e-3, 9.81, 0.2, h) - 0.2 * 1e-3 / h).abs() < 1e-15);
        assert!((push_out_speed(1.0, 1e-6, 9.81, 0.2, h) - 1e-6 / h).abs() < 1e-18, "never past the rest depth");
        assert!(push_out_speed(1.0, 1e-3, 0.0, 0.2, h) > 0.0, "comes apart without gravity");
    }

    #[test]
    fn a_bounce_is_pushed_out_only_by_what_its_separation_leaves() {
        let h = 1e-3;
        assert_eq!(excess_left(2e-3, None, h), 2e-3, "a contact that did not collide keeps its excess");
        assert_eq!(excess_left(2e-3, Some(-1.0), h), 2e-3, "an approaching contact keeps its excess");
        assert!((excess_left(2e-3, Some(1.0), h) - 1e-3).abs() < 1e-18);
        assert_eq!(push_out_speed(1.0, excess_left(2e-3, Some(3.0), h), 9.81, 0.2, h), 0.0, "it leaves by itself");
    }

    #[test]
    fn a_bounce_that_leaves_the_band_by_itself_may_be_closed_by_what_it_leaves() {
        let (h, g, beta) = (1e-3, 9.81, 0.2);
        // 2 mm deep, separating at 3 m/s: 1 mm beyond the excess over the sub-step.
        let target = push_out_target(1.0, 2e-3, Some(3.0), g, beta, h);
        assert!((target + 1.0).abs() < 1e-12, "{target}");
        // Separating slower than its excess needs: pushed by what is left, as before.
        assert_eq!(push_out_target(1.0, 2e-3, Some(1.0), g, beta, h), push_out_speed(1.0, 1e-3, g, beta, h));
        // A contact that did not collide, or approaches, keeps a target of zero at most depth.
        assert_eq!(push_out_target(1.0, -1e-3, None, g, beta, h), 0.0);
        assert_eq!(push_out_target(1.0, -1e-3, Some(-1.0), g, beta, h), 0.0);
        // Above the rest depth and separating: closed by at most its own separation, so the
        // target goes to zero with the separation (no jump at u_n = 0).
        assert!((push_out_target(1.0, -1e-3, Some(0.5), g, beta, h) + 0.5).abs() < 1e-12);
        assert!((push_out_target(1.0, -1e-3, Some(1e-12), g, beta, h) + 1e-12).abs() < 1e-24);
        assert_eq!(push_out_target(1.0, -1e-3, Some(0.0), g, beta, h), 0.0);
        assert_eq!(push_out_target(1.0, f64::NAN, Some(3.0), g, beta, h), 0.0, "NaN pushes nothing");
    }

    #[test]
    fn micro_collision_speed_follows_free_fall() {
        assert!((micro_collision_speed(9.81, 0.002) + (2.0f64 * 9.81 * 0.002).sqrt()).abs() < 1e-15);
    }
}
