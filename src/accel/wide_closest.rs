//! The closest-hit query's leaf visitor: its best hit so far, and its leaf tests of
//! one group and of two sibling one-group leaves in one 8-lane pass.

use super::{LeafVisitor, RayLeaves};
use crate::accel::BOX_MARGIN;
use crate::accel::leaf::{LANES, TriGroup, groups_for, leaf_count, scalar_lane};
use crate::accel::triangle::TriangleHit;

/// The closest-hit query's leaf test and best hit so far.
pub(super) struct ClosestLeaves<'a> {
    pub(super) leaves: RayLeaves<'a>,
    pub(super) best: Best,
}

/// The closest-hit query's best hit so far and its bounds.
#[derive(Clone, Copy)]
pub(in crate::accel) struct Best {
    /// The best hit: where the triangle sits in the leaves (`group * LANES + lane`), its
    /// index and the hit.
    pub(in crate::accel) hit: Option<(usize, u32, TriangleHit)>,
    /// The query's own t_max.
    pub(in crate::accel) limit: f32,
    /// Past the best t so far by more than the rounding of the triangle test's scaled
    /// early-out (t_scaled against bound * det, three roundings): then every triangle
    /// with t at or below the best passes it whatever the order of the leaves, and the
    /// comparison below alone decides, so the hit is the least (t, index) of the
    /// triangles hit before `limit`. It changes only with the best hit.
    pub(in crate::accel) bound: f32,
}

impl Best {
    /// No hit yet, for a query bounded by `t_max`.
    #[inline(always)]
    pub(in crate::accel) fn new(t_max: f32) -> Best {
        Best {
            hit: None,
            limit: t_max,
            bound: t_max,
        }
    }
}

impl LeafVisitor for ClosestLeaves<'_> {
    #[inline(always)]
    fn leaf(&mut self, group: usize, count: u32, t_max: &mut f32) -> bool {
        self.groups(
            group,
            count,
            t_max,
            |leaves, best, index, g, degenerate, t_max| {
                leaves.closest(best, index, g, degenerate, t_max)
            },
        )
    }
}

impl ClosestLeaves<'_> {
    /// A node's two nearest leaves (`LeafVisitor::leaf_pair`): two one-group leaves
    /// without the degenerate flag to `pair_test(leaves, best, groups, t_max)` in one
    /// pass (both against the bound of now: more lanes than one after the other may
    /// reach the exact test, which alone decides, so the same best hit), others to
    /// `test(self, group, count, t_max)` one after the other.
    #[inline(always)]
    pub(super) fn pair(
        &mut self,
        pair: [(usize, u32); 2],
        far_entry: f32,
        t_max: &mut f32,
        mut test: impl FnMut(&mut Self, usize, u32, &mut f32) -> bool,
        pair_test: impl FnOnce(&RayLeaves, &mut Best, [usize; 2], &mut f32),
    ) -> bool {
        let [(g0, c0), (g1, c1)] = pair;
        let one_group = |count| {
            let (n, degenerate) = leaf_count(count);
            (1..=LANES).contains(&n) && !degenerate
        };
        if one_group(c0) && one_group(c1) {
            pair_test(&self.leaves, &mut self.best, [g0, g1], t_max);
            false
        } else {
            test(self, g0, c0, t_max)
                || (far_entry <= *t_max * BOX_MARGIN && test(self, g1, c1, t_max))
        }
    }

    /// Calls `test(leaves, best, index, g, degenerate, t_max)` for each group `g` of
    /// the leaf at group `group` with the lane count `count` (`index`: the lane of
    /// its first triangle, `group * LANES`; `degenerate`: the leaf's flag).
    #[inline(always)]
    pub(super) fn groups(
        &mut self,
        group: usize,
        count: u32,
        t_max: &mut f32,
        mut test: impl FnMut(&RayLeaves, &mut Best, usize, &TriGroup, bool, &mut f32),
    ) -> bool {
        let (count, degenerate) = leaf_count(count);
        let groups = &self.leaves.groups[group..group + groups_for(count)];
        for (i, g) in groups.iter().enumerate() {
            let index = (group + i) * LANES;
            test(&self.leaves, &mut self.best, index, g, degenerate, t_max);
        }
        false
    }
}

impl RayLeaves<'_> {
    /// The closest-hit query's test of the one-group leaves at groups `pair` in one
    /// 8-lane pass (`RayLeaf::closest_pair`), as [`Self::closest`] tests one.
    #[inline(always)]
    pub(super) fn closest_pair(&self, best: &mut Best, pair: [usize; 2], t_max: &mut f32) {
        let groups = self.groups;
        let g = [&groups[pair[0]], &groups[pair[1]]];
        let Some(mut lanes) = self.pre.closest_pair(g, best.bound) else {
            return;
        };
        let mut prims = [0; 2 * LANES];
        prims[..LANES].copy_from_slice(&g[0].prim);
        prims[LANES..].copy_from_slice(&g[1].prim);
        if let Some(lane) = lanes.closest(&prims) {
            let h = lanes.hit(lane);
            let index = pair[lane / LANES] * LANES + lane % LANES;
            best.offer(index, prims[lane], &h, t_max);
        }
        if lanes.scalar != 0 {
            self.pair_scalar_lanes(best, pair[0], pair[1], lanes.scalar, t_max);
        }
    }

    /// [`Self::scalar_lanes`] of the lanes of `scalar` in a pair's 8-lane pass: bits
    /// `0..LANES` of group `g0`, the others of group `g1`, in one call (cold too).
    #[cold]
    #[inline(never)]
    fn pair_scalar_lanes(
        &self,
        best: &mut Best,
        g0: usize,
        g1: usize,
        scalar: u32,
        t_max: &mut f32,
    ) {
        self.scalar_lanes(best, g0, scalar, false, t_max);
        self.scalar_lanes(best, g1, scalar >> LANES, false, t_max);
    }

    /// The closest-hit query's test of group `g` (at lane `index` in the leaves, in a
    /// leaf with the flag `degenerate`): its candidate lanes decided at once
    /// (`RayLeaf::closest`), the closest decided hit offered to `best`, then each lane
    /// left to the scalar test.
    #[inline(always)]
    pub(super) fn closest(
        &self,
        best: &mut Best,
        index: usize,
        g: &TriGroup,
        degenerate: bool,
        t_max: &mut f32,
    ) {
        let Some(mut lanes) = self.pre.closest(g, best.bound, degenerate) else {
            return;
        };
        if let Some(lane) = lanes.closest(&g.prim) {
            let h = lanes.hit(lane);
            best.offer(index + lane, g.prim[lane], &h, t_max);
        }
        if lanes.scalar != 0 {
            self.scalar_lanes(best, index / LANES, lanes.scalar, degenerate, t_max);
        }
    }

    /// The scalar test of the lanes of `scalar` (bits `0..LANES`) of the group at `group`
    /// in the leaves, each hit offered to `best`: out of line and cold, as few groups
    /// have such a lane, so that the group tests hold no values across its calls.
    #[cold]
    #[inline(never)]
    fn scalar_lanes(
        &self,
        best: &mut Best,
        group: usize,
        scalar: u32,
        degenerate: bool,
        t_max: &mut f32,
    ) {
        let g = &self.groups[group];
        let mut scalar = scalar & ((1 << LANES) - 1);
        while scalar != 0 {
            let lane = scalar.trailing_zeros() as usize;
            scalar &= scalar - 1;
            if let Some(h) = scalar_lane(g, lane, self.ray, best.bound, degenerate) {
                best.offer(group * LANES + lane, g.prim[lane], &h, t_max);
            }
        }
    }
}

impl Best {
    /// Keeps hit `h` of triangle `prim` (at `lane` in the leaves) when it is closer than
    /// the best so far by (t, then prim); then lowers the bound and `t_max`.
    #[inline(always)]
    fn offer(&mut self, lane: usize, prim: u32, h: &TriangleHit, t_max: &mut f32) {
        let closer =
            |&(_, bp, bh): &(usize, u32, TriangleHit)| h.t < bh.t || (h.t == bh.t && prim < bp);
        if self.hit.as_ref().is_none_or(closer) {
            *t_max = h.t;
            self.bound = three_ulps_up(h.t).min(self.limit);
            self.hit = Some((lane, prim, *h));
        }
    }
}

/// `t.next_up()` three times, for a hit's t (positive and finite): positive floats are
/// ordered like their bits, and the one past `f32::MAX` is infinity, where `next_up`
/// stays. Integer arithmetic, where the three `next_up` were about 40 instructions of
/// NaN, infinity and sign checks per closer hit.
#[inline(always)]
pub(in crate::accel) fn three_ulps_up(t: f32) -> f32 {
    debug_assert!(t > 0.0 && t.is_finite(), "{t}");
    f32::from_bits((t.to_bits() + 3).min(f32::INFINITY.to_bits()))
}
