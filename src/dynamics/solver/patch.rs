//! Two-point patches solved as blocks: both ends' normal impulses by the 2×2 complementarity
//! problem (Box2D's block solver), one friction impulse at the patch centre ([`solve_patch`]).

use super::{
    Accumulator, Pass, SolverContact, arms_along, change_of, change_weights, effective_mass, masses, push_along,
    row_velocity, solve_contact,
};
use crate::dynamics::impulse::BodyVelocity;

/// The 2×2 normal matrix `K` of a two-point patch, `(k11, k22, k12)`, for inverse masses
/// `inverse`; `None` when the two ends nearly coincide (the block is singular).
fn patch_matrix(first: &SolverContact, second: &SolverContact, inverse: [f64; 4]) -> Option<(f64, f64, f64)> {
    let k = |(a1, b1): (f64, f64), (a2, b2): (f64, f64)| {
        inverse[0] + inverse[2] + inverse[1] * a1 * a2 + inverse[3] * b1 * b2
    };
    let (r1, r2) = (first.normal_arms, second.normal_arms);
    let (k11, k22, k12) = (k(r1, r1), k(r2, r2), k(r1, r2));
    let determinant = k11 * k22 - k12 * k12;
    (!determinant.is_nan() && determinant > 1e-9 * k11 * k22).then_some((k11, k22, k12))
}

/// Box2D's block solver: the accumulated impulses `x ≥ 0` with `w = K x + b ≥ 0` and
/// `xᵢ wᵢ = 0`, by trying the four cases of which ends push.
#[inline(always)]
fn block_impulses((k11, k22, k12): (f64, f64, f64), (b1, b2): (f64, f64)) -> (f64, f64) {
    let determinant = k11 * k22 - k12 * k12;
    let both = ((-k22 * b1 + k12 * b2) / determinant, (k12 * b1 - k11 * b2) / determinant);
    if both.0 >= 0.0 && both.1 >= 0.0 {
        both
    } else if -b1 / k11 >= 0.0 && k12 * (-b1 / k11) + b2 >= 0.0 {
        (-b1 / k11, 0.0)
    } else if -b2 / k22 >= 0.0 && k12 * (-b2 / k22) + b1 >= 0.0 {
        (0.0, -b2 / k22)
    } else {
        (0.0, 0.0)
    }
}

/// What a two-point patch's update needs that depends only on its two contacts and the bodies'
/// masses: the 2×2 normal matrix (`None` when the ends nearly coincide) and its friction point,
/// the centre, with its lever arms and tangent mass. Fixed over a sub-step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PatchBlock {
    pub(crate) matrix: Option<(f64, f64, f64)>,
    /// The tangent's angular arms at the centre ([`arms_along`]).
    pub(crate) centre_arms: (f64, f64),
    pub(super) tangent_mass: f64,
}

impl PatchBlock {
    /// The block of the patch `first`, `second` for inverse masses `inverse`.
    fn new(first: &SolverContact, second: &SolverContact, inverse: [f64; 4]) -> Self {
        let centre = (0.5 * (first.r_a + second.r_a), 0.5 * (first.r_b + second.r_b));
        Self {
            matrix: patch_matrix(first, second, inverse),
            centre_arms: arms_along(centre.0, centre.1, first.tangent()),
            tangent_mass: effective_mass(inverse, centre.0, centre.1, first.tangent()),
        }
    }
}

/// Works out every patch's block for the pass with both bodies free (the sweeps of a sub-step
/// would otherwise each work it out again; the shock pass reads it too where it holds neither
/// body); `contacts` in solving order, each patch's two ends adjacent.
pub fn prepare_patches(contacts: &mut [SolverContact]) {
    for k in 0..contacts.len() {
        contacts[k].change_weights = change_weights(&contacts[k]);
        let patch = contacts[k].patch_with_next && k + 1 < contacts.len();
        contacts[k].patch = patch.then(|| PatchBlock::new(&contacts[k], &contacts[k + 1], contacts[k].inverse));
    }
}

/// The friction increment at the centre of a patch: brings the centre's tangential velocity
/// to rest with the accumulated `*impulse` within `±limit`; returns the increment.
#[inline(always)]
fn patch_friction(
    first: &SolverContact,
    block: &PatchBlock,
    impulse: &mut f64,
    limit: f64,
    (a, b): (&BodyVelocity, &BodyVelocity),
) -> f64 {
    let u_t = row_velocity(first.tangent(), block.centre_arms, a, b);
    let new_tangent = (*impulse - block.tangent_mass * u_t).clamp(-limit, limit);
    let dt = new_tangent - *impulse;
    *impulse = new_tangent;
    dt
}

/// The block update of a two-point patch on the impulses of `which`: both normal impulses by
/// the 2×2 complementarity problem, then one friction impulse at the centre within
/// `μ₁ P₁ + μ₂ P₂` (kept on `first`). `false` when the ends nearly coincide (nothing done).
#[inline(always)]
pub(super) fn block_patch(
    first: &mut SolverContact,
    second: &mut SolverContact,
    (a, b): (&mut BodyVelocity, &mut BodyVelocity),
    inverse: [f64; 4],
    (pass, which): (Pass, Accumulator),
) -> Option<f64> {
    // The shock pass holds neither body of a contact between bodies of one level: its masses,
    // and so its block, are the free pass's.
    let block = match (pass, first.patch) {
        (Pass::Relax, Some(block)) => block,
        (Pass::Shock, Some(block)) if first.shock_hold == 0 => block,
        _ => PatchBlock::new(first, second, inverse),
    };
    let matrix = block.matrix?;
    let (k11, k22, k12) = matrix;
    let n = first.normal;
    let w1 = row_velocity(n, first.normal_arms, a, b);
    let w2 = row_velocity(n, second.normal_arms, a, b);
    let (p1, t1, target1) = first.accumulated(which);
    let (p2, t2, target2) = second.accumulated(which);
    let old = (*p1, *p2);
    // Velocities with the current impulses removed, less the targets: w = K x + b.
    let (b1, b2) = (w1 - target1, w2 - target2);
    let new = block_impulses(matrix, (b1 - (k11 * old.0 + k12 * old.1), b2 - (k12 * old.0 + k22 * old.1)));
    (*p1, *p2) = new;
    let mut tangent = *t1;
    let partner_tangent = std::mem::replace(t2, 0.0);
    push_along(inverse, n, first.normal_arms, new.0 - old.0, (a, b));
    push_along(inverse, n, second.normal_arms, new.1 - old.1, (a, b));
    let limit = first.friction * new.0 + second.friction * new.1;
    let dt = patch_friction(first, &block, &mut tangent, limit, (a, b));
    let first_tangent = std::mem::replace(first.accumulated(which).1, tangent);
    push_along(inverse, first.tangent(), block.centre_arms, dt, (a, b));
    let first_change = change_of(first, new.0 - old.0, tangent - first_tangent);
    Some(first_change.max(change_of(second, new.1 - old.1, -partner_tangent)))
}

/// One update of a two-point patch (`first` and `second` the two ends) on the impulses of
/// `which`: both normal impulses at once by the 2×2 complementarity problem (Box2D's block
/// solver: the four cases of which ends push; for the split impulses each end to its own
/// push-out speed), then one friction impulse at the patch centre bounded by `μ₁ P₁ + μ₂ P₂`.
/// Solving the ends together keeps a flat body from rocking between them (and, for the push-out,
/// from being turned at each end in turn, which walked a body resting on two supports sideways);
/// one friction point keeps the two ends from pre-stressing the body against each other.
/// Returns the larger change of the two ends (see [`sweep`](super::sweep)).
#[inline(always)]
pub fn solve_patch(
    first: &mut SolverContact,
    second: &mut SolverContact,
    (a, b): (&mut BodyVelocity, &mut BodyVelocity),
    pass: Pass,
    which: Accumulator,
) -> f64 {
    let (inverse, _, _) = masses(first, pass);
    if let Some(change) = block_patch(first, second, (a, b), inverse, (pass, which)) {
        return change;
    }
    // The two ends nearly coincide: solve them one after the other.
    let first_change = solve_contact(first, a, b, pass, which);
    first_change.max(solve_contact(second, a, b, pass, which))
}
