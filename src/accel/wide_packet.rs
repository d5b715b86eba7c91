//! Packets of up to [`PACKET`] rays through the wide BVH, one ray per SIMD lane: each
//! child box is tested against every ray of the packet at once (the box broadcast),
//! and each leaf triangle likewise (its vertices broadcast), where the single-ray
//! queries put eight boxes or four triangles in the lanes of one ray. What that buys
//! is eight lanes where a leaf group has four, and one traversal per packet.
//!
//! Every lane computes exactly what the single-ray query computes for its ray, so each
//! ray's answer is [`WideBvh::any_hit`]'s:
//! - The box test meets the boxes `RayBoxes::test` meets, at the same entry distances
//!   (through float minimums and maximums, where `RayBoxes::test` takes integer ones
//!   and side-by-side compares for a shorter chain); the near and far planes of each
//!   axis are picked per lane by the sign of the lane's inverse direction (a blend), so
//!   rays of every octant share a packet. A ray without NaN visits exactly the nodes
//!   and leaves its single-ray traversal visits (the order differs, which an any-hit
//!   answer does not depend on).
//! - The leaf prefilter is `RayLeaf::shear` + `candidates` lane by lane, with the
//!   triangle's coordinates in the ray's permuted axis order (`RayShear::{kx, ky,
//!   kz}`). That order is one per traversal: the packet is split at setup into
//!   sub-packets of rays with the same axes, each traversed on its own (coherent rays
//!   make one). The prefilter rejects only what the scalar test rejects before its
//!   division; the scalar test (`intersect_triangle_flagged`, with the leaf's
//!   degenerate flag) decides each (ray, triangle) it keeps, and a ray leaves the
//!   packet's active mask at its first hit.
//! - An entry left with a few rays hands each to the single-ray query below its node
//!   (`hand_over`), which finds the same answer (least (t, index) hit, or any hit).
//! - The any-hit query first culls the root's children by the box of the packet's ray
//!   segments (`segment_box`), which drops only children the box test rejects for
//!   every ray; a packet left with none ends there, before any per-ray setup.

use arrayvec::ArrayVec;
use glam::Vec3;
use wide::u32x8;

use super::bvh::MAX_DEPTH;
use super::leaf::{Decided, LANES, LaneValues, TriGroup, groups_for, leaf_count};
use super::ray_lanes::Lanes;
use super::segment_box::SegmentBox;
use super::triangle::{Axis, RayShear, TriangleHit, intersect_triangle_flagged};
use super::wide_node::{EMPTY, WIDTH, WideNode, leaf_lanes};
use super::wide_query::three_ulps_up;
use super::{BOX_MARGIN, HitLanes, RayLanes, WideBvh};

/// Rays per packet: one AVX2 register of f32.
pub const PACKET: usize = 8;

/// Traversal stack entries any tree needs (as the single-ray traversal's).
const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH as usize + 1;

/// The lanes of `node` holding a child.
#[inline(always)]
fn used_lanes(node: &WideNode) -> u32 {
    !u32x8::from(node.child)
        .simd_eq(u32x8::splat(EMPTY))
        .to_bitmask()
        & ((1 << WIDTH) - 1)
}

/// Bits of the first `n` rays of a packet.
#[inline(always)]
fn first_lanes(n: usize) -> u32 {
    (1u32 << n) - 1
}

/// The per-ray constants of a packet, one lane per ray; lanes without a ray hold junk
/// (never active).
pub(super) struct PacketRays {
    /// Origin, world axes.
    origin: [Lanes; 3],
    /// Direction, world axes (the scalar test's `RayShear::dir`).
    dir: [Lanes; 3],
    /// 1 / direction, world axes (the box test's).
    inv_dir: [Lanes; 3],
    /// Each ray's box cull distance (the single-ray traversal's `t_max`).
    cull: Lanes,
    /// Each ray's bound of the triangle test.
    bound: Lanes,
    /// Each ray's permuted axes as `axes_of` reads them: `2 * kz + (dir[kz] < 0)`.
    axes_key: [u32; PACKET],
    /// The lanes holding a ray.
    active: u32,
}

/// The permuted axes `[kx, ky, kz]` of a key of [`PacketRays::axes_key`], as
/// `RayShear::new` picks them.
#[inline(always)]
fn axes_of(key: u32) -> [usize; 3] {
    let kz = (key >> 1) as usize;
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if key & 1 != 0 {
        [ky, kx, kz]
    } else {
        [kx, ky, kz]
    }
}

/// The triangle test's constants of the rays of a packet with one permuted axis order
/// (a sub-packet), lane by lane: `RayShear`'s shear and the origin in that order
/// (`RayLeaf`'s). Lanes of rays with other axes hold junk (never active).
struct Shear {
    /// The permuted axes `[kx, ky, kz]`.
    axes: [usize; 3],
    /// `RayShear::{sx, sy, sz}`: the same f32 divisions, lane by lane.
    sx: Lanes,
    sy: Lanes,
    sz: Lanes,
    /// Origin in the permuted axis order.
    origin_k: [Lanes; 3],
}

impl PacketRays {
    /// The constants of the active rays of `rays` with bounds `t_max`, read lane by
    /// lane: no transposition (inactive lanes compute junk, never read).
    #[inline(always)]
    pub(super) fn from_lanes(rays: &RayLanes, t_max: &Lanes) -> PacketRays {
        let mut p = PacketRays {
            origin: rays.origin,
            dir: rays.dir,
            inv_dir: [[0.0; PACKET]; 3],
            cull: *t_max,
            bound: *t_max,
            axes_key: [0; PACKET],
            active: rays.active & first_lanes(PACKET),
        };
        // Lane by lane, in loops of their own for the compiler to vectorize (with the
        // choice of axes in the same loop, the divisions stayed scalar): the same f32
        // operations as `Vec3::recip` and `RayShear::new`'s choice of axes.
        for axis in 0..3 {
            for r in 0..PACKET {
                p.inv_dir[axis][r] = 1.0 / p.dir[axis][r];
            }
        }
        for r in 0..PACKET {
            let [x, y, z] = [p.dir[0][r], p.dir[1][r], p.dir[2][r]];
            let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
            // kz = 0 if x dominates, else 1 if y does, else 2; the swap bit is the sign
            // of dir[kz] (`RayShear::new`'s comparisons, as selects).
            let x_max = ax >= ay && ax >= az;
            let y_max = !x_max && ay >= az;
            let d_kz = if x_max {
                x
            } else if y_max {
                y
            } else {
                z
            };
            let kz = if x_max {
                0
            } else if y_max {
                2
            } else {
                4
            };
            p.axes_key[r] = kz + (d_kz < 0.0) as u32;
        }
        p
    }

    /// The rays whose permuted axes are ray `r`'s.
    #[inline(always)]
    fn same_axes(&self, r: usize) -> u32 {
        let k = self.axes_key[r];
        let mut class = 0;
        for (i, &key) in self.axes_key.iter().enumerate() {
            class |= ((key == k) as u32) << i;
        }
        class
    }

    /// The triangle test's constants for the rays with the permuted axes of ray `r`.
    #[inline(always)]
    fn shear(&self, r: usize) -> Shear {
        let axes = axes_of(self.axes_key[r]);
        let [kx, ky, kz] = axes;
        let mut s = Shear {
            axes,
            sx: [0.0; PACKET],
            sy: [0.0; PACKET],
            sz: [0.0; PACKET],
            origin_k: [self.origin[kx], self.origin[ky], self.origin[kz]],
        };
        let (dx, dy, dz) = (&self.dir[kx], &self.dir[ky], &self.dir[kz]);
        for r in 0..PACKET {
            (s.sx[r], s.sy[r], s.sz[r]) = (dx[r] / dz[r], dy[r] / dz[r], 1.0 / dz[r]);
        }
        s
    }

    /// Ray `r`'s `RayShear` (of sub-packet `s`) and origin, for the scalar test.
    #[inline(always)]
    fn scalar(&self, s: &Shear, r: usize) -> (RayShear, Vec3) {
        let [kx, ky, kz] = s.axes;
        let lane = |v: &[Lanes; 3]| Vec3::new(v[0][r], v[1][r], v[2][r]);
        let [kx, ky, kz] = [kx, ky, kz].map(Axis::of);
        let shear = RayShear {
            kx,
            ky,
            kz,
            sx: s.sx[r],
            sy: s.sy[r],
            sz: s.sz[r],
            dir: lane(&self.dir),
        };
        (shear, lane(&self.origin))
    }

    /// Each ray's entry distance into child `c` of `node` (junk where it misses) and
    /// the mask of rays that meet it in [0, cull]: what `RayBoxes::test` gives, lane by
    /// lane (the same lanes and entry distances by another route), the
    /// near plane of each axis the minimum unless the lane's inverse direction has its
    /// sign bit set (as `RayBoxes::new` picks it).
    #[inline(always)]
    fn test_box(&self, node: &WideNode, c: usize) -> (Lanes, u32) {
        let b = &node.bounds;
        let lo = [b[0][c], b[1][c], b[2][c]];
        let hi = [b[3][c], b[4][c], b[5][c]];
        let mut hit = [0u32; PACKET];
        let mut t_near = [0.0f32; PACKET];
        for r in 0..PACKET {
            let mut near = [0.0f32; 3];
            let mut far = [0.0f32; 3];
            for axis in 0..3 {
                let (o, inv) = (self.origin[axis][r], self.inv_dir[axis][r]);
                // A compare on the sign bit: one blend on the inverse itself.
                let neg = (inv.to_bits() as i32) < 0;
                let (n, f) = if neg {
                    (hi[axis], lo[axis])
                } else {
                    (lo[axis], hi[axis])
                };
                near[axis] = (n - o) * inv;
                far[axis] = (f - o) * inv;
            }
            t_near[r] = 0.0f32.max(near[0]).max(near[1]).max(near[2]);
            let far = f32::INFINITY.min(far[0]).min(far[1]).min(far[2]);
            let t_far = far.min(self.cull[r]) * BOX_MARGIN;
            hit[r] = ((t_near[r] <= t_far) as u32).wrapping_neg();
        }
        (t_near, u32x8::from(hit).to_bitmask())
    }

    /// The rays (of sub-packet `s`) that the scalar test may accept on lane `l` of `g`
    /// within their `bound`, with each ray's values of the scalar test (`Candidates`'s,
    /// rays in the lanes' place), so that most kept rays need not run it:
    /// `RayLeaf::shear` and `candidates` with the triangle in the lanes' place, the
    /// same f32 operations in the same order (bit clear only when the scalar test
    /// rejects the ray before its division).
    #[inline(always)]
    fn candidates(&self, s: &Shear, g: &TriGroup, l: usize) -> PacketCandidates {
        let [kx, ky, kz] = s.axes;
        let mut out = PacketCandidates {
            mask: 0,
            zero: 0,
            e: [[0.0; PACKET]; 3],
            det: [0.0; PACKET],
            t_scaled: [0.0; PACKET],
            sizes: [[0.0; PACKET]; 3],
        };
        let mut zeros = [0u32; PACKET];
        let v = &g.v;
        let p = |k: usize| [v[k][kx][l], v[k][ky][l], v[k][kz][l]];
        let (a, b, c) = (p(0), p(1), p(2));
        let mut bits = [0u32; PACKET];
        for (r, bit) in bits.iter_mut().enumerate() {
            let [ox, oy, oz] = [s.origin_k[0][r], s.origin_k[1][r], s.origin_k[2][r]];
            let (sx, sy, sz) = (s.sx[r], s.sy[r], s.sz[r]);
            let (a_x, a_y, a_z) = (a[0] - ox, a[1] - oy, a[2] - oz);
            let (b_x, b_y, b_z) = (b[0] - ox, b[1] - oy, b[2] - oz);
            let (c_x, c_y, c_z) = (c[0] - ox, c[1] - oy, c[2] - oz);
            let (ax, ay) = (a_x - sx * a_z, a_y - sy * a_z);
            let (bx, by) = (b_x - sx * b_z, b_y - sy * b_z);
            let (cx, cy) = (c_x - sx * c_z, c_y - sy * c_z);
            let z = [sz * a_z, sz * b_z, sz * c_z];
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            // From here `candidates` verbatim (see there for why each step is exact).
            let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
            let (ub, vb, wb) = (u.to_bits(), v.to_bits(), w.to_bits());
            let mixed = (((ub ^ vb) | (ub ^ wb)) as i32) < 0;
            let det = u + v + w;
            let t_scaled = u * z[0] + v * z[1] + w * z[2];
            let sign = det.to_bits() & 0x8000_0000;
            let signed_t = f32::from_bits(t_scaled.to_bits() ^ sign);
            let bound = f32::from_bits((self.bound[r] * det).to_bits() ^ sign);
            let inside = (signed_t > 0.0) & (signed_t < bound);
            let keep = zero | (!mixed & inside);
            *bit = (keep as u32).wrapping_neg();
            zeros[r] = (zero as u32).wrapping_neg();
            [out.e[0][r], out.e[1][r], out.e[2][r]] = [u, v, w];
            (out.det[r], out.t_scaled[r]) = (det, t_scaled);
            // `Sheared::sizes`: maxps itself, as there.
            let max = |m: f32, x: &f32| if m > x.abs() { m } else { x.abs() };
            let pz = [a_z, b_z, c_z].iter().fold(0.0, max);
            let xy = [ax, ay, bx, by, cx, cy].iter().fold(0.0, max);
            [out.sizes[0][r], out.sizes[1][r], out.sizes[2][r]] = [pz, xy, sz.abs() * pz];
        }
        out.mask = u32x8::from(bits).to_bitmask();
        out.zero = u32x8::from(zeros).to_bitmask();
        out
    }

    /// Tests rays `rays` (of sub-packet `s`) against the leaf at group `group` with the
    /// lane count `count`; returns the rays it occludes.
    #[inline(always)]
    fn occluded_in_leaf(
        &self,
        wide: &WideBvh,
        group: usize,
        count: u32,
        s: &Shear,
        rays: u32,
    ) -> u32 {
        let (count, degenerate) = leaf_count(count);
        let mut left = rays;
        for i in 0..groups_for(count) {
            let g = &wide.leaves.groups[group + i];
            // Only the lanes holding triangles: padding would pass no ray anyway.
            for l in 0..(count - i * LANES).min(LANES) {
                // The mask alone (the values' vector work is dropped): few rays are
                // kept, and the scalar test per kept ray costs less than the values
                // per triangle (Cornell direct: 872 -> 839 instructions per ray).
                let mut kept = self.candidates(s, g, l).mask & left;
                while kept != 0 {
                    let r = kept.trailing_zeros() as usize;
                    kept &= kept - 1;
                    let (shear, o) = self.scalar(s, r);
                    let tri = g.triangle(l);
                    if intersect_triangle_flagged(&shear, o, tri, self.bound[r], degenerate)
                        .is_some()
                    {
                        left &= !(1 << r);
                    }
                }
                if left == 0 {
                    return rays;
                }
            }
        }
        rays & !left
    }

    /// The rays whose entry distance `t_entry` lies within their cull distance, with
    /// the slab test's margin, compared as the single-ray traversal compares a leaf's
    /// (`LEAF`: t <= cull) or a popped entry's (not t > cull; they differ on NaN).
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn within<const LEAF: bool>(&self, t_entry: &Lanes) -> u32 {
        let mut bits = [0u32; PACKET];
        for r in 0..PACKET {
            let (t, cull) = (t_entry[r], self.cull[r] * BOX_MARGIN);
            let keep = if LEAF { t <= cull } else { !(t > cull) };
            bits[r] = (keep as u32).wrapping_neg();
        }
        u32x8::from(bits).to_bitmask()
    }

    /// Tests rays `rays` (of sub-packet `s`) against the leaf at group `group` with the
    /// lane count `count`, keeping in `best` each ray's least (t, index) hit as
    /// `ClosestLeaves` does (in its lane, field by field), and lowering its cull
    /// distance and bound with it.
    #[inline(always)]
    fn closest_in_leaf(
        &mut self,
        wide: &WideBvh,
        (group, count): (usize, u32),
        s: &Shear,
        rays: u32,
        best: &mut HitLanes,
        limit: &Lanes,
    ) {
        let (count, degenerate) = leaf_count(count);
        for i in 0..groups_for(count) {
            let g = &wide.leaves.groups[group + i];
            for l in 0..(count - i * LANES).min(LANES) {
                let candidates = self.candidates(s, g, l);
                let mut kept = candidates.mask & rays;
                // Several rays kept (coherent packets): the lanes' values decide them
                // all at once, and only those they cannot decide (a zero edge function,
                // a t too near 0) run the scalar test's path below, one by one.
                if (kept & !candidates.zero).count_ones() > 2 {
                    let p = wide.prim_at(group + i, l);
                    let slot = ((group + i) * LANES + l) as u32;
                    let tri = || g.triangle(l);
                    kept = self.decide_lanes(
                        &candidates,
                        kept,
                        (degenerate, tri),
                        p,
                        slot,
                        best,
                        limit,
                    );
                }
                while kept != 0 {
                    let r = kept.trailing_zeros() as usize;
                    kept &= kept - 1;
                    let (shear, o) = self.scalar(s, r);
                    let tri = g.triangle(l);
                    let Some(h) = candidates.hit(r, tri, degenerate, &shear, o, self.bound[r])
                    else {
                        continue;
                    };
                    let p = wide.prim_at(group + i, l);
                    let first = best.found & (1 << r) == 0;
                    if first || h.t < best.t[r] || (h.t == best.t[r] && p < best.prim[r]) {
                        self.cull[r] = h.t;
                        self.bound[r] = three_ulps_up(h.t).min(limit[r]);
                        best.set(r, p, ((group + i) * LANES + l) as u32, &h);
                    }
                }
            }
        }
    }
}

/// The packet prefilter's answer for one triangle: `leaf::Candidates` with rays in
/// the lanes' place.
type PacketCandidates = LaneValues<PACKET>;

impl PacketCandidates {
    /// The scalar test on ray `r` (in `mask`) and triangle `tri` with a bound `t_max`
    /// at most the prefilter's: [`LaneValues::decide`] with the ray in the lane's place.
    #[inline(always)]
    fn hit(
        &self,
        r: usize,
        tri: [Vec3; 3],
        may_be_degenerate: bool,
        shear: &RayShear,
        origin: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        match self.decide(r, t_max, may_be_degenerate, || tri) {
            Decided::Hit(h) => Some(h),
            Decided::Miss => None,
            Decided::Scalar => scalar_ray(shear, origin, tri, t_max, may_be_degenerate),
        }
    }
}

/// The scalar test for the few rays whose values do not decide it: out of line and
/// cold, as the closure `LaneValues::decide` once took was compiled (inlined, it cost
/// incoherent packets 6,447 -> 6,485 instructions per ray on the 100k torus).
#[cold]
#[inline(never)]
fn scalar_ray(
    shear: &RayShear,
    origin: Vec3,
    tri: [Vec3; 3],
    t_max: f32,
    may_be_degenerate: bool,
) -> Option<TriangleHit> {
    intersect_triangle_flagged(shear, origin, tri, t_max, may_be_degenerate)
}

/// Each ray's closest hit in a packet: the triangle's index, where it sits in the
/// leaves (`group * LANES + lane`) and the hit, as [`WideBvh::closest_hit_at`] gives it.
pub type PacketHits = [Option<(u32, u32, TriangleHit)>; PACKET];

/// The least of the entry distances `t` (never NaN: `test_box` starts them at 0 with
/// NaN-ignoring maxima) of the rays in `mask`, infinity if none: a blend and a tree of
/// minima across the lanes, where a loop over the rays ran a chain of eight branches
/// and NaN-checked minima per child.
#[inline(always)]
fn nearest_of(t: &Lanes, mask: u32) -> f32 {
    // One ray (incoherent packets, mostly): its own entry, no tree.
    if mask.is_power_of_two() {
        return t[mask.trailing_zeros() as usize % PACKET];
    }
    // `a < b` picks as `minps` does; both are exact, so the tree's order is free.
    let min = |a: f32, b: f32| if a < b { a } else { b };
    let mut m = [0.0f32; PACKET];
    for r in 0..PACKET {
        m[r] = if mask & (1 << r) != 0 {
            t[r]
        } else {
            f32::INFINITY
        };
    }
    let m4: [f32; 4] = std::array::from_fn(|i| min(m[i], m[i + 4]));
    min(min(m4[0], m4[2]), min(m4[1], m4[3]))
}

/// Sort key of child `c` entered at `t` (not NaN, not below zero): by t, then child.
#[inline(always)]
fn key(t: f32, c: usize) -> u64 {
    ((t.to_bits() as u64) << 32) | c as u64
}

impl WideBvh {
    /// [`Self::occluded_lanes`] compiled for whatever target features the caller has.
    #[inline(always)]
    pub(super) fn occluded_lanes_inlined(&self, rays: &RayLanes, t_max: &Lanes) -> u32 {
        if self.nodes.is_empty() || rays.active == 0 {
            return 0;
        }
        // The root's children that some ray may meet: none (most shadow packets of a
        // room split into walls and contents) ends the query before any setup.
        let root = match SegmentBox::of(rays, t_max) {
            Some(b) => b.children_met(&self.nodes[0]),
            None => (1 << WIDTH) - 1,
        };
        if root & used_lanes(&self.nodes[0]) == 0 {
            return 0;
        }
        let p = PacketRays::from_lanes(rays, t_max);
        let mut todo = p.active;
        let mut occluded = 0;
        while todo != 0 {
            let first = todo.trailing_zeros() as usize;
            let class = p.same_axes(first) & todo;
            occluded |= self.occluded_sub_packet(&p, &p.shear(first), class, root);
            todo &= !class;
        }
        occluded
    }

    /// The rays of `rays` (all of sub-packet `s`) that a triangle occludes: the any-hit
    /// traversal of [`WideBvh::traverse`] with a mask of rays per entry, leaves before
    /// interior children, until every ray is occluded or the stack is empty.
    /// Only the root's children in `root` are tested.
    #[inline(always)]
    fn occluded_sub_packet(&self, p: &PacketRays, s: &Shear, rays: u32, root: u32) -> u32 {
        let mut active = rays;
        let mut stack: ArrayVec<(u32, u32), STACK_SIZE> = ArrayVec::new();
        let hand_over = self.hand_over_rays();
        let mut next = Some((0u32, active));
        loop {
            let Some((index, mask)) = next.take().or_else(|| stack.pop()) else {
                return rays & !active;
            };
            // Rays occluded since this entry was pushed are done.
            let mask = mask & active;
            if mask == 0 {
                continue;
            }
            if mask.count_ones() <= hand_over {
                active &= !p.occluded_below(self, index, mask);
                if active == 0 {
                    return rays;
                }
                continue;
            }
            let node = &self.nodes[index as usize];
            let used = used_lanes(node) & if index == 0 { root } else { u32::MAX };
            let mut hits = [0u32; WIDTH];
            let mut lanes = used;
            while lanes != 0 {
                let c = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                hits[c] = p.test_box(node, c).1 & mask;
            }
            let leaves = leaf_lanes(node) & used;
            let mut lanes = leaves;
            while lanes != 0 {
                let c = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let m = hits[c] & active;
                if m != 0 {
                    let (child, count) = (node.child[c] as usize, node.count[c]);
                    active &= !p.occluded_in_leaf(self, child, count, s, m);
                    if active == 0 {
                        return rays;
                    }
                }
            }
            let mut lanes = used & !leaves;
            while lanes != 0 {
                let c = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let m = hits[c] & active;
                if m == 0 {
                    continue;
                }
                if let Some(prev) = next.replace((node.child[c], m)) {
                    stack.push(prev);
                }
            }
        }
    }
}

impl WideBvh {
    /// [`Self::closest_lanes`] compiled for whatever target features the caller has:
    /// the closest hit of each active lane of `rays` within its bound `t_max`.
    #[inline(always)]
    pub(super) fn closest_lanes_inlined(&self, rays: &RayLanes, t_max: &Lanes) -> HitLanes {
        let mut best = HitLanes::default();
        self.closest_lanes_into(rays, t_max, &mut best);
        best
    }

    /// [`Self::closest_lanes_inlined`] into `best` (cleared first): the hits land where
    /// the caller keeps them, with no copy of the lanes after the query.
    #[inline(always)]
    pub(super) fn closest_lanes_into(&self, rays: &RayLanes, t_max: &Lanes, best: &mut HitLanes) {
        *best = HitLanes::default();
        if self.nodes.is_empty() || rays.active == 0 {
            return;
        }
        let mut p = PacketRays::from_lanes(rays, t_max);
        let limit = p.cull;
        let mut todo = p.active;
        while todo != 0 {
            let first = todo.trailing_zeros() as usize;
            let (shear, class) = (p.shear(first), p.same_axes(first) & todo);
            self.closest_sub_packet(&mut p, &shear, class, &limit, best);
            todo &= !class;
        }
    }

    /// The closest hits of `rays` (all of sub-packet `s`) into `best`: the closest-hit
    /// traversal of [`WideBvh::traverse`] with a mask of rays and their entry distances
    /// per entry, children ordered by the least entry distance of the rays meeting them.
    /// Which hit wins does not depend on that order (see `ClosestLeaves`).
    #[inline(always)]
    fn closest_sub_packet(
        &self,
        p: &mut PacketRays,
        s: &Shear,
        rays: u32,
        limit: &Lanes,
        best: &mut HitLanes,
    ) {
        let mut stack: ArrayVec<(u32, u32, Lanes), STACK_SIZE> = ArrayVec::new();
        let hand_over = self.hand_over_rays();
        let mut next = Some((0u32, rays, [0.0f32; PACKET]));
        loop {
            let Some((index, mask, t_entry)) = next.take().or_else(|| stack.pop()) else {
                return;
            };
            // Rays whose closest hit so far lies before this box skip it.
            let mask = mask & p.within::<false>(&t_entry);
            if mask == 0 {
                continue;
            }
            if mask.count_ones() <= hand_over {
                p.closest_below(self, index, mask, limit, best);
                continue;
            }
            let node = &self.nodes[index as usize];
            let mut t_near = [[0.0f32; PACKET]; WIDTH];
            let mut hits = [0u32; WIDTH];
            // The children met, nearest first.
            let mut order: ArrayVec<u64, WIDTH> = ArrayVec::new();
            let mut lanes = used_lanes(node);
            while lanes != 0 {
                let c = lanes.trailing_zeros() as usize;
                lanes &= lanes - 1;
                let (t, h) = p.test_box(node, c);
                let h = h & mask;
                if h == 0 {
                    continue;
                }
                (t_near[c], hits[c]) = (t, h);
                let k = key(nearest_of(&t, h), c);
                let mut i = order.len();
                order.push(k);
                while i > 0 && order[i - 1] > k {
                    order[i] = order[i - 1];
                    i -= 1;
                }
                order[i] = k;
            }
            let leaves = leaf_lanes(node);
            // Interior children: the nearest next, the others pushed farthest first.
            for &k in order.iter().rev() {
                let c = k as u32 as usize;
                if leaves & (1 << c) == 0
                    && let Some(prev) = next.replace((node.child[c], hits[c], t_near[c]))
                {
                    stack.push(prev);
                }
            }
            for &k in &order {
                let c = k as u32 as usize;
                if leaves & (1 << c) == 0 {
                    continue;
                }
                let m = hits[c] & p.within::<true>(&t_near[c]);
                if m != 0 {
                    let leaf = (node.child[c] as usize, node.count[c]);
                    p.closest_in_leaf(self, leaf, s, m, best, limit);
                }
            }
        }
    }
}

#[path = "wide_packet_decide.rs"]
mod decide;

#[path = "wide_packet_hand_over.rs"]
mod hand_over;

#[cfg(test)]
#[path = "wide_packet_tests.rs"]
mod tests;
