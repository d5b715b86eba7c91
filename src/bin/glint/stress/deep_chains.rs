//! Case 7: 100 stacked semi-transparent quads, transparent shadows through them and
//! through a sphere, two facing mirrors to depth 64; all against closed forms.

use glam::Vec3;

use super::scenes::{cam, rect, scene, try_render};
use super::{Budget, Row, v3};

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
        rows.push(Row::finite(&case, img.nonfinite()));
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
        rows.push(Row::finite(case, img.nonfinite()));
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
        rows.push(Row::finite(&case, img.nonfinite()));
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
