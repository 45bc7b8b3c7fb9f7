//! What each peer engine is given for a rugosa body: its natural exact shape where it has one,
//! else polygons within a stated tolerance of the spline, cut to the engine's limits.

use glam::DVec2;
use rugosa::{BodyDesc, Spline, recentre};

use crate::polygon::{SplinePolygon, convex_hull, fan_decomposition, from_parameters, polygon_within};

/// A body's shape as the peers know it exactly (rugosa's spline only approximates it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Natural {
    /// A circle of this radius (m), centred on the body's origin.
    Circle {
        /// Radius (m).
        radius: f64,
    },
    /// A rectangle of half-extents `half` (m) with corners rounded at `radius` (m).
    RoundedBox {
        /// Half width and half height (m), corners included.
        half: DVec2,
        /// Corner radius (m); 0 for a sharp box.
        radius: f64,
    },
}

/// Which shapes a peer gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeChoice {
    /// Polygon tolerance relative to the scene's body size.
    pub relative: f64,
    /// Use circles where a body is a circle (a rounded box is always given as one: it is the
    /// engine's rounded polygon and exact at any tolerance).
    pub circles: bool,
}

impl ShapeChoice {
    /// Polygons at `relative` for everything but rounded boxes.
    #[must_use]
    pub const fn polygon(relative: f64) -> Self {
        Self { relative, circles: false }
    }

    /// Exact circles, and polygons at `relative` for every other curve.
    #[must_use]
    pub const fn natural(relative: f64) -> Self {
        Self { relative, circles: true }
    }

    /// Short label for tables: "exact shape" or "polygon 1e-4".
    #[must_use]
    pub fn label(self) -> String {
        if self.circles { "exact shape".to_owned() } else { format!("polygon {:.0e}", self.relative) }
    }
}

/// What an engine cannot take, so the shape is cut to fit.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Shortest polygon edge the engine keeps (m); shorter edges are welded by the engine, so the
    /// polygon is thinned to this first and its bound recomputed.
    pub min_edge: f64,
    /// Shortest edge of a static loop (m).
    pub min_loop_edge: f64,
    /// Most vertices of one convex piece.
    pub max_vertices: usize,
    /// Least distance (m) of a piece's vertex from the line of its neighbours that the engine
    /// keeps (it merges nearly collinear vertices): pieces that would lose a vertex are cut
    /// into triangles from the kernel.
    pub min_bulge: f64,
}

impl Limits {
    /// No limits (rapier).
    pub const NONE: Self = Self { min_edge: 0.0, min_loop_edge: 0.0, max_vertices: usize::MAX, min_bulge: 0.0 };
}

/// The geometry handed to an engine, about the body's centre of mass.
#[derive(Clone, Debug)]
pub enum Geometry {
    /// An exact circle.
    Circle(f64),
    /// An exact rounded box: half-extents of the inner box and the corner radius.
    RoundedBox {
        /// Half-extents of the box whose corners are rounded (m), radius excluded.
        inner: DVec2,
        /// Corner radius (m).
        radius: f64,
    },
    /// Convex pieces (counter-clockwise) whose union is the body.
    Pieces(Vec<Vec<DVec2>>),
    /// A polygon that is not star-shaped about its generator's centre (rapier decomposes it by
    /// VHACD; other engines are not given such bodies).
    Decompose(Vec<DVec2>),
    /// A closed loop (static bodies): counter-clockwise vertices.
    Loop(Vec<DVec2>),
}

/// How one body was given to an engine.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShapeStats {
    /// Polygon vertices (0 for an exact shape).
    pub vertices: usize,
    /// Convex pieces (1 for an exact or convex shape).
    pub pieces: usize,
    /// Verified bound of the Hausdorff distance between the engine's shape and the spline (m);
    /// 0 for an exact shape (measured against the shape the spline approximates).
    pub hausdorff: f64,
    /// Whether an approximate decomposition (VHACD) had to be used.
    pub vhacd: bool,
}

/// A body for an engine: its centroid in the spline's frame, its geometry about it, the stats.
#[derive(Clone, Debug)]
pub struct PeerShape {
    /// The spline's centroid in its own frame: the engine's body origin sits there.
    pub centroid: DVec2,
    /// The geometry, about the centroid.
    pub geometry: Geometry,
    /// How it was built.
    pub stats: ShapeStats,
}

/// The shape of `desc` for an engine with `limits`, at `tolerance` (m) where polygons are used.
#[must_use]
pub fn peer_shape(
    desc: &BodyDesc,
    natural: Option<Natural>,
    choice: ShapeChoice,
    tolerance: f64,
    limits: Limits,
) -> PeerShape {
    let (spline, centroid) = recentre(&desc.spline);
    let exact = |geometry| PeerShape { centroid, geometry, stats: ShapeStats { pieces: 1, ..ShapeStats::default() } };
    match natural {
        // Natural shapes are centred on the spline's frame origin, which is (to rounding) the
        // centroid of these symmetric curves.
        Some(Natural::RoundedBox { half, radius }) => {
            return exact(Geometry::RoundedBox { inner: half - DVec2::splat(radius), radius });
        }
        Some(Natural::Circle { radius }) if choice.circles => return exact(Geometry::Circle(radius)),
        _ => {}
    }
    let polygon = polygon_within(&spline, tolerance);
    if desc.is_static {
        let polygon = thinned(&spline, polygon, None, limits.min_loop_edge, 0.0);
        let stats = stats(&polygon, 1, false);
        return PeerShape { centroid, geometry: Geometry::Loop(polygon.vertices), stats };
    }
    // A convex body is cut (where the engine needs it) about its centroid, a blob about the
    // curve's frame origin, where generators centre their shapes: blobs are star-shaped about it.
    let convex = convex_hull(&spline, &polygon).is_some_and(|h| h.hausdorff <= tolerance);
    let kernel = if convex { DVec2::ZERO } else { -centroid };
    let polygon = thinned(&spline, polygon, Some(kernel), limits.min_edge, limits.min_bulge);
    if convex && let Some(hull) = convex_hull(&spline, &polygon) {
        let pieces = fit(vec![hull.vertices.clone()], kernel, limits);
        let stats = stats(&hull, pieces.len(), false);
        return PeerShape { centroid, geometry: Geometry::Pieces(pieces), stats };
    }
    if let Some(pieces) = fan_decomposition(&polygon.vertices, kernel) {
        let pieces = fit(pieces, kernel, limits);
        let stats = stats(&polygon, pieces.len(), false);
        return PeerShape { centroid, geometry: Geometry::Pieces(pieces), stats };
    }
    let stats = stats(&polygon, 0, true);
    PeerShape { centroid, geometry: Geometry::Decompose(polygon.vertices), stats }
}

fn stats(polygon: &SplinePolygon, pieces: usize, vhacd: bool) -> ShapeStats {
    ShapeStats { vertices: polygon.vertices.len(), pieces, hausdorff: polygon.hausdorff, vhacd }
}

/// The polygon with vertices dropped (greedy along the curve) until every edge is at least
/// `min_edge` long and, with a `kernel`, every triangle of the fan from it has each vertex at
/// least `min_bulge` off the line of the other two; its bound recomputed. Unchanged when
/// nothing is to be dropped.
fn thinned(
    spline: &Spline,
    polygon: SplinePolygon,
    kernel: Option<DVec2>,
    min_edge: f64,
    min_bulge: f64,
) -> SplinePolygon {
    let v = &polygon.vertices;
    let fat = |a: DVec2, b: DVec2| {
        a.distance(b) >= min_edge
            && kernel.is_none_or(|k| {
                let twice_area = (a - k).perp_dot(b - k).abs();
                twice_area >= min_bulge * (a - k).length().max((b - k).length()).max(a.distance(b))
            })
    };
    let mut kept: Vec<usize> = vec![0];
    for i in 1..v.len() {
        if fat(v[*kept.last().expect("non-empty")], v[i]) {
            kept.push(i);
        }
    }
    while kept.len() > 3 && !fat(v[*kept.last().expect("non-empty")], v[0]) {
        kept.pop();
    }
    if kept.len() == v.len() {
        return polygon;
    }
    from_parameters(spline, kept.iter().map(|&i| polygon.parameters[i]).collect())
}

/// Convex pieces cut to at most `limits.max_vertices` vertices, with no vertex the engine
/// would merge. A piece that does not fit is cut into the fan from `kernel` (a vertex of fan
/// pieces, inside a convex body's hull), whose consecutive triangles are joined again while
/// the result fits; the thinning made every triangle fit.
fn fit(pieces: Vec<Vec<DVec2>>, kernel: DVec2, limits: Limits) -> Vec<Vec<DVec2>> {
    let mut out = Vec::new();
    for piece in pieces {
        if fits(&piece, limits) {
            out.push(piece);
            continue;
        }
        let centre = kernel;
        let walk = if piece[0] == kernel {
            piece[1..].to_vec()
        } else {
            let mut walk = piece.clone();
            walk.push(piece[0]);
            walk
        };
        let close = |chain: &[DVec2]| {
            let mut done = Vec::with_capacity(chain.len() + 1);
            done.push(centre);
            done.extend_from_slice(chain);
            done
        };
        let mut chain = vec![walk[0]];
        for &next in &walk[1..] {
            if chain.len() >= 2 {
                let mut candidate = close(&chain);
                candidate.push(next);
                if !fits(&candidate, limits) {
                    out.push(close(&chain));
                    chain = vec![*chain.last().expect("non-empty")];
                }
            }
            chain.push(next);
        }
        out.push(close(&chain));
    }
    out
}

/// Whether a convex piece has few enough vertices and every vertex off its neighbours' line.
fn fits(piece: &[DVec2], limits: Limits) -> bool {
    let m = piece.len();
    m <= limits.max_vertices
        && (0..m).all(|i| {
            let (a, b, c) = (piece[(i + m - 1) % m], piece[i], piece[(i + 1) % m]);
            let base = c - a;
            base.length() > 0.0 && (b - a).perp_dot(base).abs() / base.length() > limits.min_bulge
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rugosa::{Generator, Rugosity};

    fn area(piece: &[DVec2]) -> f64 {
        let m = piece.len();
        0.5 * (0..m).map(|i| piece[i].perp_dot(piece[(i + 1) % m])).sum::<f64>()
    }

    #[test]
    fn pieces_cut_for_box2d_keep_the_area_and_the_limits() {
        let spline = Generator::Ellipse { a: 0.6, b: 0.3 }.build(32).unwrap();
        let desc = BodyDesc::new(spline.clone(), Rugosity::constant(32, 0.0).unwrap());
        let limits = Limits { min_edge: 0.0202, min_loop_edge: 0.00505, max_vertices: 8, min_bulge: 0.0101 };
        let shape = peer_shape(&desc, None, ShapeChoice::polygon(1e-3), 1.2e-3, limits);
        let Geometry::Pieces(pieces) = &shape.geometry else { panic!("pieces") };
        let total: f64 = pieces.iter().map(|p| area(p)).sum();
        let (recentred, _) = recentre(&spline);
        let polygon = thinned(&recentred, polygon_within(&recentred, 1.2e-3), Some(DVec2::ZERO), 0.0202, 0.0101);
        assert!((total - area(&polygon.vertices)).abs() < 1e-12, "{total}");
        assert!(pieces.iter().all(|p| fits(p, limits) && area(p) > 0.0));
        assert!(polygon.vertices.windows(2).all(|w| w[0].distance(w[1]) >= 0.0202));
    }
}
