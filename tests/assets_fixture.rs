//! Model import of the project's own glTF fixture, generated here and committed under
//! assets/fixture: it matches its generator, equals the same geometry in RON, and
//! renders directly with the file's camera and light.

mod common;

use glam::{Quat, Vec3};
use glint::Renderer;
use glint::scene::{Material, MaterialRef, Mesh, Transform, parse_scene};

use common::assets::{fixture_dir, import, render_image, small};
use common::temp_dir;

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

/// Writes the fixture: `cargo test --release --test assets_fixture -- --ignored write_fixture`.
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
    let (a, b) = (render_image(a), render_image(b));
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
    let dir = temp_dir();
    let obj = dir.path().join("tri.obj");
    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let mut r = Renderer::from_model(&obj, &small()).unwrap();
    let summary = r.render(None, &mut |_| {}).unwrap().to_string();
    assert!(summary.contains("camera: automatic"), "{summary}");
    assert!(summary.contains("default point light"), "{summary}");
    let image = r.film().image();
    // The triangle is framed: the centre pixel is lit, a top corner is background.
    assert!(image[16 * 32 + 16].max_element() > 0.1);
    assert_eq!(image[0], Vec3::ZERO);
}

#[test]
fn unsupported_required_extension_is_one_clear_error() {
    let dir = temp_dir();
    let path = dir.path().join("draco.gltf");
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
}

/// A model written out as a scene (what `glint debug` and the viewer take for a model)
/// renders exactly as the model does directly, automatic camera and default light
/// included; and `glint debug` explains a model's pixel.
#[test]
fn model_as_scene_renders_as_the_model() {
    let dir = temp_dir();
    let obj = dir.path().join("tri.obj");
    std::fs::write(&obj, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    for path in [fixture_dir().join("glint_fixture.gltf"), obj] {
        let mut direct = Renderer::from_model(&path, &small()).unwrap();
        direct.render(None, &mut |_| {}).unwrap();
        let (file, _) = Renderer::model_scene(&path, &small()).unwrap();
        let mut scene = Renderer::from_scene(&file, &path).unwrap();
        scene.render(None, &mut |_| {}).unwrap();
        let bits = |r: &Renderer| -> Vec<[u32; 3]> {
            r.film()
                .image()
                .iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect()
        };
        assert!(bits(&direct) == bits(&scene), "{}", path.display());

        let options = glint::debug::DebugOptions {
            pixel: [16, 16],
            output: dir.path().join("debug.png"),
            features: None,
            view_from: None,
            view_size: [64, 48],
            depth_test: false,
            bvh_level: None,
            dump: None,
        };
        let outcome = glint::debug::run(&path, &small(), &options).unwrap();
        let centre = direct.film().pixel(16, 16);
        assert!(outcome.entities > 0, "{}", path.display());
        assert!(centre.max_element() > 0.0, "{}", path.display());
        assert!(
            outcome.pixel_color.abs_diff_eq(centre, 1e-6),
            "{}: debug {} vs render {centre}",
            path.display(),
            outcome.pixel_color
        );
    }
}
