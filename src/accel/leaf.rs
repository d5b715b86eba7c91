//! The wide BVH's leaf triangles, structure-of-arrays in groups of [`LANES`]: each
//! leaf fills whole groups (the last one padded with NaN lanes, masked by the leaf's
//! count), so that one pass of plain lane loops, which the compiler vectorises,
//! tests all of a leaf's triangles at once.
//!
//! That pass is a conservative prefilter: it runs the early-outs of
//! [`intersect_triangle_sheared`] (shear, edge functions, sign test, det, det-scaled t
//! bound) with the same f32 operations in the same order, so it rejects exactly the
//! lanes the scalar test rejects before its division; lanes it cannot decide (a zero
//! edge function, where the scalar test falls back to f64) pass. Every lane that passes
//! is confirmed by the scalar test on that lane's vertices, so a leaf's answer is the
//! scalar test's, bit for bit, by construction.

use glam::Vec3;

use super::Ray;
use super::triangle::RayShear;
use super::wide::WideNode;

/// Triangles per group. Four beat eight on the 100k torus: the binned-SAH leaves
/// hold 3.3 triangles on average (at most 4 there), so eight lanes would mostly pad.
pub const LANES: usize = 4;

/// Lane mask of a full group.
const ALL_LANES: u32 = (1 << LANES) - 1;

/// Up to `LANES` triangles, structure-of-arrays.
#[derive(Clone, Copy, Debug)]
pub struct TriGroup {
    /// Vertex coordinates: `v[vertex][axis][lane]`; NaN in padding lanes.
    pub v: [[[f32; LANES]; 3]; 3],
}

impl TriGroup {
    const PADDING: TriGroup = TriGroup {
        v: [[[f32::NAN; LANES]; 3]; 3],
    };

    /// The vertices of the triangle in `lane`.
    #[inline(always)]
    pub fn triangle(&self, lane: usize) -> [Vec3; 3] {
        let v = &self.v;
        [0, 1, 2].map(|k| Vec3::new(v[k][0][lane], v[k][1][lane], v[k][2][lane]))
    }

    fn set_triangle(&mut self, lane: usize, tri: [Vec3; 3]) {
        for (k, p) in tri.iter().enumerate() {
            for axis in 0..3 {
                self.v[k][axis][lane] = p[axis];
            }
        }
    }

    /// True when every coordinate of `lane` is NaN (a padding lane).
    fn is_padding(&self, lane: usize) -> bool {
        self.v.iter().flatten().all(|axis| axis[lane].is_nan())
    }
}

/// All leaves' triangle groups; a leaf of the wide BVH names its first group and
/// its triangle count (see [`leaf_lane`]).
#[derive(Clone, Debug, Default)]
pub struct LeafTris {
    /// The groups, leaf after leaf in the order of their triangle slots.
    pub groups: Vec<TriGroup>,
    /// Slot (index into `WideBvh::prims`) of each group's lane 0.
    pub first: Vec<u32>,
}

/// Groups a leaf of `count` triangles fills.
#[inline(always)]
pub fn groups_for(count: usize) -> usize {
    count.div_ceil(LANES)
}

/// The `(child, count)` of a wide node's leaf lane: its first group and its triangle count.
pub fn leaf_lane(first_group: usize, count: u32) -> (u32, u32) {
    (first_group as u32, count)
}

/// Mask of the lanes holding triangles in group `i` of a leaf of `count` triangles.
#[inline(always)]
pub fn lane_mask(i: usize, count: usize) -> u32 {
    let left = count - i * LANES;
    if left >= LANES {
        ALL_LANES
    } else {
        (1 << left) - 1
    }
}

impl LeafTris {
    /// Groups the leaves of `nodes`, whose leaf lanes hold `(first slot, count)` into
    /// `prims`, and points those lanes at their groups instead.
    pub fn build(nodes: &mut [WideNode], prims: &[u32], positions: &[[Vec3; 3]]) -> LeafTris {
        let mut leaves: Vec<(usize, usize)> = Vec::new();
        for (i, node) in nodes.iter().enumerate() {
            for lane in 0..node.count.len() {
                if node.count[lane] > 0 {
                    leaves.push((i, lane));
                }
            }
        }
        // Groups in slot order, as the triangles were: neighbouring leaves stay close.
        leaves.sort_unstable_by_key(|&(i, lane)| nodes[i].child[lane]);
        let groups: usize = leaves
            .iter()
            .map(|&(i, lane)| groups_for(nodes[i].count[lane] as usize))
            .sum();
        let mut out = LeafTris {
            groups: Vec::with_capacity(groups),
            first: Vec::with_capacity(groups),
        };
        for (i, lane) in leaves {
            let (slot, count) = (nodes[i].child[lane] as usize, nodes[i].count[lane]);
            (nodes[i].child[lane], nodes[i].count[lane]) = leaf_lane(out.groups.len(), count);
            for start in (slot..slot + count as usize).step_by(LANES) {
                let mut group = TriGroup::PADDING;
                for k in start..(start + LANES).min(slot + count as usize) {
                    group.set_triangle(k - start, positions[prims[k] as usize]);
                }
                out.groups.push(group);
                out.first.push(start as u32);
            }
        }
        out
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        size_of_val(self.groups.as_slice()) + size_of_val(self.first.as_slice())
    }

    /// Checks the leaf of `count` triangles at group `first_group` against `positions`
    /// and `prims`: its groups exist and were not used by another leaf, lane `j` of
    /// group `i` holds slot `first + i * LANES + j`, padding lanes are NaN. Marks the
    /// groups used and calls `slot(k, triangle)` for each triangle slot `k`.
    pub fn validate_leaf(
        &self,
        first_group: usize,
        count: usize,
        used: &mut [bool],
        mut slot: impl FnMut(usize, [Vec3; 3]) -> Result<(), String>,
    ) -> Result<(), String> {
        let groups = first_group..first_group + groups_for(count);
        if groups.end > self.groups.len() || self.first.len() != self.groups.len() {
            return Err(format!("leaf at group {first_group}: past the end"));
        }
        let first = self.first[first_group] as usize;
        for (i, g) in groups.enumerate() {
            if std::mem::replace(&mut used[g], true) {
                return Err(format!("group {g} in two leaves"));
            }
            if self.first[g] as usize != first + i * LANES {
                return Err(format!(
                    "group {g}: first slot {} breaks its leaf",
                    self.first[g]
                ));
            }
            let mask = lane_mask(i, count);
            for lane in 0..LANES {
                if mask & (1 << lane) == 0 {
                    if !self.groups[g].is_padding(lane) {
                        return Err(format!("group {g} lane {lane}: padding is not NaN"));
                    }
                    continue;
                }
                slot(first + i * LANES + lane, self.groups[g].triangle(lane))?;
            }
        }
        Ok(())
    }
}

/// The per-ray constants of the prefilter: the shear of [`RayShear`] and the ray
/// origin's coordinates in the sheared axis order.
pub struct RayLeaf {
    axes: [usize; 3],
    origin: [f32; 3],
    sx: f32,
    sy: f32,
    sz: f32,
}

impl RayLeaf {
    /// The prefilter's constants for `ray` sheared by `s` (`RayShear::new(ray)`).
    #[inline(always)]
    pub fn new(ray: &Ray, s: &RayShear) -> RayLeaf {
        let o = ray.origin;
        RayLeaf {
            axes: [s.kx, s.ky, s.kz],
            origin: [o[s.kx], o[s.ky], o[s.kz]],
            sx: s.sx,
            sy: s.sy,
            sz: s.sz,
        }
    }

    /// Lanes of `g` the scalar test with bound `t_max` may accept: bit `lane` is clear
    /// only when [`intersect_triangle_sheared`] rejects that lane before its division.
    /// The same operations in the same order: `(p - origin)[k]` is `p[k] - origin[k]`;
    /// Rust never fuses a product and a sum. No branches, so the loop vectorises.
    #[inline(always)]
    pub fn candidates(&self, g: &TriGroup, t_max: f32) -> u32 {
        let [kx, ky, kz] = self.axes;
        let [ox, oy, oz] = self.origin;
        let (sx, sy, sz) = (self.sx, self.sy, self.sz);
        let (a, b, c) = (&g.v[0], &g.v[1], &g.v[2]);
        let mut bits = [0u32; LANES];
        for (lane, bit) in bits.iter_mut().enumerate() {
            let (a_x, a_y, a_z) = (a[kx][lane] - ox, a[ky][lane] - oy, a[kz][lane] - oz);
            let (b_x, b_y, b_z) = (b[kx][lane] - ox, b[ky][lane] - oy, b[kz][lane] - oz);
            let (c_x, c_y, c_z) = (c[kx][lane] - ox, c[ky][lane] - oy, c[kz][lane] - oz);
            let ax = a_x - sx * a_z;
            let ay = a_y - sy * a_z;
            let bx = b_x - sx * b_z;
            let by = b_y - sy * b_z;
            let cx = c_x - sx * c_z;
            let cy = c_y - sy * c_z;
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
            let mixed = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
            let det = u + v + w;
            let t_scaled = u * (sz * a_z) + v * (sz * b_z) + w * (sz * c_z);
            let bound = t_max * det;
            let outside = if det < 0.0 {
                (t_scaled >= 0.0) | (t_scaled <= bound)
            } else {
                (t_scaled <= 0.0) | (t_scaled >= bound)
            };
            let keep = zero | !(mixed | (det == 0.0) | outside);
            *bit = (keep as u32) << lane;
        }
        bits.iter().fold(0, |mask, &bit| mask | bit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::triangle::{TriangleHit, intersect_triangle_sheared};
    use crate::test_util::Lcg;
    use glam::vec3;

    /// Each lane's hit as the wide BVH's leaves compute it: prefilter, then the
    /// scalar test on the lanes that pass. Also returns the prefilter's mask.
    fn leaf_hits(ray: &Ray, g: &TriGroup, t_max: f32) -> ([Option<TriangleHit>; LANES], u32) {
        let s = RayShear::new(ray);
        let mask = RayLeaf::new(ray, &s).candidates(g, t_max);
        let hits = std::array::from_fn(|lane| {
            let [a, b, c] = g.triangle(lane);
            (mask & (1 << lane) != 0)
                .then(|| intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max))
                .flatten()
        });
        (hits, mask)
    }

    /// Every lane of every group agrees with the scalar test bit for bit; returns the
    /// lanes the scalar test missed and how many of those the prefilter rejected.
    fn check(rays: &[(Ray, f32)], tris: &[[Vec3; 3]]) -> (usize, usize) {
        let (mut misses, mut rejected) = (0, 0);
        for chunk in tris.chunks(LANES) {
            let mut g = TriGroup::PADDING;
            for (lane, &tri) in chunk.iter().enumerate() {
                g.set_triangle(lane, tri);
            }
            for &(ray, t_max) in rays {
                let (hits, mask) = leaf_hits(&ray, &g, t_max);
                let s = RayShear::new(&ray);
                for (lane, &[a, b, c]) in chunk.iter().enumerate() {
                    let expect = intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max);
                    let bits = |h: Option<TriangleHit>| {
                        h.map(|h| [h.t, h.b0, h.b1, h.b2].map(f32::to_bits))
                    };
                    assert_eq!(
                        bits(hits[lane]),
                        bits(expect),
                        "{ray:?} {t_max} {:?}",
                        [a, b, c]
                    );
                    if expect.is_none() {
                        misses += 1;
                        rejected += (mask & (1 << lane) == 0) as usize;
                    }
                }
            }
        }
        (misses, rejected)
    }

    #[test]
    fn prefilter_and_confirm_match_the_scalar_test_on_random_rays() {
        let mut rng = Lcg(77);
        let tris: Vec<[Vec3; 3]> = (0..64)
            .map(|_| {
                let c = rng.vec() * 4.0 - Vec3::splat(2.0);
                [c, c + rng.dir(), c + rng.dir()]
            })
            .collect();
        let rays: Vec<(Ray, f32)> = (0..400)
            .map(|i| {
                let mut d = rng.dir() * (0.5 + rng.next_f32());
                // Zero direction components, one or two of them.
                if i % 7 == 0 {
                    d[i % 3] = 0.0;
                }
                if i % 21 == 0 {
                    d[(i + 1) % 3] = 0.0;
                }
                let t_max = [f32::INFINITY, 2.0, 0.5][i % 3];
                (Ray::new(rng.vec() * 6.0 - Vec3::splat(3.0), d), t_max)
            })
            .collect();
        let (misses, rejected) = check(&rays, &tris);
        // Not a pass-everything filter: nearly all misses end in the vector pass.
        assert!(
            rejected * 10 > misses * 9,
            "{rejected} of {misses} misses rejected"
        );
    }

    #[test]
    fn edges_vertices_degenerate_and_nan_triangles_match_the_scalar_test() {
        let p = |x: f32, z: f32| vec3(x, 0.0, z);
        let tris = [
            // Two triangles of a unit quad (a shared diagonal) and a neighbour.
            [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)],
            [p(1.0, 0.0), p(2.0, 0.0), p(1.0, 1.0)],
            // Zero area: collinear, and one point.
            [p(0.0, 0.0), p(0.5, 0.5), p(1.0, 1.0)],
            [p(0.5, 0.5); 3],
            // NaN and infinite coordinates.
            [p(f32::NAN, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(f32::INFINITY, 0.0), p(1.0, 1.0)],
            // Thin, far from the origin.
            [p(1e4, 1e4), p(1e4 + 1e-3, 1e4), p(1e4, 1e4 + 1e-3)],
        ];
        let mut rays = Vec::new();
        // Through vertices, edge midpoints and the diagonal, straight down and slanted.
        let targets = [0.0, 0.5, 1.0, 2.0]
            .iter()
            .flat_map(|&x| [0.0, 0.5, 1.0].iter().map(move |&z| p(x, z)));
        for target in targets.chain([p(0.25, 0.25), p(0.75, 0.75), p(1e4, 1e4)]) {
            for dir in [
                vec3(0.0, -1.0, 0.0),
                vec3(0.3, -1.0, 0.2),
                vec3(-0.1, -0.7, 0.4),
            ] {
                let origin = target - 2.0 * dir;
                rays.push((Ray::new(origin, dir), f32::INFINITY));
                // Bounds at, just below and just past the exact hit distance.
                for t in [2.0f32, 2.0f32.next_down(), 2.0f32.next_up()] {
                    rays.push((Ray::new(origin, dir), t));
                }
            }
            // In the triangles' plane, and a zero direction.
            rays.push((Ray::new(target - Vec3::X, Vec3::X), f32::INFINITY));
            rays.push((
                Ray::new(target - vec3(1.0, 0.0, 1.0), vec3(1.0, 0.0, 1.0)),
                5.0,
            ));
            rays.push((Ray::new(target + Vec3::Y, Vec3::ZERO), f32::INFINITY));
        }
        check(&rays, &tris);
        // And at each hit's own t: the bound is exclusive in both tests.
        let mut at_hit = Vec::new();
        for &(ray, _) in &rays {
            for &[a, b, c] in &tris {
                if let Some(h) = intersect_triangle_sheared(
                    &RayShear::new(&ray),
                    ray.origin,
                    a,
                    b,
                    c,
                    f32::INFINITY,
                ) {
                    at_hit.extend([h.t, h.t.next_up(), h.t.next_down()].map(|t| (ray, t)));
                }
            }
        }
        assert!(!at_hit.is_empty());
        check(&at_hit, &tris);
    }

    #[test]
    fn lanes_with_a_zero_edge_function_pass_the_prefilter() {
        // Rays straight down through points on the lines of the triangle's edges beyond
        // its vertices: one edge function is exactly zero, the others of opposite signs.
        // The scalar test recomputes those in f64, so the prefilter must not decide them.
        let p = |x: f32, z: f32| vec3(x, 0.0, z);
        let mut g = TriGroup::PADDING;
        g.set_triangle(0, [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]);
        for target in [
            p(2.0, 0.0),
            p(-1.0, 0.0),
            p(1.0, 2.0),
            p(1.0, -1.0),
            p(2.0, 2.0),
        ] {
            let ray = Ray::new(target + Vec3::Y, -Vec3::Y);
            assert_eq!(leaf_hits(&ray, &g, f32::INFINITY).1 & 1, 1, "{target}");
        }
    }

    #[test]
    fn lane_masks_cover_a_leaf_exactly() {
        for count in 1..=8 {
            let lanes: u32 = (0..groups_for(count))
                .map(|i| lane_mask(i, count).count_ones())
                .sum();
            assert_eq!(lanes as usize, count);
        }
        assert_eq!(lane_mask(1, 5), 1);
    }
}
