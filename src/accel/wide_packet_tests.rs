//! Tests of the packet query against the single-ray query, ray by ray.

use super::*;
use crate::accel::triangle::TriangleHit;
use crate::accel::{Aabb, Bvh, Ray, SplitMethod};
use crate::test_util::Lcg;
use glam::vec3;

type Tri = [Vec3; 3];

/// A triangle soup, a grid of quads in the plane y = 0 (shared edges, a plane through
/// zero) and exactly collinear (degenerate) triangles, under one wide BVH.
fn scene() -> (Vec<Tri>, WideBvh) {
    let mut rng = Lcg(5);
    let mut tris: Vec<Tri> = (0..400)
        .map(|_| {
            let c = rng.vec() * 10.0 - Vec3::splat(5.0);
            [c, c + rng.dir() * 0.7, c + rng.dir() * 0.7]
        })
        .collect();
    for i in -4..4 {
        for j in -4..4 {
            let p = |a: i32, b: i32| vec3(a as f32, 0.0, b as f32);
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    for _ in 0..40 {
        let p = ((rng.vec() * 64.0).floor() - Vec3::splat(32.0)) / 8.0;
        let d = ((rng.vec() * 16.0).floor() - Vec3::splat(8.0)) / 16.0;
        tris.push([p, p + d, p + 3.0 * d]);
    }
    let wide = build(&tris);
    (tris, wide)
}

fn build(tris: &[Tri]) -> WideBvh {
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let wide = WideBvh::collapse(&Bvh::build(&bounds, SplitMethod::SahBinned), tris);
    wide.validate(tris).unwrap();
    wide
}

/// A direction with some components exactly 0 or -0 (every fourth ray), else random.
fn direction(rng: &mut Lcg, i: usize) -> Vec3 {
    let mut d = rng.dir();
    if i.is_multiple_of(4) {
        for axis in 0..3 {
            if rng.next_f32() < 0.5 {
                d[axis] = if rng.next_f32() < 0.5 { 0.0 } else { -0.0 };
            }
        }
        if d == Vec3::ZERO {
            d.y = -1.0;
        }
    }
    d
}

/// Bounds: infinite, finite, tiny, and the ray's own first hit (exactly, and just
/// past it), so that hits on the bound itself are decided as the single ray does.
fn bound(rng: &mut Lcg, wide: &WideBvh, ray: &Ray) -> f32 {
    match rng.below(6) {
        0 => f32::INFINITY,
        1 => 4.0 * rng.next_f32(),
        2 => [1e-30, f32::MIN_POSITIVE, 1e-6][rng.below(3) as usize],
        k => match wide.closest_hit(ray, f32::INFINITY) {
            Some((_, h)) if k == 3 => h.t,
            Some((_, h)) => h.t.next_up(),
            None => 2.0,
        },
    }
}

/// Rays of every kind the render and the stress cases make: incoherent (mixed octants
/// and axes), coherent (from one point to nearby targets, as shadow rays to a light),
/// and from points on the grid's edges and vertices (origins on triangles' planes).
fn rays(wide: &WideBvh, n: usize, seed: u64) -> Vec<(Ray, f32)> {
    let mut rng = Lcg(seed);
    let mut out = Vec::with_capacity(n);
    let mut from = Vec3::ZERO;
    for i in 0..n {
        let ray = match i / 8 % 3 {
            0 => Ray::new(rng.vec() * 14.0 - Vec3::splat(7.0), direction(&mut rng, i)),
            1 => {
                if i % 8 == 0 {
                    from = rng.vec() * 10.0 - Vec3::splat(5.0);
                }
                let target = vec3(0.5, 4.0, -0.5) + rng.vec() * 1.5;
                Ray::new(from, target - from)
            }
            _ => {
                let on_edge = (rng.vec() * 8.0 - Vec3::splat(4.0)).floor();
                let o = vec3(on_edge.x + 0.5 * (i % 2) as f32, 0.0, on_edge.z);
                Ray::new(o, direction(&mut rng, i) * (0.5 + rng.next_f32()))
            }
        };
        let t_max = bound(&mut rng, wide, &ray);
        out.push((ray, t_max));
    }
    out
}

/// `rays` cut into packets of 1, 2, ..., 8, 1, 2, ... rays, so that every packet size
/// (and tail) is checked.
fn packets_of_1_to_8(rays: &[(Ray, f32)]) -> Vec<&[(Ray, f32)]> {
    let (mut packets, mut start) = (Vec::new(), 0);
    for size in (1..=PACKET).cycle() {
        if start >= rays.len() {
            break;
        }
        packets.push(&rays[start..(start + size).min(rays.len())]);
        start += size;
    }
    packets
}

/// Checks `occluded` (the packet query, or a clone of it) on packets of 1 to 8 rays
/// against the single-ray query; returns how many rays were occluded.
fn check(wide: &WideBvh, rays: &[(Ray, f32)], occluded: impl Fn(&[Ray], &[f32]) -> u32) -> usize {
    let mut blocked = 0;
    for chunk in packets_of_1_to_8(rays) {
        let (r, t): (Vec<Ray>, Vec<f32>) = chunk.iter().copied().unzip();
        let got = occluded(&r, &t);
        assert_eq!(got >> chunk.len(), 0, "bits past the packet");
        for (i, (ray, t_max)) in chunk.iter().enumerate() {
            let want = wide.any_hit(ray, *t_max, |_, _| true);
            assert_eq!(got >> i & 1 == 1, want, "{ray:?} t_max {t_max}");
            blocked += want as usize;
        }
    }
    blocked
}

#[test]
fn each_ray_of_a_packet_gets_its_single_ray_answer() {
    let (_, wide) = scene();
    let rays = rays(&wide, 40_000, 11);
    let blocked = check(&wide, &rays, |r, t| wide.occluded_packet(r, t));
    // Both answers are common, so neither a packet that hits everything nor one that
    // hits nothing passes.
    assert!(
        blocked > rays.len() / 10 && blocked < rays.len() * 4 / 5,
        "{blocked}"
    );
}

/// Rays from y = 20 down onto the grid at x = i / 2 and z = j `z_step` (i, j in -8..8):
/// on its edges, vertices and diagonals among other points; one per direction of
/// `dirs`, unbounded.
fn rays_down_onto_the_grid(z_step: f32, dirs: &[Vec3]) -> Vec<(Ray, f32)> {
    let mut rays = Vec::new();
    for i in -8..8 {
        for j in -8..8 {
            let o = vec3(i as f32 * 0.5, 20.0, j as f32 * z_step);
            rays.extend(dirs.iter().map(|&d| (Ray::new(o, d), f32::INFINITY)));
        }
    }
    rays
}

#[test]
fn packets_of_rays_along_shared_edges_never_slip_through() {
    // Rays straight down onto the grid's edges and vertices: watertight for single
    // rays, and each packet lane must agree.
    let (_, wide) = scene();
    let down = [
        vec3(0.0, -1.0, 0.0),
        vec3(-0.0, -1.0, -0.0),
        vec3(1e-3, -1.0, 0.0),
    ];
    let rays = rays_down_onto_the_grid(0.5, &down);
    let blocked = check(&wide, &rays, |r, t| wide.occluded_packet(r, t));
    assert_eq!(blocked, rays.len(), "the grid covers these points");
}

#[test]
fn the_dispatched_packet_query_matches_the_baseline_build() {
    let (_, wide) = scene();
    let rays = rays(&wide, 4_000, 12);
    for chunk in rays.chunks(PACKET) {
        let (r, t): (Vec<Ray>, Vec<f32>) = chunk.iter().copied().unzip();
        let mut bounds = [0.0; PACKET];
        bounds[..t.len()].copy_from_slice(&t);
        assert_eq!(
            wide.occluded_packet(&r, &t),
            wide.occluded_lanes_inlined(&RayLanes::from_rays(&r), &bounds)
        );
    }
}

/// Checks the closest hits of packets of 1 to 8 rays against `closest_hit_at`, bit for
/// bit; returns how many rays hit.
fn check_closest(wide: &WideBvh, rays: &[(Ray, f32)]) -> usize {
    let bits = |h: &Option<(u32, u32, TriangleHit)>| {
        h.map(|(p, l, h)| (p, l, [h.t, h.b0, h.b1, h.b2].map(f32::to_bits)))
    };
    let mut hits = 0;
    for chunk in packets_of_1_to_8(rays) {
        let (r, t): (Vec<Ray>, Vec<f32>) = chunk.iter().copied().unzip();
        let got = wide.closest_packet(&r, &t);
        let mut bounds = [0.0; PACKET];
        bounds[..t.len()].copy_from_slice(&t);
        let lanes = wide.closest_lanes_inlined(&RayLanes::from_rays(&r), &bounds);
        assert_eq!(got, lanes.to_packet_hits(), "the baseline build");
        assert_eq!(lanes.found >> chunk.len(), 0, "hits past the packet");
        assert!(
            got[chunk.len()..].iter().all(Option::is_none),
            "hits past the packet"
        );
        // And the public query in lanes, with one bound for every ray.
        let within = wide.closest_packet_within(&r, t[0]);
        assert_eq!(within.found >> chunk.len(), 0, "hits past the packet");
        // Written in place over a previous packet's hits, it is the same.
        let mut reused = HitLanes {
            t: [0.5; PACKET],
            prim: [7; PACKET],
            found: u32::MAX,
            ..HitLanes::default()
        };
        wide.closest_packet_within_into(&r, t[0], &mut reused);
        assert_eq!(reused, within, "hits written over old ones");
        for (i, (ray, t_max)) in chunk.iter().enumerate() {
            let want = wide.closest_hit_at(ray, *t_max);
            assert_eq!(bits(&got[i]), bits(&want), "{ray:?} t_max {t_max}");
            hits += want.is_some() as usize;
            let want = wide.closest_hit_at(ray, t[0]);
            assert_eq!(bits(&within.get(i)), bits(&want), "{ray:?} t_max {}", t[0]);
        }
    }
    hits
}

#[test]
fn each_ray_of_a_packet_gets_its_single_ray_closest_hit() {
    let (_, wide) = scene();
    let rays = rays(&wide, 40_000, 13);
    let hits = check_closest(&wide, &rays);
    assert!(
        hits > rays.len() / 10 && hits < rays.len() * 4 / 5,
        "{hits}"
    );
}

#[test]
fn ties_on_shared_edges_go_to_the_lowest_index_in_packets() {
    // Straight down onto the grid's edges: two triangles at exactly the same t.
    let (_, wide) = scene();
    let rays = rays_down_onto_the_grid(0.25, &[vec3(0.0, -1.0, 0.0), vec3(-0.0, -1.0, 0.0)]);
    assert_eq!(check_closest(&wide, &rays), rays.len());
}

#[test]
fn grazing_hits_near_t_zero_match_in_packets() {
    // Packets of rays from points 10^-k off long or thin triangles far from the world
    // origin, grazing them: hits whose f32 t lies within its rounding error of 0, which
    // the scalar test decides again in f64 (as in leaf_tests'
    // decided_lanes_bound_the_scalar_tests_t_error).
    let mut rng = Lcg(17);
    let (mut tris, mut rays) = (Vec::new(), Vec::new());
    for i in 0..300 {
        let far = [0.0, 10.0, 1e4][i % 3];
        let centre = rng.vec() * 4.0 + Vec3::splat(far);
        let thin = if i % 5 == 0 { 1e-3 } else { 1.0 };
        let long = if i % 7 == 0 { 1e3 } else { 4.0 };
        let (e1, e2) = (rng.dir() * long, rng.dir() * thin);
        tris.push([centre, centre + e1, centre + e2]);
        let n = e1.cross(e2).normalize();
        for k in 0..8 {
            let target = centre + e1 * rng.next_f32() * 0.5 + e2 * rng.next_f32() * 0.5;
            let along = (e1.normalize() + n * 10f32.powi(-(k % 4))).normalize();
            let off = n * 10f32.powi(-1 - (i as i32 + k) % 6);
            let origin = target + off - along * 10f32.powi(-(k % 5));
            rays.push((Ray::new(origin, along), f32::INFINITY));
        }
    }
    let wide = build(&tris);
    assert!(check_closest(&wide, &rays) > rays.len() / 2);
    check(&wide, &rays, |r, t| wide.occluded_packet(r, t));
}

#[test]
fn lanes_with_holes_get_their_single_ray_answers() {
    let (_, wide) = scene();
    let rays = rays(&wide, 8_000, 13);
    let mut rng = Lcg(7);
    let mut blocked = 0;
    for chunk in rays.chunks(PACKET) {
        // A random mask of lanes holding a ray; the others keep junk (a ray, a NaN or
        // zero direction, or the zeros past the chunk).
        let mut lanes = RayLanes::default();
        let mut t_max = [0.0; PACKET];
        for (r, (ray, t)) in chunk.iter().enumerate() {
            lanes.set(r, ray);
            t_max[r] = *t;
        }
        let active = (rng.next_f32() * 256.0) as u32 & ((1 << chunk.len()) - 1);
        for r in 0..PACKET {
            if active & (1 << r) == 0 && r % 3 != 2 {
                let junk = if r % 3 == 0 { f32::NAN } else { 0.0 };
                (lanes.dir[0][r], lanes.dir[1][r]) = (junk, junk);
            }
        }
        lanes.active = active;
        let got = wide.occluded_lanes_inlined(&lanes, &t_max);
        assert_eq!(got & !lanes.active, 0, "bits of inactive lanes");
        // And the public query, with one bound for every lane.
        let one = wide.occluded_lanes(&lanes, t_max[0]);
        assert_eq!(one & !lanes.active, 0, "bits of inactive lanes");
        for r in lanes.lanes() {
            let want = wide.any_hit(&lanes.ray(r), t_max[r], |_, _| true);
            assert_eq!(got >> r & 1 == 1, want, "lane {r} of {:#b}", lanes.active);
            blocked += want as usize;
            let want = wide.any_hit(&lanes.ray(r), t_max[0], |_, _| true);
            assert_eq!(one >> r & 1 == 1, want, "lane {r}, bound {}", t_max[0]);
        }
    }
    assert!(blocked > 100, "{blocked} rays blocked");
}

#[test]
fn an_empty_tree_occludes_nothing() {
    let wide = WideBvh::default();
    let r = [Ray::new(Vec3::ZERO, Vec3::X); 3];
    assert_eq!(wide.occluded_packet(&r, &[1.0; 3]), 0);
    assert_eq!(wide.occluded_packet(&[], &[]), 0);
    assert_eq!(wide.closest_packet(&r, &[1.0; 3]), [None; PACKET]);
}

#[test]
fn nearest_of_is_the_least_entry_of_the_masked_rays() {
    let mut rng = Lcg(23);
    for round in 0..2_000 {
        let t: Lanes = std::array::from_fn(|r| match (round + r) % 5 {
            0 => 0.0,
            1 => f32::INFINITY,
            _ => rng.next_f32() * 10f32.powi(round as i32 % 7 - 3),
        });
        let mask = round as u32 % 256;
        let want = (0..PACKET)
            .filter(|r| mask & (1 << r) != 0)
            .map(|r| t[r])
            .fold(f32::INFINITY, f32::min);
        assert_eq!(
            nearest_of(&t, mask).to_bits(),
            want.to_bits(),
            "{t:?} {mask:#b}"
        );
    }
}

/// `x` moved `k` floats up (down when negative).
fn nudge(mut x: f32, k: i32) -> f32 {
    for _ in 0..k.abs() {
        x = if k > 0 { x.next_up() } else { x.next_down() };
    }
    x
}

#[test]
fn the_segment_box_keeps_every_child_some_ray_meets() {
    // Tiny boxes whose faces lie a few floats either side of a ray's origin or of its
    // end (`o + d * t_max`, a little before or past): the box test accepts some of them
    // through its margin and rounding, and the cull must keep each of those.
    let mut rng = Lcg(31);
    let (mut met, mut culled) = (0, 0);
    for round in 0..20_000 {
        let scale = [1.0, 1e-3, 1e3, 7.888_609e-31][round % 4];
        let mut lanes = RayLanes::default();
        let mut t_max = [0.0; PACKET];
        let n = 1 + rng.below(PACKET as u32) as usize;
        for r in 0..n {
            let o = (rng.vec() * 2.0 - Vec3::ONE) * scale;
            let d = direction(&mut rng, r) * [1.0, 0.25, 3.0][r % 3];
            lanes.set(r, &Ray::new(o, d));
            t_max[r] = [1.0 - 1e-4, 1.0, 0.37, 1e-3][(round + r) % 4];
        }
        let p = PacketRays::from_lanes(&lanes, &t_max);
        let mut node = WideNode::UNUSED;
        for c in 0..WIDTH {
            let r = rng.below(n as u32) as usize;
            let ray = lanes.ray(r);
            let stretch =
                [0.0, 1.0 - 1e-6, 1.0, 1.0 + 1e-7, 1.0 + 4e-7, 1.0 + 1e-5][rng.below(6) as usize];
            let q = ray.origin + ray.dir * (t_max[r] * stretch);
            for a in 0..3 {
                // Mostly within the cull's widening; sometimes past it.
                let k = match c % 2 {
                    0 => rng.below(13) as i32 - 6,
                    _ => rng.below(4001) as i32 - 2000,
                };
                let w = rng.below(4) as i32;
                node.bounds[a][c] = nudge(q[a], k);
                node.bounds[a + 3][c] = nudge(q[a], k + w);
            }
            node.child[c] = c as u32;
        }
        let cull = SegmentBox::of(&lanes, &t_max).expect("rays the cull covers");
        let kept = cull.children_met(&node);
        for c in 0..WIDTH {
            let hit = p.test_box(&node, c).1 & lanes.active;
            if hit != 0 {
                assert!(
                    kept & (1 << c) != 0,
                    "round {round}: child {c} met by {hit:#b}"
                );
                met += 1;
            } else if kept & (1 << c) == 0 {
                culled += 1;
            }
        }
    }
    assert!(met > 5_000 && culled > 20_000, "{met} met, {culled} culled");
    // A box ending one float short of the origin, whose far-plane distance rounds to
    // -0 (a subnormal times 2^-20): the box test accepts it, and so must the cull.
    let o = vec3(1e-42, 0.5, 0.5);
    let lanes = RayLanes::from_rays(&[Ray::new(o, vec3(1_048_576.0, 0.0, 0.0))]);
    let mut node = WideNode::UNUSED;
    node.bounds[0][0] = -1.0;
    node.bounds[3][0] = o.x.next_down();
    (node.bounds[1][0], node.bounds[2][0]) = (0.0, 0.0);
    (node.bounds[4][0], node.bounds[5][0]) = (1.0, 1.0);
    let t_max = [1.0; PACKET];
    let p = PacketRays::from_lanes(&lanes, &t_max);
    assert_eq!(p.test_box(&node, 0).1 & 1, 1, "the test accepts it");
    let cull = SegmentBox::of(&lanes, &t_max).unwrap();
    assert_eq!(cull.children_met(&node) & 1, 1);
}

#[test]
fn the_segment_box_culls_nothing_for_rays_it_does_not_cover() {
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    for (o, d, t) in [
        (f32::NAN, 1.0, 1.0),
        (f32::INFINITY, 1.0, 1.0),
        (0.0, 1e20, 1.0),
        (0.0, f32::NAN, 1.0),
        (0.0, 1.0, f32::INFINITY),
        (0.0, 1.0, f32::NAN),
        (0.0, 1.0, 1e-35),
    ] {
        let mut lanes = RayLanes::from_rays(&[ray, ray]);
        (lanes.origin[1][1], lanes.dir[2][1]) = (o, d);
        let t_max = [1.0, t, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert!(SegmentBox::of(&lanes, &t_max).is_none(), "{o} {d} {t}");
        // An inactive lane's junk does not matter.
        lanes.active = 1;
        assert!(SegmentBox::of(&lanes, &t_max).is_some(), "{o} {d} {t}");
    }
}

/// The tests above run through the hand-over to single rays (their scene's tree is deep
/// enough), while a tree of a few triangles keeps its packets whole.
#[test]
fn packets_hand_over_few_rays_in_deep_trees_only() {
    let (_, wide) = scene();
    assert!(wide.hand_over_rays() > 0, "depth {}", wide.depth);
    let few: Vec<Tri> = scene().0.into_iter().take(20).collect();
    assert_eq!(build(&few).hand_over_rays(), 0);
}
