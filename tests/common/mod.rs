//! Helpers shared by the test files: scenes from RON text, rendering them, temporary
//! folders that remove themselves.
#![allow(dead_code)]

pub mod assets;

use std::path::{Path, PathBuf};

use glam::Vec3;
use glint::Renderer;
use glint::scene::format::SceneFile;
use glint::scene::parse_scene;
use tempfile::TempDir;

/// Where inline scene text is taken to live: its relative paths resolve against `tests/`.
pub fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/inline.ron")
}

/// Parses RON scene text.
pub fn parse(ron: &str) -> SceneFile {
    parse_scene(ron, &scene_path()).expect("scene parses")
}

/// Loads a parsed scene.
pub fn load_file(file: &SceneFile) -> Renderer {
    Renderer::from_scene(file, &scene_path()).expect("scene is valid")
}

/// Loads RON scene text.
pub fn load(ron: &str) -> Renderer {
    load_file(&parse(ron))
}

/// Fully renders a loaded scene.
pub fn render_loaded(mut r: Renderer) -> Renderer {
    r.render(None, &mut |_| {}).expect("render succeeds");
    r
}

/// Loads and fully renders RON scene text.
pub fn render(ron: &str) -> Renderer {
    render_loaded(load(ron))
}

/// Loads and fully renders a parsed scene.
pub fn render_file(file: &SceneFile) -> Renderer {
    render_loaded(load_file(file))
}

/// A fresh folder in the system temporary directory, removed with everything in it
/// when dropped (also when the test fails).
pub fn temp_dir() -> TempDir {
    tempfile::Builder::new()
        .prefix("glint-test-")
        .tempdir()
        .expect("a temporary folder")
}

/// A fresh temporary folder holding `scene.ron` with `text`.
pub fn scene_dir(text: &str) -> TempDir {
    let dir = temp_dir();
    std::fs::write(dir.path().join("scene.ron"), text).expect("scene.ron is written");
    dir
}

/// A red sphere on a white floor under a square area light, `size` pixels square:
/// smooth silhouettes against a grey background and soft shadows. `settings` is
/// spliced into the scene's settings.
pub fn sphere_under_area_light(size: u32, settings: &str) -> String {
    format!(
        r#"(
    camera: (position: (0.0, 1.5, 4.0), look_at: (0.0, 0.5, 0.0), fov_y: 40.0, width: {size}, height: {size}),
    settings: (shading_model: lambertian, background: (0.3, 0.3, 0.3), {settings}),
    materials: {{ "white": (kd: (0.8, 0.8, 0.8)), "red": (kd: (0.8, 0.2, 0.2)) }},
    entities: [
        Mesh((material: Some("white"), geometry: Parallelogram(origin: (-3.0, 0.0, 3.0),
            edge_u: (6.0, 0.0, 0.0), edge_v: (0.0, 0.0, -6.0)))),
        Sphere((center: (0.0, 0.6, 0.0), radius: 0.5, material: "red")),
        ParallelogramLight((v0: (-0.5, 2.5, -0.5), edge01: (1.0, 0.0, 0.0), edge02: (0.0, 0.0, 1.0))),
    ],
)"#
    )
}

/// The error message of a scene that must not load.
/// The error of loading `dir/scene.ron`, which must not load.
pub fn load_error_in(dir: &Path) -> String {
    match Renderer::from_file(&dir.join("scene.ron"), &Default::default()) {
        Ok(_) => panic!("scene loaded but should not have"),
        Err(e) => e.to_string(),
    }
}

/// The error of loading scene text that must not load.
pub fn load_error(ron: &str) -> String {
    let path = Path::new("tests/bad.ron");
    match parse_scene(ron, path).and_then(|f| Renderer::from_scene(&f, path)) {
        Ok(_) => panic!("scene loaded but should not have"),
        Err(e) => e.to_string(),
    }
}

/// Asserts two colours agree within `tol` per channel.
#[track_caller]
pub fn assert_close(actual: Vec3, expected: Vec3, tol: f32) {
    assert!(
        (actual - expected).abs().max_element() <= tol,
        "got {actual}, expected {expected} (tolerance {tol})"
    );
}

/// A camera at `(0, 0, z)` looking down -z at the origin, `n x n` pixels, so that the
/// centre pixel's single sample passes exactly through the origin (n odd).
pub fn camera(z: f32, n: u32) -> String {
    format!(
        "camera: (position: (0, 0, {z}), look_at: (0, 0, 0), fov_y: 30, width: {n}, height: {n})"
    )
}

/// A 2x2 quad in the plane z = `z`, centred on the z axis, made of `material`.
pub fn quad(z: f32, material: &str) -> String {
    format!(
        "Mesh((material: Some(\"{material}\"), geometry: Parallelogram(origin: (-1, -1, {z}), edge_u: (2, 0, 0), edge_v: (0, 2, 0))))"
    )
}

/// Skips (returns from) a test with a line that libtest does not capture: the test still
/// reports "ok", so the line and its running count are what show it did not run.
pub fn skip(test: &str, why: &str) {
    use std::io::Write;
    use std::sync::atomic::{AtomicUsize, Ordering};
    static SKIPPED: AtomicUsize = AtomicUsize::new(0);
    let n = SKIPPED.fetch_add(1, Ordering::Relaxed) + 1;
    let binary = std::env::args().next().unwrap_or_default();
    let binary = Path::new(&binary)
        .file_name()
        .map_or("", |f| f.to_str().unwrap_or(""))
        .split('-')
        .next()
        .unwrap_or("")
        .to_owned();
    // Writing to the handle, not through eprintln!, bypasses libtest's capture.
    let _ = writeln!(std::io::stderr(), "SKIPPED ({n} in {binary}) {test}: {why}");
}
