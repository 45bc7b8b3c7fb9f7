//! The energy-safe law: Stronge's energetic restitution, integrated over the normal impulse.
//!
//! State along the impact: normal impulse p, tangential impulse p_t, contact velocity
//! u_t = u_t0 + K_tt p_t + K_tn p, u_n = u_n0 + K_tn p_t + K_nn p, normal work W = ∫ u_n dp.
//! In each phase dp_t/dp is constant, so u_t, u_n are linear in p and W quadratic:
//!
//!   slide (s = sign u_t):  dp_t/dp = −μ s,        du_t/dp = K_tn − μ s K_tt,  du_n/dp = K_nn − μ s K_tn
//!   stick (u_t = 0):       dp_t/dp = −K_tn/K_tt,  du_t/dp = 0,                du_n/dp = det K / K_tt
//!
//! Compression runs until u_n = 0 (work W_c < 0), restitution until the normal work done
//! since then is −e² W_c. Slip that stops turns into sticking when |K_tn| ≤ μ K_tt, else into
//! slip the other way, s' = sign(K_tn) = −s; neither of those can stop again, so there are at
//! most two phases plus the compression/restitution switch.
//!
//! Energy proof. For any impulse path ΔKE = ∫ u·dj (KE is ½ jᵀKj + u_0·j + KE_0 and its
//! gradient is u). Split: ∫ u_n dp = W_c + W_r = (1 − e²) W_c ≤ 0; ∫ u_t dp_t is −μ|u_t| dp ≤ 0
//! while sliding (friction opposes the slip) and 0 while sticking. So ΔKE ≤ 0 in every phase.
//!
//! Termination (K positive definite). A slide phase with du_n/dp ≤ 0 has μ s K_tn ≥ K_nn > 0,
//! and then K_tn² < K_tt K_nn ≤ μ s K_tn K_tt gives s du_t/dp = s K_tn − μ K_tt < 0: slip
//! decelerates and stops. Every later phase has du_n/dp > 0, so compression ends.

use super::*;

/// A phase of the impact: sliding in direction `s = ±1` along `t`, or sticking.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Slide(f64),
    Stick,
}

/// Rates of a phase per unit normal impulse.
#[derive(Clone, Copy, Debug)]
struct Rates {
    tangential_impulse: f64,
    tangential_velocity: f64,
    normal_velocity: f64,
}

/// Where the integration stands.
#[derive(Clone, Copy, Debug)]
struct ImpactState {
    normal_impulse: f64,
    tangential_impulse: f64,
    u_t: f64,
    u_n: f64,
    normal_work: f64,
}

impl ImpactState {
    fn advance(self, rates: Rates, dp: f64) -> Self {
        Self {
            normal_impulse: self.normal_impulse + dp,
            tangential_impulse: self.tangential_impulse + rates.tangential_impulse * dp,
            u_t: self.u_t + rates.tangential_velocity * dp,
            u_n: self.u_n + rates.normal_velocity * dp,
            normal_work: self.normal_work + self.u_n * dp + 0.5 * rates.normal_velocity * dp * dp,
        }
    }
}

fn phase_rates(frame: &ContactFrame, phase: Phase) -> Rates {
    match phase {
        Phase::Slide(s) => Rates {
            tangential_impulse: -frame.friction * s,
            tangential_velocity: frame.k_tn - frame.friction * s * frame.k_tt,
            normal_velocity: frame.k_nn - frame.friction * s * frame.k_tn,
        },
        Phase::Stick => {
            // K_tt = 0 forces K_tn = 0 (K is PSD): tangential impulse changes nothing, use none.
            let ratio = if frame.k_tt > 0.0 { -frame.k_tn / frame.k_tt } else { 0.0 };
            Rates {
                tangential_impulse: ratio,
                tangential_velocity: 0.0,
                // det K / K_tt ≥ 0; clamp the rounding of a near-singular K.
                normal_velocity: (frame.k_nn + frame.k_tn * ratio).max(0.0),
            }
        }
    }
}

fn initial_phase(frame: &ContactFrame) -> Phase {
    if frame.u_t > 0.0 {
        Phase::Slide(1.0)
    } else if frame.u_t < 0.0 {
        Phase::Slide(-1.0)
    } else {
        phase_after_slip_stops(frame)
    }
}

fn phase_after_slip_stops(frame: &ContactFrame) -> Phase {
    if frame.stick_is_stable() { Phase::Stick } else { Phase::Slide(frame.slip_direction_from_rest()) }
}

/// Normal impulse until the slip stops, or `∞` if the phase does not stop it.
fn impulse_to_slip_stop(state: &ImpactState, phase: Phase, rates: Rates) -> f64 {
    match phase {
        Phase::Slide(s) if s * rates.tangential_velocity < 0.0 => (-state.u_t / rates.tangential_velocity).max(0.0),
        _ => f64::INFINITY,
    }
}

/// Normal impulse until `u_n = 0`, or `∞` if `u_n` does not rise in this phase.
fn impulse_to_compression_end(state: &ImpactState, rates: Rates) -> f64 {
    if rates.normal_velocity > 0.0 { (-state.u_n / rates.normal_velocity).max(0.0) } else { f64::INFINITY }
}

/// Normal impulse until the normal work grows by `work ≥ 0` (`u_n ≥ 0`), or where `u_n`
/// returns to 0 if it falls first. Solves `u_n dp + ½ a dp² = work` without cancellation.
fn impulse_to_restitution_end(state: &ImpactState, rates: Rates, work: f64) -> f64 {
    let (u_n, a) = (state.u_n.max(0.0), rates.normal_velocity);
    let discriminant = u_n * u_n + 2.0 * a * work;
    if discriminant < 0.0 {
        // u_n peaks and falls back to 0 before the work is done: stop there (less restitution,
        // more dissipation, still energy-safe). Unreachable for positive definite K.
        return -u_n / a;
    }
    let denominator = u_n + discriminant.sqrt();
    if denominator > 0.0 { 2.0 * work / denominator } else { f64::INFINITY }
}

/// At most the initial phase, one slip stop and the switch to restitution.
const MAX_PHASE_CHANGES: usize = 4;

/// Integrates compression: returns the state at `u_n = 0`, the phase and whether slip reversed.
fn integrate_compression(frame: &ContactFrame) -> Result<(ImpactState, Phase, bool), ImpulseError> {
    let mut state =
        ImpactState { normal_impulse: 0.0, tangential_impulse: 0.0, u_t: frame.u_t, u_n: frame.u_n, normal_work: 0.0 };
    let mut phase = initial_phase(frame);
    let mut reversed = false;
    for _ in 0..MAX_PHASE_CHANGES {
        let rates = phase_rates(frame, phase);
        let to_stop = impulse_to_slip_stop(&state, phase, rates);
        let to_end = impulse_to_compression_end(&state, rates);
        if to_end <= to_stop {
            if !to_end.is_finite() {
                break;
            }
            let end = ImpactState { u_n: 0.0, ..state.advance(rates, to_end) };
            return Ok((end, phase, reversed));
        }
        (state, phase, reversed) = stop_slip(frame, state.advance(rates, to_stop), phase, reversed);
    }
    Err(ImpulseError::Unresolvable { normal_stiffness: phase_rates(frame, phase).normal_velocity })
}

/// Pins `u_t` at 0 where slip stops, picks the next phase and records a reversal.
fn stop_slip(frame: &ContactFrame, state: ImpactState, phase: Phase, reversed: bool) -> (ImpactState, Phase, bool) {
    let next = phase_after_slip_stops(frame);
    let reverses = matches!((phase, next), (Phase::Slide(s), Phase::Slide(r)) if s != r);
    (ImpactState { u_t: 0.0, ..state }, next, reversed || reverses)
}

/// Integrates restitution from the end of compression until its normal work reaches `target`.
fn integrate_restitution(frame: &ContactFrame, start: RestitutionStart) -> (ImpactState, Phase, bool) {
    let RestitutionStart { mut state, mut phase, mut reversed, target } = start;
    for _ in 0..MAX_PHASE_CHANGES {
        let remaining = target - state.normal_work;
        if remaining <= 0.0 {
            break;
        }
        let rates = phase_rates(frame, phase);
        let to_stop = impulse_to_slip_stop(&state, phase, rates);
        let to_end = impulse_to_restitution_end(&state, rates, remaining);
        if to_end <= to_stop {
            if to_end.is_finite() {
                state = state.advance(rates, to_end);
            }
            break;
        }
        (state, phase, reversed) = stop_slip(frame, state.advance(rates, to_stop), phase, reversed);
    }
    (state, phase, reversed)
}

/// Where restitution starts and the normal work it must reach.
struct RestitutionStart {
    state: ImpactState,
    phase: Phase,
    reversed: bool,
    target: f64,
}

/// Stronge's law; falls back to the frictionless Newton impulse if rounding ever broke the
/// energy bound (the proof above says it cannot, beyond `ENERGY_ROUNDING`).
pub(super) fn energy_safe_impulse(frame: &ContactFrame) -> ImpulseOutcome {
    let Ok(outcome) = stronge_impulse(frame) else {
        return frictionless_impulse(frame);
    };
    let magnitude =
        frame.velocity.dot(outcome.impulse).abs() + 0.5 * outcome.impulse.dot(frame.matrix * outcome.impulse);
    let safe = outcome.energy_change <= ENERGY_ROUNDING * magnitude;
    debug_assert!(safe, "energy-safe impulse gained energy: {outcome:?}");
    if safe { outcome } else { frictionless_impulse(frame) }
}

fn stronge_impulse(frame: &ContactFrame) -> Result<ImpulseOutcome, ImpulseError> {
    let (compressed, phase, reversed) = integrate_compression(frame)?;
    // W_c < 0; restitution must do −e² W_c of normal work. Count it from 0 rather than
    // aiming at W_c (1 − e²): for small e that difference would cancel most digits.
    let target = -frame.restitution * frame.restitution * compressed.normal_work;
    let state = ImpactState { normal_work: 0.0, ..compressed };
    let start = RestitutionStart { state, phase, reversed, target };
    let (state, phase, reversed) = integrate_restitution(frame, start);
    let impulse = frame.impulse(state.normal_impulse, state.tangential_impulse);
    let kind = if phase == Phase::Stick { ImpulseKind::Sticking } else { ImpulseKind::Sliding };
    Ok(frame.outcome(impulse, kind, reversed))
}

/// Newton's law without friction: `j = −(1+e) u_n / K_nn · n`, `ΔKE = −(1−e²) u_n²/(2 K_nn)`.
fn frictionless_impulse(frame: &ContactFrame) -> ImpulseOutcome {
    let impulse = frame.impulse(-(1.0 + frame.restitution) * frame.u_n / frame.k_nn, 0.0);
    let outcome = frame.outcome(impulse, ImpulseKind::Frictionless, false);
    ImpulseOutcome { kind: ImpulseKind::Frictionless, ..outcome }
}
