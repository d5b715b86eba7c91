use glam::{Vec2, Vec3};

use super::*;
use crate::accel::{Aabb, Bvh, SplitMethod};
use crate::scene::components::Sphere;
use crate::test_util::Lcg as Rng;
use crate::trace::geometry::{Hit, PrimKind};
use crate::trace::surface::Surface;

/// Signed numbers from the tests' shared stream.
trait Signed {
    /// In [-1, 1).
    fn signed(&mut self) -> f32;
    /// In [-1, 1)^3.
    fn vec3(&mut self) -> Vec3;
}

impl Signed for Rng {
    fn signed(&mut self) -> f32 {
        self.next_f32() * 2.0 - 1.0
    }

    fn vec3(&mut self) -> Vec3 {
        self.vec() * 2.0 - Vec3::ONE
    }
}

/// Each triangle's vertex positions, normals and texture coordinates.
type Triangles = (Vec<[Vec3; 3]>, Vec<[Vec3; 3]>, Vec<[Vec2; 3]>);

/// Triangles of every scale (2^-40 to 2^40), some degenerate (a repeated vertex, three
/// in a line, all at one point), with vertex normals that sometimes cancel.
fn triangles(rng: &mut Rng, count: usize) -> Triangles {
    let (mut positions, mut normals, mut texcoords) = (vec![], vec![], vec![]);
    for i in 0..count {
        let scale = 2f32.powi(rng.below(81) as i32 - 40);
        let offset = rng.vec3() * scale * 4.0;
        let [a, b, c] = [rng.vec3(), rng.vec3(), rng.vec3()].map(|v| offset + v * scale);
        positions.push(match i % 8 {
            1 => [a, a, c],
            2 => [a, b, a + (b - a) * 0.5],
            3 => [a, a, a],
            _ => [a, b, c],
        });
        let n = rng.vec3().normalize_or(Vec3::Y);
        normals.push(match i % 5 {
            // Opposite normals: some blends are zero and fall back to ng.
            1 => [n, -n, n],
            2 => [n, -n, Vec3::ZERO],
            _ => [
                n,
                rng.vec3().normalize_or(Vec3::X),
                rng.vec3().normalize_or(Vec3::Z),
            ],
        });
        texcoords.push([0, 1, 2].map(|_| Vec2::new(rng.signed(), rng.signed()) * scale));
    }
    (positions, normals, texcoords)
}

fn geometry(rng: &mut Rng) -> SceneGeometry {
    let (positions, tri_normals, tri_texcoords) = triangles(rng, 200);
    let bounds: Vec<Aabb> = positions.iter().map(|p| Aabb::from_points(p)).collect();
    let spheres = vec![Sphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 0.5,
    }];
    let mut g = SceneGeometry {
        tri_material: (0..positions.len() as u32).collect(),
        tri_normals,
        tri_texcoords,
        tri_bvh: Bvh::build(&bounds, SplitMethod::SahBinned),
        sphere_material: vec![7],
        sphere_bvh: Bvh::build(
            &[Aabb::new(
                Vec3::new(0.5, 1.5, 2.5),
                Vec3::new(1.5, 2.5, 3.5),
            )],
            SplitMethod::SahBinned,
        ),
        spheres,
        ..Default::default()
    };
    g.collapse_triangle_bvh(&positions);
    g
}

/// A hit on a random flattened triangle, on the sphere, or none; with barycentric
/// weights that may be slightly negative or -0 (rounding at an edge).
fn hit(rng: &mut Rng, g: &SceneGeometry) -> Option<Hit> {
    let pick = |rng: &mut Rng| match rng.below(6) {
        0 => -0.0,
        1 => -1e-7 * rng.signed().abs(),
        2 => 0.0,
        _ => rng.signed().abs(),
    };
    let bary = Vec3::new(pick(rng), pick(rng), pick(rng));
    match rng.below(10) {
        0 => None,
        1 => Some(Hit {
            t: 2.0,
            prim: 0,
            kind: PrimKind::Sphere,
            bary: Vec3::ZERO,
            instance: None,
            lane: 0,
        }),
        _ => {
            let prim = rng.below(g.triangles_flattened() as u32);
            Some(Hit {
                t: 1.0,
                prim,
                kind: PrimKind::Triangle,
                bary,
                instance: None,
                lane: g.lane(prim),
            })
        }
    }
}

fn bits(s: &Option<Surface>) -> Option<[u32; 15]> {
    s.map(|s| {
        let v = [s.p, s.p_error, s.ng, s.n].map(|v| v.to_array());
        let mut out = [0; 15];
        for (o, x) in out
            .iter_mut()
            .zip(v.iter().flatten().chain(&s.uv.to_array()))
        {
            *o = x.to_bits();
        }
        out[14] = s.material;
        out
    })
}

#[test]
fn lanes_give_surface_at_bit_for_bit() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let g = geometry(&mut rng);
    // One block for every packet: each call must overwrite what the last one left.
    let mut out = SurfaceBlock::default();
    let mut scratch = TriangleLanes::default();
    for round in 0..4000 {
        // Every packet length, front- and back-facing rays (random directions).
        let len = 1 + round % PACKET;
        let rays: Vec<Ray> = (0..len)
            .map(|_| Ray::new(rng.vec3() * 3.0, rng.vec3()))
            .collect();
        let hits: Vec<Option<Hit>> = (0..len).map(|_| hit(&mut rng, &g)).collect();
        for interpolate in [false, true] {
            let lanes = PacketSceneHits::from_hits(&hits);
            surfaces_at(&g, &rays, &lanes, interpolate, &mut scratch, &mut out);
            for (j, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
                let want = hit.map(|h| surface_at(&g, ray, &h, interpolate));
                assert_eq!(bits(&out.get(j)), bits(&want), "{hit:?} on {ray:?}");
            }
            assert_eq!(out.hit >> len, 0, "no hit past the packet");
        }
    }
}
