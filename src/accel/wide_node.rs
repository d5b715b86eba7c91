//! The 8-wide BVH's node format: [`WideNode`] (child boxes structure-of-arrays,
//! so that one slab test covers all eight), the per-ray slab test over a node's
//! children (`RayBoxes`). `wide_collapse` makes them from the binary tree.

use glam::Vec3;
use wide::u32x8;

use super::{Aabb, BOX_MARGIN, Ray};

/// Children per node. Eight beat four on the 100k torus (callgrind: 9-10% fewer
/// instructions per ray; 4-6% less time) at 68 rather than 59 bytes per triangle.
pub const WIDTH: usize = 8;

/// `child` of an unused slot.
pub(super) const EMPTY: u32 = u32::MAX;

/// A node of up to `WIDTH` children; box planes are SoA: `bounds[axis][lane]` for the
/// minimum corner (axis 0..3) and `bounds[3 + axis][lane]` for the maximum.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Child boxes: min x, y, z then max x, y, z, one lane per child.
    pub bounds: [[f32; WIDTH]; 6],
    /// Interior child: its node index. Leaf child: its first group in `leaves`. Unused: `u32::MAX`.
    pub child: [u32; WIDTH],
    /// Triangles of a leaf child, with [`super::leaf::DEGENERATE`] set when one of them is
    /// degenerate (read it through [`super::leaf::leaf_count`]); 0 for an interior or unused child.
    pub count: [u32; WIDTH],
}

impl WideNode {
    pub(super) const UNUSED: WideNode = WideNode {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
        count: [0; WIDTH],
    };

    /// The box of child `lane`.
    pub fn child_bounds(&self, lane: usize) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: Vec3::new(b[0][lane], b[1][lane], b[2][lane]),
            max: Vec3::new(b[3][lane], b[4][lane], b[5][lane]),
        }
    }

    pub(super) fn set_child_bounds(&mut self, lane: usize, a: Aabb) {
        for axis in 0..3 {
            self.bounds[axis][lane] = a.min[axis];
            self.bounds[3 + axis][lane] = a.max[axis];
        }
    }
}

/// The per-ray constants of the wide slab test.
pub(super) struct RayBoxes {
    origin: [f32; 3],
    /// Minus the inverse direction: `(origin - plane) * -inv` is `(plane - origin) * inv`
    /// to the bit but for the sign of a zero (round to nearest is symmetric, as is the
    /// product's sign), and takes the plane as the subtraction's memory operand, where
    /// `plane - origin` loaded it into a register first: one instruction less per plane.
    neg_inv: [f32; 3],
    /// Row of `WideNode::bounds` holding each axis's near plane, then the far plane's.
    near: [usize; 3],
    far: [usize; 3],
}

impl RayBoxes {
    #[cfg(test)]
    pub(super) fn new(ray: &Ray) -> RayBoxes {
        RayBoxes::with_inverse(ray, ray.dir.recip().to_array())
    }

    /// The constants for `ray` with `inv` its `dir.recip()` (an array: it indexes without
    /// glam's per-component `match`, a chain of branches).
    #[inline(always)]
    pub(super) fn with_inverse(ray: &Ray, inv: [f32; 3]) -> RayBoxes {
        // The sign of `inv[a]` is that of `dir[a]` (of a zero too: 1 / -0 is -inf),
        // taken from the direction so that the rows the first box test loads do not
        // wait for the division. (A NaN component makes that axis's distances NaN,
        // which the box test ignores in either row.)
        let d = ray.dir.to_array();
        let neg = |a: usize| d[a].is_sign_negative() as usize;
        RayBoxes {
            origin: ray.origin.to_array(),
            neg_inv: inv.map(|i| -i),
            near: [3 * neg(0), 1 + 3 * neg(1), 2 + 3 * neg(2)],
            far: [3 - 3 * neg(0), 4 - 3 * neg(1), 5 - 3 * neg(2)],
        }
    }

    /// Entry distance of each child box (lanes the ray misses hold junk) and the
    /// mask of lanes whose box the ray meets in [0, t_max]: [`Aabb::intersect_ray`]
    /// lane by lane, in loops without branches so that they compile to SIMD, and the
    /// mask through `wide` (a movemask: LLVM turns a plain loop of shifted bits into a
    /// tangle of shuffles). The same lanes and, to the bit, the same entry distances, in
    /// fewer steps on the chain from a node's load to its children's (each float
    /// min or max takes four cycles):
    /// - the entry distance is the largest of +0 and the plane distances as signed
    ///   integers of their bits (one cycle each), which order non-negative floats as
    ///   floats and put negative ones, -0 and the NaN of `0 * inf` (negative on x86)
    ///   below +0: the largest of +0 and the plane distances above it, as
    ///   `intersect_ray` takes it (a NaN with its sign bit clear, which only a NaN in
    ///   the ray or a box makes, would be taken instead of ignored);
    /// - the box is met unless the entry distance lies past an exit plane's distance
    ///   or `t_max`, each times the margin: `t_near <= min(far..., t_max) * margin`
    ///   with NaN distances ignored, as the rounded product is monotonic (the
    ///   products and compares side by side, where the minimum took three steps).
    ///
    /// A plane distance of zero may come out as -0 where `intersect_ray` has +0 (see
    /// `neg_inv`): the entry distance takes both as +0, and a compare does not tell
    /// them apart.
    #[inline(always)]
    pub(super) fn test(&self, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        let b = &node.bounds;
        let (o, ninv) = (self.origin, self.neg_inv);
        let bits = |x: f32| x.to_bits() as i32;
        let t_max = t_max * BOX_MARGIN;
        let mut t_near = [0.0f32; WIDTH];
        let mut hit = [0u32; WIDTH];
        for lane in 0..WIDTH {
            let near_x = bits((o[0] - b[self.near[0]][lane]) * ninv[0]);
            let near_y = bits((o[1] - b[self.near[1]][lane]) * ninv[1]);
            let near_z = bits((o[2] - b[self.near[2]][lane]) * ninv[2]);
            let far_x = (o[0] - b[self.far[0]][lane]) * ninv[0] * BOX_MARGIN;
            let far_y = (o[1] - b[self.far[1]][lane]) * ninv[1] * BOX_MARGIN;
            let far_z = (o[2] - b[self.far[2]][lane]) * ninv[2] * BOX_MARGIN;
            // A pair first: two steps rather than three.
            let t = f32::from_bits(near_x.max(0).max(near_y.max(near_z)) as u32);
            t_near[lane] = t;
            // Ordered compares: false for NaN.
            let past = (t > far_x) | (t > far_y) | (t > far_z) | (t > t_max);
            // All bits set where the ray meets the box: the mask is one movmskps,
            // where wide's f32x8 compare (two f32x4 halves in the dispatched clones,
            // which lack the AVX cfg) split the register and joined it again.
            hit[lane] = (!past as u32).wrapping_neg();
        }
        (t_near, u32x8::from(hit).to_bitmask())
    }
}

/// The lanes of `node` holding leaves.
#[inline(always)]
pub(super) fn leaf_lanes(node: &WideNode) -> u32 {
    !u32x8::from(node.count).simd_eq(u32x8::ZERO).to_bitmask() & ((1 << WIDTH) - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Lcg;

    /// `RayBoxes::test` is `Aabb::intersect_ray` lane by lane: the same lanes met and
    /// the same entry distance, to the bit, on rays whose origins lie on box planes
    /// with zero (both signs) direction components, where the plane distances are 0,
    /// -0 or NaN, and on unused slots.
    #[test]
    fn ray_boxes_match_the_scalar_slab_test_bit_for_bit() {
        let mut rng = Lcg(17);
        let grid = |rng: &mut Lcg| (rng.next_f32() * 4.0).floor() - 2.0;
        let mut checked = 0;
        for i in 0..4000 {
            let mut node = WideNode::UNUSED;
            // Boxes with corners on a coarse grid, so that origins land on their planes.
            for lane in 0..WIDTH - (i % 3) {
                let a = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
                let b = a + Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng)).abs();
                node.set_child_bounds(lane, Aabb { min: a, max: b });
            }
            let origin = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng))
                + if i % 2 == 0 {
                    Vec3::ZERO
                } else {
                    rng.vec() * 0.5
                };
            let mut dir = rng.dir();
            for axis in 0..3 {
                match (i / 2 + axis) % 5 {
                    0 => dir[axis] = 0.0,
                    1 => dir[axis] = -0.0,
                    _ => {}
                }
            }
            let ray = Ray::new(origin, dir);
            let t_max = if i % 4 == 0 { 2.0 } else { f32::INFINITY };
            let (t, mask) = RayBoxes::new(&ray).test(&node, t_max);
            for (lane, &t) in t.iter().enumerate() {
                let want = node
                    .child_bounds(lane)
                    .intersect_ray(origin, dir.recip(), t_max);
                assert_eq!(
                    mask & (1 << lane) != 0,
                    want.is_some(),
                    "{i} {lane} {ray:?}"
                );
                if let Some(want) = want {
                    assert_eq!(t.to_bits(), want.to_bits(), "{i} {lane} {ray:?}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 1500, "only {checked} lanes met");
    }
}
