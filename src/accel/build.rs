//! BVH builders: binned SAH after Ingo Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", IEEE Symposium on Interactive Ray
//! Tracing 2007, and an object-median split for comparison.
//!
//! The builder moves `PrimRef`s (a primitive's box and index together), so
//! binning and partitioning read memory in order instead of gathering boxes
//! through an index array. Each node's bounds come from its parent (from the
//! SAH bins and the partition pass), so a node's primitives are read twice:
//! once to bin them, once to partition them. The top of the recursion runs in
//! parallel with `rayon::join` (on more than one thread; on one, the recursion writes
//! the whole tree into one array), and nodes too large for that to have split the
//! work yet bin in parallel chunks. Every parallel step combines its parts in a
//! fixed order with exact operations (min, max, integer sums), so the tree is
//! identical whatever the thread count.
//!
//! This file holds the recursion and the primitive records; `bins`, the bins, the
//! SAH sweep over them and the partition by the chosen plane; `spatial`, the
//! triangles' build with spatial splits, which takes these object splits where they pay.

use glam::Vec3;
use multiversion::multiversion;
use rayon::prelude::*;
use wide::f32x4;

use super::Aabb;
use super::bvh::{Bvh, BvhNode, SplitMethod};
use super::huge::{Backing, HugeVec};
use super::leaf::LANES;

mod bins;
mod rooms;
mod spatial;

use bins::{Bins, best_sah_plane, partition};

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Bins per axis of nodes below [`FEW_BINS_BELOW`] primitives: they are most nodes,
/// and for them resetting and sweeping 16 bins cost more than binning their
/// primitives. On the 100k torus 8 bins below 64 primitives take 8% fewer build
/// instructions, and the SAH cost goes from 17.306 to 17.289 (1M: 20.386 to 20.360;
/// below 128: 17.300, 20.376).
const FEW_BINS: usize = 8;
/// See [`FEW_BINS`].
const FEW_BINS_BELOW: usize = 64;
/// At or below this many primitives a node is always a leaf.
const MIN_LEAF: usize = 4;
/// Above this many primitives a node is always split (if centroids differ).
const MAX_LEAF: usize = 8;
/// Nodes at least this large bin into two sets of bins (see [`Bins::add`]).
const TWO_SETS_MIN: usize = 256;
/// Subtrees at least this large are built in parallel.
const PARALLEL_MIN: usize = 4096;
/// Nodes at least this large are binned in parallel chunks of this size.
const PARALLEL_BIN_CHUNK: usize = 1 << 15;
/// From this depth on, splits are by median, which halves the count, so the
/// tree stays within the traversal stack (32 + log2(u32::MAX) < 64 levels).
const SAH_DEPTH_LIMIT: u32 = 32;
/// Cost of one node visit relative to testing one block of primitives in the SAH; it
/// only decides whether nodes of `MIN_LEAF + 1 ..= MAX_LEAF` split. On the 100k torus
/// 0.3-0.5 give the fewest instructions per ray, 1.0 makes larger leaves that cost 4-6%
/// more of them. Swept again in December 2026 (tori, bunny, Sponza, MetalRoughSpheres):
/// 0.2-0.3 within 0.1% on the tori and 0.8% fewer on Sponza's incoherent rays, 0.7
/// 0.5-0.7% more; [`MAX_LEAF`] 4 to 6 (leaves of one group) within 0.1% on the tori
/// and 1.3% fewer on Sponza's incoherent rays at 59.0 rather than 58.4 bytes per
/// triangle: too little to show in CPU time (see the collapse's `NODE_COST`).
const TRAVERSAL_COST: f32 = 0.5;
/// Primitives a leaf tests at once: the wide BVH's leaves are SIMD groups of
/// [`LANES`] triangles, so a leaf of 5 costs (and holds) as much as one of 8 and the
/// SAH counts leaves in whole blocks (Embree's `logBlockSize`).
const LEAF_BLOCK: u32 = LANES as u32;

/// SAH weight of `n` primitives in one leaf: its blocks.
#[inline(always)]
fn blocks(n: u32) -> f32 {
    n.div_ceil(LEAF_BLOCK) as f32
}

/// Four lanes (x, y, z, unused): written lane by lane so the compiler keeps
/// them in one SIMD register.
type Lanes = [f32; 4];

/// A box in [`Lanes`]; what binning and partitioning accumulate.
#[derive(Clone, Copy)]
struct Box4 {
    min: Lanes,
    max: Lanes,
}

impl Box4 {
    const EMPTY: Box4 = Box4 {
        min: [f32::INFINITY; 4],
        max: [f32::NEG_INFINITY; 4],
    };

    /// Grows to contain the box `min..max`, ignoring a NaN coordinate in it
    /// (`self` starts empty and so never holds one). Finite input gives exactly
    /// [`Aabb::union`]'s box. Per lane `min < self.min ? min : self.min` (and the
    /// same for max), which is what `fast_min` / `fast_max` compute (`minps` /
    /// `maxps`); written as selects, the compiler merged both into one blend of
    /// eight lanes with shuffles around it.
    #[inline(always)]
    fn grow(&mut self, min: Lanes, max: Lanes) {
        self.min = f32x4::from(min).fast_min(f32x4::from(self.min)).to_array();
        self.max = f32x4::from(max).fast_max(f32x4::from(self.max)).to_array();
    }

    #[inline(always)]
    fn union(mut self, o: Box4) -> Box4 {
        self.grow(o.min, o.max);
        self
    }

    fn aabb(&self) -> Aabb {
        let [x0, y0, z0, _] = self.min;
        let [x1, y1, z1, _] = self.max;
        Aabb::new(Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
    }

    /// Same value as [`Aabb::surface_area`] (the same expression on the lanes, without
    /// the round trip through `Vec3`, which the SAH sweep pays for every plane).
    #[inline(always)]
    fn surface_area(&self) -> f32 {
        let (lo, hi) = (self.min, self.max);
        if lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2] {
            return 0.0;
        }
        let e: Lanes = std::array::from_fn(|i| hi[i] - lo[i]);
        2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
    }
}

/// Flipped in a primitive's index where [`PrimRef`] keeps it in a float lane, so that
/// below 2^30 the lane holds a normal float of magnitude 2 or more (an infinity or NaN
/// from 2^30 - 2^23 on) rather than a subnormal: the binning and the partition compute
/// centroids with that lane in (masking it took an instruction per primitive in each,
/// 2.2% of the build's instructions on the 100k torus), and every value it takes there
/// (half of it, differences of such values, products with a zero scale) is then a
/// normal float, zero, infinite or NaN, none of which take the CPU's slow subnormal
/// path. No decision reads that lane.
const INDEX_TAG: u32 = 1 << 30;

/// A primitive's box and its index, moved as one 32-byte unit by the
/// partitions; each corner loads as one [`Lanes`]. The upper corner is kept
/// negated, the bins' form (see [`PrimRef::flipped`]); the unused fourth lane of
/// `neg_hi` holds the index's bits, tagged (see [`INDEX_TAG`]).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(16))]
struct PrimRef {
    lo: Lanes,
    neg_hi: Lanes,
}

impl PrimRef {
    /// A NaN coordinate of one corner takes the other corner's, so that the
    /// rest of the box is still covered (boxes grow past NaN, see [`Box4::grow`]).
    fn new(index: usize, b: &Aabb) -> PrimRef {
        let pick = |v: f32, other: f32| if v.is_nan() { other } else { v };
        let (lo, hi) = (b.min, b.max);
        PrimRef {
            lo: [pick(lo.x, hi.x), pick(lo.y, hi.y), pick(lo.z, hi.z), 0.0],
            neg_hi: [
                -pick(hi.x, lo.x),
                -pick(hi.y, lo.y),
                -pick(hi.z, lo.z),
                f32::from_bits(index as u32 ^ INDEX_TAG),
            ],
        }
    }

    fn index(&self) -> u32 {
        self.neg_hi[3].to_bits() ^ INDEX_TAG
    }

    /// The box as a [`BinBox`] grows by (with the index's lane, which no one reads): the
    /// two corners as they are, where negating the upper one for each bin took two
    /// instructions per primitive.
    #[inline(always)]
    fn flipped(&self) -> [f32; 8] {
        let (lo, n) = (self.lo, self.neg_hi);
        [lo[0], lo[1], lo[2], lo[3], n[0], n[1], n[2], n[3]]
    }

    /// The box (the upper corner's fourth lane is not a coordinate).
    #[inline(always)]
    fn box4(&self) -> Box4 {
        Box4 {
            min: self.lo,
            max: self.hi(),
        }
    }

    /// The upper corner (its fourth lane is not a coordinate).
    #[inline(always)]
    fn hi(&self) -> Lanes {
        self.neg_hi.map(|v| -v)
    }

    /// The centroid in a SIMD register (`subps` of the negated corner, which is exactly
    /// `addps` of the upper one, and `mulps`: the values of [`Aabb::centroid`], so the
    /// same bins). Its fourth lane comes from the tagged index ([`INDEX_TAG`]): nothing
    /// reads it.
    #[inline(always)]
    fn centroid_x4(&self) -> f32x4 {
        (f32x4::from(self.lo) - f32x4::from(self.neg_hi)) * f32x4::splat(0.5)
    }

    /// [`PrimRef::centroid_x4`] in [`Lanes`].
    #[inline(always)]
    fn centroid(&self) -> Lanes {
        self.centroid_x4().to_array()
    }
}

/// A node's box and the box of its primitives' centroids.
#[derive(Clone, Copy)]
struct NodeBounds {
    node: Box4,
    centroids: Box4,
}

impl NodeBounds {
    const EMPTY: NodeBounds = NodeBounds {
        node: Box4::EMPTY,
        centroids: Box4::EMPTY,
    };

    fn of(refs: &[PrimRef]) -> NodeBounds {
        if refs.len() >= 2 * PARALLEL_BIN_CHUNK {
            refs.par_chunks(PARALLEL_BIN_CHUNK)
                .map(bounds_of)
                .reduce(|| NodeBounds::EMPTY, NodeBounds::union)
        } else {
            bounds_of(refs)
        }
    }

    fn union(self, o: NodeBounds) -> NodeBounds {
        NodeBounds {
            node: self.node.union(o.node),
            centroids: self.centroids.union(o.centroids),
        }
    }
}

/// [`NodeBounds::of`] one chunk, for the best instruction set the CPU has (as the
/// binning: a plain function or closure is compiled for the baseline one).
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn bounds_of(refs: &[PrimRef]) -> NodeBounds {
    let mut acc = NodeBounds::EMPTY;
    for r in refs {
        acc.node.grow(r.lo, r.hi());
        let c = r.centroid();
        acc.centroids.grow(c, c);
    }
    acc
}

/// Writes the `PrimRef` of each box of `bounds` to `refs`, the first with index `first`,
/// for the best instruction set the CPU has.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn make_refs(refs: &mut [PrimRef], bounds: &[Aabb], first: usize) {
    for (i, (r, b)) in refs.iter_mut().zip(bounds).enumerate() {
        *r = PrimRef::new(first + i, b);
    }
}

/// A node's split: the size of its first part, both parts' bounds and the SAH cost of
/// the plane (infinite for a split by another rule).
type Split = (usize, NodeBounds, NodeBounds, f32);

/// Nodes built by one task, in depth-first order; child offsets are relative
/// to the task's subtree, whose first node lands at `shift` in the final array.
struct Piece {
    nodes: Vec<BvhNode>,
    shift: u32,
}

impl Bvh {
    /// Builds over primitive bounds (centroids = bounds' centres). Empty input → no nodes.
    pub fn build(bounds: &[Aabb], split: SplitMethod) -> Bvh {
        build(bounds, split)
    }

    /// Builds over triangles, with spatial splits where the binned SAH's boxes overlap
    /// (see `build/spatial.rs`): a triangle may then be in several leaves, each leaf's box
    /// holding its part of it. Empty input → no nodes.
    pub fn build_triangles(positions: &[[Vec3; 3]], split: SplitMethod) -> Bvh {
        spatial::build(positions, split)
    }
}

fn build(bounds: &[Aabb], split: SplitMethod) -> Bvh {
    build_backed(bounds, split, Backing::Auto)
}

/// [`build`] with the `PrimRef`s and the tree's arrays kept as `backing` says: from
/// 2 MiB on (65k `PrimRef`s) a huge-page mapping with `Auto`, where a `Vec` took a page
/// fault per 4 KiB (8k for the `PrimRef`s at 1M triangles); tests force either backing,
/// which must give the same tree.
pub(super) fn build_backed(bounds: &[Aabb], split: SplitMethod, backing: Backing) -> Bvh {
    if bounds.is_empty() {
        return Bvh::default();
    }
    let mut refs = HugeVec::<PrimRef>::zeroed(bounds.len(), backing);
    if bounds.len() >= 2 * PARALLEL_BIN_CHUNK {
        let chunks = refs.par_chunks_mut(PARALLEL_BIN_CHUNK);
        chunks
            .zip(bounds.par_chunks(PARALLEL_BIN_CHUNK))
            .enumerate()
            .for_each(|(k, (r, b))| make_refs(r, b, k * PARALLEL_BIN_CHUNK));
    } else {
        make_refs(&mut refs, bounds, 0);
    }
    let root = NodeBounds::of(&refs);
    let nodes = if refs.len() < PARALLEL_MIN || rayon::current_num_threads() == 1 {
        // No task would run beside another: the whole tree in one array kept as
        // `backing` says, without pieces (an allocation each) copied into it. Room for
        // the most nodes a tree can have (every leaf holds a primitive), written
        // through one slice; the pages never written take no memory.
        let mut nodes = HugeVec::zeroed(2 * refs.len() - 1, backing);
        let mut out = Filling {
            nodes: nodes.as_mut_slice(),
            len: 0,
        };
        let mut bins = Bins::empty(Box4::EMPTY);
        build_node(split, &mut refs, 0, 1, root, &mut bins, &mut out);
        let count = out.len;
        nodes.truncate(count);
        nodes.shrink_to_fit();
        nodes
    } else {
        let (pieces, count) = build_subtree(split, &mut refs, 0, 1, root);
        assemble(pieces, count, backing)
    };
    let mut prim_indices = HugeVec::zeroed(refs.len(), backing);
    for (p, r) in prim_indices.iter_mut().zip(refs.iter()) {
        *p = r.index();
    }
    drop(refs);
    Bvh {
        nodes,
        prim_indices,
    }
}

/// Concatenates the pieces, moving each one's child offsets to where they land, into
/// an array kept as `backing` says (like the `PrimRef`s: 17 MB of nodes at 1M).
fn assemble(mut pieces: Vec<Piece>, count: u32, backing: Backing) -> HugeVec<BvhNode> {
    if pieces.len() == 1 {
        let nodes = pieces.pop().unwrap().nodes;
        return HugeVec::from_slice(&nodes, backing);
    }
    let mut nodes = HugeVec::zeroed(count as usize, backing);
    let all = nodes.as_mut_slice();
    let mut next = 0;
    for p in pieces {
        debug_assert_eq!(p.shift as usize, next);
        next += p.nodes.len();
        for (out, n) in all[p.shift as usize..next].iter_mut().zip(&p.nodes) {
            *out = *n;
            if !n.is_leaf() {
                out.offset += p.shift;
            }
        }
    }
    nodes
}

/// Nodes to reserve for `n` primitives: SAH leaves hold 3.3 primitives on average
/// (0.61 nodes per primitive on the procedural meshes and the asset models), so
/// 2/3 of a node each avoids the reallocation (and its doubled peak) of n/2.
fn node_estimate(n: usize) -> usize {
    n / 3 * 2 + 2
}

/// Builds the subtree over `refs`, splitting its two halves in parallel while
/// they are large; returns its pieces in order and its node count.
fn build_subtree(
    method: SplitMethod,
    refs: &mut [PrimRef],
    prim_base: u32,
    depth: u32,
    b: NodeBounds,
) -> (Vec<Piece>, u32) {
    let n = refs.len();
    let mut bins = Bins::empty(Box4::EMPTY);
    if n < PARALLEL_MIN {
        let mut nodes = Vec::with_capacity(node_estimate(n));
        build_node(method, refs, prim_base, depth, b, &mut bins, &mut nodes);
        let count = nodes.len() as u32;
        return (vec![Piece { nodes, shift: 0 }], count);
    }
    let Some((mid, lb, rb, _)) = split(method, refs, b, depth, &mut bins) else {
        let leaf = BvhNode::leaf(b.node.aabb(), prim_base, n as u32);
        return (
            vec![Piece {
                nodes: vec![leaf],
                shift: 0,
            }],
            1,
        );
    };
    let (left, right) = refs.split_at_mut(mid);
    let ((lp, ln), (rp, rn)) = rayon::join(
        || build_subtree(method, left, prim_base, depth + 1, lb),
        || build_subtree(method, right, prim_base + mid as u32, depth + 1, rb),
    );
    let mut pieces = Vec::with_capacity(1 + lp.len() + rp.len());
    pieces.push(Piece {
        nodes: vec![BvhNode::interior(b.node.aabb(), 1 + ln)],
        shift: 0,
    });
    pieces.extend(lp.into_iter().map(|p| Piece {
        shift: p.shift + 1,
        ..p
    }));
    pieces.extend(rp.into_iter().map(|p| Piece {
        shift: p.shift + 1 + ln,
        ..p
    }));
    (pieces, 1 + ln + rn)
}

/// Where [`build_node`] appends nodes: a parallel build's pieces are `Vec`s, the
/// one-thread build a [`Filling`].
trait NodeOut {
    fn len(&self) -> usize;
    fn push(&mut self, node: BvhNode);
    fn set_offset(&mut self, at: usize, offset: u32);
}

impl NodeOut for Vec<BvhNode> {
    fn len(&self) -> usize {
        Vec::len(self)
    }

    fn push(&mut self, node: BvhNode) {
        Vec::push(self, node);
    }

    fn set_offset(&mut self, at: usize, offset: u32) {
        self[at].offset = offset;
    }
}

/// A slice with room for every node, filled from the front: the one-thread build's
/// `HugeVec` of nodes, whose every push and index would look at its backing (1.3% of
/// the build's instructions, torus 100k).
struct Filling<'a> {
    nodes: &'a mut [BvhNode],
    len: usize,
}

impl NodeOut for Filling<'_> {
    fn len(&self) -> usize {
        self.len
    }

    fn push(&mut self, node: BvhNode) {
        self.nodes[self.len] = node;
        self.len += 1;
    }

    fn set_offset(&mut self, at: usize, offset: u32) {
        self.nodes[at].offset = offset;
    }
}

/// Appends the subtree over `refs` to `out`. Child offsets are indices into
/// `out`; leaf offsets are global because `refs` starts at `prim_base` in
/// the final primitive order.
fn build_node(
    method: SplitMethod,
    refs: &mut [PrimRef],
    prim_base: u32,
    depth: u32,
    b: NodeBounds,
    bins: &mut Bins,
    out: &mut impl NodeOut,
) {
    let n = refs.len();
    let Some((mid, lb, rb, _)) = split(method, refs, b, depth, bins) else {
        out.push(BvhNode::leaf(b.node.aabb(), prim_base, n as u32));
        return;
    };
    let me = out.len();
    out.push(BvhNode::interior(b.node.aabb(), 0));
    let (left, right) = refs.split_at_mut(mid);
    build_node(method, left, prim_base, depth + 1, lb, bins, out);
    let next = out.len() as u32;
    out.set_offset(me, next);
    build_node(
        method,
        right,
        prim_base + mid as u32,
        depth + 1,
        rb,
        bins,
        out,
    );
}

/// Bins per axis for a node of `n` primitives: [`BINS`], or [`FEW_BINS`] below
/// [`FEW_BINS_BELOW`] primitives, but one per primitive for the nodes of `FEW_BINS + 1
/// ..= BINS`, so that evenly spread primitives can still split into whole leaf blocks.
#[inline(always)]
fn bin_count(n: usize) -> usize {
    if n >= FEW_BINS_BELOW {
        BINS
    } else if (FEW_BINS + 1..=BINS).contains(&n) {
        n
    } else {
        FEW_BINS
    }
}

/// Partitions `refs`; returns the size of the first part, both parts' bounds and the
/// SAH cost of the plane (as [`bins::Plane::cost`]; infinite for a split by another
/// rule: median, room), or None for a leaf. One clone per instruction set, picked at
/// run time (as the BVH queries): the binning and partition loops inlined into it use
/// three-operand AVX and its wider moves, and `popcnt` counts the SAH sweep's bins (in
/// software without it, 15 instructions per node). Every step is exact (min, max, +, *, no FMA
/// contraction in Rust), so each clone makes the same tree.
#[multiversion(targets("x86_64+avx2+fma+popcnt", "x86_64+sse4.2+popcnt"))]
fn split(
    method: SplitMethod,
    refs: &mut [PrimRef],
    b: NodeBounds,
    depth: u32,
    bins: &mut Bins,
) -> Option<Split> {
    let n = refs.len();
    if n <= MIN_LEAF {
        return leaf_or_room(refs, &b, depth);
    }
    let ext = b.centroids.aabb().extent();
    // All centroids coincide (or are NaN): no plane separates them.
    let widest = ext.max_element();
    if widest.is_nan() || widest <= 0.0 {
        return None;
    }
    if method == SplitMethod::Median || depth >= SAH_DEPTH_LIMIT {
        return Some(median_split(refs, ext));
    }
    let area = b.node.surface_area();
    let sah = if area > 0.0 {
        let count = bin_count(n);
        bins.fill(refs, b.centroids, count);
        best_sah_plane(bins)
    } else {
        // Flat, zero-area node (e.g. collinear points): SAH is undefined.
        None
    };
    match sah {
        Some(plane) if n > MAX_LEAF || TRAVERSAL_COST + plane.cost / area < blocks(n as u32) => {
            let (mid, lc, rc) = partition(refs, bins, &plane);
            // Binning and partition agree (`bins_of`, `first_right`), so both sides are
            // non-empty; this guards against it anyway.
            if mid == 0 || mid == n {
                return Some(median_split(refs, ext));
            }
            let (ln, rn) = bins.boxes_around(&plane);
            let side = |node, centroids| NodeBounds { node, centroids };
            Some((mid, side(ln, lc), side(rn, rc), plane.cost))
        }
        _ if n > MAX_LEAF => Some(median_split(refs, ext)),
        _ => leaf_or_room(refs, &b, depth),
    }
}

/// For a node the SAH makes a leaf: None (the leaf), or the split of a room (see
/// `rooms`). Not below the SAH's depth, where splits must halve the count.
#[inline(always)]
fn leaf_or_room(refs: &mut [PrimRef], b: &NodeBounds, depth: u32) -> Option<Split> {
    if depth >= SAH_DEPTH_LIMIT {
        return None;
    }
    rooms::split_room(refs, b).map(|(mid, l, r)| (mid, l, r, f32::INFINITY))
}

/// Object median along the widest centroid axis; both halves' bounds.
fn median_split(refs: &mut [PrimRef], centroid_extent: Vec3) -> Split {
    let axis = centroid_extent.max_position();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| {
        a.centroid()[axis].total_cmp(&b.centroid()[axis])
    });
    let (left, right) = refs.split_at(mid);
    (
        mid,
        NodeBounds::of(left),
        NodeBounds::of(right),
        f32::INFINITY,
    )
}
