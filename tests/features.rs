//! The eight features of the report, pinned to numbers: recursion closed forms, a plain
//! recursive evaluator against the wavefront, ray spawning, barycentrics, light
//! visibility, and the plan's skipped stages for every project scene.

mod common;

use common::*;
use glam::{Vec2, Vec3};
use glint::accel::Ray;
use glint::sampling::Sampler;
use glint::scene::Settings;
use glint::shade::{Shading, ShadingInput};
use glint::stats::Stage;
use glint::test_util::Lcg;
use glint::trace::camera::camera_ray;
use glint::trace::geometry::{Hit, PrimKind, SceneGeometry};
use glint::trace::lights::Lights;
use glint::trace::materials::Materials;
use glint::trace::surface::{SHADOW_EPSILON, Surface, surface_at};

// ---------------------------------------------------------------- recursion

#[test]
fn parallel_mirrors_sum_ks_powers_up_to_the_depth_limit() {
    for (max_depth, ks) in [(6u32, 0.5f32), (3, 0.8), (0, 0.9), (12, 0.9)] {
        // Camera between two facing mirrors at z = 0 and z = 2; light beside the axis.
        let scene = format!(
            "({cam}, settings: (shading_model: lambertian, max_depth: {max_depth}),
              materials: {{ \"mirror\": (kd: (0.5, 0.5, 0.5), ks: ({ks}, {ks}, {ks})) }},
              entities: [{a}, {b}, PointLight((position: (0.5, 0, 1), color: (1, 1, 1)))])",
            cam = camera(1.0, 3).replace("fov_y: 30", "fov_y: 10"),
            a = quad(0.0, "mirror"),
            b = quad(2.0, "mirror"),
        );
        let r = render(&scene);
        let cos = 1.0 / 1.25f32.sqrt();
        let sum: f32 = (0..=max_depth).map(|k| ks.powi(k as i32)).sum();
        assert_close(r.film().pixel(1, 1), Vec3::splat(0.5 * cos * sum), 1e-4);
        // The centre pixel's chain alone spawns one reflection per level.
        assert!(r.stats().rays.reflection >= max_depth as u64);
        assert_eq!(r.stats().rays.reflection == 0, max_depth == 0);
    }
}

#[test]
fn stacked_transparent_quads_blend_to_the_closed_form() {
    let (alpha, kd, layers) = (0.6f32, Vec3::new(0.9, 0.5, 0.2), 4);
    let quads: Vec<String> = (0..layers)
        .map(|i| quad(-0.25 * i as f32, "glass"))
        .collect();
    let scene = format!(
        "({cam}, settings: (shading_model: lambertian),
          materials: {{ \"glass\": (kd: ({}, {}, {}), transparency: {alpha}) }},
          entities: [{}, PointLight((position: (0, 0, 5), color: (1, 1, 1)))])",
        kd.x,
        kd.y,
        kd.z,
        quads.join(", "),
        cam = camera(3.0, 3),
    );
    let r = render(&scene);
    // Layer i sees the light through i layers, each tinting by (1-a)(1-(1-kd)a).
    let tint = (1.0 - alpha) * (Vec3::ONE - (Vec3::ONE - kd) * alpha);
    let mut expected = Vec3::ZERO;
    for i in (0..layers).rev() {
        let direct = kd * tint.powf(i as f32);
        expected = alpha * direct + (1.0 - alpha) * expected;
    }
    assert_close(r.film().pixel(1, 1), expected, 1e-5);
    assert!(r.stats().ran(Stage::SpawnPassThroughRays));
}

/// SPEC's recursive pseudo-code, written plainly with call-stack recursion, sharing only
/// the intersection and shading primitives with the tracer.
struct Recursive<'a> {
    settings: &'a Settings,
    geometry: &'a SceneGeometry,
    materials: &'a Materials,
    lights: &'a Lights,
    sampler: Sampler,
    pixel: u32,
    sample: u32,
}

impl Recursive<'_> {
    fn radiance(&self, ray: &Ray, depth: u32, path: u32) -> Vec3 {
        let s = self.settings;
        let Some(hit) = self.geometry.intersect(ray, f32::INFINITY, &mut ()) else {
            return s.background;
        };
        let surface = surface_at(self.geometry, ray, &hit, s.normal_interpolation);
        let m = self.materials.list[surface.material as usize];
        let shading = Shading {
            enabled: s.shading,
            model: s.shading_model,
            gradient: &s.gradient,
            comparison_gradient: &s.comparison_gradient,
        };
        let kd = self.materials.kd_at(surface.material, surface.uv);
        let mut c = Vec3::ZERO;
        let key = (self.pixel, self.sample, depth, path);
        self.lights
            .for_each_sample(&self.sampler, key, s.shadow_samples, |ls| {
                let Some(l) = (ls.position - surface.p).try_normalize() else {
                    return;
                };
                let shade = shading.shade(&ShadingInput {
                    n: surface.n,
                    l,
                    v: -ray.dir.normalize(),
                    light_color: ls.color,
                    kd,
                    ks: m.ks,
                    shininess: m.shininess,
                });
                let shadow = surface.shadow_ray_to(ls.position);
                let visibility = if !s.shadows {
                    Vec3::ONE
                } else if s.transparency {
                    self.geometry.transmittance(
                        &shadow,
                        1.0 - SHADOW_EPSILON,
                        self.materials,
                        &mut (),
                    )
                } else if self
                    .geometry
                    .occluded(&shadow, 1.0 - SHADOW_EPSILON, &mut ())
                {
                    Vec3::ZERO
                } else {
                    Vec3::ONE
                };
                c += shade * visibility;
            });
        if s.reflections && m.ks != Vec3::ZERO && depth < s.max_depth {
            let r = surface.reflection_ray(ray.dir);
            c += m.ks * self.radiance(&r, depth + 1, path.wrapping_mul(2).wrapping_add(1));
        }
        if s.transparency && m.alpha != 1.0 && depth < s.max_depth {
            let p = surface.pass_through_ray(ray.dir);
            let behind = self.radiance(&p, depth + 1, path.wrapping_mul(2).wrapping_add(2));
            c = m.alpha * c + (1.0 - m.alpha) * behind;
        }
        c
    }
}

/// A random vector in [lo, hi)^3.
fn between(g: &mut Lcg, lo: f32, hi: f32) -> Vec3 {
    g.vec() * (hi - lo) + Vec3::splat(lo)
}

fn random_scene(seed: u64) -> String {
    let mut g = Lcg(seed);
    let mut materials = Vec::new();
    for i in 0..4 {
        let kd = between(&mut g, 0.1, 1.0);
        let ks = if g.next_f32() < 0.5 {
            between(&mut g, 0.0, 0.8)
        } else {
            Vec3::ZERO
        };
        let alpha = if g.next_f32() < 0.5 {
            0.2 + 0.6 * g.next_f32()
        } else {
            1.0
        };
        materials.push(format!(
            "\"m{i}\": (kd: ({}, {}, {}), ks: ({}, {}, {}), shininess: {}, transparency: {alpha})",
            kd.x,
            kd.y,
            kd.z,
            ks.x,
            ks.y,
            ks.z,
            1.0 + 30.0 * g.next_f32()
        ));
    }
    let mut entities = vec![
        "Mesh((material: Some(\"m0\"), geometry: Parallelogram(origin: (-3, -1, 3), edge_u: (6, 0, 0), edge_v: (0, 0, -6))))".to_string(),
    ];
    for i in 0..3 {
        let c = between(&mut g, -0.8, 0.8);
        entities.push(format!(
            "Sphere((center: ({}, {}, {}), radius: {}, material: \"m{}\"))",
            c.x,
            c.y,
            c.z,
            0.2 + 0.3 * g.next_f32(),
            1 + i
        ));
        let t = between(&mut g, -0.8, 0.8);
        entities.push(format!(
            "Mesh((material: Some(\"m{}\"), geometry: Cube, transform: (translate: ({}, {}, {}), rotate_degrees: ({}, {}, 0), scale: (0.4, 0.4, 0.4))))",
            (i + 2) % 4,
            t.x,
            t.y,
            t.z,
            90.0 * g.next_f32(),
            90.0 * g.next_f32()
        ));
    }
    entities.push("PointLight((position: (1, 3, 2), color: (0.8, 0.8, 0.8)))".into());
    entities.push(
        "ParallelogramLight((v0: (-1, 2.5, -1), edge01: (0.8, 0, 0), edge02: (0, 0, 0.8), color0: (1, 0, 0), color1: (0, 1, 0), color2: (0, 0, 1), color3: (1, 1, 0)))".into(),
    );
    entities.push("SegmentLight((endpoint0: (-2, 1, 2), endpoint1: (2, 1.5, 2), color0: (0.5, 0.3, 0.1), color1: (0.1, 0.3, 0.5)))".into());
    format!(
        "(camera: (position: (0, 1.5, 4), look_at: (0, 0, 0), fov_y: 45, width: 12, height: 12),
          settings: (shading_model: phong, pixel_samples: 4, pixel_sampling: stratified, shadow_samples: 3, max_depth: 4, seed: {seed}, background: (0.1, 0.2, 0.3)),
          materials: {{ {} }}, entities: [{}])",
        materials.join(", "),
        entities.join(", ")
    )
}

#[test]
fn a_plain_recursive_evaluator_agrees_with_the_wavefront() {
    for seed in 1..=4u64 {
        let mut r = render(&random_scene(seed));
        let camera = r.camera().unwrap();
        let w = &r.world;
        let settings = w.resource::<Settings>();
        let eval = |pixel: u32, sample: u32, offset: Vec2| {
            let x = (pixel % camera.width) as f32 + offset.x;
            let y = (pixel / camera.width) as f32 + offset.y;
            Recursive {
                settings,
                geometry: w.resource::<SceneGeometry>(),
                materials: w.resource::<Materials>(),
                lights: w.resource::<Lights>(),
                sampler: Sampler::new(settings.seed),
                pixel,
                sample,
            }
            .radiance(&camera_ray(&camera, x, y), 0, 0)
        };
        let n = glint::sampling::samples_taken(settings.pixel_samples, settings.pixel_sampling);
        let sampler = Sampler::new(settings.seed);
        let mut worst = 0.0f32;
        for pixel in 0..camera.width * camera.height {
            let mut sum = Vec3::ZERO;
            for s in 0..n {
                let o = glint::sampling::pixel_sample_offset(
                    &sampler,
                    pixel,
                    s,
                    n,
                    settings.pixel_sampling,
                );
                sum += eval(pixel, s, o);
            }
            let expected = sum / n as f32;
            let got = r.film().pixel(pixel % camera.width, pixel / camera.width);
            worst = worst.max((got - expected).abs().max_element());
        }
        assert!(worst <= 1e-5, "seed {seed}: worst pixel differs by {worst}");
        assert!(r.stats().rays.reflection > 0 && r.stats().rays.pass_through > 0);
    }
}

// ---------------------------------------------------------------- ray spawning

fn surface_on_plane(z: f32) -> (SceneGeometry, Surface, Ray) {
    let mut r = load(&format!(
        "({}, materials: {{ \"m\": () }}, entities: [{}, {}])",
        camera(3.0, 3),
        quad(z, "m"),
        quad(z - 0.01, "m")
    ));
    r.prepare().unwrap();
    let g = r.world.resource::<SceneGeometry>().clone();
    let ray = Ray {
        origin: Vec3::new(0.1, 0.2, 3.0),
        dir: Vec3::new(0.05, -0.1, -1.0).normalize(),
    };
    let hit = g.intersect(&ray, f32::INFINITY, &mut ()).unwrap();
    let s = surface_at(&g, &ray, &hit, true);
    (g, s, ray)
}

#[test]
fn reflection_and_pass_through_rays_leave_the_surface_on_the_right_side() {
    let (g, s, ray) = surface_on_plane(0.0);
    assert!((s.p.z).abs() < 1e-6 && s.ng == Vec3::Z);

    let refl = s.reflection_ray(ray.dir);
    assert!(refl.origin.distance(s.p) < 1e-3);
    assert!(refl.origin.z > 0.0, "reflection origin below the surface");
    let d = ray.dir;
    let expected = Vec3::new(d.x, d.y, -d.z);
    assert!(refl.dir.abs_diff_eq(expected, 1e-6));
    assert!(g.intersect(&refl, f32::INFINITY, &mut ()).is_none());

    let pass = s.pass_through_ray(ray.dir);
    assert!(pass.origin.distance(s.p) < 1e-3);
    assert!(pass.origin.z < 0.0, "pass-through origin above the surface");
    assert_eq!(pass.dir, ray.dir);
    // The quad 0.01 below is still found, at the right distance.
    let below = g.intersect(&pass, f32::INFINITY, &mut ()).unwrap();
    let z = pass.origin.z + below.t * pass.dir.z;
    assert!((z + 0.01).abs() < 1e-5, "hit at z = {z}");
}

// ---------------------------------------------------------------- barycentrics

#[test]
fn barycentric_interpolation_of_normals_and_texcoords() {
    let mut r = load(
        "(camera: (position: (0, 0, 3), look_at: (0, 0, 0)), materials: { \"m\": () },
          entities: [Mesh((material: Some(\"m\"), geometry: Inline(vertices: [
            (position: (0, 0, 0), normal: Some((0, 0, 1)), texcoord: (0, 0)),
            (position: (1, 0, 0), normal: Some((1, 0, 1)), texcoord: (1, 0)),
            (position: (0, 1, 0), normal: Some((0, 1, 1)), texcoord: (0, 1))],
            triangles: [(0, 1, 2)])))])",
    );
    r.prepare().unwrap();
    let g = r.world.resource::<SceneGeometry>();
    let n = [
        Vec3::Z,
        Vec3::new(1.0, 0.0, 1.0).normalize(),
        Vec3::new(0.0, 1.0, 1.0).normalize(),
    ];
    for bary in [
        Vec3::new(0.2, 0.3, 0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.35, 0.65),
        Vec3::new(0.5, 0.5, 0.0),
    ] {
        let p = Vec3::new(bary.y, bary.z, 0.0);
        let ray = Ray {
            origin: p + Vec3::Z,
            dir: -Vec3::Z,
        };
        let hit = g.intersect(&ray, f32::INFINITY, &mut ()).unwrap();
        assert!(hit.bary.abs_diff_eq(bary, 1e-6), "{} vs {bary}", hit.bary);
        let s = surface_at(g, &ray, &hit, true);
        let expected = (bary.x * n[0] + bary.y * n[1] + bary.z * n[2]).normalize();
        assert!(s.n.abs_diff_eq(expected, 1e-6));
        assert!(s.uv.abs_diff_eq(Vec2::new(bary.y, bary.z), 1e-6));
        assert!(
            surface_at(g, &ray, &hit, false)
                .n
                .abs_diff_eq(Vec3::Z, 1e-6)
        );
    }
    // A hit reported a hair outside the triangle cannot flip the normal.
    let outside = Hit {
        t: 1.0,
        prim: 0,
        kind: PrimKind::Triangle,
        bary: Vec3::new(-1e-7, 0.5, 0.5 + 1e-7),
        instance: None,
        lane: g.lane(0),
    };
    let ray = Ray {
        origin: Vec3::new(0.5, 0.5, 1.0),
        dir: -Vec3::Z,
    };
    assert!(surface_at(g, &ray, &outside, true).n.z > 0.0);
}

// ---------------------------------------------------------------- lights and shadows

#[test]
fn binary_visibility_with_stacked_triangles() {
    let mut r = load(&format!(
        "({}, materials: {{ \"m\": () }}, entities: [{}, {}, {}])",
        camera(3.0, 3),
        quad(0.0, "m"),
        quad(0.01, "m"),
        quad(1.0, "m")
    ));
    r.prepare().unwrap();
    let g = r.world.resource::<SceneGeometry>();
    let light = Vec3::new(0.0, 0.0, 0.5);
    let at = |z: f32| {
        let ray = Ray {
            origin: Vec3::new(0.2, 0.1, z + 1e-3),
            dir: -Vec3::Z,
        };
        let hit = g.intersect(&ray, f32::INFINITY, &mut ()).unwrap();
        surface_at(g, &ray, &hit, true)
    };
    let blocked = at(0.0).shadow_ray_to(light);
    assert!(g.occluded(&blocked, 1.0 - SHADOW_EPSILON, &mut ()));
    let visible = at(0.01).shadow_ray_to(light);
    assert!(!g.occluded(&visible, 1.0 - SHADOW_EPSILON, &mut ()));
}

#[test]
fn transparent_layers_multiply_their_tints_and_opaque_blocks() {
    let layers = [
        (0.3f32, Vec3::new(1.0, 0.2, 0.2)),
        (0.5, Vec3::new(0.2, 1.0, 0.2)),
        (0.8, Vec3::new(0.5, 0.5, 1.0)),
    ];
    let materials: Vec<String> = layers
        .iter()
        .enumerate()
        .map(|(i, (a, kd))| {
            format!(
                "\"l{i}\": (kd: ({}, {}, {}), transparency: {a})",
                kd.x, kd.y, kd.z
            )
        })
        .collect();
    let quads: Vec<String> = (0..3)
        .map(|i| quad(0.2 * (i + 1) as f32, &format!("l{i}")))
        .collect();
    let scene = |extra: &str| {
        format!(
            "({}, materials: {{ {}, \"stone\": () }}, entities: [{} {extra}])",
            camera(3.0, 3),
            materials.join(", "),
            quads.join(", ")
        )
    };
    let mut r = load(&scene(""));
    r.prepare().unwrap();
    let (g, m) = (
        r.world.resource::<SceneGeometry>(),
        r.world.resource::<Materials>(),
    );
    let ray = Ray {
        origin: Vec3::ZERO,
        dir: Vec3::new(0.0, 0.0, 1.0),
    };
    let expected: Vec3 = layers
        .iter()
        .map(|(a, kd)| (1.0 - a) * (Vec3::ONE - (Vec3::ONE - *kd) * *a))
        .product();
    assert_close(
        g.transmittance(&ray, 1.0 - SHADOW_EPSILON, m, &mut ()),
        expected,
        1e-6,
    );

    let mut r = load(&scene(&format!(", {}", quad(0.5, "stone"))));
    r.prepare().unwrap();
    let (g, m) = (
        r.world.resource::<SceneGeometry>(),
        r.world.resource::<Materials>(),
    );
    assert_eq!(
        g.transmittance(&ray, 1.0 - SHADOW_EPSILON, m, &mut ()),
        Vec3::ZERO
    );
}

/// Renders the centre pixel of a floor at z = 0 under `light`, with and without `blocker`,
/// shading off so every light sample contributes the same; returns the ratio.
fn visible_fraction(light: &str, blocker: &str) -> f32 {
    let scene = |extra: &str| {
        format!(
            "({}, settings: (shading: false, shadow_samples: 4096),
              materials: {{ \"m\": (kd: (1, 1, 1)) }},
              entities: [{}, {light} {extra}])",
            camera(3.0, 1),
            quad(0.0, "m")
        )
    };
    let open = render(&scene("")).film().pixel(0, 0);
    let shaded = render(&scene(&format!(", {blocker}"))).film().pixel(0, 0);
    assert!(open.x > 0.0);
    shaded.x / open.x
}

#[test]
fn a_half_occluded_segment_light_gives_half() {
    // The light runs along x at height 1; a wall at height 0.5 hides its x < 0 half.
    let light = "SegmentLight((endpoint0: (-1, 0, 1), endpoint1: (1, 0, 1)))";
    // Its edge stops 1e-3 short of the axis so the camera ray passes: 0.1% more light.
    let wall = "Mesh((material: Some(\"m\"), geometry: Parallelogram(origin: (-1, -1, 0.5), edge_u: (0.999, 0, 0), edge_v: (0, 2, 0))))";
    let f = visible_fraction(light, wall);
    // 4096 samples: standard deviation 0.0078; 4 sigma.
    assert!((f - 0.5).abs() < 0.032, "visible fraction {f}");
}

#[test]
fn a_parallelogram_light_three_quarters_visible_gives_three_quarters() {
    let light = "ParallelogramLight((v0: (-1, -1, 1), edge01: (2, 0, 0), edge02: (0, 2, 0)))";
    // Hides the light's x < 0, y < 0 quarter (seen from the origin, a square at half height
    // covers twice its size); it stops 1e-3 short of the axis so the camera ray passes.
    let blocker = "Mesh((material: Some(\"m\"), geometry: Parallelogram(origin: (-1, -1, 0.5), edge_u: (0.999, 0, 0), edge_v: (0, 0.999, 0))))";
    let f = visible_fraction(light, blocker);
    // 4096 samples: standard deviation 0.0068; 4 sigma.
    assert!((f - 0.75).abs() < 0.028, "visible fraction {f}");
}

// ---------------------------------------------------------------- scenes and plans

const SCENES: [&str; 10] = [
    "cornell_box",
    "cornell_box_transparency",
    "cornell_box_parallelogram_light",
    "cube_transparent_segment_light",
    "cube_textured",
    "spheres",
    "spheres_reflective",
    "gradient",
    "gradient_comparison",
    "single_triangle",
];

#[test]
fn every_project_scene_renders_finite_and_not_blank_at_64x64() {
    for name in SCENES {
        let path = std::path::PathBuf::from(format!("scenes/{name}.ron"));
        let overrides = glint::Overrides {
            width: Some(64),
            height: Some(64),
            ..Default::default()
        };
        let mut r = glint::Renderer::from_file(&path, &overrides).unwrap();
        r.render(None, &mut |_| {}).unwrap();
        let image = r.film().image();
        assert!(
            image.iter().all(|p| p.is_finite()),
            "{name}: non-finite pixel"
        );
        let lit = image.iter().filter(|p| p.max_element() > 0.02).count();
        assert!(lit > image.len() / 10, "{name}: only {lit} lit pixels");
        assert_eq!(r.stats().nonfinite_samples, 0, "{name}");
    }
}

#[test]
fn the_plan_skips_what_each_scene_does_not_need() {
    let plan = |name: &str| {
        let mut r = glint::Renderer::from_file(
            format!("scenes/{name}.ron").as_ref(),
            &glint::Overrides {
                width: Some(16),
                height: Some(16),
                ..Default::default()
            },
        )
        .unwrap();
        r.render(None, &mut |_| {}).unwrap();
        (r.plan().clone(), r.stats().clone())
    };
    let (p, s) = plan("cornell_box");
    assert!(p.reflections && !p.pass_through && !p.textures && !p.area_lights);
    assert!(!p.transparent_shadows && !p.pixel_patterns);
    assert!(!s.ran(Stage::DecodeTextures) && !s.ran(Stage::SpawnPassThroughRays));
    assert!(s.ran(Stage::SpawnReflectionRays));

    let (p, s) = plan("cornell_box_transparency");
    assert!(p.pass_through && p.transparent_shadows && !p.reflections);
    assert!(s.ran(Stage::SpawnPassThroughRays) && !s.ran(Stage::SpawnReflectionRays));

    let (p, s) = plan("cube_textured");
    assert!(p.textures && s.ran(Stage::DecodeTextures));
    assert!(!p.reflections && !s.ran(Stage::SpawnReflectionRays));

    let (p, _) = plan("cornell_box_parallelogram_light");
    assert!(p.area_lights && p.pixel_patterns);

    let (p, s) = plan("spheres");
    assert!(!p.triangle_bvh && !s.ran(Stage::BuildTriangleBvh));
}
