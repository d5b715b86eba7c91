//! Up to [`PACKET`] rays side by side (SoA), one lane per ray, with a mask of the lanes
//! holding one: the form the packet queries read, which a producer that has its rays
//! in lanes already (the render's shading) fills with whole-lane writes.

use glam::Vec3;

use super::{PACKET, Ray};

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
        let mut holes = RayLanes::default();
        holes.set(6, &rays[2]);
        holes.set(1, &rays[4]);
        assert_eq!(holes.lanes().collect::<Vec<_>>(), [1, 6]);
        assert_eq!(holes.ray(6), rays[2]);
    }
}
