//! Tests of the wide BVH against the binary tree and brute force.

use super::*;
use crate::accel::leaf::{DEGENERATE, LANES, NO_PRIM, PAIR, leaf_count};
use crate::accel::triangle::{RayShear, TriangleHit, intersect_triangle_sheared};
use crate::accel::{BvhNode, Ray, SplitMethod};
use crate::test_util::Lcg;
use glam::vec3;

type Tri = [Vec3; 3];

fn random_tris(n: usize, seed: u64) -> Vec<Tri> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|_| {
            let c = rng.vec() * 10.0 - Vec3::splat(5.0);
            [c, c + rng.dir() * 0.5, c + rng.dir() * 0.5]
        })
        .collect()
}

/// A grid of quads in the plane y = 0: rays through shared edges and vertices.
fn grid(n: usize) -> Vec<Tri> {
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let p = |a: usize, b: usize| vec3(a as f32, 0.0, b as f32);
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    tris
}

fn both(tris: &[Tri], split: SplitMethod) -> (Bvh, WideBvh) {
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let bvh = Bvh::build(&bounds, split);
    let wide = WideBvh::collapse(&bvh, tris);
    (bvh, wide)
}

/// The trees the collapse tests walk, with their split: a few random triangles, many
/// (binned SAH and median) from seeds `seed` and `seed + 1`, and a grid of `grid_n`².
fn sample_trees(few: usize, many: usize, seed: u64, grid_n: usize) -> [(Vec<Tri>, SplitMethod); 4] {
    [
        (random_tris(few, seed), SplitMethod::SahBinned),
        (random_tris(many, seed + 1), SplitMethod::SahBinned),
        (random_tris(many, seed + 2), SplitMethod::Median),
        (grid(grid_n), SplitMethod::SahBinned),
    ]
}

fn rays(n: usize, seed: u64) -> Vec<(Ray, f32)> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|i| {
            let o = rng.vec() * 14.0 - Vec3::splat(7.0);
            let mut d = rng.dir();
            // Axis-aligned directions have zero components (inf inverse).
            if i % 10 == 0 {
                d = Vec3::ZERO;
                d[i / 10 % 3] = if i % 20 == 0 { 1.0 } else { -1.0 };
            }
            let t_max = if i % 3 == 0 { 4.0 } else { f32::INFINITY };
            (Ray::new(o, d * (0.5 + rng.next_f32())), t_max)
        })
        .collect()
}

fn binary_closest(bvh: &Bvh, tris: &[Tri], ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
    let s = RayShear::new(ray);
    bvh.closest_hit(ray, t_max, &mut (), |p, t| {
        let [a, b, c] = tris[p as usize];
        intersect_triangle_sheared(&s, ray.origin, a, b, c, t).map(|h| h.t)
    })
}

#[test]
fn empty_wide_bvh_never_hits_and_validates() {
    let w = WideBvh::collapse(&Bvh::default(), &[]);
    assert!(w.validate(&[]).is_ok());
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(w.closest_hit(&r, f32::INFINITY).is_none());
    assert!(!w.any_hit(&r, f32::INFINITY, |_, _| true));
}

#[test]
fn collapsed_trees_validate_and_are_wide() {
    for (tris, split) in sample_trees(3, 2000, 1, 20) {
        let (bvh, wide) = both(&tris, split);
        wide.validate(&tris).unwrap();
        if tris.len() > 100 {
            // Each wide node replaces up to three binary interior nodes (fewer where
            // leaves take its slots).
            let interior = bvh.nodes.len() - bvh.leaf_count();
            let wide_nodes = wide.nodes.len();
            assert!(3 * wide_nodes < 2 * interior, "{wide_nodes} for {interior}");
        }
    }
}

#[test]
fn validate_catches_a_shrunken_box_and_a_wrong_triangle() {
    let tris = random_tris(500, 4);
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    let mut bad = wide.clone();
    let lane = (0..WIDTH)
        .find(|&l| bad.nodes[0].child[l] != EMPTY)
        .unwrap();
    bad.nodes
        .modify(|n| n[0].bounds[3][lane] = n[0].bounds[0][lane]);
    assert!(bad.validate(&tris).is_err());
    let mut bad = wide.clone();
    bad.leaves.groups.modify(|g| g[0].v[0][0][0] += 1.0);
    assert!(bad.validate(&tris).is_err());
    // A padding lane that could hit: a copy of lane 0's triangle.
    let mut bad = wide.clone();
    let g = bad.nodes.iter().find_map(|n| {
        (0..WIDTH).find_map(|l| (1..4).contains(&n.count[l]).then_some(n.child[l] as usize))
    });
    bad.leaves.groups.modify(|groups| {
        for axis in groups[g.unwrap()].v.iter_mut().flatten() {
            axis[3] = axis[0];
        }
    });
    assert!(bad.validate(&tris).is_err());
}

#[test]
fn validate_catches_a_wrong_triangle_index_in_a_lane() {
    let tris = random_tris(500, 4);
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    wide.validate(&tris).unwrap();
    let prims: Vec<u32> = wide.leaves.prims().collect();
    let padding = prims.iter().position(|&p| p == NO_PRIM).unwrap();
    fn set_prim(w: &mut WideBvh, lane: usize, prim: u32) {
        w.leaves
            .groups
            .modify(|g| g[lane / LANES].prim[lane % LANES] = prim);
    }
    let mut broken = Vec::new();
    // Two lanes' indices swapped: each names the other's vertices.
    let mut bad = wide.clone();
    bad.leaves.groups.modify(|g| g[0].prim.swap(0, 1));
    broken.push(bad);
    // A padding lane naming a triangle, a triangle's lane naming none.
    let mut bad = wide.clone();
    set_prim(&mut bad, padding, prims[0]);
    broken.push(bad);
    let mut bad = wide.clone();
    set_prim(&mut bad, 0, NO_PRIM);
    broken.push(bad);
    // A wrong count.
    let mut bad = wide.clone();
    bad.triangles -= 1;
    broken.push(bad);
    for (i, bad) in broken.iter().enumerate() {
        assert!(bad.validate(&tris).is_err(), "case {i}");
    }
}

#[test]
fn closest_and_any_hit_match_the_binary_tree() {
    for (tris, seed) in [(random_tris(3000, 5), 6), (grid(16), 7)] {
        let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
        let mut hits = 0;
        for (ray, t_max) in rays(4000, seed) {
            let expect = binary_closest(&bvh, &tris, &ray, t_max);
            let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
            assert_eq!(got, expect, "{ray:?}");
            hits += got.is_some() as u32;
            assert_eq!(
                wide.any_hit(&ray, t_max, |_, _| true),
                expect.is_some(),
                "{ray:?}"
            );
        }
        assert!(hits > 100, "only {hits} hits");
    }
}

#[test]
fn rays_along_the_grid_edges_never_slip_through() {
    // Straight down through every vertex and edge midpoint of the grid.
    let tris = grid(8);
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    for i in 0..=16 {
        for j in 0..=16 {
            let o = vec3(i as f32 * 0.5, 1.0, j as f32 * 0.5);
            let inside = (0.0..=8.0).contains(&o.x) && (0.0..=8.0).contains(&o.z);
            let hit = wide.closest_hit(&Ray::new(o, -Vec3::Y), f32::INFINITY);
            assert_eq!(hit.is_some(), inside, "{o}");
            if let Some((_, h)) = hit {
                assert_eq!(h.t, 1.0);
            }
        }
    }
}

#[test]
fn deep_trees_still_match() {
    // A binary chain (leaf k beside the subtree of leaves k+1..), as a builder could
    // make at its depth limit: the wide tree takes three of its levels per level,
    // which is still far deeper than a balanced tree of any size.
    let n = 72;
    let tris: Vec<Tri> = (0..n)
        .map(|k| {
            let x = k as f32;
            [vec3(x, -1.0, -1.0), vec3(x, 1.0, -1.0), vec3(x, 0.0, 1.0)]
        })
        .collect();
    let boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let rest = |k: usize| boxes[k..].iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    let mut nodes = Vec::new();
    for (k, &b) in boxes[..n - 1].iter().enumerate() {
        let i = nodes.len() as u32;
        nodes.push(crate::accel::BvhNode::interior(rest(k), i + 2));
        nodes.push(crate::accel::BvhNode::leaf(b, k as u32, 1));
    }
    nodes.push(crate::accel::BvhNode::leaf(boxes[n - 1], n as u32 - 1, 1));
    let bvh = Bvh {
        nodes: nodes.into(),
        prim_indices: (0..n as u32).collect::<Vec<u32>>().into(),
    };
    let wide = WideBvh::collapse(&bvh, &tris);
    wide.validate(&tris).unwrap();
    assert!(wide.depth >= 9, "depth {}", wide.depth);
    let brute = |ray: &Ray, t_max: f32| {
        let s = RayShear::new(ray);
        let mut best: Option<(u32, f32)> = None;
        for (p, &[a, b, c]) in tris.iter().enumerate() {
            let bound = best.map_or(t_max, |b| b.1);
            if let Some(h) = intersect_triangle_sheared(&s, ray.origin, a, b, c, bound) {
                best = Some((p as u32, h.t));
            }
        }
        best
    };
    let mut hits = 0;
    for (ray, t_max) in rays(2000, 9) {
        let ray = Ray::new(ray.origin + vec3(36.0, 0.0, 0.0), ray.dir);
        let got = wide.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t));
        assert_eq!(got, brute(&ray, t_max), "{ray:?}");
        hits += got.is_some() as u32;
    }
    assert!(hits > 30, "only {hits} hits");
    let mut shallow = wide.clone();
    shallow.depth = 0;
    assert!(shallow.validate(&tris).is_err());
}

#[test]
fn a_tie_at_a_shared_edge_goes_to_the_lowest_index_in_both_trees() {
    // Straight down onto the shared diagonal of every quad of the grid.
    let tris = grid(8);
    let (bvh, wide) = both(&tris, SplitMethod::SahBinned);
    for i in 0..8 {
        for j in 0..8 {
            let o = vec3(i as f32 + 0.25, 1.0, j as f32 + 0.25);
            let ray = Ray::new(o, -Vec3::Y);
            let quad = 2 * (i * 8 + j) as u32;
            let expect = Some((quad, 1.0));
            assert_eq!(binary_closest(&bvh, &tris, &ray, f32::INFINITY), expect);
            let got = wide.closest_hit(&ray, f32::INFINITY).map(|(p, h)| (p, h.t));
            assert_eq!(got, expect);
        }
    }
}

#[test]
fn any_hit_visits_every_crossing_until_told_to_stop() {
    // Ten parallel planes of two triangles each, crossed by one ray.
    let tris: Vec<Tri> = (0..10)
        .flat_map(|k| {
            let z = k as f32;
            [
                [vec3(-1., -1., z), vec3(1., -1., z), vec3(1., 1., z)],
                [vec3(-1., -1., z), vec3(1., 1., z), vec3(-1., 1., z)],
            ]
        })
        .collect();
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    let ray = Ray::new(vec3(0.3, -0.2, -1.0), Vec3::Z);
    let mut seen = Vec::new();
    assert!(!wide.any_hit(&ray, 20.0, |p, h| {
        seen.push((p / 2, h.t));
        false
    }));
    seen.sort_by(|a, b| a.1.total_cmp(&b.1));
    assert_eq!(seen.len(), 10);
    assert!(seen.iter().enumerate().all(|(k, s)| s.0 == k as u32));
    let mut n = 0;
    assert!(wide.any_hit(&ray, 20.0, |_, _| {
        n += 1;
        n == 3
    }));
    assert_eq!(n, 3);
}

#[test]
fn any_hit_visits_each_triangle_with_the_scalar_tests_hit() {
    // Every hit the any-hit query reports, barycentrics too, is the scalar test's bit for
    // bit (its leaves take decided lanes from the prefilter's values), and none is missed.
    let bits = |p: u32, h: &TriangleHit| (p, [h.t, h.b0, h.b1, h.b2].map(f32::to_bits));
    let tris = random_tris(3000, 8);
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    let mut visits = 0;
    for (ray, t_max) in rays(1500, 9) {
        let mut seen = Vec::new();
        wide.any_hit(&ray, t_max, |p, h| {
            seen.push(bits(p, h));
            false
        });
        seen.sort();
        let s = RayShear::new(&ray);
        let expect: Vec<_> = (0..tris.len() as u32)
            .filter_map(|p| {
                let [a, b, c] = tris[p as usize];
                intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).map(|h| bits(p, &h))
            })
            .collect();
        assert_eq!(seen, expect, "{ray:?}");
        visits += seen.len();
    }
    assert!(visits > 300, "only {visits} visits");
}

#[test]
fn dispatched_queries_match_the_baseline_build_bit_for_bit() {
    // `closest_hit` runs the clone for this CPU's features (AVX2+FMA here where the CPU
    // has it); `*_inlined` called from this test is compiled for the baseline target.
    for (tris, seed) in [(random_tris(3000, 11), 12), (grid(16), 13)] {
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        for (ray, t_max) in rays(4000, seed) {
            let bits = |h: Option<(u32, u32, TriangleHit)>| {
                h.map(|(p, lane, h)| (p, lane, [h.t, h.b0, h.b1, h.b2].map(f32::to_bits)))
            };
            assert_eq!(
                bits(wide.closest_hit_at(&ray, t_max)),
                bits(wide.closest_hit_inlined(&ray, t_max)),
                "{ray:?}"
            );
            let (mut fast, mut base) = (Vec::new(), Vec::new());
            wide.any_hit(&ray, t_max, |p, h| {
                fast.push((p, h.t.to_bits()));
                false
            });
            wide.any_hit_inlined(&ray, 0, t_max, |p, h| {
                base.push((p, h.t.to_bits()));
                false
            });
            assert_eq!(fast, base, "{ray:?}");
        }
    }
}

/// The least (index, t) of all triangles hit in (0, t_max), by (t, index), and whether
/// the next distinct t is so close that rounding in the box tests may hide either.
fn brute_closest(tris: &[Tri], ray: &Ray, t_max: f32) -> (Option<(u32, f32)>, bool) {
    let s = RayShear::new(ray);
    let mut hits: Vec<(u32, f32)> = tris
        .iter()
        .enumerate()
        .filter_map(|(p, &[a, b, c])| {
            intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).map(|h| (p as u32, h.t))
        })
        .collect();
    hits.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
    let best = hits.first().copied();
    let near_tie =
        best.is_some_and(|(_, t)| hits.iter().any(|h| h.1 != t && h.1 < t * (1.0 + 1e-5)));
    (best, near_tie)
}

/// The wide BVH's closest hit on `ray` (unbounded), asserted equal to [`brute_closest`]'s;
/// `None` where a near tie lets rounding in the box tests pick either.
fn checked_closest(wide: &WideBvh, tris: &[Tri], ray: &Ray) -> Option<Option<(u32, f32)>> {
    let (expect, near_tie) = brute_closest(tris, ray, f32::INFINITY);
    if near_tie {
        return None;
    }
    let got = wide.closest_hit(ray, f32::INFINITY).map(|(p, h)| (p, h.t));
    assert_eq!(got, expect, "{ray:?}");
    Some(got)
}

#[test]
fn exact_ties_on_box_faces_go_to_the_lowest_index() {
    // Boxes on an integer lattice, touching and overlapping, so that many triangles lie
    // in the planes of their neighbours' leaf boxes and rays through lattice points and
    // edges meet several at exactly the same t: the hit must be the least (t, index)
    // whichever leaf the traversal meets first. (Hits within rounding of each other but
    // not equal may go either way: the box tests' margins do not cover the triangle
    // test's own error.)
    let mut rng = Lcg(21);
    let mut tris: Vec<Tri> = Vec::new();
    for _ in 0..300 {
        let lo = (rng.vec() * 8.0).floor();
        let hi = lo + (rng.vec() * 3.0).floor() + Vec3::ONE;
        let m = crate::test_util::cube(lo, hi);
        tris.extend((0..m.tris.len()).map(|i| {
            let (a, b, c) = m.tri(i);
            [a, b, c]
        }));
    }
    let (binary, wide) = both(&tris, SplitMethod::SahBinned);
    let (mut ties, mut checked) = (0, 0);
    for i in 0..6000 {
        let target = (rng.vec() * 11.0).floor();
        let target = if i % 2 == 0 {
            target
        } else {
            target + Vec3::X * rng.next_f32()
        };
        let origin = rng.vec() * 30.0 - Vec3::splat(10.0);
        let ray = Ray::new(origin, target - origin);
        let Some(expect) = checked_closest(&wide, &tris, &ray) else {
            continue;
        };
        // The binary tree (what the debug observes) agrees.
        let got = binary_closest(&binary, &tris, &ray, f32::INFINITY);
        assert_eq!(got, expect, "binary tree: {ray:?}");
        checked += 1;
        let s = RayShear::new(&ray);
        ties += expect.is_some_and(|(p, t)| {
            tris.iter().enumerate().any(|(q, &[a, b, c])| {
                q as u32 != p
                    && intersect_triangle_sheared(&s, ray.origin, a, b, c, f32::INFINITY)
                        .is_some_and(|h| h.t == t)
            })
        }) as u32;
    }
    assert!(
        checked > 3000 && ties > 300,
        "{checked} rays checked, {ties} exact ties"
    );
}

#[test]
fn two_group_leaves_give_the_least_hit_over_both_groups() {
    // Clusters of 5 to 8 triangles, each spanning the same unit cube (the diagonal
    // and a third vertex inside), far apart: their centroids coincide, so each cluster
    // is one leaf of two groups (the collapse's largest), whose hit must be the least
    // (t, index) over both groups, whichever way the closest-hit query tests them.
    let mut rng = Lcg(33);
    let h = Vec3::splat(0.5);
    let mut tris: Vec<Tri> = Vec::new();
    let mut centres = Vec::new();
    for k in 0..200 {
        let c = rng.vec() * 60.0;
        centres.push(c);
        for _ in 0..5 + k % 4 {
            tris.push([c - h, c + h, c + (rng.vec() * 2.0 - Vec3::ONE) * h]);
        }
    }
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    // Inner and unused lanes count 0.
    let counts = wide.nodes.iter().flat_map(|n| n.count);
    let two_groups = counts.filter(|&c| (LANES + 1..=PAIR).contains(&leaf_count(c).0));
    assert_eq!(two_groups.count(), 200);
    let (mut checked, mut hits) = (0, 0);
    for _ in 0..4000 {
        let target = centres[(rng.next_f32() * 200.0) as usize % 200] + (rng.vec() - h) * 0.8;
        let origin = rng.vec() * 80.0 - Vec3::splat(10.0);
        if let Some(hit) = checked_closest(&wide, &tris, &Ray::new(origin, target - origin)) {
            checked += 1;
            hits += hit.is_some() as u32;
        }
    }
    assert!(
        checked > 3000 && hits > 2000,
        "{checked} checked, {hits} hits"
    );
}

#[test]
fn each_triangle_reads_its_own_vertices_from_the_leaves() {
    for tris in [random_tris(1, 8), random_tris(2000, 9), grid(9)] {
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        let lanes = wide.prim_lanes();
        for (p, tri) in tris.iter().enumerate() {
            assert_eq!(wide.triangle_at(lanes[p]), *tri);
        }
        assert_eq!(wide.positions(), tris);
    }
    // Without acceleration: one leaf of many groups.
    let tris = random_tris(37, 10);
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let wide = WideBvh::collapse(&Bvh::single_leaf(&bounds), &tris);
    wide.validate(&tris).unwrap();
    assert_eq!(wide.positions(), tris);
}

#[test]
fn closest_hits_lead_to_their_triangles_vertices() {
    // The last: without acceleration, one leaf of many groups.
    for (tris, single) in [
        (random_tris(2000, 11), false),
        (grid(9), false),
        (random_tris(37, 10), true),
    ] {
        let wide = if single {
            let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
            WideBvh::collapse(&Bvh::single_leaf(&bounds), &tris)
        } else {
            both(&tris, SplitMethod::SahBinned).1
        };
        let mut found = 0;
        for (ray, t_max) in rays(2000, 14) {
            let Some((p, lane, h)) = wide.closest_hit_at(&ray, t_max) else {
                continue;
            };
            assert_eq!(wide.triangle_at(lane), tris[p as usize], "{ray:?}");
            assert_eq!(wide.closest_hit(&ray, t_max), Some((p, h)));
            found += 1;
        }
        assert!(found > 5, "{found} hits");
    }
}

#[test]
fn degenerate_triangles_are_flagged_and_never_hit() {
    // Zero-area triangles (exactly collinear: small dyadic coordinates) among ordinary
    // ones, and rays aimed at points of their segments: rounding in the shear can give
    // such a triangle a nonzero det of one sign, which only the exact test rejects, so
    // their leaves must carry the flag that keeps it.
    let mut rng = Lcg(31);
    let mut tris = random_tris(300, 32);
    let ordinary = tris.len() as u32;
    for _ in 0..60 {
        let p = ((rng.vec() * 64.0).floor() - Vec3::splat(32.0)) / 8.0;
        let d = ((rng.vec() * 16.0).floor() - Vec3::splat(8.0)) / 16.0;
        tris.push([p, p + d, p + 3.0 * d]);
    }
    let (_, wide) = both(&tris, SplitMethod::SahBinned);
    wide.validate(&tris).unwrap();
    let flagged: Vec<(usize, usize)> = (0..wide.nodes.len())
        .flat_map(|i| (0..WIDTH).map(move |l| (i, l)))
        .filter(|&(i, l)| wide.nodes[i].count[l] & DEGENERATE != 0)
        .collect();
    assert!(!flagged.is_empty());
    let mut aimed = 0;
    for i in 0..30_000 {
        let [a, _, c] = tris[ordinary as usize + i % 60];
        let target = a.lerp(c, rng.next_f32());
        let origin = target + rng.dir() * (1.0 + 3.0 * rng.next_f32());
        let ray = Ray::new(origin, target - origin);
        let Some(got) = checked_closest(&wide, &tris, &ray) else {
            continue;
        };
        assert!(got.is_none_or(|(p, _)| p < ordinary), "{ray:?}");
        wide.any_hit(&ray, f32::INFINITY, |p, _| {
            assert!(p < ordinary, "{ray:?}");
            false
        });
        aimed += 1;
    }
    assert!(aimed > 20_000, "{aimed} rays");
    // A missing flag, or one on a leaf of ordinary triangles, fails validation.
    let mut bad = wide.clone();
    let (i, l) = flagged[0];
    bad.nodes.modify(|n| n[i].count[l] &= !DEGENERATE);
    assert!(bad.validate(&tris).is_err());
    let mut bad = wide.clone();
    let (i, l) = (0..wide.nodes.len())
        .flat_map(|i| (0..WIDTH).map(move |l| (i, l)))
        .find(|&(i, l)| (1..DEGENERATE).contains(&wide.nodes[i].count[l]))
        .unwrap();
    bad.nodes.modify(|n| n[i].count[l] |= DEGENERATE);
    assert!(bad.validate(&tris).is_err());
}

/// Records the x range of each leaf the traversal visits and lowers the cull distance
/// to the leaf's nearest square on a ray along x from `origin_x` (squares across x).
struct NearestSquare<'a> {
    wide: &'a WideBvh,
    origin_x: f32,
    visited: Vec<(f32, f32)>,
}

impl LeafVisitor for NearestSquare<'_> {
    fn leaf(&mut self, group: usize, count: u32, t_max: &mut f32) -> bool {
        let (count, _) = crate::accel::leaf::leaf_count(count);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for g in group..group + groups_for(count) {
            for lane in 0..LANES {
                if self.wide.leaves.groups[g].prim[lane] != NO_PRIM {
                    let x = self.wide.leaves.groups[g].triangle(lane)[0].x;
                    (lo, hi) = (lo.min(x), hi.max(x));
                    *t_max = t_max.min((x - self.origin_x).abs());
                }
            }
        }
        self.visited.push((lo, hi));
        false
    }
}

/// The closest-hit traversal visits nodes nearest first and culls what lies beyond the
/// hits found: on rays along x through rows of clusters of squares across x, far apart
/// (so that the ray meets two and more interior children of a node), every leaf it
/// visits lies in the nearest cluster, from either side.
#[test]
fn closest_hit_traversal_visits_the_nearest_cluster_alone() {
    for (rows, columns) in [(4, 2), (2, 3), (1, 2), (1, 5)] {
        // 150 squares per cluster, 1 apart; clusters 1,000 apart in x and in y.
        let tris: Vec<Tri> = (0..rows * columns * 150)
            .flat_map(|i| {
                let (cluster, k) = (i / 150, i % 150);
                let x = (cluster % columns * 1000 + k) as f32;
                let y = (cluster / columns * 1000) as f32;
                let p = |dy: f32, z: f32| vec3(x, y + dy, z);
                [
                    [p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0)],
                    [p(-1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)],
                ]
            })
            .collect();
        let (_, wide) = both(&tris, SplitMethod::SahBinned);
        let last = ((columns - 1) * 1000 + 149) as f32;
        for row in 0..rows {
            let y = (row * 1000) as f32 + 0.1;
            let sides = [
                (-1.0, 1.0, 0.0..=149.0),
                (last + 1.0, -1.0, last - 149.0..=last),
            ];
            for (origin_x, dir, near) in sides {
                let ray = Ray::new(vec3(origin_x, y, 0.2), vec3(dir, 0.0, 0.0));
                let mut visitor = NearestSquare {
                    wide: &wide,
                    origin_x,
                    visited: Vec::new(),
                };
                let mut t_max = f32::INFINITY;
                wide.traverse::<true>(0, &RayBoxes::new(&ray), &mut t_max, &mut visitor);
                assert_eq!(t_max, 1.0, "{rows}x{columns} clusters, {ray:?}");
                for &(lo, hi) in &visitor.visited {
                    assert!(
                        near.contains(&lo) && near.contains(&hi),
                        "{rows}x{columns} clusters, {ray:?}: a leaf over x {lo}..{hi}"
                    );
                }
            }
        }
    }
}

#[path = "wide_collapse_tests.rs"]
mod collapse;

#[test]
fn the_wide_bvh_is_the_same_whichever_memory_backs_it() {
    // Small (below a huge page: a Vec with `Auto`) and large (about 3 MiB of leaf
    // groups: mapped with `Auto`), each built on every backing.
    for (n, large) in [(2000, false), (80_000, true)] {
        let tris = random_tris(n, 31);
        let (bvh, auto) = both(&tris, SplitMethod::SahBinned);
        assert_eq!(auto.leaves.groups.is_mapped(), large);
        let heap = WideBvh::collapse_backed(&bvh, &tris, Backing::Heap);
        let mapped = WideBvh::collapse_backed(&bvh, &tris, Backing::Mapped);
        assert!(!heap.nodes.is_mapped() && !heap.leaves.groups.is_mapped());
        assert!(mapped.nodes.is_mapped() && mapped.leaves.groups.is_mapped());
        let bits = |w: &WideBvh| -> Vec<u32> {
            let v = w
                .leaves
                .groups
                .iter()
                .flat_map(|g| g.v.as_flattened().as_flattened());
            v.map(|x| x.to_bits()).collect()
        };
        for w in [&heap, &mapped, &mapped.clone(), &heap.clone()] {
            w.validate(&tris).unwrap();
            assert_eq!(w.nodes, auto.nodes);
            assert!(w.leaves.prims().eq(auto.leaves.prims()));
            assert_eq!(bits(w), bits(&auto));
            assert_eq!(
                (w.triangles, w.depth, w.bytes()),
                (auto.triangles, auto.depth, auto.bytes())
            );
        }
        assert!(mapped.clone().nodes.is_mapped() && !heap.clone().nodes.is_mapped());
        for (ray, t_max) in rays(2000, 32) {
            let want = auto
                .closest_hit(&ray, t_max)
                .map(|(p, h)| (p, h.t.to_bits()));
            let occluded = auto.any_hit(&ray, t_max, |_, _| true);
            for w in [&heap, &mapped] {
                let got = w.closest_hit(&ray, t_max).map(|(p, h)| (p, h.t.to_bits()));
                assert_eq!(got, want, "{ray:?}");
                assert_eq!(w.any_hit(&ray, t_max, |_, _| true), occluded);
            }
        }
    }
}
