//! System-level tests of the spine: load a scene into a World, run the schedules,
//! assert on the film, the BVH and the statistics.

mod common;

use common::*;
use glam::Vec3;
use glint::accel::Aabb;
use glint::stats::Stage;
use glint::trace::geometry::SceneGeometry;
use glint::trace::plan::BinaryBvhObserver;

const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;

fn lit_quad_scene(model: &str, extra: &str) -> String {
    format!(
        "({cam}, settings: (shading_model: {model}),
          materials: {{ \"m\": (kd: (0.5, 0.4, 0.3), ks: (0.6, 0.6, 0.6), shininess: 2) }},
          entities: [{quad}, PointLight((position: (1, 0, 1), color: (1.0, 0.8, 0.6))) {extra}])",
        cam = camera(2.0, 3),
        quad = quad(0.0, "m"),
    )
}

#[test]
fn lambertian_pixel_equals_kd_times_light_times_cosine() {
    let r = render(&lit_quad_scene("lambertian", ""));
    let expected = Vec3::new(0.5, 0.4, 0.3) * Vec3::new(1.0, 0.8, 0.6) * SQRT_HALF;
    assert_close(r.film().pixel(1, 1), expected, 1e-4);
}

#[test]
fn an_occluder_between_point_and_light_makes_the_pixel_exactly_black() {
    let blocker = ", Mesh((material: Some(\"m\"), geometry: Parallelogram(origin: (0.4, -0.1, 0.5), edge_u: (0.2, 0, 0), edge_v: (0, 0.2, 0))))";
    let r = render(&lit_quad_scene("lambertian", blocker));
    assert_eq!(r.film().pixel(1, 1), Vec3::ZERO);
    assert!(r.stats().items(Stage::TraceShadowRays) > 0);
}

#[test]
fn phong_pixel_matches_the_closed_form() {
    // l = (1,0,1)/sqrt2, v = n = +z: r = reflect(-l, n) = (-1,0,1)/sqrt2, r.v = 1/sqrt2.
    let r = render(&lit_quad_scene("phong", ""));
    let light = Vec3::new(1.0, 0.8, 0.6);
    let diffuse = Vec3::new(0.5, 0.4, 0.3) * light * SQRT_HALF;
    let specular = Vec3::splat(0.6) * light * SQRT_HALF.powf(2.0);
    assert_close(r.film().pixel(1, 1), diffuse + specular, 1e-4);
}

#[test]
fn blinn_phong_pixel_matches_the_closed_form() {
    let r = render(&lit_quad_scene("blinn_phong", ""));
    let light = Vec3::new(1.0, 0.8, 0.6);
    let l = Vec3::new(1.0, 0.0, 1.0).normalize();
    let h = (l + Vec3::Z).normalize();
    let diffuse = Vec3::new(0.5, 0.4, 0.3) * light * SQRT_HALF;
    let specular = Vec3::splat(0.6) * light * h.z.powf(2.0);
    assert_close(r.film().pixel(1, 1), diffuse + specular, 1e-4);
}

#[test]
fn the_bvh_built_by_the_schedule_validates_and_covers_every_triangle() {
    let mut r = load(&std::fs::read_to_string("scenes/cornell_box.ron").unwrap());
    r.world.insert_resource(BinaryBvhObserver("this test"));
    r.prepare().unwrap();
    let g = r.world.resource::<SceneGeometry>();
    // 5 walls of 2 triangles, 2 boxes of 12.
    let positions = g.all_positions();
    assert_eq!(positions.len(), 34);
    let bounds: Vec<Aabb> = positions.iter().map(|p| Aabb::from_points(p)).collect();
    g.tri_bvh.validate(&bounds).unwrap();
    g.tri_wide.validate(&positions).unwrap();
    let mut covered = g.tri_bvh.prim_indices.clone();
    covered.sort_unstable();
    assert_eq!(covered, (0..34).collect::<Vec<u32>>());
    assert!(r.stats().ran(Stage::BuildTriangleBvh));
}

#[test]
fn triangles_named_by_index_lead_to_their_vertices_with_or_without_the_binary_tree() {
    for observed in [true, false] {
        let mut r = load(&std::fs::read_to_string("scenes/cornell_box.ron").unwrap());
        if observed {
            r.world.insert_resource(BinaryBvhObserver("this test"));
        }
        r.prepare().unwrap();
        let g = r.world.resource::<SceneGeometry>();
        // Kept only with the binary tree; searched without it.
        assert_eq!(g.tri_lanes.is_empty(), !observed);
        let lanes = g.tri_wide.prim_lanes();
        for p in 0..34u32 {
            assert_eq!(g.lane(p), lanes[p as usize]);
            assert_eq!(g.positions(p), g.tri_wide.triangle_at(lanes[p as usize]));
        }
    }
}

#[test]
#[should_panic(expected = "triangle 34 is not in the scene's wide BVH")]
fn a_triangle_index_past_the_scene_is_refused_not_read_from_another_lane() {
    let mut r = load(&std::fs::read_to_string("scenes/cornell_box.ron").unwrap());
    r.prepare().unwrap();
    r.world.resource::<SceneGeometry>().positions(34);
}

#[test]
fn a_render_keeps_only_the_wide_triangle_bvh() {
    let mut r = load(&std::fs::read_to_string("scenes/cornell_box.ron").unwrap());
    r.render(None, &mut |_| {}).unwrap();
    assert!(!r.plan().binary_triangle_bvh);
    let g = r.world.resource::<SceneGeometry>();
    assert!(g.tri_bvh.nodes.is_empty() && g.tri_bvh.prim_indices.is_empty());
    g.tri_wide.validate(&g.all_positions()).unwrap();
    assert_eq!(g.tri_wide.triangles, 34);
    let entry = r
        .plan()
        .entries
        .iter()
        .find(|e| e.stage == "keep binary triangle BVH");
    assert!(!entry.unwrap().runs);
}

#[test]
fn a_spheres_only_scene_builds_no_triangle_bvh() {
    let mut r = load(&std::fs::read_to_string("scenes/spheres.ron").unwrap());
    r.render(None, &mut |_| {}).unwrap();
    assert!(!r.stats().ran(Stage::BuildTriangleBvh));
    assert!(r.stats().ran(Stage::BuildSphereBvh));
    assert!(!r.plan().triangle_bvh);
}

#[test]
fn shadows_off_or_no_lights_run_no_shadow_stage() {
    let off = render(
        &lit_quad_scene("lambertian", "").replace("settings: (", "settings: (shadows: false, "),
    );
    assert!(!off.stats().ran(Stage::TraceShadowRays));
    assert_eq!(off.stats().rays.shadow, 0);
    // Without shadows the same pixel is lit even with the occluder in place.
    assert!(off.film().pixel(1, 1).x > 0.0);

    let dark = render(&format!(
        "({}, materials: {{ \"m\": () }}, entities: [{}])",
        camera(2.0, 3),
        quad(0.0, "m")
    ));
    assert!(!dark.stats().ran(Stage::TraceShadowRays));
    assert_eq!(dark.film().pixel(1, 1), Vec3::ZERO);
}

#[test]
fn one_and_two_threads_give_bit_identical_images() {
    let scene = std::fs::read_to_string("scenes/cornell_box.ron")
        .unwrap()
        .replace("width: 512", "width: 48")
        .replace("height: 512", "height: 48")
        .replace(
            "shading_model: phong,",
            "shading_model: phong, pixel_samples: 4, pixel_sampling: stratified,",
        );
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render(&scene).film().clone())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.count.iter().copied().max(), Some(4));
    assert!(one == two, "1- and 2-thread films differ");
}

#[test]
fn every_pixel_of_the_default_scene_is_finite_and_the_image_is_not_blank() {
    let scene = std::fs::read_to_string("scenes/cornell_box.ron")
        .unwrap()
        .replace("width: 512", "width: 64")
        .replace("height: 512", "height: 64");
    let r = render(&scene);
    let image = r.film().image();
    assert!(image.iter().all(|p| p.is_finite()));
    assert!(image.iter().filter(|p| p.max_element() > 0.05).count() > image.len() / 2);
    assert_eq!(r.stats().nonfinite_samples, 0);
}
