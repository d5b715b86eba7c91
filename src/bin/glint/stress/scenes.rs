//! RON fragments and checks shared by the rendered cases (6 to 11): a scene from its
//! parts, a camera at the budget's size, a two-sided rectangle.

use std::path::Path;

use glam::Vec3;

use super::{Budget, Rendered, Row, render_ron, v3};
use glint::render::Renderer;
use glint::scene::parse_scene;

/// A scene with a camera, settings, materials and entities (RON fragments).
pub fn scene(camera: &str, settings: &str, materials: &str, entities: &str) -> String {
    format!(
        "(camera: ({camera}), settings: ({settings}), materials: {{ {materials} }}, entities: [ {entities} ])"
    )
}

pub fn cam(b: &Budget, position: Vec3, look_at: Vec3, fov: f32) -> String {
    format!(
        "position: {}, look_at: {}, fov_y: {fov:?}, width: {}, height: {}",
        v3(position),
        v3(look_at),
        b.width,
        b.height()
    )
}

/// A two-sided rectangle `origin + s*u + t*v` as a RON mesh entity.
pub fn rect(origin: Vec3, u: Vec3, v: Vec3, material: &str) -> String {
    format!(
        "Mesh((geometry: Parallelogram(origin: {}, edge_u: {}, edge_v: {}), material: Some(\"{material}\"))),",
        v3(origin),
        v3(u),
        v3(v)
    )
}

/// Renders, or turns the error into a failing row.
pub fn try_render(case: &str, text: &str, rows: &mut Vec<Row>) -> Option<Rendered> {
    match render_ron(text) {
        Ok(r) => Some(r),
        Err(e) => {
            rows.push(Row::error(case, e));
            None
        }
    }
}

/// Pixels whose largest component differs from `expected` by more than `tol` (relative).
pub fn mismatches(img: &Rendered, expected: Vec3, tol: f32) -> f64 {
    img.image
        .iter()
        .filter(|p| {
            let e = (**p - expected).abs().max_element();
            e.is_nan() || e > tol * expected.max_element().max(1e-30)
        })
        .count() as f64
}

/// The load error of a scene, as its one-line message (None when it loads).
pub fn load_error(text: &str) -> Option<String> {
    let path = Path::new("stress.ron");
    let result: glint::Result<Renderer> =
        parse_scene(text, path).and_then(|f| Renderer::from_scene(&f, path));
    match result {
        Ok(_) => None,
        Err(e) => Some(e.to_string()),
    }
}
