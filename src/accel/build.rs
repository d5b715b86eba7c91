//! BVH builders: binned SAH after Ingo Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", IEEE Symposium on Interactive Ray
//! Tracing 2007, and an object-median split for comparison.
//!
//! The builder moves `PrimRef`s (a primitive's box and index together), so
//! binning and partitioning read memory in order instead of gathering boxes
//! through an index array. Each node's bounds come from its parent (from the
//! SAH bins and the partition pass), so a node's primitives are read twice:
//! once to bin them, once to partition them. The top of the recursion runs in
//! parallel with `rayon::join`, and nodes too large for that to have split the
//! work yet bin in parallel chunks. Every parallel step combines its parts in a
//! fixed order with exact operations (min, max, integer sums), so the tree is
//! identical whatever the thread count.

use glam::Vec3;
use multiversion::multiversion;
use rayon::prelude::*;
use wide::{f32x4, f32x8};

use super::Aabb;
use super::bvh::{Bvh, BvhNode, SplitMethod};
use super::leaf::LANES;

/// Number of SAH bins per axis.
const BINS: usize = 16;
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
/// more of them.
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

/// A box as its lower corner and its negated upper corner, the bins' form: growing
/// it is one lane-wise min over all eight lanes. `-a < -b` exactly when `a > b`, so
/// the min of the negated corners picks the same values as [`Box4::grow`]'s max,
/// bit for bit (zeros' signs and NaNs included).
#[derive(Clone, Copy)]
struct BinBox(f32x8);

impl BinBox {
    const EMPTY: BinBox = BinBox(f32x8::new([f32::INFINITY; 8]));

    /// Grows to contain `o` (a [`PrimRef::flipped`] or another bin box): per lane
    /// `o < self ? o : self`, which is what `fast_min` computes (`minps`). Written as a
    /// select on the bin's memory, the compiler turned it into a masked store, whose
    /// value the next primitive in the same bin cannot load until it has retired.
    #[inline(always)]
    fn grow(&mut self, o: f32x8) {
        self.0 = o.fast_min(self.0);
    }

    #[inline(always)]
    fn union(mut self, o: BinBox) -> BinBox {
        self.grow(o.0);
        self
    }

    #[inline(always)]
    fn box4(&self) -> Box4 {
        let b = self.0.to_array();
        Box4 {
            min: [b[0], b[1], b[2], b[3]],
            max: [-b[4], -b[5], -b[6], -b[7]],
        }
    }

    #[cfg(test)]
    fn of(b: Box4) -> BinBox {
        let (lo, hi) = (b.min, b.max);
        BinBox(f32x8::new([
            lo[0], lo[1], lo[2], lo[3], -hi[0], -hi[1], -hi[2], -hi[3],
        ]))
    }
}

/// A primitive's box and its index, moved as one 32-byte unit by the
/// partitions; each corner loads as one [`Lanes`]. The unused fourth lane of
/// `hi` holds the index's bits (see [`PrimRef::hi`]).
#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct PrimRef {
    lo: Lanes,
    hi: Lanes,
}

impl PrimRef {
    /// A NaN coordinate of one corner takes the other corner's, so that the
    /// rest of the box is still covered (boxes grow past NaN, see [`Box4::grow`]).
    fn new(index: usize, b: &Aabb) -> PrimRef {
        let pick = |v: f32, other: f32| if v.is_nan() { other } else { v };
        let (lo, hi) = (b.min, b.max);
        PrimRef {
            lo: [pick(lo.x, hi.x), pick(lo.y, hi.y), pick(lo.z, hi.z), 0.0],
            hi: [
                pick(hi.x, lo.x),
                pick(hi.y, lo.y),
                pick(hi.z, lo.z),
                f32::from_bits(index as u32),
            ],
        }
    }

    fn index(&self) -> u32 {
        self.hi[3].to_bits()
    }

    /// The upper corner with the index's lane zeroed: growing boxes ignores
    /// that lane, but arithmetic on it could meet subnormals (slow) or NaN.
    #[inline(always)]
    fn hi(&self) -> Lanes {
        [self.hi[0], self.hi[1], self.hi[2], 0.0]
    }

    /// The box as a [`BinBox`] grows by (the index's lane negated, which no one reads).
    #[inline(always)]
    fn flipped(&self) -> f32x8 {
        let (lo, hi) = (self.lo, self.hi);
        f32x8::new([lo[0], lo[1], lo[2], lo[3], -hi[0], -hi[1], -hi[2], -hi[3]])
    }

    /// [`PrimRef::centroid`] in a SIMD register (`addps`, `mulps`: the same values).
    #[inline(always)]
    fn centroid_x4(&self) -> f32x4 {
        (f32x4::from(self.lo) + f32x4::from(self.hi())) * f32x4::splat(0.5)
    }

    /// Same expression as [`Aabb::centroid`], so the same bins.
    #[inline(always)]
    fn centroid(&self) -> Lanes {
        let (lo, hi) = (self.lo, self.hi());
        std::array::from_fn(|i| (lo[i] + hi[i]) * 0.5)
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
        let fold = |mut acc: NodeBounds, r: &PrimRef| {
            acc.node.grow(r.lo, r.hi);
            let c = r.centroid();
            acc.centroids.grow(c, c);
            acc
        };
        if refs.len() >= 2 * PARALLEL_BIN_CHUNK {
            refs.par_chunks(PARALLEL_BIN_CHUNK)
                .map(|c| c.iter().fold(NodeBounds::EMPTY, fold))
                .reduce(|| NodeBounds::EMPTY, NodeBounds::union)
        } else {
            refs.iter().fold(NodeBounds::EMPTY, fold)
        }
    }

    fn union(self, o: NodeBounds) -> NodeBounds {
        NodeBounds {
            node: self.node.union(o.node),
            centroids: self.centroids.union(o.centroids),
        }
    }
}

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
}

fn build(bounds: &[Aabb], split: SplitMethod) -> Bvh {
    if bounds.is_empty() {
        return Bvh::default();
    }
    let make = |(i, b): (usize, &Aabb)| PrimRef::new(i, b);
    let mut refs: Vec<PrimRef> = if bounds.len() >= 2 * PARALLEL_BIN_CHUNK {
        bounds.par_iter().enumerate().map(make).collect()
    } else {
        bounds.iter().enumerate().map(make).collect()
    };
    let root = NodeBounds::of(&refs);
    let (pieces, count) = build_subtree(split, &mut refs, 0, 1, root);
    let prim_indices: Vec<u32> = refs.iter().map(PrimRef::index).collect();
    drop(refs);
    Bvh {
        nodes: assemble(pieces, count),
        prim_indices,
    }
}

/// Concatenates the pieces, moving each one's child offsets to where it lands.
fn assemble(mut pieces: Vec<Piece>, count: u32) -> Vec<BvhNode> {
    if pieces.len() == 1 {
        let mut nodes = pieces.pop().unwrap().nodes;
        nodes.shrink_to_fit();
        return nodes;
    }
    let mut nodes = Vec::with_capacity(count as usize);
    for p in pieces {
        debug_assert_eq!(p.shift as usize, nodes.len());
        nodes.extend(p.nodes.iter().map(|n| {
            let mut n = *n;
            if !n.is_leaf() {
                n.offset += p.shift;
            }
            n
        }));
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
    let Some((mid, lb, rb)) = split(method, refs, b, depth, &mut bins) else {
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
    out: &mut Vec<BvhNode>,
) {
    let n = refs.len();
    let Some((mid, lb, rb)) = split(method, refs, b, depth, bins) else {
        out.push(BvhNode::leaf(b.node.aabb(), prim_base, n as u32));
        return;
    };
    let me = out.len();
    out.push(BvhNode::interior(b.node.aabb(), 0));
    let (left, right) = refs.split_at_mut(mid);
    build_node(method, left, prim_base, depth + 1, lb, bins, out);
    out[me].offset = out.len() as u32;
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

/// Partitions `refs`; returns the size of the first part and both parts'
/// bounds, or None for a leaf. One clone per instruction set, picked at run time
/// (as the BVH queries): the binning and partition loops inlined into it use three-
/// operand AVX and its wider moves. Every step is exact (min, max, +, *, no FMA
/// contraction in Rust), so each clone makes the same tree.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn split(
    method: SplitMethod,
    refs: &mut [PrimRef],
    b: NodeBounds,
    depth: u32,
    bins: &mut Bins,
) -> Option<(usize, NodeBounds, NodeBounds)> {
    let n = refs.len();
    if n <= MIN_LEAF {
        return None;
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
        bins.fill(refs, b.centroids);
        best_sah_plane(bins)
    } else {
        // Flat, zero-area node (e.g. collinear points): SAH is undefined.
        None
    };
    match sah {
        Some(plane) if n > MAX_LEAF || TRAVERSAL_COST + plane.cost / area < blocks(n as u32) => {
            let (mid, lc, rc) = partition(refs, bins, &plane);
            // Binning and partition agree (`bins_of`, `goes_left`), so both sides are non-empty;
            // this guards against it anyway.
            if mid == 0 || mid == n {
                return Some(median_split(refs, ext));
            }
            let (ln, rn) = bins.boxes_around(&plane);
            Some((
                mid,
                NodeBounds {
                    node: ln,
                    centroids: lc,
                },
                NodeBounds {
                    node: rn,
                    centroids: rc,
                },
            ))
        }
        _ if n > MAX_LEAF => Some(median_split(refs, ext)),
        _ => None,
    }
}

/// Rows of [`Bins`]: one per axis, and one for the unused fourth lane, whose count
/// (never read) keeps the bin indices in four SIMD lanes in [`Bins::add`].
const ROWS: usize = 4;

/// Per axis, the count and box of the primitives whose centroids fall in each bin.
struct Bins {
    min: Lanes,
    scale: Lanes,
    counts: [[u32; BINS]; ROWS],
    boxes: [[BinBox; BINS]; ROWS],
}

impl Bins {
    fn empty(centroids: Box4) -> Bins {
        let mut bins = Bins {
            min: [0.0; 4],
            scale: [0.0; 4],
            counts: [[0; BINS]; ROWS],
            boxes: [[BinBox::EMPTY; BINS]; ROWS],
        };
        bins.reset(centroids);
        bins
    }

    /// Bins `refs` into `self` (scratch reused across nodes: no copies of
    /// its 2.3 KB), in parallel chunks when there are many.
    #[inline(always)]
    fn fill(&mut self, refs: &[PrimRef], centroids: Box4) {
        if refs.len() >= 2 * PARALLEL_BIN_CHUNK {
            *self = refs
                .par_chunks(PARALLEL_BIN_CHUNK)
                .map(|c| bin_chunk(c, centroids))
                .reduce(|| Bins::empty(centroids), Bins::merge);
        } else {
            self.reset(centroids);
            self.add(refs);
        }
    }

    #[inline(always)]
    fn reset(&mut self, centroids: Box4) {
        let (min, max) = (centroids.min, centroids.max);
        self.min = min;
        self.scale = std::array::from_fn(|i| {
            let ext = max[i] - min[i];
            if ext > 0.0 { BINS as f32 / ext } else { 0.0 }
        });
        self.counts = [[0; BINS]; ROWS];
        // The fourth row's boxes are never grown.
        for row in &mut self.boxes[..3] {
            *row = [BinBox::EMPTY; BINS];
        }
    }

    /// Bins `refs`. Large nodes bin their first half into `self` and their second
    /// half into a second set of bins, one primitive of each per step, merged at the
    /// end: runs of neighbouring primitives fall in the same bins, and with one set
    /// each one's update waited for the previous one's (load, min, store). Halves, not
    /// alternate primitives: the merge then meets the values in their order, so ties
    /// (+0 and -0) resolve as one pass would resolve them, bit for bit.
    #[inline(always)]
    fn add(&mut self, refs: &[PrimRef]) {
        if refs.len() < TWO_SETS_MIN {
            for r in refs {
                self.add_one(r);
            }
            return;
        }
        let mut second = Bins::empty(Box4::EMPTY);
        (second.min, second.scale) = (self.min, self.scale);
        let (front, back) = refs.split_at(refs.len() / 2);
        for (a, b) in front.iter().zip(back) {
            self.add_one(a);
            second.add_one(b);
        }
        // `back` has one more when the count is odd.
        for r in &back[front.len()..] {
            second.add_one(r);
        }
        self.merge_in(&second);
    }

    /// The bins' flat index of each lane, `row * BINS + bin`, is formed in the
    /// lanes too: indexing the rows one by one made the compiler take the lanes apart.
    #[inline(always)]
    fn add_one(&mut self, r: &PrimRef) {
        let counts = self.counts.as_flattened_mut();
        let boxes = self.boxes.as_flattened_mut();
        let flipped = r.flipped();
        let k = bins_of(r.centroid(), self.min, self.scale);
        let at: [u32; 4] = std::array::from_fn(|i| (k[i] % BINS as u32) | (i * BINS) as u32);
        for &at in &at[..3] {
            let at = at as usize % (ROWS * BINS);
            counts[at] += 1;
            boxes[at].grow(flipped);
        }
        counts[at[3] as usize % (ROWS * BINS)] += 1;
    }

    #[inline(always)]
    fn merge_in(&mut self, o: &Bins) {
        for axis in 0..3 {
            for k in 0..BINS {
                self.counts[axis][k] += o.counts[axis][k];
                self.boxes[axis][k] = self.boxes[axis][k].union(o.boxes[axis][k]);
            }
        }
    }

    fn merge(mut self, o: Bins) -> Bins {
        self.merge_in(&o);
        self
    }

    /// The boxes of the primitives left and right of `plane`.
    #[inline(always)]
    fn boxes_around(&self, plane: &Plane) -> (Box4, Box4) {
        let boxes = &self.boxes[plane.axis];
        let union = |s: &[BinBox]| s.iter().fold(BinBox::EMPTY, |a, b| a.union(*b)).box4();
        (union(&boxes[..plane.bin]), union(&boxes[plane.bin..]))
    }
}

/// The bins of one chunk of a large node, for the best instruction set the CPU has (a
/// closure of [`Bins::fill`] would be compiled for the baseline one, outside `split`).
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn bin_chunk(refs: &[PrimRef], centroids: Box4) -> Bins {
    let mut bins = Bins::empty(centroids);
    bins.add(refs);
    bins
}

/// A candidate plane: centroids in bins `< bin` on `axis` go left.
struct Plane {
    axis: usize,
    bin: usize,
    /// Unnormalised SAH cost `A_L B_L + A_R B_R`, `B` counting [`blocks`].
    cost: f32,
}

/// Bin index of a centroid coordinate: `((c - min) * scale)` truncated into
/// `0..BINS`, NaN → 0, as `as usize` then `min(BINS - 1)` would give; clamped as a
/// float by compare-and-select. [`goes_left`] is the same test against a plane.
#[inline(always)]
fn bin_position(c: f32, min: f32, scale: f32) -> f32 {
    let x = (c - min) * scale;
    let x = if x > 0.0 { x } else { 0.0 };
    if x < (BINS - 1) as f32 {
        x
    } else {
        (BINS - 1) as f32
    }
}

/// [`bin_position`] truncated, lane by lane. `x as i32` would check every lane for
/// NaN and overflow (five instructions each, a tenth of the build); `x` is already
/// in `0..=BINS-1`, where its floor plus 2^23 holds the floor in its low mantissa
/// bits: exact truncation, in float SIMD lanes. The floor is one `roundps` in the
/// SSE4.1+ clones of `split` (the baseline clone calls `floorf`: the same values).
#[inline(always)]
fn bins_of(c: Lanes, min: Lanes, scale: Lanes) -> [u32; 4] {
    const MAGIC: f32 = (1u32 << 23) as f32;
    std::array::from_fn(|i| {
        let x = bin_position(c[i], min[i], scale[i]);
        (x.floor() + MAGIC).to_bits() - MAGIC.to_bits()
    })
}

/// [`bin_position`] of four lanes at once, kept in SIMD registers: `fast_max` /
/// `fast_min` (`maxps` / `minps`) are exactly its two compare-and-selects.
#[inline(always)]
fn bin_positions(c: f32x4, min: f32x4, scale: f32x4) -> f32x4 {
    ((c - min) * scale)
        .fast_max(f32x4::ZERO)
        .fast_min(f32x4::splat((BINS - 1) as f32))
}

/// Whether a centroid coordinate whose [`bin_position`] is `x` bins below `bin` (≥ 1):
/// for `x` ≥ 0, `trunc(x) < bin` exactly when `x < bin`, so no truncation is needed;
/// the clamps change nothing either side of `bin` (NaN goes to bin 0, left).
#[inline(always)]
fn goes_left(x: f32, bin: usize) -> bool {
    x < bin as f32
}

/// Cheapest binned-SAH plane over the three axes, if any separates the centroids.
/// The sweeps visit only the occupied bins, from a bit mask: an empty bin changes
/// neither the running box nor the count, so plane `k` costs what the plane after
/// the previous occupied bin does, and only a strictly cheaper plane replaces the best
/// one. The choice is the per-bin sweep's (the tests' reference), without its
/// unpredictable branch per bin.
#[inline(always)]
fn best_sah_plane(bins: &Bins) -> Option<Plane> {
    let mut best: Option<Plane> = None;
    for axis in 0..3 {
        if bins.scale[axis] == 0.0 {
            continue;
        }
        let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
        let mut occupied = 0u32;
        for (k, &n) in counts.iter().enumerate() {
            occupied |= u32::from(n > 0) << k;
        }
        if occupied == 0 {
            continue;
        }
        // right_cost[r]: area * blocks of the occupied bins from the r-th (counting
        // from 0 upwards) on, for r >= 1 (the lowest occupied bin is never on the right).
        let mut right_cost = [0.0f32; BINS];
        let mut acc_box = BinBox::EMPTY;
        let mut acc_n = 0u32;
        let mut rank = occupied.count_ones() as usize;
        let mut rest = occupied & occupied.wrapping_sub(1);
        while rest != 0 {
            let k = (u32::BITS - 1 - rest.leading_zeros()) as usize % BINS;
            rest ^= 1 << k;
            rank -= 1;
            acc_box = acc_box.union(boxes[k]);
            acc_n += counts[k];
            right_cost[rank % BINS] = acc_box.box4().surface_area() * blocks(acc_n);
        }
        // The plane after each occupied bin but the highest (which has nothing
        // on its right).
        let mut left_box = BinBox::EMPTY;
        let mut left_n = 0u32;
        let mut rank = 0;
        let highest = u32::BITS - 1 - occupied.leading_zeros();
        let mut rest = occupied & !(1 << highest);
        while rest != 0 {
            let k = rest.trailing_zeros() as usize % BINS;
            rest &= rest - 1;
            rank += 1;
            left_box = left_box.union(boxes[k]);
            left_n += counts[k];
            let cost = left_box.box4().surface_area() * blocks(left_n) + right_cost[rank % BINS];
            if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Plane {
                    axis,
                    bin: k + 1,
                    cost,
                });
            }
        }
    }
    best
}

/// Object median along the widest centroid axis; both halves' bounds.
fn median_split(refs: &mut [PrimRef], centroid_extent: Vec3) -> (usize, NodeBounds, NodeBounds) {
    let axis = centroid_extent.max_position();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| {
        a.centroid()[axis].total_cmp(&b.centroid()[axis])
    });
    let (left, right) = refs.split_at(mid);
    (mid, NodeBounds::of(left), NodeBounds::of(right))
}

/// In-place partition by `plane`; returns how many primitives go left (now at
/// the front) and the centroid boxes of both sides. The swap order is fixed:
/// it decides the primitive order in the leaves.
#[inline(always)]
fn partition(refs: &mut [PrimRef], bins: &Bins, plane: &Plane) -> (usize, Box4, Box4) {
    // One loop per axis: a lane picked at run time went through memory.
    match plane.axis {
        0 => partition_on::<0>(refs, bins, plane.bin),
        1 => partition_on::<1>(refs, bins, plane.bin),
        _ => partition_on::<2>(refs, bins, plane.bin),
    }
}

/// [`partition`] on axis `AXIS`.
#[inline(always)]
fn partition_on<const AXIS: usize>(
    refs: &mut [PrimRef],
    bins: &Bins,
    bin: usize,
) -> (usize, Box4, Box4) {
    let (min, scale) = (f32x4::from(bins.min), f32x4::from(bins.scale));
    let mut left = Box4::EMPTY;
    let mut right = Box4::EMPTY;
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        let r = refs[i];
        // All four lanes in SIMD registers: picking the axis's lane first made the
        // compiler take the centroid apart and put it back together.
        let c = r.centroid_x4();
        let x = bin_positions(c, min, scale).to_array();
        let c = c.to_array();
        if goes_left(x[AXIS], bin) {
            left.grow(c, c);
            i += 1;
        } else {
            right.grow(c, c);
            j -= 1;
            // refs.swap(i, j), without its round trip through the stack.
            refs[i] = refs[j];
            refs[j] = r;
        }
    }
    (i, left, right)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The per-axis sweep [`best_sah_plane`] must agree with (the builder's before it
    /// swept the axes together).
    fn best_sah_plane_reference(bins: &Bins) -> Option<Plane> {
        let mut best: Option<Plane> = None;
        for axis in 0..3 {
            if bins.scale[axis] == 0.0 {
                continue;
            }
            let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
            // right_cost[k]: area * blocks of bins k.. (the right side of plane k).
            let mut right_cost = [0.0f32; BINS];
            let mut acc_box = Box4::EMPTY;
            let mut acc_n = 0u32;
            let mut right = f32::INFINITY; // empty right side: not a split
            for k in (1..BINS).rev() {
                // An empty bin changes neither the box nor the count: skip the area.
                if counts[k] > 0 {
                    acc_box = acc_box.union(boxes[k].box4());
                    acc_n += counts[k];
                    right = acc_box.surface_area() * blocks(acc_n);
                }
                right_cost[k] = right;
            }
            let mut left_box = Box4::EMPTY;
            let mut left_n = 0u32;
            for k in 1..BINS {
                // Plane k costs the same as plane k - 1 when bin k - 1 is empty,
                // and only a strictly cheaper plane replaces the best one.
                if counts[k - 1] == 0 {
                    continue;
                }
                left_box = left_box.union(boxes[k - 1].box4());
                left_n += counts[k - 1];
                let cost = left_box.surface_area() * blocks(left_n) + right_cost[k];
                if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Plane { axis, bin: k, cost });
                }
            }
        }
        best
    }

    #[test]
    fn sweep_matches_the_per_axis_reference() {
        // Bins as nodes of a few to many primitives leave them: mostly empty to full,
        // flat and inverted (empty) boxes, infinite coordinates, ties between bins
        // and between axes (copied boxes), an axis with zero extent.
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut planes = 0;
        for round in 0..20_000 {
            let mut bins = Bins::empty(Box4::EMPTY);
            let full = next() % 17;
            for axis in 0..3 {
                bins.scale[axis] = if next() % 13 == 0 { 0.0 } else { 1.0 };
                for k in 0..BINS {
                    if next() % 16 >= full {
                        continue;
                    }
                    bins.counts[axis][k] = (next() % 9 + 1) as u32;
                    let v: [f32; 4] = std::array::from_fn(|_| (next() % 64) as f32 * 0.25 - 8.0);
                    let (lo, hi): (Lanes, Lanes) = match next() % 20 {
                        0 => (Box4::EMPTY.min, Box4::EMPTY.max),
                        1 => ([f32::NEG_INFINITY, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 0.0]),
                        2 => ([v[0], v[1], 0.0, 0.0], [v[0], 8.0, 0.0, 0.0]),
                        _ => (
                            [v[0], v[1], v[2], 0.0],
                            [v[0] + v[3] + 8.0, v[1] + 4.0, v[2] + 2.0, 0.0],
                        ),
                    };
                    bins.boxes[axis][k] = BinBox::of(Box4 { min: lo, max: hi });
                }
            }
            if round % 7 == 0 {
                bins.counts[1] = bins.counts[0];
                bins.boxes[1] = bins.boxes[0];
            }
            let got = best_sah_plane(&bins).map(|p| (p.axis, p.bin, p.cost.to_bits()));
            let want = best_sah_plane_reference(&bins).map(|p| (p.axis, p.bin, p.cost.to_bits()));
            assert_eq!(got, want, "round {round}");
            planes += usize::from(got.is_some());
        }
        assert!(planes > 10_000, "{planes}");
    }

    #[test]
    fn two_sets_of_bins_match_one_pass_bit_for_bit() {
        // Coordinates of +0 and -0 (ties the order decides) among a few values,
        // enough primitives for the two sets; odd and even counts.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for n in [TWO_SETS_MIN, 999, 4096] {
            let values = [0.0f32, -0.0, 1.0, -1.0, 0.5];
            let refs: Vec<PrimRef> = (0..n)
                .map(|i| {
                    let mut v = || values[(next() % 5) as usize];
                    let lo = Vec3::new(v(), v(), v());
                    let hi = lo + Vec3::new(v().abs(), v().abs(), v().abs());
                    PrimRef::new(i, &Aabb::new(lo, hi))
                })
                .collect();
            let centroids = NodeBounds::of(&refs).centroids;
            let mut two = Bins::empty(centroids);
            two.add(&refs);
            let mut one = Bins::empty(centroids);
            for r in &refs {
                one.add_one(r);
            }
            // The fourth row counts the unused lane and is never merged or read.
            assert_eq!(one.counts[..3], two.counts[..3], "{n}");
            for axis in 0..3 {
                for k in 0..BINS {
                    let bits = |b: &Bins| b.boxes[axis][k].0.to_array().map(f32::to_bits);
                    assert_eq!(bits(&one), bits(&two), "{n} prims, axis {axis} bin {k}");
                }
            }
        }
    }

    /// Every float the binning can meet near the bin edges, and the awkward ones.
    fn samples() -> Vec<f32> {
        let mut xs = vec![
            0.0, -0.0, -1.0, 1e-30, 0.5, 1.5, 2.5, 14.5, 15.0, 15.5, 16.0,
        ];
        xs.extend([1e9, f32::MAX, f32::INFINITY, f32::NEG_INFINITY, f32::NAN]);
        for k in 0..=BINS as u32 {
            let b = k as f32;
            xs.extend([b, b.next_down(), b.next_up(), b + 0.25, b + 0.5, b + 0.75]);
        }
        for i in 0..10_000 {
            xs.push(i as f32 * 0.0017);
        }
        xs
    }

    #[test]
    fn bins_of_truncates_exactly_like_as() {
        for x in samples() {
            let position = bin_position(x, 0.0, 1.0);
            let expected = position as u32;
            assert_eq!(bins_of([x; 4], [0.0; 4], [1.0; 4]), [expected; 4], "{x}");
            let lanes = bin_positions(f32x4::splat(x), f32x4::ZERO, f32x4::ONE).to_array();
            assert_eq!(lanes.map(f32::to_bits), [position.to_bits(); 4], "{x}");
            for bin in 1..BINS {
                assert_eq!(
                    goes_left(lanes[0], bin),
                    (expected as usize) < bin,
                    "{x} {bin}"
                );
            }
        }
    }
}
