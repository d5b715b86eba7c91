//! Tests of the spatial splits: the tree they make over long thin triangles, its
//! validation, its hits against brute force, and the cut of one triangle.

use super::*;
use crate::accel::leaf::{LANES, leaf_count};
use crate::accel::triangle::{RayShear, intersect_triangle_sheared};
use crate::accel::wide_node::{EMPTY, WIDTH};
use crate::accel::{Ray, WideBvh};
use crate::test_util::Lcg;

type Tri = [Vec3; 3];

/// `n` slivers 6 to 10 long along an axis and 0.02 to 0.1 wide in [-7, 7]³, as
/// Sponza's columns, beams and floor strips are (boxes that overlap a lot), every
/// fourth a small triangle.
fn slivers(n: usize, seed: u64) -> Vec<Tri> {
    let mut rng = Lcg(seed);
    (0..n)
        .map(|i| {
            let a = rng.vec() * 8.0 - Vec3::splat(4.0);
            if i % 4 == 0 {
                return [a, a + rng.dir() * 0.3, a + rng.dir() * 0.3];
            }
            let mut long = Vec3::ZERO;
            long[i % 3] = 6.0 + 4.0 * rng.next_f32();
            let wide = rng.dir() * (0.02 + 0.08 * rng.next_f32());
            [a - 0.5 * long, a + 0.5 * long + wide * 0.1, a + wide]
        })
        .collect()
}

fn object_tree(tris: &[Tri]) -> Bvh {
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    Bvh::build(&bounds, SplitMethod::SahBinned)
}

/// The closest hit by brute force, ties to the lower index, and whether another hit
/// lies within a relative 1e-5 of it (where rounding in the box tests may pick either).
fn brute_closest(tris: &[Tri], ray: &Ray) -> (Option<(u32, f32)>, bool) {
    let s = RayShear::new(ray);
    let mut hits: Vec<(u32, f32)> = tris
        .iter()
        .enumerate()
        .filter_map(|(p, &[a, b, c])| {
            intersect_triangle_sheared(&s, ray.origin, a, b, c, f32::INFINITY)
                .map(|h| (p as u32, h.t))
        })
        .collect();
    hits.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)));
    let best = hits.first().copied();
    let near_tie =
        best.is_some_and(|(_, t)| hits.iter().any(|h| h.1 != t && h.1 < t * (1.0 + 1e-5)));
    (best, near_tie)
}

#[test]
fn spatial_splits_cut_slivers_lower_the_sah_cost_and_find_every_hit() {
    let tris = slivers(3000, 5);
    let object = object_tree(&tris);
    let bvh = Bvh::build_triangles(&tris, SplitMethod::SahBinned);
    let n = tris.len();
    // Some triangles cut, within the budget (rounding may add one per split).
    assert!(
        bvh.prim_indices.len() > n + n / 20,
        "{}",
        bvh.prim_indices.len()
    );
    assert!(bvh.prim_indices.len() <= n + (BUDGET * n as f32) as usize + n / 100);
    assert!(
        bvh.sah_cost() < 0.9 * object.sah_cost(),
        "{} vs {}",
        bvh.sah_cost(),
        object.sah_cost()
    );
    let wide = WideBvh::collapse(&bvh, &tris);
    assert_eq!(wide.triangles, n);
    wide.validate(&tris).unwrap();
    // Every lane `prim_lanes` names holds its triangle.
    for (p, &lane) in wide.prim_lanes().iter().enumerate() {
        assert_eq!(wide.triangle_at(lane), tris[p]);
    }
    let mut rng = Lcg(11);
    let mut checked = 0;
    for i in 0..4000 {
        // From inside the slivers' cloud, and from outside towards it.
        let o = rng.vec() * 16.0 - Vec3::splat(8.0);
        let d = if i % 2 == 0 {
            rng.dir()
        } else {
            (rng.vec() * 4.0 - Vec3::splat(2.0) - o).normalize()
        };
        let ray = Ray::new(o, d);
        let (expect, near_tie) = brute_closest(&tris, &ray);
        let t_max = expect.map_or(f32::INFINITY, |(_, t)| t * 0.999);
        let s = RayShear::new(&ray);
        let any = tris
            .iter()
            .any(|&[a, b, c]| intersect_triangle_sheared(&s, ray.origin, a, b, c, t_max).is_some());
        assert_eq!(wide.any_hit(&ray, t_max, |_, _| true), any, "ray {i}");
        if near_tie {
            continue;
        }
        let got = wide.closest_hit(&ray, f32::INFINITY).map(|(p, h)| (p, h.t));
        assert_eq!(got, expect, "ray {i}");
        checked += 1;
    }
    assert!(checked > 3000);
}

#[test]
fn spheres_and_non_finite_triangles_keep_the_object_build() {
    let mut tris = slivers(200, 6);
    let object = object_tree(&tris);
    // Object splits only with the median.
    let median = Bvh::build_triangles(&tris, SplitMethod::Median);
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    assert_eq!(
        median.tree_hash(),
        Bvh::build(&bounds, SplitMethod::Median).tree_hash()
    );
    assert_ne!(
        Bvh::build_triangles(&tris, SplitMethod::SahBinned).tree_hash(),
        object.tree_hash()
    );
    tris[7][1].x = f32::NAN;
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let b = Bvh::build_triangles(&tris, SplitMethod::SahBinned);
    assert_eq!(
        b.tree_hash(),
        Bvh::build(&bounds, SplitMethod::SahBinned).tree_hash()
    );
}

#[test]
fn validate_accepts_cut_triangles_and_catches_a_missing_one_and_a_shrunk_box() {
    let tris = slivers(1000, 7);
    let wide = WideBvh::collapse(&Bvh::build_triangles(&tris, SplitMethod::SahBinned), &tris);
    wide.validate(&tris).unwrap();
    // A triangle in no leaf.
    let mut more = tris.clone();
    more.push(tris[0]);
    let mut bad = wide.clone();
    bad.triangles += 1;
    assert!(bad.validate(&more).unwrap_err().contains("in no leaf"));
    // A leaf holding part of a cut triangle, its box shrunk to its lower corner.
    let (node, lane) = (0..wide.nodes.len())
        .flat_map(|i| (0..WIDTH).map(move |l| (i, l)))
        .find(|&(i, l)| {
            let n = &wide.nodes[i];
            let b = n.child_bounds(l);
            n.child[l] != EMPTY
                && n.count[l] != 0
                && (0..leaf_count(n.count[l]).0).any(|k| {
                    let lane = n.child[l] as usize * LANES + k;
                    !b.contains_box(&Aabb::from_points(&wide.triangle_at(lane as u32)))
                })
        })
        .expect("a leaf with part of a triangle");
    let mut bad = wide.clone();
    bad.nodes.modify(|n| {
        for axis in 0..3 {
            n[node].bounds[3 + axis][lane] = n[node].bounds[axis][lane];
        }
    });
    assert!(bad.validate(&tris).is_err());
}

#[test]
fn a_cut_triangle_s_parts_hold_the_exact_crossings() {
    let tri = [
        Vec3::ZERO,
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 1.0),
    ];
    let b = PrimRef::new(0, &Aabb::from_points(&tri)).box4();
    let (l, r) = clip::<true>(&tri, &b, 0, 1.0);
    // Left: x in [0, 1], y up to 3 (the corner), z up to 1; right: x in [1, 3], y up
    // to where the long edge crosses x = 1 (2), z up to 2/3. Outward by an ulp at most.
    let close =
        |got: f32, want: f32| (got - want).abs() <= 2.0 * f32::EPSILON * want.abs().max(1.0);
    assert_eq!(
        (l.min[0], l.max[0], r.min[0], r.max[0]),
        (0.0, 1.0, 1.0, 3.0)
    );
    assert!(close(l.max[1], 3.0) && close(l.max[2], 1.0));
    assert!(r.max[1] >= 2.0 && close(r.max[1], 2.0));
    assert!(r.max[2] >= 2.0 / 3.0 && close(r.max[2], 2.0 / 3.0));
    assert!(r.min[1] <= 0.0 && r.min[2] <= 0.0);
    // A plane beside the triangle leaves one side empty.
    let (l, r) = clip::<true>(&tri, &b, 0, 3.5);
    assert!(r.aabb().is_empty() && !l.aabb().is_empty());
}

#[test]
fn the_tree_is_the_same_on_one_thread_and_on_four() {
    // Enough triangles that the object build below the spatial splits runs in parallel.
    let tris = slivers(30_000, 8);
    let build = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| Bvh::build_triangles(&tris, SplitMethod::SahBinned))
    };
    let (one, many) = (build(1), build(4));
    assert!(one.prim_indices.len() > tris.len());
    assert_eq!(one.nodes, many.nodes);
    assert_eq!(one.prim_indices, many.prim_indices);
    WideBvh::collapse(&one, &tris).validate(&tris).unwrap();
}

/// `triangle_bounds` is `Aabb::from_points` per triangle, their `union` and the
/// finiteness of every coordinate, bit for bit, on coordinates with signed zeros, NaN
/// and infinities (whose order decides `min` and `max`).
#[test]
fn triangle_bounds_match_the_scalar_boxes_bit_for_bit() {
    let mut rng = Lcg(41);
    let special = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    let coordinate = |rng: &mut Lcg| {
        let k = (rng.next_f32() * 10.0) as usize;
        special
            .get(k)
            .copied()
            .unwrap_or_else(|| rng.next_f32() * 4.0 - 2.0)
    };
    for n in [1, 2, 7, 100] {
        let tris: Vec<Tri> = (0..n)
            .map(|_| {
                [0; 3].map(|_| {
                    Vec3::new(
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                        coordinate(&mut rng),
                    )
                })
            })
            .collect();
        let (bounds, finite, root) = triangle_bounds(&tris);
        let bits = |b: &Aabb| [b.min.to_array(), b.max.to_array()].map(|v| v.map(f32::to_bits));
        let mut want_root = Aabb::EMPTY;
        for (t, b) in tris.iter().zip(&bounds) {
            let want = Aabb::from_points(t);
            assert_eq!(bits(b), bits(&want), "{t:?}");
            want_root = want_root.union(want);
        }
        assert_eq!(bits(&root), bits(&want_root));
        assert_eq!(finite, tris.iter().flatten().all(|v| v.is_finite()));
    }
    // All finite: the flag is set.
    assert!(triangle_bounds(&slivers(8, 3)).1);
}
