//! Model import: the project's own glTF fixture (always), and the third-party glTF and
//! OBJ files in ../shared/assets (skipped with a printed reason when absent).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::{Quat, Vec3};
use glint::scene::model::{ImportOptions, ImportReport, import_model};
use glint::scene::{Material, MaterialRef, Mesh, Transform, parse_scene};
use glint::shade::texture::WrapMode;
use glint::{GlintError, Overrides, Renderer};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn fixture_dir() -> PathBuf {
    repo().join("assets/fixture")
}

/// The shared assets folder, or `None` (with the reason printed) when it is absent.
fn shared_assets(test: &str) -> Option<PathBuf> {
    let dir = repo().join("../shared/assets");
    if dir.join("README.md").is_file() {
        Some(dir)
    } else {
        println!(
            "{test}: skipped: {} not found (third-party assets are not in the repository)",
            dir.display()
        );
        None
    }
}

fn import(path: &Path) -> Result<(World, ImportReport, Vec<String>), GlintError> {
    let mut world = World::new();
    let mut warnings = Vec::new();
    let report = import_model(&mut world, path, &ImportOptions::default(), &mut warnings)?;
    Ok((world, report, warnings))
}

fn small() -> Overrides {
    Overrides {
        width: Some(32),
        height: Some(32),
        seed: None,
        set: vec![("pixel_samples".into(), "1".into())],
    }
}

fn render(mut r: Renderer) -> Vec<Vec3> {
    r.render(None, &mut |_| {}).expect("render");
    r.film().image()
}

// ---------------------------------------------------------------------------------------
// The project's fixture: generated here, committed under assets/fixture.

const FIXTURE_LIGHT: Vec3 = Vec3::new(2.0, 4.0, 3.0);
/// |light - bounds centre|^2 with the centre at (0, 0.5, 0): the import gives colour 1.
const FIXTURE_INTENSITY: f32 = 4.0 + 12.25 + 9.0;
const BOX_YAW_DEGREES: f32 = 30.0;

fn push_f32s(bin: &mut Vec<u8>, values: impl IntoIterator<Item = f32>) {
    for v in values {
        bin.extend_from_slice(&v.to_le_bytes());
    }
}

/// The fixture: a checker-textured floor (REPEAT sampler, uv 0..2), a red box rotated and
/// lifted by its node, a KHR_lights_punctual point light and a camera. Returns the glTF
/// JSON, the .bin buffer and the checker PNG.
fn fixture_files() -> (String, Vec<u8>, Vec<u8>) {
    // Floor: 4 vertices in y = 0, counter-clockwise from above; glTF uv (v down the image).
    let floor_p = [
        [-2.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
        [2.0, 0.0, -2.0],
        [-2.0, 0.0, -2.0],
    ];
    let floor_uv = [[0.0, 2.0], [2.0, 2.0], [2.0, 0.0], [0.0, 0.0]];
    let floor_idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    // Box: glint's own unit cube, so the RON scene can say `Cube`.
    let cube = glint::scene::shapes::cube();
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut view = |bin: &mut Vec<u8>, start: usize, target: u32| {
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{start},"byteLength":{},"target":{target}}}"#,
            bin.len() - start
        ));
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.len() - 1
    };
    let vec3_minmax = |p: &[[f32; 3]]| {
        let lo = p.iter().fold([f32::MAX; 3], |a, b| {
            [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])]
        });
        let hi = p.iter().fold([f32::MIN; 3], |a, b| {
            [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])]
        });
        format!(
            r#""min":[{},{},{}],"max":[{},{},{}]"#,
            lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
        )
    };
    let mut add = |bin: &mut Vec<u8>, data: Attr| {
        let start = bin.len();
        let (count, kind, comp, extra, target) = match &data {
            Attr::Vec3(v, minmax) => {
                push_f32s(bin, v.iter().flatten().copied());
                let extra = if *minmax {
                    format!(",{}", vec3_minmax(v))
                } else {
                    String::new()
                };
                (v.len(), "VEC3", 5126, extra, 34962)
            }
            Attr::Vec2(v) => {
                push_f32s(bin, v.iter().flatten().copied());
                (v.len(), "VEC2", 5126, String::new(), 34962)
            }
            Attr::Index(v) => {
                for i in v {
                    bin.extend_from_slice(&i.to_le_bytes());
                }
                (v.len(), "SCALAR", 5123, String::new(), 34963)
            }
        };
        let v = view(bin, start, target);
        accessors.push(format!(
            r#"{{"bufferView":{v},"componentType":{comp},"count":{count},"type":"{kind}"{extra}}}"#
        ));
        accessors.len() - 1
    };
    let fp = add(&mut bin, Attr::Vec3(floor_p.to_vec(), true));
    let fn_ = add(&mut bin, Attr::Vec3(vec![[0.0, 1.0, 0.0]; 4], false));
    let fuv = add(&mut bin, Attr::Vec2(floor_uv.to_vec()));
    let fi = add(&mut bin, Attr::Index(floor_idx.to_vec()));
    let cp = add(
        &mut bin,
        Attr::Vec3(
            cube.vertices
                .iter()
                .map(|v| v.position.to_array())
                .collect(),
            true,
        ),
    );
    let cn = add(
        &mut bin,
        Attr::Vec3(
            cube.vertices.iter().map(|v| v.normal.to_array()).collect(),
            false,
        ),
    );
    let cuv = add(
        &mut bin,
        Attr::Vec2(
            cube.vertices
                .iter()
                .map(|v| [v.texcoord.x, 1.0 - v.texcoord.y])
                .collect(),
        ),
    );
    let ci = add(
        &mut bin,
        Attr::Index(cube.triangles.iter().flatten().map(|&i| i as u16).collect()),
    );
    let yaw = Quat::from_rotation_y(BOX_YAW_DEGREES.to_radians());
    // Camera at (0, 2.5, 6) looking at (0, 0.5, 0): pitch down by atan(2 / 6).
    let pitch = Quat::from_rotation_x(-(2.0f32 / 6.0).atan());
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0", "generator": "glint tests/assets.rs (fixture_files)", "copyright": "glint project, MIT OR Apache-2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"name": "lamp", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": {FIXTURE_INTENSITY}}}]}}}},
  "scene": 0,
  "scenes": [{{"name": "fixture", "nodes": [0, 1, 2, 3]}}],
  "nodes": [
    {{"name": "floor", "mesh": 0}},
    {{"name": "box", "mesh": 1, "translation": [0.0, 0.5, 0.0], "rotation": [{}, {}, {}, {}]}},
    {{"name": "lamp", "translation": [{}, {}, {}], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"name": "view", "camera": 0, "translation": [0.0, 2.5, 6.0], "rotation": [{}, {}, {}, {}]}}
  ],
  "cameras": [{{"name": "view", "type": "perspective", "perspective": {{"yfov": 0.7, "aspectRatio": 1.0, "znear": 0.1}}}}],
  "meshes": [
    {{"name": "floor", "primitives": [{{"attributes": {{"POSITION": {fp}, "NORMAL": {fn_}, "TEXCOORD_0": {fuv}}}, "indices": {fi}, "material": 0}}]}},
    {{"name": "box", "primitives": [{{"attributes": {{"POSITION": {cp}, "NORMAL": {cn}, "TEXCOORD_0": {cuv}}}, "indices": {ci}, "material": 1}}]}}
  ],
  "materials": [
    {{"name": "checker", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0.0, "roughnessFactor": 1.0}}}},
    {{"name": "red", "pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.15, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}}}}
  ],
  "textures": [{{"sampler": 0, "source": 0}}],
  "samplers": [{{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}}],
  "images": [{{"uri": "checker.png"}}],
  "buffers": [{{"uri": "glint_fixture.bin", "byteLength": {}}}],
  "bufferViews": [
    {}
  ],
  "accessors": [
    {}
  ]
}}
"#,
        yaw.x,
        yaw.y,
        yaw.z,
        yaw.w,
        FIXTURE_LIGHT.x,
        FIXTURE_LIGHT.y,
        FIXTURE_LIGHT.z,
        pitch.x,
        pitch.y,
        pitch.z,
        pitch.w,
        bin.len(),
        views.join(",\n    "),
        accessors.join(",\n    "),
    );
    // A 4x4 checker of white and cyan, 8 texels a cell so bilinear filtering keeps the
    // edges sharp: components 0 and 255 are the same in sRGB and linear, so the RON scene
    // (linear PNG decode) sees the same texels as glTF (sRGB).
    let img = image::RgbImage::from_fn(32, 32, |x, y| {
        if (x / 8 + y / 8) % 2 == 0 {
            image::Rgb([255, 255, 255])
        } else {
            image::Rgb([0, 255, 255])
        }
    });
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    (json, bin, png)
}

enum Attr {
    Vec3(Vec<[f32; 3]>, bool),
    Vec2(Vec<[f32; 2]>),
    Index(Vec<u16>),
}

/// Writes the fixture: `cargo test --release --test assets -- --ignored write_fixture`.
#[test]
#[ignore = "writes assets/fixture; run by hand after changing fixture_files"]
fn write_fixture() {
    let (json, bin, png) = fixture_files();
    let dir = fixture_dir();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("glint_fixture.gltf"), json).unwrap();
    std::fs::write(dir.join("glint_fixture.bin"), bin).unwrap();
    std::fs::write(dir.join("checker.png"), png).unwrap();
}

#[test]
fn committed_fixture_matches_its_generator() {
    let (json, bin, _) = fixture_files();
    let dir = fixture_dir();
    assert_eq!(
        std::fs::read_to_string(dir.join("glint_fixture.gltf")).unwrap(),
        json,
        "run the write_fixture test to regenerate"
    );
    assert_eq!(std::fs::read(dir.join("glint_fixture.bin")).unwrap(), bin);
}

const FIXTURE_CAMERA: &str = "camera: (position: (0.0, 2.5, 6.0), look_at: (0.0, 0.5, 0.0), fov_y: 40.0, width: 48, height: 48)";

#[test]
fn fixture_through_ron_equals_the_same_geometry_in_ron() {
    let scene_path = fixture_dir().join("virtual_scene.ron");
    let via_gltf = format!(
        r#"({FIXTURE_CAMERA}, entities: [Mesh((geometry: Gltf(path: "glint_fixture.gltf")))])"#
    );
    // The material mapping by hand (docs/materials.md): checker = rough dielectric
    // (kd = texture, ks = 0, shininess 1); red: roughness 0.5 -> ks = 0.04 * 0.5, n = 30.
    let in_ron = format!(
        r#"({FIXTURE_CAMERA},
        materials: {{
            "checker": (kd: (1.0, 1.0, 1.0), kd_texture: Some("checker.png"), wrap: (repeat, repeat)),
            "red": (kd: (0.8, 0.15, 0.1), ks: (0.02, 0.02, 0.02), shininess: 30.0, wrap: (repeat, repeat)),
        }},
        entities: [
            Mesh((material: Some("checker"), geometry: Inline(
                vertices: [
                    (position: (-2.0, 0.0, 2.0), normal: Some((0.0, 1.0, 0.0)), texcoord: (0.0, -1.0)),
                    (position: (2.0, 0.0, 2.0), normal: Some((0.0, 1.0, 0.0)), texcoord: (2.0, -1.0)),
                    (position: (2.0, 0.0, -2.0), normal: Some((0.0, 1.0, 0.0)), texcoord: (2.0, 1.0)),
                    (position: (-2.0, 0.0, -2.0), normal: Some((0.0, 1.0, 0.0)), texcoord: (0.0, 1.0)),
                ],
                triangles: [(0, 1, 2), (0, 2, 3)]))),
            Mesh((material: Some("red"), geometry: Cube,
                transform: (translate: (0.0, 0.5, 0.0), rotate_degrees: (0.0, {BOX_YAW_DEGREES}, 0.0)))),
            PointLight((position: ({}, {}, {}), color: (1.0, 1.0, 1.0))),
        ])"#,
        FIXTURE_LIGHT.x, FIXTURE_LIGHT.y, FIXTURE_LIGHT.z
    );
    let a = Renderer::from_scene(&parse_scene(&via_gltf, &scene_path).unwrap(), &scene_path)
        .expect("glTF scene loads");
    let b = Renderer::from_scene(&parse_scene(&in_ron, &scene_path).unwrap(), &scene_path)
        .expect("RON scene loads");
    let (a, b) = (render(a), render(b));
    let lit = a.iter().filter(|p| p.max_element() > 0.05).count();
    assert!(
        lit > a.len() / 4,
        "the fixture should fill the view ({lit} lit)"
    );
    let mut worst = 0.0f32;
    for (i, (p, q)) in a.iter().zip(&b).enumerate() {
        let d = (*p - *q).abs().max_element();
        worst = worst.max(d);
        assert!(d < 2e-3, "pixel {i}: glTF {p} vs RON {q}");
    }
    println!("largest difference {worst}");
}

#[test]
fn ron_material_overrides_the_files_materials() {
    let scene_path = fixture_dir().join("virtual_scene.ron");
    let text = format!(
        r#"({FIXTURE_CAMERA}, materials: {{"grey": (kd: (0.5, 0.5, 0.5))}},
        entities: [Mesh((material: Some("grey"), geometry: Gltf(path: "glint_fixture.gltf"),
            transform: (translate: (10.0, 0.0, 0.0))))])"#
    );
    let mut r =
        Renderer::from_scene(&parse_scene(&text, &scene_path).unwrap(), &scene_path).unwrap();
    let w = &mut r.world;
    let materials: Vec<String> = w
        .query::<&Material>()
        .iter(w)
        .map(|m| m.name.clone())
        .collect();
    assert_eq!(materials, vec!["grey".to_string()]);
    let mut q = w.query::<(&Mesh, &Transform, &MaterialRef)>();
    let placed: Vec<Vec3> = q
        .iter(w)
        .map(|(_, t, _)| t.world_from_object.translation.into())
        .collect();
    assert_eq!(placed.len(), 2);
    // The RON transform composes with the node's: the box sits at (10, 0.5, 0).
    assert!(
        placed
            .iter()
            .any(|p| p.abs_diff_eq(Vec3::new(10.0, 0.5, 0.0), 1e-6))
    );
    // The file's light comes along; the RON camera stays.
    assert_eq!(r.camera().unwrap().width, 48);
}

#[test]
fn direct_render_uses_the_files_camera_and_light() {
    let path = fixture_dir().join("glint_fixture.gltf");
    let mut r = Renderer::from_model(&path, &small()).unwrap();
    let c = r.camera().unwrap();
    assert!(c.position.abs_diff_eq(Vec3::new(0.0, 2.5, 6.0), 1e-5));
    assert!((c.fov_y_degrees - 0.7f32.to_degrees()).abs() < 1e-4);
    let lights: Vec<_> = r
        .world
        .query::<&glint::scene::PointLight>()
        .iter(&r.world)
        .copied()
        .collect();
    assert_eq!(lights.len(), 1);
    assert!(lights[0].position.abs_diff_eq(FIXTURE_LIGHT, 1e-5));
    assert!(
        lights[0].color.abs_diff_eq(Vec3::ONE, 1e-5),
        "{}",
        lights[0].color
    );
    let summary = r.render(None, &mut |_| {}).unwrap().to_string();
    assert!(summary.contains("camera: the file's \"view\""), "{summary}");
    assert!(summary.contains("lights: 1 from the file"), "{summary}");
}

#[test]
fn direct_render_without_camera_or_light_says_so() {
    // An OBJ has neither: the automatic camera must frame it, with a default light.
    let dir = std::env::temp_dir().join(format!("glint-assets-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("tri.obj");
    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let mut r = Renderer::from_model(&obj, &small()).unwrap();
    let summary = r.render(None, &mut |_| {}).unwrap().to_string();
    assert!(summary.contains("camera: automatic"), "{summary}");
    assert!(summary.contains("default point light"), "{summary}");
    let image = r.film().image();
    // The triangle is framed: the centre pixel is lit, a top corner is background.
    assert!(image[16 * 32 + 16].max_element() > 0.1);
    assert_eq!(image[0], Vec3::ZERO);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unsupported_required_extension_is_one_clear_error() {
    let dir = std::env::temp_dir().join(format!("glint-ext-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("draco.gltf");
    std::fs::write(
        &path,
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["EXT_meshopt_compression"],"extensionsRequired":["EXT_meshopt_compression"]}"#,
    )
    .unwrap();
    let Err(err) = import(&path) else {
        panic!("a required unsupported extension must fail");
    };
    let err = err.to_string();
    assert!(err.contains("EXT_meshopt_compression"), "{err}");
    assert_eq!(err.lines().count(), 1);
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------
// Third-party files in ../shared/assets.

/// Triangle counts per model folder from the assets README ("scene" counts).
fn readme_counts(assets: &Path) -> HashMap<String, u64> {
    let text = std::fs::read_to_string(assets.join("README.md")).unwrap();
    let mut counts = HashMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 6 || cells[1] == "Folder" || cells[1].starts_with("---") {
            continue;
        }
        // "3,884 defs / 7,724 scene": the default-scene count is after the last '/'.
        let part = cells[4].rsplit('/').next().unwrap();
        let digits: String = part
            .trim()
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == ',')
            .filter(char::is_ascii_digit)
            .collect();
        if let Ok(n) = digits.parse() {
            counts.insert(cells[1].to_owned(), n);
        }
    }
    counts
}

fn gltf_files(assets: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for model in std::fs::read_dir(assets.join("khronos-gltf")).unwrap() {
        let model = model.unwrap().path();
        let Ok(variants) = std::fs::read_dir(&model) else {
            continue;
        };
        for variant in variants {
            let Ok(entries) = std::fs::read_dir(variant.unwrap().path()) else {
                continue;
            };
            for f in entries {
                let f = f.unwrap().path();
                if matches!(f.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                    files.push(f);
                }
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_khronos_file_loads_counts_and_renders() {
    let Some(assets) = shared_assets("every_khronos_file_loads_counts_and_renders") else {
        return;
    };
    let counts = readme_counts(&assets);
    let files = gltf_files(&assets);
    assert!(files.len() >= 70, "found {} files", files.len());
    let mut failures = Vec::new();
    for f in &files {
        let folder = f
            .parent()
            .and_then(Path::parent)
            .and_then(Path::file_name)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let variant = f.parent().unwrap().file_name().unwrap().to_string_lossy();
        let expected_error = match variant.as_ref() {
            "glTF-Draco" => Some("KHR_draco_mesh_compression"),
            "glTF-Quantized" => Some("KHR_mesh_quantization"),
            _ => None,
        };
        let result = import(f);
        match (result, expected_error) {
            (Err(e), Some(ext)) => {
                let msg = e.to_string();
                if !msg.contains(ext) || msg.lines().count() != 1 {
                    failures.push(format!("{}: unclear error: {msg}", f.display()));
                }
            }
            (Ok(_), Some(ext)) => failures.push(format!(
                "{}: loaded, expected an error naming {ext}",
                f.display()
            )),
            (Err(e), None) => failures.push(format!("{}: {e}", f.display())),
            (Ok((_, report, _)), None) => {
                match counts.get(&folder) {
                    None => failures.push(format!("{folder}: no count in the assets README")),
                    Some(&n) if report.triangles != n => failures.push(format!(
                        "{}: {} triangles, README says {n}",
                        f.display(),
                        report.triangles
                    )),
                    Some(_) => {}
                }
                let (lo, hi) = report.bounds.expect("bounds");
                if !(lo.is_finite() && hi.is_finite()) {
                    failures.push(format!("{}: bounds not finite", f.display()));
                }
                // One render per model folder and variant is enough; the 1M-triangle file
                // renders once (its .gltf), at the same size.
                let big = folder == "MetalRoughSpheresNoTextures" && variant == "glTF-Binary";
                if !big {
                    let image = render(Renderer::from_model(f, &small()).unwrap());
                    if image.iter().any(|p| !p.is_finite()) {
                        failures.push(format!("{}: non-finite pixel", f.display()));
                    }
                    if image.iter().all(|p| *p == Vec3::ZERO) {
                        failures.push(format!("{}: all black", f.display()));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn khronos(assets: &Path, model: &str, variant: &str, file: &str) -> PathBuf {
    assets
        .join("khronos-gltf")
        .join(model)
        .join(variant)
        .join(file)
}

/// World-space vertices of the mesh entity whose name starts with `prefix`.
fn world_vertices(world: &mut World, prefix: &str) -> (Vec<Vec3>, Vec<glam::Vec2>, Entity) {
    let mut q = world.query::<(&Name, &Mesh, &Transform, &MaterialRef)>();
    let (_, mesh, t, m) = q
        .iter(world)
        .find(|(n, ..)| n.as_str().starts_with(prefix))
        .unwrap_or_else(|| panic!("no mesh named {prefix}*"));
    let p = mesh
        .data
        .vertices
        .iter()
        .map(|v| t.world_from_object.transform_point3(v.position))
        .collect();
    let uv = mesh.data.vertices.iter().map(|v| v.texcoord).collect();
    (p, uv, m.0)
}

fn mean<T: Copy + std::iter::Sum<T> + std::ops::Div<f32, Output = T>>(v: &[T]) -> T {
    v.iter().copied().sum::<T>() / v.len() as f32
}

#[test]
fn texture_coordinate_test_corners_land_where_labelled() {
    let Some(assets) = shared_assets("texture_coordinate_test_corners_land_where_labelled") else {
        return;
    };
    let f = khronos(
        &assets,
        "TextureCoordinateTest",
        "glTF",
        "TextureCoordinateTest.gltf",
    );
    let (mut world, report, _) = import(&f).unwrap();
    let (lo, hi) = report.bounds.unwrap();
    let centre = 0.5 * (lo + hi);
    // Each labelled square sits in its corner of the model (x right, y up, facing +z) and
    // reads the same corner of the image: glint's v runs up, so "top" is v > 0.5.
    for (name, right, top) in [
        ("TopLeftObj", false, true),
        ("TopRightObj", true, true),
        ("BottomLeftObj", false, false),
        ("BottomRightObj", true, false),
    ] {
        let (p, uv, _) = world_vertices(&mut world, name);
        let (p, uv) = (mean(&p), mean(&uv));
        assert_eq!(p.x > centre.x, right, "{name} at {p}");
        assert_eq!(p.y > centre.y, top, "{name} at {p}");
        assert_eq!(uv.x > 0.5, right, "{name} reads u = {}", uv.x);
        assert_eq!(uv.y > 0.5, top, "{name} reads v = {}", uv.y);
    }
}

#[test]
fn orientation_test_arrows_point_at_their_targets() {
    let Some(assets) = shared_assets("orientation_test_arrows_point_at_their_targets") else {
        return;
    };
    let f = khronos(&assets, "OrientationTest", "glTF", "OrientationTest.gltf");
    let (mut world, _, _) = import(&f).unwrap();
    for axis in ["X1", "X2", "Y1", "Y2", "Z1", "Z2"] {
        let (arrow, _, _) = world_vertices(&mut world, &format!("Arrow{axis}/"));
        let (target, _, _) = world_vertices(&mut world, &format!("Target{axis}/"));
        let mut q = world.query::<(&Name, &Transform)>();
        let base: Vec3 = q
            .iter(&world)
            .find(|(n, _)| n.as_str().starts_with(&format!("Arrow{axis}/")))
            .unwrap()
            .1
            .world_from_object
            .translation
            .into();
        // The tip is the arrow vertex farthest from the node's origin (the arrow's base).
        let tip = arrow
            .iter()
            .copied()
            .max_by(|a, b| a.distance(base).total_cmp(&b.distance(base)))
            .unwrap();
        // Compare directions in the plane the node rotates in (across its axis); the
        // arrow head's thickness along the axis is not part of the test.
        let rotation_axis = match &axis[..1] {
            "X" => Vec3::X,
            "Y" => Vec3::Y,
            _ => Vec3::Z,
        };
        let flat = |v: Vec3| v - v.dot(rotation_axis) * rotation_axis;
        let angle = flat(tip - base)
            .angle_between(flat(mean(&target) - base))
            .to_degrees();
        println!("Arrow{axis}: {angle:.2} degrees off its target");
        // A transposed rotation turns the arrows 10 to 70 degrees away.
        assert!(
            angle < 3.0,
            "Arrow{axis} points {angle} degrees off its target"
        );
    }
}

#[test]
fn negative_scale_test_keeps_normals_outward() {
    let Some(assets) = shared_assets("negative_scale_test_keeps_normals_outward") else {
        return;
    };
    let f = khronos(
        &assets,
        "NegativeScaleTest",
        "glTF-Binary",
        "NegativeScaleTest.glb",
    );
    let (mut world, _, _) = import(&f).unwrap();
    let mut mirrored = 0;
    let mut q = world.query::<(&Name, &Mesh, &Transform)>();
    for (name, mesh, t) in q.iter(&world) {
        let m = t.world_from_object;
        if m.matrix3.determinant() < 0.0 {
            mirrored += 1;
        }
        let normal_from_object = m.matrix3.inverse().transpose();
        let v = &mesh.data.vertices;
        let (mut agree, mut total) = (0, 0);
        for tri in &mesh.data.triangles {
            let [a, b, c] = tri.map(|i| &v[i as usize]);
            let [pa, pb, pc] = [a, b, c].map(|v| m.transform_point3(v.position));
            let ng = (pb - pa).cross(pc - pa);
            if ng.length() < 1e-12 {
                continue;
            }
            let n: Vec3 =
                (normal_from_object * glam::Vec3A::from(a.normal + b.normal + c.normal)).into();
            total += 1;
            if ng.dot(n) > 0.0 {
                agree += 1;
            }
        }
        // The winding (geometric normal) and the vertex normals agree after mirroring.
        assert!(
            agree as f64 >= 0.99 * total as f64,
            "{name}: {agree} of {total} triangles face along their normals"
        );
    }
    assert!(mirrored > 0, "the file has mirrored nodes");
}

#[test]
fn texture_settings_test_wrap_modes_follow_the_samplers() {
    let Some(assets) = shared_assets("texture_settings_test_wrap_modes_follow_the_samplers") else {
        return;
    };
    let f = khronos(
        &assets,
        "TextureSettingsTest",
        "glTF",
        "TextureSettingsTest.gltf",
    );
    let (mut world, _, _) = import(&f).unwrap();
    let mut q = world.query::<&Material>();
    let wrap: HashMap<String, [WrapMode; 2]> =
        q.iter(&world).map(|m| (m.name.clone(), m.wrap)).collect();
    use WrapMode::*;
    // Samplers as the file sets them (wrapS, wrapT), per the README's tests.
    assert_eq!(wrap["TextureRepeatMaterialT"], [Clamp, Repeat]);
    assert_eq!(wrap["TextureClampMaterialT"], [Repeat, Clamp]);
    assert_eq!(wrap["TextureMirrorMaterialT"], [Repeat, MirroredRepeat]);
    assert_eq!(wrap["TextureRepeatMaterialS"], [Repeat, Clamp]);
    assert_eq!(wrap["TextureClampMaterialS"], [Clamp, Repeat]);
    assert_eq!(wrap["TextureMirrorMaterialS"], [MirroredRepeat, Repeat]);
    // And they matter: the same texture read past its edge differs by mode.
    let mut q = world.query::<&Material>();
    let m = q
        .iter(&world)
        .find(|m| m.name == "TextureRepeatMaterialT")
        .unwrap();
    let Some(glint::scene::TextureSource::Decoded(t)) = &m.kd_texture else {
        panic!("decoded texture expected");
    };
    let differ = |a: WrapMode, b: WrapMode| {
        (0..64 * 64).any(|k| {
            let (i, j) = ((k % 64) as f32, (k / 64) as f32);
            let uv = glam::Vec2::new((i + 0.5) / 64.0, 1.0 + (j + 0.5) / 64.0);
            t.sample_nearest(uv, [Clamp, a]) != t.sample_nearest(uv, [Clamp, b])
        })
    };
    assert!(
        differ(Repeat, Clamp) && differ(Repeat, MirroredRepeat) && differ(Clamp, MirroredRepeat)
    );
}

#[test]
fn box_textured_renders_identically_in_all_three_forms() {
    let Some(assets) = shared_assets("box_textured_renders_identically_in_all_three_forms") else {
        return;
    };
    let images: Vec<Vec<Vec3>> = [
        ("glTF", "BoxTextured.gltf"),
        ("glTF-Binary", "BoxTextured.glb"),
        ("glTF-Embedded", "BoxTextured.gltf"),
    ]
    .iter()
    .map(|(v, f)| {
        render(Renderer::from_model(&khronos(&assets, "BoxTextured", v, f), &small()).unwrap())
    })
    .collect();
    assert!(images[0].iter().any(|p| p.max_element() > 0.1));
    assert_eq!(images[0], images[1]);
    assert_eq!(images[0], images[2]);
}

#[test]
fn classic_obj_models_load_with_the_readme_triangle_counts() {
    let Some(assets) = shared_assets("classic_obj_models_load_with_the_readme_triangle_counts")
    else {
        return;
    };
    let c = assets.join("classic");
    let mcguire = c.join("cornell-box/mcguire");
    let mut cases = vec![
        (c.join("utah-teapot/teapot.obj"), 6_320),
        (c.join("utah-teapot/mcguire/teapot.obj"), 15_704),
        (c.join("stanford-bunny/stanford-bunny.obj"), 69_451),
        (c.join("stanford-dragon/dragon.obj"), 19_332),
        (c.join("suzanne/suzanne.obj"), 968),
        (c.join("cornell-box/original-measured/cornell_box.obj"), 36),
        (mcguire.join("CornellBox-Original.obj"), 36),
        (mcguire.join("CornellBox-Mirror.obj"), 36),
        (mcguire.join("CornellBox-Sphere.obj"), 2_188),
        (mcguire.join("CornellBox-Glossy.obj"), 1_112),
        (mcguire.join("CornellBox-Water.obj"), 7_088),
        (c.join("sponza-dabrovic/sponza.obj"), 66_450),
    ];
    for f in std::fs::read_dir(&mcguire).unwrap() {
        let f = f.unwrap().path();
        if f.file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("CornellBox-Empty")
            && f.extension().is_some_and(|e| e == "obj")
        {
            cases.push((f, 12));
        }
    }
    for (f, n) in cases {
        let (mut world, report, warnings) =
            import(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(report.triangles, n, "{}", f.display());
        let (lo, hi) = report.bounds.unwrap();
        assert!(lo.is_finite() && hi.is_finite());
        let name = f.file_name().unwrap().to_string_lossy();
        if name == "dragon.obj" {
            // Its MTL file is missing upstream: one warning, default material.
            assert!(warnings.iter().any(|w| w.contains("material library")));
        } else {
            // McGuire's boxes have an emissive `light` material: noted, nothing else.
            assert!(
                warnings.iter().all(|w| w.contains("emissive")),
                "{}: {warnings:?}",
                f.display()
            );
        }
        if name == "sponza.obj" {
            // Every map_Kd resolves, some only case-insensitively.
            let mut q = world.query::<&Material>();
            let textured = q.iter(&world).filter(|m| m.kd_texture.is_some()).count();
            assert!(textured > 10, "{textured} textured materials");
        }
    }
}
