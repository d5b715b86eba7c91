//! A conservative cull for the any-hit packet query: the box around the segments of a
//! packet's rays, from each origin to its bound, against the eight child boxes of a node
//! in one pass. A child outside it is one that the box test (`PacketRays::test_box`)
//! rejects for every ray of the packet, so dropping it before the per-ray tests changes
//! no answer; what the cull keeps is tested ray by ray as before.
//!
//! Why the test rejects a box outside the segments' box, axis by axis, for a ray with
//! origin `o`, direction `d` (`d >= 0` here; `d < 0` is the mirror image), inverse
//! `inv = 1 / d` rounded, and bound `t_max`, writing `C = t_max * BOX_MARGIN` rounded
//! (the test's exit distance is at most `C`, and its entry distance at least 0):
//! - Far plane: `(hi - o) * inv` is below 0 when `hi < o` (a rounded difference has the
//!   exact one's sign), and then the test rejects the box; unless the product rounds to
//!   -0, which needs `o - hi < 2^-150 * |d|`: below [`ORIGIN_PAD`] while `|d| <=`
//!   [`MAX_DIR`]. So an accepted box has `hi >= o - ORIGIN_PAD`.
//! - Near plane: an accepted box has `(lo - o) * inv <= C` after two roundings, so
//!   `lo - o <= C * d * (1 + 3u)` (u = 2^-24; with `d` below [`MAX_DIR`] and `C` at
//!   least [`LEAST_REACH`] no step leaves the normal range except by less than
//!   [`TINY`]). The far end `o + d * C` here is widened by [`WIDEN`] and
//!   [`TINY`], far more than those roundings and its own.
//!
//! A ray outside those ranges (a NaN, an infinity, a huge direction, a bound below
//! [`LEAST_REACH`]) turns the cull off for its packet.

use wide::u32x8;

use super::ray_lanes::Lanes;
use super::wide_node::{WIDTH, WideNode};
use super::{BOX_MARGIN, PACKET, RayLanes};

/// Relative widening of the segments' far ends (2^-16): the roundings it covers are a
/// few times 2^-24.
const WIDEN: f32 = 1.0 / 65536.0;
/// Absolute widening of the far ends (2^-100): covers roundings in the subnormal range
/// (2^-150 each).
const TINY: f32 = 7.888_609e-31;
/// Widening of the origins (2^-110): more than a far-plane distance that rounds to -0
/// can hide (`2^-150 * MAX_DIR` = 2^-118).
const ORIGIN_PAD: f32 = 7.703_72e-34;
/// Largest direction component (2^32) and origin coordinate (2^64) the cull accepts.
const MAX_DIR: f32 = 4_294_967_296.0;
const MAX_ORIGIN: f32 = 18_446_744_073_709_551_616.0;
/// Least and largest `t_max * BOX_MARGIN` the cull accepts (2^-100, 2^64).
const LEAST_REACH: f32 = TINY;
const MAX_REACH: f32 = MAX_ORIGIN;

/// The box around the segments of a packet's active rays (see the module docs).
pub(super) struct SegmentBox {
    /// Least corner, per axis.
    lo: [f32; 3],
    /// Greatest corner, per axis.
    hi: [f32; 3],
}

/// `a < b ? a : b`, as `minps` picks (no NaN reaches it).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// `a > b ? a : b`, as `maxps` picks (no NaN reaches it).
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

impl SegmentBox {
    /// The box of the segments of the active rays of `rays` with bounds `t_max`, or
    /// `None` when a ray lies outside the ranges the argument covers.
    #[inline(always)]
    pub(super) fn of(rays: &RayLanes, t_max: &Lanes) -> Option<SegmentBox> {
        let mut lo = [[0.0f32; PACKET]; 3];
        let mut hi = [[0.0f32; PACKET]; 3];
        let mut bad = [0u32; PACKET];
        for r in 0..PACKET {
            let on = rays.active & (1 << r) != 0;
            // An inactive lane's corners become (inf, -inf) through a maximum and a
            // minimum, not a select: the compiler made the selects masked stores,
            // which the loads of the reduction below waited for.
            let least = if on { f32::NEG_INFINITY } else { f32::INFINITY };
            let reach = t_max[r] * BOX_MARGIN * (1.0 + WIDEN);
            let mut ok = (LEAST_REACH..=MAX_REACH).contains(&reach);
            for a in 0..3 {
                let (o, d) = (rays.origin[a][r], rays.dir[a][r]);
                ok &= (o.abs() <= MAX_ORIGIN) & (d.abs() <= MAX_DIR);
                let end = o + d * reach;
                let pad = end.abs() * WIDEN + TINY;
                // (An active lane's values are not NaN, or `ok` is false.)
                lo[a][r] = max(min(o - ORIGIN_PAD, end - pad), least);
                hi[a][r] = min(max(o + ORIGIN_PAD, end + pad), -least);
            }
            bad[r] = ((on & !ok) as u32).wrapping_neg();
        }
        if u32x8::from(bad).to_bitmask() != 0 {
            return None;
        }
        let fold = |v: &Lanes, f: fn(f32, f32) -> f32| {
            let v4: [f32; 4] = std::array::from_fn(|i| f(v[i], v[i + 4]));
            f(f(v4[0], v4[2]), f(v4[1], v4[3]))
        };
        Some(SegmentBox {
            lo: std::array::from_fn(|a| fold(&lo[a], min)),
            hi: std::array::from_fn(|a| fold(&hi[a], max)),
        })
    }

    /// The lanes of `node` whose child box meets this box (or is NaN somewhere): every
    /// other child the box test rejects for each ray of the packet.
    #[inline(always)]
    pub(super) fn children_met(&self, node: &WideNode) -> u32 {
        let b = &node.bounds;
        let mut met = [0u32; WIDTH];
        for (c, m) in met.iter_mut().enumerate() {
            let mut apart = false;
            for a in 0..3 {
                apart |= (b[a][c] > self.hi[a]) | (b[a + 3][c] < self.lo[a]);
            }
            *m = (!apart as u32).wrapping_neg();
        }
        u32x8::from(met).to_bitmask()
    }
}
