//! The closest hits of a packet of rays on the whole scene, as the shading reads them:
//! those on flattened triangles in lanes ([`HitLanes`], as the wide BVH's packet query
//! keeps them, so the shading points' lanes are filled with whole-lane copies), the
//! rare others (instanced triangles, spheres) one by one.

use arrayvec::ArrayVec;

use super::geometry::{Hit, PrimKind, SceneGeometry, triangle_hit};
use crate::accel::{HitLanes, PACKET, Ray, TriangleHit};

/// The closest hits of up to [`PACKET`] rays: lane `r`'s is in `flat` when bit `r` of
/// `flat.found` is set, else in `others` if listed there, else it missed.
#[derive(Clone, Debug, Default)]
pub struct PacketSceneHits {
    /// Hits on flattened triangles.
    pub flat: HitLanes,
    /// Other hits (instanced triangles, spheres), each with its lane.
    pub others: ArrayVec<(u32, Hit), PACKET>,
}

impl PacketSceneHits {
    /// `hits` (at most [`PACKET`]), lane `r` holding `hits[r]`.
    pub fn from_hits(hits: &[Option<Hit>]) -> PacketSceneHits {
        let mut out = PacketSceneHits::default();
        for (r, hit) in hits.iter().enumerate() {
            out.set(r, *hit);
        }
        out
    }

    /// Puts `hit` in lane `r`, which holds none yet.
    fn set(&mut self, r: usize, hit: Option<Hit>) {
        match hit {
            None => {}
            Some(
                h @ Hit {
                    kind: PrimKind::Triangle,
                    instance: None,
                    ..
                },
            ) => {
                let [b0, b1, b2] = h.bary.to_array();
                let th = TriangleHit { t: h.t, b0, b1, b2 };
                self.flat.set(r, h.prim, h.lane, &th);
            }
            Some(h) => self.others.push((r as u32, h)),
        }
    }

    /// Lane `r`'s hit.
    pub fn get(&self, r: usize) -> Option<Hit> {
        match self.flat.get(r) {
            Some((prim, lane, h)) => Some(Hit {
                lane,
                ..triangle_hit(prim, &h)
            }),
            None => self
                .others
                .iter()
                .find(|&&(l, _)| l as usize == r)
                .map(|&(_, h)| h),
        }
    }
}

impl SceneGeometry {
    /// [`Self::intersect`] (unobserved) of up to [`PACKET`] rays with one `t_max`, into
    /// `hits` (as long as `rays`): [`Self::intersect_packet_lanes`], one hit per ray.
    pub fn intersect_packet(&self, rays: &[Ray], t_max: f32, hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "a hit per ray");
        let found = self.intersect_packet_lanes(rays, t_max);
        for (r, hit) in hits.iter_mut().enumerate() {
            *hit = found.get(r);
        }
    }

    /// [`Self::intersect`] (unobserved) of up to [`PACKET`] rays with one `t_max`, lane
    /// `r` holding `rays[r]`'s hit. The flattened triangles take the rays as one packet
    /// (`WideBvh::closest_packet_within`, its hits kept in lanes); instances and
    /// spheres, each ray after it.
    pub fn intersect_packet_lanes(&self, rays: &[Ray], t_max: f32) -> PacketSceneHits {
        let mut hits = PacketSceneHits::default();
        self.intersect_packet_lanes_into(rays, t_max, &mut hits);
        hits
    }

    /// [`Self::intersect_packet_lanes`] into `hits` (whatever it held before): the
    /// packet query's lanes land in place, where a returned value cost a zero fill and
    /// two copies of the hits per packet (720 bytes; `memmove` was 1% of the Cornell
    /// render).
    pub fn intersect_packet_lanes_into(
        &self,
        rays: &[Ray],
        t_max: f32,
        hits: &mut PacketSceneHits,
    ) {
        hits.others.clear();
        if !self.use_wide::<()>() {
            hits.flat = HitLanes::default();
            for (r, ray) in rays.iter().enumerate() {
                hits.set(r, self.intersect(ray, t_max, &mut ()));
            }
            return;
        }
        self.tri_wide
            .closest_packet_within_into(rays, t_max, &mut hits.flat);
        if !self.instanced.is_empty() || !self.sphere_bvh.nodes.is_empty() {
            for (r, ray) in rays.iter().enumerate() {
                let flat = hits.flat.found & (1 << r) != 0;
                let t = if flat { hits.flat.t[r] } else { t_max };
                // A closer hit beyond the flattened triangles replaces the lane's.
                if let Some(h) = self.closest_beyond_triangles(ray, t, &mut ()) {
                    hits.flat.found &= !(1 << r);
                    hits.others.push((r as u32, h));
                }
            }
        }
    }
}
