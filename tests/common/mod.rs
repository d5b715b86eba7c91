//! Helpers shared by the system-level tests: build a World from RON text and render it.
#![allow(dead_code)]

use std::path::Path;

use glam::Vec3;
use glint::Renderer;
use glint::scene::parse_scene;

/// Loads RON scene text (relative paths resolve against `tests/`).
pub fn load(ron: &str) -> Renderer {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/inline.ron");
    let file = parse_scene(ron, &path).expect("scene parses");
    Renderer::from_scene(&file, &path).expect("scene is valid")
}

/// Loads and fully renders RON scene text.
pub fn render(ron: &str) -> Renderer {
    let mut r = load(ron);
    r.render(None, &mut |_| {}).expect("render succeeds");
    r
}

/// The error message of a scene that must not load.
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
