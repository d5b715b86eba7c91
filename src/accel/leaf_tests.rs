//! Tests of the leaf prefilter and its decided lanes against the scalar triangle test.

use super::*;
use crate::accel::triangle::{intersect_triangle_sheared, t_and_error};
use crate::test_util::Lcg;
use glam::vec3;

/// Each lane's hit as the wide BVH's leaves compute it: prefilter, then each lane
/// that passes decided from its values or by the scalar test, with the group's
/// degenerate flag as a leaf of it would carry it. Also returns the prefilter's mask.
fn leaf_hits(ray: &Ray, g: &TriGroup, t_max: f32) -> ([Option<TriangleHit>; LANES], u32) {
    let s = RayShear::new(ray);
    let Some(candidates) = RayLeaf::new(ray, &s).candidates(g, t_max) else {
        return ([None; LANES], 0);
    };
    let mask = candidates.mask;
    let degenerate = (0..LANES).any(|lane| {
        let [a, b, c] = g.triangle(lane);
        is_degenerate(a, b, c)
    });
    let hits = std::array::from_fn(|lane| {
        (mask & (1 << lane) != 0)
            .then(|| candidates.hit(lane, g, degenerate, ray, t_max))
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
                let bits =
                    |h: Option<TriangleHit>| h.map(|h| [h.t, h.b0, h.b1, h.b2].map(f32::to_bits));
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
            if let Some(h) =
                intersect_triangle_sheared(&RayShear::new(&ray), ray.origin, a, b, c, f32::INFINITY)
            {
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
fn decided_lanes_bound_the_scalar_tests_t_error() {
    // Hits of random rays, and of grazing rays from points a little off triangles
    // far from the world origin (small t, large coordinates), long thin triangles
    // included: the bound the decided lanes use is never below the scalar test's,
    // and it decides ordinary hits.
    let mut rng = Lcg(91);
    let (mut hits, mut decided, mut near) = (0, 0, 0);
    for i in 0..20_000 {
        let far = [0.0, 10.0, 1e4][i % 3];
        let centre = rng.vec() * 4.0 + Vec3::splat(far);
        let thin = if i % 5 == 0 { 1e-3 } else { 1.0 };
        // Some long ones: vertices far to the side of the ray, whose relative x or y
        // exceeds every relative z many times.
        let long = if i % 7 == 0 { 1e3 } else { 4.0 };
        let (e1, e2) = (rng.dir() * long, rng.dir() * thin);
        let tri = [centre, centre + e1, centre + e2];
        let target = centre + e1 * rng.next_f32() * 0.5 + e2 * rng.next_f32() * 0.5;
        let ray = if i % 2 == 0 {
            let d = rng.dir();
            Ray::new(target - d * (0.5 + 3.0 * rng.next_f32()), d)
        } else {
            // From a point 10^-k off the triangle, grazing it.
            let n = e1.cross(e2).normalize();
            let along = (e1.normalize() + n * 10f32.powi(-((i % 4) as i32))).normalize();
            let off = n * 10f32.powi(-1 - (i % 6) as i32);
            Ray::new(target + off - along * 10f32.powi(-((i % 5) as i32)), along)
        };
        let s = RayShear::new(&ray);
        let Some((t, scalar)) = t_and_error(&s, ray.origin, tri) else {
            continue;
        };
        let mut g = TriGroup::PADDING;
        g.set_triangle(0, tri);
        // The prefilter rejects only what the scalar test rejects before its division:
        // a t that is not positive, where the bound is not used.
        let Some(c) = RayLeaf::new(&ray, &s).candidates(&g, f32::INFINITY) else {
            assert!(t.is_nan() || t <= 0.0, "{ray:?} {tri:?}: {t} rejected");
            continue;
        };
        assert_eq!(c.zero & 1, 0);
        let (det, sizes) = (c.det[0], c.sizes.map(|s| s[0]));
        assert_eq!(c.t_scaled[0] * (1.0 / det), t);
        let ours = t_error_bound(t, det, sizes);
        assert!(ours >= scalar, "{ray:?} {tri:?}: {ours} < {scalar}");
        if t > 0.0 {
            hits += 1;
            decided += clear_of_zero(t, det, sizes) as usize;
            near += (f64::from(t) <= 3.0 * scalar) as usize;
        }
    }
    assert!(hits > 5000 && near > 0, "{hits} hits, {near} near");
    assert!(decided * 10 > hits * 8, "{decided} of {hits} decided");
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

#[test]
fn padding_lanes_never_pass_the_prefilter() {
    // The leaf test does not mask a group by its leaf's count: the prefilter itself
    // must reject the NaN padding lanes, whatever the ray and bound.
    let mut rng = Lcg(5);
    let mut g = TriGroup::PADDING;
    g.set_triangle(0, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    for i in 0..2000 {
        let mut d = rng.dir();
        if i % 5 == 0 {
            d[i % 3] = 0.0;
        }
        let ray = Ray::new(rng.vec() * 4.0 - Vec3::splat(2.0), d);
        for t_max in [f32::INFINITY, 1.0, 0.0, -1.0, f32::NAN] {
            let (_, mask) = leaf_hits(&ray, &g, t_max);
            assert_eq!(mask & !1, 0, "{ray:?} {t_max}");
        }
    }
}

#[test]
fn clear_of_zero_times_det_decides_as_the_divided_bound() {
    // The test without the division against `t > 3.0001 t_error_bound` (the divided
    // form the scalar test's bound was proven for), over magnitudes from f32's least
    // to its largest: the same answer except within f64 rounding of the boundary,
    // where either answer is sound.
    let mut rng = Lcg(23);
    let magnitude = |rng: &mut Lcg| {
        let e = (rng.next_f32() * 250.0) as i32 - 140;
        (2.0f32).powi(e) * (1.0 + rng.next_f32())
    };
    let (mut clear, mut unclear) = (0, 0);
    for _ in 0..200_000 {
        let sizes = [
            magnitude(&mut rng),
            magnitude(&mut rng),
            magnitude(&mut rng),
        ];
        let det = magnitude(&mut rng) * if rng.next_f32() < 0.5 { -1.0 } else { 1.0 };
        // A t near the boundary: a multiple of the bound around 3.0001.
        let bound = t_error_bound(1.0, det, sizes);
        let near = (3.0001 * bound) as f32 * (0.5 + rng.next_f32());
        for t in [near, magnitude(&mut rng)] {
            if !t.is_finite() || t == 0.0 {
                continue;
            }
            let divided = f64::from(t) / (3.0001 * t_error_bound(t, det, sizes));
            let ours = clear_of_zero(t, det, sizes);
            if (divided - 1.0).abs() > 1e-12 {
                assert_eq!(ours, divided > 1.0, "{t:e} {det:e} {sizes:?}");
            }
            clear += ours as usize;
            unclear += !ours as usize;
        }
    }
    assert!(
        clear > 10_000 && unclear > 10_000,
        "{clear} clear, {unclear} not"
    );
    // Not positive, NaN: never clear.
    for t in [0.0, -0.0, -1.0, f32::NAN] {
        assert!(!clear_of_zero(t, 1.0, [1.0; 3]));
    }
}

/// The closest-hit query's answer for one group as its leaf test computes it
/// (`RayLeaf::closest`, then the closest decided lane and the lanes left to the
/// scalar test, kept by (t, then prim)): the lane and its hit.
fn group_closest(
    ray: &Ray,
    g: &TriGroup,
    t_max: f32,
    degenerate: bool,
) -> Option<(usize, TriangleHit)> {
    let s = RayShear::new(ray);
    let lanes = RayLeaf::new(ray, &s).closest(g, t_max, degenerate)?;
    least_hit(lanes, &g.prim, |lane| {
        scalar_lane(g, lane, ray, t_max, degenerate)
    })
}

/// The least (t, then prim) of the closest decided lane of `lanes` and of the hits
/// `scalar(lane)` of the lanes it leaves to the scalar test: the lane and its hit.
fn least_hit<const N: usize>(
    mut lanes: GroupHits<N>,
    prims: &[u32; N],
    scalar: impl Fn(usize) -> Option<TriangleHit>,
) -> Option<(usize, TriangleHit)> {
    let mut best: Option<(usize, TriangleHit)> = None;
    let mut offer = |lane: usize, h: TriangleHit| {
        let closer = |&(bl, bh): &(usize, TriangleHit)| {
            h.t < bh.t || (h.t == bh.t && prims[lane] < prims[bl])
        };
        if best.as_ref().is_none_or(closer) {
            best = Some((lane, h));
        }
    };
    if let Some(lane) = lanes.closest(prims) {
        offer(lane, lanes.hit(lane));
    }
    for lane in (0..N).filter(|&l| lanes.scalar & (1 << l) != 0) {
        if let Some(h) = scalar(lane) {
            offer(lane, h);
        }
    }
    best
}

/// A triangle (corner `centre`, edges `e1`, `e2`) near the world origin or far from it
/// (by `i`), and a ray aimed at its centroid `target` from up to 2.5 away.
struct Aimed {
    centre: Vec3,
    e1: Vec3,
    e2: Vec3,
    target: Vec3,
    ray: Ray,
}

impl Aimed {
    fn new(rng: &mut Lcg, i: usize) -> Aimed {
        let far = [0.0, 10.0, 1e4][i % 3];
        let centre = rng.vec() * 4.0 + Vec3::splat(far);
        let (e1, e2) = (rng.dir(), rng.dir());
        let dir = rng.dir();
        let target = centre + (e1 + e2) / 3.0;
        let origin = target - dir * (0.5 + 2.0 * rng.next_f32());
        Aimed {
            centre,
            e1,
            e2,
            target,
            ray: Ray::new(origin, dir),
        }
    }
}

#[test]
fn a_groups_closest_lane_is_the_scalar_tests_least_t_then_prim() {
    // Groups of parallel copies of a triangle stacked along the ray (some at the same
    // distance, in lanes whose prims fall, so that ties go to a later lane), near the
    // world origin and far from it, some within rounding of the ray's origin (a t the
    // lanes' values cannot decide), some degenerate: the group's answer is the least
    // (t, prim) of the scalar test's hits, bit for bit.
    let mut rng = Lcg(31);
    let (mut hits, mut ties, mut unclear) = (0, 0, 0);
    for i in 0..20_000 {
        let Aimed {
            centre,
            e1,
            e2,
            target,
            ray,
        } = Aimed::new(&mut rng, i);
        let (origin, dir) = (ray.origin, ray.dir);
        let mut g = TriGroup::PADDING;
        let lanes = 1 + rng.below(LANES as u32) as usize;
        for lane in 0..lanes {
            // Offsets along the ray: a few shared, some tiny (next to the origin).
            let offset = match rng.below(4) {
                0 => 0.0,
                1 => 0.25,
                2 => -(target - origin).length() * (1.0 - 1e-6 * rng.next_f32()),
                _ => rng.next_f32(),
            };
            let shift = dir * offset;
            let mut tri = [centre + shift, centre + e1 + shift, centre + e2 + shift];
            if i % 11 == 0 && lane == 0 {
                tri[2] = tri[0] + (tri[1] - tri[0]) * 0.5;
            }
            g.set_triangle(lane, tri);
            g.prim[lane] = (LANES - lane) as u32 * 10 + rng.below(3);
        }
        let degenerate = (0..lanes).any(|l| {
            let [a, b, c] = g.triangle(l);
            is_degenerate(a, b, c)
        });
        let t_max = [f32::INFINITY, 3.0][i % 2];
        let s = RayShear::new(&ray);
        let mut want: Option<(usize, TriangleHit)> = None;
        for lane in 0..lanes {
            let [a, b, c] = g.triangle(lane);
            let Some(h) = intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max) else {
                continue;
            };
            let closer = |&(bl, bh): &(usize, TriangleHit)| {
                h.t < bh.t || (h.t == bh.t && g.prim[lane] < g.prim[bl])
            };
            if want.as_ref().is_none_or(closer) {
                if want.is_some_and(|(_, bh)| bh.t == h.t) {
                    ties += 1;
                }
                want = Some((lane, h));
            }
        }
        let got = group_closest(&ray, &g, t_max, degenerate);
        let bits = |w: Option<(usize, TriangleHit)>| {
            w.map(|(l, h)| (l, [h.t, h.b0, h.b1, h.b2].map(f32::to_bits)))
        };
        assert_eq!(bits(got), bits(want), "{ray:?} {t_max} {g:?}");
        hits += want.is_some() as usize;
        if let Some(mut c) = RayLeaf::new(&ray, &s).closest(&g, t_max, degenerate) {
            unclear += (c.hits != 0 && c.closest(&g.prim).is_none()) as usize;
        }
    }
    assert!(
        hits > 10_000 && ties > 100 && unclear > 10,
        "{hits} hits, {ties} ties, {unclear} unclear"
    );
}

#[test]
fn a_lane_whose_t_is_not_clear_of_zero_may_still_be_the_closest() {
    // Lane 0: a triangle the ray grazes from just off it (t within the f32 test's
    // rounding of 0, which the scalar test recomputes in f64); lane 1: a small
    // triangle across the ray, placed between that recomputed t and lane 0's f32 t.
    // The recomputed one is the closer, though lane 1's t is the least of the lanes'
    // values.
    let mut rng = Lcg(57);
    let mut found = 0;
    for i in 0..200_000 {
        let centre = rng.vec() * 4.0 + Vec3::splat([1.0, 10.0, 100.0][i % 3]);
        let (e1, e2) = (rng.dir() * 4.0, rng.dir() * 1e-2);
        let a = [centre, centre + e1, centre + e2];
        let target = centre + e1 * 0.3 + e2 * 0.3;
        let n = e1.cross(e2).normalize();
        let along = (e1.normalize() + n * 10f32.powi(-((i % 4) as i32) - 1)).normalize();
        let ray = Ray::new(target + n * 1e-4 - along * 1e-3, along);
        let s = RayShear::new(&ray);
        let Some((t32, _)) = t_and_error(&s, ray.origin, a) else {
            continue;
        };
        let Some(h) = intersect_triangle_sheared(&s, ray.origin, a[0], a[1], a[2], f32::INFINITY)
        else {
            continue;
        };
        // Only where the recomputed t is the lower (a NaN t32 fails the check below).
        if h.t >= t32 {
            continue;
        }
        // Lane 1 across the ray at a t between the two.
        let t_mid = 0.5 * (h.t + t32);
        let p = ray.origin + ray.dir * t_mid;
        let (u, v) = ray.dir.any_orthonormal_pair();
        let r = 0.1 * t_mid.max(1e-6);
        let b = [p + u * r, p - u * r + v * r, p - u * r - v * r];
        let Some(hb) = intersect_triangle_sheared(&s, ray.origin, b[0], b[1], b[2], f32::INFINITY)
        else {
            continue;
        };
        if !(h.t < hb.t && hb.t < t32) {
            continue;
        }
        let mut g = TriGroup::PADDING;
        g.set_triangle(0, a);
        g.set_triangle(1, b);
        g.prim[0] = 1;
        g.prim[1] = 0;
        let got = group_closest(&ray, &g, f32::INFINITY, false);
        assert_eq!(
            got.map(|(l, h)| (l, h.t.to_bits())),
            Some((0, h.t.to_bits())),
            "{ray:?} {a:?} {b:?}"
        );
        found += 1;
    }
    assert!(found > 0, "{found}");
}

/// The closest-hit query's answer for two one-group leaves tested in one pass
/// (`RayLeaf::closest_pair`, as `RayLeaves::closest_pair` uses it): the pair's lane
/// (`group * LANES + lane`) and its hit.
fn pair_closest(ray: &Ray, g: [&TriGroup; 2], t_max: f32) -> Option<(usize, TriangleHit)> {
    let s = RayShear::new(ray);
    let lanes = RayLeaf::new(ray, &s).closest_pair(g, t_max)?;
    let prims: [u32; PAIR] = std::array::from_fn(|l| g[l / LANES].prim[l % LANES]);
    least_hit(lanes, &prims, |lane| {
        scalar_lane(g[lane / LANES], lane % LANES, ray, t_max, false)
    })
}

#[test]
fn a_pairs_closest_lane_is_the_scalar_tests_least_t_then_prim_over_both_groups() {
    // Two groups of parallel copies of a triangle stacked along the ray, as in the
    // single-group test above, with the second group's prims lower, so that ties go
    // to it, and its copies often nearer (the far leaf holding the closer hit): the
    // pair's answer is the least (t, prim) of the scalar test's hits over both groups.
    let mut rng = Lcg(37);
    let (mut hits, mut second, mut ties) = (0, 0, 0);
    for i in 0..20_000 {
        let Aimed {
            centre,
            e1,
            e2,
            target,
            ray,
        } = Aimed::new(&mut rng, i);
        let (origin, dir) = (ray.origin, ray.dir);
        let mut g = [TriGroup::PADDING; 2];
        for (k, group) in g.iter_mut().enumerate() {
            let lanes = 1 + rng.below(LANES as u32) as usize;
            for lane in 0..lanes {
                let offset = match rng.below(4) {
                    0 => 0.0,
                    1 => 0.25,
                    2 => -(target - origin).length() * (1.0 - 1e-6 * rng.next_f32()),
                    _ => rng.next_f32() - 0.5 * k as f32,
                };
                let shift = dir * offset;
                group.set_triangle(
                    lane,
                    [centre + shift, centre + e1 + shift, centre + e2 + shift],
                );
                group.prim[lane] = ((2 - k) * LANES - lane) as u32 * 10 + rng.below(3);
            }
        }
        let t_max = [f32::INFINITY, 3.0][i % 2];
        let s = RayShear::new(&ray);
        let mut want: Option<(usize, TriangleHit)> = None;
        for lane in 0..PAIR {
            let (k, l) = (lane / LANES, lane % LANES);
            if g[k].is_padding(l) {
                continue;
            }
            let [a, b, c] = g[k].triangle(l);
            let Some(h) = intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max) else {
                continue;
            };
            let prim = |lane: usize| g[lane / LANES].prim[lane % LANES];
            let closer = |&(bl, bh): &(usize, TriangleHit)| {
                h.t < bh.t || (h.t == bh.t && prim(lane) < prim(bl))
            };
            if want.as_ref().is_none_or(closer) {
                if want.is_some_and(|(_, bh)| bh.t == h.t) {
                    ties += 1;
                }
                want = Some((lane, h));
            }
        }
        let got = pair_closest(&ray, [&g[0], &g[1]], t_max);
        let bits = |w: Option<(usize, TriangleHit)>| {
            w.map(|(l, h)| (l, [h.t, h.b0, h.b1, h.b2].map(f32::to_bits)))
        };
        assert_eq!(bits(got), bits(want), "{ray:?} {t_max} {g:?}");
        hits += want.is_some() as usize;
        second += want.is_some_and(|(l, _)| l >= LANES) as usize;
    }
    assert!(
        hits > 10_000 && second > 3_000 && ties > 100,
        "{hits} hits, {second} in the second group, {ties} ties"
    );
}

/// `one_plain_group` holds exactly for leaves of 1 to `LANES` triangles without the
/// degenerate flag, as `leaf_count` reads them.
#[test]
fn one_plain_group_is_one_group_without_the_flag() {
    for count in 0..3 * LANES as u32 {
        for degenerate in [false, true] {
            let (_, c) = leaf_lane(5, count.max(1), degenerate);
            let (n, flag) = leaf_count(c);
            assert_eq!(
                one_plain_group(c),
                (1..=LANES).contains(&n) && !flag,
                "{count} {degenerate}"
            );
        }
    }
    assert!(!one_plain_group(0));
}
