//! Seeded mutation test (issue 11): a few hundred mutations each of a RON scene, a small
//! GLB and an OBJ go through the real loaders and one render pass; every one must end in
//! an image or a one-line error, never a panic. The fuzz targets in `fuzz/` do the same
//! for as long as one lets them run; this guards against regressions in the normal suite.

mod common;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use common::temp_dir;
use glint::{Overrides, Renderer};
use serde_json::{Value, json};

/// xorshift64*: a tiny deterministic generator, so a failure names a reproducible case.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that break parsers and numerics: extremes, signs, specials, big indices.
const TOKENS: [&str; 14] = [
    "0",
    "-1",
    "1e38",
    "-3e38",
    "1e-45",
    "NaN",
    "inf",
    "-0",
    "4294967295",
    "65536",
    "99999999999",
    "\"\"",
    "[]",
    "",
];
const BYTES: &[u8] = b"\0\xff\x7f\x80-9.e[](){}\",:/\n";

/// One to four random edits: bit flips, special bytes, deletions, duplications, and (in
/// text) a number replaced by one of [`TOKENS`].
fn mutate(input: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut out = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        if out.is_empty() {
            break;
        }
        let at = rng.below(out.len());
        match rng.below(5) {
            0 => out[at] ^= 1 << rng.below(8),
            1 => out[at] = BYTES[rng.below(BYTES.len())],
            2 => {
                let end = (at + 1 + rng.below(8)).min(out.len());
                out.drain(at..end);
            }
            3 => {
                let end = (at + 1 + rng.below(16)).min(out.len());
                let chunk = out[at..end].to_vec();
                let to = rng.below(out.len());
                out.splice(to..to, chunk);
            }
            _ => {
                // The number (or word) around `at`.
                let is_num = |b: u8| b.is_ascii_alphanumeric() || b"-+.".contains(&b);
                let (mut s, mut e) = (at, at);
                while s > 0 && is_num(out[s - 1]) {
                    s -= 1;
                }
                while e < out.len() && is_num(out[e]) {
                    e += 1;
                }
                let token = TOKENS[rng.below(TOKENS.len())].as_bytes().to_vec();
                out.splice(s..e, token);
            }
        }
    }
    out
}

/// Loads `file` and renders one pass at 4x4; a panic fails the test naming the case.
fn survive(file: &Path, case: &str) {
    let tiny = Overrides {
        width: Some(4),
        height: Some(4),
        seed: None,
        set: vec![],
    };
    let run = catch_unwind(AssertUnwindSafe(|| {
        let mut renderer = Renderer::from_file(file, &tiny)?;
        renderer.render_pass(0, &mut |_| {})
    }));
    match run {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            let line = e.to_string();
            assert!(!line.contains('\n'), "{case}: a multi-line error: {line}");
        }
        Err(_) => panic!("{case}: panicked (the input is {})", file.display()),
    }
}

/// The committed glTF fixture packed as one GLB: its buffer and PNG in the BIN chunk.
fn fixture_glb() -> (Value, Vec<u8>) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/fixture");
    let mut gltf: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("glint_fixture.gltf")).unwrap())
            .unwrap();
    let mut bin = std::fs::read(dir.join("glint_fixture.bin")).unwrap();
    let png = std::fs::read(dir.join("checker.png")).unwrap();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let views = gltf["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": png.len()}));
    let view = views.len() - 1;
    bin.extend_from_slice(&png);
    gltf["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
    gltf["buffers"] = json!([{"byteLength": bin.len()}]);
    (gltf, bin)
}

/// A GLB container: header, JSON chunk, BIN chunk, each padded to 4 bytes.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |data: &[u8], fill: u8| {
        let mut v = data.to_vec();
        while !v.len().is_multiple_of(4) {
            v.push(fill);
        }
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    for (chunk, kind) in [(&json, b"JSON"), (&bin, b"BIN\0")] {
        out.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(chunk);
    }
    out
}

#[test]
fn mutated_ron_scenes_never_panic() {
    let base =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cube_textured.ron"))
            .unwrap();
    let dir = temp_dir();
    std::fs::create_dir(dir.path().join("assets")).unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/checker.png"),
        dir.path().join("assets/checker.png"),
    )
    .unwrap();
    let scenes = dir.path().join("scenes");
    std::fs::create_dir(&scenes).unwrap();
    let file = scenes.join("scene.ron");
    let mut rng = Rng(0x5EED_0001);
    for case in 0..300 {
        std::fs::write(&file, mutate(&base, &mut rng)).unwrap();
        survive(&file, &format!("RON mutation {case}"));
    }
}

#[test]
fn mutated_glb_models_never_panic() {
    let (gltf, bin) = fixture_glb();
    let json = serde_json::to_vec(&gltf).unwrap();
    let dir = temp_dir();
    let file = dir.path().join("model.glb");
    std::fs::write(&file, glb(&json, &bin)).unwrap();
    survive(&file, "the unmutated GLB");
    let mut rng = Rng(0x5EED_0002);
    for case in 0..300 {
        // Half in the JSON (then packed into a well-formed container), half anywhere.
        let bytes = if case % 2 == 0 {
            glb(&mutate(&json, &mut rng), &bin)
        } else {
            mutate(&glb(&json, &bin), &mut rng)
        };
        std::fs::write(&file, bytes).unwrap();
        survive(&file, &format!("GLB mutation {case}"));
    }
}

#[test]
fn mutated_obj_models_never_panic() {
    let base = b"# a textured quad and a triangle\nmtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\nv 0 0 1\nv 2 0 1\nv 0 2 1\nf 5 6 7\nf -1 -2 -3\n";
    let mtl = b"newmtl red\nKd 0.8 0.1 0.1\nKs 0.2 0.2 0.2\nNs 32\nd 0.5\nmap_Kd checker.png\n";
    let dir = temp_dir();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/checker.png"),
        dir.path().join("checker.png"),
    )
    .unwrap();
    let file = dir.path().join("model.obj");
    let mut rng = Rng(0x5EED_0003);
    for case in 0..300 {
        let (obj, mtl) = if case % 3 == 0 {
            (base.to_vec(), mutate(mtl, &mut rng))
        } else {
            (mutate(base, &mut rng), mtl.to_vec())
        };
        std::fs::write(&file, obj).unwrap();
        std::fs::write(dir.path().join("quad.mtl"), mtl).unwrap();
        survive(&file, &format!("OBJ mutation {case}"));
    }
}

/// Found by the OBJ mutations: `tobj` unwraps a colour of two components.
#[test]
fn an_mtl_colour_with_two_components_is_an_error_not_a_panic() {
    let dir = temp_dir();
    let file = dir.path().join("model.obj");
    std::fs::write(
        &file,
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl red\nKd 0.8 0.1\n").unwrap();
    let error = Renderer::from_file(&file, &Overrides::default())
        .err()
        .expect("an error")
        .to_string();
    assert!(error.contains("model.obj: malformed OBJ file"), "{error}");
}
