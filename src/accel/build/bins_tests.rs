//! Tests of the bins, the SAH sweep and the partition against their references.

use glam::Vec3;
use wide::f32x4;

use super::super::{FEW_BINS, NodeBounds, blocks};
use super::*;
use crate::accel::Aabb;
use crate::test_util::Lcg;

/// [`bin_position`] of four lanes at once, kept in SIMD registers: `fast_max` /
/// `fast_min` (`maxps` / `minps`) are exactly its two compare-and-selects.
fn bin_positions(c: f32x4, min: f32x4, scale: f32x4) -> f32x4 {
    ((c - min) * scale)
        .fast_max(f32x4::ZERO)
        .fast_min(f32x4::splat((BINS - 1) as f32))
}

/// Whether a centroid coordinate whose [`bin_position`] is `x` bins below `bin` (≥ 1):
/// for `x` ≥ 0, `trunc(x) < bin` exactly when `x < bin`, so no truncation is needed;
/// the clamps change nothing either side of `bin` (NaN goes to bin 0, left).
fn goes_left(x: f32, bin: usize) -> bool {
    x < bin as f32
}

/// The partition before [`first_right`], which [`partition`] must match primitive for
/// primitive and bit for bit: each centroid's bin position computed and compared.
fn partition_reference(refs: &mut [PrimRef], bins: &Bins, plane: &Plane) -> (usize, Box4, Box4) {
    let (min, scale) = (f32x4::from(bins.min), f32x4::from(bins.scale));
    let mut left = Box4::EMPTY;
    let mut right = Box4::EMPTY;
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        let r = refs[i];
        let c = r.centroid_x4();
        let x = bin_positions(c, min, scale).to_array();
        let c = c.to_array();
        if goes_left(x[plane.axis], plane.bin) {
            left.grow(c, c);
            i += 1;
        } else {
            right.grow(c, c);
            j -= 1;
            refs.swap(i, j);
        }
    }
    (i, left, right)
}

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
        assert_eq!(one.counts, two.counts, "{n}");
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
fn first_right_sides_match_bin_positions() {
    // Axes from tiny to huge extents, far from and around zero, with scales up to
    // infinite (extent under 16 / f32::MAX); centroids around each plane's threshold,
    // on bin edges and anywhere in the node, and the awkward values.
    let mut rng = Lcg(0x1405_7b7e_f767_814f);
    let mut xs = samples();
    for round in 0..3000 {
        let min = [0.0, -0.0, 1e-30, -3.0, 1000.0, -7.5e6, 1e30][rng.below(7) as usize]
            + (rng.below(1000) as f32 - 500.0) * [0.0, 1e-3, 1.0][rng.below(3) as usize];
        let ext = [1e-40, 1e-6, 0.3, 1.0, 17.0, 1e7, 1e38][rng.below(7) as usize]
            * (1.0 + rng.below(100) as f32 * 0.01);
        let scale = BINS as f32 / ext;
        let bin = 1 + rng.below(BINS as u32 - 1) as usize;
        let first = first_right(min, scale, bin);
        xs.truncate(samples().len());
        for k in 0..=BINS {
            xs.push(min + k as f32 / scale);
        }
        for _ in 0..20 {
            xs.push(min + ext * rng.next_f32());
        }
        let mut c = first;
        for _ in 0..4 {
            c = c.next_down();
        }
        for _ in 0..8 {
            xs.push(c);
            c = c.next_up();
        }
        for &x in &xs {
            let position = bin_positions(f32x4::splat(x), f32x4::splat(min), f32x4::splat(scale));
            let want = goes_left(position.to_array()[0], bin);
            assert_eq!(
                !x.ge(&first),
                want,
                "round {round}: {x} {min} {scale} {bin}"
            );
        }
    }
}

#[test]
fn partition_matches_the_reference_order_and_boxes() {
    // Nodes of clustered, spread, coincident, huge and NaN coordinates; each split by
    // its best plane and by every plane on each axis (all left or all right too).
    let mut rng = Lcg(0x6a09_e667_f3bc_c908);
    let mut planes = 0;
    for round in 0..300 {
        let n = 2 + rng.below(600) as usize;
        let spread = [1e-3, 1.0, 1e5][rng.below(3) as usize];
        let refs: Vec<PrimRef> = (0..n)
            .map(|i| {
                let lo = if rng.below(10) == 0 {
                    Vec3::splat(0.5)
                } else {
                    Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * spread
                };
                let mut hi = lo + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let mut lo = lo;
                if rng.below(30) == 0 {
                    // A NaN centroid coordinate, which goes left.
                    let axis = rng.below(3) as usize;
                    (lo[axis], hi[axis]) = (f32::NAN, f32::NAN);
                }
                if rng.below(4) == 0 {
                    // Centroid coordinates of +0 and -0: ties the boxes' order decides.
                    let axis = rng.below(3) as usize;
                    let zero = if rng.below(2) == 0 { 0.0 } else { -0.0 };
                    (lo[axis], hi[axis]) = (zero, zero);
                }
                PrimRef::new(i, &Aabb::new(lo, hi))
            })
            .collect();
        let centroids = NodeBounds::of(&refs).centroids;
        let mut bins = Bins::empty(centroids);
        bins.add(&refs);
        let mut cases: Vec<Plane> = best_sah_plane(&bins).into_iter().collect();
        for axis in 0..3 {
            if bins.scale[axis] > 0.0 {
                for bin in 1..BINS {
                    let (occupied, cost) = (0, 0.0);
                    cases.push(Plane {
                        axis,
                        bin,
                        occupied,
                        cost,
                    });
                }
            }
        }
        for plane in &cases {
            let (mut got, mut want) = (refs.clone(), refs.clone());
            let (gm, gl, gr) = partition(&mut got, &bins, plane);
            let (wm, wl, wr) = partition_reference(&mut want, &bins, plane);
            let order = |v: &[PrimRef]| v.iter().map(PrimRef::index).collect::<Vec<_>>();
            assert_eq!((gm, order(&got)), (wm, order(&want)), "round {round}");
            let bits = |b: Box4| BinBox::of(b).0.map(f32::to_bits);
            assert_eq!((bits(gl), bits(gr)), (bits(wl), bits(wr)), "round {round}");
            planes += 1;
        }
    }
    assert!(planes > 5000, "{planes}");
}

#[test]
fn bins_of_truncates_exactly_like_as() {
    for x in samples() {
        let position = bin_position(x, 0.0, 1.0);
        let expected = position as u32;
        let k = bins_of(f32x4::splat(x), f32x4::ZERO, f32x4::ONE, (BINS - 1) as f32).to_array();
        assert_eq!(k, [expected as i32; 4], "{x}");
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

/// Nodes of random boxes (a few NaN centroid coordinates among them).
fn random_refs(rng: &mut Lcg, n: usize) -> Vec<PrimRef> {
    (0..n)
        .map(|i| {
            let mut lo = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let mut hi = lo + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.1;
            if rng.below(50) == 0 {
                let axis = rng.below(3) as usize;
                (lo[axis], hi[axis]) = (f32::NAN, f32::NAN);
            }
            PrimRef::new(i, &Aabb::new(lo, hi))
        })
        .collect()
}

#[test]
fn few_bins_in_reused_scratch_match_fresh_bins() {
    // Nodes alternately of 16 and 8 bins in one scratch: the bins from 8 on keep the
    // previous node's boxes, which nothing may read.
    let mut rng = Lcg(0x1f83_d9ab_fb41_bd6b);
    let mut scratch = Bins::empty(Box4::EMPTY);
    for round in 0..400 {
        let n = 2 + rng.below(300) as usize;
        let refs = random_refs(&mut rng, n);
        let centroids = NodeBounds::of(&refs).centroids;
        let count = if round % 2 == 0 { BINS } else { FEW_BINS };
        scratch.fill(&refs, centroids, count);
        let mut fresh = Bins::empty(centroids);
        fresh.reset(centroids, count);
        for r in &refs {
            fresh.add_one(r);
        }
        for axis in 0..3 {
            let c = scratch.counts[axis];
            assert_eq!(c, fresh.counts[axis], "round {round}");
            assert!(c[count..].iter().all(|&k| k == 0), "round {round}");
            if scratch.scale[axis] > 0.0 {
                assert!(
                    c[count - 1] > 0,
                    "round {round}: the last bin holds the max"
                );
            }
        }
        let (got, want) = (best_sah_plane(&scratch), best_sah_plane(&fresh));
        assert_eq!(got.is_some(), want.is_some(), "round {round}");
        let (Some(got), Some(want)) = (got, want) else {
            continue;
        };
        assert!(got.bin < count, "round {round}");
        let key = |p: &Plane| (p.axis, p.bin, p.occupied, p.cost.to_bits());
        assert_eq!(key(&got), key(&want), "round {round}");
        let bits = |(l, r): (Box4, Box4)| [l, r].map(|b| BinBox::of(b).0.map(f32::to_bits));
        assert_eq!(
            bits(scratch.boxes_around(&got)),
            bits(fresh.boxes_around(&want))
        );
    }
}

#[test]
fn index_lane_keeps_the_index_and_never_goes_subnormal() {
    // The index's lane takes part in the centroid and the bin positions unmasked: its
    // values there must never be subnormal (slow), whatever the index below 2^30 - 2^23.
    let slow = |v: f32| v.is_subnormal();
    let b = Aabb::new(Vec3::splat(-1e-30), Vec3::splat(1e-30));
    let mut rng = Lcg(0x9b05_688c_2b3e_6c1f);
    let mut indices: Vec<usize> = vec![0, 1, 2, 255, 1 << 23, (1 << 30) - (1 << 23) - 1];
    indices.extend((0..200).map(|_| rng.below(1 << 24) as usize));
    let refs: Vec<PrimRef> = indices.iter().map(|&i| PrimRef::new(i, &b)).collect();
    for (r, &i) in refs.iter().zip(&indices) {
        assert_eq!(r.index() as usize, i);
        let c = r.centroid();
        assert!(
            !slow(c[3]) && c[3].is_finite(),
            "index {i}: centroid lane {}",
            c[3]
        );
    }
    let centroids = NodeBounds::of(&refs).centroids;
    let bins = Bins::empty(centroids);
    // Differences of floats of magnitude 1 or more are not subnormal, and a zero scale
    // makes them zero (or NaN).
    assert_eq!(bins.scale[3], 0.0);
    let min = f32x4::from(bins.min);
    for r in &refs {
        let d = (r.centroid_x4() - min).to_array()[3];
        assert!(!slow(d), "difference {d}");
    }
}
