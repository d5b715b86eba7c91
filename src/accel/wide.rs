//! An 8-wide BVH over triangles for the render's hot path: the binned-SAH binary
//! tree of [`super::build`] collapsed into nodes of up to eight children whose
//! boxes are stored structure-of-arrays, so that one slab test covers all eight
//! (plain `[f32; 8]` lanes that the compiler vectorises, one AVX2 register in the
//! AVX2 clone of the queries; safe code only, as `lib.rs` forbids any other), and the
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

use super::bvh::{Bvh, MAX_DEPTH};
use super::huge::{Backing, HugeSlice, HugeVec};
use super::leaf::{LANES, LeafTris, NO_PRIM, groups_for, push_leaf};
use super::wide_collapse::collapse;
use super::wide_node::{EMPTY, RayBoxes, leaf_lanes};
pub use super::wide_node::{WIDTH, WideNode};
use super::wide_query::LeafVisitor;
use super::{Aabb, BOX_MARGIN};
use arrayvec::ArrayVec;
use glam::Vec3;
use std::collections::HashMap;

/// A `WIDTH`-wide BVH with its triangles in leaf order; root at node 0.
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// Nodes, each after its parent; empty for no triangles.
    pub nodes: HugeSlice<WideNode>,
    /// Triangle vertices in leaf order, in groups of `leaf::LANES`, each with the
    /// caller's index of its triangles.
    pub leaves: LeafTris,
    /// Triangles held (lanes that are not padding).
    pub triangles: usize,
    /// Bounds of everything.
    pub bounds: Aabb,
    /// Levels of nodes below the root's (at most the binary tree's depth).
    pub depth: u32,
}

/// Wide nodes to reserve for a binary tree of `binary` nodes: the collapse makes 0.10
/// per binary node on the anchors' meshes (torus 100k: 5,008 for 52,185; Sponza 0.10,
/// MetalRoughSpheres 0.09), so an eighth leaves room.
fn wide_node_estimate(binary: usize) -> usize {
    binary / 8 + 1
}

/// Traversal stack entries any tree needs: each of at most `MAX_DEPTH` levels below
/// the root pushes at most `WIDTH - 1` children, plus the root.
const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH as usize + 1;

/// The traversal stack: on the call stack and never initialised (an `ArrayVec`
/// writes only what is pushed), so its size costs nothing per ray.
type Stack = ArrayVec<(u32, f32), STACK_SIZE>;

/// Sort key of lane `lane` entered at `t` (not NaN, not below zero): ordered by t
/// then lane, as the bits of a non-negative f32 are ordered like the f32.
#[inline(always)]
fn key(t: f32, lane: u32) -> u64 {
    ((t.to_bits() as u64) << 32) | lane as u64
}

/// Whether a box entered at `t_entry` lies beyond the cull distance `t_max`, with the
/// slab test's margin: a box entry rounded just past a hit on its face must not hide a
/// tie there, or the hit found would depend on the visiting order.
#[inline(always)]
fn beyond(t_entry: f32, t_max: f32) -> bool {
    t_entry > t_max * BOX_MARGIN
}

/// Pops the node of the top entry, skipping (with `CULL`) entries whose box lies
/// `beyond` `t_max`: pushed earlier, it may now lie beyond the closest hit found
/// since. None when the stack runs out.
#[inline(always)]
fn pop_node<const CULL: bool>(stack: &mut Stack, t_max: f32) -> Option<u32> {
    while let Some((index, t_entry)) = stack.pop() {
        if CULL && beyond(t_entry, t_max) {
            continue;
        }
        return Some(index);
    }
    None
}

impl WideBvh {
    /// Collapses `bvh` (built over `positions`) into `WIDTH`-wide nodes, each taking the
    /// cut of its binary subtree of least surface-area cost, each leaf a binary subtree
    /// of up to `wide_collapse::MAX_LEAF` triangles (see `wide_collapse`); the
    /// triangles keep the binary tree's order.
    pub fn collapse(bvh: &Bvh, positions: &[[Vec3; 3]]) -> WideBvh {
        WideBvh::collapse_backed(bvh, positions, Backing::Auto)
    }

    /// [`WideBvh::collapse`] with the nodes and leaf groups kept as `backing` says
    /// (huge-page mappings from 2 MiB on with `Auto`; tests force either).
    pub(super) fn collapse_backed(bvh: &Bvh, positions: &[[Vec3; 3]], backing: Backing) -> WideBvh {
        if bvh.nodes.is_empty() {
            return WideBvh::default();
        }
        let groups = bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| groups_for(n.count as usize))
            .sum();
        // As many groups as the binary leaves fill: merged leaves may fill fewer, so the
        // array is cut to what was written.
        let mut leaves = HugeVec::zeroed(groups, backing);
        let nodes = wide_node_estimate(bvh.nodes.len());
        let mut nodes = HugeVec::with_backing(nodes, backing);
        let (out, mut next) = (leaves.as_mut_slice(), 0);
        let depth = collapse(bvh, &mut nodes, &mut |slot, count| {
            let lane = push_leaf(out, next, slot, count, &bvh.prim_indices, positions);
            next += groups_for(count as usize);
            lane
        });
        leaves.truncate(next);
        // Not shrunk to fit: a `Vec` of 64-byte-aligned nodes has no `realloc` of its
        // own (Rust's allocator copies over-aligned memory into a fresh block), so the
        // shrink copied every node (torus 100k: 1.3 MB; the collapse's page faults
        // 414 -> 321 without it); the unused tail, about a fifth, is never written.
        WideBvh {
            nodes: nodes.into(),
            leaves: LeafTris {
                groups: leaves.into(),
            },
            // Not `prim_indices.len()`: a spatial split's tree holds some triangles twice.
            triangles: positions.len(),
            bounds: bvh.bounds(),
            depth,
        }
    }

    /// FNV-1a over the bytes of every node and leaf group, 8 at a time: equal for equal
    /// trees, so a collapse change that alters the wide tree shows.
    pub fn tree_hash(&self) -> u64 {
        let nodes: &[u64] = bytemuck::cast_slice(self.nodes.as_slice());
        let groups: &[u64] = bytemuck::cast_slice(self.leaves.groups.as_slice());
        nodes
            .iter()
            .chain(groups)
            .fold(0xcbf2_9ce4_8422_2325, |h, &w| {
                (h ^ w).wrapping_mul(0x0000_0100_0000_01b3)
            })
    }

    /// Bytes held: nodes, triangles and indices (not the huge-page mappings' unused
    /// room: see [`WideBvh::reserved_bytes`]).
    pub fn bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice()) + self.leaves.bytes()
    }

    /// Bytes of address space the nodes and leaf groups reserve: a large array's
    /// mapping is whole huge pages and one more for alignment, of which only the
    /// pages touched take memory (the array rounded up to a huge page).
    pub fn reserved_bytes(&self) -> usize {
        self.nodes.reserved_bytes() + self.leaves.groups.reserved_bytes()
    }

    /// The caller's index of the triangle in lane `lane` of group `group` (a lane
    /// holding a triangle, not padding).
    #[inline(always)]
    pub fn prim_at(&self, group: usize, lane: usize) -> u32 {
        self.leaves.groups[group].prim[lane]
    }

    /// The vertices of the triangle at `lane` (`group * LANES + lane`, as
    /// [`WideBvh::closest_hit_at`] reports it), read from its leaf group.
    #[inline]
    pub fn triangle_at(&self, lane: u32) -> [Vec3; 3] {
        let lane = lane as usize;
        self.leaves.groups[lane / LANES].triangle(lane % LANES)
    }

    /// Where each of the caller's triangles sits in `leaves` (`group * LANES + lane`; its
    /// last lane where a spatial split put it in several, which all hold its vertices):
    /// computed, not held, as a render reaches a triangle's vertices through its hit.
    pub fn prim_lanes(&self) -> Vec<u32> {
        let mut lanes = vec![0; self.triangles];
        for (lane, p) in self.leaves.prims().enumerate() {
            if p != NO_PRIM {
                lanes[p as usize] = lane as u32;
            }
        }
        lanes
    }

    /// The vertices of every triangle, in the caller's order.
    pub fn positions(&self) -> Vec<[Vec3; 3]> {
        self.prim_lanes()
            .into_iter()
            .map(|lane| self.triangle_at(lane))
            .collect()
    }

    /// Visits the leaves below node `root` (0: the whole tree) the ray of `boxes` meets
    /// in near-to-far order of their boxes' entry distances while they start before
    /// `*t_max` (`NEAREST_FIRST`), or each node's leaves before its interior children
    /// without sorting (for any-hit queries, where order does not decide the answer);
    /// `visitor.leaf(first, count, t_max)` may lower `t_max` and returns true to stop.
    /// Returns whether a leaf stopped it.
    #[inline(always)]
    pub(super) fn traverse<const NEAREST_FIRST: bool>(
        &self,
        root: u32,
        boxes: &RayBoxes,
        t_max: &mut f32,
        visitor: &mut impl LeafVisitor,
    ) -> bool {
        // No test of the root's own box: the root's test of its children's boxes culls
        // the same rays (a box inside another is met only by rays that meet that one),
        // and most rays meet it anyway (a packet hands over a node whose box it met).
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = Stack::new();
        // The node to visit: the root, then a node's nearest interior child (any-hit:
        // its last, which would be popped first) without a round trip through the
        // stack, else the top of the stack.
        let mut index = root;
        // Lane indices below are taken `% WIDTH` (a no-op: masks have WIDTH bits) so
        // that the compiler drops the bounds checks on the node's lane arrays: 1,528 /
        // 1,914 -> 1,515 / 1,898 instructions per primary / incoherent ray (torus 100k).
        // The same in `queue_nearest_first` cost 1,542 / 1,938 (code layout), so not there.
        loop {
            let node = &self.nodes[index as usize];
            let (t, hit) = boxes.test(node, *t_max);
            let leaf_mask = leaf_lanes(node);
            let (mut leaves, inner) = (hit & leaf_mask, hit & !leaf_mask);
            let mut next = if NEAREST_FIRST {
                self.queue_nearest_first(node, &t, inner, &mut stack)
            } else {
                // Any hit: the last interior child next, the others pushed. Its leaves
                // are tested below before either. No entry distance: the cull distance
                // of any-hit queries never falls, so no box met is culled later (a zero,
                // not `t[lane]`, spares the store of `t`).
                let mut inner = inner;
                let mut next = None;
                while inner != 0 {
                    let lane = inner.trailing_zeros() as usize % WIDTH;
                    inner &= inner - 1;
                    let entry = (node.child[lane], 0.0);
                    if inner == 0 {
                        next = Some(entry);
                    } else {
                        stack.push(entry);
                    }
                }
                next
            };
            if leaves != 0 {
                // `next` waits on the stack while the leaves are tested, popped after
                // them with the others' entry distance check (the leaves may lower the
                // cull distance below it): then no node index lives across the leaf
                // tests' calls, which kept it on the call stack at every node. Without
                // leaves it needs no check: its box was met just now within the same
                // cull distance (entry <= min(exit, t_max) * BOX_MARGIN <= t_max *
                // BOX_MARGIN, the product being monotonic). The stack still takes at
                // most `WIDTH - 1` entries per level: a node with leaves has at most
                // that many interior children.
                if let Some(entry) = next.take() {
                    stack.push(entry);
                }
                // The leaves met load from memory together, while the first is tested:
                // the first read of a leaf's group, a cache miss, was the leaf test's
                // largest stall in perf (a quarter of its time). Prefetching the next
                // node as well did not pay, nor did these prefetches before the
                // queueing above. (A pointer: no bounds check, as nothing is read
                // through it.)
                let groups = self.leaves.groups.as_ptr();
                if NEAREST_FIRST && leaves & (leaves - 1) == 0 {
                    // One leaf (three in four nodes with leaves on the torus): no loop,
                    // whose exit branch the predictor missed, and no entry distance
                    // check, as its box was met just now within the same cull distance
                    // (see `next` above).
                    let lane = leaves.trailing_zeros() as usize % WIDTH;
                    let (child, count) = (node.child[lane], node.count[lane]);
                    visitor.prefetch(groups.wrapping_add(child as usize));
                    if visitor.leaf(child as usize, count, t_max) {
                        return true;
                    }
                } else if NEAREST_FIRST {
                    let mut met = leaves;
                    while met != 0 {
                        let lane = met.trailing_zeros() as usize % WIDTH;
                        met &= met - 1;
                        visitor.prefetch(groups.wrapping_add(node.child[lane] as usize));
                    }
                    // Leaves nearest first, after the interior children are queued, the
                    // two nearest at a time (`LeafVisitor::leaf_pair`: one 8-lane pass
                    // for two one-group leaves). The far one's box starts no nearer, so
                    // when the near one's is culled, so is the far one's.
                    let leaf = |lane: u32| {
                        let lane = lane as usize % WIDTH;
                        (node.child[lane] as usize, node.count[lane])
                    };
                    while leaves != 0 {
                        if leaves & (leaves - 1) == 0 {
                            let lane = leaves.trailing_zeros();
                            leaves = 0;
                            let (child, count) = leaf(lane);
                            if t[lane as usize % WIDTH] <= *t_max * BOX_MARGIN
                                && visitor.leaf(child, count, t_max)
                            {
                                return true;
                            }
                            continue;
                        }
                        let mut rest = leaves;
                        let (mut near, mut far) = (u64::MAX, u64::MAX);
                        while rest != 0 {
                            let lane = rest.trailing_zeros();
                            rest &= rest - 1;
                            let k = key(t[lane as usize % WIDTH], lane);
                            if k < near {
                                far = near;
                                near = k;
                            } else {
                                far = far.min(k);
                            }
                        }
                        let (near, far) = (near as u32, far as u32);
                        leaves &= !(1 << near | 1 << far);
                        if t[near as usize % WIDTH] <= *t_max * BOX_MARGIN
                            && visitor.leaf_pair(
                                [leaf(near), leaf(far)],
                                t[far as usize % WIDTH],
                                t_max,
                            )
                        {
                            return true;
                        }
                    }
                } else {
                    // Any hit: the cull distance stays.
                    while leaves != 0 {
                        let lane = leaves.trailing_zeros() as usize % WIDTH;
                        leaves &= leaves - 1;
                        let (child, count) = (node.child[lane], node.count[lane]);
                        if visitor.leaf(child as usize, count, t_max) {
                            return true;
                        }
                    }
                }
            }
            index = match next {
                Some((child, _)) => child,
                None => match pop_node::<NEAREST_FIRST>(&mut stack, *t_max) {
                    Some(child) => child,
                    None => return false,
                },
            };
        }
    }

    /// Queues the interior children `inner` of `node` met at entry distances `t`
    /// nearest first: returns the nearest, to visit next, and pushes the others nearest
    /// last, so that it is popped first; most nodes have at most one, which needs no
    /// sort.
    #[inline(always)]
    fn queue_nearest_first(
        &self,
        node: &WideNode,
        t: &[f32; WIDTH],
        mut inner: u32,
        stack: &mut Stack,
    ) -> Option<(u32, f32)> {
        if inner & inner.wrapping_sub(1) == 0 {
            if inner == 0 {
                return None;
            }
            let lane = inner.trailing_zeros() as usize;
            return Some((node.child[lane], t[lane]));
        }
        if (inner & (inner - 1)).count_ones() == 1 {
            // Two: one comparison, of the t bits alone, as the lanes are in order (the
            // keys' order). Lanes `% WIDTH` (a no-op) to drop the bounds checks. A branch
            // (the two arms push different entries), not a select: the next node's load
            // then waits for neither t nor the compare where the order is predicted, as
            // on coherent rays (torus 100k primary rays 2% less time, incoherent the same).
            let a = inner.trailing_zeros() as usize % WIDTH;
            let b = (31 - inner.leading_zeros()) as usize % WIDTH;
            if t[b].to_bits() < t[a].to_bits() {
                stack.push((node.child[a], t[a]));
                return Some((node.child[b], t[b]));
            }
            stack.push((node.child[b], t[b]));
            return Some((node.child[a], t[a]));
        }
        // Three or four (nine in ten nodes of three or more on the torus): the keys of
        // the first four lanes (the fourth's the largest key when there are three)
        // through a sorting network, without a branch but on their number.
        let r1 = inner & (inner - 1);
        let r2 = r1 & (r1 - 1);
        let r3 = r2 & (r2 - 1);
        if r3 & r3.wrapping_sub(1) == 0 {
            let key_at = |m: u32| {
                let lane = m.trailing_zeros();
                key(t[lane as usize % WIDTH], lane)
            };
            let mut k = [key_at(inner), key_at(r1), key_at(r2), u64::MAX];
            if r3 != 0 {
                k[3] = key_at(r3);
            }
            // Ascending: k[0] the nearest.
            let mut exchange = |i: usize, j: usize| {
                let (a, b) = (k[i], k[j]);
                k[i] = a.min(b);
                k[j] = a.max(b);
            };
            exchange(0, 1);
            exchange(2, 3);
            exchange(0, 2);
            exchange(1, 3);
            exchange(1, 2);
            let entry = |k: u64| {
                let lane = k as u32 as usize % WIDTH;
                (node.child[lane], t[lane])
            };
            // The fourth pushed then dropped again when there are three, so that the
            // number pushed takes no branch.
            let len = stack.len();
            stack.push(entry(k[3]));
            stack.truncate(len + (r3 != 0) as usize);
            stack.push(entry(k[2]));
            stack.push(entry(k[1]));
            return Some(entry(k[0]));
        }
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
        Some((node.child[lane], t[lane]))
    }

    /// Checks every structural invariant against the triangles it was built from;
    /// Err names the first violation. Invariants: every node is reached once from the
    /// root and after its parent; leaves are non-empty and own their triangle groups,
    /// a lane holding triangle `p` holding `positions[p]`, padding lanes NaN and
    /// [`NO_PRIM`]; each of `0..positions.len()` is in a lane, and `triangles` counts
    /// them; every group belongs to a leaf; a child box contains its node's children's
    /// boxes; a triangle lies in a leaf box that holds it whole or (cut by spatial
    /// splits) in the union of its leaves' boxes, which [`covers`] samples; `bounds`
    /// contains the root's children; unused slots have no box; no node lies deeper than
    /// `depth`.
    pub fn validate(&self, positions: &[[Vec3; 3]]) -> Result<(), String> {
        let n = positions.len();
        if self.triangles != n {
            return Err(format!("{} triangles counted for {n}", self.triangles));
        }
        if self.nodes.is_empty() {
            return if n == 0 {
                Ok(())
            } else {
                Err(format!("no nodes for {n} triangles"))
            };
        }
        let mut used = vec![false; self.leaves.groups.len()];
        let mut reached = vec![false; self.nodes.len()];
        // Whether a leaf box holds triangle `p` whole; else the boxes of its leaves.
        let mut whole = vec![false; n];
        let mut parts: HashMap<u32, Vec<Aabb>> = HashMap::new();
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
                let leaf = |p: u32, tri: [Vec3; 3]| {
                    let Some(w) = whole.get_mut(p as usize) else {
                        return Err(format!("triangle {p} out of range"));
                    };
                    if tri != positions[p as usize] {
                        return Err(format!("a lane of triangle {p} holds other vertices"));
                    }
                    if b.contains_box(&Aabb::from_points(&tri)) {
                        *w = true;
                    } else {
                        parts.entry(p).or_default().push(b);
                    }
                    Ok(())
                };
                self.leaves
                    .validate_leaf(child as usize, count, &mut used, leaf)
                    .map_err(|e| format!("node {i} lane {lane}: {e}"))?;
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Err(format!("node {i} is unreachable"));
        }
        for (p, tri) in positions.iter().enumerate() {
            if whole[p] {
                continue;
            }
            match parts.get(&(p as u32)) {
                None => return Err(format!("triangle {p} is in no leaf")),
                Some(boxes) if !covers(boxes, tri) => {
                    return Err(format!("triangle {p} is outside its leaves' boxes"));
                }
                Some(_) => {}
            }
        }
        if let Some(g) = used.iter().position(|u| !u) {
            return Err(format!("triangle group {g} is in no leaf"));
        }
        Ok(())
    }
}

/// Whether the union of `boxes` holds triangle `tri`, sampled: its points at barycentric
/// coordinates in steps of 1/8, each within a few units in the last place of the
/// triangle's largest coordinate (the samples' rounding) of a box.
fn covers(boxes: &[Aabb], tri: &[Vec3; 3]) -> bool {
    const STEPS: u32 = 8;
    let [a, b, c] = *tri;
    let size = a.abs().max(b.abs()).max(c.abs()).max_element();
    let slack = Vec3::splat(8.0 * f32::EPSILON * size);
    (0..=STEPS).all(|i| {
        (0..=STEPS - i).all(|j| {
            let (u, v) = (i as f32 / STEPS as f32, j as f32 / STEPS as f32);
            let p = a + u * (b - a) + v * (c - a);
            boxes
                .iter()
                .any(|bx| (bx.min - slack).cmple(p).all() && p.cmple(bx.max + slack).all())
        })
    })
}

#[cfg(test)]
#[path = "wide_tests.rs"]
mod tests;
