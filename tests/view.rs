//! `glint view` without a window: egui_kittest drives the viewer's UI headless, and the
//! render thread renders for real. Needs the `view` feature, on by default (`cargo test --release --test view`).
#![allow(dead_code)]

#[path = "../src/bin/glint/view/mod.rs"]
mod view;

use std::path::Path;
use std::process::Command;

use egui::{Key, Pos2, pos2, vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::Vec3;
use glint::Overrides;
use view::controls::{ORBIT_PER_POINT, view_matrix};
use view::{ViewScene, Viewer};

const CORNELL: &str = "scenes/cornell_box.ron";

/// A headless window of 640x360 points on `scene`, after its first frames.
fn harness(scene: &str) -> Harness<'static, Viewer> {
    let scene = ViewScene::load(Path::new(scene), &Overrides::default()).unwrap();
    let viewer = Viewer::new(scene).unwrap();
    let mut h = Harness::builder()
        .with_size(vec2(640.0, 360.0))
        .build_ui_state(|ui, v: &mut Viewer| v.show(ui), viewer);
    h.run_steps(2);
    h
}

/// A point on the image at fractions `fx`, `fy` of its width and height.
fn on_image(v: &Viewer, fx: f32, fy: f32) -> Pos2 {
    let r = v.image_rect;
    pos2(r.min.x + fx * r.width(), r.min.y + fy * r.height())
}

#[test]
fn r_over_a_pixel_creates_the_primitives_glint_debug_dumps() {
    let mut h = harness(CORNELL);
    let p = on_image(h.state(), 0.5, 0.6);
    // One point is one pixel here: the image is as large as its area of the window.
    let (r, c) = (h.state().image_rect, &h.state().camera);
    assert_eq!((c.width, c.height), (r.width() as u32, r.height() as u32));
    let pixel = [(p.x - r.min.x) as u32, (p.y - r.min.y) as u32];
    h.hover_at(p);
    h.key_press(Key::R);
    h.run_steps(3);
    h.state_mut().wait_traces();
    let v = h.state();
    assert_eq!(v.traces.len(), 1, "{}", v.message);
    let traced = &v.traces[0];
    assert_eq!(traced.pixel, pixel);
    assert!(!traced.primitives.is_empty());

    // `glint debug --pixel --dump` on the scene saved with the viewer's view.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("view.ron");
    v.save_scene(scene.to_str().unwrap()).unwrap();
    let dump = dir.path().join("dump.ron");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["debug", scene.to_str().unwrap(), "-o"])
        .arg(dir.path().join("debug.png"))
        .arg("--pixel")
        .arg(format!("{},{}", pixel[0], pixel[1]))
        .arg("--dump")
        .arg(&dump)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(std::fs::read_to_string(&dump).unwrap(), traced.dump);

    // C clears the traced pixels.
    h.key_press(Key::C);
    h.run_steps(2);
    assert!(h.state().traces.is_empty());
}

#[test]
fn toggling_a_setting_changes_the_plan_and_restarts_accumulation() {
    let mut h = harness(CORNELL);
    let before = h.state_mut().wait_finished().unwrap().clone();
    assert!(!before.skipped.contains(&"trace_shadow_rays".to_owned()));
    let generation = h.state().generation;
    h.get_by_label("shadows").click();
    h.run_steps(2);
    assert!(!h.state().settings.shadows);
    assert_eq!(h.state().generation, generation + 1);
    let after = h.state_mut().wait_finished().unwrap().clone();
    assert_eq!(after.generation, generation + 1);
    assert!(
        after.skipped.contains(&"trace_shadow_rays".to_owned()),
        "{:?}",
        after.skipped
    );
    assert!(
        after.info.contains("skipped trace_shadow_rays"),
        "{}",
        after.info
    );
    // Without shadows, no pixel is darker and some (the shadows) are brighter.
    let brighter = before
        .pixels
        .iter()
        .zip(&after.pixels)
        .filter(|(b, a)| a.element_sum() > b.element_sum() + 1e-3)
        .count();
    assert!(brighter > 100, "{brighter}");
}

#[test]
fn a_camera_drag_orbits_about_the_point_looked_at() {
    let mut h = harness(CORNELL);
    let start = h.state().camera.clone();
    let m0 = view_matrix(&start);
    let p = on_image(h.state(), 0.5, 0.5);
    h.drag_at(p);
    for i in 1..=8 {
        h.hover_at(p + vec2(10.0 * i as f32, 0.0));
    }
    h.drop_at(p + vec2(80.0, 0.0));
    h.run_steps(2);
    let end = h.state().camera.clone();
    assert_eq!(end.look_at, start.look_at);
    let (a, b) = (start.position - start.look_at, end.position - end.look_at);
    assert!((a.length() - b.length()).abs() < 1e-3 * a.length());
    // A horizontal drag turns the eye about the up axis only, by the dragged distance.
    assert!((a.y - b.y).abs() < 1e-3 * a.length());
    let turned = Vec3::new(a.x, 0.0, a.z).angle_between(Vec3::new(b.x, 0.0, b.z));
    let dragged = turned / ORBIT_PER_POINT;
    assert!((60.0..=80.5).contains(&dragged), "{dragged} points");
    // Dragging right moves the eye to the left: the view matrix maps the point looked
    // at to the same place and the old eye to the right of the new one.
    let m1 = view_matrix(&end);
    assert_ne!(m0, m1);
    assert!(m1.transform_point3(start.position).x > 0.0);
}

#[test]
fn a_saved_scene_renders_in_batch_the_image_the_viewer_shows() {
    let mut h = harness(CORNELL);
    {
        let v = h.state_mut();
        view::controls::orbit(&mut v.camera, 30.0, -10.0);
        view::controls::zoom(&mut v.camera, 1.0);
        v.settings.pixel_samples = 4;
        v.settings.shading_model = glint::scene::ShadingModel::BlinnPhong;
    }
    h.run_steps(2);
    let shown = h.state_mut().wait_finished().unwrap().clone();
    assert_eq!(shown.samples, 4);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("saved.ron");
    h.state().save_scene(path.to_str().unwrap()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("blinn_phong"), "{text}");
    let mut batch = glint::Renderer::from_file(&path, &Overrides::default()).unwrap();
    batch.render(None, &mut |_| {}).unwrap();
    let film = batch.film();
    assert_eq!((film.width, film.height), (shown.width, shown.height));
    assert!(film.image() == shown.pixels, "the batch render differs");

    // Save image writes what the viewer shows, as `glint render` would.
    let png = dir.path().join("view.png");
    h.state_mut().save_image(png.to_str().unwrap()).unwrap();
    let batch_png = dir.path().join("batch.png");
    glint::film::write_image(
        &batch_png,
        film.width,
        film.height,
        &film.image(),
        glint::film::Encoding::Linear,
    )
    .unwrap();
    assert_eq!(
        std::fs::read(&png).unwrap(),
        std::fs::read(&batch_png).unwrap()
    );
    let exr = dir.path().join("view.exr");
    h.state_mut().save_image(exr.to_str().unwrap()).unwrap();
    assert!(std::fs::metadata(&exr).unwrap().len() > 0);
}

/// Time to the first frame and frame time while orbiting at 800x600, for the README:
/// `cargo test --release --test view -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement, not a check"]
fn timings_at_800x600() {
    use std::time::{Duration, Instant};
    use view::worker::{Job, Report, Worker};
    let sponza = "../shared/assets/classic/sponza-dabrovic/sponza.obj";
    for path in [CORNELL, sponza] {
        if !Path::new(path).exists() {
            println!("{path}: skipped: not found");
            continue;
        }
        let opened = Instant::now();
        let scene = ViewScene::load(Path::new(path), &Overrides::default()).unwrap();
        let renderer = glint::Renderer::from_scene(&scene.file, &scene.path).unwrap();
        let loaded = opened.elapsed();
        let worker = Worker::spawn(renderer, Default::default());
        let mut camera = scene.camera();
        (camera.width, camera.height) = (800, 600);
        let job = |generation, camera: &glint::scene::Camera, moving| Job {
            generation,
            camera: camera.clone(),
            settings: scene.file.settings.clone(),
            moving,
        };
        worker.submit(job(1, &camera, false));
        let mut first = None;
        let full = loop {
            match worker
                .reports
                .recv_timeout(Duration::from_secs(300))
                .unwrap()
            {
                Report::Frame(f) => {
                    first.get_or_insert(opened.elapsed());
                    if f.done {
                        break opened.elapsed();
                    }
                }
                Report::Error(_, e) => panic!("{e}"),
            }
        };
        // Orbiting: one moving job after another, each waited for, as a drag does.
        let mut times = Vec::new();
        for g in 2..22 {
            view::controls::orbit(&mut camera, 5.0, 0.0);
            let start = Instant::now();
            worker.submit(job(g, &camera, true));
            loop {
                if let Report::Frame(f) = worker.reports.recv().unwrap()
                    && f.generation == g
                {
                    break;
                }
            }
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{path}: load {:.0} ms, first frame {:.0} ms, full frame {:.0} ms; orbiting: median {:.0} ms, min {:.0}, max {:.0} per frame",
            loaded.as_secs_f64() * 1e3,
            first.unwrap().as_secs_f64() * 1e3,
            full.as_secs_f64() * 1e3,
            times[times.len() / 2],
            times[0],
            times[times.len() - 1]
        );
    }
}

#[test]
fn a_traced_texture_lookup_brings_the_texture_for_its_panel() {
    let scene =
        ViewScene::load(Path::new("scenes/cube_textured.ron"), &Overrides::default()).unwrap();
    let camera = scene.camera();
    let centre = [camera.width / 2, camera.height / 2];
    let t = view::traces::trace_pixel(&scene, &camera, &scene.file.settings, centre, None).unwrap();
    let panel = t
        .panels
        .first()
        .expect("the centre pixel looks up the texture");
    let [w, h] = panel.image.size;
    assert!(w > 1 && h > 1 && w <= 256 && h <= 256, "{w}x{h}");
    assert!(
        panel
            .image
            .pixels
            .iter()
            .any(|p| *p != panel.image.pixels[0])
    );
}
