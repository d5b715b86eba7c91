//! Case 8: spheres of radius 1e-6 and 1e6, a camera inside a sphere, tangent rays.

use glam::Vec3;

use super::reference::{Prim, RefScene};
use super::scenes::{cam, mismatches, scene, try_render};
use super::{Budget, Row, v3};
use glint::accel::{Ray, intersect_sphere};
use glint::scene::Camera;
use glint::test_util::Lcg;

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
        rows.push(Row::finite(case, tiny.nonfinite()));
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
        rows.push(Row::finite(case, img.nonfinite()));
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
            rows.push(Row::finite(&case, img.nonfinite()));
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
