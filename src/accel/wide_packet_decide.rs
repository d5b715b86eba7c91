//! The closest-hit packet's decision for a triangle that keeps several rays: the scalar
//! test's checks (`LaneValues::decide`) for all of them at once, in lane loops.

use glam::Vec3;
use wide::u32x8;

use super::{PACKET, PacketCandidates, PacketRays};
use crate::accel::HitLanes;
use crate::accel::leaf::clear_of_zero;
use crate::accel::ray_lanes::Lanes;
use crate::accel::triangle::{TriangleHit, is_degenerate};
use crate::accel::wide_query::three_ulps_up;

impl PacketRays {
    /// [`LaneValues::decide`] of triangle `p` (at `slot` in the leaves) for every ray
    /// of `kept` without a zero edge function, lane by lane in vectors, each hit kept
    /// in `best` as `closest_in_leaf` keeps it; returns the rays of `kept` left to the
    /// scalar path: those with a zero edge function or a t not clear of 0 (which
    /// `decide` hands to the scalar test). `degenerate` is the leaf's flag and the
    /// triangle's vertices, tested for degeneracy as `decide` tests them.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // The triangle, its place, and the hits kept.
    pub(super) fn decide_lanes(
        &mut self,
        c: &PacketCandidates,
        kept: u32,
        (degenerate, tri): (bool, impl FnOnce() -> [Vec3; 3]),
        p: u32,
        slot: u32,
        best: &mut HitLanes,
        limit: &Lanes,
    ) -> u32 {
        let lanes = kept & !c.zero;
        // A degenerate triangle: `decide` gives every lane past its bound check None.
        if degenerate {
            let [a, b, v] = tri();
            if is_degenerate(a, b, v) {
                return kept & c.zero;
            }
        }
        let mut accept = [0u32; PACKET];
        let mut unclear = [0u32; PACKET];
        let mut t = [0.0f32; PACKET];
        let mut inv_det = [0.0f32; PACKET];
        for r in 0..PACKET {
            let (det, t_scaled, t_max) = (c.det[r], c.t_scaled[r], self.bound[r]);
            // `decide`'s checks in its order, as selects.
            let beyond = if det < 0.0 {
                t_scaled <= t_max * det
            } else {
                t_scaled >= t_max * det
            };
            inv_det[r] = 1.0 / det;
            t[r] = t_scaled * inv_det[r];
            let inside = !beyond & (t[r] > 0.0) & (t[r] < t_max);
            let sizes = [c.sizes[0][r], c.sizes[1][r], c.sizes[2][r]];
            let clear = clear_of_zero(t[r], det, sizes);
            accept[r] = ((inside & clear) as u32).wrapping_neg();
            unclear[r] = ((inside & !clear) as u32).wrapping_neg();
        }
        let mut accepted = u32x8::from(accept).to_bitmask() & lanes;
        let unclear = u32x8::from(unclear).to_bitmask() & lanes;
        while accepted != 0 {
            let r = accepted.trailing_zeros() as usize;
            accepted &= accepted - 1;
            let (t, first) = (t[r], best.found & (1 << r) == 0);
            if first || t < best.t[r] || (t == best.t[r] && p < best.prim[r]) {
                let h = TriangleHit {
                    t,
                    b0: c.e[0][r] * inv_det[r],
                    b1: c.e[1][r] * inv_det[r],
                    b2: c.e[2][r] * inv_det[r],
                };
                self.cull[r] = t;
                self.bound[r] = three_ulps_up(t).min(limit[r]);
                best.set(r, p, slot, &h);
            }
        }
        (kept & c.zero) | unclear
    }
}
