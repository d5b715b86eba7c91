//! Progressive rendering: a time-budgeted or interrupted render equals a fixed-spp
//! render with the samples it reached; Ctrl-C on `glint render` writes the image.

mod common;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use common::*;
use glint::Renderer;

/// The shared area-light scene, `size` pixels square, seed 9.
fn scene(size: u32, settings: &str) -> String {
    sphere_under_area_light(size, &format!("seed: 9, {settings}"))
}

/// A fixed render of `spp` uniform samples per pixel.
fn fixed(size: u32, spp: u32) -> Renderer {
    let mut r = load(&scene(
        size,
        &format!("pixel_samples: {spp}, pixel_sampling: uniform"),
    ));
    let s = r.render(None, &mut |_| {}).unwrap();
    assert_eq!(s.samples, spp);
    assert!(!s.interrupted);
    r
}

#[test]
fn time_budgeted_render_equals_fixed_spp_render() {
    let mut r = load(&scene(16, "pixel_samples: 64, pixel_sampling: uniform"));
    // Each pass sleeps 20 ms, so a 200 ms budget stops after about ten passes, far
    // from both 1 (which samples pixel centres) and 64.
    let summary = r
        .render(Some(Duration::from_millis(200)), &mut |_| {
            std::thread::sleep(Duration::from_millis(20))
        })
        .unwrap();
    let m = summary.samples;
    assert!((2..64).contains(&m), "reached {m} passes");
    assert!(!summary.interrupted);
    let reference = fixed(16, m);
    assert_eq!(r.film(), reference.film(), "{m} spp");
    assert!(r.film().count.iter().all(|&c| c == m));
}

#[test]
fn interrupt_between_passes_keeps_whole_passes() {
    let mut r = load(&scene(32, "pixel_samples: 16, pixel_sampling: uniform"));
    let flag = Arc::new(AtomicBool::new(false));
    r.set_interrupt(flag.clone());
    // 32x32 is one region, so the callback runs once per pass: stop after pass 3.
    let mut calls = 0;
    let summary = r
        .render(None, &mut |_| {
            calls += 1;
            if calls == 3 {
                flag.store(true, Ordering::Relaxed);
            }
        })
        .unwrap();
    assert!(summary.interrupted);
    assert_eq!(summary.samples, 3);
    assert_eq!(r.film(), fixed(32, 3).film());
}

#[test]
fn interrupt_between_regions_finishes_the_region_in_flight() {
    // A square just over one region: two regions (REGION_PIXELS + the rest).
    let side = (glint::schedule::REGION_PIXELS as f64).sqrt() as u32 + 2;
    assert!(side * side < 2 * glint::schedule::REGION_PIXELS);
    let mut r = load(&scene(
        side,
        "pixel_samples: 8, pixel_sampling: uniform, shadow_samples: 1",
    ));
    let flag = Arc::new(AtomicBool::new(false));
    r.set_interrupt(flag.clone());
    let mut calls = 0;
    let summary = r
        .render(None, &mut |_| {
            calls += 1;
            // Pass 1's two regions, then pass 2's first region.
            if calls == 3 {
                flag.store(true, Ordering::Relaxed);
            }
        })
        .unwrap();
    assert!(summary.interrupted);
    assert_eq!(summary.samples, 1, "complete passes");
    let count = &r.film().count;
    let first = glint::schedule::REGION_PIXELS as usize;
    assert!(count[..first].iter().all(|&c| c == 2));
    assert!(count[first..].iter().all(|&c| c == 1));
}

#[test]
fn ctrl_c_writes_the_image_so_far() {
    if std::process::Command::new("kill")
        .arg("-l")
        .output()
        .is_err()
    {
        common::skip(
            "ctrl_c_writes_the_image_so_far",
            "no `kill` command to send SIGINT",
        );
        return;
    }
    let tmp = temp_dir();
    let dir = tmp.path();
    let scene_path = dir.join("scene.ron");
    // Far more samples than the test waits for.
    std::fs::write(
        &scene_path,
        scene(64, "pixel_samples: 65536, pixel_sampling: uniform"),
    )
    .unwrap();
    let output = dir.join("out.exr");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("render")
        .arg(&scene_path)
        .arg("-o")
        .arg(&output)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("holds") && stderr.contains("samples per pixel"),
        "{stderr}"
    );
    let img = image::open(&output).unwrap().into_rgb32f();
    assert_eq!(img.dimensions(), (64, 64));
    assert!(img.pixels().any(|p| p.0[0] > 0.0), "the image has samples");
}

/// `Renderer::restart` (the viewer's entry point): after a change of camera and
/// settings, its passes give the film a fresh renderer of that view gives, with the
/// plan and the tables prepared again once (not added to the old ones).
#[test]
fn restart_with_a_new_view_and_settings_renders_as_a_fresh_renderer() {
    let mut r = load(&scene(16, "pixel_samples: 4, pixel_sampling: uniform"));
    r.render(None, &mut |_| {}).unwrap();
    let triangles = r
        .world
        .resource::<glint::trace::geometry::SceneGeometry>()
        .triangles_flattened();
    let mut camera = r.camera().unwrap();
    camera.position += glam::Vec3::new(0.3, 0.2, 0.0);
    (camera.width, camera.height) = (12, 10);
    let mut settings = r.settings().clone();
    settings.shadows = false;
    r.restart(&camera, &settings);
    for sample in 0..r.samples_per_pixel() {
        r.render_pass(sample, &mut |_| {}).unwrap();
    }
    assert!(!r.plan().shadow_rays);
    let geometry = r.world.resource::<glint::trace::geometry::SceneGeometry>();
    assert_eq!(geometry.triangles_flattened(), triangles);

    let mut fresh = load(&scene(
        16,
        "pixel_samples: 4, pixel_sampling: uniform, shadows: false",
    ));
    fresh.restart(&camera, &settings);
    fresh.render(None, &mut |_| {}).unwrap();
    assert_eq!((r.film().width, r.film().height), (12, 10));
    assert_eq!(r.film(), fresh.film());
}

#[test]
fn render_loops_run_on_a_rayon_worker() {
    // The pass loops run inside one rayon scope (one hand-off per render, not one per
    // region), so the progress callback is called from a pool worker.
    let on_worker = |progress_calls: &mut u32| {
        *progress_calls += 1;
        assert!(
            rayon::current_thread_index().is_some(),
            "progress reported from outside the pool"
        );
    };
    let mut calls = 0;
    let mut r = load(&scene(8, "pixel_samples: 2, pixel_sampling: uniform"));
    r.render(None, &mut |_| on_worker(&mut calls)).unwrap();
    let rule = glint::render::StopRule {
        time: Some(Duration::ZERO),
        target_rmse: Some(1e-12),
        target_rel_error: None,
    };
    let mut r = load(&scene(8, "pixel_samples: 2, pixel_sampling: uniform"));
    r.render_until(&rule, &mut |_| on_worker(&mut calls))
        .unwrap();
    let mut r = load(&scene(8, "pixel_samples: 2, pixel_sampling: uniform"));
    let full = glint::film::part::Crop::full(8, 8);
    r.render_part(0..2, full, &mut |_| on_worker(&mut calls))
        .unwrap();
    // Two passes, one pass (the time is spent), two passes: one region each.
    assert_eq!(calls, 5);
}
