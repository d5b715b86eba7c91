//! The binned SAH's bins (after Wald 2007, see [`super`]): each node's primitives
//! counted and boxed per axis in `BINS` bins of their centroids, the sweep that costs
//! every plane between bins, and the in-place partition by the chosen plane. Binning
//! and partition place a centroid by the same arithmetic, so they always agree.

use multiversion::multiversion;
use rayon::prelude::*;
use wide::f32x4;

use super::{BINS, Box4, Lanes, PARALLEL_BIN_CHUNK, PrimRef, TWO_SETS_MIN, blocks};

/// A box as its lower corner and its negated upper corner, the bins' form: growing
/// it is one lane-wise min over all eight lanes. `-a < -b` exactly when `a > b`, so
/// the min of the negated corners picks the same values as [`Box4::grow`]'s max,
/// bit for bit (zeros' signs and NaNs included).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct BinBox([f32; 8]);

impl BinBox {
    const EMPTY: BinBox = BinBox([f32::INFINITY; 8]);

    /// Grows to contain `o` (a [`PrimRef::flipped`] or another bin box): per lane
    /// `o < self ? o : self` (what `minps` computes). Plain lanes, not `wide`'s f32x8,
    /// which is two halves in the dispatched clones (no AVX cfg): the AVX2 clone's
    /// binning loop makes it one eight-lane compare and masked store (`vmaskmovps`)
    /// where two four-lane `minps` and two stores were, 8% less build time on the
    /// 100k torus, although a masked store's value reaches the next load of the same
    /// bin only once it has retired.
    #[inline(always)]
    fn grow(&mut self, o: [f32; 8]) {
        let mut m = self.0;
        for i in 0..8 {
            m[i] = if o[i] < m[i] { o[i] } else { m[i] };
        }
        self.0 = m;
    }

    #[inline(always)]
    fn union(mut self, o: BinBox) -> BinBox {
        self.grow(o.0);
        self
    }

    /// [`Box4::surface_area`] of [`BinBox::box4`], bit for bit (a NaN's sign aside: a
    /// NaN cost never wins), without negating the upper corner: a lower plus a negated
    /// upper coordinate is `lo - hi`, exactly the extent negated (IEEE rounding is
    /// symmetric), so the products and sums are the extent's, and it is positive
    /// exactly where `lo > hi` (an empty axis). The empty test is a select after the
    /// area, not three branches before it: the SAH sweep computes two areas per plane.
    #[inline(always)]
    fn surface_area(&self) -> f32 {
        let b = self.0;
        let d: [f32; 4] = std::array::from_fn(|i| b[i] + b[4 + i]);
        let area = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
        let empty = (d[0] > 0.0) | (d[1] > 0.0) | (d[2] > 0.0);
        if empty { 0.0 } else { area }
    }

    #[inline(always)]
    fn box4(&self) -> Box4 {
        let b = self.0;
        Box4 {
            min: [b[0], b[1], b[2], b[3]],
            max: [-b[4], -b[5], -b[6], -b[7]],
        }
    }

    #[cfg(test)]
    fn of(b: Box4) -> BinBox {
        let (lo, hi) = (b.min, b.max);
        BinBox([lo[0], lo[1], lo[2], lo[3], -hi[0], -hi[1], -hi[2], -hi[3]])
    }
}

/// Rows of [`Bins`]: one per axis, and one for the unused fourth lane, whose count
/// (never read) keeps the bin indices in four SIMD lanes in [`Bins::add`] (without
/// that increment the compiler took the lanes apart: 3 times the build time).
const ROWS: usize = 4;

/// Per axis, the count and box of the primitives whose centroids fall in each bin.
pub(super) struct Bins {
    min: Lanes,
    scale: Lanes,
    counts: [[u32; BINS]; ROWS],
    boxes: [[BinBox; BINS]; ROWS],
}

impl Bins {
    pub(super) fn empty(centroids: Box4) -> Bins {
        let mut bins = Bins {
            min: [0.0; 4],
            scale: [0.0; 4],
            counts: [[0; BINS]; ROWS],
            boxes: [[BinBox::EMPTY; BINS]; ROWS],
        };
        bins.reset(centroids);
        bins
    }

    /// Bins `refs` into `self` (scratch reused across nodes: no copies of
    /// its 2.3 KB), in parallel chunks when there are many.
    #[inline(always)]
    pub(super) fn fill(&mut self, refs: &[PrimRef], centroids: Box4) {
        if refs.len() >= 2 * PARALLEL_BIN_CHUNK {
            *self = refs
                .par_chunks(PARALLEL_BIN_CHUNK)
                .map(|c| bin_chunk(c, centroids))
                .reduce(|| Bins::empty(centroids), Bins::merge);
        } else {
            self.reset(centroids);
            self.add(refs);
        }
    }

    #[inline(always)]
    fn reset(&mut self, centroids: Box4) {
        let (min, max) = (centroids.min, centroids.max);
        self.min = min;
        self.scale = std::array::from_fn(|i| {
            let ext = max[i] - min[i];
            if ext > 0.0 { BINS as f32 / ext } else { 0.0 }
        });
        self.counts = [[0; BINS]; ROWS];
        // The fourth row's boxes are never grown.
        for row in &mut self.boxes[..3] {
            *row = [BinBox::EMPTY; BINS];
        }
    }

    /// Bins `refs`. Large nodes bin their first half into `self` and their second
    /// half into a second set of bins, one primitive of each per step, merged at the
    /// end: runs of neighbouring primitives fall in the same bins, and with one set
    /// each one's update waited for the previous one's (load, min, store). Halves, not
    /// alternate primitives: the merge then meets the values in their order, so ties
    /// (+0 and -0) resolve as one pass would resolve them, bit for bit.
    #[inline(always)]
    fn add(&mut self, refs: &[PrimRef]) {
        if refs.len() < TWO_SETS_MIN {
            for r in refs {
                self.add_one(r);
            }
            return;
        }
        let mut second = Bins::empty(Box4::EMPTY);
        (second.min, second.scale) = (self.min, self.scale);
        let (front, back) = refs.split_at(refs.len() / 2);
        for (a, b) in front.iter().zip(back) {
            self.add_one(a);
            second.add_one(b);
        }
        // `back` has one more when the count is odd.
        for r in &back[front.len()..] {
            second.add_one(r);
        }
        self.merge_in(&second);
    }

    /// The bins' flat index of each lane, `row * BINS + bin`, is formed in the
    /// lanes too: indexing the rows one by one made the compiler take the lanes apart.
    #[inline(always)]
    fn add_one(&mut self, r: &PrimRef) {
        let counts = self.counts.as_flattened_mut();
        let boxes = self.boxes.as_flattened_mut();
        let flipped = r.flipped();
        let k = bins_of(r.centroid(), self.min, self.scale);
        let at: [u32; 4] = std::array::from_fn(|i| (k[i] % BINS as u32) | (i * BINS) as u32);
        for &at in &at[..3] {
            let at = at as usize % (ROWS * BINS);
            counts[at] += 1;
            boxes[at].grow(flipped);
        }
        counts[at[3] as usize % (ROWS * BINS)] += 1;
    }

    #[inline(always)]
    fn merge_in(&mut self, o: &Bins) {
        for axis in 0..3 {
            for k in 0..BINS {
                self.counts[axis][k] += o.counts[axis][k];
                self.boxes[axis][k] = self.boxes[axis][k].union(o.boxes[axis][k]);
            }
        }
    }

    fn merge(mut self, o: Bins) -> Bins {
        self.merge_in(&o);
        self
    }

    /// The boxes of the primitives left and right of `plane`: the unions of its axis's
    /// occupied bins in order (an empty bin's box is empty, which changes no union),
    /// so small nodes skip most of the 16 bins.
    #[inline(always)]
    pub(super) fn boxes_around(&self, plane: &Plane) -> (Box4, Box4) {
        let boxes = &self.boxes[plane.axis];
        let union = |mut bits: u32| {
            let mut b = BinBox::EMPTY;
            while bits != 0 {
                let k = bits.trailing_zeros() as usize % BINS;
                bits &= bits - 1;
                b = b.union(boxes[k]);
            }
            b.box4()
        };
        let below = (1u32 << (plane.bin % BINS)) - 1;
        (
            union(plane.occupied & below),
            union(plane.occupied & !below),
        )
    }
}

/// The bins of one chunk of a large node, for the best instruction set the CPU has (a
/// closure of [`Bins::fill`] would be compiled for the baseline one, outside `split`).
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn bin_chunk(refs: &[PrimRef], centroids: Box4) -> Bins {
    let mut bins = Bins::empty(centroids);
    bins.add(refs);
    bins
}

/// A candidate plane: centroids in bins `< bin` on `axis` go left.
pub(super) struct Plane {
    axis: usize,
    bin: usize,
    /// The occupied bins on `axis`, bit `k` for bin `k`.
    occupied: u32,
    /// Unnormalised SAH cost `A_L B_L + A_R B_R`, `B` counting [`blocks`].
    pub(super) cost: f32,
}

/// Bin index of a centroid coordinate: `((c - min) * scale)` truncated into
/// `0..BINS`, NaN → 0, as `as usize` then `min(BINS - 1)` would give; clamped as a
/// float by compare-and-select. [`goes_left`] is the same test against a plane.
#[inline(always)]
fn bin_position(c: f32, min: f32, scale: f32) -> f32 {
    let x = (c - min) * scale;
    let x = if x > 0.0 { x } else { 0.0 };
    if x < (BINS - 1) as f32 {
        x
    } else {
        (BINS - 1) as f32
    }
}

/// [`bin_position`] truncated, lane by lane. `x as i32` would check every lane for
/// NaN and overflow (five instructions each, a tenth of the build); `x` is already
/// in `0..=BINS-1`, where its floor plus 2^23 holds the floor in its low mantissa
/// bits: exact truncation, in float SIMD lanes. The floor is one `roundps` in the
/// SSE4.1+ clones of `split` (the baseline clone calls `floorf`: the same values).
#[inline(always)]
fn bins_of(c: Lanes, min: Lanes, scale: Lanes) -> [u32; 4] {
    const MAGIC: f32 = (1u32 << 23) as f32;
    std::array::from_fn(|i| {
        let x = bin_position(c[i], min[i], scale[i]);
        (x.floor() + MAGIC).to_bits() - MAGIC.to_bits()
    })
}

/// [`bin_position`] of four lanes at once, kept in SIMD registers: `fast_max` /
/// `fast_min` (`maxps` / `minps`) are exactly its two compare-and-selects.
#[inline(always)]
fn bin_positions(c: f32x4, min: f32x4, scale: f32x4) -> f32x4 {
    ((c - min) * scale)
        .fast_max(f32x4::ZERO)
        .fast_min(f32x4::splat((BINS - 1) as f32))
}

/// Whether a centroid coordinate whose [`bin_position`] is `x` bins below `bin` (≥ 1):
/// for `x` ≥ 0, `trunc(x) < bin` exactly when `x < bin`, so no truncation is needed;
/// the clamps change nothing either side of `bin` (NaN goes to bin 0, left).
#[inline(always)]
fn goes_left(x: f32, bin: usize) -> bool {
    x < bin as f32
}

/// Cheapest binned-SAH plane over the three axes, if any separates the centroids.
/// The sweeps visit only the occupied bins, from a bit mask: an empty bin changes
/// neither the running box nor the count, so plane `k` costs what the plane after
/// the previous occupied bin does, and only a strictly cheaper plane replaces the best
/// one. The choice is the per-bin sweep's (the tests' reference), without its
/// unpredictable branch per bin.
#[inline(always)]
pub(super) fn best_sah_plane(bins: &Bins) -> Option<Plane> {
    // The best plane so far as selects, not a branch, whose outcome at each plane no
    // predictor learns: infinity until a plane, so that `cost < best_cost` is also the
    // test that the cost is finite (costs are never below zero; NaN fails it).
    let mut best_cost = f32::INFINITY;
    let (mut best_axis, mut best_bin, mut best_occupied) = (0, 0, 0);
    for axis in 0..3 {
        if bins.scale[axis] == 0.0 {
            continue;
        }
        let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
        let mut occupied = 0u32;
        for (k, &n) in counts.iter().enumerate() {
            occupied |= u32::from(n > 0) << k;
        }
        if occupied == 0 {
            continue;
        }
        // right_cost[r]: area * blocks of the occupied bins from the r-th (counting
        // from 0 upwards) on, for r >= 1 (the lowest occupied bin is never on the right).
        let mut right_cost = [0.0f32; BINS];
        let mut acc_box = BinBox::EMPTY;
        let mut acc_n = 0u32;
        let mut rank = occupied.count_ones() as usize;
        let mut rest = occupied & occupied.wrapping_sub(1);
        while rest != 0 {
            let k = (u32::BITS - 1 - rest.leading_zeros()) as usize % BINS;
            rest ^= 1 << k;
            rank -= 1;
            acc_box = acc_box.union(boxes[k]);
            acc_n += counts[k];
            right_cost[rank % BINS] = acc_box.surface_area() * blocks(acc_n);
        }
        // The plane after each occupied bin but the highest (which has nothing
        // on its right).
        let mut left_box = BinBox::EMPTY;
        let mut left_n = 0u32;
        let mut rank = 0;
        let highest = u32::BITS - 1 - occupied.leading_zeros();
        let mut rest = occupied & !(1 << highest);
        while rest != 0 {
            let k = rest.trailing_zeros() as usize % BINS;
            rest &= rest - 1;
            rank += 1;
            left_box = left_box.union(boxes[k]);
            left_n += counts[k];
            let cost = left_box.surface_area() * blocks(left_n) + right_cost[rank % BINS];
            let better = cost < best_cost;
            best_cost = if better { cost } else { best_cost };
            best_axis = if better { axis } else { best_axis };
            best_bin = if better { k + 1 } else { best_bin };
            best_occupied = if better { occupied } else { best_occupied };
        }
    }
    (best_cost < f32::INFINITY).then_some(Plane {
        axis: best_axis,
        bin: best_bin,
        occupied: best_occupied,
        cost: best_cost,
    })
}

/// In-place partition by `plane`; returns how many primitives go left (now at
/// the front) and the centroid boxes of both sides. The swap order is fixed:
/// it decides the primitive order in the leaves.
#[inline(always)]
pub(super) fn partition(refs: &mut [PrimRef], bins: &Bins, plane: &Plane) -> (usize, Box4, Box4) {
    // One loop per axis: a lane picked at run time went through memory.
    match plane.axis {
        0 => partition_on::<0>(refs, bins, plane.bin),
        1 => partition_on::<1>(refs, bins, plane.bin),
        _ => partition_on::<2>(refs, bins, plane.bin),
    }
}

/// [`partition`] on axis `AXIS`.
#[inline(always)]
fn partition_on<const AXIS: usize>(
    refs: &mut [PrimRef],
    bins: &Bins,
    bin: usize,
) -> (usize, Box4, Box4) {
    let (min, scale) = (f32x4::from(bins.min), f32x4::from(bins.scale));
    let mut left = Box4::EMPTY;
    let mut right = Box4::EMPTY;
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        let r = refs[i];
        // All four lanes in SIMD registers: picking the axis's lane first made the
        // compiler take the centroid apart and put it back together.
        let c = r.centroid_x4();
        let x = bin_positions(c, min, scale).to_array();
        let c = c.to_array();
        if goes_left(x[AXIS], bin) {
            left.grow(c, c);
            i += 1;
        } else {
            right.grow(c, c);
            j -= 1;
            // refs.swap(i, j), without its round trip through the stack.
            refs[i] = refs[j];
            refs[j] = r;
        }
    }
    (i, left, right)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::NodeBounds;
    use super::*;
    use crate::accel::Aabb;
    use crate::test_util::Lcg;

    /// The per-axis sweep [`best_sah_plane`] must agree with (the builder's before it
    /// swept the axes together).
    fn best_sah_plane_reference(bins: &Bins) -> Option<Plane> {
        let mut best: Option<Plane> = None;
        for axis in 0..3 {
            if bins.scale[axis] == 0.0 {
                continue;
            }
            let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
            // right_cost[k]: area * blocks of bins k.. (the right side of plane k).
            let mut right_cost = [0.0f32; BINS];
            let mut acc_box = Box4::EMPTY;
            let mut acc_n = 0u32;
            let mut right = f32::INFINITY; // empty right side: not a split
            for k in (1..BINS).rev() {
                // An empty bin changes neither the box nor the count: skip the area.
                if counts[k] > 0 {
                    acc_box = acc_box.union(boxes[k].box4());
                    acc_n += counts[k];
                    right = acc_box.surface_area() * blocks(acc_n);
                }
                right_cost[k] = right;
            }
            let mut left_box = Box4::EMPTY;
            let mut left_n = 0u32;
            for k in 1..BINS {
                // Plane k costs the same as plane k - 1 when bin k - 1 is empty,
                // and only a strictly cheaper plane replaces the best one.
                if counts[k - 1] == 0 {
                    continue;
                }
                left_box = left_box.union(boxes[k - 1].box4());
                left_n += counts[k - 1];
                let cost = left_box.surface_area() * blocks(left_n) + right_cost[k];
                if cost.is_finite() && best.as_ref().is_none_or(|b| cost < b.cost) {
                    let occupied = (0..BINS).fold(0, |m, k| m | u32::from(counts[k] > 0) << k);
                    best = Some(Plane {
                        axis,
                        bin: k,
                        occupied,
                        cost,
                    });
                }
            }
        }
        best
    }

    #[test]
    fn sweep_matches_the_per_axis_reference() {
        // Bins as nodes of a few to many primitives leave them: mostly empty to full,
        // flat and inverted (empty) boxes, infinite coordinates, ties between bins
        // and between axes (copied boxes), an axis with zero extent.
        let mut rng = Lcg(0x9e37_79b9_7f4a_7c15);
        let mut planes = 0;
        for round in 0..20_000 {
            let mut bins = Bins::empty(Box4::EMPTY);
            let full = rng.below(17);
            for axis in 0..3 {
                bins.scale[axis] = if rng.below(13) == 0 { 0.0 } else { 1.0 };
                for k in 0..BINS {
                    if rng.below(16) >= full {
                        continue;
                    }
                    bins.counts[axis][k] = rng.below(9) + 1;
                    let v: [f32; 4] = std::array::from_fn(|_| rng.below(64) as f32 * 0.25 - 8.0);
                    let (lo, hi): (Lanes, Lanes) = match rng.below(20) {
                        0 => (Box4::EMPTY.min, Box4::EMPTY.max),
                        1 => ([f32::NEG_INFINITY, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 0.0]),
                        2 => ([v[0], v[1], 0.0, 0.0], [v[0], 8.0, 0.0, 0.0]),
                        _ => (
                            [v[0], v[1], v[2], 0.0],
                            [v[0] + v[3] + 8.0, v[1] + 4.0, v[2] + 2.0, 0.0],
                        ),
                    };
                    bins.boxes[axis][k] = BinBox::of(Box4 { min: lo, max: hi });
                }
            }
            if round % 7 == 0 {
                bins.counts[1] = bins.counts[0];
                bins.boxes[1] = bins.boxes[0];
            }
            let plane = best_sah_plane(&bins);
            let key = |p: &Plane| (p.axis, p.bin, p.occupied, p.cost.to_bits());
            let want = best_sah_plane_reference(&bins);
            assert_eq!(
                plane.as_ref().map(key),
                want.as_ref().map(key),
                "round {round}"
            );
            if let Some(plane) = plane {
                // The boxes either side, from the occupied bins, are the unions of all.
                let boxes = &bins.boxes[plane.axis];
                let union = |s: &[BinBox]| s.iter().fold(BinBox::EMPTY, |a, b| a.union(*b)).0;
                let bits = |b: Box4| BinBox::of(b).0.map(f32::to_bits);
                let (left, right) = bins.boxes_around(&plane);
                let want = (union(&boxes[..plane.bin]), union(&boxes[plane.bin..]));
                assert_eq!(bits(left), want.0.map(f32::to_bits), "round {round}");
                assert_eq!(bits(right), want.1.map(f32::to_bits), "round {round}");
                planes += 1;
            }
        }
        assert!(planes > 10_000, "{planes}");
    }

    #[test]
    fn two_sets_of_bins_match_one_pass_bit_for_bit() {
        // Coordinates of +0 and -0 (ties the order decides) among a few values,
        // enough primitives for the two sets; odd and even counts.
        let mut rng = Lcg(0x2545_f491_4f6c_dd1d);
        for n in [TWO_SETS_MIN, 999, 4096] {
            let values = [0.0f32, -0.0, 1.0, -1.0, 0.5];
            let refs: Vec<PrimRef> = (0..n)
                .map(|i| {
                    let mut v = || values[rng.below(5) as usize];
                    let lo = Vec3::new(v(), v(), v());
                    let hi = lo + Vec3::new(v().abs(), v().abs(), v().abs());
                    PrimRef::new(i, &Aabb::new(lo, hi))
                })
                .collect();
            let centroids = NodeBounds::of(&refs).centroids;
            let mut two = Bins::empty(centroids);
            two.add(&refs);
            let mut one = Bins::empty(centroids);
            for r in &refs {
                one.add_one(r);
            }
            // The fourth row counts the unused lane and is never merged or read.
            assert_eq!(one.counts[..3], two.counts[..3], "{n}");
            for axis in 0..3 {
                for k in 0..BINS {
                    let bits = |b: &Bins| b.boxes[axis][k].0.map(f32::to_bits);
                    assert_eq!(bits(&one), bits(&two), "{n} prims, axis {axis} bin {k}");
                }
            }
        }
    }

    /// Every float the binning can meet near the bin edges, and the awkward ones.
    fn samples() -> Vec<f32> {
        let mut xs = vec![
            0.0, -0.0, -1.0, 1e-30, 0.5, 1.5, 2.5, 14.5, 15.0, 15.5, 16.0,
        ];
        xs.extend([1e9, f32::MAX, f32::INFINITY, f32::NEG_INFINITY, f32::NAN]);
        for k in 0..=BINS as u32 {
            let b = k as f32;
            xs.extend([b, b.next_down(), b.next_up(), b + 0.25, b + 0.5, b + 0.75]);
        }
        for i in 0..10_000 {
            xs.push(i as f32 * 0.0017);
        }
        xs
    }

    #[test]
    fn bin_box_area_is_box4_area_bit_for_bit_or_both_nan() {
        // Every pair of corner coordinates from awkward values, per axis: boxes empty
        // on any one axis, flat, infinite, signed zeros, NaN.
        let values = [
            -1e30f32,
            -2.5,
            -0.0,
            0.0,
            1e-40,
            0.75,
            3.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut rng = Lcg(0x5851_f42d_4c95_7f2d);
        for _ in 0..50_000 {
            let mut pick = || values[rng.below(values.len() as u32) as usize];
            let min: Lanes = [pick(), pick(), pick(), 0.0];
            let max: Lanes = [pick(), pick(), pick(), 0.0];
            let b = Box4 { min, max };
            let (got, want) = (BinBox::of(b).surface_area(), b.surface_area());
            let same = got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan());
            assert!(same, "{min:?} {max:?}: {got} for {want}");
        }
    }

    #[test]
    fn bins_of_truncates_exactly_like_as() {
        for x in samples() {
            let position = bin_position(x, 0.0, 1.0);
            let expected = position as u32;
            assert_eq!(bins_of([x; 4], [0.0; 4], [1.0; 4]), [expected; 4], "{x}");
            let lanes = bin_positions(f32x4::splat(x), f32x4::ZERO, f32x4::ONE).to_array();
            assert_eq!(lanes.map(f32::to_bits), [position.to_bits(); 4], "{x}");
            for bin in 1..BINS {
                assert_eq!(
                    goes_left(lanes[0], bin),
                    (expected as usize) < bin,
                    "{x} {bin}"
                );
            }
        }
    }
}
