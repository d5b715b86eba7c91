//! A flat bounding volume hierarchy over axis-aligned boxes, laid out depth
//! first in 32-byte nodes, as in Pharr, Jakob and Humphreys, *Physically
//! Based Rendering* (3rd ed.), §4.3 "Bounding Volume Hierarchies"
//! (`LinearBVHNode`). The builders live in [`super::build`], traversal in
//! [`super::traverse`].

use glam::Vec3;

use super::Aabb;
use super::huge::HugeVec;

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
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
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
    /// Nodes in depth-first order; empty for no primitives. A [`HugeVec`]: in a
    /// huge-page mapping when large, as the build leaves it (see `build.rs`).
    pub nodes: HugeVec<BvhNode>,
    /// Primitive indices (into the builder's `bounds`), grouped by leaf; a triangle cut
    /// by spatial splits is in several leaves.
    pub prim_indices: HugeVec<u32>,
}

/// Deepest tree the fixed traversal stack supports (the builder stays within it).
pub const MAX_DEPTH: u32 = 64;

// `Bvh::build` is in build.rs: the builder depends on the tree, not the reverse.
impl Bvh {
    /// One leaf holding every primitive: the "no acceleration" mode, traversed by the same code.
    pub fn single_leaf(bounds: &[Aabb]) -> Bvh {
        if bounds.is_empty() {
            return Bvh::default();
        }
        let b = bounds.iter().fold(Aabb::EMPTY, |acc, b| acc.union(*b));
        Bvh {
            nodes: vec![BvhNode::leaf(b, 0, bounds.len() as u32)].into(),
            prim_indices: (0..bounds.len() as u32).collect::<Vec<u32>>().into(),
        }
    }

    /// FNV-1a over every node (a zero's sign ignored: no box test sees it) and the
    /// primitive order: equal for equal trees, so a build change that alters the tree shows.
    pub fn tree_hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u32| {
            for byte in x.to_le_bytes() {
                h = (h ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for n in &self.nodes {
            for v in n.min.iter().chain(&n.max) {
                eat((v + 0.0).to_bits());
            }
            eat(n.offset);
            eat(n.count);
        }
        for &p in &self.prim_indices {
            eat(p);
        }
        h
    }

    /// SAH cost with unit node and primitive costs, relative to the root's area: the
    /// tree's quality, for comparing builds (0 for no nodes).
    pub fn sah_cost(&self) -> f64 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let cost: f64 = self
            .nodes
            .iter()
            .map(|n| {
                let a = n.bounds().surface_area() as f64;
                if n.is_leaf() { a * n.count as f64 } else { a }
            })
            .sum();
        cost / root.bounds().surface_area() as f64
    }

    /// Checks every structural invariant; Err names the first violation.
    ///
    /// Invariants: `prim_indices` is a permutation of `0..bounds.len()`; nodes
    /// are in depth-first (pre-)order, so a walk from the root meets them as
    /// 0, 1, 2, … and reaches every node once; an interior node's second child
    /// lies after its first; leaves are non-empty and cover `prim_indices` in
    /// order without gaps or overlap; every node box contains its children's
    /// boxes and a leaf box contains its primitives' boxes; depth ≤ [`MAX_DEPTH`]. A
    /// tree of [`Bvh::build_triangles`] that cut triangles holds them in several leaves,
    /// each leaf box holding a part: not a permutation, nor whole boxes. Check its
    /// collapse with `WideBvh::validate`, which allows both.
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
            if let Some(p) = parent
                && !self.nodes[p as usize].bounds().contains_box(&b)
            {
                return Err(format!("node {i} box is not inside its parent {p}"));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Lcg;
    use glam::vec3;

    /// Boxes of `n` random small triangles in [-5, 5]³.
    pub(crate) fn random_tri_bounds(n: usize, seed: u64) -> Vec<Aabb> {
        let mut rng = Lcg(seed);
        (0..n)
            .map(|_| {
                let c = rng.vec() * 10.0 - Vec3::splat(5.0);
                Aabb::from_points(&[c, c + rng.dir() * 0.3, c + rng.dir() * 0.3])
            })
            .collect()
    }

    const METHODS: [SplitMethod; 2] = [SplitMethod::SahBinned, SplitMethod::Median];

    #[test]
    fn empty_input() {
        for m in METHODS {
            let b = Bvh::build(&[], m);
            assert!(b.nodes.is_empty() && b.prim_indices.is_empty());
            assert_eq!(b.validate(&[]), Ok(()));
            assert_eq!((b.depth(), b.leaf_count()), (0, 0));
            assert_eq!(b.bounds(), Aabb::EMPTY);
        }
        assert!(Bvh::single_leaf(&[]).nodes.is_empty());
    }

    #[test]
    fn one_prim() {
        let bounds = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        for m in METHODS {
            let b = Bvh::build(&bounds, m);
            assert_eq!(b.validate(&bounds), Ok(()));
            assert_eq!(b.nodes, vec![BvhNode::leaf(bounds[0], 0, 1)]);
            assert_eq!((b.depth(), b.leaf_count()), (1, 1));
            assert_eq!(b.bounds(), bounds[0]);
        }
    }

    #[test]
    fn all_prims_at_one_point_make_one_leaf() {
        let p = vec3(1.5, -2.0, 0.25);
        let bounds = vec![Aabb::from_points(&[p]); 1000];
        for m in METHODS {
            let b = Bvh::build(&bounds, m);
            assert_eq!(b.validate(&bounds), Ok(()));
            assert_eq!(b.nodes.len(), 1);
            assert_eq!(b.nodes[0].count, 1000);
        }
    }

    #[test]
    fn collinear_and_flat_input() {
        // Point boxes on a line: every node box has zero area.
        let bounds: Vec<Aabb> = (0..500)
            .map(|i| Aabb::from_points(&[vec3(i as f32 * 0.37, 0.0, 0.0)]))
            .collect();
        for m in METHODS {
            let b = Bvh::build(&bounds, m);
            assert_eq!(b.validate(&bounds), Ok(()));
            assert!(b.nodes.iter().all(|n| n.count <= 8));
        }
    }

    #[test]
    fn random_triangles_validate() {
        for n in [2, 5, 9, 1000, 20_000] {
            let bounds = random_tri_bounds(n, n as u64);
            for m in METHODS {
                let b = Bvh::build(&bounds, m);
                assert_eq!(b.validate(&bounds), Ok(()), "{m:?} n={n}");
                assert!(b.nodes.iter().all(|x| x.count <= 8), "{m:?} leaf too large");
                assert!(b.depth() < MAX_DEPTH);
                let sum: u32 = b.nodes.iter().map(|x| x.count).sum();
                assert_eq!(sum as usize, n);
            }
            let s = Bvh::single_leaf(&bounds);
            assert_eq!(s.validate(&bounds), Ok(()));
            assert_eq!((s.depth(), s.leaf_count()), (1, 1));
        }
    }

    #[test]
    fn median_shape_is_analytic() {
        // 16 boxes along x: median halves down to leaves of 4, a full tree.
        let bounds: Vec<Aabb> = (0..16)
            .map(|i| Aabb::from_points(&[vec3(i as f32, 0.0, 0.0), vec3(i as f32 + 0.5, 1.0, 1.0)]))
            .collect();
        let b = Bvh::build(&bounds, SplitMethod::Median);
        assert_eq!(b.validate(&bounds), Ok(()));
        assert_eq!((b.nodes.len(), b.depth(), b.leaf_count()), (7, 3, 4));
        // Depth-first: root, left, left-left, left-right, right, ...
        assert_eq!(b.nodes[0].offset, 4);
        assert_eq!(b.nodes[1].offset, 3);
        assert_eq!(
            b.nodes[0].bounds(),
            Aabb::new(Vec3::ZERO, vec3(15.5, 1.0, 1.0))
        );
        // The first leaf holds the four smallest x.
        let mut first: Vec<u32> = b.prim_indices[0..4].to_vec();
        first.sort();
        assert_eq!(first, vec![0, 1, 2, 3]);
    }

    #[test]
    fn sah_cost_counts_leaf_primitives_by_area() {
        let unit = |x: f32| Aabb {
            min: Vec3::new(x, 0.0, 0.0),
            max: Vec3::new(x + 1.0, 1.0, 1.0),
        };
        // One leaf of three: three primitive tests over the root's own area.
        assert_eq!(Bvh::single_leaf(&[unit(0.0); 3]).sah_cost(), 3.0);
        assert_eq!(Bvh::default().sah_cost(), 0.0);
        // 64 boxes in a row: the SAH tree costs far less than testing all 64 in one
        // leaf, and more than the root alone.
        let row: Vec<Aabb> = (0..64).map(|i| unit(2.0 * i as f32)).collect();
        let cost = Bvh::build(&row, SplitMethod::SahBinned).sah_cost();
        assert!(cost > 1.0 && cost < 16.0, "{cost}");
    }

    #[test]
    fn sah_counts_leaves_in_whole_groups() {
        // Three groups' worth of unit boxes in a row. Counting primitives, the SAH
        // halves the row (leaves of 1.5 groups, padded to 2 each); counting whole
        // groups, a third-and-two-thirds split is cheaper, so every leaf is one full group.
        let g = crate::accel::leaf::LANES;
        let row: Vec<Aabb> = (0..3 * g)
            .map(|i| {
                Aabb::new(
                    vec3(2.0 * i as f32, 0.0, 0.0),
                    vec3(2.0 * i as f32 + 1.0, 1.0, 1.0),
                )
            })
            .collect();
        let b = Bvh::build(&row, SplitMethod::SahBinned);
        assert_eq!(b.validate(&row), Ok(()));
        let leaves: Vec<u32> = b
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| n.count)
            .collect();
        assert_eq!(leaves, vec![g as u32; 3]);
    }

    #[test]
    fn sah_separates_clusters() {
        // Two tight clusters far apart: the SAH root split separates them.
        let mut rng = Lcg(9);
        let mut bounds = Vec::new();
        for k in 0..2 {
            for _ in 0..100 {
                let c = rng.vec() + Vec3::splat(k as f32 * 100.0);
                bounds.push(Aabb::new(c, c + Vec3::splat(0.01)));
            }
        }
        let b = Bvh::build(&bounds, SplitMethod::SahBinned);
        assert_eq!(b.validate(&bounds), Ok(()));
        let left = b.nodes[1].bounds();
        let right = b.nodes[b.nodes[0].offset as usize].bounds();
        assert!(left.max.x < 2.0 || right.max.x < 2.0);
        assert!(left.min.x > 90.0 || right.min.x > 90.0);
    }

    #[test]
    fn build_is_deterministic_across_thread_counts() {
        let bounds = random_tri_bounds(30_000, 1);
        for m in METHODS {
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap()
                .install(|| Bvh::build(&bounds, m));
            let many = rayon::ThreadPoolBuilder::new()
                .num_threads(4)
                .build()
                .unwrap()
                .install(|| Bvh::build(&bounds, m));
            assert_eq!(one.nodes, many.nodes);
            assert_eq!(one.prim_indices, many.prim_indices);
        }
    }

    #[test]
    fn sah_tree_matches_reference_for_any_thread_count() {
        // Hashes of the trees the first builder (index array, no PrimRefs) made,
        // renewed when the SAH began to count leaves in blocks of `leaf::LANES`
        // (which changes splits), and again when small nodes began to take fewer bins
        // (`build::bin_count`): a faster builder
        // must make the same splits, leaves and order.
        // 70k primitives take the parallel binning path at the root.
        let mut odd = random_tri_bounds(3000, 5);
        for b in &mut odd[1000..1200] {
            *b = Aabb::new(Vec3::ONE, Vec3::ONE); // coincident centroids
        }
        for b in &mut odd[2000..2100] {
            b.max.z = b.min.z; // flat boxes
        }
        let cases = [
            (random_tri_bounds(70_000, 7), 0x6f68_a641_ed1b_8b00),
            (odd, 0x2339_f6e7_b4a4_f59b),
            (random_tri_bounds(500, 3), 0x0b3f_502a_f602_36ea),
        ];
        for (bounds, want) in &cases {
            for threads in [1, 2, 4] {
                let b = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| Bvh::build(bounds, SplitMethod::SahBinned));
                assert_eq!(b.validate(bounds), Ok(()));
                assert_eq!(
                    b.tree_hash(),
                    *want,
                    "{} prims, {threads} threads",
                    bounds.len()
                );
            }
        }
    }

    #[test]
    fn build_is_the_same_whichever_backing_its_arrays_have() {
        use crate::accel::build::build_backed;
        use crate::accel::huge::Backing;
        // 70k primitives fill their `PrimRef`s in parallel (and take a mapping with
        // `Auto`); 500 fill them in order. On one thread the nodes go straight into
        // the array `backing` says, on more they are built in pieces and copied: two
        // threads at least, whatever the machine, so that both ways are compared.
        let pool = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
        };
        let (one, two) = (pool(1), pool(2));
        for n in [70_000, 500] {
            let bounds = random_tri_bounds(n, 7);
            let want = two.install(|| Bvh::build(&bounds, SplitMethod::SahBinned));
            for backing in [Backing::Heap, Backing::Mapped] {
                let b = two.install(|| build_backed(&bounds, SplitMethod::SahBinned, backing));
                assert_eq!(b.nodes, want.nodes, "{n} prims, {backing:?}");
                assert_eq!(b.prim_indices, want.prim_indices, "{n} prims, {backing:?}");
                let b = one.install(|| build_backed(&bounds, SplitMethod::SahBinned, backing));
                assert_eq!(b.nodes, want.nodes, "{n} prims, {backing:?}, 1 thread");
                assert_eq!(
                    b.prim_indices, want.prim_indices,
                    "{n} prims, {backing:?}, 1 thread"
                );
            }
        }
    }

    #[test]
    fn nan_coordinates_do_not_shrink_boxes() {
        // A NaN coordinate is ignored wherever it comes in the order, so the
        // finite boxes around it stay covered.
        let mut bounds = random_tri_bounds(200, 8);
        for i in (0..200).step_by(9) {
            bounds[i].min.x = f32::NAN;
            bounds[i + 1].max.y = f32::NAN;
        }
        for m in METHODS {
            let b = Bvh::build(&bounds, m);
            let mut seen = vec![0u32; bounds.len()];
            for &p in &b.prim_indices {
                seen[p as usize] += 1;
            }
            assert!(seen.iter().all(|&c| c == 1));
            for leaf in b.nodes.iter().filter(|n| n.is_leaf()) {
                let r = leaf.offset as usize..(leaf.offset + leaf.count) as usize;
                for &p in &b.prim_indices[r] {
                    let mut finite = bounds[p as usize];
                    for k in 0..3 {
                        if finite.min[k].is_nan() {
                            finite.min[k] = finite.max[k];
                        }
                        if finite.max[k].is_nan() {
                            finite.max[k] = finite.min[k];
                        }
                    }
                    assert!(leaf.bounds().contains_box(&finite), "{m:?}: prim {p}");
                }
            }
            assert!(
                b.bounds()
                    .contains_box(&Aabb::new(Vec3::splat(-4.9), Vec3::splat(4.9)))
            );
        }
    }

    #[test]
    fn validate_reports_violations() {
        let bounds = random_tri_bounds(200, 4);
        let good = Bvh::build(&bounds, SplitMethod::SahBinned);
        assert_eq!(good.validate(&bounds), Ok(()));
        let leaf = good.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let interior = 0;

        let mut b = good.clone();
        b.prim_indices[1] = b.prim_indices[0];
        assert!(b.validate(&bounds).unwrap_err().contains("twice"));

        let mut b = good.clone();
        b.prim_indices[0] = 999;
        assert!(b.validate(&bounds).unwrap_err().contains("out of range"));

        let mut b = good.clone();
        b.nodes[leaf].max[0] -= 1.0;
        assert!(b.validate(&bounds).is_err());

        let mut b = good.clone();
        b.nodes[interior].min[1] += 0.5;
        assert!(
            b.validate(&bounds)
                .unwrap_err()
                .contains("not inside its parent")
        );

        let mut b = good.clone();
        b.nodes[interior].offset = b.nodes.len() as u32;
        assert!(b.validate(&bounds).is_err());

        let mut b = good.clone();
        let second = b.nodes[0].offset as usize;
        b.nodes.swap(1, second);
        assert!(b.validate(&bounds).is_err());

        let mut b = good.clone();
        b.nodes.push(BvhNode::leaf(bounds[0], 0, 1));
        assert!(b.validate(&bounds).unwrap_err().contains("unreachable"));

        // An empty leaf is an interior node pointing nowhere sensible.
        let mut b = good.clone();
        let last = b.nodes.len() - 1;
        b.nodes[last].count = 0;
        assert!(b.validate(&bounds).is_err());

        assert!(good.validate(&bounds[1..]).is_err());
    }
}
