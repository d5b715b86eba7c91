//! Cases 6 to 11, rendered: coincident surfaces, deep chains, sphere extremes, light and
//! sampling extremes, texture extremes, and input validation. Each compares with a
//! closed form wherever one exists (shading off makes a lit pixel exactly `kd * light`).

use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use super::reference::{Prim, RefScene};
use super::{Budget, Rendered, Row, render, render_ron, v3};
use crate::accel::{Ray, intersect_sphere};
use crate::render::{RenderSummary, Renderer};
use crate::scene::components::{MeshData, Vertex};
use crate::scene::{
    Camera, Material, MaterialRef, Mesh, PointLight, Settings, TextureSource, Transform,
    parse_scene,
};
use crate::shade::texture::{Texture, WrapMode};
use crate::test_util::Lcg;

/// A scene with a camera, settings, materials and entities (RON fragments).
fn scene(camera: &str, settings: &str, materials: &str, entities: &str) -> String {
    format!(
        "(camera: ({camera}), settings: ({settings}), materials: {{ {materials} }}, entities: [ {entities} ])"
    )
}

fn cam(b: &Budget, position: Vec3, look_at: Vec3, fov: f32) -> String {
    format!(
        "position: {}, look_at: {}, fov_y: {fov:?}, width: {}, height: {}",
        v3(position),
        v3(look_at),
        b.width,
        b.height()
    )
}

/// A two-sided rectangle `origin + s*u + t*v` as a RON mesh entity.
fn rect(origin: Vec3, u: Vec3, v: Vec3, material: &str) -> String {
    format!(
        "Mesh((geometry: Parallelogram(origin: {}, edge_u: {}, edge_v: {}), material: Some(\"{material}\"))),",
        v3(origin),
        v3(u),
        v3(v)
    )
}

/// Renders, or turns the error into a failing row.
fn try_render(case: &str, text: &str, rows: &mut Vec<Row>) -> Option<Rendered> {
    match render_ron(text) {
        Ok(r) => Some(r),
        Err(e) => {
            rows.push(Row::error(case, e));
            None
        }
    }
}

/// Pixels whose largest component differs from `expected` by more than `tol` (relative).
fn mismatches(img: &Rendered, expected: Vec3, tol: f32) -> f64 {
    img.image
        .iter()
        .filter(|p| {
            let e = (**p - expected).abs().max_element();
            e.is_nan() || e > tol * expected.max_element().max(1e-30)
        })
        .count() as f64
}

/// Case 6: coincident and near-coincident surfaces, a surface at a light.
pub fn coincident(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let red = Vec3::new(0.8, 0.1, 0.1);
    let mats = "\"red\": (kd: (0.8, 0.1, 0.1)), \"green\": (kd: (0.1, 0.8, 0.1))";
    let camera = cam(b, Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 30.0);
    let quad = |z: f32, m: &str| rect(Vec3::new(-2.0, -2.0, z), Vec3::X * 4.0, Vec3::Y * 4.0, m);
    for gap in [1e-3f32, 1e-5, 0.0] {
        let case = format!("coincident gap {gap:e}");
        let text = scene(
            &camera,
            "shading: false",
            mats,
            &format!(
                "{} {} PointLight((position: (0.0, 0.0, 5.0))),",
                quad(0.0, "red"),
                quad(-gap, "green")
            ),
        );
        let (Some(a), Some(again)) = (
            try_render(&case, &text, &mut rows),
            try_render(&case, &text, &mut rows),
        ) else {
            continue;
        };
        rows.push(Row::at_most(
            &case,
            "non-finite pixels and samples",
            a.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            &case,
            "difference between two runs",
            a.max_diff(&again),
            0.0,
        ));
        if gap > 0.0 {
            // The nearer (red) quad must win everywhere: the closed form is kd_red.
            rows.push(Row::at_most(
                &case,
                "pixels not showing the nearer quad",
                mismatches(&a, red, 1e-6),
                0.0,
            ));
        }
    }
    // A light exactly on the surface lights nothing (n.l = 0); 1e-5 above, everything.
    for (label, light, expected) in [
        ("point light on the surface", "PointLight((position: (0.25, 0.125, 0.0)))".to_string(), Vec3::ZERO),
        ("point light 1e-5 above", "PointLight((position: (0.25, 0.125, 1e-5)))".to_string(), red),
        (
            "area light in the surface",
            "ParallelogramLight((v0: (-1.0, -1.0, 0.0), edge01: (2.0, 0.0, 0.0), edge02: (0.0, 2.0, 0.0)))".to_string(),
            Vec3::ZERO,
        ),
        (
            "area light 1e-5 above",
            "ParallelogramLight((v0: (-1.0, -1.0, 1e-5), edge01: (2.0, 0.0, 0.0), edge02: (0.0, 2.0, 0.0)))".to_string(),
            red,
        ),
    ] {
        let case = format!("coincident {label}");
        let text = scene(&camera, "shading: false", mats, &format!("{} {light},", quad(0.0, "red")));
        let (Some(a), Some(again)) = (try_render(&case, &text, &mut rows), try_render(&case, &text, &mut rows)) else {
            continue;
        };
        rows.push(Row::at_most(&case, "non-finite pixels and samples", a.nonfinite(), 0.0));
        rows.push(Row::at_most(&case, "difference between two runs", a.max_diff(&again), 0.0));
        let tol = if expected == Vec3::ZERO { 0.0 } else { 1e-6 };
        let wrong = a
            .image
            .iter()
            .filter(|p| {
                let e = (**p - expected).abs().max_element();
                e.is_nan() || e > tol
            })
            .count() as f64;
        rows.push(Row::at_most(&case, "pixels off the closed form", wrong, 0.0));
    }
    rows
}

/// Case 7: 100 stacked semi-transparent quads; transparent shadows through 100 quads and
/// through a sphere; two facing mirrors to depth 64. All against closed forms.
pub fn deep_chains(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    // Stack seen head-on, shading off, shadows off: layer i adds a (1-a)^i kd, the rest
    // of the light is the background (or, at the depth limit, the last layer unblended).
    let (a, kd, bg) = (0.05f32, Vec3::new(0.8, 0.5, 0.2), Vec3::new(0.2, 0.4, 0.6));
    let mut stack = String::new();
    for i in 0..100 {
        stack += &rect(
            Vec3::new(-2.0, -2.0, -0.01 * i as f32),
            Vec3::X * 4.0,
            Vec3::Y * 4.0,
            "glass",
        );
    }
    stack += "PointLight((position: (0.0, 0.0, 5.0))),";
    for depth in [16u32, 64, 100, 128] {
        let case = format!("chain 100 quads, max_depth {depth}");
        let text = scene(
            &cam(b, Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 30.0),
            &format!(
                "shading: false, shadows: false, max_depth: {depth}, background: {}",
                v3(bg)
            ),
            &format!("\"glass\": (kd: {}, transparency: {a:?})", v3(kd)),
            &stack,
        );
        let Some(img) = try_render(&case, &text, &mut rows) else {
            continue;
        };
        let mut expected = 0.0f64;
        let layers = depth.min(100);
        for i in 0..layers {
            expected += a as f64 * (1.0 - a as f64).powi(i as i32);
        }
        let rest = (1.0 - a as f64).powi(layers as i32);
        let expected = if depth < 100 {
            kd.as_dvec3() * (expected + rest)
        } else {
            kd.as_dvec3() * expected + bg.as_dvec3() * rest
        };
        rows.push(Row::at_most(
            &case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            &case,
            "max |pixel - closed form|",
            img.max_diff_to(expected.as_vec3()),
            2e-5,
        ));
    }

    // Transparent shadows: a floor lit through 100 horizontal quads; each multiplies the
    // light by (1 - a)(1 - (1 - kd) a).
    let (a, kd_glass, kd_floor) = (0.02f32, Vec3::new(0.9, 0.7, 0.5), Vec3::new(0.9, 0.6, 0.3));
    let mut ents = rect(
        Vec3::new(-50.0, 0.0, -50.0),
        Vec3::Z * 100.0,
        Vec3::X * 100.0,
        "floor",
    );
    for i in 0..100 {
        ents += &rect(
            Vec3::new(-10.0, 1.0 + 0.01 * i as f32, -10.0),
            Vec3::Z * 20.0,
            Vec3::X * 20.0,
            "glass",
        );
    }
    ents += "PointLight((position: (0.0, 3.0, 0.0))),";
    let case = "chain transparent shadow through 100 quads";
    let text = scene(
        &cam(b, Vec3::new(0.0, 0.9, 0.5), Vec3::ZERO, 40.0),
        "shading: false",
        &format!(
            "\"glass\": (kd: {}, transparency: {a:?}), \"floor\": (kd: {})",
            v3(kd_glass),
            v3(kd_floor)
        ),
        &ents,
    );
    if let Some(img) = try_render(case, &text, &mut rows) {
        let t = (1.0 - a as f64)
            * (glam::DVec3::ONE - (glam::DVec3::ONE - kd_glass.as_dvec3()) * a as f64);
        let expected = kd_floor.as_dvec3() * t.powf(100.0);
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "max |pixel - closed form|",
            img.max_diff_to(expected.as_vec3()),
            1e-5,
        ));
    }

    // A transparent sphere is two surfaces: light through it is tinted twice.
    let case = "chain transparent shadow through a sphere";
    let text = scene(
        &format!(
            "position: (0.0, 0.8, 0.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, 1.0), fov_y: 20.0, width: {}, height: {}",
            b.width,
            b.height()
        ),
        "shading: false",
        "\"glass\": (kd: (0.5, 0.5, 0.5), transparency: 0.5), \"floor\": (kd: (0.9, 0.6, 0.3))",
        &format!(
            "{} Sphere((center: (0.0, 1.5, 0.0), radius: 0.5, material: \"glass\")), PointLight((position: (0.0, 3.0, 0.0))),",
            rect(
                Vec3::new(-5.0, 0.0, -5.0),
                Vec3::Z * 10.0,
                Vec3::X * 10.0,
                "floor"
            )
        ),
    );
    if let Some(img) = try_render(case, &text, &mut rows) {
        let t = 0.5 * (1.0 - 0.5 * 0.5);
        let expected = Vec3::new(0.9, 0.6, 0.3) * (t * t);
        rows.push(Row::at_most(
            case,
            "max |pixel - closed form|",
            img.max_diff_to(expected),
            1e-6,
        ));
    }

    // Facing mirrors 2 apart, camera and light between them: sum of kd ks^d, d = 0..D.
    let (kd, ks) = (0.1f64, 0.9f64);
    for depth in [1u32, 8, 64] {
        let case = format!("chain facing mirrors, max_depth {depth}");
        let text = scene(
            &cam(b, Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 10.0),
            &format!("shading: false, max_depth: {depth}"),
            "\"mirror\": (kd: (0.1, 0.1, 0.1), ks: (0.9, 0.9, 0.9))",
            &format!(
                "{} {} PointLight((position: (0.0, 0.0, 0.0))),",
                rect(
                    Vec3::new(-100.0, -100.0, -1.0),
                    Vec3::X * 200.0,
                    Vec3::Y * 200.0,
                    "mirror"
                ),
                rect(
                    Vec3::new(-100.0, -100.0, 1.0),
                    Vec3::X * 200.0,
                    Vec3::Y * 200.0,
                    "mirror"
                )
            ),
        );
        let Some(img) = try_render(&case, &text, &mut rows) else {
            continue;
        };
        let expected = kd * (1.0 - ks.powi(depth as i32 + 1)) / (1.0 - ks);
        let pixels = (img.width * img.height) as f64;
        rows.push(Row::at_most(
            &case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            &case,
            "max |pixel - closed form|",
            img.max_diff_to(Vec3::splat(expected as f32)),
            1e-5,
        ));
        rows.push(Row::exactly(
            &case,
            "reflection rays traced",
            img.stats.rays.reflection as f64,
            pixels * depth as f64,
        ));
    }
    rows
}

/// Case 8: spheres of radius 1e-6 and 1e6, a camera inside a sphere, tangent rays.
pub fn spheres(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    // The same lit sphere at radius 1e-6 and 1: identical images (scale invariance).
    let lit_sphere = |s: f32| {
        scene(
            &cam(b, Vec3::new(0.0, 0.0, 4.0) * s, Vec3::ZERO, 40.0),
            "shading_model: lambertian",
            "\"m\": (kd: (0.7, 0.7, 0.7))",
            &format!(
                "Sphere((center: (0.0, 0.0, 0.0), radius: {s:?}, material: \"m\")), PointLight((position: {})),",
                v3(Vec3::new(2.0, 3.0, 4.0) * s)
            ),
        )
    };
    let case = "sphere radius 1e-6";
    if let (Some(tiny), Some(unit)) = (
        try_render(case, &lit_sphere(1e-6), &mut rows),
        try_render(case, &lit_sphere(1.0), &mut rows),
    ) {
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            tiny.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "mean |image - radius 1 image|",
            tiny.mean_diff(&unit),
            2e-3,
        ));
    }

    // A ground sphere of radius 1e6 under a point light, shading off: no acne, no leaks.
    let case = "sphere radius 1e6 (ground)";
    let camera = Camera {
        position: Vec3::new(0.0, 1.0, 4.0),
        look_at: Vec3::new(0.0, 0.25, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 40.0,
        width: b.width,
        height: b.height(),
    };
    let text = scene(
        &cam(b, camera.position, camera.look_at, 40.0),
        "shading: false",
        "\"m\": (kd: (0.5, 0.5, 0.5))",
        "Sphere((center: (0.0, -1e6, 0.0), radius: 1e6, material: \"m\")), Sphere((center: (0.0, 0.5, 0.0), radius: 0.5, material: \"m\")), PointLight((position: (2.0, 5.0, 3.0))),",
    );
    if let Some(img) = try_render(case, &text, &mut rows) {
        let reference = RefScene {
            prims: vec![
                Prim::Sphere {
                    center: glam::DVec3::new(0.0, -1e6, 0.0),
                    radius: 1e6,
                },
                Prim::Sphere {
                    center: glam::DVec3::new(0.0, 0.5, 0.0),
                    radius: 0.5,
                },
            ],
            light: glam::DVec3::new(2.0, 5.0, 3.0),
            // The ground's numbers are ~1e6, where f32 resolves 1/16 of a unit: the same
            // eight spacings as for the scene placed 1e6 from the origin (case far).
            margin: 8.0 * f32::EPSILON as f64 * 1e6,
        };
        let c = reference.count(&camera, &img, Vec3::splat(0.5));
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "acne pixels (lit expected, dark rendered)",
            c.acne as f64,
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "leak pixels (dark expected, lit rendered)",
            c.leaks as f64,
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "hits where the reference misses",
            c.wrong_miss as f64,
            0.0,
        ));
        let undecided = c.unknown as f64 / (img.width * img.height) as f64;
        rows.push(Row::at_most(
            case,
            "pixels too near a boundary to judge (fraction)",
            undecided,
            0.6,
        ));
    }

    // Camera inside a sphere, the light inside too: every pixel sees the lit inside.
    for (label, center, radius) in [
        ("camera inside radius 2", Vec3::ZERO, 2.0f32),
        ("camera inside radius 2 at 1e5", Vec3::splat(1e5), 2.0),
        ("camera inside radius 1e6", Vec3::ZERO, 1e6),
    ] {
        let case = format!("sphere {label}");
        let eye = center + Vec3::new(0.25, 0.125, 0.0625);
        let text = scene(
            &cam(b, eye, eye + Vec3::new(1.0, 0.25, 0.5), 60.0),
            "shading: false",
            "\"m\": (kd: (0.25, 0.5, 0.75))",
            &format!(
                "Sphere((center: {}, radius: {radius:?}, material: \"m\")), PointLight((position: {})),",
                v3(center),
                v3(center + Vec3::new(0.0, 0.5, 0.0))
            ),
        );
        if let Some(img) = try_render(&case, &text, &mut rows) {
            rows.push(Row::at_most(
                &case,
                "non-finite pixels and samples",
                img.nonfinite(),
                0.0,
            ));
            rows.push(Row::at_most(
                &case,
                "pixels off the closed form (kd)",
                mismatches(&img, Vec3::new(0.25, 0.5, 0.75), 1e-6),
                0.0,
            ));
        }
    }

    // Tangent rays: perpendicular distance r (1 +- 1e-3) hits exactly when inside; exactly
    // tangent rays may go either way but never give NaN.
    let mut rng = Lcg(3);
    let mut wrong = 0usize;
    let mut nan = 0usize;
    let mut n = 0usize;
    for radius in [1e-6f32, 1.0, 1e6] {
        for center in [Vec3::ZERO, Vec3::new(1e3, -2e3, 5e2) * radius] {
            for _ in 0..(b.rays / 64).max(1000) {
                let d = rng.dir();
                let side = d.any_orthonormal_vector();
                for delta in [-1e-3f32, 0.0, 1e-3] {
                    let o = center + side * radius * (1.0 + delta) - d * 3.0 * radius;
                    let t = intersect_sphere(&Ray::new(o, d), center, radius, f32::INFINITY);
                    n += 1;
                    if t.is_some_and(|t| !t.is_finite()) {
                        nan += 1;
                    }
                    if delta != 0.0 && t.is_some() != (delta < 0.0) {
                        wrong += 1;
                    }
                }
            }
        }
    }
    rows.push(Row::at_most(
        "sphere tangent rays",
        format!("wrong hit/miss at 1e-3 off tangent (of {n})"),
        wrong as f64,
        0.0,
    ));
    rows.push(Row::at_most(
        "sphere tangent rays",
        "non-finite t",
        nan as f64,
        0.0,
    ));
    rows
}

/// Case 9: degenerate area lights, huge colours, a light inside geometry, 1 and 4096
/// shadow samples, and radiance overflowing to infinity (dropped and counted by the film).
pub fn lights(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let floor = rect(
        Vec3::new(-50.0, 0.0, -50.0),
        Vec3::Z * 100.0,
        Vec3::X * 100.0,
        "floor",
    );
    let camera = cam(b, Vec3::new(0.0, 3.0, 4.0), Vec3::ZERO, 40.0);
    let lit = |settings: &str, light: &str, kd: f32| {
        scene(
            &camera,
            settings,
            &format!("\"floor\": (kd: ({kd:?}, {kd:?}, {kd:?}))"),
            &format!("{floor} {light},"),
        )
    };
    let p = "(0.5, 2.0, 0.25)";
    let c = "(1.0, 0.5, 0.25)";
    let lam = "shading_model: lambertian";
    let Some(point) = try_render(
        "lights",
        &lit(
            lam,
            &format!("PointLight((position: {p}, color: {c}))"),
            0.5,
        ),
        &mut rows,
    ) else {
        return rows;
    };
    for (label, light) in [
        (
            "parallelogram of area 1e-60",
            format!(
                "ParallelogramLight((v0: {p}, edge01: (1e-30, 0.0, 0.0), edge02: (0.0, 0.0, 1e-30), color0: {c}, color1: {c}, color2: {c}, color3: {c}))"
            ),
        ),
        (
            "parallelogram of zero area",
            format!(
                "ParallelogramLight((v0: {p}, edge01: (0.0, 0.0, 0.0), edge02: (0.0, 0.0, 0.0), color0: {c}, color1: {c}, color2: {c}, color3: {c}))"
            ),
        ),
        (
            "segment of zero length",
            format!("SegmentLight((endpoint0: {p}, endpoint1: {p}, color0: {c}, color1: {c}))"),
        ),
    ] {
        let case = format!("light {label}");
        if let Some(img) = try_render(&case, &lit(lam, &light, 0.5), &mut rows) {
            rows.push(Row::at_most(
                &case,
                "non-finite pixels and samples",
                img.nonfinite(),
                0.0,
            ));
            rows.push(Row::at_most(
                &case,
                "max |image - point light image|",
                img.max_diff(&point),
                1e-6,
            ));
        }
    }
    let case = "light parallelogram with nearly parallel edges";
    let light = "ParallelogramLight((v0: (-1.0, 2.0, 0.0), edge01: (2.0, 0.0, 0.0), edge02: (2.0, 1e-7, 0.0)))";
    if let Some(img) = try_render(case, &lit(lam, light, 0.5), &mut rows) {
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
    }
    let case = "light colour 1e6";
    if let Some(img) = try_render(
        case,
        &lit(
            lam,
            &format!("PointLight((position: {p}, color: (1e6, 5e5, 2.5e5)))"),
            0.5,
        ),
        &mut rows,
    ) {
        let worst = img
            .image
            .iter()
            .zip(&point.image)
            .map(|(a, b)| ((*a / 1e6 - *b).abs().max_element() / b.max_element().max(1e-6)) as f64)
            .fold(0.0, f64::max);
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "max relative |image / 1e6 - colour 1 image|",
            worst,
            1e-6,
        ));
    }
    // A point light inside a closed cube standing on the floor: nothing outside is lit.
    let case = "light inside a closed cube";
    let text = scene(
        &camera,
        "shading: false",
        "\"floor\": (kd: (0.5, 0.5, 0.5))",
        &format!(
            "{floor} Mesh((geometry: Cube, material: Some(\"floor\"), transform: (translate: (0.0, 0.5, 0.0)))), PointLight((position: (0.0, 0.5, 0.0))),"
        ),
    );
    if let Some(img) = try_render(case, &text, &mut rows) {
        rows.push(Row::at_most(
            case,
            "non-finite pixels and samples",
            img.nonfinite(),
            0.0,
        ));
        rows.push(Row::at_most(
            case,
            "lit pixels (light leaking out)",
            img.image.iter().filter(|p| p.max_element() != 0.0).count() as f64,
            0.0,
        ));
    }
    // A uniform area light and shadow_samples 1 or 4096: every sample sees the light, the
    // closed form is kd * colour whatever the count.
    for samples in [1u32, 4096] {
        let case = format!("light shadow_samples {samples}");
        let light = "ParallelogramLight((v0: (-1.0, 2.0, -1.0), edge01: (2.0, 0.0, 0.0), edge02: (0.0, 0.0, 2.0), color0: (0.75, 0.75, 0.75), color1: (0.75, 0.75, 0.75), color2: (0.75, 0.75, 0.75), color3: (0.75, 0.75, 0.75)))";
        let text = lit(
            &format!("shading: false, shadow_samples: {samples}"),
            light,
            0.5,
        );
        if let Some(img) = try_render(&case, &text, &mut rows) {
            rows.push(Row::at_most(
                &case,
                "non-finite pixels and samples",
                img.nonfinite(),
                0.0,
            ));
            rows.push(Row::at_most(
                &case,
                "pixels off the closed form",
                mismatches(&img, Vec3::splat(0.375), 1e-5),
                0.0,
            ));
        }
    }
    // Two lights of colour 3e38 on kd 1: every sample overflows to +inf. The film must
    // drop and count each one, keep finite pixels, and the summary must say so.
    let case = "light colour 3e38 x 2 (overflow)";
    let big = "PointLight((position: (0.0, 2.0, 0.0), color: (3e38, 3e38, 3e38)))";
    let text = lit("shading: false", &format!("{big}, {big}"), 1.0);
    if let Some(img) = try_render(case, &text, &mut rows) {
        let pixels = (img.width * img.height) as f64;
        let finite_pixels = img.image.iter().filter(|p| p.is_finite()).count() as f64;
        let summary = RenderSummary {
            width: img.width,
            height: img.height,
            samples: 1,
            seconds: 1.0,
            stats: img.stats.clone(),
            notes: Vec::new(),
            interrupted: false,
        }
        .to_string();
        rows.push(Row::exactly(
            case,
            "non-finite samples dropped by the film",
            img.stats.nonfinite_samples as f64,
            pixels,
        ));
        rows.push(Row::exactly(
            case,
            "finite film pixels",
            finite_pixels,
            pixels,
        ));
        rows.push(Row::exactly(
            case,
            "render summary reports the dropped samples",
            summary.contains(&format!(
                "{} non-finite samples dropped",
                img.stats.nonfinite_samples
            )) as u8 as f64,
            1.0,
        ));
    }
    rows
}

/// A camera looking at a textured unit quad `[-1, 1]^2` at z = 0 with per-corner
/// texture coordinates, shading off, so a pixel is its texel.
fn texture_render(
    b: &Budget,
    tex: &Arc<Texture>,
    wrap: [WrapMode; 2],
    uv: [Vec2; 4],
    bilinear: bool,
) -> crate::Result<Rendered> {
    let mut world = World::new();
    world.spawn(Camera {
        position: Vec3::new(0.0, 0.0, 2.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_degrees: 40.0,
        width: b.width,
        height: b.height(),
    });
    let material = world
        .spawn(Material {
            name: "textured".into(),
            kd_texture: Some(TextureSource::Decoded(tex.clone())),
            wrap,
            ..Default::default()
        })
        .id();
    let corner = |p: Vec3, t: Vec2| Vertex {
        position: p,
        normal: Vec3::Z,
        texcoord: t,
    };
    let data = MeshData {
        vertices: vec![
            corner(Vec3::new(-1.0, -1.0, 0.0), uv[0]),
            corner(Vec3::new(1.0, -1.0, 0.0), uv[1]),
            corner(Vec3::new(1.0, 1.0, 0.0), uv[2]),
            corner(Vec3::new(-1.0, 1.0, 0.0), uv[3]),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    world.spawn((
        Mesh {
            data: Arc::new(data),
        },
        Transform::default(),
        MaterialRef(material),
    ));
    world.spawn(PointLight {
        position: Vec3::new(0.0, 0.0, 3.0),
        color: Vec3::ONE,
    });
    world.insert_resource(Settings {
        shading: false,
        bilinear_filtering: bilinear,
        ..Default::default()
    });
    render(Renderer::from_world(world))
}

/// Case 10: 1x1 and very non-square textures, texture coordinates of +-1e6 in every wrap
/// mode, NaN texture coordinates in the input.
pub fn textures(b: &Budget) -> Vec<Row> {
    let mut rows = Vec::new();
    let modes = [WrapMode::Clamp, WrapMode::Repeat, WrapMode::MirroredRepeat];
    let far = [
        Vec2::new(-1e6, -1e6),
        Vec2::new(1e6, -1e6),
        Vec2::new(1e6, 1e6),
        Vec2::new(-1e6, 1e6),
    ];
    // 1x1: every lookup anywhere is the one texel.
    let one = Arc::new(Texture {
        width: 1,
        height: 1,
        texels: vec![Vec3::new(0.2, 0.4, 0.6)],
    });
    let mut wrong = 0.0;
    let mut nonfinite = 0.0;
    for mode in modes {
        for bilinear in [false, true] {
            match texture_render(b, &one, [mode; 2], far, bilinear) {
                Ok(img) => {
                    nonfinite += img.nonfinite();
                    wrong += mismatches(&img, Vec3::new(0.2, 0.4, 0.6), 1e-6);
                }
                Err(e) => rows.push(Row::error("texture 1x1", e)),
            }
        }
    }
    rows.push(Row::at_most(
        "texture 1x1, uv +-1e6",
        "non-finite pixels and samples",
        nonfinite,
        0.0,
    ));
    rows.push(Row::at_most(
        "texture 1x1, uv +-1e6",
        "pixels not the texel",
        wrong,
        0.0,
    ));

    // A 2x2 checker at constant uv = (+-1e6 + 1/4, -+1e6 + 3/4): f32 keeps 1/16 at 1e6,
    // and interpolation may move it by a few of those, still inside the same texel.
    let texels = vec![
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 0.0),
    ];
    let checker = Arc::new(Texture {
        width: 2,
        height: 2,
        texels: texels.clone(),
    });
    let mut wrong = 0.0;
    let mut nonfinite = 0.0;
    for mode in [WrapMode::Repeat, WrapMode::MirroredRepeat] {
        for uv in [
            Vec2::new(1e6 + 0.25, -1e6 + 0.75),
            Vec2::new(-1e6 + 0.25, 1e6 + 0.75),
        ] {
            // Both u and v sit a quarter of a period into an even period: column 0 and
            // (v = 3/4, counted from the bottom) row 0.
            match texture_render(b, &checker, [mode; 2], [uv; 4], false) {
                Ok(img) => {
                    nonfinite += img.nonfinite();
                    wrong += mismatches(&img, texels[0], 1e-6);
                }
                Err(e) => rows.push(Row::error("texture 2x2", e)),
            }
        }
    }
    rows.push(Row::at_most(
        "texture 2x2, uv +-1e6 repeat/mirror",
        "non-finite pixels and samples",
        nonfinite,
        0.0,
    ));
    rows.push(Row::at_most(
        "texture 2x2, uv +-1e6 repeat/mirror",
        "pixels not the expected texel",
        wrong,
        0.0,
    ));

    // 4096x1 and 1x4096 ramps: clamped +-1e6 reads the end texels; every mode stays finite
    // and inside the ramp's range.
    let ramp: Vec<Vec3> = (0..4096)
        .map(|i| Vec3::splat((i as f32 + 0.5) / 4096.0))
        .collect();
    let mut out_of_range = 0.0;
    let mut nonfinite = 0.0;
    let mut wrong_clamp = 0.0;
    for (w, h) in [(4096u32, 1u32), (1, 4096)] {
        let tex = Arc::new(Texture {
            width: w,
            height: h,
            texels: ramp.clone(),
        });
        for mode in modes {
            for bilinear in [false, true] {
                match texture_render(b, &tex, [mode; 2], far, bilinear) {
                    Ok(img) => {
                        nonfinite += img.nonfinite();
                        out_of_range += img
                            .image
                            .iter()
                            .filter(|p| {
                                !(p.min_element() >= ramp[0].x && p.max_element() <= ramp[4095].x)
                            })
                            .count() as f64;
                    }
                    Err(e) => rows.push(Row::error("texture ramp", e)),
                }
            }
            // Clamp at u = v = 1e6: the last texel along the ramp (x: right end, y: top = row 0).
            let end = if w > 1 { ramp[4095] } else { ramp[0] };
            if mode == WrapMode::Clamp {
                match texture_render(b, &tex, [mode; 2], [Vec2::splat(1e6); 4], true) {
                    Ok(img) => wrong_clamp += mismatches(&img, end, 1e-6),
                    Err(e) => rows.push(Row::error("texture ramp", e)),
                }
            }
        }
    }
    rows.push(Row::at_most(
        "texture 4096x1 and 1x4096, uv +-1e6",
        "non-finite pixels and samples",
        nonfinite,
        0.0,
    ));
    rows.push(Row::at_most(
        "texture 4096x1 and 1x4096, uv +-1e6",
        "pixels outside the texel range",
        out_of_range,
        0.0,
    ));
    rows.push(Row::at_most(
        "texture 4096x1 and 1x4096, clamp at 1e6",
        "pixels not the end texel",
        wrong_clamp,
        0.0,
    ));

    let text = "(camera: (position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0)), materials: { \"m\": () }, entities: [Mesh((geometry: Inline(vertices: [(position: (0.0, 0.0, 0.0)), (position: (1.0, 0.0, 0.0), texcoord: (NaN, 0.5)), (position: (0.0, 1.0, 0.0))], triangles: [(0, 1, 2)]), material: Some(\"m\")))])";
    let rejected = load_error(text).is_some_and(|e| e.contains("vertices[1].texcoord"));
    rows.push(Row::exactly(
        "texture NaN texcoord in the input",
        "rejected at load, naming the field",
        rejected as u8 as f64,
        1.0,
    ));
    rows
}

/// The load error of a scene, as its one-line message (None when it loads).
fn load_error(text: &str) -> Option<String> {
    let path = Path::new("stress.ron");
    let result: crate::Result<Renderer> =
        parse_scene(text, path).and_then(|f| Renderer::from_scene(&f, path));
    match result {
        Ok(_) => None,
        Err(e) => Some(e.to_string()),
    }
}

/// Case 11: every bad numeric input is rejected at load with a one-line message naming
/// the file, the entity and the field; repairable ones load with a warning.
pub fn validation(_b: &Budget) -> Vec<Row> {
    let case = "validation";
    let camera = "position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0)";
    let tri = |v0: &str, v1: &str, idx: &str| {
        format!(
            "Mesh((geometry: Inline(vertices: [{v0}, {v1}, (position: (0.0, 1.0, 0.0))], triangles: [{idx}]), material: Some(\"m\"))),"
        )
    };
    let ok_v0 = "(position: (0.0, 0.0, 0.0))";
    let ok_v1 = "(position: (1.0, 0.0, 0.0))";
    let mat = "\"m\": ()";
    // (what, field the message must name, scene)
    let bad: Vec<(&str, &str, String)> = vec![
        (
            "camera position NaN",
            "position",
            scene(
                "position: (NaN, 0.0, 3.0), look_at: (0.0, 0.0, 0.0)",
                "",
                mat,
                "",
            ),
        ),
        (
            "camera look_at = position",
            "look_at",
            scene(
                "position: (1.0, 2.0, 3.0), look_at: (1.0, 2.0, 3.0)",
                "",
                mat,
                "",
            ),
        ),
        (
            "camera up parallel to view",
            "up",
            scene(
                "position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, -2.0)",
                "",
                mat,
                "",
            ),
        ),
        (
            "camera up zero",
            "up",
            scene(
                "position: (0.0, 0.0, 3.0), look_at: (0.0, 0.0, 0.0), up: (0.0, 0.0, 0.0)",
                "",
                mat,
                "",
            ),
        ),
        (
            "camera fov 180",
            "fov_y",
            scene(&format!("{camera}, fov_y: 180.0"), "", mat, ""),
        ),
        (
            "camera fov inf",
            "fov_y",
            scene(&format!("{camera}, fov_y: inf"), "", mat, ""),
        ),
        (
            "camera width 0",
            "width",
            scene(&format!("{camera}, width: 0"), "", mat, ""),
        ),
        (
            "kd inf",
            "kd",
            scene(camera, "", "\"m\": (kd: (inf, 0.0, 0.0))", ""),
        ),
        (
            "ks negative",
            "ks",
            scene(camera, "", "\"m\": (ks: (-0.1, 0.0, 0.0))", ""),
        ),
        (
            "shininess negative",
            "shininess",
            scene(camera, "", "\"m\": (shininess: -1.0)", ""),
        ),
        (
            "shininess NaN",
            "shininess",
            scene(camera, "", "\"m\": (shininess: NaN)", ""),
        ),
        (
            "alpha above 1",
            "transparency",
            scene(camera, "", "\"m\": (transparency: 1.5)", ""),
        ),
        (
            "alpha below 0",
            "transparency",
            scene(camera, "", "\"m\": (transparency: -0.25)", ""),
        ),
        (
            "empty gradient",
            "gradient",
            scene(camera, "gradient: []", mat, ""),
        ),
        (
            "gradient t NaN",
            "comparison_gradient",
            scene(
                camera,
                "comparison_gradient: [(NaN, (1.0, 0.0, 0.0))]",
                mat,
                "",
            ),
        ),
        (
            "background NaN",
            "background",
            scene(camera, "background: (NaN, 0.0, 0.0)", mat, ""),
        ),
        (
            "pixel_samples 0",
            "pixel_samples",
            scene(camera, "pixel_samples: 0", mat, ""),
        ),
        (
            "shadow_samples 0",
            "shadow_samples",
            scene(camera, "shadow_samples: 0", mat, ""),
        ),
        (
            "max_depth huge",
            "max_depth",
            scene(camera, "max_depth: 100000", mat, ""),
        ),
        (
            "index out of range",
            "triangles[0]",
            scene(camera, "", mat, &tri(ok_v0, ok_v1, "(0, 1, 3)")),
        ),
        (
            "vertex position inf",
            "vertices[0].position",
            scene(
                camera,
                "",
                mat,
                &tri("(position: (inf, 0.0, 0.0))", ok_v1, "(0, 1, 2)"),
            ),
        ),
        (
            "vertex normal NaN",
            "vertices[1].normal",
            scene(
                camera,
                "",
                mat,
                &tri(
                    ok_v0,
                    "(position: (1.0, 0.0, 0.0), normal: Some((NaN, 0.0, 1.0)))",
                    "(0, 1, 2)",
                ),
            ),
        ),
        (
            "texcoord NaN",
            "vertices[1].texcoord",
            scene(
                camera,
                "",
                mat,
                &tri(
                    ok_v0,
                    "(position: (1.0, 0.0, 0.0), texcoord: (0.5, NaN))",
                    "(0, 1, 2)",
                ),
            ),
        ),
        (
            "vertex overflowing after the transform",
            "vertices[1].position",
            scene(
                camera,
                "",
                mat,
                "Mesh((geometry: Inline(vertices: [(position: (0.0, 0.0, 0.0)), (position: (3e38, 0.0, 0.0)), (position: (0.0, 1.0, 0.0))], triangles: [(0, 1, 2)]), material: Some(\"m\"), transform: (scale: (10.0, 1.0, 1.0)))),",
            ),
        ),
        (
            "transform scale zero",
            "transform.scale",
            scene(
                camera,
                "",
                mat,
                "Mesh((geometry: Cube, material: Some(\"m\"), transform: (scale: (1.0, 0.0, 1.0)))),",
            ),
        ),
        (
            "transform translate NaN",
            "transform.translate",
            scene(
                camera,
                "",
                mat,
                "Mesh((geometry: Cube, material: Some(\"m\"), transform: (translate: (NaN, 0.0, 0.0)))),",
            ),
        ),
        (
            "parallel parallelogram edges",
            "geometry",
            scene(
                camera,
                "",
                mat,
                "Mesh((geometry: Parallelogram(origin: (0.0, 0.0, 0.0), edge_u: (1.0, 0.0, 0.0), edge_v: (2.0, 0.0, 0.0)), material: Some(\"m\"))),",
            ),
        ),
        (
            "plane subdivisions 0",
            "geometry.subdivisions",
            scene(
                camera,
                "",
                mat,
                "Mesh((geometry: Plane(subdivisions: 0), material: Some(\"m\"))),",
            ),
        ),
        (
            "sphere radius 0",
            "radius",
            scene(
                camera,
                "",
                mat,
                "Sphere((center: (0.0, 0.0, 0.0), radius: 0.0, material: \"m\")),",
            ),
        ),
        (
            "sphere radius NaN",
            "radius",
            scene(
                camera,
                "",
                mat,
                "Sphere((center: (0.0, 0.0, 0.0), radius: NaN, material: \"m\")),",
            ),
        ),
        (
            "sphere radius 1e30 (square overflows)",
            "radius",
            scene(
                camera,
                "",
                mat,
                "Sphere((center: (0.0, 0.0, 0.0), radius: 1e30, material: \"m\")),",
            ),
        ),
        (
            "sphere radius 1e-30 (square underflows)",
            "radius",
            scene(
                camera,
                "",
                mat,
                "Sphere((center: (0.0, 0.0, 0.0), radius: 1e-30, material: \"m\")),",
            ),
        ),
        (
            "sphere centre inf",
            "center",
            scene(
                camera,
                "",
                mat,
                "Sphere((center: (0.0, inf, 0.0), radius: 1.0, material: \"m\")),",
            ),
        ),
        (
            "point light position NaN",
            "position",
            scene(camera, "", mat, "PointLight((position: (NaN, 0.0, 0.0))),"),
        ),
        (
            "point light colour negative",
            "color",
            scene(
                camera,
                "",
                mat,
                "PointLight((position: (0.0, 0.0, 0.0), color: (1.0, -1.0, 1.0))),",
            ),
        ),
        (
            "segment light endpoint inf",
            "endpoint1",
            scene(
                camera,
                "",
                mat,
                "SegmentLight((endpoint0: (0.0, 0.0, 0.0), endpoint1: (0.0, -inf, 0.0))),",
            ),
        ),
        (
            "parallelogram light edge NaN",
            "edge02",
            scene(
                camera,
                "",
                mat,
                "ParallelogramLight((v0: (0.0, 0.0, 0.0), edge01: (1.0, 0.0, 0.0), edge02: (NaN, 0.0, 0.0))),",
            ),
        ),
        (
            "parallelogram light colour inf",
            "color3",
            scene(
                camera,
                "",
                mat,
                "ParallelogramLight((v0: (0.0, 0.0, 0.0), edge01: (1.0, 0.0, 0.0), edge02: (0.0, 0.0, 1.0), color3: (inf, 0.0, 0.0))),",
            ),
        ),
    ];
    let mut accepted = Vec::new();
    let mut unclear = Vec::new();
    for (what, field, text) in &bad {
        match load_error(text) {
            None => accepted.push(*what),
            Some(msg) => {
                // One line naming the file, the entity (or section) and the field.
                let named = msg.starts_with("stress.ron: ")
                    && msg.contains(&format!(": {field}: "))
                    && !msg.contains('\n');
                // A syntax error (e.g. RON refusing a literal) is not a validation message.
                if !named {
                    unclear.push(format!("{what}: {msg}"));
                }
            }
        }
    }
    let mut rows = vec![
        Row::at_most(
            case,
            format!("bad inputs accepted (of {}){}", bad.len(), list(&accepted)),
            accepted.len() as f64,
            0.0,
        ),
        Row::at_most(
            case,
            format!("errors not naming file, entity and field{}", list(&unclear)),
            unclear.len() as f64,
            0.0,
        ),
    ];
    // Repairs: a zero-length normal is re-derived from the triangles, with a warning.
    let text = scene(
        camera,
        "",
        mat,
        &tri(
            ok_v0,
            "(position: (1.0, 0.0, 0.0), normal: Some((0.0, 0.0, 0.0)))",
            "(0, 1, 2)",
        ),
    );
    let path = Path::new("stress.ron");
    let warned = parse_scene(&text, path)
        .and_then(|f| Renderer::from_scene(&f, path))
        .map(|r| {
            r.warnings()
                .iter()
                .filter(|w| w.contains("zero-length normal"))
                .count()
        })
        .unwrap_or(0);
    rows.push(Row::exactly(
        case,
        "zero-length normal loads with a repair warning",
        warned as f64,
        1.0,
    ));
    rows
}

fn list(items: &[impl std::fmt::Display]) -> String {
    if items.is_empty() {
        String::new()
    } else {
        let s: Vec<String> = items.iter().map(|i| i.to_string()).collect();
        format!(": {}", s.join("; "))
    }
}
