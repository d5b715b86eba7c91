//! Instancing: meshes shared by several entities go into a two-level BVH instead of
//! being flattened; they must render as the flattened copies do, hit where the
//! transforms put them, and cost memory per instance, not per triangle drawn.

mod common;

use std::sync::Arc;

use common::*;
use glam::{Affine3A, Vec3};
use glint::Renderer;
use glint::accel::{Aabb, Bvh, Instance, Ray, SplitMethod, TwoLevelBvh, WideBvh};
use glint::scene::Mesh;
use glint::trace::geometry::{PrimKind, SceneGeometry};
use glint::trace::materials::Materials;
use glint::trace::packet_hits::PacketSceneHits;
use glint::trace::surface::surface_at;

/// Spheres and cubes under translations, rotations, non-uniform and mirroring scales,
/// on a plane, lit by a point light: diffuse, reflective and transparent materials.
fn scene(n: u32) -> String {
    let mut entities = vec![
        "PointLight((position: (2, 6, 4), color: (30, 30, 30)))".to_owned(),
        "Mesh((material: Some(\"floor\"), geometry: Plane(subdivisions: 2), transform: (translate: (0, -1, 0), scale: (8, 1, 8))))".to_owned(),
    ];
    let placements = [
        ("(-1.5, 0, 0)", "(0, 0, 0)", "(1, 1, 1)", "matte"),
        ("(0, 0, -1)", "(20, 40, 10)", "(0.7, 1.2, 0.9)", "mirror"),
        ("(1.5, 0, 0)", "(0, 30, 0)", "(-1, 1, 1)", "matte"),
        ("(0.3, 0.8, 1)", "(10, 0, 70)", "(0.5, 0.4, -0.6)", "glass"),
    ];
    for geometry in ["UvSphere(segments: 24, rings: 12)", "Cube"] {
        for (k, (t, r, s, m)) in placements.iter().enumerate() {
            let lift = if geometry == "Cube" { 1.6 } else { 0.0 };
            let t = t.replace("(", "").replace(")", "");
            let v: Vec<f32> = t.split(',').map(|x| x.trim().parse().unwrap()).collect();
            entities.push(format!(
                "Mesh((material: Some(\"{m}\"), geometry: {geometry}, transform: (translate: ({}, {}, {}), rotate_degrees: {r}, scale: {s})))",
                v[0] + 0.1 * k as f32,
                v[1] + lift,
                v[2]
            ));
        }
    }
    format!(
        "(camera: (position: (0, 1.5, 6), look_at: (0, 0.3, 0), fov_y: 45, width: {n}, height: {n}),
          settings: (max_depth: 4),
          materials: {{
            \"floor\": (kd: (0.6, 0.6, 0.6)),
            \"matte\": (kd: (0.8, 0.3, 0.2)),
            \"mirror\": (kd: (0.1, 0.1, 0.1), ks: (0.7, 0.7, 0.7)),
            \"glass\": (kd: (0.2, 0.7, 0.9), transparency: 0.5),
          }},
          entities: [{}])",
        entities.join(", ")
    )
}

/// Makes every mesh entity with the same geometry as an earlier one share its data.
fn share_meshes(r: &mut Renderer) {
    let w = &mut r.world;
    let mut q = w.query::<&mut Mesh>();
    let mut seen: Vec<Arc<glint::scene::MeshData>> = Vec::new();
    for mut m in q.iter_mut(w) {
        match seen.iter().find(|d| ***d == *m.data) {
            Some(d) => m.data = d.clone(),
            None => seen.push(m.data.clone()),
        }
    }
}

fn geometry(r: &Renderer) -> &SceneGeometry {
    r.world.resource::<SceneGeometry>()
}

#[test]
fn instanced_meshes_render_like_flattened_copies() {
    let n = 64;
    let copied = render(&scene(n));
    let mut shared = load(&scene(n));
    share_meshes(&mut shared);
    let shared = render_loaded(shared);
    assert_eq!(geometry(&copied).instanced.instances.len(), 0);
    let g = geometry(&shared);
    assert_eq!(g.instanced.meshes.len(), 2);
    assert_eq!(g.instanced.instances.len(), 8);
    // Only the floor is flattened.
    assert_eq!(g.triangles_flattened(), 8);
    // Rays meet instances in object space: t and barycentrics round differently than on
    // the flattened copies, so colours agree to rounding (relative 5e-5; measured 1.3e-5
    // at most, through mirrors and glass); about three in four pixels are identical.
    let (mut identical, total) = (0, (n * n) as usize);
    for y in 0..n {
        for x in 0..n {
            let (a, b) = (copied.film().pixel(x, y), shared.film().pixel(x, y));
            identical += (a == b) as usize;
            let tol = 5e-5 * a.abs().max_element().max(1.0);
            assert!(
                (a - b).abs().max_element() <= tol,
                "pixel {x},{y}: flattened {a}, instanced {b}"
            );
        }
    }
    assert!(identical * 2 >= total, "{identical} of {total} identical");
}

#[test]
fn without_acceleration_shared_meshes_are_flattened() {
    let n = 16;
    let none = scene(n).replace("settings: (", "settings: (acceleration: none, ");
    let copied = render(&none);
    let mut shared = load(&none);
    share_meshes(&mut shared);
    let shared = render_loaded(shared);
    let g = geometry(&shared);
    assert!(
        g.instanced.is_empty(),
        "a top-level BVH under acceleration: None"
    );
    // Every triangle of every copy, in the one leaf, and the same image.
    assert_eq!(
        g.triangles_flattened(),
        geometry(&copied).triangles_flattened()
    );
    assert_eq!(g.tri_wide.nodes.len(), 1);
    for (x, y) in (0..n).flat_map(|y| (0..n).map(move |x| (x, y))) {
        assert_eq!(shared.film().pixel(x, y), copied.film().pixel(x, y));
    }
}

/// Three instances of a quad (sheared, mirrored, plain) and two of a glass cube, with
/// the transforms set on the loaded entities; prepared, not rendered.
fn placed_instances() -> Renderer {
    let mut r = load(
        "(camera: (position: (0, 0, 5), look_at: (0, 0, 0), fov_y: 30, width: 8, height: 8),
          materials: {
            \"a\": (kd: (0.5, 0.5, 0.5)),
            \"glass\": (kd: (0.2, 0.6, 0.8), transparency: 0.5),
          },
          entities: [
            Mesh((name: Some(\"sheared\"), material: Some(\"a\"), geometry: Quad)),
            Mesh((name: Some(\"mirrored\"), material: Some(\"a\"), geometry: Quad)),
            Mesh((name: Some(\"plain\"), material: Some(\"a\"), geometry: Quad,
                  transform: (translate: (0, 0, -10)))),
            Mesh((name: Some(\"glass1\"), material: Some(\"glass\"), geometry: Cube,
                  transform: (translate: (0, 5, 0)))),
            Mesh((name: Some(\"glass2\"), material: Some(\"glass\"), geometry: Cube,
                  transform: (translate: (0, 5, -3), scale: (1, 1, 0.5)))),
            PointLight((position: (0, 0, 5), color: (1, 1, 1))),
          ])",
    );
    let w = &mut r.world;
    let mut q = w.query::<(&bevy_ecs::name::Name, &mut glint::scene::Transform)>();
    for (name, mut t) in q.iter_mut(w) {
        t.world_from_object = match name.as_str() {
            // z' = z + 0.5 x tilts the quad: its normal is M^-T z, not M z.
            "sheared" => Affine3A::from_cols(
                Vec3::new(1.0, 0.0, 0.5).into(),
                Vec3::Y.into(),
                Vec3::Z.into(),
                Vec3::ZERO.into(),
            ),
            "mirrored" => Affine3A::from_scale_rotation_translation(
                Vec3::new(-2.0, 1.0, 1.0),
                glam::Quat::IDENTITY,
                Vec3::new(5.0, 0.0, 0.0),
            ),
            _ => t.world_from_object,
        };
    }
    share_meshes(&mut r);
    r.prepare().expect("prepares");
    r
}

#[test]
fn instanced_hits_land_where_the_transforms_put_them() {
    let r = placed_instances();
    let g = geometry(&r);
    assert_eq!(g.instanced.instances.len(), 5);
    assert_eq!(g.instanced.meshes.len(), 2);
    assert_eq!(g.triangles_flattened(), 0);

    // The sheared quad: plane z = 0.5 x. t is in units of the (non-unit) direction.
    let ray = Ray::new(Vec3::new(0.1, 0.1, 5.0), Vec3::new(0.0, 0.0, -2.0));
    let hit = g.intersect(&ray, f32::INFINITY, &mut ()).expect("hits");
    assert_eq!((hit.kind, hit.instance), (PrimKind::Triangle, Some(0)));
    assert!((hit.t - 4.95 / 2.0).abs() < 1e-6, "t = {}", hit.t);
    let s = surface_at(g, &ray, &hit, true);
    assert_close(s.p, Vec3::new(0.1, 0.1, 0.05), 1e-6);
    let normal = Vec3::new(-0.5, 0.0, 1.0).normalize();
    assert_close(s.ng, normal, 1e-6);
    assert_close(s.n, normal, 1e-6);
    assert_close(s.uv.extend(0.0), Vec3::new(0.6, 0.6, 0.0), 1e-6);

    // The mirrored quad spans x in [4, 6]; its u runs from +x to -x.
    let ray = Ray::new(Vec3::new(5.5, 0.2, 3.0), Vec3::new(0.0, 0.0, -2.0));
    let hit = g.intersect(&ray, f32::INFINITY, &mut ()).expect("hits");
    assert_eq!(hit.instance, Some(1));
    assert!((hit.t - 1.5).abs() < 1e-6);
    let s = surface_at(g, &ray, &hit, true);
    assert_close(s.p, Vec3::new(5.5, 0.2, 0.0), 1e-6);
    assert_close(s.n, Vec3::Z, 1e-6);
    assert_close(s.ng, Vec3::Z, 1e-6);
    assert_close(s.uv.extend(0.0), Vec3::new(0.25, 0.7, 0.0), 1e-6);
    // From below, both normals face the ray.
    let below = Ray::new(Vec3::new(5.5, 0.2, -3.0), Vec3::Z);
    let hit = g.intersect(&below, f32::INFINITY, &mut ()).expect("hits");
    assert_eq!(hit.instance, Some(1));
    assert_close(surface_at(g, &below, &hit, true).n, -Vec3::Z, 1e-6);
    // Beside it (x = 6.1) nothing; beyond t_max nothing.
    let beside = Ray::new(Vec3::new(6.1, 0.2, 3.0), -Vec3::Z);
    assert!(g.intersect(&beside, f32::INFINITY, &mut ()).is_none());
    assert!(g.intersect(&ray, 1.4, &mut ()).is_none());

    // Through the origin's quad to the plain one behind it: the nearer wins.
    let ray = Ray::new(Vec3::new(-0.3, 0.0, 5.0), -Vec3::Z);
    let hit = g.intersect(&ray, f32::INFINITY, &mut ()).expect("hits");
    assert_eq!(hit.instance, Some(0));
    assert!(g.occluded(&ray, 20.0, &mut ()));
    assert!(!g.occluded(&ray, 5.0 + -0.3 * 0.5 - 1e-3, &mut ()));
    let miss = Ray::new(Vec3::new(2.0, 2.0, 5.0), Vec3::new(0.0, 0.0, -10.0));
    assert!(!g.occluded(&miss, 1.0, &mut ()));
}

#[test]
fn shadow_rays_through_instanced_glass_multiply_every_face() {
    let r = placed_instances();
    let g = geometry(&r);
    let materials = r.world.resource::<Materials>();
    let glass = materials
        .list
        .iter()
        .position(|m| m.alpha < 1.0)
        .expect("a glass material") as u32;
    let alpha = materials.list[glass as usize].alpha;
    let kd = materials.kd_at(glass, glam::Vec2::ZERO);
    let face = (1.0 - alpha) * (Vec3::ONE - (Vec3::ONE - kd) * alpha);
    // Through both cubes along -z: four faces.
    let ray = Ray::new(Vec3::new(0.1, 5.1, 10.0), Vec3::new(0.0, 0.0, -20.0));
    let tint = g.transmittance(&ray, 1.0, materials, &mut ());
    assert_close(tint, face * face * face * face, 1e-6);
    // Stopping between the cubes (z = -1): two faces.
    let tint = g.transmittance(&ray, 0.55, materials, &mut ());
    assert_close(tint, face * face, 1e-6);
    // Through the opaque sheared quad: nothing.
    let ray = Ray::new(Vec3::new(0.1, 0.1, 5.0), Vec3::new(0.0, 0.0, -10.0));
    assert_eq!(g.transmittance(&ray, 1.0, materials, &mut ()), Vec3::ZERO);
}

/// An icosphere-like mesh: `n` thin triangles fanned around the unit sphere.
fn small_mesh(n: usize) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|i| {
            let a = i as f32 / n as f32 * std::f32::consts::TAU;
            let b = (i + 1) as f32 / n as f32 * std::f32::consts::TAU;
            [
                Vec3::new(a.cos(), a.sin(), -0.5),
                Vec3::new(b.cos(), b.sin(), -0.5),
                Vec3::new(0.0, 0.0, 0.5),
            ]
        })
        .collect()
}

#[test]
fn a_million_instances_cost_memory_per_instance_not_per_triangle() {
    let tris = small_mesh(1000);
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t)).collect();
    let mesh = WideBvh::collapse(&Bvh::build(&bounds, SplitMethod::SahBinned), &tris);
    let mesh_bytes = mesh.bytes();
    // A 1000 x 1000 grid of unit cones, spacing 3, each turned a little.
    let side = 1000;
    let instances: Vec<Instance> = (0..side * side)
        .map(|k| {
            let (i, j) = ((k % side) as f32, (k / side) as f32);
            let m = Affine3A::from_scale_rotation_translation(
                Vec3::splat(1.0 + 0.1 * (k % 7) as f32),
                glam::Quat::from_rotation_z(0.01 * (k % 13) as f32),
                Vec3::new(3.0 * i, 3.0 * j, 0.0),
            );
            Instance::new(m, 0).unwrap()
        })
        .collect();
    let two = TwoLevelBvh::new(vec![mesh], instances, SplitMethod::SahBinned);
    assert_eq!(two.triangles_drawn(), 1_000_000_000);
    let per_instance = (two.bytes() - mesh_bytes) as f64 / 1e6;
    // Two affine maps and an index (144 bytes with glam's SIMD padding) and the top
    // level's nodes and indices; flattening would hold ~10^11 bytes.
    eprintln!("{per_instance} bytes per instance, {} in all", two.bytes());
    assert!(per_instance < 250.0, "{per_instance} bytes per instance");
    assert!(two.bytes() < 300_000_000);
    // Down onto the apex of the instance at grid (500, 200): the top of its cone.
    let k = 200 * side + 500;
    let ray = Ray::new(Vec3::new(1500.0, 600.0, 10.0), -Vec3::Z);
    let (instance, _, h) = two.closest_hit(&ray, f32::INFINITY).expect("hits");
    assert_eq!(instance, k as u32);
    let scale = 1.0 + 0.1 * (k % 7) as f32;
    assert!((h.t - (10.0 - 0.5 * scale)).abs() < 1e-4, "t = {}", h.t);
    assert!(two.any_hit(&ray, f32::INFINITY, |_, _, _| true));
    // Between the cones.
    let gap = Ray::new(Vec3::new(1501.5 + 0.05, 601.5, 10.0), -Vec3::Z);
    assert!(two.closest_hit(&gap, f32::INFINITY).is_none());
}

#[test]
fn metal_rough_spheres_share_one_sphere_under_the_two_level_bvh() {
    let Some(assets) = common::assets::shared_assets("metal_rough_spheres_share_one_sphere") else {
        return;
    };
    let file = assets.join(
        "khronos-gltf/MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
    );
    let mut r = Renderer::from_model(&file, &common::assets::small()).expect("loads");
    r.prepare().expect("prepares");
    let g = geometry(&r);
    // 98 meshes (one per material) read the same accessors: one geometry, 98 instances.
    assert_eq!(g.instanced.meshes.len(), 1);
    assert_eq!(g.instanced.instances.len(), 98);
    assert_eq!(g.triangles_drawn(), 1_040_409);
    // Stored once, the scene's triangles take about a megabyte, not ~150 MB.
    assert!(
        g.triangle_bytes() < 2_000_000,
        "{} bytes",
        g.triangle_bytes()
    );
}

/// Rays from the camera's side through a grid of points, and segments from points
/// on the floor to the light: hits on the flattened floor, on instances, on spheres,
/// and misses; shadow segments blocked and clear.
fn mixed_rays() -> Vec<(Ray, f32)> {
    let mut rays = Vec::new();
    for i in 0..24 {
        for j in 0..24 {
            let (u, v) = (i as f32 / 23.0, j as f32 / 23.0);
            let eye = Vec3::new(-0.3 + 0.6 * v, 1.5, 6.0);
            let target = Vec3::new(-3.0 + 6.0 * u, -2.5 + 5.0 * v, -1.0 + u * v);
            rays.push((Ray::new(eye, target - eye), f32::INFINITY));
            let floor = Vec3::new(-4.0 + 8.0 * u, -0.999, -4.0 + 8.0 * v);
            let light = Vec3::new(2.0, 6.0, 4.0);
            rays.push((Ray::new(floor, light - floor), 1.0));
        }
    }
    rays
}

#[test]
fn packet_queries_give_each_ray_its_answer_over_triangles_instances_and_spheres() {
    // The render traces its queues 8 rays at a time: triangles as one packet, then
    // instances and spheres ray by ray. Each ray must get the single-ray query's answer.
    let spheres = "entities: [
        Sphere((center: (0.5, 0.2, 2.0), radius: 0.4, material: \"matte\")),
        Sphere((center: (-2.0, 1.0, -1.0), radius: 0.6, material: \"mirror\")), ";
    let mut r = load(&scene(8).replace("entities: [", spheres));
    share_meshes(&mut r);
    r.prepare().expect("prepares");
    let g = geometry(&r);
    assert!(g.triangles_flattened() > 0 && !g.instanced.is_empty());
    assert!(!g.sphere_bvh.nodes.is_empty());
    let rays = mixed_rays();
    let (mut kinds, mut blocked) = ([0; 4], 0);
    // The render's buffer of hits, reused packet after packet: the last packet's hits
    // must not show through.
    let mut reused = PacketSceneHits::default();
    for chunk in rays.chunks(7).flat_map(|c| [&c[..1], &c[1..]]) {
        let (r, t): (Vec<Ray>, Vec<f32>) = chunk.iter().copied().unzip();
        // One t_max per call, as the render passes it: split by bound.
        for bound in [f32::INFINITY, 1.0] {
            let (rs, _): (Vec<Ray>, Vec<f32>) = r
                .iter()
                .zip(&t)
                .filter(|(_, tm)| **tm == bound)
                .map(|(r, t)| (*r, *t))
                .unzip();
            if rs.is_empty() {
                continue;
            }
            let mut hits = vec![None; rs.len()];
            g.intersect_packet(&rs, bound, &mut hits);
            g.intersect_packet_lanes_into(&rs, bound, &mut reused);
            for (r, hit) in hits.iter().enumerate() {
                assert_eq!(reused.get(r), *hit, "lane {r} of a reused buffer");
            }
            let occluded = g.occluded_packet(&rs, bound);
            for (i, (ray, hit)) in rs.iter().zip(&hits).enumerate() {
                let want = g.intersect(ray, bound, &mut ());
                assert_eq!(*hit, want, "{ray:?} t_max {bound}");
                let k = match want {
                    None => 0,
                    Some(h) if h.kind == PrimKind::Sphere => 1,
                    Some(h) if h.instance.is_some() => 2,
                    Some(_) => 3,
                };
                kinds[k] += 1;
                let want = g.occluded(ray, bound, &mut ());
                assert_eq!(occluded >> i & 1 == 1, want, "{ray:?} t_max {bound}");
                blocked += want as usize;
            }
        }
    }
    // Every kind of answer occurs, so a packet path that skipped one would fail.
    assert!(
        kinds.iter().all(|&k| k > 10),
        "misses, spheres, instances, flattened: {kinds:?}"
    );
    assert!(
        blocked > 100 && blocked < rays.len() - 100,
        "{blocked} of {}",
        rays.len()
    );
}
