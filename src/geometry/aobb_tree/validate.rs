//! The tree's own check of its structure and containment ([`AobbTree::validate`]), against the
//! curve it was built from.

use super::{AobbNode, AobbNodeKind, AobbTree, VALIDATION_RELATIVE_SLACK, VALIDATION_SAMPLES_PER_SEGMENT};
use crate::geometry::obb::Obb;
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;

impl AobbTree {
    /// Checks the structure and the containment at every level against the curve it was built from.
    ///
    /// Checks: node and leaf counts, leaf `i` holds segment `i`, children precede their parent and
    /// every node but the root has exactly one parent, segment spans are consistent, boxes are finite
    /// with unit axes and non-negative extents, children's corners lie in their parent, and dense
    /// samples of each segment, grown by the band λ (floored at `floor`) there, lie in its leaf.
    ///
    /// # Errors
    /// A message naming the first violated invariant and the node.
    pub fn validate(&self, spline: &Spline, rugosity: &Rugosity, floor: f64) -> Result<(), String> {
        self.validate_counts(spline.segment_count(), rugosity.tolerances().len())?;
        self.validate_links()?;
        self.validate_boxes()?;
        let slack = self.validation_slack();
        self.validate_nesting(slack)?;
        self.validate_bands(spline, rugosity, floor, slack)
    }

    fn validate_counts(&self, segments: usize, tolerances: usize) -> Result<(), String> {
        let leaves = self.leaf_count as usize;
        if leaves != segments || tolerances != segments {
            return Err(format!("tree has {leaves} leaves, curve {segments} segments, rugosity {tolerances} values"));
        }
        if self.nodes.len() != 2 * leaves - 1 {
            return Err(format!("{} nodes for {leaves} leaves, expected {}", self.nodes.len(), 2 * leaves - 1));
        }
        if leaves > 1 && self.depth != leaves.next_power_of_two().trailing_zeros() {
            return Err(format!("depth {} for {leaves} leaves", self.depth));
        }
        Ok(())
    }

    fn validate_links(&self) -> Result<(), String> {
        let leaves = self.leaf_count as usize;
        let mut parents = vec![0u32; self.nodes.len()];
        for (index, node) in self.nodes.iter().enumerate() {
            match node.kind {
                AobbNodeKind::Leaf { segment } => {
                    if index >= leaves || segment as usize != index || node.first_segment != segment {
                        return Err(format!("node {index}: leaf of segment {segment} out of place"));
                    }
                    if node.segment_count != 1 {
                        return Err(format!("node {index}: leaf spans {} segments", node.segment_count));
                    }
                }
                AobbNodeKind::Branch { children } => {
                    self.validate_branch_span(index, node, children)?;
                    children.iter().for_each(|&c| parents[c as usize] += 1);
                }
            }
        }
        let root = self.nodes.len() - 1;
        match parents.iter().enumerate().find(|&(i, &count)| count != u32::from(i != root)) {
            Some((i, count)) => Err(format!("node {i} has {count} parents")),
            None if self.root().segment_count != self.leaf_count => Err("root does not span every segment".into()),
            None => Ok(()),
        }
    }

    fn validate_branch_span(&self, index: usize, node: &AobbNode, children: [u32; 2]) -> Result<(), String> {
        if index < self.leaf_count as usize || children.iter().any(|&c| c as usize >= index) {
            return Err(format!("node {index}: branch with children {children:?} out of order"));
        }
        let [left, right] = children.map(|c| &self.nodes[c as usize]);
        let spans_join = left.first_segment + left.segment_count == right.first_segment;
        let span_matches =
            node.first_segment == left.first_segment && node.segment_count == left.segment_count + right.segment_count;
        if !(spans_join && span_matches) {
            return Err(format!("node {index}: segment span does not match children {children:?}"));
        }
        Ok(())
    }

    fn validate_boxes(&self) -> Result<(), String> {
        for (index, node) in self.nodes.iter().enumerate() {
            let Obb { centre, axis, half_extents } = node.obb;
            if !(centre.is_finite() && axis.is_finite() && half_extents.is_finite()) {
                return Err(format!("node {index}: non-finite box {:?}", node.obb));
            }
            if (axis.length() - 1.0).abs() > 1e-12 || half_extents.min_element() < 0.0 {
                return Err(format!("node {index}: bad axis or extents {:?}", node.obb));
            }
        }
        Ok(())
    }

    /// Rounding slack for containment: relative to the root box's size and distance from the origin.
    fn validation_slack(&self) -> f64 {
        let root = self.root().obb;
        VALIDATION_RELATIVE_SLACK * (root.half_extents.max_element() + root.centre.abs().max_element())
    }

    fn validate_nesting(&self, slack: f64) -> Result<(), String> {
        for (index, node) in self.nodes.iter().enumerate() {
            let AobbNodeKind::Branch { children } = node.kind else { continue };
            for child in children {
                let corners = self.nodes[child as usize].obb.corners();
                if let Some(corner) = corners.iter().find(|&&c| !node.obb.contains_point(c, slack)) {
                    return Err(format!("node {index}: corner {corner} of child {child} outside {:?}", node.obb));
                }
            }
        }
        Ok(())
    }

    fn validate_bands(&self, spline: &Spline, rugosity: &Rugosity, floor: f64, slack: f64) -> Result<(), String> {
        for (segment_index, segment) in spline.segments().enumerate() {
            let band = rugosity.segment_tolerance(segment_index, floor);
            let leaf = self.nodes[segment_index].obb;
            for k in 0..=VALIDATION_SAMPLES_PER_SEGMENT {
                let t = k as f64 / VALIDATION_SAMPLES_PER_SEGMENT as f64;
                // The band around p(t) is the disc of radius λ(t): inside iff p(t) is λ(t) inside each side.
                if !leaf.contains_point(segment.position(t), slack - band.at(t)) {
                    return Err(format!("segment {segment_index}: band at t = {t} sticks out of its leaf {leaf:?}"));
                }
            }
        }
        Ok(())
    }
}
