//! Up to [`PACKET`] rays side by side (SoA), one lane per ray, with a mask of the lanes
//! holding one: the form the packet queries read, which a producer that has its rays
//! in lanes already (the render's shading) fills with whole-lane writes; and their
//! closest hits side by side ([`HitLanes`]), as the closest-hit packet query keeps
//! them and the shading reads them.

use glam::Vec3;

use super::{PACKET, PacketHits, Ray, TriangleHit};

/// One f32 per lane.
pub type Lanes = [f32; PACKET];

/// Rays in lanes: lane `r` holds a ray when bit `r` of `active` is set; other lanes may
/// hold anything (they are never read as rays).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayLanes {
    /// Origins, world axes.
    pub origin: [Lanes; 3],
    /// Directions, world axes.
    pub dir: [Lanes; 3],
    /// The lanes holding a ray.
    pub active: u32,
}

impl RayLanes {
    /// `rays` (at most [`PACKET`]) in lanes `0..rays.len()`; the other lanes zero.
    #[inline(always)]
    pub fn from_rays(rays: &[Ray]) -> RayLanes {
        assert!(rays.len() <= PACKET, "a packet of {} rays", rays.len());
        // A full packet (the render's camera packets) as one transposition, which the
        // compiler vectorizes: ray by ray, it moved each float alone, 62 instructions a
        // packet more (Cornell direct: about 2 per ray).
        if let Ok(full) = <&[Ray; PACKET]>::try_from(rays) {
            let (o, d) = (
                full.map(|r| r.origin.to_array()),
                full.map(|r| r.dir.to_array()),
            );
            return RayLanes {
                origin: std::array::from_fn(|a| std::array::from_fn(|r| o[r][a])),
                dir: std::array::from_fn(|a| std::array::from_fn(|r| d[r][a])),
                active: (1 << PACKET) - 1,
            };
        }
        let mut lanes = RayLanes::default();
        for (r, ray) in rays.iter().enumerate() {
            lanes.set(r, ray);
        }
        lanes
    }

    /// Puts `ray` in lane `r` and marks the lane active.
    #[inline(always)]
    pub fn set(&mut self, r: usize, ray: &Ray) {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        for axis in 0..3 {
            self.origin[axis][r] = o[axis];
            self.dir[axis][r] = d[axis];
        }
        self.active |= 1 << r;
    }

    /// The ray in lane `r`.
    #[inline(always)]
    pub fn ray(&self, r: usize) -> Ray {
        let lane = |v: &[Lanes; 3]| Vec3::new(v[0][r], v[1][r], v[2][r]);
        Ray::new(lane(&self.origin), lane(&self.dir))
    }

    /// The active lanes, lowest first.
    pub fn lanes(&self) -> impl Iterator<Item = usize> + use<> {
        let mut left = self.active;
        std::iter::from_fn(move || {
            (left != 0).then(|| {
                let r = left.trailing_zeros() as usize;
                left &= left - 1;
                r
            })
        })
    }
}

/// Each lane's closest hit of a packet on triangles of a wide BVH: lane `r` holds one
/// when bit `r` of `found` is set; other lanes may hold anything (never read as hits).
/// Kept field by field (one lane written at a time, never copied whole mid-query): a
/// whole hit written in 4-byte pieces and read back in 8-byte ones stalled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HitLanes {
    /// Ray parameter of each hit (`TriangleHit::t`).
    pub t: Lanes,
    /// Barycentric weights of each hit's vertices (`TriangleHit::{b0, b1, b2}`).
    pub bary: [Lanes; 3],
    /// Index of each hit triangle, as the caller numbered it.
    pub prim: [u32; PACKET],
    /// Where each hit triangle sits in the leaves (`group * LANES + lane`), as
    /// `WideBvh::closest_hit_at` reports it.
    pub lane: [u32; PACKET],
    /// The lanes holding a hit.
    pub found: u32,
}

impl HitLanes {
    /// Puts hit `h` on triangle `prim` at leaf lane `lane` in lane `r` (one lane's
    /// stores, nothing read back) and marks the lane found.
    #[inline(always)]
    pub fn set(&mut self, r: usize, prim: u32, lane: u32, h: &TriangleHit) {
        self.t[r] = h.t;
        [self.bary[0][r], self.bary[1][r], self.bary[2][r]] = [h.b0, h.b1, h.b2];
        self.prim[r] = prim;
        self.lane[r] = lane;
        self.found |= 1 << r;
    }

    /// Lane `r`'s hit as `(prim, lane, hit)`, if it holds one.
    #[inline(always)]
    pub fn get(&self, r: usize) -> Option<(u32, u32, TriangleHit)> {
        (self.found & (1 << r) != 0).then(|| {
            let h = TriangleHit {
                t: self.t[r],
                b0: self.bary[0][r],
                b1: self.bary[1][r],
                b2: self.bary[2][r],
            };
            (self.prim[r], self.lane[r], h)
        })
    }

    /// Every lane's hit, one entry per lane.
    pub fn to_packet_hits(&self) -> PacketHits {
        std::array::from_fn(|r| self.get(r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_come_back_from_their_lanes() {
        let rays: Vec<Ray> = (0..5)
            .map(|i| {
                Ray::new(
                    Vec3::new(i as f32, 1.0, -2.0),
                    Vec3::new(0.5, i as f32, 3.0),
                )
            })
            .collect();
        let lanes = RayLanes::from_rays(&rays);
        assert_eq!(lanes.active, 0b1_1111);
        assert_eq!(lanes.lanes().collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
        let back: Vec<Ray> = lanes.lanes().map(|r| lanes.ray(r)).collect();
        assert_eq!(back, rays);
        // A full packet takes the one-transposition path.
        let full: Vec<Ray> = (0..PACKET)
            .map(|i| {
                Ray::new(
                    Vec3::new(i as f32, -1.0, 2.0),
                    Vec3::new(1.0, 0.5, i as f32),
                )
            })
            .collect();
        let lanes = RayLanes::from_rays(&full);
        assert_eq!(lanes.active, (1 << PACKET) - 1);
        let back: Vec<Ray> = lanes.lanes().map(|r| lanes.ray(r)).collect();
        assert_eq!(back, full);
        let mut holes = RayLanes::default();
        holes.set(6, &rays[2]);
        holes.set(1, &rays[4]);
        assert_eq!(holes.lanes().collect::<Vec<_>>(), [1, 6]);
        assert_eq!(holes.ray(6), rays[2]);
    }

    #[test]
    fn hits_come_back_from_their_lanes() {
        let h = |i: u32| TriangleHit {
            t: i as f32 + 0.5,
            b0: 0.25,
            b1: -0.0,
            b2: i as f32,
        };
        let mut lanes = HitLanes::default();
        lanes.set(6, 11, 40, &h(1));
        lanes.set(2, 7, 3, &h(2));
        // A lane set twice keeps its last hit.
        lanes.set(6, 12, 41, &h(3));
        assert_eq!(lanes.found, 0b100_0100);
        let mut want = [None; PACKET];
        want[2] = Some((7, 3, h(2)));
        want[6] = Some((12, 41, h(3)));
        assert_eq!(lanes.to_packet_hits(), want);
        assert_eq!(lanes.get(6).unwrap().2.b1.to_bits(), (-0.0f32).to_bits());
    }
}
