//! Case 11: bad numeric input the scene tests (tests/bad_input.rs) do not cover is
//! rejected at load with a one-line message naming the file, the entity and the field.

use std::path::Path;

use super::scenes::{load_error, scene};
use super::{Budget, Row};
use glint::render::Renderer;
use glint::scene::parse_scene;

/// Case 11: bad numeric input is rejected at load with a one-line message naming the
/// file, the entity and the field; repairable input loads with a warning. The inputs that
/// `tests/bad_input.rs` already rejects (zero radius, look_at at the camera, an empty
/// gradient, an index out of range...) are not repeated here.
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
            "ks negative",
            "ks",
            scene(camera, "", "\"m\": (ks: (-0.1, 0.0, 0.0))", ""),
        ),
        (
            "shininess NaN",
            "shininess",
            scene(camera, "", "\"m\": (shininess: NaN)", ""),
        ),
        (
            "alpha below 0",
            "transparency",
            scene(camera, "", "\"m\": (transparency: -0.25)", ""),
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
