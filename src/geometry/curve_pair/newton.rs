//! Safeguarded Newton on `D = ½|p(t) − q(s)|²`: ε-active set on the box, Levenberg–Marquardt
//! shift, backtracking on `D`.

use super::*;

/// `D`, its gradient and Hessian at one parameter pair.
#[derive(Clone, Copy, Debug)]
pub(super) struct DistanceJet {
    pub(super) value: f64,
    pub(super) gradient: DVec2,
    /// `[H_tt, H_ts, H_ss]`.
    pub(super) hessian: [f64; 3],
    /// `|p'|² + |q'|²`, the scale of the Hessian.
    pub(super) speed: f64,
}

pub(super) fn distance_jet(a: &CubicSegment, b: &CubicSegment, x: DVec2) -> DistanceJet {
    let [p, p1, p2] = a.jet(x.x);
    let [q, q1, q2] = b.jet(x.y);
    let r = p - q;
    DistanceJet {
        value: 0.5 * r.length_squared(),
        gradient: DVec2::new(r.dot(p1), -r.dot(q1)),
        hessian: [p1.length_squared() + r.dot(p2), -p1.dot(q1), q1.length_squared() - r.dot(q2)],
        speed: p1.length_squared() + q1.length_squared(),
    }
}

pub(super) struct NewtonResult {
    pub(super) x: DVec2,
    pub(super) distance: f64,
    pub(super) iterations: u32,
    /// [`distance_jet`] at `x` where Newton worked it out (the same bits: a caller that needs
    /// it there does not evaluate the pieces again).
    pub(super) jet: Option<DistanceJet>,
}

/// A box of parameter pairs `(t, s)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct ParamBox {
    pub(super) low: DVec2,
    pub(super) high: DVec2,
}

impl ParamBox {
    pub(super) const UNIT: Self = Self { low: DVec2::ZERO, high: DVec2::ONE };

    pub(super) fn clamp(&self, x: DVec2) -> DVec2 {
        x.clamp(self.low, self.high)
    }

    /// Whether `x` lies on a side of this box that is not a side of the unit square.
    pub(super) fn on_inner_side(&self, x: DVec2) -> bool {
        let inner = |xi: f64, lo: f64, hi: f64| (xi <= lo && lo > 0.0) || (xi >= hi && hi < 1.0);
        inner(x.x, self.low.x, self.high.x) || inner(x.y, self.low.y, self.high.y)
    }
}

/// Newton confined to the cell first, so that every flat cell yields its own minimum even
/// where a nearly flat valley would carry an unconfined iterate to another basin; a minimum
/// on an inner side of the cell is then released into the whole square, unless it is no
/// nearer than `polished`, a true minimum already found.
///
/// Such a release could only matter by descending into another cell's basin below
/// `polished`; that cell finds its own minimum when it is searched, or was set aside because
/// its bound shows it holds nothing nearer. In a search the cells next to the minimum's own
/// each stop on their side facing it, and their releases found that minimum again.
pub(super) fn minimize_from_cell(
    a: &CubicSegment,
    b: &CubicSegment,
    cell: &Cell,
    settings: &CurvePairSettings,
    polished: Option<f64>,
) -> NewtonResult {
    let bounds = ParamBox { low: DVec2::new(cell.t0, cell.s0), high: DVec2::new(cell.t1, cell.s1) };
    let local = minimize_distance(a, b, cell.centre(), bounds, settings, RoundingFloor::Crawl);
    if !bounds.on_inner_side(local.x) || polished.is_some_and(|nearest| local.distance >= nearest) {
        return local;
    }
    let released = minimize_distance(a, b, local.x, ParamBox::UNIT, settings, RoundingFloor::Crawl);
    NewtonResult { iterations: local.iterations + released.iterations, ..released }
}

/// Where Newton stops once the line search only finds decreases of `D` within its rounding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum RoundingFloor {
    /// Keep stepping while any decrease is found (the search: its answers match a brute-force
    /// reference to 1e-12, including which point of a nearly flat valley decides the band).
    Crawl,
    /// Stop there (a recalled contact, whose answer may lie `2δ` above the minimum anyway: along
    /// the flat valley of a tangency the crawl took 1e-16 per step up to the iteration cap; and
    /// a seeded search's first point, which the slab certificate or the cells then decide).
    Stop,
}

/// Local minimum of `D` over `bounds` from `start`, by Newton with an active set, a
/// Levenberg–Marquardt shift and backtracking. Never increases `D`.
pub(super) fn minimize_distance(
    a: &CubicSegment,
    b: &CubicSegment,
    start: DVec2,
    bounds: ParamBox,
    settings: &CurvePairSettings,
    floor: RoundingFloor,
) -> NewtonResult {
    let mut x = bounds.clamp(start);
    let mut jet = distance_jet(a, b, x);
    let mut iterations = 0;
    let mut previous_move = f64::INFINITY;
    // Along the valley of conformal pieces (parallel flats) the distance does not change and
    // Newton only crawls: two steps in a row that gain less than the distance tolerance end it.
    let gain_floor = settings.distance_tolerance * pair_scale(a, b);
    let mut idle = 0;
    while iterations < settings.max_newton_iterations {
        let Some(step) = newton_step(x, &jet, &bounds) else { break };
        // A full step this short: `x` is the minimum to the tolerance, so the step is not taken
        // (taking it costs an evaluation, and near the rounding floor of `D` the test of
        // sufficient decrease fails by noise and starts a run of backtracked steps).
        if step.abs().max_element() <= settings.newton_step_tolerance {
            break;
        }
        let Some((mut next, mut next_jet, full_step)) = backtrack(a, b, x, &jet, step, &bounds) else { break };
        iterations += 1;
        let moved = (next - x).abs().max_element();
        // Near a tangency D is quartic along the valley and Newton only shrinks the error by
        // 2/3 per step; the step that removes it is three times as long: try it.
        if (0.55..0.8).contains(&(moved / previous_move)) {
            let far = bounds.clamp(x + 3.0 * (next - x));
            let far_jet = distance_jet(a, b, far);
            if far_jet.value < next_jet.value {
                (next, next_jet) = (far, far_jet);
            }
        }
        previous_move = moved;
        let gain = (2.0 * jet.value).sqrt() - (2.0 * next_jet.value).sqrt();
        idle = if gain <= gain_floor && full_step { idle + 1 } else { 0 };
        // A step the line search cut back below the tolerance for a decrease within the
        // rounding of `D`: Newton is at the floor of what `D` resolves.
        let at_floor = floor == RoundingFloor::Stop
            && moved <= settings.newton_step_tolerance
            && jet.value - next_jet.value <= 8.0 * f64::EPSILON * jet.value;
        x = next;
        jet = next_jet;
        if (moved <= settings.newton_step_tolerance && full_step) || idle >= 2 || at_floor {
            break;
        }
    }
    NewtonResult { x, distance: (2.0 * jet.value).sqrt(), iterations, jet: Some(jet) }
}

/// Parameters within this fraction of the box width of a bound count as on it (active set).
pub(super) const ACTIVE_BOUND: f64 = 1e-9;

/// The Newton step on the free variables (pinned ones snap to their bound); `None` at a
/// Karush–Kuhn–Tucker point. Inlined into [`minimize_distance`], which takes a step each
/// iteration.
#[inline(always)]
pub(super) fn newton_step(x: DVec2, jet: &DistanceJet, bounds: &ParamBox) -> Option<DVec2> {
    let g = jet.gradient;
    let margin = ACTIVE_BOUND * (bounds.high - bounds.low);
    // ε-active set: a variable this close to a bound, pushed outward, is pinned and snapped to
    // the bound; plain projection would crawl towards it in ever shorter steps.
    let pinned = |xi: f64, gi: f64, lo: f64, hi: f64, m: f64| (xi <= lo + m && gi > 0.0) || (xi >= hi - m && gi < 0.0);
    let free_t = !pinned(x.x, g.x, bounds.low.x, bounds.high.x, margin.x);
    let free_s = !pinned(x.y, g.y, bounds.low.y, bounds.high.y, margin.y);
    let snap = |xi: f64, gi: f64, lo: f64, hi: f64| if gi > 0.0 { lo - xi } else { hi - xi };
    let snap_t = || snap(x.x, g.x, bounds.low.x, bounds.high.x);
    let snap_s = || snap(x.y, g.y, bounds.low.y, bounds.high.y);
    let [htt, hts, hss] = jet.hessian;
    // A Hessian eigenvalue below this is shifted up to it (Levenberg–Marquardt). Small, so
    // the nearly singular Hessian of a tangency still gives full Newton steps.
    let floor = 1e-14 * jet.speed + f64::MIN_POSITIVE;
    let step = match (free_t, free_s) {
        (false, false) => DVec2::new(snap_t(), snap_s()),
        (true, false) => DVec2::new((-g.x / htt.max(floor)).clamp(-1.0, 1.0), snap_s()),
        (false, true) => DVec2::new(snap_t(), (-g.y / hss.max(floor)).clamp(-1.0, 1.0)),
        (true, true) => solve_shifted([htt, hts, hss], g, floor),
    };
    (step != DVec2::ZERO && step.is_finite()).then_some(step)
}

/// Solves `(H + μI) Δ = −g` with μ lifting the smallest eigenvalue of `H` to at least `floor`
/// and, where that step would leave a box of unit width, raised further (Levenberg–Marquardt):
/// a nearly singular `H` (parallel tangents) must not turn rounding noise into the step.
pub(super) fn solve_shifted([htt, hts, hss]: [f64; 3], g: DVec2, floor: f64) -> DVec2 {
    let mean = 0.5 * (htt + hss);
    let radius = (0.25 * (htt - hss) * (htt - hss) + hts * hts).sqrt();
    let mut shift = (floor - (mean - radius)).max(0.0);
    let scale = htt.abs() + hss.abs() + floor;
    for _ in 0..64 {
        let (a, c) = (htt + shift, hss + shift);
        let det = a * c - hts * hts;
        let step = DVec2::new(-(c * g.x - hts * g.y) / det, -(a * g.y - hts * g.x) / det);
        if det > 0.0 && step.is_finite() && step.abs().max_element() <= 1.0 {
            return step;
        }
        shift = (4.0 * shift).max(1e-12 * scale);
    }
    DVec2::ZERO
}

/// Projected backtracking (Armijo) on `D`: the new point, its jet and whether the full step was
/// taken; `None` when no step length decreases `D`.
pub(super) fn backtrack(
    a: &CubicSegment,
    b: &CubicSegment,
    x: DVec2,
    jet: &DistanceJet,
    step: DVec2,
    bounds: &ParamBox,
) -> Option<(DVec2, DistanceJet, bool)> {
    let mut alpha = 1.0;
    for _ in 0..40 {
        let next = bounds.clamp(x + alpha * step);
        if next == x {
            return None;
        }
        let next_jet = distance_jet(a, b, next);
        if next_jet.value <= jet.value + 1e-4 * jet.gradient.dot(next - x) {
            return Some((next, next_jet, alpha == 1.0));
        }
        alpha *= 0.5;
    }
    None
}
