//! The viewer's scene: any scene or model as a parsed RON scene, and that scene written
//! back with the viewer's camera and settings.

use std::path::{Path, PathBuf};

use glam::Vec3;
use glint::Renderer;
use glint::scene::format::{CameraDesc, EntityDesc, GeometryDesc, MeshDesc, SceneFile};
use glint::scene::model::SceneFormat;
use glint::scene::{Camera, Settings, read_scene};
use glint::trace::geometry::SceneGeometry;

/// A scene as the viewer holds it: every render and debug trace starts from `file`.
#[derive(Clone, Debug)]
pub struct ViewScene {
    /// The scene (a model is wrapped in a scene of one mesh entity).
    pub file: SceneFile,
    /// Where it came from: resolves the file's relative paths.
    pub path: PathBuf,
    /// The RON text it was read from (`None` for a model), kept so that saving changes
    /// only the camera and the settings and keeps the rest as the user wrote it.
    pub text: Option<String>,
    /// The loader's notes (automatic camera, default light).
    pub notes: Vec<String>,
}

impl ViewScene {
    /// Reads a RON scene, or a glTF/OBJ model with glint's automatic camera and light.
    pub fn load(path: &Path, overrides: &glint::Overrides) -> glint::Result<Self> {
        if SceneFormat::of(path) == SceneFormat::Ron {
            let mut file = read_scene(path)?;
            overrides.apply(&mut file)?;
            // Validates it now, so a bad scene fails before a window opens.
            Renderer::from_scene(&file, path)?;
            let text = std::fs::read_to_string(path).ok();
            return Ok(Self {
                file,
                path: path.to_owned(),
                text,
                notes: Vec::new(),
            });
        }
        let (mut file, mut renderer) = Renderer::model_scene(path, overrides)?;
        renderer.prepare()?;
        let mut notes = renderer.summary(0, Default::default()).notes;
        // Inside an interior, the camera and the default light go inside, under the roof.
        if notes.iter().any(|n| n.starts_with("camera: automatic")) {
            let b = renderer.world.resource::<SceneGeometry>().bounds();
            if let Some(inside) = interior_camera(
                b.min,
                b.max,
                &renderer.camera().ok_or(glint::GlintError::NoCamera)?,
            ) {
                file.camera = CameraDesc::from(&inside);
                let c = 0.5 * (b.min + b.max);
                for e in &mut file.entities {
                    if let EntityDesc::PointLight(light) = e {
                        light.position = Vec3::new(c.x, b.min.y + 0.8 * (b.max.y - b.min.y), c.z);
                    }
                }
                notes.push("viewer: an interior, entered; its default light is inside".into());
            }
        }
        Ok(Self {
            file,
            path: path.to_owned(),
            text: None,
            notes,
        })
    }

    /// The scene's own camera.
    pub fn camera(&self) -> Camera {
        let c = &self.file.camera;
        Camera {
            position: c.position,
            look_at: c.look_at,
            up: c.up,
            fov_y_degrees: c.fov_y,
            width: c.width,
            height: c.height,
        }
    }

    /// The scene with `camera` and `settings` in place of its own.
    pub fn with_view(&self, camera: &Camera, settings: &Settings) -> SceneFile {
        let mut file = self.file.clone();
        file.camera = CameraDesc::from(camera);
        file.settings = settings.clone();
        file
    }

    /// The scene as RON text with `camera` and `settings`: the original text with its
    /// `camera` and `settings` fields replaced, or a new scene for a model.
    pub fn to_ron(&self, camera: &Camera, settings: &Settings) -> String {
        let camera_text = camera_ron(camera);
        let settings_text = ron::ser::to_string_pretty(settings, ron::ser::PrettyConfig::new())
            .expect("settings serialise");
        if let Some(text) = &self.text
            && let Some(patched) = patch_fields(text, &camera_text, &settings_text)
        {
            return patched;
        }
        let mut out = String::from("// Saved by glint view.\n(\n");
        out += &format!("    camera: {camera_text},\n");
        out += &format!("    settings: {},\n", indent(&settings_text));
        out += "    entities: [\n";
        for e in &self.file.entities {
            match e {
                EntityDesc::Mesh(MeshDesc {
                    geometry: GeometryDesc::Obj { path },
                    ..
                }) => out += &format!("        Mesh((geometry: Obj(path: {}))),\n", quote(path)),
                EntityDesc::Mesh(MeshDesc {
                    geometry: GeometryDesc::Gltf { path, .. },
                    ..
                }) => out += &format!("        Mesh((geometry: Gltf(path: {}))),\n", quote(path)),
                EntityDesc::PointLight(l) => {
                    out += &format!(
                        "        PointLight((name: Some({}), position: {}, color: {})),\n",
                        quote(l.name.as_deref().unwrap_or("light")),
                        vec3(l.position),
                        vec3(l.color)
                    )
                }
                _ => {}
            }
        }
        out += "    ],\n)\n";
        out
    }
}

/// For a model with no camera that is wider than it is tall (an interior such as
/// Sponza), a camera inside it at a quarter of its height, looking along its longer
/// side, instead of the framing view from outside.
pub fn interior_camera(min: Vec3, max: Vec3, camera: &Camera) -> Option<Camera> {
    let size = max - min;
    let wide = size.x.max(size.z);
    if wide < 2.0 * size.y || !wide.is_finite() {
        return None;
    }
    let centre = 0.5 * (min + max);
    let eye = Vec3::new(centre.x, min.y + 0.25 * size.y, centre.z);
    let along = if size.x >= size.z { Vec3::X } else { Vec3::Z };
    Some(Camera {
        position: eye - along * 0.35 * wide,
        look_at: eye + along * 0.35 * wide,
        up: Vec3::Y,
        fov_y_degrees: 60.0,
        ..camera.clone()
    })
}

fn quote(s: &str) -> String {
    ron::to_string(s).expect("strings serialise")
}

/// A vector in RON, with each component written so that it reads back exactly.
fn vec3(v: Vec3) -> String {
    format!("({:?}, {:?}, {:?})", v.x, v.y, v.z)
}

fn camera_ron(c: &Camera) -> String {
    format!(
        "(position: {}, look_at: {}, up: {}, fov_y: {:?}, width: {}, height: {})",
        vec3(c.position),
        vec3(c.look_at),
        vec3(c.up),
        c.fov_y_degrees,
        c.width,
        c.height
    )
}

fn indent(text: &str) -> String {
    text.replace('\n', "\n    ")
}

/// `text` with the values of its top-level `camera` and `settings` fields replaced
/// (`settings` added after `camera` when absent); `None` if it has no `camera` field.
pub fn patch_fields(text: &str, camera: &str, settings: &str) -> Option<String> {
    let fields = top_level_fields(text);
    let (_, cam) = fields.iter().find(|(k, _)| k == "camera")?.clone();
    let set = fields.iter().find(|(k, _)| k == "settings").map(|f| f.1);
    let mut edits = vec![(cam, camera.to_owned())];
    match set {
        Some(span) => edits.push((span, indent(settings))),
        None => edits.push((
            (cam.1, cam.1),
            format!(",\n    settings: {}", indent(settings)),
        )),
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0.0));
    let mut out = text.to_owned();
    for ((a, b), new) in edits {
        out.replace_range(a..b, &new);
    }
    Some(out)
}

/// The top-level fields of a RON struct: each name with the byte span of its value.
fn top_level_fields(text: &str) -> Vec<(String, (usize, usize))> {
    let b = text.as_bytes();
    let mut fields = Vec::new();
    let (mut i, mut depth) = (0, 0i32);
    let mut value: Option<(String, usize)> = None;
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        if c == b'/' && b.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                i += 1;
            }
            i += 2;
            continue;
        }
        if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            continue;
        }
        match c {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                depth -= 1;
                if depth == 0
                    && let Some((name, start)) = value.take()
                {
                    fields.push((name, trimmed(text, start, i)));
                }
            }
            b',' if depth == 1 => {
                if let Some((name, start)) = value.take() {
                    fields.push((name, trimmed(text, start, i)));
                }
            }
            _ if depth == 1 && value.is_none() && (c.is_ascii_alphabetic() || c == b'_') => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                let name = text[start..i].to_owned();
                let mut j = i;
                while j < b.len() && b[j].is_ascii_whitespace() {
                    j += 1;
                }
                if b.get(j) == Some(&b':') {
                    value = Some((name, j + 1));
                    i = j + 1;
                }
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    fields
}

/// The span `start..end` of `text` without surrounding whitespace and comments' lines.
fn trimmed(text: &str, start: usize, end: usize) -> (usize, usize) {
    let s = &text[start..end];
    let lead = s.len() - s.trim_start().len();
    let trail = s.len() - s.trim_end().len();
    (start + lead, end - trail)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patch_replaces_camera_and_adds_settings() {
        let text =
            "// c\n(\n  camera: (position: (0, 0, 1), look_at: (0, 0, 0)),\n  entities: [],\n)\n";
        let out = patch_fields(text, "(X)", "(Y)").unwrap();
        assert_eq!(
            out,
            "// c\n(\n  camera: (X),\n    settings: (Y),\n  entities: [],\n)\n"
        );
    }

    #[test]
    fn only_a_model_much_wider_than_tall_is_entered() {
        let c = glint::scene::model::framing_camera(Vec3::ZERO, 1.0, 80, 60);
        assert!(interior_camera(Vec3::splat(-1.0), Vec3::ONE, &c).is_none());
        let (min, max) = (Vec3::new(-20.0, 0.0, -8.0), Vec3::new(20.0, 10.0, 8.0));
        let inside = interior_camera(min, max, &c).unwrap();
        for p in [inside.position, inside.look_at] {
            assert!(p.cmpgt(min).all() && p.cmplt(max).all(), "{p}");
        }
        assert_eq!((inside.width, inside.height), (80, 60));
    }

    #[test]
    fn patch_replaces_both_and_skips_strings_and_comments() {
        let text = "(camera: (a: \"x),\"), /* settings: 1 */ settings: (b: 2), materials: {})";
        let out = patch_fields(text, "C", "S").unwrap();
        assert_eq!(
            out,
            "(camera: C, /* settings: 1 */ settings: S, materials: {})"
        );
    }
}
