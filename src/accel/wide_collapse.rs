//! The collapse of the binary tree into `WIDTH`-wide nodes, chosen by a cost (after
//! Ylitie, Karras, Laine 2017, "Efficient incoherent ray traversal on GPUs through
//! compressed wide BVHs"): for each binary node and each number of lanes `i`, the least
//! surface-area cost of holding its subtree in at most `i` lanes of a wide node, each
//! lane a wide node of its own or a leaf. A leaf may be a whole binary subtree of up
//! to [`MAX_LEAF`] triangles, so that small sibling leaves share one group of
//! [`LANES`] instead of padding two (its triangles are consecutive slots, so it stays
//! one `(slot, count)`); and a node takes whichever cut of its subtree costs least,
//! not the largest-area children first, which left the nodes below half empty.
//!
//! The tree changes, the answers do not: the queries decide the closest hit by
//! (t, index) whatever the visiting order, and every box holds its triangles.

use arrayvec::ArrayVec;

use super::Aabb;
use super::bvh::{Bvh, BvhNode};
use super::huge::{Backing, HugeSlice, HugeVec};
use super::leaf::{LANES, groups_for};
use super::wide_node::{WIDTH, WideNode};

/// Cost of a ray meeting a node's box: its slab test of `WIDTH` children and their
/// ordering, the unit of the costs below. The figures hardly matter: from leaf 0 to 1
/// and group 0.8 to 3 (callgrind, torus 100k) single rays and packets cost within 1% of each
/// other, at 52.8 to 55.3 bytes per triangle. Swept again with a node's two nearest
/// one-group leaves in one 8-lane pass (December 2026, single rays; tori, bunny,
/// Sponza, MetalRoughSpheres): leaf 0 to 1 and group 1.2 to 3 within 0.5% of these
/// instructions per ray on the tori (group 1.6: 55.7 bytes per triangle); group 0.9
/// 1% more (53.7 bytes), 0.6 3-5% more (51.7 bytes). Leaves of one group only (here
/// and in the build) took 2.7% fewer on Sponza's incoherent rays at 61.1 rather than
/// 58.4 bytes per triangle, the tori within 0.3%; no CPU time showed on the torus, and
/// the same instructions saved by the kernel (a two-group leaf in one pass) bought
/// Sponza none either (2M rays, 8 alternated runs).
pub(super) const NODE_COST: f32 = 1.0;
/// Cost of a ray visiting a leaf, beside its groups: the visit and its bookkeeping.
const LEAF_COST: f32 = 0.3;
/// Cost of testing a ray against one group of `LANES` triangles.
const GROUP_COST: f32 = 1.2;
/// Most triangles a subtree merged into one leaf may hold (two groups); the binary
/// leaves, which the binned SAH makes of 1 to 8, stay leaves whatever their size. Four
/// (one group) cost the same per ray at 55.3 rather than 54.7 bytes per triangle.
const MAX_LEAF: u32 = 2 * LANES as u32;

/// A wide node's lanes: `(binary node, leaf)`.
type Lanes = ArrayVec<(usize, bool), WIDTH>;

/// Per binary node: its subtree's first slot in `prim_indices` and triangle count,
/// whether all its leaves are flat (for subtrees of at most [`MAX_LEAF`] triangles),
/// and `cost[i - 1]`, the least cost of its subtree in at most `i` lanes.
struct Costs {
    first: HugeSlice<u32>,
    count: HugeSlice<u32>,
    flat: Vec<bool>,
    cost: HugeSlice<[f32; WIDTH]>,
}

/// Whether `b` has zero extent along an axis (a box in an axis plane).
fn is_flat(b: &Aabb) -> bool {
    let e = b.extent();
    e.x == 0.0 || e.y == 0.0 || e.z == 0.0
}

/// Whether an interior node of box `b` whose leaves are all flat encloses space as a
/// room's walls do: its own box has volume, as the build's room split
/// (`build/rooms.rs`) makes them. Merged into one leaf, its box would be the room's,
/// which every ray starting in the room meets; apart, each wall's flat box is met only
/// by rays crossing it. Closed meshes have no flat leaves, so this is never asked.
fn encloses(b: &Aabb) -> bool {
    !is_flat(b) && !b.is_empty()
}

/// Cost of a leaf of `count` triangles whose box has area `area` (the odds of a ray
/// meeting a box grow with its area).
pub(super) fn leaf_cost(area: f32, count: u32) -> f32 {
    area * (LEAF_COST + GROUP_COST * groups_for(count as usize) as f32)
}

/// The least cost of an interior node as one lane, and whether that is a leaf (else a
/// wide node of its own), from its box's area, its triangles and the least cost of its
/// children in `WIDTH` lanes; a `room` (see [`encloses`]) is never merged into a leaf.
fn single(area: f32, count: u32, children: f32, room: bool) -> (f32, bool) {
    let node = NODE_COST * area + children;
    if count <= MAX_LEAF && !room {
        let leaf = leaf_cost(area, count);
        if leaf <= node {
            return (leaf, true);
        }
    }
    (node, false)
}

/// The least cost of two children, of lane costs `left` and `right`, in at most `i`
/// lanes together: entry `i - 1` (infinite for one lane). The same sums and minimum as
/// `Costs::split`, all `i` at once and without branches: the collapse took 2.1 times
/// the greedy one's instructions with a `split` per `i`, 1.6 times with this (torus
/// 100k: 15.5 -> 24.9 million, about 1 ms more).
#[inline(always)]
fn splits(left: &[f32; WIDTH], right: &[f32; WIDTH]) -> [f32; WIDTH] {
    let mut least = [f32::INFINITY; WIDTH];
    // Left child in k lanes, right in the rest: a select per lane, no branch.
    for k in 1..WIDTH {
        let l = left[k - 1];
        for (least, &r) in least[k..].iter_mut().zip(&right[..WIDTH - k]) {
            let cost = l + r;
            *least = if cost < *least { cost } else { *least };
        }
    }
    least
}

impl Costs {
    /// The costs of every node of the binary tree `nodes` (not empty), children before
    /// parents.
    fn new(nodes: &[BvhNode]) -> Costs {
        let n = nodes.len();
        // Zeroed huge-page mappings from 2 MiB on (the costs are 17 MB at 1M
        // triangles, where `vec!`'s pages took a fault per 4 KiB, or a `memset` when
        // reused), written through plain slices: a `HugeVec`'s every access looks at its
        // backing. `flat` stays a `Vec` (`bool` is not `Pod`; 0.5 MB at 1M).
        let mut first_v = HugeVec::zeroed(n, Backing::Auto);
        let mut count_v = HugeVec::zeroed(n, Backing::Auto);
        let mut cost_v = HugeVec::zeroed(n, Backing::Auto);
        let mut flat = vec![false; n];
        let (first, count) = (first_v.as_mut_slice(), count_v.as_mut_slice());
        let cost: &mut [[f32; WIDTH]] = cost_v.as_mut_slice();
        // Children follow their parent: reverse order meets them first.
        for b in (0..n).rev() {
            let node = &nodes[b];
            if node.is_leaf() {
                let bounds = node.bounds();
                (first[b], count[b]) = (node.offset, node.count);
                flat[b] = is_flat(&bounds);
                cost[b] = [leaf_cost(bounds.surface_area(), node.count); WIDTH];
                continue;
            }
            let (left, right) = (b + 1, node.offset as usize);
            (first[b], count[b]) = (first[left], count[left] + count[right]);
            // Only what a leaf could hold needs it (`single`); above, it stays false.
            if count[b] <= MAX_LEAF {
                flat[b] = flat[left] && flat[right];
            }
            let splits = splits(&cost[left], &cost[right]);
            let bounds = node.bounds();
            let room = flat[b] && encloses(&bounds);
            let mut best = single(bounds.surface_area(), count[b], splits[WIDTH - 1], room).0;
            cost[b][0] = best;
            for i in 2..=WIDTH {
                best = best.min(splits[i - 1]);
                cost[b][i - 1] = best;
            }
        }
        Costs {
            first: first_v.into(),
            count: count_v.into(),
            flat,
            cost: cost_v.into(),
        }
    }

    /// [`single`] of interior node `b`.
    fn single(&self, nodes: &[BvhNode], b: usize) -> (f32, bool) {
        let bounds = nodes[b].bounds();
        let room = self.flat[b] && encloses(&bounds);
        single(
            bounds.surface_area(),
            self.count[b],
            self.split(nodes, b, WIDTH).0,
            room,
        )
    }

    /// The least cost of interior node `b`'s two children in at most `i` (2 or more)
    /// lanes together, and the lanes of the first child in it (the fewest of equals).
    fn split(&self, nodes: &[BvhNode], b: usize, i: usize) -> (f32, usize) {
        let (left, right) = (b + 1, nodes[b].offset as usize);
        let mut best = (f32::INFINITY, 1);
        for k in 1..i {
            let cost = self.cost[left][k - 1] + self.cost[right][i - k - 1];
            if cost < best.0 {
                best = (cost, k);
            }
        }
        best
    }

    /// Appends to `lanes` the lanes of binary node `b`'s subtree in at most `i` lanes,
    /// at the least cost, in depth-first (slot) order: `(node, leaf)`.
    fn lanes(&self, nodes: &[BvhNode], b: usize, i: usize, lanes: &mut Lanes) {
        if nodes[b].is_leaf() {
            lanes.push((b, true));
            return;
        }
        // The fewest lanes that reach the least cost, as `new` took the minimum.
        let fewest = (1..=i)
            .find(|&j| self.cost[b][j - 1] == self.cost[b][i - 1])
            .unwrap_or(i);
        if fewest == 1 {
            lanes.push((b, self.single(nodes, b).1));
            return;
        }
        let k = self.split(nodes, b, fewest).1;
        self.lanes(nodes, b + 1, k, lanes);
        self.lanes(nodes, nodes[b].offset as usize, fewest - k, lanes);
    }

    /// Appends the wide node for binary node `b` (a leaf only at the root) and its
    /// subtree at `depth`; returns its index and the deepest level in its subtree. Each
    /// leaf lane's `(child, count)` comes from `leaf(first slot, count)`, called in slot
    /// order.
    fn node(
        &self,
        nodes: &[BvhNode],
        b: usize,
        depth: u32,
        out: &mut HugeVec<WideNode>,
        leaf: &mut impl FnMut(u32, u32) -> (u32, u32),
    ) -> (u32, u32) {
        let me = out.len();
        out.push(WideNode::UNUSED);
        let mut lanes = Lanes::new();
        if nodes[b].is_leaf() {
            lanes.push((b, true));
        } else {
            let k = self.split(nodes, b, WIDTH).1;
            self.lanes(nodes, b + 1, k, &mut lanes);
            self.lanes(nodes, nodes[b].offset as usize, WIDTH - k, &mut lanes);
        }
        let mut deepest = depth;
        for (lane, &(k, is_leaf)) in lanes.iter().enumerate() {
            out[me].set_child_bounds(lane, nodes[k].bounds());
            if is_leaf {
                (out[me].child[lane], out[me].count[lane]) = leaf(self.first[k], self.count[k]);
            } else {
                let (child, d) = self.node(nodes, k, depth + 1, out, leaf);
                out[me].child[lane] = child;
                deepest = deepest.max(d);
            }
        }
        (me as u32, deepest)
    }
}

/// Appends the wide nodes of `bvh` (not empty), root first; returns the deepest level
/// below the root. Each leaf lane's `(child, count)` comes from `leaf(first slot,
/// count)`, called in slot order (a leaf's triangles are `prim_indices[first..first +
/// count]`).
pub(super) fn collapse(
    bvh: &Bvh,
    out: &mut HugeVec<WideNode>,
    leaf: &mut impl FnMut(u32, u32) -> (u32, u32),
) -> u32 {
    // The nodes as one slice: a `HugeVec`'s every index looks at its backing.
    let nodes = bvh.nodes.as_slice();
    Costs::new(nodes).node(nodes, 0, 0, out, leaf).1
}

/// The least cost the collapse finds for `bvh` (not empty), root node included: the
/// cost of the tree it makes.
#[cfg(test)]
pub(super) fn least_cost(bvh: &Bvh) -> f32 {
    let nodes = bvh.nodes.as_slice();
    let c = Costs::new(nodes);
    let root = &nodes[0];
    let lanes = if root.is_leaf() {
        c.cost[0][0]
    } else {
        c.split(nodes, 0, WIDTH).0
    };
    NODE_COST * root.bounds().surface_area() + lanes
}
