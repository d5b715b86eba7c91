//! Malformed glTF files, made from the project's own fixture or written here: each must
//! fail with one error line naming the file, never a panic, an abort or silent loss.

mod common;

use std::path::Path;
use std::process::Command;

use common::temp_dir;
use serde_json::{Value, json};

/// The fixture's JSON, with its buffer and texture copied beside `dir`'s copy of it.
fn fixture_in(dir: &Path) -> Value {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/fixture");
    for f in ["glint_fixture.bin", "checker.png"] {
        std::fs::copy(fixture.join(f), dir.join(f)).unwrap();
    }
    serde_json::from_str(&std::fs::read_to_string(fixture.join("glint_fixture.gltf")).unwrap())
        .unwrap()
}

/// Runs `glint info` on `gltf` written as `model.gltf` in `dir`: (exit code, stderr).
fn info(dir: &Path, gltf: &Value) -> (Option<i32>, String) {
    std::fs::write(dir.join("model.gltf"), gltf.to_string()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir)
        .args(["info", "model.gltf"])
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// One clean error line naming the file; `code` 1, not 101 (panic) or a signal (abort).
fn assert_clean_error(dir: &Path, gltf: &Value, expect: &str) {
    let (code, stderr) = info(dir, gltf);
    assert_eq!(code, Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: model.gltf: "), "{stderr}");
    assert!(
        stderr.contains(expect),
        "expected \"{expect}\" in: {stderr}"
    );
}

#[test]
fn the_fixture_itself_loads() {
    let dir = temp_dir();
    let gltf = fixture_in(dir.path());
    let (code, stderr) = info(dir.path(), &gltf);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn an_attribute_naming_a_missing_accessor_is_an_error_not_a_panic() {
    let dir = temp_dir();
    let gltf = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]
    });
    assert_clean_error(dir.path(), &gltf, "malformed glTF file");
}

#[test]
fn an_embedded_image_without_a_mime_type_is_an_error_not_a_panic() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    gltf["images"] = json!([{"bufferView": 0}]);
    assert_clean_error(dir.path(), &gltf, "malformed glTF file");
}

#[test]
fn a_node_cycle_is_an_error_naming_the_node() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    gltf["nodes"][0]["children"] = json!([0, 1]);
    assert_clean_error(dir.path(), &gltf, "is reached twice");
}

/// Shared children would let 40 nodes draw 2^20 instances: a 2 KB file that once kept
/// glint busy for minutes. A node has one parent, so instances are bounded by the file.
#[test]
fn nodes_shared_between_parents_cannot_multiply_instances() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    let levels = 20;
    let mut nodes: Vec<Value> = (0..2 * (levels - 1))
        .map(|i| json!({"children": [2 * (i / 2) + 2, 2 * (i / 2) + 3]}))
        .collect();
    nodes.extend([json!({"mesh": 0}), json!({"mesh": 0})]);
    gltf["nodes"] = Value::Array(nodes);
    gltf["scenes"] = json!([{"nodes": [0, 1]}]);
    gltf["scene"] = json!(0);
    assert_clean_error(dir.path(), &gltf, "is reached twice");
}

#[test]
fn a_200000_deep_node_chain_is_an_error_not_a_stack_overflow() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    let n = 200_000;
    let mut nodes: Vec<Value> = (0..n - 1).map(|i| json!({"children": [i + 1]})).collect();
    nodes.push(json!({"mesh": 0}));
    gltf["nodes"] = Value::Array(nodes);
    gltf["scenes"] = json!([{"nodes": [0]}]);
    gltf["scene"] = json!(0);
    assert_clean_error(dir.path(), &gltf, "levels deep");
}

#[test]
fn a_missing_texture_is_an_error_naming_the_material_and_the_image() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    gltf["images"] = json!([{"uri": "missing.png"}]);
    assert_clean_error(
        dir.path(),
        &gltf,
        "material \"checker\": base colour image 0 (\"missing.png\") cannot be read",
    );
}

#[test]
fn a_corrupt_texture_is_an_error_naming_the_material_and_the_image() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    std::fs::write(dir.path().join("checker.png"), b"\x89PNG not really").unwrap();
    gltf["images"] = json!([{"uri": "checker.png"}]);
    assert_clean_error(dir.path(), &gltf, "material \"checker\"");
}

#[test]
fn a_buffer_view_longer_than_its_buffer_is_refused_not_read() {
    let dir = temp_dir();
    let mut gltf = fixture_in(dir.path());
    gltf["bufferViews"][0]["byteLength"] = json!(100_000);
    assert_clean_error(dir.path(), &gltf, "has no readable POSITION attribute");
}

#[test]
fn a_missing_buffer_file_is_an_error_naming_the_buffer_and_the_file() {
    let dir = temp_dir();
    let gltf = fixture_in(dir.path());
    std::fs::remove_file(dir.path().join("glint_fixture.bin")).unwrap();
    assert_clean_error(
        dir.path(),
        &gltf,
        "buffer 0: file not found: glint_fixture.bin",
    );
}
