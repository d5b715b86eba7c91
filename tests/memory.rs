//! Sizes the validator accepts but the machine cannot hold: refused before allocating,
//! with one line that says how much is needed and how much is available (issue 11,
//! item 4). `GLINT_MAX_MEMORY` stands in for a small machine, so the tests do not
//! depend on this one's memory.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::*;

const SCENE: &str = r#"(
    camera: (position: (0, 0, 3), look_at: (0, 0, 0), fov_y: 40, width: 8, height: 8),
    materials: { "m": (kd: (0.5, 0.5, 0.5)) },
    entities: [
        Mesh((name: Some("ball"), material: Some("m"), geometry: GEOMETRY)),
        PointLight((position: (0, 2, 2), color: (1, 1, 1))),
    ],
)"#;

fn glint(dir: &Path, limit: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir)
        .env("GLINT_MAX_MEMORY", limit)
        .args(args)
        .output()
        .expect("glint runs")
}

/// The one error line of a run that must fail without writing `out.png`.
#[track_caller]
fn refusal(dir: &Path, out: Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!dir.join("out.png").exists(), "an image was written");
    let lines: Vec<_> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    lines[0].to_owned()
}

#[track_caller]
fn assert_mentions(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "{message:?} does not mention {p:?}");
    }
}

#[test]
fn a_film_larger_than_memory_is_refused_before_the_render() {
    let dir = scene_dir(&SCENE.replace("GEOMETRY", "Cube"));
    let args = [
        "render",
        "scene.ron",
        "--width",
        "8192",
        "--height",
        "8192",
        "-o",
        "out.png",
    ];
    let line = refusal(dir.path(), glint(dir.path(), "256M", &args));
    // 8192² pixels of 120 bytes.
    assert_mentions(
        &line,
        &["8192x8192 film", "8.1 GB", "268.4 MB", "GLINT_MAX_MEMORY"],
    );
    let fits = glint(
        dir.path(),
        "256M",
        &["render", "scene.ron", "-o", "out.png"],
    );
    assert!(fits.status.success(), "{:?}", fits);
}

#[test]
fn a_sphere_larger_than_memory_is_refused_at_load() {
    let dir = scene_dir(&SCENE.replace("GEOMETRY", "UvSphere(segments: 16384, rings: 16384)"));
    let args = ["render", "scene.ron", "-o", "out.png"];
    let line = refusal(dir.path(), glint(dir.path(), "1G", &args));
    assert_mentions(
        &line,
        &["scene.ron", "ball", "geometry", "536870912 triangles", "GB"],
    );
}

/// A 1-bit grey PNG of `side`² black pixels: a few kilobytes that decode to gigabytes.
fn tiny_huge_png(side: u32) -> Vec<u8> {
    let mut png = Vec::new();
    let mut e = png::Encoder::new(&mut png, side, side);
    e.set_color(png::ColorType::Grayscale);
    e.set_depth(png::BitDepth::One);
    e.set_compression(png::Compression::Fast);
    let mut header = e.write_header().unwrap();
    let mut writer = header.stream_writer().unwrap();
    let row = vec![0u8; side.div_ceil(8) as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut writer, &row).unwrap();
    }
    writer.finish().unwrap();
    header.finish().unwrap();
    png
}

#[test]
fn a_texture_larger_than_memory_is_refused_naming_the_material() {
    let scene = SCENE
        .replace("GEOMETRY", "Cube")
        .replace("(kd: (0.5, 0.5, 0.5))", r#"(kd_texture: Some("huge.png"))"#);
    let dir = scene_dir(&scene);
    let png = tiny_huge_png(20000);
    assert!(png.len() < 1_000_000, "{} bytes", png.len());
    std::fs::write(dir.path().join("huge.png"), png).unwrap();
    let args = ["render", "scene.ron", "-o", "out.png"];
    let line = refusal(dir.path(), glint(dir.path(), "2G", &args));
    assert_mentions(
        &line,
        &[
            "huge.png",
            "material \"m\"",
            "kd_texture",
            "20000x20000 texture",
        ],
    );
}

#[test]
fn a_bad_memory_limit_is_an_error() {
    let dir = scene_dir(&SCENE.replace("GEOMETRY", "Cube"));
    let args = ["render", "scene.ron", "-o", "out.png"];
    let line = refusal(dir.path(), glint(dir.path(), "lots", &args));
    assert_mentions(&line, &["GLINT_MAX_MEMORY=lots", "512M"]);
}
