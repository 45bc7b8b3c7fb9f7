//! Augmented oriented bounding-box tree over a boundary's segments, and tree-against-tree
//! traversal (MODEL §3).
//!
//! # Layout
//! A flat `Vec` of nodes: the `n` leaves first, leaf `i` holding segment `i` (so a leaf's node index
//! is its segment index), then the branches level by level; the root is the last node. Each level
//! pairs adjacent boxes `(2k, 2k+1)` of the level below; an odd last box is carried up unchanged
//! (it gets no new node), so there are always `2n − 1` nodes.
//!
//! # Orientation of branch boxes
//! A branch at tree level `ℓ` covers leaves `[k·2^ℓ, min((k+1)·2^ℓ, n))`. Its axis is the principal
//! axis of [`COVARIANCE_SAMPLES`] points sampled over the same stretch of the level-`ℓ`
//! multiresolution curve (ℓ steps of [`reverse_subdivide`], available while the control-point count
//! is even and ≥ 8). Which parameter range of the coarse curve matches a stretch of the original
//! curve is measured, not assumed: see [`MultiresolutionLadder`]. Where no level-`ℓ` curve exists,
//! or its samples are isotropic, the axis is the principal axis of the children's corners. The
//! extents always come from the children's corners, so a branch encloses its children whatever
//! the axis.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::geometry::multiresolution::reverse_subdivide;
use crate::geometry::obb::{COVARIANCE_SAMPLES, Obb, principal_axis};
use crate::geometry::pose::Pose;
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;

mod validate;

/// Largest shift, in fine-segment units, tried when aligning a coarse curve with its fine curve.
pub const MAX_ALIGNMENT_SHIFT: i64 = 3;

/// Samples per coarse segment used to measure the alignment of a coarse curve.
const ALIGNMENT_SAMPLES_PER_SEGMENT: usize = 4;

/// Dense samples per segment used by [`AobbTree::validate`] for the band-containment check.
pub const VALIDATION_SAMPLES_PER_SEGMENT: usize = 64;

/// Relative slack (of the root box's size and distance from the origin) allowed by
/// [`AobbTree::validate`] for rounding.
pub const VALIDATION_RELATIVE_SLACK: f64 = 1e-10;

/// What a node holds: a segment (leaf) or two child nodes (branch).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AobbNodeKind {
    /// An elementary box around one segment.
    Leaf {
        /// The segment index.
        segment: u32,
    },
    /// A box around two child boxes.
    Branch {
        /// Node indices of the two children, in segment order.
        children: [u32; 2],
    },
}

/// One node of an [`AobbTree`]: its box (body frame), content, and the segments below it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AobbNode {
    /// The box, in the body frame.
    pub obb: Obb,
    /// Leaf or branch.
    pub kind: AobbNodeKind,
    /// First segment below this node.
    pub first_segment: u32,
    /// Number of consecutive segments below this node.
    pub segment_count: u32,
}

/// Augmented oriented bounding-box tree of one boundary (MODEL §3), in the body frame.
///
/// Boxes do not move with the body: callers pass the pose to queries, which transform boxes on
/// the fly, so the tree is built once per shape and rugosity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AobbTree {
    nodes: Vec<AobbNode>,
    leaf_count: u32,
    depth: u32,
    /// The band floor the leaves were fattened with: queries of this tree use it too.
    floor: f64,
}

/// Scratch memory of [`AobbTree::overlapping_leaves`]: keep one and reuse it so steady-state
/// traversals allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct TraversalWorkspace {
    stack: Vec<(u32, u32)>,
}

impl TraversalWorkspace {
    /// An empty workspace; it grows to the largest stack it has needed and keeps that memory.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Entries the stack holds without growing.
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.stack.capacity()
    }

    /// Grows the stack to hold at least `capacity` entries.
    pub fn reserve(&mut self, capacity: usize) {
        self.stack.reserve_exact(capacity.saturating_sub(self.stack.len()));
    }
}

/// Work done by one traversal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalCounters {
    /// Box-pair overlap tests made.
    pub box_tests: usize,
    /// Leaf pairs reported.
    pub leaf_pairs: usize,
}

impl std::ops::AddAssign for TraversalCounters {
    fn add_assign(&mut self, other: Self) {
        self.box_tests += other.box_tests;
        self.leaf_pairs += other.leaf_pairs;
    }
}

impl AobbTree {
    /// Builds the tree of `spline` with tolerance band `rugosity`, floored at `floor` (the minimum
    /// band of smooth surfaces).
    ///
    /// # Panics
    /// If the rugosity does not have one tolerance per segment, or the curve has more than
    /// `u32::MAX / 2` segments.
    #[must_use]
    pub fn build(spline: &Spline, rugosity: &Rugosity, floor: f64) -> Self {
        let leaf_count = spline.segment_count();
        assert_eq!(rugosity.tolerances().len(), leaf_count, "one rugosity tolerance per segment");
        assert!(leaf_count <= (u32::MAX / 2) as usize, "too many segments for u32 node indices");
        let ladder = MultiresolutionLadder::analyse(spline);
        let mut nodes = elementary_nodes(spline, rugosity, floor);
        let mut level: Vec<u32> = (0..leaf_count as u32).collect();
        let mut depth = 0;
        while level.len() > 1 {
            depth += 1;
            level = pair_level(&mut nodes, &level, depth, &ladder);
        }
        debug_assert_eq!(nodes.len(), 2 * leaf_count - 1);
        debug_assert_eq!(level.first().copied(), Some(nodes.len() as u32 - 1));
        Self { nodes, leaf_count: leaf_count as u32, depth, floor }
    }

    /// The band floor the tree was built with (`floor` of [`AobbTree::build`]): a tree query
    /// floors this body's tolerances at it, so tree and query can never disagree.
    #[must_use]
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// All nodes: leaves `0..leaf_count` (leaf `i` holds segment `i`), then branches; root last.
    #[must_use]
    pub fn nodes(&self) -> &[AobbNode] {
        &self.nodes
    }

    /// The root node (whose box holds the whole boundary and its band).
    #[must_use]
    pub fn root(&self) -> &AobbNode {
        self.nodes.last().expect("a tree has at least one node")
    }

    /// Index of the root node.
    #[must_use]
    pub fn root_index(&self) -> u32 {
        self.nodes.len() as u32 - 1
    }

    /// The elementary box of segment `segment`, in the body frame.
    #[must_use]
    pub fn leaf_box(&self, segment: usize) -> &Obb {
        &self.nodes[segment].obb
    }

    /// Number of leaves (= segments).
    #[must_use]
    pub fn leaf_count(&self) -> usize {
        self.leaf_count as usize
    }

    /// Number of pairing levels above the leaves (`⌈log₂ n⌉`); the root is at this level.
    #[must_use]
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Leaf pairs `(segment of self, segment of other)` whose elementary boxes overlap, with
    /// `self` placed at `pose_self` and `other` at `pose_other`.
    ///
    /// Simultaneous descent of both trees in the frame of `self` (`other`'s boxes are moved by the
    /// relative pose, one transform per test); non-overlapping pairs are pruned; of two branches the
    /// one with the larger box (half-diagonal) is descended. `out` is cleared, then filled in
    /// lexicographic order, whatever the descent order. `workspace` holds the stack: reuse it and the
    /// call allocates nothing once `out` and the stack have grown.
    pub fn overlapping_leaves(
        &self,
        pose_self: &Pose,
        other: &AobbTree,
        pose_other: &Pose,
        workspace: &mut TraversalWorkspace,
        out: &mut Vec<(u32, u32)>,
    ) -> TraversalCounters {
        self.overlapping_leaves_within(pose_self, other, pose_other, 0.0, workspace, out)
    }

    /// As [`AobbTree::overlapping_leaves`], with every box of `self` fattened by `margin ≥ 0`:
    /// the leaf pairs whose boxes come within `margin` of each other. Pairs left out are more
    /// than `margin` apart, which is what conservative advancement needs.
    pub fn overlapping_leaves_within(
        &self,
        pose_self: &Pose,
        other: &AobbTree,
        pose_other: &Pose,
        margin: f64,
        workspace: &mut TraversalWorkspace,
        out: &mut Vec<(u32, u32)>,
    ) -> TraversalCounters {
        out.clear();
        let box_tests =
            self.visit_leaves_within(pose_self, other, pose_other, margin, workspace, |pair| out.push(pair));
        out.sort_unstable();
        TraversalCounters { box_tests, leaf_pairs: out.len() }
    }

    /// The descent of [`AobbTree::overlapping_leaves_within`], handing each leaf pair found to
    /// `visit` (in the descent's order); returns the box tests.
    pub(crate) fn visit_leaves_within(
        &self,
        pose_self: &Pose,
        other: &AobbTree,
        pose_other: &Pose,
        margin: f64,
        workspace: &mut TraversalWorkspace,
        mut visit: impl FnMut((u32, u32)),
    ) -> usize {
        debug_assert!(margin >= 0.0, "margin must be non-negative");
        let other_to_self = pose_self.relative(pose_other);
        // A leaf's box fattened along its own axes by `m` lies within `m √2` of the box, and so
        // within its branch's box fattened along the branch's axes by `m √2`: a branch of `self`
        // tested with that margin is pruned only where none of its leaves passes the leaf test,
        // so the descent lists exactly the pairs the leaf test passes (a kept front, filtered by
        // that test, lists the same). `other`'s boxes are not fattened: a branch holds its leaves.
        let branch_margin = margin * std::f64::consts::SQRT_2;
        let mut box_tests = 0;
        let stack = &mut workspace.stack;
        stack.clear();
        stack.push((self.root_index(), other.root_index()));
        while let Some((a, b)) = stack.pop() {
            box_tests += 1;
            let node_a = &self.nodes[a as usize];
            let node_b = &other.nodes[b as usize];
            let margin = if matches!(node_a.kind, AobbNodeKind::Leaf { .. }) { margin } else { branch_margin };
            if !within(&node_a.obb, &node_b.obb, &other_to_self, margin) {
                continue;
            }
            if let Some(pair) = push_child_pairs(stack, (a, node_a), (b, node_b)) {
                visit(pair);
            }
        }
        box_tests
    }

    /// Of `candidates` (pairs of a segment of `self` and one of `other`), in order, those whose
    /// elementary boxes come within `margin` of each other: the leaf test of
    /// [`AobbTree::overlapping_leaves_within`], without the descent. Returns the box tests.
    pub fn leaf_pairs_within(
        &self,
        pose_self: &Pose,
        other: &AobbTree,
        pose_other: &Pose,
        margin: f64,
        candidates: &[(u32, u32)],
        out: &mut Vec<(u32, u32)>,
    ) -> usize {
        let other_to_self = pose_self.relative(pose_other);
        out.clear();
        // The leaf test of a descent (`within`) in its two halves: the candidates run over a few
        // of `other`'s leaves for each of `self`'s, so the last few of `other`'s boxes moved into
        // `self`'s frame are kept, by index, and A's box is fattened once a leaf; each with the
        // reach of its centre that the overlap test scales its slack by (kept as `Option`s, and
        // the reaches worked out at every test, cost the landing piles of 100 and 500 blobs 0.1 M
        // and 0.29 M instructions a step).
        let mut moved = [KeptBox::EMPTY; MOVED_LEAVES];
        let mut fattened = KeptBox::EMPTY;
        for &(i, j) in candidates {
            if fattened.leaf != i {
                fattened = KeptBox::new(i, self.leaf_box(i as usize).fattened(margin));
            }
            let b = &mut moved[j as usize % MOVED_LEAVES];
            if b.leaf != j {
                *b = KeptBox::new(j, other.leaf_box(j as usize).transformed(&other_to_self));
            }
            if fattened.obb.overlaps_reaching(&b.obb, (fattened.reach, b.reach)) {
                out.push((i, j));
            }
        }
        candidates.len()
    }

    /// How far the farthest corner of the root box lies from the body's origin: turning the
    /// body by `δθ` moves every box of the tree by at most this times `δθ`.
    #[must_use]
    pub fn reach(&self) -> f64 {
        self.root().obb.corners().iter().map(|c| c.length()).fold(0.0, f64::max)
    }
}

/// How many of the other tree's leaf boxes [`AobbTree::leaf_pairs_within`] keeps moved into
/// this tree's frame.
const MOVED_LEAVES: usize = 8;

/// A leaf box [`AobbTree::leaf_pairs_within`] keeps for the candidates that follow: the leaf,
/// its box as the leaf test reads it (fattened or moved) and that box's
/// [`Obb::centre_reach`].
#[derive(Clone, Copy)]
struct KeptBox {
    /// The segment, [`KeptBox::EMPTY`]'s `u32::MAX` before any (no tree has that many).
    leaf: u32,
    obb: Obb,
    reach: f64,
}

impl KeptBox {
    /// A place that holds no box yet.
    const EMPTY: Self = Self {
        leaf: u32::MAX,
        obb: Obb { centre: DVec2::ZERO, axis: DVec2::X, half_extents: DVec2::ZERO },
        reach: 0.0,
    };

    fn new(leaf: u32, obb: Obb) -> Self {
        Self { leaf, obb, reach: obb.centre_reach() }
    }
}

/// The box test of a descent: whether `a` (in A's frame), fattened by `margin`, overlaps `b`
/// (in B's frame, `b_to_a` taking it to A's).
fn within(a: &Obb, b: &Obb, b_to_a: &Pose, margin: f64) -> bool {
    a.fattened(margin).overlaps(&b.transformed(b_to_a))
}

/// After an overlapping pair: returns a leaf pair, or pushes the pairs of the node to descend
/// (left child popped first).
fn push_child_pairs(stack: &mut Vec<(u32, u32)>, a: (u32, &AobbNode), b: (u32, &AobbNode)) -> Option<(u32, u32)> {
    let descend_a = match (a.1.kind, b.1.kind) {
        (AobbNodeKind::Leaf { segment: sa }, AobbNodeKind::Leaf { segment: sb }) => return Some((sa, sb)),
        (AobbNodeKind::Branch { .. }, AobbNodeKind::Leaf { .. }) => true,
        (AobbNodeKind::Leaf { .. }, AobbNodeKind::Branch { .. }) => false,
        (AobbNodeKind::Branch { .. }, AobbNodeKind::Branch { .. }) => {
            a.1.obb.half_extents.length_squared() >= b.1.obb.half_extents.length_squared()
        }
    };
    match (descend_a, a.1.kind, b.1.kind) {
        (true, AobbNodeKind::Branch { children: [left, right] }, _) => {
            stack.extend([(right, b.0), (left, b.0)]);
        }
        (false, _, AobbNodeKind::Branch { children: [left, right] }) => {
            stack.extend([(a.0, right), (a.0, left)]);
        }
        _ => unreachable!("only a branch is descended"),
    }
    None
}

/// Level 0: one elementary box per segment, fattened by the floored maximum of λ on the segment.
fn elementary_nodes(spline: &Spline, rugosity: &Rugosity, floor: f64) -> Vec<AobbNode> {
    let mut nodes = Vec::with_capacity(2 * spline.segment_count() - 1);
    nodes.extend(spline.segments().enumerate().map(|(i, segment)| {
        let band = rugosity.max_on_segment(i).max(floor);
        AobbNode {
            obb: Obb::around_segment(&segment, band),
            kind: AobbNodeKind::Leaf { segment: i as u32 },
            first_segment: i as u32,
            segment_count: 1,
        }
    }));
    nodes
}

/// Pairs the nodes of one level `(2k, 2k+1)` into new nodes at `tree_level`; an odd last node is
/// carried up as it is. Returns the next level's node indices.
fn pair_level(nodes: &mut Vec<AobbNode>, level: &[u32], tree_level: u32, ladder: &MultiresolutionLadder) -> Vec<u32> {
    level
        .chunks(2)
        .map(|pair| match *pair {
            [left, right] => {
                let parent = enclosing_node(nodes, [left, right], tree_level, ladder);
                nodes.push(parent);
                nodes.len() as u32 - 1
            }
            [carried] => carried,
            _ => unreachable!("chunks(2) yields one or two nodes"),
        })
        .collect()
}

/// The branch over two adjacent nodes: axis from the multiresolution curve (else the children's
/// corners), extents from the children's corners.
fn enclosing_node(nodes: &[AobbNode], children: [u32; 2], tree_level: u32, ladder: &MultiresolutionLadder) -> AobbNode {
    let [left, right] = children.map(|c| &nodes[c as usize]);
    debug_assert_eq!(left.first_segment + left.segment_count, right.first_segment, "children must be adjacent");
    let first_segment = left.first_segment;
    let segment_count = left.segment_count + right.segment_count;
    let corners: [DVec2; 8] =
        std::array::from_fn(|k| if k < 4 { left.obb.corners()[k] } else { right.obb.corners()[k - 4] });
    let axis = ladder
        .axis_over(tree_level, first_segment as f64, (first_segment + segment_count) as f64)
        .or_else(|| principal_axis(&corners))
        .unwrap_or(DVec2::X);
    AobbNode { obb: Obb::fitted(axis, corners), kind: AobbNodeKind::Branch { children }, first_segment, segment_count }
}

/// One coarse curve of the multiresolution ladder and how its parameter maps to the original one.
#[derive(Clone, Debug)]
pub struct CoarseLevel {
    /// The coarse curve (unchecked: only used to orient boxes).
    pub curve: Spline,
    /// `o` in `u = 2^ℓ·v + o`: original parameter `u` of coarse parameter `v` (measured).
    pub offset: f64,
    /// RMS distance between the coarse curve and the finer one at the measured alignment.
    #[cfg_attr(not(test), expect(dead_code, reason = "a measurement the round-trip test reads"))]
    pub alignment_error: f64,
}

/// The coarse curves of a boundary by repeated [`reverse_subdivide`] (level ℓ has `n / 2^ℓ`
/// segments), with their measured alignment to the original parameter.
///
/// Alignment: for each step, the coarse curve `C` is compared with the finer curve `F` at
/// `F(2v + s)` for integer shifts `|s| ≤` [`MAX_ALIGNMENT_SHIFT`] (fine-segment units); the shift of
/// least RMS distance wins (ties go to the smaller `|s|`). With the Bartels–Samavati taps centred on
/// `f_{2i}` the measured shift is 0, i.e. coarse segment `i` spans fine segments `2i` and `2i+1`
/// (checked in the tests by a subdivide/analyse round trip), but the tree does not rely on that.
#[derive(Clone, Debug, Default)]
pub struct MultiresolutionLadder {
    /// `levels[ℓ − 1]` is multiresolution level `ℓ`.
    pub levels: Vec<CoarseLevel>,
}

impl MultiresolutionLadder {
    /// Analyses `spline` while the control-point count is even and at least 8.
    #[must_use]
    pub fn analyse(spline: &Spline) -> Self {
        let mut levels: Vec<CoarseLevel> = Vec::new();
        loop {
            let finer = levels.last().map_or(spline, |level| &level.curve);
            let Some((coarse, _details)) = reverse_subdivide(finer.control_points()) else { break };
            if coarse.iter().any(|c| !c.is_finite()) {
                break;
            }
            let curve = Spline::from_control_points_unchecked(coarse);
            let (shift, alignment_error) = alignment_shift(finer, &curve);
            let finer_scale = (1u64 << levels.len()) as f64;
            let finer_offset = levels.last().map_or(0.0, |level| level.offset);
            levels.push(CoarseLevel { curve, offset: finer_offset + finer_scale * shift as f64, alignment_error });
        }
        Self { levels }
    }

    /// Principal axis of the level-`level` curve sampled over the original parameter range
    /// `[u_start, u_end]`; `None` if that level does not exist or the samples are isotropic.
    #[must_use]
    pub fn axis_over(&self, level: u32, u_start: f64, u_end: f64) -> Option<DVec2> {
        let coarse = self.levels.get((level as usize).checked_sub(1)?)?;
        let scale = (1u64 << level) as f64;
        let (v_start, v_end) = ((u_start - coarse.offset) / scale, (u_end - coarse.offset) / scale);
        let last = (COVARIANCE_SAMPLES - 1) as f64;
        let samples: [DVec2; COVARIANCE_SAMPLES] =
            std::array::from_fn(|k| coarse.curve.position(v_start + (v_end - v_start) * k as f64 / last));
        principal_axis(&samples)
    }
}

/// The shift `s` (fine-segment units) minimising the RMS of `|C(v) − F(2v + s)|`, and that RMS.
fn alignment_shift(fine: &Spline, coarse: &Spline) -> (i64, f64) {
    (-MAX_ALIGNMENT_SHIFT..=MAX_ALIGNMENT_SHIFT)
        .map(|shift| (shift, alignment_mismatch(fine, coarse, shift)))
        .min_by(|x, y| x.1.total_cmp(&y.1).then(x.0.abs().cmp(&y.0.abs())))
        .expect("at least one shift is tried")
}

fn alignment_mismatch(fine: &Spline, coarse: &Spline, shift: i64) -> f64 {
    let samples = coarse.segment_count() * ALIGNMENT_SAMPLES_PER_SEGMENT;
    let sum: f64 = (0..samples)
        .map(|k| {
            let v = (k as f64 + 0.5) / ALIGNMENT_SAMPLES_PER_SEGMENT as f64;
            coarse.position(v).distance_squared(fine.position(2.0 * v + shift as f64))
        })
        .sum();
    (sum / samples as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::construct::Generator;
    use crate::geometry::multiresolution::subdivide;

    fn blob_tree(segments: usize) -> (Spline, Rugosity, AobbTree) {
        let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 3 }.build(segments).unwrap();
        let rugosity = Rugosity::constant(segments, 0.01).unwrap();
        let tree = AobbTree::build(&spline, &rugosity, 1e-3);
        (spline, rugosity, tree)
    }

    #[test]
    fn coarse_segment_i_spans_fine_segments_2i_and_2i_plus_1() {
        let spline = Generator::Blob { radius: 1.0, roughness: 0.5, seed: 9 }.build(16).unwrap();
        let fine = Spline::from_control_points_unchecked(subdivide(spline.control_points()));
        let ladder = MultiresolutionLadder::analyse(&fine);
        let first = &ladder.levels[0];
        assert!(first.alignment_error < 1e-12, "round trip error {}", first.alignment_error);
        assert_eq!(first.offset, 0.0, "reverse_subdivide alignment changed; the tree adapts, update the docs");
        assert_eq!(ladder.levels.len(), 3, "32 → 16 → 8 → 4");
    }

    #[test]
    fn validate_rejects_a_shrunken_leaf() {
        let (spline, rugosity, mut tree) = blob_tree(32);
        assert_eq!(tree.validate(&spline, &rugosity, 1e-3), Ok(()));
        tree.nodes[7].obb.half_extents *= 0.9;
        let error = tree.validate(&spline, &rugosity, 1e-3).unwrap_err();
        assert!(error.contains("segment 7") || error.contains("child 7"), "{error}");
    }

    #[test]
    fn validate_rejects_a_shrunken_branch_and_bad_links() {
        let (spline, rugosity, tree) = blob_tree(32);
        let mut shrunk = tree.clone();
        shrunk.nodes[40].obb.half_extents.x *= 0.95;
        assert!(shrunk.validate(&spline, &rugosity, 1e-3).unwrap_err().contains("outside"));
        let mut relinked = tree.clone();
        relinked.nodes[40].kind = AobbNodeKind::Branch { children: [0, 1] };
        assert!(relinked.validate(&spline, &rugosity, 1e-3).is_err());
        let mut nan = tree;
        nan.nodes[3].obb.centre.x = f64::NAN;
        assert!(nan.validate(&spline, &rugosity, 1e-3).unwrap_err().contains("non-finite"));
    }

    #[test]
    fn odd_counts_carry_the_last_box_up() {
        let (_, _, tree) = blob_tree(5);
        assert_eq!(tree.nodes().len(), 9);
        assert_eq!(tree.depth(), 3);
        // Level 1: (0,1) → 5, (2,3) → 6, 4 carried; level 2: (5,6) → 7, 4 carried; level 3: (7,4) → 8.
        assert_eq!(tree.root().kind, AobbNodeKind::Branch { children: [7, 4] });
    }
}
