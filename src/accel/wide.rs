//! A 4-wide BVH over triangles for the render's hot path: the binned-SAH binary
//! tree of [`super::build`] collapsed into nodes of up to four children whose
//! boxes are stored structure-of-arrays, so that one slab test covers all four
//! (plain `[f32; 4]` lanes that the compiler vectorises; no `unsafe`), and the
//! triangles copied in leaf order, so a leaf reads consecutive memory instead of
//! going through the primitive indices.
//!
//! The slab test is the binary tree's (Ize 2013: near and far planes chosen by
//! the sign of the inverse direction, NaN bounds ignored, exit distance enlarged
//! by `1 + 2 gamma(3)`), so a box is culled only when the exact ray misses it,
//! and the triangle test is the same watertight test with the per-ray shear: the
//! closest hit is the binary tree's, up to which of two triangles at exactly the
//! same t is met first.

use glam::Vec3;

use super::bvh::{Bvh, MAX_DEPTH};
use super::triangle::{RayShear, TriangleHit, intersect_triangle_sheared};
use super::{Aabb, Ray, gamma};

/// Children per node.
pub const WIDTH: usize = 4;

/// `child` of an unused slot.
const EMPTY: u32 = u32::MAX;

/// A node of up to four children; box planes are SoA: `bounds[axis][lane]` for the
/// minimum corner (axis 0..3) and `bounds[3 + axis][lane]` for the maximum.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Child boxes: min x, y, z then max x, y, z, one lane per child.
    pub bounds: [[f32; WIDTH]; 6],
    /// Interior child: its node index. Leaf child: its first slot in `tris`. Unused: `u32::MAX`.
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

/// A 4-wide BVH with its triangles in leaf order; root at node 0.
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// Nodes, each after its parent; empty for no triangles.
    pub nodes: Vec<WideNode>,
    /// Triangle vertices in leaf order.
    pub tris: Vec<[Vec3; 3]>,
    /// The caller's index of each triangle in `tris`.
    pub prims: Vec<u32>,
    /// Bounds of everything.
    pub bounds: Aabb,
    /// Levels of nodes below the root's (at most the binary tree's depth).
    pub depth: u32,
}

/// Traversal stack entries on the call stack: enough for a tree of depth 21, as
/// each level pushes at most three children. It is filled once per ray, so it is
/// kept small; deeper trees take a heap stack (3 × `MAX_DEPTH` + 1 at most).
const STACK_SIZE: usize = 64;

/// Stack entries a tree of `depth` levels below the root needs.
fn stack_size(depth: u32) -> usize {
    (WIDTH - 1) * depth as usize + 1
}

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

    /// Entry distance of each child box the ray meets in [0, t_max], else +inf.
    /// The same arithmetic as [`Aabb::intersect_ray`], lane by lane, in a loop
    /// without branches so that it compiles to SIMD.
    #[inline(always)]
    fn test(&self, node: &WideNode, t_max: f32) -> [f32; WIDTH] {
        let b = &node.bounds;
        let (o, inv) = (self.origin, self.inv_dir);
        let scale = 1.0 + 2.0 * gamma(3);
        let mut out = [f32::INFINITY; WIDTH];
        for (lane, out) in out.iter_mut().enumerate() {
            let near_x = (b[self.near[0]][lane] - o[0]) * inv[0];
            let near_y = (b[self.near[1]][lane] - o[1]) * inv[1];
            let near_z = (b[self.near[2]][lane] - o[2]) * inv[2];
            let far_x = (b[self.far[0]][lane] - o[0]) * inv[0];
            let far_y = (b[self.far[1]][lane] - o[1]) * inv[1];
            let far_z = (b[self.far[2]][lane] - o[2]) * inv[2];
            let t_near = 0.0f32.max(near_x).max(near_y).max(near_z);
            let t_far = t_max.min(far_x).min(far_y).min(far_z) * scale;
            *out = if t_near <= t_far {
                t_near
            } else {
                f32::INFINITY
            };
        }
        out
    }
}

impl WideBvh {
    /// Collapses `bvh` (built over `positions`) into 4-wide nodes, each taking the
    /// largest-area interior grandchildren in place of their parents; leaves and
    /// their triangle order are the binary tree's.
    pub fn collapse(bvh: &Bvh, positions: &[[Vec3; 3]]) -> WideBvh {
        if bvh.nodes.is_empty() {
            return WideBvh::default();
        }
        let mut nodes = Vec::with_capacity(bvh.nodes.len() / 2 + 1);
        let depth = collapse_node(bvh, 0, 0, &mut nodes).1;
        let prims = bvh.prim_indices.clone();
        let tris = prims.iter().map(|&p| positions[p as usize]).collect();
        WideBvh {
            nodes,
            tris,
            prims,
            bounds: bvh.bounds(),
            depth,
        }
    }

    /// Bytes held: nodes, triangles and indices.
    pub fn bytes(&self) -> usize {
        size_of_val(self.nodes.as_slice())
            + size_of_val(self.tris.as_slice())
            + size_of_val(self.prims.as_slice())
    }

    /// Visits leaves in near-to-far order of their boxes' entry distances while
    /// they start before `*t_max`; `leaf(first, count, t_max)` may lower `t_max`
    /// and returns true to stop. Returns whether a leaf stopped it.
    #[inline(always)]
    fn traverse(
        &self,
        ray: &Ray,
        t_max: &mut f32,
        mut leaf: impl FnMut(usize, usize, &mut f32) -> bool,
    ) -> bool {
        if self.nodes.is_empty()
            || self
                .bounds
                .intersect_ray(ray.origin, ray.dir.recip(), *t_max)
                .is_none()
        {
            return false;
        }
        let need = stack_size(self.depth);
        let mut small = [(0, 0.0); STACK_SIZE];
        let mut large = Vec::new();
        // One call site, so that the traversal and the leaf test inline into it once.
        let stack: &mut [(u32, f32)] = if need <= STACK_SIZE {
            &mut small
        } else {
            large.resize(need, (0, 0.0));
            &mut large
        };
        self.traverse_with(stack, ray, t_max, &mut leaf)
    }

    /// [`Self::traverse`] with the stack given (root at entry 0).
    #[inline(always)]
    fn traverse_with(
        &self,
        stack: &mut [(u32, f32)],
        ray: &Ray,
        t_max: &mut f32,
        leaf: &mut impl FnMut(usize, usize, &mut f32) -> bool,
    ) -> bool {
        let boxes = RayBoxes::new(ray);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (index, t_entry) = stack[sp];
            // A box pushed earlier may now lie beyond the closest hit found since.
            if t_entry > *t_max {
                continue;
            }
            let node = &self.nodes[index as usize];
            let t = boxes.test(node, *t_max);
            // Children met, nearest last so that it is popped first.
            let mut order = [0usize; WIDTH];
            let mut n = 0;
            for lane in 0..WIDTH {
                if t[lane] == f32::INFINITY {
                    continue;
                }
                let mut k = n;
                while k > 0 && t[order[k - 1]] < t[lane] {
                    order[k] = order[k - 1];
                    k -= 1;
                }
                order[k] = lane;
                n += 1;
            }
            for &lane in &order[..n] {
                let (child, count) = (node.child[lane], node.count[lane]);
                if count == 0 {
                    stack[sp] = (child, t[lane]);
                    sp += 1;
                }
            }
            // Leaves nearest first, after the interior children are queued.
            for &lane in order[..n].iter().rev() {
                let (child, count) = (node.child[lane], node.count[lane]);
                if count > 0 && t[lane] <= *t_max && leaf(child as usize, count as usize, t_max) {
                    return true;
                }
            }
        }
        false
    }

    /// The closest hit in (0, t_max): the caller's triangle index and the hit. Of
    /// triangles hit at exactly the same t (where two meet), the lowest index wins,
    /// whatever order the traversal meets them in.
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(u32, TriangleHit)> {
        let shear = RayShear::new(ray);
        let mut best: Option<(u32, TriangleHit)> = None;
        let mut t_max = t_max;
        self.traverse(ray, &mut t_max, |first, count, t_max| {
            for k in first..first + count {
                let [a, b, c] = self.tris[k];
                // Up to and including the best t so far, for the tie-break.
                let bound = if best.is_some() {
                    t_max.next_up()
                } else {
                    *t_max
                };
                let Some(h) = intersect_triangle_sheared(&shear, ray.origin, a, b, c, bound) else {
                    continue;
                };
                let p = self.prims[k];
                if best.is_none_or(|(bp, bh)| h.t < bh.t || p < bp) {
                    *t_max = h.t;
                    best = Some((p, h));
                }
            }
            false
        });
        best
    }

    /// Visits triangles the ray meets in (0, t_max), in no particular order, until
    /// `visit(prim, hit)` returns true (stop); returns whether it stopped.
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, &TriangleHit) -> bool,
    ) -> bool {
        let shear = RayShear::new(ray);
        let mut t = t_max;
        self.traverse(ray, &mut t, |first, count, _| {
            (first..first + count).any(|k| {
                let [a, b, c] = self.tris[k];
                intersect_triangle_sheared(&shear, ray.origin, a, b, c, t_max)
                    .is_some_and(|h| visit(self.prims[k], &h))
            })
        })
    }

    /// Checks every structural invariant against the triangles it was built from;
    /// Err names the first violation. Invariants: `prims` is a permutation of
    /// `0..positions.len()` and `tris[k] == positions[prims[k]]`; every node is
    /// reached once from the root and after its parent; leaves are non-empty and
    /// cover `tris` without gaps or overlap; a child box contains its node's
    /// children's boxes, a leaf box its triangles; `bounds` contains the root's
    /// children; unused slots have no box; no node lies deeper than `depth`.
    pub fn validate(&self, positions: &[[Vec3; 3]]) -> Result<(), String> {
        let n = positions.len();
        if self.prims.len() != n || self.tris.len() != n {
            return Err(format!(
                "{} prims and {} tris for {n} triangles",
                self.prims.len(),
                self.tris.len()
            ));
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
            if self.tris[k] != positions[p as usize] {
                return Err(format!("tris[{k}] is not triangle {p}"));
            }
        }
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
                let (first, count) = (child as usize, count as usize);
                if first + count > n {
                    return Err(format!("node {i} lane {lane}: leaf past the end"));
                }
                let slots = first..first + count;
                for (k, tri) in slots.clone().zip(&self.tris[slots]) {
                    if std::mem::replace(&mut covered[k], true) {
                        return Err(format!("triangle slot {k} in two leaves"));
                    }
                    if !b.contains_box(&Aabb::from_points(tri)) {
                        return Err(format!("node {i} lane {lane}: slot {k} outside the box"));
                    }
                }
            }
        }
        if let Some(i) = reached.iter().position(|r| !r) {
            return Err(format!("node {i} is unreachable"));
        }
        if let Some(k) = covered.iter().position(|c| !c) {
            return Err(format!("triangle slot {k} is in no leaf"));
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
    // Open the interior child of largest area until four children are reached.
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
mod tests {
    use super::*;
    use crate::accel::SplitMethod;
    use crate::test_util::Lcg;
    use glam::vec3;

    type Tri = [Vec3; 3];

    fn random_tris(n: usize, seed: u64) -> Vec<Tri> {
        let mut rng = Lcg(seed);
        (0..n)
            .map(|_| {
                let c = rng.vec() * 10.0 - Vec3::splat(5.0);
                [c, c + rng.dir() * 0.5, c + rng.dir() * 0.5]
            })
            .collect()
    }

    /// A grid of quads in the plane y = 0: rays through shared edges and vertices.
    fn grid(n: usize) -> Vec<Tri> {
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let p = |a: usize, b: usize| vec3(a as f32, 0.0, b as f32);
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        tris
    }

    fn both(tris: &[Tri], split: SplitMethod) -> (Bvh, WideBvh) {
        let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
        let bvh = Bvh::build(&bounds, split);
        let wide = WideBvh::collapse(&bvh, tris);
        (bvh, wide)
    }

    fn rays(n: usize, seed: u64) -> Vec<(Ray, f32)> {
        let mut rng = Lcg(seed);
        (0..n)
            .map(|i| {
                let o = rng.vec() * 14.0 - Vec3::splat(7.0);
                let mut d = rng.dir();
                // Axis-aligned directions have zero components (inf inverse).
                if i % 10 == 0 {
                    d = Vec3::ZERO;
                    d[i / 10 % 3] = if i % 20 == 0 { 1.0 } else { -1.0 };
                }
                let t_max = if i % 3 == 0 { 4.0 } else { f32::INFINITY };
                (Ray::new(o, d * (0.5 + rng.next_f32())), t_max)
            })
            .collect()
    }

    fn binary_closest(bvh: &Bvh, tris: &[Tri], ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
        let s = RayShear::new(ray);
        bvh.closest_hit(ray, t_max, &mut (), |p, t| {
            let [a, b, c] = tris[p as usize];
            intersect_triangle_sheared(&s, ray.origin, a, b, c, t).map(|h| h.t)
        })
    }

    #[test]
    fn empty_wide_bvh_never_hits_and_validates() {
        let w = WideBvh::collapse(&Bvh::default(), &[]);
        assert!(w.validate(&[]).is_ok());
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(w.closest_hit(&r, f32::INFINITY).is_none());
        assert!(!w.any_hit(&r, f32::INFINITY, |_, _| true));
    }

    #[test]
    fn collapsed_trees_validate_and_are_wide() {
        for (tris, split) in [
            (random_tris(3, 1), SplitMethod::SahBinned),
            (random_tris(2000, 2), SplitMethod::SahBinned),
            (random_tris(2000, 3), SplitMethod::Median),
            (grid(20), SplitMethod::SahBinned),
        ] {
            let (bvh, wide) = both(&tris, split);
            wide.validate(&tris).unwrap();
            if tris.len() > 100 {
                // Each wide node replaces up to three binary interior nodes (fewer where
                // leaves take its slots).
                let interior = bvh.nodes.len() - bvh.leaf_count();
                let wide_nodes = wide.nodes.len();
                assert!(3 * wide_nodes < 2 * interior, "{wide_nodes} for {interior}");
            }
        }
    }

    #[test]
    fn validate_catches_a_shrunken_box_and_a_wrong_triangle() {
        let tris = random_tris(500, 4);
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        let mut bad = wide.clone();
        let lane = (0..WIDTH)
            .find(|&l| bad.nodes[0].child[l] != EMPTY)
            .unwrap();
        bad.nodes[0].bounds[3][lane] = bad.nodes[0].bounds[0][lane];
        assert!(bad.validate(&tris).is_err());
        let mut bad = wide.clone();
        bad.tris.swap(0, 1);
        assert!(bad.validate(&tris).is_err());
    }

    #[test]
    fn closest_and_any_hit_match_the_binary_tree() {
        for (tris, seed) in [(random_tris(3000, 5), 6), (grid(16), 7)] {
            let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
            let mut hits = 0;
            for (ray, t_max) in rays(4000, seed) {
                let expect = binary_closest(&bvh, &tris, &ray, t_max);
                let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
                assert_eq!(got, expect, "{ray:?}");
                hits += got.is_some() as u32;
                assert_eq!(
                    wide.any_hit(&ray, t_max, |_, _| true),
                    expect.is_some(),
                    "{ray:?}"
                );
            }
            assert!(hits > 100, "only {hits} hits");
        }
    }

    #[test]
    fn rays_along_the_grid_edges_never_slip_through() {
        // Straight down through every vertex and edge midpoint of the grid.
        let tris = grid(8);
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        for i in 0..=16 {
            for j in 0..=16 {
                let o = vec3(i as f32 * 0.5, 1.0, j as f32 * 0.5);
                let inside = (0.0..=8.0).contains(&o.x) && (0.0..=8.0).contains(&o.z);
                let hit = wide.closest_hit(&Ray::new(o, -Vec3::Y), f32::INFINITY);
                assert_eq!(hit.is_some(), inside, "{o}");
                if let Some((_, h)) = hit {
                    assert_eq!(h.t, 1.0);
                }
            }
        }
    }

    #[test]
    fn deep_trees_take_a_heap_stack_and_still_match() {
        // A binary chain (leaf k beside the subtree of leaves k+1..), as a builder could
        // make at its depth limit: the wide tree takes three of its levels per level,
        // which is still deeper than the stack on the call stack holds.
        let n = 72;
        let tris: Vec<Tri> = (0..n)
            .map(|k| {
                let x = k as f32;
                [vec3(x, -1.0, -1.0), vec3(x, 1.0, -1.0), vec3(x, 0.0, 1.0)]
            })
            .collect();
        let boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
        let rest = |k: usize| boxes[k..].iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let mut nodes = Vec::new();
        for (k, &b) in boxes[..n - 1].iter().enumerate() {
            let i = nodes.len() as u32;
            nodes.push(crate::accel::BvhNode::interior(rest(k), i + 2));
            nodes.push(crate::accel::BvhNode::leaf(b, k as u32, 1));
        }
        nodes.push(crate::accel::BvhNode::leaf(boxes[n - 1], n as u32 - 1, 1));
        let bvh = Bvh {
            nodes,
            prim_indices: (0..n as u32).collect(),
        };
        let wide = WideBvh::collapse(&bvh, &tris);
        wide.validate(&tris).unwrap();
        assert!(stack_size(wide.depth) > STACK_SIZE, "depth {}", wide.depth);
        let brute = |ray: &Ray, t_max: f32| {
            let s = RayShear::new(ray);
            let mut best: Option<(u32, f32)> = None;
            for (p, &[a, b, c]) in tris.iter().enumerate() {
                let bound = best.map_or(t_max, |b| b.1);
                if let Some(h) = intersect_triangle_sheared(&s, ray.origin, a, b, c, bound) {
                    best = Some((p as u32, h.t));
                }
            }
            best
        };
        let mut hits = 0;
        for (ray, t_max) in rays(2000, 9) {
            let ray = Ray::new(ray.origin + vec3(36.0, 0.0, 0.0), ray.dir);
            let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
            assert_eq!(got, brute(&ray, t_max), "{ray:?}");
            hits += got.is_some() as u32;
        }
        assert!(hits > 30, "only {hits} hits");
        let mut shallow = wide.clone();
        shallow.depth = 0;
        assert!(shallow.validate(&tris).is_err());
    }

    #[test]
    fn a_tie_at_a_shared_edge_goes_to_the_lowest_index_in_both_trees() {
        // Straight down onto the shared diagonal of every quad of the grid.
        let tris = grid(8);
        let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
        for i in 0..8 {
            for j in 0..8 {
                let o = vec3(i as f32 + 0.25, 1.0, j as f32 + 0.25);
                let ray = Ray::new(o, -Vec3::Y);
                let quad = 2 * (i * 8 + j) as u32;
                let expect = Some((quad, 1.0));
                assert_eq!(binary_closest(&bvh, &tris, &ray, f32::INFINITY), expect);
                let got = wide.closest_hit(&ray, f32::INFINITY).map(|(p, h)| (p, h.t));
                assert_eq!(got, expect);
            }
        }
    }

    #[test]
    fn any_hit_visits_every_crossing_until_told_to_stop() {
        // Ten parallel planes of two triangles each, crossed by one ray.
        let tris: Vec<Tri> = (0..10)
            .flat_map(|k| {
                let z = k as f32;
                [
                    [vec3(-1., -1., z), vec3(1., -1., z), vec3(1., 1., z)],
                    [vec3(-1., -1., z), vec3(1., 1., z), vec3(-1., 1., z)],
                ]
            })
            .collect();
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        let ray = Ray::new(vec3(0.3, -0.2, -1.0), Vec3::Z);
        let mut seen = Vec::new();
        assert!(!wide.any_hit(&ray, 20.0, |p, h| {
            seen.push((p / 2, h.t));
            false
        }));
        seen.sort_by(|a, b| a.1.total_cmp(&b.1));
        assert_eq!(seen.len(), 10);
        assert!(seen.iter().enumerate().all(|(k, s)| s.0 == k as u32));
        let mut n = 0;
        assert!(wide.any_hit(&ray, 20.0, |_, _| {
            n += 1;
            n == 3
        }));
        assert_eq!(n, 3);
    }
}
