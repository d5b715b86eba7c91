//! Case 6: coincident and near-coincident surfaces, a surface at a light.

use glam::Vec3;

use super::scenes::{cam, mismatches, rect, scene, try_render};
use super::{Budget, Row};

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
        rows.push(Row::finite(&case, a.nonfinite()));
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
        rows.push(Row::finite(&case, a.nonfinite()));
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
