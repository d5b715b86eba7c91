//! The closest-hit query's decision for a group: `LaneValues::decide`'s division and
//! range check for all of its candidate lanes at once, in a lane loop (one division
//! for the four), then only the closest hit handed on, where each candidate lane went
//! through `decide` one after the other. Whether t is clear of 0 is asked of the hit
//! lanes alone, one by one (nearly always one): in the lane loop, its f64 arithmetic
//! for every lane, on the path to the branch on the hits, made primary rays 5% slower
//! (torus 100k) for fewer instructions.

use super::{
    LANES, LaneValues, PAIR, RayLeaf, TriGroup, clear_of_zero, is_degenerate, lane_mask_of,
};
use crate::accel::triangle::TriangleHit;

/// A group's lanes for the closest-hit query ([`RayLeaf::closest`]): those its
/// values may decide as hits against the group's first bound, those left to the
/// scalar test, and the lanes' values.
pub struct GroupHits<const N: usize = LANES> {
    /// Lanes with no zero edge function and a t in range: hits, as
    /// `LaneValues::decide` decides them, when their t is clear of 0 (which
    /// [`GroupHits::closest`] asks).
    pub hits: u32,
    /// Lanes the scalar test decides: a zero edge function (and, after
    /// [`GroupHits::closest`], a t in range that is not clear of 0).
    pub scalar: u32,
    t: [f32; N],
    inv_det: [f32; N],
    det: [f32; N],
    sizes: [[f32; N]; 3],
    e: [[f32; N]; 3],
}

impl RayLeaf {
    /// The closest-hit query's lanes of group `g` with bound `t_max` (see
    /// [`GroupHits`]); `degenerate` is the leaf's flag (`leaf::DEGENERATE`). None when
    /// the prefilter rejects every lane. Every lane the scalar test may hit with
    /// `t_max` is in `hits` or `scalar`; a lane of `hits` whose t is clear of 0 is the
    /// scalar test's hit with `t_max`, and with any lower bound above its t (the
    /// caller's bound stays three ulps past the best t: see `Best::bound`), so that
    /// the closest of those by (t, prim) is the only one of them that can be the best.
    #[inline(always)]
    pub fn closest(&self, g: &TriGroup, t_max: f32, degenerate: bool) -> Option<GroupHits> {
        let c = self.candidates(g, t_max)?;
        let mut mask = c.mask;
        if degenerate {
            // The scalar test never hits a degenerate triangle.
            mask &= !degenerate_lanes(g, mask);
        }
        Some(decide(c, mask, t_max))
    }

    /// [`Self::closest`] of two one-group leaves without the degenerate flag in one
    /// 8-lane pass (lanes 0-3 of `pair[0]`, 4-7 of `pair[1]`): the cost of one group
    /// on AVX, one call for the two nearest leaves of a node.
    #[inline(always)]
    pub fn closest_pair(&self, pair: [&TriGroup; 2], t_max: f32) -> Option<GroupHits<PAIR>> {
        let axes = self.axes();
        // Each vertex coordinate of the two groups side by side (two loads into a
        // ymm), in the sheared axis order.
        let mut v = [[[0.0; PAIR]; 3]; 3];
        for (i, vertex) in v.iter_mut().enumerate() {
            for (row, k) in vertex.iter_mut().zip(axes) {
                row[..LANES].copy_from_slice(&pair[0].v[i][k]);
                row[LANES..].copy_from_slice(&pair[1].v[i][k]);
            }
        }
        let c = self.prefilter(&v, t_max)?;
        let mask = c.mask;
        Some(decide(c, mask, t_max))
    }
}

/// The lanes of `mask` in `c` decided at once (see [`GroupHits`]).
#[inline(always)]
fn decide<const N: usize>(c: LaneValues<N>, mask: u32, t_max: f32) -> GroupHits<N> {
    let mut hit = [0u32; N];
    let mut t = [0.0; N];
    let mut inv_det = [0.0; N];
    for lane in 0..N {
        // `decide`'s checks after its bound check, which the prefilter made with
        // this bound (the same comparison): the division's range; whether t is
        // clear of 0 is asked of the closest lane alone (`GroupHits::closest`).
        inv_det[lane] = 1.0 / c.det[lane];
        t[lane] = c.t_scaled[lane] * inv_det[lane];
        let inside = (t[lane] > 0.0) & (t[lane] < t_max);
        hit[lane] = (inside as u32).wrapping_neg();
    }
    let decided = mask & !c.zero;
    GroupHits {
        hits: lane_mask_of(&hit) & decided,
        scalar: mask & c.zero,
        t,
        inv_det,
        det: c.det,
        sizes: c.sizes,
        e: c.e,
    }
}

/// The lanes of `mask` in `g` whose triangle is degenerate (`is_degenerate`): out of
/// line, for the few leaves that hold one.
#[cold]
#[inline(never)]
fn degenerate_lanes(g: &TriGroup, mask: u32) -> u32 {
    (0..LANES)
        .filter(|&lane| mask & (1 << lane) != 0)
        .filter(|&lane| {
            let [a, b, c] = g.triangle(lane);
            is_degenerate(a, b, c)
        })
        .fold(0, |m, lane| m | 1 << lane)
}

impl<const N: usize> GroupHits<N> {
    /// The lane of `hits` with the least (t, then prim) of the group's `prims`, the
    /// only one of them that may be the best, once the lanes of `hits` whose t is not
    /// clear of 0 (`clear_of_zero`) are moved to `scalar`: the scalar test recomputes
    /// such a t in f64, which may move it below the others, or miss it. None when no
    /// lane of `hits` is clear. Nearly always one lane is hit, and clear.
    #[inline(always)]
    pub fn closest(&mut self, prims: &[u32; N]) -> Option<usize> {
        let mut best: Option<usize> = None;
        let mut lanes = self.hits;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let [pz, xy, z] = &self.sizes;
            if !clear_of_zero(self.t[lane], self.det[lane], [pz[lane], xy[lane], z[lane]]) {
                self.scalar |= 1 << lane;
                continue;
            }
            let t = self.t[lane];
            let closer = |b: usize| t < self.t[b] || (t == self.t[b] && prims[lane] < prims[b]);
            if best.is_none_or(closer) {
                best = Some(lane);
            }
        }
        best
    }

    /// The hit of lane `lane` (in `hits`): the scalar test's, bit for bit.
    #[inline(always)]
    pub fn hit(&self, lane: usize) -> TriangleHit {
        let inv_det = self.inv_det[lane];
        TriangleHit {
            t: self.t[lane],
            b0: self.e[0][lane] * inv_det,
            b1: self.e[1][lane] * inv_det,
            b2: self.e[2][lane] * inv_det,
        }
    }
}
