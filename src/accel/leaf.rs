//! The wide BVH's leaf triangles, structure-of-arrays in groups of [`LANES`]: each
//! leaf fills whole groups (the last one padded with NaN lanes, which the prefilter
//! rejects), so that one pass of plain lane loops, which the compiler vectorises,
//! tests all of a leaf's triangles at once.
//!
//! That pass is a conservative prefilter: it runs the early-outs of
//! [`intersect_triangle_sheared`] (shear, edge functions, sign test, det, det-scaled t
//! bound) with the same f32 operations in the same order, so it rejects exactly the
//! lanes the scalar test rejects before its division; lanes it cannot decide (a zero
//! edge function, where the scalar test falls back to f64) pass. Every lane that passes
//! is confirmed by the scalar test on that lane's vertices, so a leaf's answer is the
//! scalar test's, bit for bit, by construction.
//!
//! [`intersect_triangle_sheared`]: super::intersect_triangle_sheared

use glam::Vec3;
use multiversion::target::match_target;
use multiversion::{inherit_target, multiversion};
use wide::u32x4;

use super::Ray;
use super::huge::HugeSlice;
use super::triangle::{Axis, RayShear, TriangleHit, intersect_triangle_flagged, is_degenerate};

/// Triangles per group. Four beat eight on the 100k torus: the binned-SAH leaves
/// hold 3.3 triangles on average (at most 4 there), so eight lanes would mostly pad.
pub const LANES: usize = 4;

/// Lanes of two groups tested in one pass (`RayLeaf::closest_pair`): one AVX register.
pub const PAIR: usize = 2 * LANES;

/// Lane mask of a full group.
const ALL_LANES: u32 = (1 << LANES) - 1;

/// Up to `LANES` triangles, structure-of-arrays, and the caller's index of each.
///
/// The indices sit in the group (as Embree's `Triangle4` keeps its `primID`s), not in an
/// array of their own: the closest-hit query read its hit's index from that array once
/// at the end, a cache miss on which perf put 7% of the traversal's samples, where here
/// it shares a cache line with the vertices' last row, which the leaf test has just
/// read. 160 bytes aligned to 32, so that the indices and that row are always in one
/// line (for no memory: the array held as many indices).
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(32))]
pub struct TriGroup {
    /// Vertex coordinates: `v[vertex][axis][lane]`; NaN in padding lanes.
    pub v: [[[f32; LANES]; 3]; 3],
    /// The caller's index of the triangle in each lane; [`NO_PRIM`] in padding lanes.
    pub prim: [u32; LANES],
}

impl TriGroup {
    pub(super) const PADDING: TriGroup = TriGroup {
        v: [[[f32::NAN; LANES]; 3]; 3],
        prim: [NO_PRIM; LANES],
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
    /// The groups, leaf after leaf in the order of their triangle slots, each with its
    /// lanes' triangle indices ([`TriGroup::prim`]): a hit's lane names its triangle
    /// with one load. Per lane rather than per triangle plus each group's first slot:
    /// smaller while groups average less than one padding lane (Sponza 64.5 -> 63.8
    /// bytes per triangle).
    pub groups: HugeSlice<TriGroup>,
}

/// [`TriGroup::prim`] of a padding lane: no triangle (a triangle count is below it).
pub const NO_PRIM: u32 = u32::MAX;

/// Groups a leaf of `count` triangles fills.
#[inline(always)]
pub fn groups_for(count: usize) -> usize {
    count.div_ceil(LANES)
}

/// Bit of a leaf lane's `count` ([`leaf_lane`]) set when one of the leaf's triangles is
/// degenerate (`is_degenerate`: exactly collinear vertices). Decided once, when the
/// leaf is grouped, so that a query repeats that exact f64 test only in such leaves,
/// not on every lane it may hit (no memory per triangle: counts are far below 2^31).
pub const DEGENERATE: u32 = 1 << 31;

/// The `(child, count)` of a wide node's leaf lane: its first group and its triangle
/// count, with [`DEGENERATE`] set when one of its triangles is.
pub fn leaf_lane(first_group: usize, count: u32, degenerate: bool) -> (u32, u32) {
    assert!(count < DEGENERATE, "a leaf of {count} triangles");
    let flag = if degenerate { DEGENERATE } else { 0 };
    (first_group as u32, count | flag)
}

/// A leaf lane's `count` ([`leaf_lane`]) read back: its triangle count, and whether one
/// of its triangles may be degenerate.
#[inline(always)]
pub fn leaf_count(count: u32) -> (usize, bool) {
    ((count & !DEGENERATE) as usize, count & DEGENERATE != 0)
}

/// Whether a leaf lane's `count` ([`leaf_lane`]) is a leaf of one group without
/// [`DEGENERATE`]: one compare, as the flag (the top bit) puts the count minus one past
/// `LANES`.
#[inline(always)]
pub fn one_plain_group(count: u32) -> bool {
    count.wrapping_sub(1) < LANES as u32
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

/// How many slots ahead of a leaf [`push_leaf`] prefetches the triangles of.
const PREFETCH_SLOTS: usize = 16;

/// Writes to `groups` (the [`LeafTris::groups`] being made), from group `first_group`
/// on, the [`groups_for`] `count` groups of the leaf of `count` triangles at slot `slot`
/// of `prims`; returns the wide node's `(child, count)` for it ([`leaf_lane`]). Leaves
/// written in slot order keep the groups in the triangles' order: neighbouring leaves
/// stay close. Into a slice made once, not pushed: a `HugeVec::push` per group took ~50
/// instructions of call and growth checks, a mapped one's ~90 (the slice of the whole
/// mapping cast again per write).
///
/// Leaves come in slot order, so each call asks the caches for the triangles
/// `PREFETCH_SLOTS` slots on, which a later call reads: `prims` is in the tree's order,
/// not the mesh's, and these reads missed (1M-triangle torus: the collapse from 45 to
/// 36.5 ms). A clone for SSE, where the prefetch is a safe call.
#[multiversion(targets("x86_64+sse4.2"))]
pub fn push_leaf(
    groups: &mut [TriGroup],
    first_group: usize,
    slot: u32,
    count: u32,
    prims: &[u32],
    positions: &[[Vec3; 3]],
) -> (u32, u32) {
    let (slot, end) = (slot as usize, (slot + count) as usize);
    /// Prefetches both cache lines `tri` may span into every level, in the clone with
    /// the instruction's target feature (nothing in the fallback). A hint: it reads
    /// nothing and faults on no address.
    #[inherit_target]
    #[inline]
    fn prefetch(tri: &[Vec3; 3]) {
        let start = (tri as *const [Vec3; 3]).cast::<i8>();
        for line in [start, start.wrapping_add(size_of::<[Vec3; 3]>() - 1)] {
            match_target! {
                "x86_64+sse4.2" => std::arch::x86_64::_mm_prefetch::<
                    { std::arch::x86_64::_MM_HINT_T0 },
                >(line),
                _ => {
                    let _ = line;
                }
            }
        }
    }
    let ahead = (slot + PREFETCH_SLOTS).min(prims.len())..(end + PREFETCH_SLOTS).min(prims.len());
    for &prim in &prims[ahead] {
        if let Some(tri) = positions.get(prim as usize) {
            prefetch(tri);
        }
    }
    let mut degenerate = false;
    let out = &mut groups[first_group..first_group + groups_for(count as usize)];
    for (out, start) in out.iter_mut().zip((slot..end).step_by(LANES)) {
        // Written in place: a group made in a local was kept in 40 registers and
        // spilled, then stored a lane at a time.
        *out = TriGroup::PADDING;
        for k in start..(start + LANES).min(end) {
            let tri @ [a, b, c] = positions[prims[k] as usize];
            degenerate |= is_degenerate(a, b, c);
            out.set_triangle(k - start, tri);
            out.prim[k - start] = prims[k];
        }
    }
    leaf_lane(first_group, count, degenerate)
}

impl LeafTris {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        size_of_val(self.groups.as_slice())
    }

    /// The caller's index of the triangle in lane `lane` (`group * LANES + lane`), or
    /// [`NO_PRIM`] for a padding lane.
    #[inline(always)]
    pub fn prim(&self, lane: usize) -> u32 {
        self.groups[lane / LANES].prim[lane % LANES]
    }

    /// Every lane's triangle index ([`LeafTris::prim`]), in lane order.
    pub fn prims(&self) -> impl Iterator<Item = u32> + '_ {
        self.groups.iter().flat_map(|g| g.prim)
    }

    /// Checks the leaf at group `first_group` with the lane count `count` ([`leaf_lane`]):
    /// its groups exist and were not used by another leaf, its first `count` lanes hold
    /// triangles and a triangle index, the others are padding (NaN, [`NO_PRIM`]),
    /// [`DEGENERATE`] is set exactly when one of its triangles is degenerate. Marks the
    /// groups used and calls `lane(prim, triangle)` for each of its triangles.
    pub fn validate_leaf(
        &self,
        first_group: usize,
        count: u32,
        used: &mut [bool],
        mut lane: impl FnMut(u32, [Vec3; 3]) -> Result<(), String>,
    ) -> Result<(), String> {
        let (count, flagged) = leaf_count(count);
        let mut degenerate = false;
        let groups = first_group..first_group + groups_for(count);
        if groups.end > self.groups.len() {
            return Err(format!("leaf at group {first_group}: past the end"));
        }
        for (i, g) in groups.enumerate() {
            if std::mem::replace(&mut used[g], true) {
                return Err(format!("group {g} in two leaves"));
            }
            let mask = lane_mask(i, count);
            for l in 0..LANES {
                let prim = self.groups[g].prim[l];
                if mask & (1 << l) == 0 {
                    if !self.groups[g].is_padding(l) || prim != NO_PRIM {
                        return Err(format!(
                            "group {g} lane {l}: padding is not NaN and NO_PRIM"
                        ));
                    }
                    continue;
                }
                if prim == NO_PRIM {
                    return Err(format!("group {g} lane {l}: a triangle without an index"));
                }
                let tri @ [a, b, c] = self.groups[g].triangle(l);
                degenerate |= is_degenerate(a, b, c);
                lane(prim, tri)?;
            }
        }
        if degenerate != flagged {
            return Err(format!(
                "leaf at group {first_group}: degenerate flag {flagged}, triangles {degenerate}"
            ));
        }
        Ok(())
    }
}

/// The per-ray constants of the prefilter: the shear of [`RayShear`] and the ray
/// origin's coordinates in the sheared axis order, each spread to the [`LANES`] lanes
/// once per ray, so that the leaf test reads them from here as vectors, where it
/// spread and spilled them to its stack at every call.
pub struct RayLeaf {
    /// `RayShear`'s kx, ky, kz, as `Axis` so that the leaf test indexes a group's
    /// rows without bounds checks.
    axes: [Axis; 3],
    origin: [[f32; PAIR]; 3],
    sx: [f32; PAIR],
    sy: [f32; PAIR],
    sz: [f32; PAIR],
    abs_sz: [f32; PAIR],
}

impl RayLeaf {
    /// The prefilter's constants for `ray` sheared by `s` (`RayShear::new(ray)`).
    #[inline(always)]
    pub fn new(ray: &Ray, s: &RayShear) -> RayLeaf {
        // The origin in place, indexed without a copy of it on the stack.
        let o: &[f32; 3] = ray.origin.as_ref();
        RayLeaf {
            axes: [s.kx, s.ky, s.kz],
            origin: [s.kx, s.ky, s.kz].map(|k| [o[k as usize]; PAIR]),
            sx: [s.sx; PAIR],
            sy: [s.sy; PAIR],
            sz: [s.sz; PAIR],
            abs_sz: [s.sz.abs(); PAIR],
        }
    }

    /// The prefilter of group `g` with bound `t_max`: the lanes the scalar test may
    /// accept (bit `lane` is clear only when the scalar test rejects that
    /// lane before its division) and the values that decide most of them without it;
    /// None when it rejects every lane (a third of the groups primary rays meet on the
    /// torus, two thirds for incoherent ones), whose values are then neither stored
    /// nor their sizes computed (torus 100k: 1,491 / 1,890 / 1,224 -> 1,464 / 1,821 /
    /// 1,168 instructions per primary / incoherent / shadow ray).
    /// The same operations in the same order: `(p - origin)[k]` is `p[k] - origin[k]`;
    /// Rust never fuses a product and a sum. No branches, so the loop vectorises.
    #[inline(always)]
    pub fn candidates(&self, g: &TriGroup, t_max: f32) -> Option<Candidates> {
        let [kx, ky, kz] = self.axes();
        let [a, b, c] = &g.v;
        let v = [
            [a[kx], a[ky], a[kz]],
            [b[kx], b[ky], b[kz]],
            [c[kx], c[ky], c[kz]],
        ];
        self.prefilter(&v, t_max)
    }

    /// The sheared axes of the ray (`RayShear`'s kx, ky, kz).
    #[inline(always)]
    pub(super) fn axes(&self) -> [usize; 3] {
        // One at a time: an `Axis` read alone keeps its range, where the three read
        // as one (`map`) were read as an integer of 3 bytes and bounds-checked again.
        let [kx, ky, kz] = &self.axes;
        [*kx as usize, *ky as usize, *kz as usize]
    }

    /// [`Self::candidates`] over `N` lanes (a multiple of [`LANES`]) of vertices `v`
    /// (`v[vertex][k]`, the coordinates in the sheared axis order): one group, or two
    /// sibling leaves' groups in one 8-lane pass.
    #[inline(always)]
    pub(super) fn prefilter<const N: usize>(
        &self,
        v: &[[[f32; N]; 3]; 3],
        t_max: f32,
    ) -> Option<LaneValues<N>> {
        // Local arrays, every lane written, gathered at the end: LLVM then drops their
        // zero initialisation, which it kept (six stores per group) in a struct
        // written field by field.
        let mut e = [[0.0; N]; 3];
        let mut dets = [0.0; N];
        let mut t_scaleds = [0.0; N];
        let mut sizes = [[0.0; N]; 3];
        // All bits set in a lane that passes, so that the masks are one movmskps each
        // (a lane's bit shifted into place became shuffles, ors and extracts; LANES is
        // 4, one u32x4).
        let mut bits = [0u32; N];
        let mut zeros = [0u32; N];
        for lane in 0..N {
            let sheared = self.shear(v, lane);
            let (xy, z) = (sheared.xy, sheared.z);
            let [ax, ay, bx, by, cx, cy] = xy;
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
            // Where no edge function is zero (the others pass anyway), the scalar test's
            // sign test is on their sign bits: mixed when two differ. A NaN one may land
            // either way: the scalar test rejects it (its t is NaN). Of one sign, their
            // sum det is not zero and has that sign too, so the scalar test's det == 0
            // never rejects what passes here.
            let (ub, vb, wb) = (u.to_bits(), v.to_bits(), w.to_bits());
            let mixed = (((ub ^ vb) | (ub ^ wb)) as i32) < 0;
            let det = u + v + w;
            let t_scaled = u * z[0] + v * z[1] + w * z[2];
            // The scaled t bound test with both sides times the sign of det (exact):
            // t_scaled >= 0 or <= t_max det for a negative det, <= 0 or >= t_max det
            // for a positive one.
            let sign = det.to_bits() & 0x8000_0000;
            let signed_t = f32::from_bits(t_scaled.to_bits() ^ sign);
            let bound = f32::from_bits((t_max * det).to_bits() ^ sign);
            // Inside, not "not outside": a NaN t_scaled, as in padding lanes, fails it.
            let inside = (signed_t > 0.0) & (signed_t < bound);
            let keep = zero | (!mixed & inside);
            bits[lane] = (keep as u32).wrapping_neg();
            zeros[lane] = (zero as u32).wrapping_neg();
            [e[0][lane], e[1][lane], e[2][lane]] = [u, v, w];
            dets[lane] = det;
            t_scaleds[lane] = t_scaled;
            // Only used when a lane passes: computed after that test (LLVM sinks it).
            [sizes[0][lane], sizes[1][lane], sizes[2][lane]] = sheared.sizes(self.abs_sz[lane]);
        }
        let mask = lane_mask_of(&bits);
        if mask == 0 {
            return None;
        }
        Some(LaneValues {
            mask,
            zero: lane_mask_of(&zeros),
            e,
            det: dets,
            t_scaled: t_scaleds,
            sizes,
        })
    }

    /// Lane `lane` of vertices `v` (in the sheared axis order) in ray space, as the
    /// scalar test computes it.
    #[inline(always)]
    fn shear<const N: usize>(&self, v: &[[[f32; N]; 3]; 3], lane: usize) -> Sheared {
        let o = &self.origin;
        let (ox, oy, oz) = (o[0][lane], o[1][lane], o[2][lane]);
        let (sx, sy, sz) = (self.sx[lane], self.sy[lane], self.sz[lane]);
        let (a, b, c) = (&v[0], &v[1], &v[2]);
        let (a_x, a_y, a_z) = (a[0][lane] - ox, a[1][lane] - oy, a[2][lane] - oz);
        let (b_x, b_y, b_z) = (b[0][lane] - ox, b[1][lane] - oy, b[2][lane] - oz);
        let (c_x, c_y, c_z) = (c[0][lane] - ox, c[1][lane] - oy, c[2][lane] - oz);
        Sheared {
            rel_z: [a_z, b_z, c_z],
            xy: [
                a_x - sx * a_z,
                a_y - sy * a_z,
                b_x - sx * b_z,
                b_y - sy * b_z,
                c_x - sx * c_z,
                c_y - sy * c_z,
            ],
            z: [sz * a_z, sz * b_z, sz * c_z],
        }
    }
}

/// Bit `i` set where `lanes[i]` has all bits set: a movmskps per [`LANES`] lanes.
#[inline(always)]
pub(super) fn lane_mask_of<const N: usize>(lanes: &[u32; N]) -> u32 {
    let mut mask = 0;
    for (i, chunk) in lanes.chunks_exact(LANES).enumerate() {
        let chunk: [u32; LANES] = chunk.try_into().unwrap_or_default();
        mask |= u32x4::from(chunk).to_bitmask() << (i * LANES);
    }
    mask
}

/// A triangle in ray space: the z coordinates of its vertices relative to the origin
/// (permuted axes), their sheared x and y, their scaled z.
struct Sheared {
    rel_z: [f32; 3],
    xy: [f32; 6],
    z: [f32; 3],
}

impl Sheared {
    /// Pz, S, Z: the largest magnitude of `rel_z`, of `xy` and of `z` (with `abs_sz` the
    /// ray's |sz|), from which [`t_error_bound`] bounds what the scalar test's error
    /// bound on t grows with. Z is |sz| Pz: rounding is monotonic, so that product is
    /// the largest of the rounded |sz z|, without their own abs and max. A NaN
    /// coordinate makes t NaN, so it may be skipped.
    #[inline(always)]
    fn sizes(&self, abs_sz: f32) -> [f32; 3] {
        error_sizes(&self.rel_z, &self.xy, abs_sz)
    }
}

/// [`Sheared::sizes`] of a triangle with relative z coordinates `rel_z` and sheared
/// x and y `xy`, for a ray with |sz| `abs_sz`: what [`clear_of_zero`] takes, for the
/// lanes and for the scalar test alike.
#[inline(always)]
pub(super) fn error_sizes(rel_z: &[f32; 3], xy: &[f32; 6], abs_sz: f32) -> [f32; 3] {
    // maxps itself: f32::max would add a NaN check per lane.
    let max = |m: f32, x: &f32| if m > x.abs() { m } else { x.abs() };
    let pz = rel_z.iter().fold(0.0, max);
    [pz, xy.iter().fold(0.0, max), abs_sz * pz]
}

/// The prefilter's answer for one triangle test over `N` lanes (a group's triangles
/// against one ray, or one triangle against a packet's rays): the lanes the scalar
/// test may accept, and the scalar test's own intermediate values on each lane, bit
/// for bit.
pub struct LaneValues<const N: usize> {
    /// Lanes the scalar test may accept.
    pub mask: u32,
    /// Lanes with an edge function exactly zero, which the scalar test redoes in f64.
    pub(super) zero: u32,
    /// The edge functions u, v, w.
    pub(super) e: [[f32; N]; 3],
    pub(super) det: [f32; N],
    pub(super) t_scaled: [f32; N],
    /// [`Sheared::sizes`] of each lane.
    pub(super) sizes: [[f32; N]; 3],
}

/// The prefilter's answer for one group against one ray.
pub type Candidates = LaneValues<LANES>;

/// What a lane's values decide ([`LaneValues::decide`]).
pub(super) enum Decided {
    /// The scalar test's hit, bit for bit.
    Hit(TriangleHit),
    /// The scalar test's miss.
    Miss,
    /// Not decided: the caller runs the scalar test itself.
    Scalar,
}

impl<const N: usize> LaneValues<N> {
    /// The scalar test's answer on lane `i` (in `mask`), with a bound `t_max` at most
    /// the prefilter's; `may_be_degenerate` false vouches that the lane's triangle
    /// (`triangle()`) is not degenerate ([`DEGENERATE`]). From the lane's values when
    /// they decide it: no zero edge function (so the signs, det and the sign of
    /// t_scaled passed as in the scalar test) and a t far enough from 0 that the scalar
    /// test's error bound on t cannot send it to its f64 recheck (see `clear_of_zero`);
    /// else [`Decided::Scalar`]. An answer, not a closure for the scalar test: such a
    /// closure was compiled apart, and every candidate lane stored its captures and
    /// read its answer back through memory (torus 100k, with the first group of a
    /// leaf tested apart: 1,506 / 1,906 / 1,231 -> 1,491 / 1,890 / 1,224 instructions per
    /// primary / incoherent / shadow ray).
    #[inline(always)]
    pub(super) fn decide(
        &self,
        i: usize,
        t_max: f32,
        may_be_degenerate: bool,
        triangle: impl FnOnce() -> [Vec3; 3],
    ) -> Decided {
        if self.zero & (1 << i) != 0 {
            return Decided::Scalar;
        }
        let (det, t_scaled) = (self.det[i], self.t_scaled[i]);
        // The scalar test's remaining checks, in its order, against the current bound.
        let beyond = if det < 0.0 {
            t_scaled <= t_max * det
        } else {
            t_scaled >= t_max * det
        };
        if beyond {
            return Decided::Miss;
        }
        if may_be_degenerate {
            let [a, b, c] = triangle();
            if is_degenerate(a, b, c) {
                return Decided::Miss;
            }
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        if !(t > 0.0 && t < t_max) {
            return Decided::Miss;
        }
        // Lane `i` of each array, not a copy of the arrays.
        let [pz, xy, z] = &self.sizes;
        if !clear_of_zero(t, det, [pz[i], xy[i], z[i]]) {
            return Decided::Scalar;
        }
        let [u, v, w] = [self.e[0][i], self.e[1][i], self.e[2][i]];
        Decided::Hit(TriangleHit {
            t,
            b0: u * inv_det,
            b1: v * inv_det,
            b2: w * inv_det,
        })
    }
}

impl Candidates {
    /// The scalar test, [`super::intersect_triangle_sheared`], on lane `lane` (in
    /// `mask`) of group `g`, with a bound `t_max` at most the prefilter's: see
    /// `LaneValues::decide`. The vertices are read only where they are needed: the
    /// scalar test, and the exact degenerate test in leaves that hold a degenerate
    /// triangle.
    #[inline(always)]
    pub fn hit(
        &self,
        lane: usize,
        g: &TriGroup,
        may_be_degenerate: bool,
        ray: &Ray,
        t_max: f32,
    ) -> Option<TriangleHit> {
        match self.decide(lane, t_max, may_be_degenerate, || g.triangle(lane)) {
            Decided::Hit(h) => Some(h),
            Decided::Miss => None,
            Decided::Scalar => scalar_lane(g, lane, ray, t_max, may_be_degenerate),
        }
    }
}

/// The scalar test on lane `lane` of `g`, for the few lanes whose values do not decide
/// it: out of line and cold, so that the hot path builds nothing for it. It makes the
/// ray's `RayShear` itself (the prefilter's shear to the bit: `RayShear::with_inverse`
/// is `RayShear::new`), so that a query stores only the prefilter's constants per ray,
/// not a second copy of the shear for this rare path.
#[cold]
#[inline(never)]
pub(super) fn scalar_lane(
    g: &TriGroup,
    lane: usize,
    ray: &Ray,
    t_max: f32,
    may_be_degenerate: bool,
) -> Option<TriangleHit> {
    let shear = RayShear::new(ray);
    intersect_triangle_flagged(
        &shear,
        ray.origin,
        g.triangle(lane),
        t_max,
        may_be_degenerate,
    )
}

/// True when `t` exceeds three times the scalar test's bound on its rounding error
/// (`triangle::t_error`), so that the test keeps t without its f64 recheck. `sizes`
/// are Pz, S, Z ([`Sheared::sizes`]): the largest magnitude of the relative vertex
/// z coordinates, of their sheared x and y, and of the scaled z. The largest relative
/// coordinate P is then at most (S + Pz) (1 + u): a relative x is its sheared x (at
/// most S (1 + u) before rounding) plus sx times its z, rounded (at most Pz, as
/// |sx| <= 1); the same for y. With the edge functions all of one sign
/// (|u| + |v| + |w| <= |det| (1 + 3u)) and |sx|, |sy| <= 1, each term of that bound is
/// at most: the errors of the sheared coordinates 2 gamma(5) P; of the edge functions
/// together 24 gamma(5) P S + 6 gamma(2) S^2 =: E; of det E + gamma(2) |det|, of
/// t_scaled E Z + gamma(6) Z |det|; so the bound is at most
/// (1 + 1e-5) u ((120 P S + 12 S^2) (Z + t) / |det| + 6 Z + 2 t), u = 2^-24. The test
/// compares both sides times |det| (positive), which decides the same, without the
/// division: t |det| > 3.0001 u ((120 P S + 12 S^2) (Z + t) + (6 Z + 2 t) |det|),
/// evaluated in f64 from f32 inputs (t |det| exact; every term positive, so each side
/// is within a few f64 roundings, 1e-15 relative, of its exact value, which the margin
/// of 3.0001 over 3 (1 + 1e-5) dwarfs; products of at most three f32 magnitudes
/// neither overflow nor underflow). A t that is not positive, or NaN, is never clear.
#[inline(always)]
pub(super) fn clear_of_zero(t: f32, det: f32, sizes: [f32; 3]) -> bool {
    let [pz, s, z] = sizes.map(f64::from);
    let (t, det) = (f64::from(t), f64::from(det).abs());
    let unit = f64::from(f32::EPSILON) * 0.5;
    // (S + Pz) (1 + u), with a margin for the rounding of this sum and product.
    let p = (s + pz) * (1.0 + 2.0 * unit);
    let bound = (120.0 * p * s + 12.0 * s * s) * (z + t) + (6.0 * z + 2.0 * t) * det;
    t * det > 3.0001 * unit * bound
}

/// The bound of [`clear_of_zero`] on the scalar test's bound on t's rounding error,
/// divided out, as `clear_of_zero` compared t with it before it multiplied both sides
/// by |det|; for the tests (the two forms must agree but next to the boundary).
#[cfg(test)]
fn t_error_bound(t: f32, det: f32, sizes: [f32; 3]) -> f64 {
    let [pz, s, z] = sizes.map(f64::from);
    let (t, det) = (f64::from(t).abs(), f64::from(det).abs());
    let unit = f64::from(f32::EPSILON) * 0.5;
    // (S + Pz) (1 + u), with a margin for the rounding of this sum and product.
    let p = (s + pz) * (1.0 + 2.0 * unit);
    unit * ((120.0 * p * s + 12.0 * s * s) * (z + t) / det + 6.0 * z + 2.0 * t)
}

#[path = "leaf_closest.rs"]
mod closest;
pub use closest::GroupHits;

#[cfg(test)]
#[path = "leaf_tests.rs"]
mod tests;
