//! Tests of the watertight ray/triangle test.

use super::*;
use glam::vec3;

use crate::test_util::{Lcg, Mesh, cube, icosphere};

const V0: Vec3 = Vec3::new(0.0, 0.0, 0.0);
const V1: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const V2: Vec3 = Vec3::new(0.0, 1.0, 0.0);

fn down_at(x: f32, y: f32) -> Ray {
    Ray::new(vec3(x, y, 2.0), vec3(0.0, 0.0, -1.0))
}

#[test]
fn interior_hit_is_analytic() {
    let h = intersect_triangle(&down_at(0.25, 0.5), V0, V1, V2, f32::INFINITY).unwrap();
    assert_eq!(h.t, 2.0);
    assert!((h.b0 - 0.25).abs() < 1e-6);
    assert!((h.b1 - 0.25).abs() < 1e-6);
    assert!((h.b2 - 0.5).abs() < 1e-6);
    // Non-unit direction: t in units of dir.
    let r = Ray::new(vec3(0.25, 0.5, 2.0), vec3(0.0, 0.0, -4.0));
    let h = intersect_triangle(&r, V0, V1, V2, f32::INFINITY).unwrap();
    assert_eq!(h.t, 0.5);
}

#[test]
fn both_windings_hit_with_same_weights() {
    let a = intersect_triangle(&down_at(0.2, 0.3), V0, V1, V2, 10.0).unwrap();
    let b = intersect_triangle(&down_at(0.2, 0.3), V0, V2, V1, 10.0).unwrap();
    assert_eq!(a.t, b.t);
    assert!((a.b1 - b.b2).abs() < 1e-6 && (a.b2 - b.b1).abs() < 1e-6);
    // From below as well.
    let up = Ray::new(vec3(0.2, 0.3, -1.0), vec3(0.0, 0.0, 1.0));
    assert_eq!(intersect_triangle(&up, V0, V1, V2, 10.0).unwrap().t, 1.0);
}

#[test]
fn vertex_and_edge_hits() {
    let h = intersect_triangle(&down_at(1.0, 0.0), V0, V1, V2, 10.0).unwrap();
    assert_eq!((h.t, h.b0, h.b1, h.b2), (2.0, 0.0, 1.0, 0.0));
    let h = intersect_triangle(&down_at(0.0, 0.0), V0, V1, V2, 10.0).unwrap();
    assert_eq!((h.b0, h.b1, h.b2), (1.0, 0.0, 0.0));
    // Midpoint of the hypotenuse v1-v2.
    let h = intersect_triangle(&down_at(0.5, 0.5), V0, V1, V2, 10.0).unwrap();
    assert_eq!(h.b0, 0.0);
    assert!((h.b1 - 0.5).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
    // Just outside that edge.
    assert!(intersect_triangle(&down_at(0.5, 0.5001), V0, V1, V2, 10.0).is_none());
}

#[test]
fn t_range_is_open() {
    // Behind the origin, at exactly t_max, and beyond t_max: no hit.
    let r = Ray::new(vec3(0.2, 0.2, -1.0), vec3(0.0, 0.0, -1.0));
    assert!(intersect_triangle(&r, V0, V1, V2, 10.0).is_none());
    assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 2.0).is_none());
    assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 1.5).is_none());
    assert!(intersect_triangle(&down_at(0.2, 0.2), V0, V1, V2, 2.0001).is_some());
    // Origin on the triangle: t = 0 is not a hit.
    let r = Ray::new(vec3(0.2, 0.2, 0.0), vec3(0.0, 0.0, 1.0));
    assert!(intersect_triangle(&r, V0, V1, V2, 10.0).is_none());
}

#[test]
fn near_hits_on_long_thin_triangles_are_kept() {
    // Sponza's floor trim: a triangle 10.8 long and 0.015 wide, hit at a grazing
    // angle from 0.002 above a neighbouring surface, well inside (barycentrics 0.61,
    // 0.32, 0.07). Exact t (rational arithmetic on these f32 values) 0.0033638108;
    // the f32 computation's error is 2.6e-5 but its first-order bound 0.004, which
    // alone would drop the hit (Embree, tinybvh and obvhs all report it).
    let r = Ray::new(
        vec3(-6.630026, 15.621754, 2.423566),
        vec3(0.6863056, 0.38305056, -0.6182693),
    );
    let (a, b, c) = (
        vec3(-10.812759, 15.61831, 2.421486),
        vec3(0.00724, 15.633309, 2.421487),
        vec3(0.00724, 15.61831, 2.421487),
    );
    let h = intersect_triangle(&r, a, b, c, f32::INFINITY).expect("a hit at t = 0.00336");
    assert!((h.t - 0.003_363_810_8).abs() < 1e-8, "t = {}", h.t);
    // Still open at t = 0: from an origin exactly on such a triangle (in the plane
    // z = 0, so that f32 origins lie exactly on it), no grazing direction hits it.
    let (a, b, c) = (
        vec3(-10.812759, 0.0, 0.0),
        vec3(0.00724, 0.015, 0.0),
        Vec3::ZERO,
    );
    let mut rng = Lcg(11);
    for _ in 0..10_000 {
        let w = [rng.next_f32(), rng.next_f32()];
        let o = a + w[0] * (b - a) + w[1] * (1.0 - w[0]) * (c - a);
        let d = vec3(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            1e-4 * (rng.next_f32() - 0.5),
        );
        assert!(o.z == 0.0);
        if let Some(h) = intersect_triangle(&Ray::new(o, d), a, b, c, f32::INFINITY) {
            assert!(h.t * d.length() < 1e-5, "origin {o} dir {d}: t = {}", h.t);
        }
    }
}

/// The scalar test keeps a t that `clear_of_zero` clears without its f64 error bound:
/// on rays that start on or a few ulps off long thin triangles, at grazing angles and
/// far from the origin of coordinates (where that bound decides most often), the
/// answer with the shortcut is the answer without it, bit for bit.
#[test]
fn the_t_shortcut_gives_the_bounded_tests_answer() {
    let mut rng = Lcg(23);
    let (mut hits, mut near) = (0, 0);
    for k in 0..40_000 {
        let scale = [1.0, 1e3, 1e5][k % 3];
        let offset = vec3(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale;
        let (a, b, c) = (
            offset + vec3(-10.8, 0.0, 0.0),
            offset + vec3(0.007, 0.015, 0.0),
            offset + vec3(0.007, 0.0, 1e-3 * (rng.next_f32() - 0.5)),
        );
        let w = [rng.next_f32(), rng.next_f32()];
        let mut o = a + w[0] * (b - a) + w[1] * (1.0 - w[0]) * (c - a);
        // On the surface, or moved a few ulps off it.
        let ulps = (rng.next_f32() * 8.0) as u32 % 4;
        for _ in 0..ulps {
            o.z = o.z.next_up();
        }
        let d = vec3(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            1e-4 * (rng.next_f32() - 0.5),
        );
        let ray = Ray::new(o, d);
        let s = RayShear::new(&ray);
        let with = intersect_triangle_checked::<true>(&s, o, [a, b, c], f32::INFINITY, true);
        let without = intersect_triangle_checked::<false>(&s, o, [a, b, c], f32::INFINITY, true);
        let bits = |h: Option<TriangleHit>| h.map(|h| [h.t, h.b0, h.b1, h.b2].map(f32::to_bits));
        assert_eq!(
            bits(with),
            bits(without),
            "origin {o} dir {d} triangle {a} {b} {c}"
        );
        if let Some(h) = without {
            hits += 1;
            near += usize::from(h.t * d.length() < 1e-2 * scale);
        }
    }
    // Enough hits, and near ones, for the comparison to mean something.
    assert!(hits > 5_000 && near > 1_000, "{hits} hits, {near} near");
}

#[test]
fn degenerate_triangles_never_hit() {
    let mut rng = Lcg(7);
    let tris = [
        // Two equal vertices.
        (
            vec3(0.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
        ),
        // Collinear, not axis aligned.
        (
            vec3(0.0, 0.0, 0.0),
            vec3(1.0, 1.0, 1.0),
            vec3(3.0, 3.0, 3.0),
        ),
        (
            vec3(0.1, 0.2, 0.3),
            vec3(0.2, 0.4, 0.6),
            vec3(0.4, 0.8, 1.2),
        ),
        // All points equal.
        (
            vec3(0.5, 0.5, 0.5),
            vec3(0.5, 0.5, 0.5),
            vec3(0.5, 0.5, 0.5),
        ),
    ];
    for (a, b, c) in tris {
        for i in 0..20000 {
            // Aim at points of the degenerate segment (and at its ends).
            let s = if i % 3 == 0 {
                (i % 2) as f32
            } else {
                rng.next_f32()
            };
            let target = a.lerp(c, s);
            let origin = target + rng.dir() * 3.0;
            let r = Ray::new(origin, target - origin);
            assert!(intersect_triangle(&r, a, b, c, f32::INFINITY).is_none());
        }
    }
}

#[test]
fn ray_in_plane_misses_without_nan() {
    let r = Ray::new(vec3(-1.0, 0.2, 0.0), vec3(1.0, 0.0, 0.0));
    assert!(intersect_triangle(&r, V0, V1, V2, f32::INFINITY).is_none());
    // Zero direction: no hit, no NaN hit.
    let r = Ray::new(vec3(0.2, 0.2, 1.0), Vec3::ZERO);
    assert!(intersect_triangle(&r, V0, V1, V2, f32::INFINITY).is_none());
}

#[test]
fn random_hits_reproduce_the_hit_point() {
    let mut rng = Lcg(3);
    for _ in 0..10000 {
        let (a, b, c) = (rng.vec(), rng.vec(), rng.vec());
        let (w1, w2) = (rng.next_f32(), rng.next_f32());
        let (w1, w2) = if w1 + w2 > 1.0 {
            (1.0 - w1, 1.0 - w2)
        } else {
            (w1, w2)
        };
        let p = a + w1 * (b - a) + w2 * (c - a);
        let o = p + rng.dir() * 2.0;
        let r = Ray::new(o, p - o);
        if let Some(h) = intersect_triangle(&r, a, b, c, 10.0) {
            assert!(h.b0 >= 0.0 && h.b1 >= 0.0 && h.b2 >= 0.0);
            assert!((h.b0 + h.b1 + h.b2 - 1.0).abs() < 1e-4);
            assert!((h.t - 1.0).abs() < 1e-3, "t {}", h.t);
        }
    }
}

/// `AXES` names the two axes after the dominant one in cyclic order, swapped when
/// the dominant component is negative, and `RayShear::new` picks them so (the
/// winding every triangle test relies on).
#[test]
fn axes_follow_the_dominant_axis_cyclically_swapped_when_negative() {
    for kz in 0..3 {
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let axes = AXES[kz].map(|pair| pair.map(|k| k as usize));
        assert_eq!(axes, [[kx, ky], [ky, kx]], "{kz}");
        for sign in [1.0, -1.0] {
            let mut dir = Vec3::splat(0.25);
            dir[kz] = sign;
            let s = RayShear::new(&Ray::new(Vec3::ZERO, dir));
            let want = if sign < 0.0 { (ky, kx) } else { (kx, ky) };
            assert_eq!(s.indices(), [want.0, want.1, kz], "{dir}");
        }
    }
}

/// The shear from the inverse direction is `RayShear::new`'s, to the bit: on
/// directions of every dominant axis and sign, with zero (both signs), tiny and huge
/// components.
#[test]
fn shear_from_the_inverse_direction_is_new_bit_for_bit() {
    let mut rng = Lcg(29);
    let special = [0.0, -0.0, 1e-30, -3e-39, 7e30, -1.0];
    for i in 0..20000 {
        let mut d = rng.dir() * (0.01 + 10.0 * rng.next_f32());
        if i % 2 == 0 {
            d[i / 2 % 3] = special[i / 6 % special.len()];
        }
        let ray = Ray::new(rng.vec(), d);
        let (a, b) = (
            RayShear::new(&ray),
            RayShear::with_inverse(&ray, ray.dir.recip().to_array()),
        );
        let bits = |s: &RayShear| {
            let f = [s.sx, s.sy, s.sz].map(f32::to_bits);
            (s.kx, s.ky, s.kz, f, s.dir.to_array().map(f32::to_bits))
        };
        assert_eq!(bits(&a), bits(&b), "{ray:?}");
    }
}

/// Counts rays that hit no triangle of `mesh` (brute force).
fn misses(mesh: &Mesh, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| {
            let s = RayShear::new(r);
            !(0..mesh.tris.len()).any(|i| {
                let (a, b, c) = mesh.tri(i);
                intersect_triangle_sheared(&s, r.origin, a, b, c, f32::INFINITY).is_some()
            })
        })
        .count()
}

/// Points exactly on shared edges (several fractions along each) and on vertices.
fn edge_and_vertex_points(mesh: &Mesh, rng: &mut Lcg) -> Vec<Vec3> {
    let mut pts = mesh.verts.clone();
    for i in 0..mesh.tris.len() {
        let (a, b, c) = mesh.tri(i);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            for f in [0.5, 0.25, rng.next_f32(), rng.next_f32()] {
                pts.push(p.lerp(q, f));
            }
        }
    }
    pts
}

fn check_closed(mesh: &Mesh, centre: Vec3, seed: u64, reps: usize) {
    let mut rng = Lcg(seed);
    let pts: Vec<Vec3> = (0..reps)
        .flat_map(|_| edge_and_vertex_points(mesh, &mut rng))
        .collect();
    // From outside, along the outward radial line through the point: the
    // ray crosses the surface transversally there, so it must hit.
    let outside: Vec<Ray> = pts
        .iter()
        .map(|&p| {
            let o = centre + (p - centre) * 3.0;
            Ray::new(o, p - o)
        })
        .collect();
    // From inside (random interior points) through the same points.
    let inside: Vec<Ray> = pts
        .iter()
        .map(|&p| {
            let o = centre + (rng.vec() - Vec3::splat(0.5)) * 0.2;
            Ray::new(o, p - o)
        })
        .collect();
    // From inside in random directions.
    let random: Vec<Ray> = (0..pts.len())
        .map(|_| Ray::new(centre, rng.dir()))
        .collect();
    assert!(pts.len() > 1000, "too few test rays: {}", pts.len());
    assert_eq!(misses(mesh, &outside), 0, "outside rays slipped through");
    assert_eq!(misses(mesh, &inside), 0, "inside rays slipped through");
    assert_eq!(misses(mesh, &random), 0, "random inside rays escaped");
}

#[test]
fn watertight_icosphere() {
    let mut m = icosphere(3);
    // Move it off the origin with awkward values so the arithmetic rounds.
    let off = vec3(0.3137, -1.771, 2.0913);
    for v in &mut m.verts {
        *v = *v * 1.37 + off;
    }
    check_closed(&m, off, 11, 1);
}

#[test]
fn watertight_cube() {
    let min = vec3(-0.713, -1.291, 0.377);
    let max = vec3(1.119, 0.8537, 2.2211);
    let m = cube(min, max);
    // Many rays through the few edges of a cube.
    let mut rng = Lcg(5);
    let centre = (min + max) * 0.5;
    let mut rays = Vec::new();
    for _ in 0..200 {
        for p in edge_and_vertex_points(&m, &mut rng) {
            let o = centre + (rng.vec() - Vec3::splat(0.5)) * 0.5;
            rays.push(Ray::new(o, p - o));
            let o = centre + (p - centre) * (2.0 + rng.next_f32());
            rays.push(Ray::new(o, p - o));
        }
    }
    assert!(rays.len() > 10000);
    assert_eq!(misses(&m, &rays), 0);
    check_closed(&m, centre, 17, 50);
}
