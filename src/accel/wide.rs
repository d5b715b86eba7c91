//! An 8-wide BVH over triangles for the render's hot path: the binned-SAH binary
//! tree of [`super::build`] collapsed into nodes of up to eight children whose
//! boxes are stored structure-of-arrays, so that one slab test covers all eight
//! (plain `[f32; 8]` lanes that the compiler vectorises, one AVX2 register in the
//! AVX2 clone of the queries; no `unsafe`), and the
//! triangles copied in leaf order, structure-of-arrays ([`super::leaf`]), so a leaf
//! reads consecutive memory instead of going through the primitive indices and tests
//! its triangles' early-outs in one vectorised pass.
//!
//! The slab test is the binary tree's (Ize 2013: near and far planes chosen by
//! the sign of the inverse direction, NaN bounds ignored, exit distance enlarged
//! by `1 + 2 gamma(3)`), so a box is culled only when the exact ray misses it,
//! and the triangle test is the same watertight test with the per-ray shear: the
//! closest hit is the binary tree's, up to which of two triangles at exactly the
//! same t is met first.

use arrayvec::ArrayVec;
use glam::Vec3;
use wide::{f32x8, u32x8};

use super::bvh::{Bvh, MAX_DEPTH};
use super::leaf::LeafTris;
use super::wide_query::LeafVisitor;
use super::{Aabb, BOX_MARGIN, Ray};

/// Children per node. Eight beat four on the 100k torus (callgrind: 9-10% fewer
/// instructions per ray; 4-6% less time) at 68 rather than 59 bytes per triangle.
pub const WIDTH: usize = 8;

/// `child` of an unused slot.
const EMPTY: u32 = u32::MAX;

/// A node of up to `WIDTH` children; box planes are SoA: `bounds[axis][lane]` for the
/// minimum corner (axis 0..3) and `bounds[3 + axis][lane]` for the maximum.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Child boxes: min x, y, z then max x, y, z, one lane per child.
    pub bounds: [[f32; WIDTH]; 6],
    /// Interior child: its node index. Leaf child: its first group in `leaves`. Unused: `u32::MAX`.
    pub child: [u32; WIDTH],
    /// Triangles of a leaf child; 0 for an interior or unused child.
    pub count: [u32; WIDTH],
}

impl WideNode {
    const UNUSED: WideNode = WideNode {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
        count: [0; WIDTH],
    };

    /// The box of child `lane`.
    pub fn child_bounds(&self, lane: usize) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: Vec3::new(b[0][lane], b[1][lane], b[2][lane]),
            max: Vec3::new(b[3][lane], b[4][lane], b[5][lane]),
        }
    }

    fn set_child_bounds(&mut self, lane: usize, a: Aabb) {
        for axis in 0..3 {
            self.bounds[axis][lane] = a.min[axis];
            self.bounds[3 + axis][lane] = a.max[axis];
        }
    }
}

/// A `WIDTH`-wide BVH with its triangles in leaf order; root at node 0.
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// Nodes, each after its parent; empty for no triangles.
    pub nodes: Vec<WideNode>,
    /// Triangle vertices in leaf order, in groups of `leaf::LANES`.
    pub leaves: LeafTris,
    /// The caller's index of each triangle slot, in leaf order.
    pub prims: Vec<u32>,
    /// Bounds of everything.
    pub bounds: Aabb,
    /// Levels of nodes below the root's (at most the binary tree's depth).
    pub depth: u32,
}

/// Traversal stack entries any tree needs: each of at most `MAX_DEPTH` levels below
/// the root pushes at most `WIDTH - 1` children, plus the root.
const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH as usize + 1;

/// The traversal stack: on the call stack and never initialised (an `ArrayVec`
/// writes only what is pushed), so its size costs nothing per ray.
type Stack = ArrayVec<(u32, f32), STACK_SIZE>;

/// The per-ray constants of the wide slab test.
struct RayBoxes {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    /// Row of `WideNode::bounds` holding each axis's near plane, then the far plane's.
    near: [usize; 3],
    far: [usize; 3],
}

impl RayBoxes {
    fn new(ray: &Ray) -> RayBoxes {
        let inv = ray.dir.recip();
        let neg = |a: usize| inv[a].is_sign_negative() as usize;
        RayBoxes {
            origin: ray.origin.to_array(),
            inv_dir: inv.to_array(),
            near: [3 * neg(0), 1 + 3 * neg(1), 2 + 3 * neg(2)],
            far: [3 - 3 * neg(0), 4 - 3 * neg(1), 5 - 3 * neg(2)],
        }
    }

    /// Entry distance of each child box (lanes the ray misses hold junk) and the
    /// mask of lanes whose box the ray meets in [0, t_max]. The same arithmetic
    /// as [`Aabb::intersect_ray`], lane by lane, in loops without branches so
    /// that they compile to SIMD, and the mask through `wide` (a movemask: LLVM
    /// turns the plain loop into a tangle of shuffles).
    #[inline(always)]
    fn test(&self, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        let b = &node.bounds;
        let (o, inv) = (self.origin, self.inv_dir);
        let mut t_near = [0.0f32; WIDTH];
        let mut t_far = [0.0f32; WIDTH];
        for lane in 0..WIDTH {
            let near_x = (b[self.near[0]][lane] - o[0]) * inv[0];
            let near_y = (b[self.near[1]][lane] - o[1]) * inv[1];
            let near_z = (b[self.near[2]][lane] - o[2]) * inv[2];
            let far_x = (b[self.far[0]][lane] - o[0]) * inv[0];
            let far_y = (b[self.far[1]][lane] - o[1]) * inv[1];
            let far_z = (b[self.far[2]][lane] - o[2]) * inv[2];
            t_near[lane] = 0.0f32.max(near_x).max(near_y).max(near_z);
            t_far[lane] = t_max.min(far_x).min(far_y).min(far_z) * BOX_MARGIN;
        }
        let hit = f32x8::from(t_near).simd_le(f32x8::from(t_far));
        (t_near, hit.to_bitmask())
    }
}

/// The lanes of `node` holding leaves.
#[inline(always)]
fn leaf_lanes(node: &WideNode) -> u32 {
    !u32x8::from(node.count).simd_eq(u32x8::ZERO).to_bitmask() & ((1 << WIDTH) - 1)
}

/// Sort key of lane `lane` entered at `t` (not NaN, not below zero): ordered by t
/// then lane, as the bits of a non-negative f32 are ordered like the f32.
#[inline(always)]
fn key(t: f32, lane: u32) -> u64 {
    ((t.to_bits() as u64) << 32) | lane as u64
}

impl WideBvh {
    /// Collapses `bvh` (built over `positions`) into `WIDTH`-wide nodes, each taking the
    /// largest-area interior grandchildren in place of their parents; leaves and
    /// their triangle order are the binary tree's.
    pub fn collapse(bvh: &Bvh, positions: &[[Vec3; 3]]) -> WideBvh {
        WideBvh::collapse_with(bvh, bvh.prim_indices.clone(), positions)
    }

    /// [`WideBvh::collapse`] of a binary tree not kept after it: its `prim_indices`
    /// move into `prims` instead of being copied.
    pub fn collapse_owned(mut bvh: Bvh, positions: &[[Vec3; 3]]) -> WideBvh {
        let prims = std::mem::take(&mut bvh.prim_indices);
        WideBvh::collapse_with(&bvh, prims, positions)
    }

    /// [`WideBvh::collapse`] with the binary tree's `prim_indices` given as `prims`.
    fn collapse_with(bvh: &Bvh, prims: Vec<u32>, positions: &[[Vec3; 3]]) -> WideBvh {
        if bvh.nodes.is_empty() {
            return WideBvh::default();
        }
        let mut nodes = Vec::with_capacity(bvh.nodes.len() / 2 + 1);
        let depth = collapse_node(bvh, 0, 0, &mut nodes).1;
        let leaves = LeafTris::build(&mut nodes, &prims, positions);
        WideBvh {
            nodes,
            leaves,
            prims,
            bounds: bvh.bounds(),
            depth,
        }
    }

    /// Bytes held: nodes, triangles and indices.
    pub fn bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice())
            + self.leaves.bytes()
            + size_of_val(self.prims.as_slice())
    }

    /// Visits leaves in near-to-far order of their boxes' entry distances while
    /// they start before `*t_max` (`NEAREST_FIRST`), or each node's leaves before
    /// its interior children without sorting (for any-hit queries, where order does
    /// not decide the answer); `visitor.leaf(first, count, t_max)` may lower `t_max`
    /// and returns true to stop. Returns whether a leaf stopped it.
    #[inline(always)]
    pub(super) fn traverse<const NEAREST_FIRST: bool>(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        visitor: &mut impl LeafVisitor,
    ) -> bool {
        if self.nodes.is_empty()
            || self
                .bounds
                .intersect_ray(ray.origin, ray.dir.recip(), *t_max)
                .is_none()
        {
            return false;
        }
        let mut stack = Stack::new();
        // The node to visit next without a round trip through the stack: a node's
        // nearest interior child (any-hit: its last, which would be popped first).
        let mut next = Some((0, 0.0));
        let boxes = RayBoxes::new(ray);
        while let Some((index, t_entry)) = next.take().or_else(|| stack.pop()) {
            // A box pushed earlier may now lie beyond the closest hit found since. With
            // the slab test's margin: a box entry rounded just past a hit on its face must
            // not hide a tie there, or the hit found would depend on the visiting order.
            if t_entry > *t_max * BOX_MARGIN {
                continue;
            }
            let node = &self.nodes[index as usize];
            let (t, hit) = boxes.test(node, *t_max);
            let leaf_mask = leaf_lanes(node);
            let (mut leaves, mut inner) = (hit & leaf_mask, hit & !leaf_mask);
            if !NEAREST_FIRST {
                while leaves != 0 {
                    let lane = leaves.trailing_zeros() as usize;
                    leaves &= leaves - 1;
                    let (child, count) = (node.child[lane], node.count[lane]);
                    if visitor.leaf(child as usize, count as usize, t_max) {
                        return true;
                    }
                }
                while inner != 0 {
                    let lane = inner.trailing_zeros() as usize;
                    inner &= inner - 1;
                    let entry = (node.child[lane], t[lane]);
                    if inner == 0 {
                        next = Some(entry);
                    } else {
                        stack.push(entry);
                    }
                }
                continue;
            }
            // Interior children met: the nearest next, the others pushed nearest last so
            // that it is popped first; most nodes have at most one, which needs no sort.
            if inner & inner.wrapping_sub(1) == 0 {
                if inner != 0 {
                    let lane = inner.trailing_zeros() as usize;
                    next = Some((node.child[lane], t[lane]));
                }
            } else if (inner & (inner - 1)).count_ones() == 1 {
                // Two: one comparison.
                let (a, b) = (inner.trailing_zeros(), 31 - inner.leading_zeros());
                let (a, b) = (key(t[a as usize], a), key(t[b as usize], b));
                let (near, far) = if a < b { (a, b) } else { (b, a) };
                let (near, far) = (near as u32 as usize, far as u32 as usize);
                stack.push((node.child[far], t[far]));
                next = Some((node.child[near], t[near]));
            } else {
                let mut keys = [0u64; WIDTH];
                let mut n = 0;
                while inner != 0 {
                    let lane = inner.trailing_zeros();
                    inner &= inner - 1;
                    let k = key(t[lane as usize], lane);
                    let mut i = n;
                    while i > 0 && keys[i - 1] < k {
                        keys[i] = keys[i - 1];
                        i -= 1;
                    }
                    keys[i] = k;
                    n += 1;
                }
                for &k in &keys[..n - 1] {
                    let lane = k as u32 as usize;
                    stack.push((node.child[lane], t[lane]));
                }
                let lane = keys[n - 1] as u32 as usize;
                next = Some((node.child[lane], t[lane]));
            }
            // Leaves nearest first, after the interior children are queued.
            while leaves != 0 {
                let lane = if leaves & (leaves - 1) == 0 {
                    leaves.trailing_zeros()
                } else {
                    let mut rest = leaves;
                    let mut best = u64::MAX;
                    while rest != 0 {
                        let lane = rest.trailing_zeros();
                        rest &= rest - 1;
                        best = best.min(key(t[lane as usize], lane));
                    }
                    best as u32
                };
                leaves &= !(1 << lane);
                let lane = lane as usize;
                let (child, count) = (node.child[lane], node.count[lane]);
                if t[lane] <= *t_max * BOX_MARGIN
                    && visitor.leaf(child as usize, count as usize, t_max)
                {
                    return true;
                }
            }
        }
        false
    }

    /// Checks every structural invariant against the triangles it was built from;
    /// Err names the first violation. Invariants: `prims` is a permutation of
    /// `0..positions.len()`; every node is reached once from the root and after its
    /// parent; leaves are non-empty, own their triangle groups and cover the slots of
    /// `prims` without gaps or overlap, slot `k` holding `positions[prims[k]]` and
    /// padding lanes NaN; every group belongs to a leaf; a child box contains its
    /// node's children's boxes, a leaf box its triangles; `bounds` contains the root's
    /// children; unused slots have no box; no node lies deeper than `depth`.
    pub fn validate(&self, positions: &[[Vec3; 3]]) -> Result<(), String> {
        let n = positions.len();
        if self.prims.len() != n {
            return Err(format!("{} prims for {n} triangles", self.prims.len()));
        }
        if self.nodes.is_empty() {
            return if n == 0 {
                Ok(())
            } else {
                Err(format!("no nodes for {n} triangles"))
            };
        }
        let mut seen = vec![false; n];
        for (k, &p) in self.prims.iter().enumerate() {
            let Some(s) = seen.get_mut(p as usize).filter(|s| !**s) else {
                return Err(format!("prims[{k}] = {p} is out of range or repeated"));
            };
            *s = true;
        }
        let mut used = vec![false; self.leaves.groups.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut covered = vec![false; n];
        if self.depth > MAX_DEPTH {
            return Err(format!("depth {} exceeds {MAX_DEPTH}", self.depth));
        }
        let mut stack = vec![(0usize, self.bounds, 0u32)];
        reached[0] = true;
        while let Some((i, outer, depth)) = stack.pop() {
            if depth > self.depth {
                return Err(format!(
                    "node {i} at depth {depth}, below the recorded {}",
                    self.depth
                ));
            }
            let node = &self.nodes[i];
            for lane in 0..WIDTH {
                let (child, count) = (node.child[lane], node.count[lane]);
                let b = node.child_bounds(lane);
                if child == EMPTY {
                    if !b.is_empty() || count != 0 {
                        return Err(format!("node {i} lane {lane}: unused slot with a box"));
                    }
                    continue;
                }
                if !outer.contains_box(&b) {
                    return Err(format!("node {i} lane {lane}: box outside its parent's"));
                }
                if count == 0 {
                    let c = child as usize;
                    if c <= i || c >= self.nodes.len() || reached[c] {
                        return Err(format!("node {i} lane {lane}: bad child {child}"));
                    }
                    reached[c] = true;
                    stack.push((c, b, depth + 1));
                    continue;
                }
                let leaf = |k: usize, tri: [Vec3; 3]| {
                    if k >= n || std::mem::replace(&mut covered[k], true) {
                        return Err(format!("triangle slot {k} past the end or in two leaves"));
                    }
                    if tri != positions[self.prims[k] as usize] {
                        return Err(format!("slot {k} is not triangle {}", self.prims[k]));
                    }
                    if !b.contains_box(&Aabb::from_points(&tri)) {
                        return Err(format!("node {i} lane {lane}: slot {k} outside the box"));
                    }
                    Ok(())
                };
                self.leaves
                    .validate_leaf(child as usize, count as usize, &mut used, leaf)
                    .map_err(|e| format!("node {i} lane {lane}: {e}"))?;
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Err(format!("node {i} is unreachable"));
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return Err(format!("triangle slot {k} is in no leaf"));
        }
        if let Some(g) = used.iter().position(|u| !u) {
            return Err(format!("triangle group {g} is in no leaf"));
        }
        Ok(())
    }
}

/// Appends the wide node for binary node `b` (and its subtree) at `depth`; returns its
/// index and the deepest level in its subtree.
fn collapse_node(bvh: &Bvh, b: usize, depth: u32, out: &mut Vec<WideNode>) -> (u32, u32) {
    let me = out.len();
    out.push(WideNode::UNUSED);
    let first = &bvh.nodes[b];
    let mut kids: Vec<usize> = if first.is_leaf() {
        vec![b]
    } else {
        vec![b + 1, first.offset as usize]
    };
    // Open the interior child of largest area until `WIDTH` children are reached.
    while kids.len() < WIDTH {
        let Some(k) = (0..kids.len())
            .filter(|&k| !bvh.nodes[kids[k]].is_leaf())
            .max_by(|&x, &y| {
                let area = |k: usize| bvh.nodes[kids[k]].bounds().surface_area();
                area(x).total_cmp(&area(y))
            })
        else {
            break;
        };
        let open = kids[k];
        kids[k] = open + 1;
        kids.insert(k + 1, bvh.nodes[open].offset as usize);
    }
    let mut deepest = depth;
    for (lane, &k) in kids.iter().enumerate() {
        let node = bvh.nodes[k];
        out[me].set_child_bounds(lane, node.bounds());
        if node.is_leaf() {
            out[me].child[lane] = node.offset;
            out[me].count[lane] = node.count;
        } else {
            let (child, d) = collapse_node(bvh, k, depth + 1, out);
            out[me].child[lane] = child;
            deepest = deepest.max(d);
        }
    }
    (me as u32, deepest)
}

#[cfg(test)]
#[path = "wide_tests.rs"]
mod tests;
