//! Branch-and-bound search of the parameter square: cells, their hull bounds, the edge minima
//! and the crossing test (see the module documentation of `curve_pair`).

use super::*;

/// A cell of the parameter square with the pieces over its intervals and its distance bound.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cell {
    pub(super) a: CubicSegment,
    pub(super) b: CubicSegment,
    pub(super) t0: f64,
    pub(super) t1: f64,
    pub(super) s0: f64,
    pub(super) s1: f64,
    pub(super) depth: u32,
    pub(super) lower_bound: f64,
}

impl Cell {
    pub(super) fn centre(&self) -> DVec2 {
        DVec2::new(0.5 * (self.t0 + self.t1), 0.5 * (self.s0 + self.s1))
    }

    pub(super) fn contains(&self, x: DVec2) -> bool {
        x.x >= self.t0 && x.x <= self.t1 && x.y >= self.s0 && x.y <= self.s1
    }
}

/// `p(½)` of a piece, straight from its Bézier points.
pub(super) fn midpoint(piece: &CubicSegment) -> DVec2 {
    let [b0, b1, b2, b3] = piece.bezier;
    0.125 * (b0 + b3 + 3.0 * (b1 + b2))
}

/// Best point found so far; `polished` when Newton converged there.
#[derive(Clone, Copy, Debug)]
pub(super) struct Best {
    pub(super) x: DVec2,
    pub(super) distance: f64,
    pub(super) polished: bool,
}

pub(super) struct SearchResult {
    pub(super) closest: Option<ClosestPoints>,
    pub(super) iterations: u32,
    /// A lower bound on the distance over the whole square: the smaller of the distance found
    /// and the bounds of the cells set aside unsearched (by the cutoff or the best distance).
    pub(super) lower_bound: f64,
}

/// Global minimum of the distance, searched only where it can be at most `cutoff`.
///
/// `closest` is `None` when every cell was pruned by the cutoff.
pub(super) fn search(a: &CubicSegment, b: &CubicSegment, settings: &CurvePairSettings, cutoff: f64) -> SearchResult {
    search_from(a, b, settings, cutoff, (None, None))
}

/// [`search()`] with the local minimum Newton reaches from `seed` as its first best point: a
/// true point of the pieces, so the branch and bound stays exact, and cells that cannot come
/// nearer are set aside without Newton of their own (the pairs a landing pile searches again
/// are mostly contacts that moved past their trust radius, their last answer close to the new).
/// `root_gap` is the pieces' [`hull_gap`] where the caller has it already.
pub(super) fn search_from(
    a: &CubicSegment,
    b: &CubicSegment,
    settings: &CurvePairSettings,
    cutoff: f64,
    (seed, root_gap): (Option<DVec2>, Option<f64>),
) -> SearchResult {
    let scale = pair_scale(a, b);
    let touch = settings.intersection_tolerance * scale;
    let slack = settings.distance_tolerance * scale;
    let max_depth = settings.max_subdivision_depth.min(MAX_SUBDIVISION_DEPTH);
    let lower_bound = root_gap.unwrap_or_else(|| hull_gap(a, b));
    debug_assert!(lower_bound.to_bits() == hull_gap(a, b).to_bits(), "the root gap is the pieces' hull gap");
    let root = Cell { a: *a, b: *b, t0: 0.0, t1: 1.0, s0: 0.0, s1: 1.0, depth: 0, lower_bound };
    if root.lower_bound > cutoff {
        // Far apart: one hull test, and nothing to search.
        return SearchResult { closest: None, iterations: 0, lower_bound: root.lower_bound };
    }
    let mut stack = CellStack::new();
    stack.push(root);
    let mut best = Best { x: DVec2::splat(0.5), distance: f64::INFINITY, polished: false };
    let mut iterations = 0;
    if let Some(seed) = seed {
        let found = minimize_distance(a, b, seed, ParamBox::UNIT, settings, RoundingFloor::Stop);
        iterations += found.iterations;
        let (x, distance) = polish_root(a, b, &found, slack);
        best = Best { x, distance, polished: true };
    }
    // The slab of the best point while it is Newton's (a true minimum): cells it proves no
    // nearer are set aside without being split. A seeded search whose root cell it sets aside
    // is proven without a cell (no Newton cell ran, so the edges are not searched either).
    let mut slab: Option<Slab> = None;
    let mut budget = settings.max_cells;
    let mut set_aside = f64::INFINITY;
    // Whether Newton ran in a cell: its answer is local, so the edges are searched after.
    let mut newton_cells = false;
    // The cell on top of the stack is read where it lies (copied out, 176 bytes, it cost a call
    // to memcpy a cell), and taken off once it is done with or split.
    while best.distance > touch
        && let Some(cell) = stack.last()
    {
        if cell.lower_bound > cutoff || cell.lower_bound > best.distance - slack {
            set_aside = set_aside.min(cell.lower_bound);
            stack.pop();
            continue;
        }
        if best.polished && slab.is_none_or(|slab| slab.x != best.x) {
            slab = Slab::at(a, b, best.x);
        }
        if let Some(bound) =
            slab.map(|slab| slab.bound(cell, best.distance - slack)).filter(|&bound| bound > best.distance - slack)
        {
            set_aside = set_aside.min(bound);
            stack.pop();
            continue;
        }
        budget = budget.saturating_sub(1);
        let refine = budget > 0 && cell.depth < max_depth;
        if !is_newton_cell(cell, settings, max_depth, scale) {
            split_top(&mut stack, &mut best, (cutoff, slack), &mut set_aside);
        } else if cell.lower_bound <= touch {
            // The hulls overlap: look for a crossing, else keep subdividing while allowed.
            newton_cells = true;
            if let Some(x) = crossing_in_cell(a, b, cell, touch, settings) {
                best = Best { x, distance: a.position(x.x).distance(b.position(x.y)), polished: true };
                stack.pop();
            } else if refine {
                split_top(&mut stack, &mut best, (cutoff, slack), &mut set_aside);
            } else {
                iterations += minimize_in_cell(a, b, cell, settings, &mut best);
                stack.pop();
            }
        } else if !(best.polished && cell.contains(best.x)) {
            newton_cells = true;
            iterations += minimize_in_cell(a, b, cell, settings, &mut best);
            stack.pop();
        } else {
            stack.pop();
        }
    }
    if !best.polished && best.distance - slack > cutoff && set_aside > cutoff {
        // Proven beyond the cutoff with no Newton answer nearer than a cell's centre: every cell
        // set aside lies beyond it, and a Newton cell's minimum (its answer) came no nearer than
        // the best centre. Polishing would give the exact distance, which no caller beyond the
        // cutoff uses (it is the lower bound that answers them); 46 % of the fixed pile's
        // searches past the root cell end here (a scratch count), and polishing them was a
        // fifth of its Newton steps.
        let lower_bound = set_aside.min(best.distance - slack).max(root.lower_bound);
        return SearchResult { closest: Some(closest_at(a, b, best.x, iterations)), iterations, lower_bound };
    }
    if best.distance > touch && newton_cells {
        iterations += edge_minima(a, b, settings, cutoff, slack, &mut best);
    }
    let (closest, iterations) = finish_search(a, b, best, iterations, settings);
    let searched = closest.map_or(f64::INFINITY, |c| c.distance - slack);
    SearchResult { closest, iterations, lower_bound: searched.min(set_aside).max(root.lower_bound) }
}

/// The slab between the lines through the pieces' points `p = a(t)` and `q = b(s)` at `x`
/// across `d = p − q`: for any points `a`, `b` of the pieces, `(a − b)·d̂ = (a − p)·d̂ + |d| +
/// (q − b)·d̂`, so `|d|` plus the least signed distances of a cell's Bézier points (each piece's
/// hull holds it) from the lines, towards their own sides, bounds the distance over the cell
/// from below. A cell holding `x` has its pieces split there: the halves' first edges run along
/// the tangents at `p` and `q`, so pieces bending away from each other near a minimum (as those
/// of convex bodies do) reach at least `|d|` less the rounding, where their Bézier points stand
/// out past the tangents. Where the pieces turn back elsewhere (a concave stretch), the cells
/// there fail it and are split, while those near `x` are set aside at once (docs/model.md §3a).
#[derive(Clone, Copy, Debug)]
pub(super) struct Slab {
    x: DVec2,
    p: DVec2,
    q: DVec2,
    d: DVec2,
    distance: f64,
    /// Where one piece bends towards the other, less than the other bends away: the ring that
    /// separates them instead ([`Ring`]).
    ring: Option<Ring>,
}

/// A circle through the nearest point of the piece that bends away more (the inner piece),
/// tangent to it there and curving a little less, so that this piece lies inside it near the
/// point while the other, bending towards it less, lies outside the concentric circle through
/// its own nearest point. For any `a`, `b` of the pieces `|a − b| ≥ |a − c| − |b − c|` (`c` the
/// centre), and `|p(t) − c|²` over a piece is a polynomial of degree 6 whose every value lies
/// between its least and largest Bernstein coefficient: so the square root of the outer piece's
/// least coefficient less that of the inner piece's largest bounds the distance over a cell
/// from below. Any centre gives a true bound; the curvatures only choose a useful one. A blob
/// resting in another's hollow fails the slab between its nearest points at every depth (the
/// hollow's piece turns towards the blob), and passes the ring near the point.
#[derive(Clone, Copy, Debug)]
struct Ring {
    centre: DVec2,
    /// Whether B's piece is the inner one.
    inner_is_b: bool,
}

impl Slab {
    /// `None` where the points coincide.
    ///
    /// Not inlined: inlined into [`search_from`], its arithmetic was hoisted to wherever the best
    /// point may have changed (after every split, its best point a cell's centre), and ran three
    /// times as often as a slab is needed (in the landing pile of 100 blobs, 0.4 M instructions
    /// a step).
    #[inline(never)]
    pub(super) fn at(a: &CubicSegment, b: &CubicSegment, x: DVec2) -> Option<Self> {
        let [p, p1, p2] = a.jet(x.x);
        let [q, q1, q2] = b.jet(x.y);
        let d = (p - q).try_normalize()?;
        let distance = p.distance(q);
        // Each piece's curvature along the line between the points, positive where it bends
        // away from the other.
        let (bend_a, bend_b) = (p2.dot(d) / p1.length_squared(), -q2.dot(d) / q1.length_squared());
        // The inner piece must bend away by more than the outer bends towards it, measured at
        // the outer circle, `k / (1 − δ k)`; the ring's curvature lies halfway between.
        let radius = |away: f64, towards: f64| {
            let shrink = 1.0 - distance * towards;
            let needed = towards / shrink;
            (shrink > 0.0 && away > needed && away.is_finite()).then(|| 2.0 / (away + needed))
        };
        let ring = if bend_a < 0.0 {
            radius(bend_b, -bend_a).map(|radius| Ring { centre: q - radius * d, inner_is_b: true })
        } else if bend_b < 0.0 {
            radius(bend_a, -bend_b).map(|radius| Ring { centre: p + radius * d, inner_is_b: false })
        } else {
            None
        };
        Some(Self { x, p, q, d, distance, ring })
    }

    /// A lower bound of the distance over the cell: the slab's, and where that does not exceed
    /// `beat` and there is a ring, the larger of it and the ring's.
    pub(super) fn bound(&self, cell: &Cell, beat: f64) -> f64 {
        let (pieces_a, count_a) = split_at(&cell.a, (cell.t0, cell.t1), self.x.x);
        let (pieces_b, count_b) = split_at(&cell.b, (cell.s0, cell.s1), self.x.y);
        let (pieces_a, pieces_b) = (&pieces_a[..count_a], &pieces_b[..count_b]);
        let least = |pieces: &[CubicSegment], at: DVec2, towards: DVec2| {
            pieces.iter().flat_map(|piece| piece.bezier).map(|c| (c - at).dot(towards)).fold(f64::INFINITY, f64::min)
        };
        let slab = self.distance + least(pieces_a, self.p, self.d) + least(pieces_b, self.q, -self.d);
        let Some(ring) = self.ring.filter(|_| slab <= beat) else { return slab };
        let (inner, outer) = if ring.inner_is_b { (pieces_b, pieces_a) } else { (pieces_a, pieces_b) };
        let extreme = |pieces: &[CubicSegment], start: f64, pick: fn(f64, f64) -> f64| {
            pieces.iter().flat_map(|piece| squared_distance_coefficients(piece, ring.centre)).fold(start, pick)
        };
        let nearest = extreme(outer, f64::INFINITY, f64::min);
        let farthest = extreme(inner, f64::NEG_INFINITY, f64::max);
        slab.max(nearest.max(0.0).sqrt() - farthest.sqrt())
    }
}

/// The piece over `[low, high]` of the leaf's parameter, split at `t` where that lies inside.
fn split_at(piece: &CubicSegment, (low, high): (f64, f64), t: f64) -> ([CubicSegment; 2], usize) {
    if t > low && t < high {
        let (first, second) = piece.split((t - low) / (high - low));
        ([first, second], 2)
    } else {
        ([*piece, *piece], 1)
    }
}

/// The Bernstein coefficients of `|p(t) − c|²` over the piece (degree 6): with `u_i` its Bézier
/// points less `c`, `w_k = Σ_{i+j=k} C(3,i) C(3,j) / C(6,k) u_i·u_j`.
fn squared_distance_coefficients(piece: &CubicSegment, centre: DVec2) -> [f64; 7] {
    let [u0, u1, u2, u3] = piece.bezier.map(|point| point - centre);
    [
        u0.dot(u0),
        u0.dot(u1),
        0.4 * u0.dot(u2) + 0.6 * u1.dot(u1),
        0.1 * u0.dot(u3) + 0.9 * u1.dot(u2),
        0.4 * u1.dot(u3) + 0.6 * u2.dot(u2),
        u2.dot(u3),
        u3.dot(u3),
    ]
}

/// Whether [`Slab`] proves no two points of the pieces nearer than those at `x`, less `slack`
/// (with its ring where `ring`).
#[cfg(test)]
pub(super) fn slab_separates(a: &CubicSegment, b: &CubicSegment, x: DVec2, slack: f64, ring: bool) -> bool {
    let root = Cell { a: *a, b: *b, t0: 0.0, t1: 1.0, s0: 0.0, s1: 1.0, depth: 0, lower_bound: 0.0 };
    Slab::at(a, b, x)
        .map(|slab| Slab { ring: slab.ring.filter(|_| ring), ..slab })
        .is_some_and(|slab| slab.bound(&root, slab.distance - slack) > slab.distance - slack)
}

/// One Newton step on the distance's gradient from Newton's answer `x`, without the line
/// search: Newton stops where `D` no longer resolves a decrease, at a parameter error of about
/// `√(ε D / H)` (1e-10 for a contact of 4 mm between pieces 4 cm long), which tilts the
/// tangents off the slab by as much; the gradient still resolves it, and one step brings it to
/// the rounding. The step is kept where it is that short and its distance at most `slack` above
/// the answer's; returns the point kept and its distance.
fn polish_root(a: &CubicSegment, b: &CubicSegment, found: &NewtonResult, slack: f64) -> (DVec2, f64) {
    // Newton's own jet at its answer where it has one (the same bits as working it out again).
    let jet = found.jet.unwrap_or_else(|| distance_jet(a, b, found.x));
    let Some(step) = newton_step(found.x, &jet, &ParamBox::UNIT).filter(|step| step.abs().max_element() <= POLISH_STEP)
    else {
        return (found.x, found.distance);
    };
    let next = ParamBox::UNIT.clamp(found.x + step);
    let distance = a.position(next.x).distance(b.position(next.y));
    if distance <= found.distance + slack { (next, distance) } else { (found.x, found.distance) }
}

/// The longest step [`polish_root`] takes (parameters).
const POLISH_STEP: f64 = 1e-6;

/// The minima on the four edges of the square (an end of one piece against the other piece),
/// each found exactly by the 1-D nearest point and polished in the whole square. In a nearly
/// flat valley a leaf cell can hold an interior minimum and a lower one on the edge; this
/// finds the latter.
pub(super) fn edge_minima(
    a: &CubicSegment,
    b: &CubicSegment,
    settings: &CurvePairSettings,
    cutoff: f64,
    slack: f64,
    best: &mut Best,
) -> u32 {
    let mut iterations = 0;
    for end in [0.0, 1.0] {
        let (end_a, end_b) = (a.position(end), b.position(end));
        let candidates = [(end_a, b, true), (end_b, a, false)];
        for (point, piece, t_fixed) in candidates {
            let point_piece = CubicSegment { bezier: [point; 4] };
            let gap = hull_gap(&point_piece, piece);
            if gap > cutoff || gap > best.distance - slack {
                continue;
            }
            let (along, distance) = piece.nearest_parameter(point);
            iterations += 1;
            if distance > cutoff || distance > best.distance {
                continue;
            }
            let start = if t_fixed { DVec2::new(end, along) } else { DVec2::new(along, end) };
            let polished = minimize_distance(a, b, start, ParamBox::UNIT, settings, RoundingFloor::Crawl);
            iterations += polished.iterations;
            if polished.distance < best.distance {
                *best = Best { x: polished.x, distance: polished.distance, polished: true };
            }
        }
    }
    iterations
}

/// Runs Newton from a cell and keeps the result if it beats `best`; returns the iterations.
pub(super) fn minimize_in_cell(
    a: &CubicSegment,
    b: &CubicSegment,
    cell: &Cell,
    settings: &CurvePairSettings,
    best: &mut Best,
) -> u32 {
    let found = minimize_from_cell(a, b, cell, settings, best.polished.then_some(best.distance));
    if found.distance < best.distance {
        *best = Best { x: found.x, distance: found.distance, polished: true };
    }
    found.iterations
}

/// Polishes an unpolished best point (one found only as a cell centre): the nearest points,
/// if any cell was searched, and the iterations spent in all.
pub(super) fn finish_search(
    a: &CubicSegment,
    b: &CubicSegment,
    mut best: Best,
    mut iterations: u32,
    settings: &CurvePairSettings,
) -> (Option<ClosestPoints>, u32) {
    if best.distance.is_infinite() {
        return (None, iterations);
    }
    if !best.polished {
        let found = minimize_distance(a, b, best.x, ParamBox::UNIT, settings, RoundingFloor::Crawl);
        iterations += found.iterations;
        if found.distance <= best.distance {
            best = Best { x: found.x, distance: found.distance, polished: true };
        }
    }
    (Some(closest_at(a, b, best.x, iterations)), iterations)
}

/// A crossing `p(t) = q(s)` inside the cell by Newton on `p(t) − q(s) = 0` from its centre
/// (quadratic at a transversal crossing, whatever other minima of the distance are near).
pub(super) fn crossing_in_cell(
    a: &CubicSegment,
    b: &CubicSegment,
    cell: &Cell,
    touch: f64,
    settings: &CurvePairSettings,
) -> Option<DVec2> {
    let bounds = ParamBox { low: DVec2::new(cell.t0, cell.s0), high: DVec2::new(cell.t1, cell.s1) };
    let mut x = cell.centre();
    for _ in 0..settings.max_newton_iterations.min(24) {
        let residual = a.position(x.x) - b.position(x.y);
        if residual.length() <= touch {
            return Some(x);
        }
        let (pa, qb) = (a.derivative(x.x), b.derivative(x.y));
        // Solve pa·δt − qb·δs = −residual by Cramer's rule.
        let det = -pa.perp_dot(qb);
        if det.abs() <= 1e-14 * pa.length() * qb.length() || !det.is_finite() {
            return None;
        }
        let step = DVec2::new(-(-residual).perp_dot(qb) / det, pa.perp_dot(-residual) / det);
        let next = bounds.clamp(x + step);
        if next == x {
            return None;
        }
        x = next;
    }
    None
}

/// Takes the cell on top of the stack off it and pushes its children that survive pruning,
/// nearest centres on top; the smallest bound of the children set aside lowers `set_aside`, and
/// a child's centre nearer than the best point becomes it (unpolished). Each half piece is in
/// two children: what their hull tests read of it alone ([`PieceHull`]) and its midpoint are
/// worked out once. A child is built where it is pushed (built first, in an array of the four,
/// and then copied onto the stack, the cells cost the landing pile of 100 blobs 0.3 M
/// instructions a step in copies alone).
pub(super) fn split_top(stack: &mut CellStack, best: &mut Best, (cutoff, slack): (f64, f64), set_aside: &mut f64) {
    let cell = stack.last().expect("a cell to split");
    let (a0, a1) = cell.a.split(0.5);
    let (b0, b1) = cell.b.split(0.5);
    let tm = 0.5 * (cell.t0 + cell.t1);
    let sm = 0.5 * (cell.s0 + cell.s1);
    let (ts, ss) = ([(cell.t0, tm), (tm, cell.t1)], [(cell.s0, sm), (sm, cell.s1)]);
    let depth = cell.depth + 1;
    // A point-like piece (an edge of the square seen from the other piece) is not split.
    let chosen: &[usize] = match (is_point(&cell.a), is_point(&cell.b)) {
        (true, true) => &[0],
        (true, false) => &[0, 1],
        (false, true) => &[0, 2],
        (false, false) => &[0, 1, 2, 3],
    };
    stack.pop();
    let (halves_a, halves_b) = ([&a0, &a1], [&b0, &b1]);
    let hulls_a = [PieceHull::of(&a0), PieceHull::of(&a1)];
    let hulls_b = [PieceHull::of(&b0), PieceHull::of(&b1)];
    let (mids_a, mids_b) = ([midpoint(&a0), midpoint(&a1)], [midpoint(&b0), midpoint(&b1)]);
    // Child `k` is over A's half `k / 2` and B's half `k % 2`: its bound and the distance of
    // its centre points.
    let halves = |k: usize| (k >> 1, k & 1);
    let bounds: [f64; 4] = std::array::from_fn(|k| {
        let (i, j) = halves(k);
        hull_gap_of((halves_a[i], &hulls_a[i]), (halves_b[j], &hulls_b[j]))
    });
    let centre_distances: [f64; 4] = std::array::from_fn(|k| {
        let (i, j) = halves(k);
        mids_a[i].distance(mids_b[j])
    });
    for &k in chosen {
        if centre_distances[k] < best.distance {
            let (i, j) = halves(k);
            let centre = DVec2::new(0.5 * (ts[i].0 + ts[i].1), 0.5 * (ss[j].0 + ss[j].1));
            *best = Best { x: centre, distance: centre_distances[k], polished: false };
        }
    }
    // Farthest first onto the stack so the nearest centres are searched first. The indices are
    // ordered, not the cells, by a stable insertion sort, so equal distances keep the children's
    // order.
    let mut order = [0; 4];
    order[..chosen.len()].copy_from_slice(chosen);
    for i in 1..chosen.len() {
        let mut j = i;
        while j > 0 && centre_distances[order[j]].total_cmp(&centre_distances[order[j - 1]]).is_gt() {
            order.swap(j, j - 1);
            j -= 1;
        }
    }
    for &k in &order[..chosen.len()] {
        let lower_bound = bounds[k];
        if lower_bound <= cutoff && lower_bound <= best.distance - slack {
            let (i, j) = halves(k);
            let ((t0, t1), (s0, s1)) = (ts[i], ss[j]);
            // Cannot overflow: each level leaves at most three siblings waiting.
            stack.push(Cell { a: *halves_a[i], b: *halves_b[j], t0, t1, s0, s1, depth, lower_bound });
        } else {
            *set_aside = set_aside.min(lower_bound);
        }
    }
}

pub(super) fn is_point(piece: &CubicSegment) -> bool {
    let [b0, b1, b2, b3] = piece.bezier;
    b0 == b1 && b1 == b2 && b2 == b3
}

pub(super) fn is_newton_cell(cell: &Cell, settings: &CurvePairSettings, max_depth: u32, scale: f64) -> bool {
    cell.depth >= max_depth
        || (cell.depth >= settings.seed_depth
            && is_flat(&cell.a, settings.flatness_ratio, scale)
            && is_flat(&cell.b, settings.flatness_ratio, scale))
}

/// Inner Bézier points within `ratio` × chord of the chord (a point-like piece is flat).
pub(super) fn is_flat(piece: &CubicSegment, ratio: f64, scale: f64) -> bool {
    let [b0, b1, b2, b3] = piece.bezier;
    let chord = b3 - b0;
    let length = chord.length();
    let size = bezier_diagonal(piece);
    if size <= 1e-12 * scale {
        return true;
    }
    if length <= 1e-3 * size {
        return false;
    }
    let deviation = (b1 - b0).perp_dot(chord).abs().max((b2 - b0).perp_dot(chord).abs()) / length;
    // The inner points must also project inside the chord, or the piece folds back on itself.
    let inside = |p: DVec2| (-ratio..=1.0 + ratio).contains(&((p - b0).dot(chord) / (length * length)));
    deviation <= ratio * length && inside(b1) && inside(b2)
}

/// Lower bound of the distance between two pieces: the largest gap between the projections of
/// their Bézier points on the centre line, the two chord normals and the coordinate axes.
pub(super) fn hull_gap(a: &CubicSegment, b: &CubicSegment) -> f64 {
    hull_gap_of((a, &PieceHull::of(a)), (b, &PieceHull::of(b)))
}

/// What [`hull_gap`] reads of one piece alone: its Bézier points' ranges along the coordinate
/// axes and along its own chord normal, and their centroid. A leaf's piece is in several leaf
/// pairs, whose hull tests then share it ([`hull_gap_of`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PieceHull {
    x: (f64, f64),
    y: (f64, f64),
    centre: DVec2,
    /// The chord normal (not normalised) and the range of the projections on it.
    normal: (DVec2, (f64, f64)),
}

impl PieceHull {
    /// What the hull tests read of `piece` alone. Inlined: called, it returned its 80 bytes on
    /// the stack and the narrow phase's placed pieces copied them in (with the copy below it
    /// removed, 0.12 M of the landing pile of 100 blobs' 23.3 M instructions a step).
    #[inline]
    pub(crate) fn of(piece: &CubicSegment) -> Self {
        let normal = chord_normal(piece);
        Self {
            x: range4(&piece.bezier.map(|p| p.x)),
            y: range4(&piece.bezier.map(|p| p.y)),
            centre: bezier_centroid(piece),
            normal: (normal, range4(&piece.bezier.map(|p| p.dot(normal)))),
        }
    }
}

/// [`hull_gap`] of two pieces with their [`PieceHull`]s: the same operations on the same
/// numbers, so the same bits.
pub(crate) fn hull_gap_of((a, hull_a): (&CubicSegment, &PieceHull), (b, hull_b): (&CubicSegment, &PieceHull)) -> f64 {
    // The coordinate axes need no products and no normalisation.
    let mut gap = ranges_gap(hull_a.x, hull_b.x).max(ranges_gap(hull_a.y, hull_b.y)).max(0.0);
    let project = |piece: &CubicSegment, axis: DVec2| range4(&piece.bezier.map(|p| p.dot(axis)));
    // The centre line, then each chord normal (oblique_axes' order), with the ranges of the
    // pieces' own normals as they were worked out.
    let centre_line = hull_b.centre - hull_a.centre;
    let oblique = [
        (centre_line, project(a, centre_line), project(b, centre_line)),
        (hull_a.normal.0, hull_a.normal.1, project(b, hull_a.normal.0)),
        (hull_b.normal.0, project(a, hull_b.normal.0), hull_b.normal.1),
    ];
    for (axis, range_a, range_b) in oblique {
        // Projections on the unnormalised axis scale the gap by |axis|: only a gap larger
        // than the best so far needs the square root (overlapping hulls, the common case deep
        // in a search, skip it).
        let scaled = ranges_gap(range_a, range_b);
        if scaled > 0.0 && scaled * scaled > gap * gap * axis.length_squared() {
            let length = axis.length();
            if length > 0.0 && length.is_finite() {
                gap = gap.max(scaled / length);
            }
        }
    }
    gap
}

/// The axes of [`hull_gap`] besides the coordinate axes (not normalised): the line between the
/// pieces' Bézier centroids and the two chord normals.
pub(super) fn oblique_axes(a: &CubicSegment, b: &CubicSegment) -> [DVec2; 3] {
    [bezier_centroid(b) - bezier_centroid(a), chord_normal(a), chord_normal(b)]
}

/// The mean of a piece's Bézier points.
fn bezier_centroid(piece: &CubicSegment) -> DVec2 {
    let [b0, b1, b2, b3] = piece.bezier;
    0.25 * (b0 + b1 + b2 + b3)
}

/// A piece's chord turned a quarter counter-clockwise (not normalised).
fn chord_normal(piece: &CubicSegment) -> DVec2 {
    (piece.bezier[3] - piece.bezier[0]).perp()
}

/// Number of axes [`separating_axes`] tries.
pub const SEPARATING_AXES: usize = 6;

/// The pieces' gaps along the axes of `hull_gap` (the centre line, the two chord normals and
/// the coordinate axes) and along the direction between their nearest points
/// (`nearest_direction`), each between the pieces' exact projections on that fixed world
/// axis: `(unit axis, gap)`, the axis oriented from A's side to B's (B's projection lies beyond
/// A's by `gap`), the gap ≤ 0 where the axis does not separate them. Unlike a distance bound, a
/// gap along a fixed axis closes only as fast as A moves towards B along it, `(v_A − v_B)·axis`,
/// which conservative advancement uses for pieces that slide past each other or move apart.
#[must_use]
pub fn separating_axes(a: &CubicSegment, b: &CubicSegment) -> [(DVec2, f64); SEPARATING_AXES] {
    let [centre_line, normal_a, normal_b, x, y] = hull_separating_axes(a, b);
    [centre_line, normal_a, normal_b, x, y, nearest_separating_axis(a, b)]
}

/// The first five of [`separating_axes`]: the hull test's axes, without Newton.
pub(crate) fn hull_separating_axes(a: &CubicSegment, b: &CubicSegment) -> [(DVec2, f64); SEPARATING_AXES - 1] {
    hull_axes(a, b).map(|axis| gap_along(a, b, axis))
}

/// The axes of [`hull_separating_axes`], not normalised, in its order: the gap along each is
/// [`gap_along`]'s, which a caller that needs only some of them works out one by one.
pub(crate) fn hull_axes(a: &CubicSegment, b: &CubicSegment) -> [DVec2; SEPARATING_AXES - 1] {
    let [centre_line, normal_a, normal_b] = oblique_axes(a, b);
    [centre_line, normal_a, normal_b, DVec2::X, DVec2::Y]
}

/// The last of [`separating_axes`]: along the direction towards the nearest points (four
/// Newton steps: in a landing pile, 60 % of what the other five cost together).
pub(crate) fn nearest_separating_axis(a: &CubicSegment, b: &CubicSegment) -> (DVec2, f64) {
    gap_along(a, b, nearest_direction(a, b))
}

/// `(unit axis, gap)` of [`separating_axes`] along `axis` (not normalised).
pub(crate) fn gap_along(a: &CubicSegment, b: &CubicSegment, axis: DVec2) -> (DVec2, f64) {
    let Some(axis) = axis.try_normalize() else { return (DVec2::ZERO, f64::NEG_INFINITY) };
    let (a_low, a_high) = a.projection_range(axis);
    let (b_low, b_high) = b.projection_range(axis);
    // Oriented from A's side to B's: the gap closes at `(v_A − v_B)·axis`.
    if b_low - a_high >= a_low - b_high { (axis, b_low - a_high) } else { (-axis, a_low - b_high) }
}

/// The direction from A's piece to B's between the points Newton reaches from the pieces'
/// middles in at most [`AXIS_NEWTON_STEPS`] steps: about the direction of their nearest points.
/// Where two pieces face each other with their bulges (two convex bodies), their exact
/// projections on it are apart by about their distance, while the hull's axes can all fail: a
/// piece of a 0.1 m blob 4 cm long bulges 2 mm off its chord, as much as the band. Sliding past
/// each other at a few m/s, such pieces then bounded the sub-step by their full speed (a third
/// of a landing pile's sub-steps, docs/performance.md). Any axis is a valid one: a poor one only
/// separates less.
fn nearest_direction(a: &CubicSegment, b: &CubicSegment) -> DVec2 {
    let settings = CurvePairSettings { max_newton_iterations: AXIS_NEWTON_STEPS, ..CurvePairSettings::default() };
    let found = minimize_distance(a, b, DVec2::splat(0.5), ParamBox::UNIT, &settings, RoundingFloor::Stop);
    b.position(found.x.y) - a.position(found.x.x)
}

/// Newton steps towards the nearest points for [`nearest_direction`]: in a landing pile two
/// steps gave 196 sub-steps over 20 steps, four 191, eight and the exact direction 187 (a
/// scratch count; 226 without the axis).
const AXIS_NEWTON_STEPS: u32 = 4;

/// Gap between two ranges `(low, high)` (negative when they overlap).
fn ranges_gap((a_low, a_high): (f64, f64), (b_low, b_high): (f64, f64)) -> f64 {
    let forward = b_low - a_high;
    let backward = a_low - b_high;
    if forward > backward { forward } else { backward }
}

/// Smallest and largest of four finite values, by plain comparisons.
pub(super) fn range4(v: &[f64; 4]) -> (f64, f64) {
    let (low01, high01) = if v[0] < v[1] { (v[0], v[1]) } else { (v[1], v[0]) };
    let (low23, high23) = if v[2] < v[3] { (v[2], v[3]) } else { (v[3], v[2]) };
    (if low01 < low23 { low01 } else { low23 }, if high01 > high23 { high01 } else { high23 })
}

pub(super) fn bezier_diagonal(piece: &CubicSegment) -> f64 {
    let low = piece.bezier.iter().copied().fold(DVec2::splat(f64::INFINITY), DVec2::min);
    let high = piece.bezier.iter().copied().fold(DVec2::splat(f64::NEG_INFINITY), DVec2::max);
    (high - low).length()
}

/// Size of a piece pair: the larger control-box diagonal (lengths in the settings scale by it).
#[must_use]
pub fn pair_scale(a: &CubicSegment, b: &CubicSegment) -> f64 {
    bezier_diagonal(a).max(bezier_diagonal(b))
}

pub(super) fn closest_at(a: &CubicSegment, b: &CubicSegment, x: DVec2, newton_iterations: u32) -> ClosestPoints {
    let point_a = a.position(x.x);
    let point_b = b.position(x.y);
    ClosestPoints { t: x.x, s: x.y, point_a, point_b, distance: point_a.distance(point_b), newton_iterations }
}
