//! Packets that go on as single rays: an entry of a packet's traversal left with
//! [`HAND_OVER_RAYS`] rays or fewer hands each to the single-ray query below its node.
//! Such a packet tests each of a node's boxes, and each triangle of a leaf, against a
//! few rays, where the single-ray query tests a node's eight boxes, and a group's four
//! triangles, at once for one. Both answer by the same exact triangle test whatever
//! the order: the closest-hit query keeps the least (t, index) hit below the bound
//! (see `ClosestLeaves`), the any-hit query any hit below it; so each ray's answer is
//! the packet's, and the single-ray query's.

use glam::Vec3;

use super::{Lanes, PacketRays};
use crate::accel::wide_query::{Best, any_hit_dispatched, closest_hit_dispatched};
use crate::accel::{HitLanes, Ray, WideBvh};

/// A packet's entry with this many rays or fewer goes on as single rays
/// ([`PacketRays::closest_below`], [`PacketRays::occluded_below`]) in trees of
/// [`HAND_OVER_DEPTH`] levels or more. Instructions per ray of the anchors' ray sets
/// traced as packets (`GLINT_RAYS_PACKETS=1 rays`, torus 100k primary / incoherent /
/// shadow) from 1,231 / 6,433 / 3,761 without: 1 ray 1,200 / 2,047 / 1,338, 2 rays
/// 1,176 / 1,749 / 1,162, 3 rays 1,160 / 1,655 / 1,098, 4 rays 1,158 / 1,631 / 1,079,
/// 6 rays 1,179 / 1,627 / 1,062 (1M: 1,936 / 7,664 / 4,604 without, 1,387 / 1,814 /
/// 1,170 with 4, 1,335 / 1,809 / 1,150 with 6); least CPU time best at 4.
const HAND_OVER_RAYS: u32 = 4;

/// See [`HAND_OVER_RAYS`].
const HAND_OVER_DEPTH: u32 = 2;

impl PacketRays {
    /// The closest hit of each ray of `rays` below node `root` by the single-ray query,
    /// from its best hit so far in `best`, its bound and its cull distance; keeps what
    /// it finds there.
    #[inline(always)]
    pub(super) fn closest_below(
        &mut self,
        wide: &WideBvh,
        root: u32,
        rays: u32,
        limit: &Lanes,
        best: &mut HitLanes,
    ) {
        let mut left = rays;
        while left != 0 {
            let r = left.trailing_zeros() as usize;
            left &= left - 1;
            self.hand_over(wide, root, r, limit, best);
        }
    }

    /// The rays of `rays` that meet a triangle below node `root` within their bound,
    /// by the single-ray any-hit query from there.
    #[inline(always)]
    pub(super) fn occluded_below(&self, wide: &WideBvh, root: u32, rays: u32) -> u32 {
        let mut occluded = 0;
        let mut left = rays;
        while left != 0 {
            let r = left.trailing_zeros() as usize;
            left &= left - 1;
            let ray = self.ray(r);
            if any_hit_dispatched(wide, &ray, root, self.bound[r], &mut |_, _| true) {
                occluded |= 1 << r;
            }
        }
        occluded
    }

    /// [`Self::closest_below`] of ray `r`: its best hit in and out of the single-ray
    /// query's form.
    #[inline(always)]
    fn hand_over(
        &mut self,
        wide: &WideBvh,
        root: u32,
        r: usize,
        limit: &Lanes,
        best: &mut HitLanes,
    ) {
        let ray = self.ray(r);
        let hit = best.get(r).map(|(prim, slot, h)| (slot as usize, prim, h));
        let before = Best {
            hit,
            limit: limit[r],
            bound: self.bound[r],
        };
        let after = closest_hit_dispatched(wide, &ray, root, before, self.cull[r]);
        if let Some((slot, prim, h)) = after.hit {
            best.set(r, prim, slot as u32, &h);
            self.cull[r] = h.t;
            self.bound[r] = after.bound;
        }
    }

    /// Ray `r`, as the caller gave it.
    #[inline(always)]
    fn ray(&self, r: usize) -> Ray {
        let lane = |v: &[Lanes; 3]| Vec3::new(v[0][r], v[1][r], v[2][r]);
        Ray {
            origin: lane(&self.origin),
            dir: lane(&self.dir),
        }
    }
}

impl WideBvh {
    /// The most rays of a packet's entry that go on as single rays: none in a shallow
    /// tree, where the single-ray query's setup per ray costs more than what is left of
    /// the traversal (the Cornell box's 34 triangles, 3 nodes: 338 -> 348 instructions
    /// per ray with [`HAND_OVER_RAYS`] there).
    #[inline(always)]
    pub(super) fn hand_over_rays(&self) -> u32 {
        if self.depth >= HAND_OVER_DEPTH {
            HAND_OVER_RAYS
        } else {
            0
        }
    }
}
