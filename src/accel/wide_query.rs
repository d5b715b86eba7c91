//! The wide BVH's queries: closest hit and any hit, each compiled once per
//! instruction set (runtime dispatch through `multiversion`) with the traversal of
//! [`super::wide`] and the leaf test of [`super::leaf`] compiled into every clone.
//!
//! The leaf test reaches the traversal as a [`LeafVisitor`] whose method is
//! `#[inline(always)]`, not as a closure: rustc compiles a closure as a function of
//! its own, which LLVM did not inline into the clones, so the SoA prefilter ran as
//! baseline SSE2 code behind a call per leaf. The closest-hit clones call their leaf
//! test out of line all the same, as a function of their own compiled for the clone's
//! instruction set (`#[inherit_target]`): with the leaf test inlined, the node loop
//! reloaded the box test's per-ray constants from the stack at every node (primary
//! rays about 2% faster without). Any-hit queries keep it inline: shadow rays did not
//! gain from it.

use multiversion::target::match_target;
use multiversion::{inherit_target, multiversion};

use super::leaf::{LANES, RayLeaf, TriGroup, groups_for, leaf_count, one_plain_group};
use super::triangle::{RayShear, TriangleHit};
use super::wide_node::RayBoxes;
use super::wide_packet::{PACKET, PacketHits};
use super::{BOX_MARGIN, HitLanes, Ray, RayLanes, WideBvh};

#[path = "wide_closest.rs"]
mod closest;
pub(super) use closest::Best;
use closest::ClosestLeaves;
pub(super) use closest::three_ulps_up;

/// What a query does at each leaf the traversal reaches.
pub(super) trait LeafVisitor {
    /// Tests the leaf at group `group` with the lane count `count` (`leaf::leaf_lane`:
    /// triangles and flag); may lower `t_max` (the traversal's cull distance); returns
    /// true to stop the traversal.
    fn leaf(&mut self, group: usize, count: u32, t_max: &mut f32) -> bool;

    /// Tests a node's two nearest leaves met, `(group, count)` each, the second's
    /// box entered at `far_entry`: by default one after the other, the second only if
    /// its box still starts within the cull distance. Returns true to stop.
    #[inline(always)]
    fn leaf_pair(&mut self, pair: [(usize, u32); 2], far_entry: f32, t_max: &mut f32) -> bool {
        let [(g0, c0), (g1, c1)] = pair;
        self.leaf(g0, c0, t_max) || (far_entry <= *t_max * BOX_MARGIN && self.leaf(g1, c1, t_max))
    }

    /// Asks the cache for the memory of `item` (a leaf group the traversal is about
    /// to read; never read through this pointer); nothing by default.
    #[inline(always)]
    fn prefetch<T>(&self, item: *const T) {
        let _ = item;
    }
}

/// Calls `line(address)` for each 64-byte cache line `item` covers.
#[inline(always)]
fn each_line<T>(item: *const T, line: impl Fn(*const u8)) {
    let start = item.cast::<u8>();
    let mut offset = 0;
    while offset < size_of::<T>() {
        line(start.wrapping_add(offset));
        offset += 64;
    }
    // The line of the last byte, which the steps above miss when `item` may not start
    // on a line (a leaf group; not a node, aligned to whole lines).
    if align_of::<T>() < 64 || !size_of::<T>().is_multiple_of(64) {
        line(start.wrapping_add(size_of::<T>() - 1));
    }
}

/// The per-ray constants of the leaf test.
struct RayLeaves<'a> {
    /// The leaves' groups (`WideBvh::leaves`), at hand rather than behind the tree: one
    /// load less per leaf call.
    groups: &'a [TriGroup],
    ray: &'a Ray,
    /// The prefilter's constants; the rare scalar test makes its `RayShear` from `ray`.
    pre: RayLeaf,
}

impl RayLeaves<'_> {
    /// Tests the triangles of the leaf at `group` with the lane count `count`: the SoA
    /// prefilter, then the exact test's answer on each lane it keeps (from the lane's
    /// values where they decide it), both against `*bound`;
    /// `hit(lane, prim, hit, bound)` may lower the bound and returns true to stop
    /// (`lane`: `group * LANES + lane`, where the triangle's vertices are; `prim`: the
    /// caller's index of the triangle, read from the group the test has just read).
    /// The any-hit query's leaf test (the closest-hit query's is [`Self::closest`]).
    /// Any-hit queries too take a lane's hit from the prefilter's values: the scalar
    /// test on each candidate lane cost the shadow rays 8% more instructions.
    /// One loop over the groups: testing the first group apart (for the closest-hit
    /// query) took 3% fewer instructions per torus ray, but no less time on the tori or
    /// Sponza, and made the Cornell box's single rays 10-17% slower (anchors).
    #[inline(always)]
    fn hits(
        &self,
        group: usize,
        count: u32,
        bound: &mut f32,
        mut hit: impl FnMut(usize, u32, &TriangleHit, &mut f32) -> bool,
    ) -> bool {
        let (count, degenerate) = leaf_count(count);
        let groups = &self.groups[group..group + groups_for(count)];
        for (i, g) in groups.iter().enumerate() {
            if self.group_hits(group + i, g, degenerate, bound, &mut hit) {
                return true;
            }
        }
        false
    }

    /// [`Self::hits`] of group `g`, the group at `index` in the leaves.
    #[inline(always)]
    fn group_hits(
        &self,
        index: usize,
        g: &TriGroup,
        degenerate: bool,
        bound: &mut f32,
        hit: &mut impl FnMut(usize, u32, &TriangleHit, &mut f32) -> bool,
    ) -> bool {
        // The bound only falls within the group, so the group's first bound lets
        // through every lane a later, lower one accepts.
        let Some(candidates) = self.pre.candidates(g, *bound) else {
            return false;
        };
        // Padding lanes (NaN) never pass the prefilter: no mask by the count.
        let mut lanes = candidates.mask;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let h = candidates.hit(lane, g, degenerate, self.ray, *bound);
            let Some(h) = h else {
                continue;
            };
            if hit(index * LANES + lane, g.prim[lane % LANES], &h, bound) {
                return true;
            }
        }
        false
    }
}

/// A leaf visitor that hands each leaf to `test(leaves, group, count, t_max)` and
/// each cache line to prefetch to `line(address)`.
struct Calls<'a, V, F, Q, P> {
    leaves: &'a mut V,
    test: F,
    /// The test of a node's two nearest leaves (`LeafVisitor::leaf_pair`).
    pair: Q,
    line: P,
}

impl<V, F, Q, P> LeafVisitor for Calls<'_, V, F, Q, P>
where
    F: FnMut(&mut V, usize, u32, &mut f32) -> bool,
    Q: FnMut(&mut V, [(usize, u32); 2], f32, &mut f32) -> bool,
    P: Fn(*const u8),
{
    #[inline(always)]
    fn leaf(&mut self, group: usize, count: u32, t_max: &mut f32) -> bool {
        (self.test)(self.leaves, group, count, t_max)
    }

    #[inline(always)]
    fn leaf_pair(&mut self, pair: [(usize, u32); 2], far_entry: f32, t_max: &mut f32) -> bool {
        (self.pair)(self.leaves, pair, far_entry, t_max)
    }

    #[inline(always)]
    fn prefetch<T>(&self, item: *const T) {
        each_line(item, &self.line);
    }
}

/// The any-hit query's leaf test and the caller's visitor.
struct AnyLeaves<'a, F> {
    leaves: RayLeaves<'a>,
    bound: f32,
    visit: F,
}

impl<F: FnMut(u32, &TriangleHit) -> bool> LeafVisitor for AnyLeaves<'_, F> {
    #[inline(always)]
    fn leaf(&mut self, group: usize, count: u32, _: &mut f32) -> bool {
        let visit = &mut self.visit;
        self.leaves
            .hits(group, count, &mut self.bound, |_, prim, h, _| {
                visit(prim, h)
            })
    }
}

impl WideBvh {
    /// The closest hit in (0, t_max): the caller's triangle index and the hit. Of
    /// triangles hit at exactly the same t (where two meet), the lowest index wins,
    /// whatever order the traversal meets them in. Inlined into the caller: a call of
    /// its own only moved the dispatched query's result into the caller's shape (18
    /// instructions per ray).
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<(u32, TriangleHit)> {
        self.closest_hit_at(ray, t_max).map(|(p, _, h)| (p, h))
    }

    /// [`Self::closest_hit`] with where the triangle's vertices sit in `leaves`
    /// (`group * LANES + lane`, for [`WideBvh::triangle_at`]): (prim, lane, hit).
    #[inline]
    pub fn closest_hit_at(&self, ray: &Ray, t_max: f32) -> Option<(u32, u32, TriangleHit)> {
        let (lane, prim, h) = closest_hit_dispatched(self, ray, 0, Best::new(t_max), t_max).hit?;
        Some((prim, lane as u32, h))
    }

    /// [`Self::closest_hit_at`] compiled for whatever target features the caller has.
    #[cfg(test)]
    #[inline(always)]
    pub(super) fn closest_hit_inlined(
        &self,
        ray: &Ray,
        t_max: f32,
    ) -> Option<(u32, u32, TriangleHit)> {
        let (lane, prim, h) = self
            .closest_hit_with(
                ray,
                0,
                Best::new(t_max),
                t_max,
                |leaves, group, count, t_max| leaves.leaf(group, count, t_max),
                |leaves, pair, far_entry, t_max| {
                    leaves.pair(
                        pair,
                        far_entry,
                        t_max,
                        |leaves, group, count, t_max| leaves.leaf(group, count, t_max),
                        |leaves, best, groups, t_max| leaves.closest_pair(best, groups, t_max),
                    )
                },
                |_| {},
            )
            .hit?;
        Some((prim, lane as u32, h))
    }

    /// The closest-hit query of `ray` below node `root` (0: the whole tree) from the
    /// best hit so far `best` and the cull distance `cull` (the best hit's t, or the
    /// query's bound): the best hit after it. With the leaf test `test(leaves, group,
    /// count, t_max)`: `leaves.leaf(group, count, t_max)`, inlined or called;
    /// `line(address)` prefetches a cache line (or does nothing).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // The query's state and its three leaf calls.
    fn closest_hit_with(
        &self,
        ray: &Ray,
        root: u32,
        best: Best,
        cull: f32,
        test: impl FnMut(&mut ClosestLeaves, usize, u32, &mut f32) -> bool,
        pair: impl FnMut(&mut ClosestLeaves, [(usize, u32); 2], f32, &mut f32) -> bool,
        line: impl Fn(*const u8),
    ) -> Best {
        // One division for the box test's inverse direction and the shear's scale.
        let inv = ray.dir.recip().to_array();
        let boxes = RayBoxes::with_inverse(ray, inv);
        let mut leaves = ClosestLeaves {
            leaves: RayLeaves::new(self, ray, inv),
            best,
        };
        let mut cull = cull;
        let mut visitor = Calls {
            leaves: &mut leaves,
            test,
            pair,
            line,
        };
        self.traverse::<true>(root, &boxes, &mut cull, &mut visitor);
        leaves.best
    }

    /// Visits triangles the ray meets in (0, t_max), in no particular order, until
    /// `visit(prim, hit)` returns true (stop); returns whether it stopped.
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, &TriangleHit) -> bool,
    ) -> bool {
        any_hit_dispatched(self, ray, 0, t_max, &mut visit)
    }

    /// [`Self::any_hit`] compiled for whatever target features the caller has.
    #[inline(always)]
    pub(super) fn any_hit_inlined(
        &self,
        ray: &Ray,
        root: u32,
        t_max: f32,
        visit: impl FnMut(u32, &TriangleHit) -> bool,
    ) -> bool {
        let inv = ray.dir.recip().to_array();
        let boxes = RayBoxes::with_inverse(ray, inv);
        let mut leaves = AnyLeaves {
            leaves: RayLeaves::new(self, ray, inv),
            bound: t_max,
            visit,
        };
        let mut cull = t_max;
        self.traverse::<false>(root, &boxes, &mut cull, &mut leaves)
    }

    /// For up to [`PACKET`] rays at once (a packet, traced with one ray
    /// per SIMD lane; see `accel::wide_packet`): bit `i` is set when a triangle lies on
    /// `rays[i]` in (0, `t_max[i]`), exactly when `any_hit(&rays[i], t_max[i], |_, _|
    /// true)` is true.
    pub fn occluded_packet(&self, rays: &[Ray], t_max: &[f32]) -> u32 {
        assert!(
            rays.len() <= PACKET && t_max.len() == rays.len(),
            "a packet of {} rays and {} bounds",
            rays.len(),
            t_max.len()
        );
        occluded_packet_dispatched(self, rays, t_max)
    }

    /// [`Self::occluded_packet`] of the active lanes of `rays`, each bounded by `t_max`:
    /// bit `i` set when a triangle occludes lane `i`'s ray (never for an inactive
    /// lane). The rays are read in lanes as they are, not transposed.
    pub fn occluded_lanes(&self, rays: &RayLanes, t_max: f32) -> u32 {
        occluded_lanes_dispatched(self, rays, t_max)
    }

    /// For up to [`PACKET`] rays at once (a packet; see
    /// `accel::wide_packet`): entry `i` is exactly `closest_hit_at(&rays[i], t_max[i])`.
    pub fn closest_packet(&self, rays: &[Ray], t_max: &[f32]) -> PacketHits {
        assert!(
            rays.len() <= PACKET && t_max.len() == rays.len(),
            "a packet of {} rays and {} bounds",
            rays.len(),
            t_max.len()
        );
        closest_packet_dispatched(self, rays, t_max).to_packet_hits()
    }

    /// [`Self::closest_packet`] of `rays`, all bounded by `t_max`, in lanes: lane `i`
    /// holds `closest_hit_at(&rays[i], t_max)`. The rays are put in lanes and the bound
    /// spread to them inside the dispatched clone.
    pub fn closest_packet_within(&self, rays: &[Ray], t_max: f32) -> HitLanes {
        let mut hits = HitLanes::default();
        self.closest_packet_within_into(rays, t_max, &mut hits);
        hits
    }

    /// [`Self::closest_packet_within`] into `hits` (whatever it held before): the query
    /// writes the caller's lanes in place, where a returned value cost a copy of them.
    pub fn closest_packet_within_into(&self, rays: &[Ray], t_max: f32, hits: &mut HitLanes) {
        assert!(rays.len() <= PACKET, "a packet of {} rays", rays.len());
        closest_packet_within_dispatched(self, rays, t_max, hits);
    }
}

impl<'a> RayLeaves<'a> {
    #[inline(always)]
    fn new(wide: &'a WideBvh, ray: &'a Ray, inv: [f32; 3]) -> RayLeaves<'a> {
        let pre = RayLeaf::new(ray, &RayShear::with_inverse(ray, inv));
        RayLeaves {
            groups: &wide.leaves.groups,
            ray,
            pre,
        }
    }
}

// Runtime dispatch: one clone of each query per instruction set, the traversal and
// triangle tests (`#[inline(always)]`) compiled inside each, picked once per process
// from the CPU's features; no `-C target-cpu` needed. Rust never contracts a * b + c
// into an FMA by itself, so every clone computes bit-identical results. The any-hit
// query also has an x86-64-v4 (AVX-512) clone: the same 8-lane code with 32 vector
// registers spills less (rays example, torus 100k, least CPU time of 7: shadow 202-204
// -> 195-197 ms). The closest-hit query has none, nor do the packet queries (packets of
// primary rays 7% slower in a first anchors run). What made its v4 clone slower (primary
// rays 463-491 against 424-432 ms, 4M rays, least of 7) was 512-bit instructions, not
// the 32 registers or mask compares: the clones are tuned for the generic x86-64 CPU,
// which prefers 512-bit vectors once AVX-512 is on, so LLVM merged adjacent 32-byte
// stores (the ray's `RayLeaf` constants, the pair test's values) and the sort keys'
// 64-byte zeroing into zmm stores (10 instructions), which cost the whole clone time
// (presumably the clock or port 1 that 512-bit instructions take: the loss went with them).
// Without them (built with `-C target-feature=+prefer-256-bit`, an LLVM tuning flag Rust
// only takes globally, with a warning) the clone was 2% faster on primary rays (417-430
// against 425-436 ms) and no faster on incoherent ones, with the leaf test inlined (its
// constants then stay in registers) or out of line, and with the box test's mask taken
// by vmovmskps (AVX compares) instead of masked compares and kmov: below the 3% that
// would pay for the flag. The any-hit v4 clone has no zmm instruction; a change to it
// should keep it so (`objdump -d` of the clone, `grep zmm`).

/// [`WideBvh::closest_hit_with`] for the best instruction set the CPU has: the query
/// from the root, or a packet's ray handed over below a node. (Its inner functions
/// reach the query through closures: a function with target features implements no
/// `Fn` trait, whatever clippy's `redundant_closure` says.)
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
#[allow(clippy::redundant_closure)]
pub(super) fn closest_hit_dispatched(
    wide: &WideBvh,
    ray: &Ray,
    root: u32,
    best: Best,
    cull: f32,
) -> Best {
    /// The test of a leaf of several groups (or one with the degenerate flag) out of
    /// line (but compiled for this clone's instruction set): the traversal's loop,
    /// without the leaf test's many values, then keeps the box test's per-ray
    /// constants in registers instead of reloading them from the stack at every node
    /// (with the loop over the groups inlined, the traversal took 110 more
    /// instructions per primary ray on the torus).
    #[inherit_target]
    #[inline(never)]
    fn leaf(leaves: &mut ClosestLeaves, first: usize, count: u32, t_max: &mut f32) -> bool {
        leaves.groups(
            first,
            count,
            t_max,
            |l, best, index, g, degenerate, t_max| group(l, best, index, g, degenerate, t_max),
        )
    }
    /// The test of one group out of line too: in the loop over a leaf's groups (2.29
    /// groups per 2.26 leaves, primary rays on the torus), LLVM loaded the ray's
    /// constants on entry and spilled them to the stack at every call, where a
    /// straight group reads them from `leaves` at their use. The ray's constants
    /// come by shared reference, apart from the best hit it writes.
    #[inherit_target]
    #[inline(never)]
    fn group(
        leaves: &RayLeaves,
        best: &mut Best,
        index: usize,
        g: &TriGroup,
        degenerate: bool,
        t_max: &mut f32,
    ) {
        leaves.closest(best, index, g, degenerate, t_max)
    }
    /// `group` for a leaf of one group without the degenerate flag (nearly all leaves):
    /// without the flag's call to `degenerate_lanes` (the scalar lanes' test is out of
    /// line too, at the end), no value lives across a call, so the test saves two
    /// registers on entry where `group` saves six (torus 100k, per primary / incoherent
    /// ray: 1,215 / 1,475 -> 1,188 / 1,442 instructions with the scalar lanes' test out
    /// of line and the one-compare check in `one`).
    #[inherit_target]
    #[inline(never)]
    fn plain(leaves: &RayLeaves, best: &mut Best, index: usize, g: &TriGroup, t_max: &mut f32) {
        leaves.closest(best, index, g, false, t_max)
    }
    /// Prefetches the cache line at `address` into every cache level, in the clones
    /// with the instruction's target feature (a safe call only there; nothing in the
    /// fallback). A hint: it reads nothing and faults on no address.
    #[inherit_target]
    #[inline]
    fn prefetch(address: *const u8) {
        match_target! {
            "x86_64+avx2" => std::arch::x86_64::_mm_prefetch::<
                { std::arch::x86_64::_MM_HINT_T0 },
            >(address.cast()),
            "x86_64+sse4.2" => std::arch::x86_64::_mm_prefetch::<
                { std::arch::x86_64::_MM_HINT_T0 },
            >(address.cast()),
            _ => {
                let _ = address;
            }
        }
    }
    /// A node's two nearest one-group leaves in one 8-lane pass, out of line as
    /// `group` is. The groups as two arguments, in registers: an array of two went
    /// through the stack.
    #[inherit_target]
    #[inline(never)]
    fn pair(leaves: &RayLeaves, best: &mut Best, g0: usize, g1: usize, t_max: &mut f32) {
        leaves.closest_pair(best, [g0, g1], t_max)
    }
    /// The test of a leaf: one group without the degenerate flag straight to its test
    /// (`plain`): nearly all of them (2.29 groups per 2.26 leaves, primary rays on the
    /// torus), and `leaf`'s loop cost a second call (torus 100k, per primary /
    /// incoherent ray: 1,401 / 1,734 -> 1,331 / 1,636 instructions).
    #[inherit_target]
    #[inline]
    fn one(leaves: &mut ClosestLeaves, first: usize, count: u32, t_max: &mut f32) -> bool {
        if one_plain_group(count) {
            let g = &leaves.leaves.groups[first];
            plain(&leaves.leaves, &mut leaves.best, first * LANES, g, t_max);
            false
        } else {
            leaf(leaves, first, count, t_max)
        }
    }
    wide.closest_hit_with(
        ray,
        root,
        best,
        cull,
        |leaves, first, count, t_max| one(leaves, first, count, t_max),
        |leaves, leaf_pair, far_entry, t_max| {
            leaves.pair(
                leaf_pair,
                far_entry,
                t_max,
                |leaves, first, count, t_max| one(leaves, first, count, t_max),
                |l, best, [g0, g1], t_max| pair(l, best, g0, g1, t_max),
            )
        },
        |address| prefetch(address),
    )
}

/// [`WideBvh::any_hit_inlined`] for the best instruction set the CPU has: the query
/// from the root, or a packet's ray handed over below a node.
#[multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "x86_64+sse4.2"
))]
pub(super) fn any_hit_dispatched(
    wide: &WideBvh,
    ray: &Ray,
    root: u32,
    t_max: f32,
    visit: &mut dyn FnMut(u32, &TriangleHit) -> bool,
) -> bool {
    wide.any_hit_inlined(ray, root, t_max, visit)
}

/// [`WideBvh::occluded_packet`] for the best instruction set the CPU has (the rays are
/// put in lanes in here, with its instructions).
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn occluded_packet_dispatched(wide: &WideBvh, rays: &[Ray], t_max: &[f32]) -> u32 {
    let mut bounds = [0.0; PACKET];
    bounds[..t_max.len()].copy_from_slice(t_max);
    wide.occluded_lanes_inlined(&RayLanes::from_rays(rays), &bounds)
}

/// [`WideBvh::occluded_lanes`] for the best instruction set the CPU has. The bound is
/// spread to the lanes in here: an array of it made by the caller (two 16-byte stores
/// without AVX) stalled the 32-byte load that read it back.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn occluded_lanes_dispatched(wide: &WideBvh, rays: &RayLanes, t_max: f32) -> u32 {
    wide.occluded_lanes_inlined(rays, &[t_max; PACKET])
}

/// [`WideBvh::closest_packet`] for the best instruction set the CPU has.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn closest_packet_dispatched(wide: &WideBvh, rays: &[Ray], t_max: &[f32]) -> HitLanes {
    let mut bounds = [0.0; PACKET];
    bounds[..t_max.len()].copy_from_slice(t_max);
    wide.closest_lanes_inlined(&RayLanes::from_rays(rays), &bounds)
}

/// [`WideBvh::closest_packet_within`] for the best instruction set the CPU has (the
/// bound spread to the lanes in here, as in `occluded_lanes_dispatched`).
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn closest_packet_within_dispatched(wide: &WideBvh, rays: &[Ray], t_max: f32, hits: &mut HitLanes) {
    wide.closest_lanes_into(&RayLanes::from_rays(rays), &[t_max; PACKET], hits);
}

#[cfg(test)]
mod tests {
    use super::{each_line, three_ulps_up};
    use crate::accel::leaf::TriGroup;
    use crate::accel::wide_node::WideNode;
    use std::cell::RefCell;

    /// The 64-byte lines `each_line` names for `item`, as line numbers.
    fn lines_named<T>(item: &T) -> Vec<usize> {
        let lines = RefCell::new(Vec::new());
        each_line(item, |address| {
            lines.borrow_mut().push(address as usize / 64)
        });
        let mut lines = lines.into_inner();
        lines.sort();
        lines.dedup();
        lines
    }

    /// Every line of an item's bytes is prefetched: a leaf group (160 bytes, at both
    /// offsets from a line that its alignment of 32 allows) and a node (whole lines,
    /// each named once).
    #[test]
    fn each_line_names_every_line_of_an_item() {
        // 160 bytes: successive groups start 32 bytes further along a line, so they
        // start at both multiples of 32 below 64.
        let groups = vec![TriGroup::PADDING; 4];
        let offsets: std::collections::HashSet<usize> = groups
            .iter()
            .map(|g| g as *const TriGroup as usize % 64)
            .collect();
        assert_eq!(offsets.len(), 2);
        for g in &groups {
            let start = g as *const TriGroup as usize;
            let want: Vec<usize> =
                (start / 64..=(start + size_of::<TriGroup>() - 1) / 64).collect();
            assert_eq!(lines_named(g), want);
        }
        let node = WideNode::UNUSED;
        let calls = RefCell::new(0);
        each_line(&node, |_| *calls.borrow_mut() += 1);
        let start = &node as *const WideNode as usize / 64;
        assert_eq!(lines_named(&node), (start..start + 4).collect::<Vec<_>>());
        assert_eq!(calls.into_inner(), 4);
    }

    #[test]
    fn three_ulps_up_is_three_next_ups() {
        let mut ts = vec![
            f32::from_bits(1),
            f32::MIN_POSITIVE.next_down(),
            f32::MIN_POSITIVE,
            1e-30,
            0.5,
            1.0,
            1.0f32.next_down(),
            3.7e12,
            f32::MAX,
        ];
        // Up to three floats below the largest: the steps into infinity.
        for _ in 0..4 {
            ts.push(ts.last().unwrap().next_down());
        }
        // And a spread over every binade of positive finite floats.
        ts.extend((1..f32::MAX.to_bits()).step_by(9_973).map(f32::from_bits));
        for t in ts {
            let want = t.next_up().next_up().next_up();
            assert_eq!(three_ulps_up(t).to_bits(), want.to_bits(), "{t:e}");
        }
    }
}
