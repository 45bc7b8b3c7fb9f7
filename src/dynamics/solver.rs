//! The iterated contact solver (MODEL §7a): sequential impulses with accumulated-impulse
//! clamping on resting contacts, warm-started from the persistent manifold; and the
//! split-impulse pass that removes position error with pseudo-velocities that never become
//! kinetic energy, finished by shock propagation.
//!
//! Conventions as in [`crate::dynamics::impulse`]: `n` is B's outward normal (towards A),
//! `t = n.perp()`, an impulse `j` acts on A and `−j` on B, `u_n < 0` approaches.
//!
//! Everything here is serial and runs over contacts in a fixed order, so results do not depend
//! on the thread count.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::dynamics::impulse::{BodyVelocity, ImpulseKind};

mod lanes;
mod patch;

pub use patch::{PatchBlock, prepare_patches, solve_patch};

/// Identity of a contact across steps, which its warm start is found by: the body pair and
/// either, for a lone contact, the two segments and its ordinal among the contacts of that
/// segment pair ([`RECOVERY_ORDINAL`] for an overlap-recovery contact of crossing curves), or,
/// for an end of a flat patch, [`PATCH_END`] in place of A's segment, the patch's index among
/// the pair's patches in place of B's and which end it is (0 the low end along `t = n.perp()`,
/// 1 the high end) as the ordinal.
///
/// A patch end is whichever leaf pair's overlap reaches furthest, and that leaf pair can
/// change from one step to the next while the end barely moves (where a rounded corner meets
/// a flat side within the band, the corner's piece reports the overlap's end in some steps and
/// the side's piece in others). Keyed by its segments, such an end started from the force of
/// whatever point had that key last step, or from none: a pyramid of 210 boxes set down at
/// rest lost some patch's warm start in every step, its solve never converged and its top box
/// slid sideways at 0.1–1.4 mm/s for seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct ContactKey {
    /// Body slots `(a, b)`, `a < b`.
    pub bodies: (u32, u32),
    /// Segment of A, or [`PATCH_END`].
    pub segment_a: u32,
    /// Segment of B, or the patch's index among the pair's patches.
    pub segment_b: u32,
    /// Ordinal of the contact among those of the same segment pair, or which end of its patch.
    pub ordinal: u32,
}

/// Ordinal given to the overlap-recovery contact of a pair whose curves cross.
pub const RECOVERY_ORDINAL: u32 = u32::MAX;

/// A's segment in the key of an end of a flat patch (see [`ContactKey`]).
pub const PATCH_END: u32 = u32::MAX;

/// A contact's accumulated impulses, kept from one sub-step to the next as forces (impulse per
/// second) so a sub-step of another length starts from the same force.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CachedImpulse {
    /// Which contact.
    pub key: ContactKey,
    /// Normal force `P_n / h` (N).
    pub normal_force: f64,
    /// Friction force `P_t / h` (N), along `t = n.perp()`.
    pub tangent_force: f64,
}

/// One contact as the solver sees it: lever arms, effective masses, friction and targets.
///
/// Laid out in declaration order (`repr(C)`), with what a sweep reads and writes first: the
/// resting sweeps' rows, masses, friction, change weights, impulses, patch block, island
/// indices and flags (212 bytes), then the push-out's impulses and target and the shock pass's
/// masses (the first 256 of its 472 bytes), so that a sweep touches fewer
/// lines: the base-40 pyramid's resting solve missed the first-level cache 16 % less often
/// under callgrind's cache model with the sweeps' fields first, and 5 % less again with the
/// push-out's and the shock pass's after the resting sweeps' (docs/performance.md).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct SolverContact {
    /// Unit normal, outward of B.
    pub normal: DVec2,
    /// The angular entries of the normal's row of the Jacobian, `(r_A × n, r_B × n)`
    /// ([`arms_along`]; set with `r_a`, `r_b` and `normal`).
    pub normal_arms: (f64, f64),
    /// The same for the tangent, `(r_A × t, r_B × t)`.
    pub tangent_arms: (f64, f64),
    /// Inverse masses and inertias `(1/m_A, 1/I_A, 1/m_B, 1/I_B)`.
    pub inverse: [f64; 4],
    /// `1 / (nᵀ K n)`.
    pub normal_mass: f64,
    /// `1 / (tᵀ K t)`.
    pub tangent_mass: f64,
    /// Friction coefficient `μ = max(μ_A(λ_A), μ_B(λ_B))`.
    pub friction: f64,
    /// What a sweep's change of the impulses `(|ΔP_n|, |ΔP_t|)` weighs in its convergence test,
    /// `(1 / (m_n band), 1 / (m_t band))` ([`change_of`]), set with the patch blocks by
    /// [`prepare_patches`]: one division a sub-step instead of three every sweep.
    pub change_weights: (f64, f64),
    /// Accumulated normal impulse `P_n ≥ 0` of the resting solve.
    pub normal_impulse: f64,
    /// Accumulated friction impulse `|P_t| ≤ μ P_n`.
    pub tangent_impulse: f64,
    /// On the first end of a patch: its block for the pass with both bodies free, worked out
    /// once per sub-step by [`prepare_patches`] (the sweeps only read it).
    pub patch: Option<PatchBlock>,
    /// The bodies' indices among their island's velocities ([`IslandVelocities`]).
    pub local: (u32, u32),
    /// Shock level: the lower of the two bodies' distances from a static body in the contact
    /// graph (0 touches the ground); contacts are solved from the ground up.
    pub level: u32,
    /// The island of the contact's bodies (its representative body slot): no dynamic body is in
    /// two islands, so each island's contacts are solved on their own, to their own convergence.
    pub island: u32,
    /// Whether this contact and the next one are the two ends of one flat patch: their normal
    /// impulses are solved together and their friction once, at the patch centre, within
    /// `μ₁ P₁ + μ₂ P₂` (stored on this contact; the partner's friction impulse stays 0).
    pub patch_with_next: bool,
    /// Which body the shock pass holds: 0 none, 1 A, 2 B.
    pub shock_hold: u8,
    /// Whether the velocity pass's shock propagation solves this contact: it lies in an island
    /// with a heavy-on-light contact (set by the contact solver).
    pub velocity_shock: bool,
    /// Whether the body above is at least [`HEAVY_ON_LIGHT`] times heavier than the one held
    /// below (set with the contact).
    pub heavy_on_light: bool,
    /// Accumulated split impulse `≥ 0`.
    pub bias_impulse: f64,
    /// Accumulated split friction impulse, `|·| ≤ μ` times the split impulse.
    pub bias_tangent_impulse: f64,
    /// Target speed of the split-impulse pass (m/s), set per sub-step: the push-out speed, or a
    /// negative speed for a bounce that leaves the band by itself (`laws::push_out_target`).
    pub bias_speed: f64,
    /// Effective masses with the lower body held (shock propagation); equal to the above when
    /// neither body is below the other.
    pub shock_masses: (f64, f64),
    /// Combined band `λ_A + λ_B` (floored) at the contact (m): the scale of the solver's
    /// convergence test.
    pub band: f64,
    /// Identity (for warm starting).
    pub key: ContactKey,
    /// The segments `(A, B)` the contact lies on (for events).
    pub segments: (u32, u32),
    /// Contact point in the world (for events).
    pub point: DVec2,
    /// Global parameters `(u_A, u_B)` of the contact (for events).
    pub parameters: (f64, f64),
    /// Unfloored tolerances `(λ_A, λ_B)` at the contact (for events).
    pub raw_lambda: (f64, f64),
    /// Each surface's friction coefficient `(μ_A(λ_A), μ_B(λ_B))` (for events).
    pub mu: (f64, f64),
    /// Contact point relative to A's centre of mass.
    pub r_a: DVec2,
    /// Contact point relative to B's centre of mass.
    pub r_b: DVec2,
    /// Restitution of a collision at this contact.
    pub restitution: f64,
    /// The seed's contact restitution `e_c(δ)` at this contact's depth: scales its push-out.
    pub push_restitution: f64,
    /// Penetration into the band beyond the rest depth (m); positive when too deep.
    pub excess_depth: f64,
    /// Warm-start forces `(F_n, F_t)` (N).
    pub warm: (f64, f64),
    /// Whether the contact had no force cached from the last sub-step (its warm start is then
    /// the statics estimate of `prepare_contacts`).
    pub cold: bool,
    /// Impulse of the collision law at this contact (zero if it did not collide).
    pub collision_impulse: DVec2,
    /// `u_n` when the solve started (after the forces).
    pub normal_velocity_before: f64,
    /// Position in the narrow phase's order (pair, then contact): ties of `level` keep it.
    pub sequence: u32,
    /// Whether the collision law acted here this sub-step.
    pub collided: bool,
    /// How the last collision impulse behaved (sticking, sliding, frictionless).
    pub collision_kind: Option<ImpulseKind>,
}

impl SolverContact {
    /// Tangent `t = n.perp()`.
    #[must_use]
    pub fn tangent(&self) -> DVec2 {
        self.normal.perp()
    }

    /// Relative velocity of the contact point, `u = (v_A + ω_A × r_A) − (v_B + ω_B × r_B)`.
    #[must_use]
    pub fn relative_velocity(&self, a: BodyVelocity, b: BodyVelocity) -> DVec2 {
        a.point_velocity(self.r_a) - b.point_velocity(self.r_b)
    }

    /// Total impulse on A: resting solve plus collision.
    #[must_use]
    pub fn total_impulse(&self) -> DVec2 {
        self.normal * self.normal_impulse + self.tangent() * self.tangent_impulse + self.collision_impulse
    }
}

/// `1 / (dᵀ K d)` for direction `d` with inverse masses `[1/m_A, 1/I_A, 1/m_B, 1/I_B]`
/// (0 when no impulse along `d` moves the contact).
#[must_use]
pub fn effective_mass(inverse: [f64; 4], r_a: DVec2, r_b: DVec2, d: DVec2) -> f64 {
    let k = inverse_mass_along(inverse, (r_a.perp_dot(d), r_b.perp_dot(d)));
    if k > 0.0 { 1.0 / k } else { 0.0 }
}

/// `dᵀ K d`, the inverse effective mass along a direction whose angular arms are `arms`
/// ([`arms_along`]): how fast an impulse along it moves its own row.
#[inline(always)]
pub(crate) fn inverse_mass_along(inverse: [f64; 4], (ra, rb): (f64, f64)) -> f64 {
    inverse[0] + inverse[2] + inverse[1] * ra * ra + inverse[3] * rb * rb
}

/// Applies impulse `j` (on A; `−j` on B) to two body velocities.
#[inline(always)]
pub fn apply(inverse: [f64; 4], r_a: DVec2, r_b: DVec2, j: DVec2, a: &mut BodyVelocity, b: &mut BodyVelocity) {
    a.linear += inverse[0] * j;
    a.angular += inverse[1] * r_a.perp_dot(j);
    b.linear -= inverse[2] * j;
    b.angular -= inverse[3] * r_b.perp_dot(j);
}

/// The angular arms `(r_A × d, r_B × d)` of direction `d` at lever arms `r_a`, `r_b`: an
/// impulse `p d` turns A by `p (r_A × d) / I_A`, and the contact point's velocity along `d` is
/// `d · (v_A − v_B) + ω_A (r_A × d) − ω_B (r_B × d)` ([`row_velocity`]).
#[must_use]
#[inline(always)]
pub fn arms_along(r_a: DVec2, r_b: DVec2, d: DVec2) -> (f64, f64) {
    (r_a.perp_dot(d), r_b.perp_dot(d))
}

/// The relative velocity along `d` of the point with angular arms `arms` ([`arms_along`]).
#[inline(always)]
pub(crate) fn row_velocity(d: DVec2, (arm_a, arm_b): (f64, f64), a: &BodyVelocity, b: &BodyVelocity) -> f64 {
    d.dot(a.linear - b.linear) + a.angular * arm_a - b.angular * arm_b
}

/// Applies the impulse `p d` (on A; `−p d` on B) at the point with angular arms `arms`: what
/// [`apply`] does for `j = p d`, with the arms worked out once per sub-step instead of per update.
#[inline(always)]
pub(crate) fn push_along(
    inverse: [f64; 4],
    d: DVec2,
    (arm_a, arm_b): (f64, f64),
    p: f64,
    (a, b): (&mut BodyVelocity, &mut BodyVelocity),
) {
    push_body([inverse[0], inverse[1]], d, arm_a, p, a);
    push_body([inverse[2], inverse[3]], d, arm_b, -p, b);
}

/// [`push_along`]'s change of one body, of inverse mass and inertia `inverse` at angular arm
/// `arm`: `p` for A, `−p` for B (for any `p` but a NaN, the same bits as subtracting `p`'s
/// change: negation is exact, and `x − y` is `x + (−y)`).
#[inline(always)]
pub(crate) fn push_body(inverse: [f64; 2], d: DVec2, arm: f64, p: f64, body: &mut BodyVelocity) {
    body.linear += (inverse[0] * p) * d;
    body.angular += inverse[1] * (p * arm);
}

/// Which of the two masses a pass uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Both bodies free.
    Relax,
    /// The lower body held (shock propagation): the level above cannot push it down.
    Shock,
}

/// One sequential-impulse update of a contact on the impulses of `which`: the normal increment
/// that brings `u_n` to the target (0 for the resting solve, the push-out speed for the split
/// impulses) with the accumulated normal impulse `≥ 0`, then the friction increment that
/// brings `u_t` to 0 within `μ` times it (the max rule's μ). For the split impulses that
/// friction matters: without it a push at one end of a body's support would turn it, the turn
/// would slide its other contacts sideways with nothing to hold them, and a pyramid of boxes
/// crept apart. Returns the change the update made (see [`sweep`]).
#[inline(always)]
pub fn solve_contact(
    contact: &mut SolverContact,
    a: &mut BodyVelocity,
    b: &mut BodyVelocity,
    pass: Pass,
    which: Accumulator,
) -> f64 {
    let (inverse, normal_mass, tangent_mass) = masses(contact, pass);
    let (n, t, friction) = (contact.normal, contact.tangent(), contact.friction);
    let (normal_arms, tangent_arms) = (contact.normal_arms, contact.tangent_arms);
    let u_n = row_velocity(n, normal_arms, a, b);
    let (normal, _, target) = contact.accumulated(which);
    let new_normal = (*normal - normal_mass * (u_n - target)).max(0.0);
    let dn = new_normal - *normal;
    *normal = new_normal;
    push_along(inverse, n, normal_arms, dn, (a, b));
    let u_t = row_velocity(t, tangent_arms, a, b);
    let (normal, tangent, _) = contact.accumulated(which);
    let limit = friction * *normal;
    let new_tangent = (*tangent - tangent_mass * u_t).clamp(-limit, limit);
    let dt = new_tangent - *tangent;
    *tangent = new_tangent;
    push_along(inverse, t, tangent_arms, dt, (a, b));
    change_of(contact, dn, dt)
}

/// How much an update of `contact` that changed its impulses by `(dn, dt)` changed its relative
/// velocity, per metre of its combined band (see [`sweep`]); 0 without a band.
#[inline(always)]
fn change_of(contact: &SolverContact, dn: f64, dt: f64) -> f64 {
    let (normal, tangent) = contact.change_weights;
    dn.abs() * normal + dt.abs() * tangent
}

/// [`SolverContact::change_weights`] of `contact`: `1 / (m band)` for each row, 0 for a row
/// without mass (no impulse moves it) or a contact without a band.
fn change_weights(contact: &SolverContact) -> (f64, f64) {
    let weight = |mass: f64| {
        let scale = mass * contact.band;
        if scale > 0.0 && scale.is_finite() { 1.0 / scale } else { 0.0 }
    };
    (weight(contact.normal_mass), weight(contact.tangent_mass))
}

/// Which accumulated impulses an update works on: which pass of the solver it belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accumulator {
    /// The resting solve's `(P_n, P_t)`, target `u_n = 0`.
    Velocity,
    /// The split impulses, target `u_n = bias_speed` (pseudo-velocities).
    Split,
}

impl SolverContact {
    /// The accumulated normal and tangent impulses of `which`, and its normal target speed.
    #[inline(always)]
    pub(crate) fn accumulated(&mut self, which: Accumulator) -> (&mut f64, &mut f64, f64) {
        match which {
            Accumulator::Velocity => (&mut self.normal_impulse, &mut self.tangent_impulse, 0.0),
            Accumulator::Split => (&mut self.bias_impulse, &mut self.bias_tangent_impulse, self.bias_speed),
        }
    }

    /// What [`SolverContact::accumulated`] gives, read only: `(P_n, P_t, target)` of `which`.
    #[inline(always)]
    pub(crate) fn impulses(&self, which: Accumulator) -> (f64, f64, f64) {
        match which {
            Accumulator::Velocity => (self.normal_impulse, self.tangent_impulse, 0.0),
            Accumulator::Split => (self.bias_impulse, self.bias_tangent_impulse, self.bias_speed),
        }
    }
}

/// Where a sweep reads and writes the velocities of a contact's two bodies: the bodies' states
/// (resting solve) or their pseudo-velocities (push-out), by body slot, or an island's own
/// velocities by the contact's index in the island ([`IslandVelocities`]).
pub trait PairVelocities {
    /// The velocities of the bodies of `contact`.
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity);
    /// Writes back the velocities of the bodies of `contact`.
    fn set_pair(&mut self, contact: &SolverContact, a: BodyVelocity, b: BodyVelocity);

    /// `update` of its contact (which it may change) and of the velocities of that contact's
    /// bodies: what [`pair`](Self::pair) reads, changed by `update`, written back as
    /// [`set_pair`](Self::set_pair) writes them. The sweeps' velocities find the two bodies once
    /// for both (by indices read before `update` writes the contact), so that neither the
    /// indices nor their bounds are checked again for the write.
    #[inline(always)]
    fn update(&mut self, mut update: impl Update) -> f64 {
        let (mut a, mut b) = self.pair(update.contact());
        let change = update.apply(&mut a, &mut b);
        self.set_pair(update.contact(), a, b);
        change
    }
}

/// One update of a sweep ([`PairVelocities::update`]): of a lone contact or of a patch's two
/// ends, on the velocities of their bodies.
pub trait Update {
    /// The contact whose bodies' velocities the update changes (a patch's first end).
    fn contact(&self) -> &SolverContact;
    /// The update, on the velocities `a` and `b` of the contact's bodies; returns its change of
    /// relative velocity per metre of band (see [`sweep`]).
    fn apply(&mut self, a: &mut BodyVelocity, b: &mut BodyVelocity) -> f64;
}

/// [`PairVelocities::update`] of the velocities at `(a, b)` of `velocities`: each body's index
/// checked once, for the read and the write.
#[inline(always)]
pub(crate) fn update_at(velocities: &mut [BodyVelocity], (a, b): (usize, usize), mut update: impl Update) -> f64 {
    let (mut va, mut vb) = (velocities[a], velocities[b]);
    let change = update.apply(&mut va, &mut vb);
    (velocities[a], velocities[b]) = (va, vb);
    change
}

impl PairVelocities for [BodyVelocity] {
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity) {
        let (a, b) = contact.key.bodies;
        (self[a as usize], self[b as usize])
    }

    fn set_pair(&mut self, contact: &SolverContact, va: BodyVelocity, vb: BodyVelocity) {
        let (a, b) = contact.key.bodies;
        (self[a as usize], self[b as usize]) = (va, vb);
    }

    #[inline(always)]
    fn update(&mut self, update: impl Update) -> f64 {
        let (a, b) = update.contact().key.bodies;
        update_at(self, (a as usize, b as usize), update)
    }
}

/// The velocities of one island's bodies, indexed by [`SolverContact::local`]: what an island's
/// solve owns while the islands are solved in parallel.
pub struct IslandVelocities<'a>(pub &'a mut [BodyVelocity]);

impl PairVelocities for IslandVelocities<'_> {
    fn pair(&self, contact: &SolverContact) -> (BodyVelocity, BodyVelocity) {
        let (a, b) = contact.local;
        (self.0[a as usize], self.0[b as usize])
    }

    fn set_pair(&mut self, contact: &SolverContact, va: BodyVelocity, vb: BodyVelocity) {
        let (a, b) = contact.local;
        (self.0[a as usize], self.0[b as usize]) = (va, vb);
    }

    #[inline(always)]
    fn update(&mut self, update: impl Update) -> f64 {
        let (a, b) = update.contact().local;
        update_at(self.0, (a as usize, b as usize), update)
    }
}

/// One sweep over `contacts` in order on the impulses of `which`, a patch's two ends together.
/// In the resting solve's shock pass only the contacts marked `velocity_shock` are solved.
/// Returns the largest change of a contact's relative velocity the sweep made, per metre of
/// its combined band (`(|ΔP_n| nᵀKn + |ΔP_t| tᵀKt) / (λ_A + λ_B)`, 1/s): times the sub-step, the
/// fraction of its band a contact would move by what the sweep still changed.
///
/// (Alternating forward and backward sweeps, symmetric Gauss–Seidel, was tried: it converged no
/// faster on a landing pile and left a 210-box pyramid further from rest.)
///
/// Always inlined: its callers pass `which` and `pass` as constants, and a sweep specialised to
/// them takes fewer instructions (compiled once for all, with them read at run time, the settling
/// base-20 pyramid's resting solve took 2 % more).
#[inline(always)]
pub fn sweep<V: PairVelocities + ?Sized>(
    contacts: &mut [SolverContact],
    velocities: &mut V,
    which: Accumulator,
    pass: Pass,
) -> f64 {
    let mut change: f64 = 0.0;
    let mut k = 0;
    while k < contacts.len() {
        // A lone contact (or a patch's first end at the end of the slice, solved alone).
        if !(contacts[k].patch_with_next && k + 1 < contacts.len()) {
            change = most(change, solve_lone(&mut contacts[k], velocities, which, pass));
            k += 1;
            continue;
        }
        // Two patches whose pairs share no body, in lanes: the same bits as one after the other.
        if which == Accumulator::Velocity && pass == Pass::Relax && lanes::pairable(&contacts[k..]) {
            let [one, two] = lanes::solve_two_patches(&mut contacts[k..], velocities);
            change = most(most(change, one), two);
            k += 4;
            continue;
        }
        change = most(change, solve_unit(&mut contacts[k..k + 2], velocities, which, pass));
        k += 2;
    }
    change
}

/// The larger of a sweep's largest change so far, `change` (never NaN: it starts at 0), and an
/// update's change `x` (`+0` or more, or NaN): what `change.max(x)` gives, NaN passed over, with
/// one comparison instead of `max`'s test for NaN on both sides. (`f64::max` on two changes
/// that are equal returns that value either way: a change is never `−0`.)
#[inline(always)]
pub(crate) fn most(change: f64, x: f64) -> f64 {
    if x > change { x } else { change }
}

/// One update of a lone contact; returns its change of relative velocity per metre of band
/// (see [`sweep`]).
#[inline(always)]
fn solve_lone<V: PairVelocities + ?Sized>(
    contact: &mut SolverContact,
    velocities: &mut V,
    which: Accumulator,
    pass: Pass,
) -> f64 {
    if which == Accumulator::Velocity && pass == Pass::Shock && !contact.velocity_shock {
        return 0.0;
    }
    velocities.update(Lone { contact, which, pass })
}

/// A lone contact's update ([`solve_contact`]).
struct Lone<'a> {
    contact: &'a mut SolverContact,
    which: Accumulator,
    pass: Pass,
}

impl Update for Lone<'_> {
    #[inline(always)]
    fn contact(&self) -> &SolverContact {
        self.contact
    }

    #[inline(always)]
    fn apply(&mut self, a: &mut BodyVelocity, b: &mut BodyVelocity) -> f64 {
        solve_contact(self.contact, a, b, self.pass, self.which)
    }
}

/// A patch's update ([`solve_patch`]).
struct Patch<'a> {
    first: &'a mut SolverContact,
    second: &'a mut SolverContact,
    which: Accumulator,
    pass: Pass,
}

impl Update for Patch<'_> {
    #[inline(always)]
    fn contact(&self) -> &SolverContact {
        self.first
    }

    #[inline(always)]
    fn apply(&mut self, a: &mut BodyVelocity, b: &mut BodyVelocity) -> f64 {
        solve_patch(self.first, self.second, (a, b), self.pass, self.which)
    }
}

/// One update of a lone contact or of a patch's two ends (`unit`); returns its largest change
/// of relative velocity per metre of band (see [`sweep`]).
#[inline(always)]
fn solve_unit<V: PairVelocities + ?Sized>(
    unit: &mut [SolverContact],
    velocities: &mut V,
    which: Accumulator,
    pass: Pass,
) -> f64 {
    match unit {
        [first, second] => {
            if which == Accumulator::Velocity && pass == Pass::Shock && !first.velocity_shock {
                return 0.0;
            }
            velocities.update(Patch { first, second, which, pass })
        }
        [contact] => solve_lone(contact, velocities, which, pass),
        // `sweep` passes one contact or a patch's two ends, nothing else.
        _ => 0.0,
    }
}

/// Mass ratio from which a contact is *heavy on light* (MODEL §7a, our choice): sequential
/// impulses converge slowly when a heavy body rests on a light one (at 10⁴ the light body cannot
/// hold the heavy one within any practical number of sweeps), so the velocity pass holds the
/// light body for such contacts. Between bodies of similar mass holding the lower body would
/// carry the relaxation's leftover motion up a structure (a pyramid kept creeping), so it
/// is not done there.
pub const HEAVY_ON_LIGHT: f64 = 10.0;

/// Sweeps per level of a shock-propagation pass: a body resting on two others (a pyramid)
/// needs its two contacts to agree, which one sweep in a fixed order does not give.
pub const SHOCK_SWEEPS: u32 = 4;

/// Calls `solve` on each run of `contacts` that shares `key`, in order.
pub fn for_each_run<K: PartialEq>(
    contacts: &mut [SolverContact],
    key: impl Fn(&SolverContact) -> K,
    mut solve: impl FnMut(&mut [SolverContact]),
) {
    let mut start = 0;
    while start < contacts.len() {
        let first = key(&contacts[start]);
        let end = start + contacts[start..].iter().take_while(|c| key(c) == first).count();
        solve(&mut contacts[start..end]);
        start = end;
    }
}

/// Calls `solve` on the contacts of each shock level in turn, from the ground up (`contacts`
/// sorted by level, or by island and then level: islands share no dynamic body, so each
/// island's levels in turn are as good).
pub fn for_each_level(contacts: &mut [SolverContact], solve: impl FnMut(&mut [SolverContact])) {
    for_each_run(contacts, |c| (c.island, c.level), solve);
}

#[inline(always)]
fn masses(contact: &SolverContact, pass: Pass) -> ([f64; 4], f64, f64) {
    let mut inverse = contact.inverse;
    match (pass, contact.shock_hold) {
        (Pass::Shock, 1) => {
            inverse[0] = 0.0;
            inverse[1] = 0.0;
        }
        (Pass::Shock, 2) => {
            inverse[2] = 0.0;
            inverse[3] = 0.0;
        }
        _ => return (inverse, contact.normal_mass, contact.tangent_mass),
    }
    (inverse, contact.shock_masses.0, contact.shock_masses.1)
}

#[cfg(test)]
impl SolverContact {
    /// A contact between bodies of inverse masses `inverse` at arms `(r_a, r_b)` along `normal`,
    /// its effective masses worked out, with `friction` (for tests).
    pub(crate) fn for_test(inverse: [f64; 4], (r_a, r_b): (DVec2, DVec2), normal: DVec2, friction: f64) -> Self {
        Self {
            r_a,
            r_b,
            normal,
            normal_arms: arms_along(r_a, r_b, normal),
            tangent_arms: arms_along(r_a, r_b, normal.perp()),
            inverse,
            normal_mass: effective_mass(inverse, r_a, r_b, normal),
            tangent_mass: effective_mass(inverse, r_a, r_b, normal.perp()),
            friction,
            ..Self::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box_on_ground(friction: f64) -> SolverContact {
        let arms = (DVec2::new(0.3, -0.5), DVec2::new(0.3, 0.0));
        SolverContact::for_test([1.0, 2.0, 0.0, 0.0], arms, DVec2::Y, friction)
    }

    #[test]
    fn normal_impulse_stops_approach_and_never_pulls() {
        let mut c = box_on_ground(0.0);
        let mut a = BodyVelocity { linear: DVec2::new(0.0, -1.0), angular: 0.0 };
        let mut b = BodyVelocity::ZERO;
        solve_contact(&mut c, &mut a, &mut b, Pass::Relax, Accumulator::Velocity);
        assert!(c.relative_velocity(a, b).dot(DVec2::Y).abs() < 1e-14);
        assert!(c.normal_impulse > 0.0);
        let mut away = BodyVelocity { linear: DVec2::new(0.0, 1.0), angular: 0.0 };
        let mut c = box_on_ground(0.0);
        solve_contact(&mut c, &mut away, &mut b, Pass::Relax, Accumulator::Velocity);
        assert_eq!(c.normal_impulse, 0.0);
        assert_eq!(away.linear, DVec2::new(0.0, 1.0));
    }

    #[test]
    fn friction_stays_inside_the_cone() {
        let mut c = box_on_ground(0.5);
        let mut a = BodyVelocity { linear: DVec2::new(3.0, -0.1), angular: 0.0 };
        let mut b = BodyVelocity::ZERO;
        for _ in 0..20 {
            solve_contact(&mut c, &mut a, &mut b, Pass::Relax, Accumulator::Velocity);
        }
        assert!(c.tangent_impulse.abs() <= 0.5 * c.normal_impulse * (1.0 + 1e-12));
        let slip = DVec2::new(3.0, 0.0);
        assert!((c.tangent() * c.tangent_impulse).dot(slip) < 0.0, "friction opposes the slip");
    }

    #[test]
    fn push_out_does_not_slide_a_rough_contact() {
        // A push at an off-centre point turns the box; with friction the pseudo-velocity of the
        // contact point along the ground is brought to rest (the push is far inside the cone),
        // without friction it slides.
        for (friction, slides) in [(0.5, false), (0.0, true)] {
            let mut c = box_on_ground(friction);
            c.bias_speed = 0.1;
            let (mut a, mut b) = (BodyVelocity::ZERO, BodyVelocity::ZERO);
            for _ in 0..20 {
                solve_contact(&mut c, &mut a, &mut b, Pass::Relax, Accumulator::Split);
            }
            let u = c.relative_velocity(a, b);
            assert!((u.y - 0.1).abs() < 1e-12, "pushed out at the push-out speed: {u}");
            assert_eq!(u.x.abs() > 1e-3, slides, "μ = {friction}: tangential pseudo-velocity {}", u.x);
            assert!(c.bias_tangent_impulse.abs() <= friction * c.bias_impulse * (1.0 + 1e-12));
        }
    }

    #[test]
    fn shock_pass_holds_the_lower_body() {
        let mut c = box_on_ground(0.0);
        c.inverse = [1.0, 0.0, 1.0, 0.0];
        c.shock_hold = 2;
        c.shock_masses = (1.0, 1.0);
        let mut a = BodyVelocity { linear: DVec2::new(0.0, -1.0), angular: 0.0 };
        let mut b = BodyVelocity::ZERO;
        solve_contact(&mut c, &mut a, &mut b, Pass::Shock, Accumulator::Velocity);
        assert_eq!(b.linear, DVec2::ZERO, "the held body is not pushed");
        assert!(a.linear.y.abs() < 1e-15);
    }

    #[test]
    fn bias_reaches_the_push_speed_without_pulling() {
        let mut c = box_on_ground(0.0);
        c.bias_speed = 0.2;
        let (mut a, mut b) = (BodyVelocity::ZERO, BodyVelocity::ZERO);
        solve_contact(&mut c, &mut a, &mut b, Pass::Relax, Accumulator::Split);
        assert!((c.relative_velocity(a, b).dot(DVec2::Y) - 0.2).abs() < 1e-14);
    }

    #[test]
    fn rows_read_and_push_what_the_lever_arms_give() {
        // The rows' angular arms stand for the lever arms: the velocity along a row and an
        // impulse along it agree with `relative_velocity` and `apply` up to rounding.
        let mut k = 0.0_f64;
        let mut next = || {
            k += 1.0;
            (k * 0.754_877_666).fract() * 2.0 - 1.0
        };
        for _ in 0..200 {
            let (r_a, r_b) = (DVec2::new(next(), next()), DVec2::new(next(), next()));
            let normal = DVec2::new(next(), next()).normalize();
            let inverse = [next().abs(), next().abs(), next().abs(), next().abs()];
            let c = SolverContact::for_test(inverse, (r_a, r_b), normal, 0.5);
            let velocity = |linear: DVec2, angular: f64| BodyVelocity { linear, angular };
            let (a, b) = (velocity(DVec2::new(next(), next()), next()), velocity(DVec2::new(next(), next()), next()));
            for (d, arms) in [(c.normal, c.normal_arms), (c.tangent(), c.tangent_arms)] {
                let read = row_velocity(d, arms, &a, &b);
                assert!((read - c.relative_velocity(a, b).dot(d)).abs() < 1e-14, "row velocity {read}");
                let p = next();
                let (mut pa, mut pb, mut qa, mut qb) = (a, b, a, b);
                push_along(inverse, d, arms, p, (&mut pa, &mut pb));
                apply(inverse, r_a, r_b, p * d, &mut qa, &mut qb);
                for (x, y) in [(pa, qa), (pb, qb)] {
                    assert!((x.linear - y.linear).length() < 1e-14 && (x.angular - y.angular).abs() < 1e-14);
                }
            }
        }
    }
}
