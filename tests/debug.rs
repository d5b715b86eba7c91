//! System-level tests of the visual debug: the debug trace runs the render's own
//! schedules, its emitters spawn the expected entities, and the view projects and clips.

mod common;

use std::any::TypeId;
use std::path::Path;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{ScheduleLabel, Schedules};
use common::{load_file, parse, render_file, scene_path, temp_dir};
use glam::{Vec2, Vec3};
use glint::accel::TraversalStats;
use glint::debug::overlay::{Canvas, OverlayInput, draw_world};
use glint::debug::record::recorder_types;
use glint::debug::{
    DebugEmit, DebugPrimitive, DebugRequest, DebugSession, DebugTrace, Feature, Shape, Values,
    ViewCamera, debug_emit_schedule,
};
use glint::scene::format::SceneFile;
use glint::scene::{Camera, read_scene};
use glint::schedule::{Bounce, Prepare, RenderPass};
use glint::trace::camera::camera_ray;
use glint::trace::geometry::{PrimKind, SceneGeometry};
use glint::trace::log::TraceLog;

fn debug(file: &SceneFile, request: DebugRequest) -> DebugSession {
    DebugSession::trace(file, &scene_path(), request).unwrap()
}

fn only(x: u32, y: u32, features: &[Feature]) -> DebugRequest {
    DebugRequest {
        pixel: [x, y],
        features: features.iter().copied().collect(),
        bvh_level: None,
    }
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

fn with_what<'a>(prims: &'a [DebugPrimitive], what: &str) -> Vec<&'a DebugPrimitive> {
    prims.iter().filter(|p| p.values.what == what).collect()
}

/// A mirror at 45 degrees at the origin sends the centre ray to +x, a second mirror at
/// x = 2 sends it up to a diffuse ceiling at y = 3, lit from below; a transparent pane
/// and an area light elsewhere so every stage runs.
const MIRRORS: &str = r#"(
    camera: (position: (0.0, 0.0, 4.0), look_at: (0.0, 0.0, 0.0), fov_y: 40.0, width: 65, height: 65),
    settings: (shading_model: lambertian, pixel_samples: 1),
    materials: {
        "mirror": (kd: (0.0, 0.0, 0.0), ks: (1.0, 1.0, 1.0)),
        "ceiling": (kd: (0.8, 0.6, 0.4)),
        "glass": (kd: (0.2, 0.4, 0.9), transparency: 0.5),
    },
    entities: [
        Mesh((material: Some("mirror"), geometry: Parallelogram(
            origin: (-0.35355, -0.5, 0.35355), edge_u: (0.0, 1.0, 0.0), edge_v: (0.70711, 0.0, -0.70711)))),
        Mesh((material: Some("mirror"), geometry: Parallelogram(
            origin: (1.64645, -0.35355, -0.5), edge_u: (0.0, 0.0, 1.0), edge_v: (0.70711, 0.70711, 0.0)))),
        Mesh((material: Some("ceiling"), geometry: Parallelogram(
            origin: (1.0, 3.0, -1.0), edge_u: (2.0, 0.0, 0.0), edge_v: (0.0, 0.0, 2.0)))),
        Mesh((material: Some("glass"), geometry: Parallelogram(
            origin: (-2.0, -1.5, 0.5), edge_u: (1.0, 0.0, 0.0), edge_v: (0.0, 1.0, 0.0)))),
        Mesh((material: Some("ceiling"), geometry: Parallelogram(
            origin: (-3.0, -2.0, -1.0), edge_u: (3.0, 0.0, 0.0), edge_v: (0.0, 2.0, 0.0)))),
        PointLight((position: (2.0, 2.0, 0.5), color: (1.0, 1.0, 1.0))),
        SegmentLight((endpoint0: (-2.0, 1.0, 2.0), endpoint1: (-1.0, 1.0, 2.0), color0: (0.5, 0.5, 0.5), color1: (0.5, 0.2, 0.2))),
    ],
)"#;

/// A floor lit by a segment light across x in [-2, 2] at y = 2; a blocker at y = 1
/// covers x < 0, so from the floor point (0.5, 0, 0) a light sample is visible exactly
/// when its x > -0.5.
const SHADOWS: &str = r#"(
    camera: (position: (0.5, 5.0, 3.0), look_at: (0.5, 0.0, 0.0), fov_y: 30.0, width: 65, height: 65),
    settings: (shading_model: lambertian, shadow_samples: 16),
    materials: { "white": (kd: (0.8, 0.8, 0.8)) },
    entities: [
        Mesh((material: Some("white"), geometry: Parallelogram(
            origin: (-5.0, 0.0, 5.0), edge_u: (10.0, 0.0, 0.0), edge_v: (0.0, 0.0, -10.0)))),
        Mesh((material: Some("white"), geometry: Parallelogram(
            origin: (-5.0, 1.0, -5.0), edge_u: (5.0, 0.0, 0.0), edge_v: (0.0, 0.0, 10.0)))),
        SegmentLight((endpoint0: (-2.0, 2.0, 0.0), endpoint1: (2.0, 2.0, 0.0), color0: (1.0, 0.5, 0.2), color1: (1.0, 0.5, 0.2))),
        PointLight((position: (-3.0, 3.0, 0.0), color: (0.3, 0.3, 0.3))),
    ],
)"#;

/// Spheres and an icosphere in one BVH-heavy scene, with stratified samples.
const BUSY: &str = r#"(
    camera: (position: (0.0, 1.0, 6.0), look_at: (0.0, 0.5, 0.0), fov_y: 45.0, width: 48, height: 40),
    settings: (shading_model: blinn_phong, pixel_samples: 4, pixel_sampling: stratified, shadow_samples: 2),
    materials: {
        "a": (kd: (0.7, 0.3, 0.2), ks: (0.3, 0.3, 0.3), shininess: 20.0),
        "b": (kd: (0.2, 0.7, 0.3), transparency: 0.6),
        "floor": (kd: (0.6, 0.6, 0.6), ks: (0.2, 0.2, 0.2)),
    },
    entities: [
        Mesh((material: Some("a"), geometry: Icosphere(subdivisions: 3),
            transform: (translate: (-0.8, 0.8, 0.0), scale: (0.8, 0.8, 0.8)))),
        Sphere((center: (0.9, 0.7, 0.3), radius: 0.7, material: "b")),
        Mesh((material: Some("floor"), geometry: Plane(subdivisions: 8),
            transform: (scale: (8.0, 1.0, 8.0)))),
        ParallelogramLight((v0: (-1.0, 3.0, -1.0), edge01: (2.0, 0.0, 0.0), edge02: (0.0, 0.0, 2.0),
            color0: (1.0, 1.0, 1.0), color1: (1.0, 0.8, 0.8), color2: (0.8, 0.8, 1.0), color3: (1.0, 1.0, 1.0))),
    ],
)"#;

#[test]
fn debug_colour_equals_rendered_colour() {
    let mut scenes = vec![
        ("mirrors", parse(MIRRORS)),
        ("shadows", parse(SHADOWS)),
        ("busy", parse(BUSY)),
    ];
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.ron");
    let mut file = read_scene(&cornell).unwrap();
    file.camera.width = 64;
    file.camera.height = 64;
    scenes.push(("cornell", file));
    for (name, file) in &scenes {
        let rendered = render_file(file);
        let film = rendered.film();
        let (w, h) = (film.width, film.height);
        let mut lit = 0;
        for (x, y) in [
            (w / 2, h / 2),
            (3, 5),
            (w - 1, h - 1),
            (w / 3, 2 * h / 3),
            (2 * w / 3, h / 4),
        ] {
            let session = debug(file, DebugRequest::all(x, y));
            let expected = film.pixel(x, y);
            // Exactly equal: the same systems traced the same samples.
            assert_eq!(session.pixel_color(), expected, "{name} pixel {x},{y}");
            lit += (expected != Vec3::ZERO) as u32;
        }
        assert!(lit >= 2, "{name}: too few lit pixels to compare");
    }
}

/// The system types in the render schedules of `world`.
fn render_system_types(world: &World) -> Vec<TypeId> {
    let schedules = world.resource::<Schedules>();
    let mut types = Vec::new();
    for label in [Prepare.intern(), RenderPass.intern(), Bounce.intern()] {
        let schedule = schedules.get(label).expect("render schedule");
        let systems = schedule.systems().expect("schedule ran");
        types.extend(systems.map(|(_, s)| s.system_type()));
    }
    types
}

#[test]
fn normal_render_schedules_no_recorder() {
    let file = parse(BUSY);
    let r = render_file(&file);
    let types = render_system_types(&r.world);
    assert!(types.len() >= 10, "the render schedules ran");
    for recorder in recorder_types() {
        assert!(!types.contains(&recorder), "a recorder in a normal render");
    }
    assert!(r.world.get_resource::<TraceLog>().is_none());

    // A debug session's render schedules hold every recorder.
    let s = debug(&file, DebugRequest::all(24, 20));
    let types = render_system_types(&s.renderer.world);
    for recorder in recorder_types() {
        assert!(
            types.contains(&recorder),
            "a recorder missing in a debug run"
        );
    }
}

#[test]
fn normal_render_spawns_no_debug_entities() {
    let file = parse(BUSY);
    let mut r = load_file(&file);
    // Even with the emitters registered, a render without a debug trace emits nothing.
    r.world.add_schedule(debug_emit_schedule());
    r.render(None, &mut |_| {}).unwrap();
    r.world.run_schedule(DebugEmit);
    let mut q = r.world.query::<&DebugPrimitive>();
    assert_eq!(q.iter(&r.world).count(), 0);
    assert!(r.world.get_resource::<DebugTrace>().is_none());

    // The same scene in a debug run does emit.
    let mut s = debug(&file, DebugRequest::all(24, 20));
    assert!(s.primitives().len() > 10);
}

#[test]
fn reflection_chain_matches_analytic_bounce_points() {
    let mut s = debug(&parse(MIRRORS), only(32, 32, &[Feature::Reflections]));
    let prims = s.primitives();
    let camera = with_what(&prims, "camera ray");
    assert_eq!(camera.len(), 1);
    let Shape::Segment { a, b } = camera[0].shape else {
        panic!("camera ray is a segment")
    };
    assert!(close(a, Vec3::new(0.0, 0.0, 4.0), 1e-6));
    assert!(close(b, Vec3::ZERO, 1e-4), "first bounce at {b}");
    assert!((camera[0].values.t.unwrap() - 4.0).abs() < 1e-4);

    let rays = with_what(&prims, "reflection ray");
    assert_eq!(
        rays.len(),
        2,
        "two reflection levels: the ceiling is diffuse"
    );
    let expected = [
        (Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)),
        (Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 3.0, 0.0)),
    ];
    for (p, (ea, eb)) in rays.iter().zip(expected) {
        let Shape::Segment { a, b } = p.shape else {
            panic!("reflection ray is a segment")
        };
        assert!(close(a, ea, 1e-4) && close(b, eb, 1e-4), "{a} -> {b}");
    }
    // Each level in its own colour, starting from red.
    assert_eq!(rays[0].color, glint::debug::emit::REFLECTION_FIRST);
    assert_ne!(rays[0].color, rays[1].color);
    assert_eq!(rays[1].values.depth, Some(2));

    let normals = with_what(&prims, "normal at reflection");
    assert_eq!(normals.len(), 2);
    let s2 = std::f32::consts::FRAC_1_SQRT_2;
    for (p, (at, n)) in normals.iter().zip([
        (Vec3::ZERO, Vec3::new(s2, 0.0, s2)),
        (Vec3::new(2.0, 0.0, 0.0), Vec3::new(-s2, s2, 0.0)),
    ]) {
        let Shape::Segment { a, b } = p.shape else {
            panic!("normal is a segment")
        };
        assert!(close(a, at, 1e-4));
        assert!(
            close((b - a).normalize(), n, 1e-3),
            "normal {}",
            (b - a).normalize()
        );
        assert_eq!(p.color, glint::debug::emit::NORMAL);
    }
    // Only the asked feature (and the pixel itself) emitted.
    assert!(
        prims
            .iter()
            .all(|p| matches!(p.feature, Feature::Pixel | Feature::Reflections))
    );
}

#[test]
fn the_debug_keeps_the_binary_triangle_bvh_a_render_drops() {
    let file = parse(BUSY);
    let s = debug(&file, only(12, 20, &[Feature::Bvh]));
    assert!(s.renderer.plan().binary_triangle_bvh);
    let g = s.renderer.world.resource::<SceneGeometry>();
    assert!(!g.tri_bvh.nodes.is_empty());
    // The wide tree's lanes hold the binary tree's triangle order, padding aside.
    let lanes = g.tri_wide.leaves.prims();
    let in_lanes: Vec<u32> = lanes
        .filter(|&p| p != glint::accel::leaf::NO_PRIM)
        .collect();
    assert_eq!(g.tri_bvh.prim_indices, in_lanes);
    // The trace log walked it: the camera ray visited triangle nodes.
    let nodes = &s.log().rays[0].traversal.nodes;
    assert!(nodes.iter().any(|v| v.kind == PrimKind::Triangle));
}

#[test]
fn bvh_visits_match_traversal_statistics() {
    let file = parse(BUSY);
    for (x, y) in [(12, 20), (30, 22), (24, 35)] {
        let mut s = debug(&file, only(x, y, &[Feature::Bvh]));
        let prims = s.primitives();
        let boxes: Vec<_> = prims
            .iter()
            .filter(|p| matches!(p.shape, Shape::Box { .. }))
            .collect();
        let ray = s.log().camera_samples[0].ray;
        let geometry = s.renderer.world.resource::<SceneGeometry>();
        let mut stats = TraversalStats::default();
        let hit = geometry.intersect(&ray, f32::INFINITY, &mut stats);
        assert_eq!(boxes.len() as u64, stats.nodes_visited, "pixel {x},{y}");
        assert_eq!(
            s.log().rays[0].traversal.prims.len() as u64,
            stats.prims_tested
        );
        let hit = hit.expect("these pixels hit something");
        // One white final leaf holding the hit point; the root box is red.
        let finals = with_what(&prims, "final bvh leaf");
        assert_eq!(finals.len(), 1);
        assert_eq!(finals[0].color, Vec3::ONE);
        let p = ray.at(hit.t);
        let Shape::Box { min, max } = finals[0].shape else {
            panic!("a box")
        };
        assert!(p.cmpge(min - 1e-4).all() && p.cmple(max + 1e-4).all());
        let root = boxes.iter().find(|b| b.values.depth == Some(0)).unwrap();
        assert_eq!(root.color, Vec3::new(1.0, 0.0, 0.0));
        let hit_marker = with_what(&prims, "bvh hit point");
        assert_eq!(hit_marker.len(), 1);
        assert!((hit_marker[0].values.t.unwrap() - hit.t).abs() < 1e-6);
    }

    // The whole-scene level view: every node at the level, nothing else of the BVH.
    let mut request = only(24, 20, &[Feature::Bvh]);
    request.bvh_level = Some(2);
    let mut s = debug(&file, request);
    let level = with_what(&s.primitives(), "bvh level").len();
    let g = s.renderer.world.resource::<SceneGeometry>();
    let expected = [&g.tri_bvh, &g.sphere_bvh]
        .iter()
        .map(|b| {
            glint::debug::emit::node_depths(b)
                .iter()
                .filter(|(_, d)| *d == 2)
                .count()
        })
        .sum::<usize>();
    assert!(expected > 0);
    assert_eq!(level, expected);
}

#[test]
fn shadow_ray_colours_match_visibility() {
    let mut s = debug(&parse(SHADOWS), only(32, 32, &[Feature::Lights]));
    let prims = s.primitives();
    let first = with_what(&prims, "first hit");
    let Shape::Marker { center, .. } = first[0].shape else {
        panic!("a marker")
    };
    assert!(close(center, Vec3::new(0.5, 0.0, 0.0), 1e-3), "{center}");
    let samples: Vec<_> = with_what(&prims, "light sample")
        .into_iter()
        .filter(|p| p.values.light == Some(1))
        .collect();
    assert_eq!(samples.len(), 16);
    let (mut seen_visible, mut seen_blocked) = (0, 0);
    for p in &samples {
        let Shape::Segment { a, .. } = p.shape else {
            panic!("a segment")
        };
        let visible = a.x > -0.5;
        assert_eq!(p.values.visible, Some(visible), "light sample at {a}");
        if visible {
            assert!(
                close(p.color, Vec3::new(1.0, 0.5, 0.2), 1e-5),
                "{}",
                p.color
            );
            assert_ne!(p.values.arrived, Some(Vec3::ZERO));
            seen_visible += 1;
        } else {
            assert_eq!(p.color, Vec3::ZERO);
            assert_eq!(p.values.arrived, Some(Vec3::ZERO));
            seen_blocked += 1;
        }
    }
    assert!(seen_visible > 0 && seen_blocked > 0);
    // The point light at x = -3 is behind the blocker: black.
    let point: Vec<_> = with_what(&prims, "light sample")
        .into_iter()
        .filter(|p| p.values.light == Some(0))
        .collect();
    assert_eq!(point.len(), 1);
    assert_eq!(point[0].color, Vec3::ZERO);
    // Every area light sample is marked on the light.
    assert_eq!(with_what(&prims, "area light sample").len(), 16);
}

#[test]
fn sample_grid_shows_the_pattern() {
    let mut file = parse(BUSY);
    file.settings.pixel_samples = 9;
    let mut s = debug(&file, only(10, 10, &[Feature::Samples]));
    let prims = s.primitives();
    let grids: Vec<_> = prims
        .iter()
        .filter_map(|p| match &p.shape {
            Shape::SampleGrid { strata, points } => Some((*strata, points.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(grids.len(), 1);
    let (strata, points) = &grids[0];
    assert_eq!(*strata, Some(3));
    let mut cells: Vec<(u32, u32)> = points
        .iter()
        .map(|p| ((p.x * 3.0) as u32, (p.y * 3.0) as u32))
        .collect();
    cells.sort();
    cells.dedup();
    assert_eq!(cells.len(), 9, "one sample per stratum");

    file.settings.pixel_sampling = glint::scene::PixelSampling::Uniform;
    file.settings.pixel_samples = 5;
    let mut s = debug(&file, only(10, 10, &[Feature::Samples]));
    let grid = s.primitives().into_iter().find_map(|p| match p.shape {
        Shape::SampleGrid { strata, points } => Some((strata, points.len())),
        _ => None,
    });
    assert_eq!(grid, Some((None, 5)));
    let what = |s: &mut DebugSession| {
        s.primitives()
            .into_iter()
            .find(|p| matches!(p.shape, Shape::SampleGrid { .. }))
            .map(|p| p.values.what)
    };
    assert_eq!(what(&mut s), Some("uniform samples"));
    // Under the Sobol' sampler the offsets are its points, and the label says so.
    file.settings.sampler = glint::scene::SamplerKind::Sobol;
    let mut s = debug(&file, only(10, 10, &[Feature::Samples]));
    assert_eq!(what(&mut s), Some("Sobol' samples"));

    // One sample per pixel: multisampling is off in the scene, so nothing is emitted.
    file.settings.pixel_samples = 1;
    let mut s = debug(&file, only(10, 10, &[Feature::Samples]));
    assert!(s.primitives().iter().all(|p| p.feature == Feature::Pixel));
}

#[test]
fn emitters_run_only_for_features_on_and_asked() {
    let mut file = parse(BUSY);
    let mut s = debug(&file, only(24, 20, &[Feature::Lights]));
    let prims = s.primitives();
    assert!(prims.iter().any(|p| p.feature == Feature::Lights));
    assert!(
        prims
            .iter()
            .all(|p| matches!(p.feature, Feature::Pixel | Feature::Lights))
    );
    // BVH asked for but off in the scene.
    file.settings.acceleration = glint::scene::Acceleration::None;
    let mut s = debug(&file, only(24, 20, &[Feature::Bvh]));
    assert!(s.primitives().iter().all(|p| p.feature == Feature::Pixel));
    assert_eq!(s.features_off(), vec![Feature::Bvh]);
}

#[test]
fn texture_panel_marks_the_looked_up_texels() {
    let tmp = temp_dir();
    let png = tmp.path().join("checker.png");
    let img = image::RgbImage::from_fn(4, 4, |i, j| {
        image::Rgb([(i * 60) as u8, (j * 60) as u8, 100])
    });
    img.save(&png).unwrap();
    // The quad's texture coordinate at the origin (the centre pixel) is (0.3, 0.8).
    let text = format!(
        r#"(
        camera: (position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0), width: 33, height: 33),
        settings: (shading: false, bilinear_filtering: {{BILINEAR}}),
        materials: {{ "tex": (kd_texture: Some("{}")) }},
        entities: [
            Mesh((material: Some("tex"), geometry: Parallelogram(
                origin: (-0.6, -1.6, 0.0), edge_u: (2.0, 0.0, 0.0), edge_v: (0.0, 2.0, 0.0)))),
            PointLight((position: (0.0, 0.0, 2.0), color: (1.0, 1.0, 1.0))),
        ],
    )"#,
        png.display()
    );
    for bilinear in [false, true] {
        let file = parse(&text.replace("{BILINEAR}", &bilinear.to_string()));
        let mut s = debug(&file, only(16, 16, &[Feature::Textures]));
        let prims = s.primitives();
        let panel = prims
            .iter()
            .find_map(|p| match &p.shape {
                Shape::TexturePanel {
                    size, uv, texels, ..
                } => Some((*size, *uv, texels.clone())),
                _ => None,
            })
            .expect("a texture panel");
        assert_eq!(panel.0, [4, 4]);
        assert!(
            (panel.1 - Vec2::new(0.3, 0.8)).abs().max_element() < 1e-4,
            "{}",
            panel.1
        );
        let mut texels = panel.2;
        texels.sort_by_key(|t| t.0);
        if bilinear {
            let expect = [
                ([0, 0], 0.21),
                ([0, 1], 0.09),
                ([1, 0], 0.49),
                ([1, 1], 0.21),
            ];
            assert_eq!(texels.len(), 4);
            for (got, want) in texels.iter().zip(expect) {
                assert_eq!(got.0, want.0);
                assert!((got.1 - want.1).abs() < 1e-3, "{got:?}");
            }
        } else {
            // Column floor(0.3 * 4) = 1, row from the top floor((1 - 0.8) * 4) = 0.
            assert_eq!(texels, vec![([1, 0], 1.0)]);
        }
        // The debug colour is the rendered one (shading off: the texel colour itself).
        assert_eq!(s.pixel_color(), render_file(&file).film().pixel(16, 16));
    }
}

fn test_view() -> ViewCamera {
    ViewCamera::new(
        Camera {
            position: Vec3::new(1.0, 2.0, 5.0),
            look_at: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 50.0,
            width: 120,
            height: 90,
        },
        0.01,
    )
}

#[test]
fn projection_lands_on_the_expected_pixels() {
    let view = test_view();
    let pa = camera_ray(&view.camera, 10.5, 20.5).at(3.0);
    let pb = camera_ray(&view.camera, 100.5, 70.5).at(7.0);
    let (a, _) = view.project(pa).unwrap();
    let (b, _) = view.project(pb).unwrap();
    assert!((a - Vec2::new(10.5, 20.5)).length() < 1e-3, "{a}");
    assert!((b - Vec2::new(100.5, 70.5)).length() < 1e-3, "{b}");

    let prim = DebugPrimitive {
        feature: Feature::Pixel,
        color: Vec3::ONE,
        shape: Shape::Segment { a: pa, b: pb },
        values: Values::default(),
    };
    let mut canvas = Canvas::new(120, 90, Vec3::ZERO);
    let input = OverlayInput {
        view: &view,
        scene_depth: None,
        textures: &[],
    };
    draw_world(&mut canvas, &input, &[&prim]);
    // Both ends and the screen-space midpoint are drawn; a pixel off the line is not.
    for (x, y) in [(10, 20), (100, 70), (55, 45)] {
        assert_eq!(canvas.get(x, y), Vec3::ONE, "({x}, {y})");
    }
    assert_eq!(canvas.get(100, 20), Vec3::ZERO);
}

#[test]
fn segment_crossing_behind_the_view_is_clipped_not_wrapped() {
    let view = test_view();
    let front = view.camera.position + view.basis.forward * 4.0 + view.basis.right * 0.5;
    let behind = view.camera.position - view.basis.forward * 4.0 + view.basis.right * 0.5;
    let ((a, za), (b, zb)) = view
        .project_segment(front, behind)
        .expect("part is in front");
    assert!((za - 4.0).abs() < 1e-4);
    assert!(
        (zb - view.near).abs() < 1e-4,
        "clipped at the near plane: {zb}"
    );
    // The segment stays right of the centre all the way, so its projection runs right.
    assert!(b.x > a.x && a.x > 60.0, "{a} -> {b}");
    // A naive projection of the point behind the eye lands on the wrong (left) side.
    let v = behind - view.camera.position;
    let naive_x = v.dot(view.basis.right)
        / (v.dot(view.basis.forward) * view.basis.tan_half * view.basis.aspect);
    assert!(naive_x < 0.0);
    assert!(view.project(behind).is_none());
    // Wholly behind: nothing.
    assert!(
        view.project_segment(behind, behind - view.basis.forward)
            .is_none()
    );

    // Drawn: nothing appears left of the front end's projection.
    let prim = DebugPrimitive {
        feature: Feature::Pixel,
        color: Vec3::ONE,
        shape: Shape::Segment {
            a: front,
            b: behind,
        },
        values: Values::default(),
    };
    let mut canvas = Canvas::new(120, 90, Vec3::ZERO);
    let input = OverlayInput {
        view: &view,
        scene_depth: None,
        textures: &[],
    };
    draw_world(&mut canvas, &input, &[&prim]);
    let lit: Vec<u32> = (0..90)
        .flat_map(|y| (0..120).map(move |x| (x, y)))
        .filter(|&(x, y)| canvas.get(x, y) == Vec3::ONE)
        .map(|(x, _)| x)
        .collect();
    assert!(!lit.is_empty());
    assert!(
        lit.iter().all(|&x| x as f32 >= a.x - 2.0),
        "wrapped pixels drawn"
    );
}

#[test]
fn dump_lists_entities_as_ron() {
    let mut s = debug(&parse(MIRRORS), DebugRequest::all(32, 32));
    let text = s.dump_ron().unwrap();
    let n = s.primitives().len();
    assert_eq!(text.matches("kind:").count(), n);
    for needle in [
        "kind: \"segment\"",
        "feature: reflections",
        "t: ",
        "barycentrics:",
        "what: \"reflection ray\"",
    ] {
        assert!(text.contains(needle), "dump lacks {needle}");
    }
    // It is valid RON.
    let value: ron::Value = ron::from_str(&text).unwrap();
    assert!(matches!(value, ron::Value::Map(_)));
}

#[test]
fn debug_image_is_written() {
    let mut s = debug(&parse(BUSY), DebugRequest::all(24, 20));
    let view = s.view(None, 160, 120);
    // The auto view is not the render camera.
    assert_ne!(view.camera.position, s.renderer.camera().unwrap().position);
    let background = s.background(&view).unwrap();
    let canvas = s.draw(&view, background.clone(), true);
    assert_eq!((canvas.width, canvas.height), (160, 120));
    assert_ne!(canvas.pixels, background.pixels, "something was drawn");
}
