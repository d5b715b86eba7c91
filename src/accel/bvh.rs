//! A flat bounding volume hierarchy over axis-aligned boxes, laid out depth
//! first in 32-byte nodes, as in Pharr, Jakob and Humphreys, *Physically
//! Based Rendering* (3rd ed.), §4.3 "Bounding Volume Hierarchies"
//! (`LinearBVHNode`). The builders live in [`super::build`], traversal in
//! [`super::traverse`].

use glam::Vec3;

use super::Aabb;
use super::build;

/// How the builder chooses split planes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SplitMethod {
    /// Binned surface area heuristic (Wald 2007).
    #[default]
    SahBinned,
    /// Object median along the widest centroid axis.
    Median,
}

/// 32-byte node, depth-first: an interior node's first child is at index+1, its second at `offset`; a leaf holds prim_indices[offset..offset+count].
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct BvhNode {
    /// Box minimum corner.
    pub min: [f32; 3],
    /// Interior: index of the second child. Leaf: first entry in `prim_indices`.
    pub offset: u32,
    /// Box maximum corner.
    pub max: [f32; 3],
    /// Number of primitives; 0 marks an interior node.
    pub count: u32,
}

impl BvhNode {
    /// The node's bounding box.
    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from_array(self.min),
            max: Vec3::from_array(self.max),
        }
    }

    /// True for a leaf (`count > 0`).
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// A leaf over `prim_indices[offset..offset+count]`.
    pub fn leaf(bounds: Aabb, offset: u32, count: u32) -> BvhNode {
        BvhNode {
            min: bounds.min.to_array(),
            offset,
            max: bounds.max.to_array(),
            count,
        }
    }

    /// An interior node whose second child is at `second_child`.
    pub fn interior(bounds: Aabb, second_child: u32) -> BvhNode {
        BvhNode {
            min: bounds.min.to_array(),
            offset: second_child,
            max: bounds.max.to_array(),
            count: 0,
        }
    }
}

/// A BVH: depth-first nodes (root at 0) and the primitive order the leaves refer to.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes in depth-first order; empty for no primitives.
    pub nodes: Vec<BvhNode>,
    /// Primitive indices (into the builder's `bounds`), grouped by leaf.
    pub prim_indices: Vec<u32>,
}

/// Deepest tree the fixed traversal stack supports (the builder stays within it).
pub const MAX_DEPTH: u32 = 64;

impl Bvh {
    /// Builds over primitive bounds (centroids = bounds' centres). Empty input → no nodes.
    pub fn build(bounds: &[Aabb], split: SplitMethod) -> Bvh {
        build::build(bounds, split)
    }

    /// One leaf holding every primitive: the "no acceleration" mode, traversed by the same code.
    pub fn single_leaf(bounds: &[Aabb]) -> Bvh {
        if bounds.is_empty() {
            return Bvh::default();
        }
        let b = bounds.iter().fold(Aabb::EMPTY, |acc, b| acc.union(*b));
        Bvh {
            nodes: vec![BvhNode::leaf(b, 0, bounds.len() as u32)],
            prim_indices: (0..bounds.len() as u32).collect(),
        }
    }

    /// Checks every structural invariant; Err names the first violation.
    ///
    /// Invariants: `prim_indices` is a permutation of `0..bounds.len()`; nodes
    /// are in depth-first (pre-)order, so a walk from the root meets them as
    /// 0, 1, 2, … and reaches every node once; an interior node's second child
    /// lies after its first; leaves are non-empty and cover `prim_indices` in
    /// order without gaps or overlap; every node box contains its children's
    /// boxes and a leaf box contains its primitives' boxes; depth ≤ [`MAX_DEPTH`].
    pub fn validate(&self, bounds: &[Aabb]) -> Result<(), String> {
        if self.nodes.is_empty() {
            if bounds.is_empty() && self.prim_indices.is_empty() {
                return Ok(());
            }
            return Err(format!(
                "no nodes but {} primitives and {} indices",
                bounds.len(),
                self.prim_indices.len()
            ));
        }
        if self.prim_indices.len() != bounds.len() {
            return Err(format!(
                "{} prim indices for {} primitives",
                self.prim_indices.len(),
                bounds.len()
            ));
        }
        let mut seen = vec![false; bounds.len()];
        for &p in &self.prim_indices {
            let Some(s) = seen.get_mut(p as usize) else {
                return Err(format!("prim index {p} out of range"));
            };
            if *s {
                return Err(format!("prim index {p} appears twice"));
            }
            *s = true;
        }

        let n = self.nodes.len() as u32;
        let mut next_node = 0u32;
        let mut next_prim = 0u32;
        // (node, parent, depth)
        let mut stack: Vec<(u32, Option<u32>, u32)> = vec![(0, None, 1)];
        while let Some((i, parent, depth)) = stack.pop() {
            if i != next_node {
                return Err(format!(
                    "node {i} visited where depth-first order expects {next_node}"
                ));
            }
            next_node += 1;
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let node = &self.nodes[i as usize];
            let b = node.bounds();
            if let Some(p) = parent {
                if !self.nodes[p as usize].bounds().contains_box(&b) {
                    return Err(format!("node {i} box is not inside its parent {p}"));
                }
            }
            if node.is_leaf() {
                if node.offset != next_prim {
                    return Err(format!(
                        "leaf {i} starts at prim {} instead of {next_prim}",
                        node.offset
                    ));
                }
                let end = node.offset as u64 + node.count as u64;
                if end > self.prim_indices.len() as u64 {
                    return Err(format!("leaf {i} range ends at {end}, past the indices"));
                }
                for k in node.offset..node.offset + node.count {
                    let p = self.prim_indices[k as usize];
                    if !b.contains_box(&bounds[p as usize]) {
                        return Err(format!("leaf {i} box does not contain prim {p}"));
                    }
                }
                next_prim += node.count;
            } else {
                if i + 1 >= n || node.offset <= i + 1 || node.offset >= n {
                    return Err(format!(
                        "interior node {i} has child offsets {} and {} outside {}..{n}",
                        i + 1,
                        node.offset,
                        i + 2
                    ));
                }
                // Pushed second so the first child is visited next.
                stack.push((node.offset, Some(i), depth + 1));
                stack.push((i + 1, Some(i), depth + 1));
            }
        }
        if next_node != n {
            return Err(format!("{} of {n} nodes are unreachable", n - next_node));
        }
        if next_prim as usize != self.prim_indices.len() {
            return Err(format!(
                "leaves cover {next_prim} of {} prim indices",
                self.prim_indices.len()
            ));
        }
        Ok(())
    }

    /// Number of levels (root alone = 1, empty = 0).
    pub fn depth(&self) -> u32 {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut max = 0;
        let mut stack = vec![(0u32, 1u32)];
        while let Some((i, d)) = stack.pop() {
            max = max.max(d);
            let node = &self.nodes[i as usize];
            if !node.is_leaf() {
                stack.push((i + 1, d + 1));
                stack.push((node.offset, d + 1));
            }
        }
        max
    }

    /// Number of leaf nodes.
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Bounds of everything (`Aabb::EMPTY` when there are no nodes).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds())
    }
}
