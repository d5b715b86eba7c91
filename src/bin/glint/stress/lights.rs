//! Case 9: degenerate area lights, huge colours, a light inside geometry, 1 and 4096
//! shadow samples, radiance overflowing to infinity.

use glam::Vec3;

use super::scenes::{cam, mismatches, rect, scene, try_render};
use super::{Budget, Row};
use glint::render::RenderSummary;

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
            rows.push(Row::finite(&case, img.nonfinite()));
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
        rows.push(Row::finite(case, img.nonfinite()));
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
        rows.push(Row::finite(case, img.nonfinite()));
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
        rows.push(Row::finite(case, img.nonfinite()));
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
            rows.push(Row::finite(&case, img.nonfinite()));
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
            prepare_seconds: 0.0,
            stats: img.stats.clone(),
            notes: Vec::new(),
            interrupted: false,
            error: None,
            ended: Default::default(),
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
