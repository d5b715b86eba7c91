//! Axis-aligned bounding boxes and the robust ray/box slab test of
//! Thiago Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013.

use glam::Vec3;

use super::gamma;

/// An axis-aligned box; `EMPTY` (min = +inf, max = -inf) is the identity of `union`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The empty box: growing it by a point gives that point's box.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Creates a box from its corners.
    pub fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// The smallest box containing all `points` (`EMPTY` for none).
    pub fn from_points(points: &[Vec3]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in points {
            b.grow(p);
        }
        b
    }

    /// Enlarges the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both boxes.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The centre point.
    pub fn centroid(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths `max - min`.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Surface area; 0 for the empty box.
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// True when the box contains no point (some `min > max`).
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// True when `o` lies inside this box (the empty box lies inside every box).
    pub fn contains_box(&self, o: &Aabb) -> bool {
        o.is_empty() || (self.min.cmple(o.min).all() && o.max.cmple(self.max).all())
    }

    /// Slab test: the entry t (≥ 0) if the ray meets the box within `[0, t_max]`.
    ///
    /// `inv_dir` is `1 / dir` per component; zero components give ±inf. Where
    /// the origin lies exactly on a slab plane, `0 * inf` is NaN: the near and
    /// far planes are chosen by the sign of `inv_dir`, and `f32::min`/`f32::max`
    /// return the non-NaN argument, so such a bound is ignored (the ray counts
    /// as inside that slab) instead of turning the test into a miss. The exit
    /// distance is enlarged by `1 + 2 gamma(3)` (Ize 2013) so that rounding never
    /// culls a box the exact ray touches.
    #[inline(always)]
    pub fn intersect_ray(&self, origin: Vec3, inv_dir: Vec3, t_max: f32) -> Option<f32> {
        let (near_x, far_x) = slab(self.min.x, self.max.x, origin.x, inv_dir.x);
        let (near_y, far_y) = slab(self.min.y, self.max.y, origin.y, inv_dir.y);
        let (near_z, far_z) = slab(self.min.z, self.max.z, origin.z, inv_dir.z);
        // f32::max/min return the non-NaN argument, so a NaN slab bound
        // leaves the running interval unchanged.
        let t_near = 0.0f32.max(near_x).max(near_y).max(near_z);
        let t_far = t_max.min(far_x).min(far_y).min(far_z);
        let t_far = t_far * (1.0 + 2.0 * gamma(3));
        if t_near <= t_far { Some(t_near) } else { None }
    }
}

/// Entry and exit distances of one slab, choosing the near plane by the sign
/// of the inverse direction (not by `min(t0, t1)`, which would turn a
/// `0 * inf = NaN` bound into the other bound, ±inf, and wrongly miss).
#[inline(always)]
fn slab(min: f32, max: f32, origin: f32, inv_dir: f32) -> (f32, f32) {
    let (near, far) = if inv_dir.is_sign_negative() {
        (max, min)
    } else {
        (min, max)
    };
    ((near - origin) * inv_dir, (far - origin) * inv_dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn empty_box_properties() {
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert_eq!(Aabb::from_points(&[]), Aabb::EMPTY);
        assert_eq!(Aabb::EMPTY.union(unit()), unit());
        assert!(unit().contains_box(&Aabb::EMPTY));
        assert!(!Aabb::EMPTY.contains_box(&unit()));
    }

    #[test]
    fn grow_union_measures() {
        let b = Aabb::from_points(&[vec3(1.0, 2.0, 3.0), vec3(-1.0, 0.0, 5.0)]);
        assert_eq!(b.min, vec3(-1.0, 0.0, 3.0));
        assert_eq!(b.max, vec3(1.0, 2.0, 5.0));
        assert_eq!(b.centroid(), vec3(0.0, 1.0, 4.0));
        assert_eq!(b.extent(), vec3(2.0, 2.0, 2.0));
        assert_eq!(b.surface_area(), 24.0);
        let u = unit().union(Aabb::new(Vec3::splat(2.0), Vec3::splat(3.0)));
        assert_eq!(u, Aabb::new(Vec3::ZERO, Vec3::splat(3.0)));
        assert!(u.contains_box(&unit()));
        assert!(!unit().contains_box(&u));
        // A point box is not empty and has zero area.
        let p = Aabb::from_points(&[Vec3::ONE]);
        assert!(!p.is_empty());
        assert_eq!(p.surface_area(), 0.0);
    }

    #[test]
    fn slab_basic_hit_and_miss() {
        let b = unit();
        let o = vec3(-1.0, 0.5, 0.5);
        let d = vec3(1.0, 0.0, 0.0);
        assert_eq!(b.intersect_ray(o, d.recip(), f32::INFINITY), Some(1.0));
        // t_max before the box.
        assert_eq!(b.intersect_ray(o, d.recip(), 0.5), None);
        // Pointing away.
        assert_eq!(b.intersect_ray(o, (-d).recip(), f32::INFINITY), None);
        // Origin inside: entry clamps to 0.
        assert_eq!(
            b.intersect_ray(Vec3::splat(0.5), d.recip(), f32::INFINITY),
            Some(0.0)
        );
    }

    #[test]
    fn slab_axis_aligned_rays_no_nan() {
        let b = unit();
        // Every axis direction, both signs, passing inside and outside the box,
        // including origins exactly on the slab planes (0 * inf = NaN cases).
        for axis in 0..3 {
            for sign in [1.0f32, -1.0] {
                let mut d = Vec3::ZERO;
                d[axis] = sign;
                let inv = d.recip();
                for &u in &[0.0f32, 0.5, 1.0, -0.5, 1.5] {
                    for &v in &[0.0f32, 0.5, 1.0, -0.5, 1.5] {
                        let mut o = Vec3::ZERO;
                        o[axis] = if sign > 0.0 { -2.0 } else { 3.0 };
                        o[(axis + 1) % 3] = u;
                        o[(axis + 2) % 3] = v;
                        let inside = (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v);
                        let r = b.intersect_ray(o, inv, f32::INFINITY);
                        match r {
                            Some(t) => {
                                assert!(inside, "false hit axis {axis} o {o}");
                                assert_eq!(t, 2.0);
                            }
                            None => assert!(!inside, "missed axis {axis} o {o}"),
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn slab_negative_zero_and_flat_boxes() {
        // -0.0 components give -inf inverses and still hit.
        let d = vec3(-0.0, -0.0, 1.0);
        let t = unit().intersect_ray(vec3(0.5, 0.5, -1.0), d.recip(), 10.0);
        assert_eq!(t, Some(1.0));
        // A flat box (a quad's box) with the ray lying in its plane is hit.
        let flat = Aabb::new(vec3(0.0, 0.0, 0.0), vec3(1.0, 1.0, 0.0));
        let r = flat.intersect_ray(vec3(-1.0, 0.5, 0.0), vec3(1.0, 0.0, 0.0).recip(), 5.0);
        assert_eq!(r, Some(1.0));
        // Straight through the flat box, perpendicular.
        let r = flat.intersect_ray(vec3(0.5, 0.5, 2.0), vec3(0.0, 0.0, -1.0).recip(), 5.0);
        assert_eq!(r, Some(2.0));
    }

    #[test]
    fn slab_is_conservative_at_grazing_corner() {
        // The ray o + t d with integer d enters the x slab exactly where it
        // leaves the y slab (both at t = 1). Rounded `a * (1/a)` and `b * (1/b)`
        // differ by an ulp either way; the Ize bound keeps every one a hit.
        let mut unprotected_misses = 0;
        for a in 1..200 {
            for b in 2..60 {
                let d = vec3(a as f32, b as f32, 1.0);
                let bx = Aabb::new(
                    vec3(a as f32, b as f32 - 1.0, 0.0),
                    vec3(a as f32 + 1.0, b as f32, 2.0),
                );
                let inv = d.recip();
                assert!(
                    bx.intersect_ray(Vec3::ZERO, inv, f32::INFINITY).is_some(),
                    "{a} {b}"
                );
                if a as f32 * inv.x > b as f32 * inv.y {
                    unprotected_misses += 1;
                }
            }
        }
        // Shows the test exercises the rounding case at all.
        assert!(unprotected_misses > 0);
    }
}
