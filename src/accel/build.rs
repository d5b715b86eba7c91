//! BVH builders: binned SAH after Ingo Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", IEEE Symposium on Interactive Ray
//! Tracing 2007, and an object-median split for comparison.
//!
//! The top of the recursion runs in parallel with `rayon::join`; each parallel
//! branch builds its subtree into its own vector, which the parent appends in
//! a fixed order, so the node array is identical whatever the thread count.

use glam::Vec3;

use super::Aabb;
use super::bvh::{Bvh, BvhNode, SplitMethod};

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// At or below this many primitives a node is always a leaf.
const MIN_LEAF: usize = 4;
/// Above this many primitives a node is always split (if centroids differ).
const MAX_LEAF: usize = 8;
/// Subtrees at least this large are built in parallel.
const PARALLEL_MIN: usize = 4096;
/// From this depth on, splits are by median, which halves the count, so the
/// tree stays within the traversal stack (32 + log2(u32::MAX) < 64 levels).
const SAH_DEPTH_LIMIT: u32 = 32;
/// Cost of one node visit relative to one primitive test in the SAH.
const TRAVERSAL_COST: f32 = 1.0;

struct Ctx<'a> {
    bounds: &'a [Aabb],
    centroids: Vec<Vec3>,
    split: SplitMethod,
}

impl Bvh {
    /// Builds over primitive bounds (centroids = bounds' centres). Empty input → no nodes.
    pub fn build(bounds: &[Aabb], split: SplitMethod) -> Bvh {
        if bounds.is_empty() {
            return Bvh::default();
        }
        let ctx = Ctx {
            bounds,
            centroids: bounds.iter().map(Aabb::centroid).collect(),
            split,
        };
        let mut prim_indices: Vec<u32> = (0..bounds.len() as u32).collect();
        let mut nodes = Vec::with_capacity(node_estimate(bounds.len()));
        build_node(&ctx, &mut prim_indices, 0, 1, &mut nodes);
        // The estimate may overshoot (smaller leaves): give back what is unused.
        nodes.shrink_to_fit();
        Bvh {
            nodes,
            prim_indices,
        }
    }
}

/// Nodes to reserve for `n` primitives: SAH leaves hold 3.3 primitives on average
/// (0.61 nodes per primitive on the procedural meshes and the asset models), so
/// 2/3 of a node each avoids the reallocation (and its doubled peak) of n/2.
fn node_estimate(n: usize) -> usize {
    n / 3 * 2 + 2
}

/// Appends the subtree over `indices` to `out`. Child offsets are indices into
/// `out`; leaf offsets are global because `indices` starts at `prim_base` in
/// the final `prim_indices`.
fn build_node(ctx: &Ctx, indices: &mut [u32], prim_base: u32, depth: u32, out: &mut Vec<BvhNode>) {
    let mut node_bounds = Aabb::EMPTY;
    let mut centroid_bounds = Aabb::EMPTY;
    for &i in indices.iter() {
        node_bounds = node_bounds.union(ctx.bounds[i as usize]);
        centroid_bounds.grow(ctx.centroids[i as usize]);
    }
    let n = indices.len();
    let Some(mid) = split(ctx, indices, node_bounds, centroid_bounds, depth) else {
        out.push(BvhNode::leaf(node_bounds, prim_base, n as u32));
        return;
    };
    let me = out.len();
    out.push(BvhNode::interior(node_bounds, 0));
    let (left, right) = indices.split_at_mut(mid);
    let right_base = prim_base + mid as u32;
    if n >= PARALLEL_MIN {
        let (l, r) = rayon::join(
            || {
                let mut v = Vec::with_capacity(node_estimate(left.len()));
                build_node(ctx, left, prim_base, depth + 1, &mut v);
                v
            },
            || {
                let mut v = Vec::with_capacity(node_estimate(right.len()));
                build_node(ctx, right, right_base, depth + 1, &mut v);
                v
            },
        );
        append_shifted(out, &l);
        out[me].offset = out.len() as u32;
        append_shifted(out, &r);
    } else {
        build_node(ctx, left, prim_base, depth + 1, out);
        out[me].offset = out.len() as u32;
        build_node(ctx, right, right_base, depth + 1, out);
    }
}

/// Appends a subtree built in its own vector, moving its child offsets to where it lands.
fn append_shifted(out: &mut Vec<BvhNode>, sub: &[BvhNode]) {
    let base = out.len() as u32;
    out.extend(sub.iter().map(|n| {
        let mut n = *n;
        if !n.is_leaf() {
            n.offset += base;
        }
        n
    }));
}

/// Partitions `indices` and returns the size of the first part, or None for a leaf.
fn split(
    ctx: &Ctx,
    indices: &mut [u32],
    node_bounds: Aabb,
    centroid_bounds: Aabb,
    depth: u32,
) -> Option<usize> {
    let n = indices.len();
    if n <= MIN_LEAF {
        return None;
    }
    let ext = centroid_bounds.extent();
    // All centroids coincide (or are NaN): no plane separates them.
    let widest = ext.max_element();
    if widest.is_nan() || widest <= 0.0 {
        return None;
    }
    if ctx.split == SplitMethod::Median || depth >= SAH_DEPTH_LIMIT {
        return Some(median_split(ctx, indices, ext));
    }
    let area = node_bounds.surface_area();
    let sah = if area > 0.0 {
        best_sah_plane(ctx, indices, centroid_bounds)
    } else {
        // Flat, zero-area node (e.g. collinear points): SAH is undefined.
        None
    };
    match sah {
        Some(plane) if n > MAX_LEAF || TRAVERSAL_COST + plane.cost / area < n as f32 => {
            let mid = partition(indices, |i| plane.is_left(ctx.centroids[i as usize]));
            // Binning and partition share `bin_of`, so both sides are non-empty;
            // this guards against it anyway.
            if mid == 0 || mid == n {
                Some(median_split(ctx, indices, ext))
            } else {
                Some(mid)
            }
        }
        _ if n > MAX_LEAF => Some(median_split(ctx, indices, ext)),
        _ => None,
    }
}

/// A candidate plane: centroids in bins `< bin` on `axis` go left.
struct Plane {
    axis: usize,
    bin: usize,
    min: f32,
    scale: f32,
    /// Unnormalised SAH cost `A_L N_L + A_R N_R`.
    cost: f32,
}

impl Plane {
    fn is_left(&self, c: Vec3) -> bool {
        bin_of(c[self.axis], self.min, self.scale) < self.bin
    }
}

/// Bin index of a centroid coordinate (shared by binning and partitioning).
#[inline]
fn bin_of(c: f32, min: f32, scale: f32) -> usize {
    // `as usize` saturates (NaN → 0), so no index is out of range.
    (((c - min) * scale) as usize).min(BINS - 1)
}

/// Cheapest binned-SAH plane over the three axes, if any separates the centroids.
fn best_sah_plane(ctx: &Ctx, indices: &[u32], centroid_bounds: Aabb) -> Option<Plane> {
    let ext = centroid_bounds.extent();
    let cmin = centroid_bounds.min;
    let scale = Vec3::select(
        ext.cmpgt(Vec3::ZERO),
        Vec3::splat(BINS as f32) / ext,
        Vec3::ZERO,
    );
    let mut counts = [[0u32; BINS]; 3];
    let mut boxes = [[Aabb::EMPTY; BINS]; 3];
    for &i in indices {
        let c = ctx.centroids[i as usize];
        let b = ctx.bounds[i as usize];
        for axis in 0..3 {
            let k = bin_of(c[axis], cmin[axis], scale[axis]);
            counts[axis][k] += 1;
            boxes[axis][k] = boxes[axis][k].union(b);
        }
    }
    let mut best: Option<Plane> = None;
    for axis in 0..3 {
        if scale[axis] == 0.0 {
            continue;
        }
        // right_cost[k]: area * count of bins k.. (the right side of plane k).
        let mut right_cost = [0.0f32; BINS];
        let mut acc_box = Aabb::EMPTY;
        let mut acc_n = 0u32;
        for k in (1..BINS).rev() {
            acc_box = acc_box.union(boxes[axis][k]);
            acc_n += counts[axis][k];
            right_cost[k] = if acc_n > 0 {
                acc_box.surface_area() * acc_n as f32
            } else {
                f32::INFINITY // empty right side: not a split
            };
        }
        let mut left_box = Aabb::EMPTY;
        let mut left_n = 0u32;
        for k in 1..BINS {
            left_box = left_box.union(boxes[axis][k - 1]);
            left_n += counts[axis][k - 1];
            if left_n == 0 {
                continue;
            }
            let cost = left_box.surface_area() * left_n as f32 + right_cost[k];
            if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Plane {
                    axis,
                    bin: k,
                    min: cmin[axis],
                    scale: scale[axis],
                    cost,
                });
            }
        }
    }
    best
}

/// Object median along the widest centroid axis.
fn median_split(ctx: &Ctx, indices: &mut [u32], centroid_extent: Vec3) -> usize {
    let axis = centroid_extent.max_position();
    let mid = indices.len() / 2;
    let c = &ctx.centroids;
    indices.select_nth_unstable_by(mid, |&a, &b| {
        c[a as usize][axis].total_cmp(&c[b as usize][axis])
    });
    mid
}

/// In-place partition; returns how many elements satisfy `left` (now at the front).
fn partition(indices: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = indices.len();
    while i < j {
        if left(indices[i]) {
            i += 1;
        } else {
            j -= 1;
            indices.swap(i, j);
        }
    }
    i
}
