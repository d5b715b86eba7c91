//! Model files (glTF, OBJ) as scenes: what the importers share, and direct rendering of a
//! model (`glint render model.glb`) with an automatic camera and light when it has none.

use std::collections::BTreeMap;
use std::path::Path;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3};

use super::components::*;
use super::format::{CameraDesc, SceneFile};
use super::load::{MAX_IMAGE_SIDE, SceneSource, validate_camera, validate_settings};
use super::settings::Settings;
use crate::error::{GlintError, Result};
use crate::render::{Overrides, Renderer};

/// Vertical field of view of the automatic camera, in degrees.
pub const AUTO_FOV_Y: f32 = 40.0;
/// Image side used when neither the command line nor the file's camera gives one.
pub const DEFAULT_SIDE: u32 = 512;

/// How an imported file is placed into the world.
#[derive(Clone, Debug)]
pub struct ImportOptions {
    /// Maps the file's coordinates to world space (the RON entity's transform).
    pub world_from_file: Affine3A,
    /// A material that replaces every material of the file.
    pub material: Option<Entity>,
    /// glTF scene index; the file's default scene when `None`.
    pub scene: Option<usize>,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self {
            world_from_file: Affine3A::IDENTITY,
            material: None,
            scene: None,
        }
    }
}

/// A camera found in an imported file (world space).
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedCamera {
    /// The camera's name in the file.
    pub name: String,
    /// Eye position.
    pub position: Vec3,
    /// A point on the view axis.
    pub look_at: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
    /// Width / height, when the file gives it.
    pub aspect_ratio: Option<f32>,
}

/// What an import spawned.
#[derive(Clone, Debug, Default)]
pub struct ImportReport {
    /// Triangles drawn, counting each instance.
    pub triangles: u64,
    /// Triangles stored once per distinct mesh (what instancing by reference keeps in memory).
    pub unique_triangles: u64,
    /// World-space bounds of everything spawned (conservative for rotated instances).
    pub bounds: Option<(Vec3, Vec3)>,
    /// Point lights spawned.
    pub lights: usize,
    /// Perspective cameras found, in file order.
    pub cameras: Vec<ImportedCamera>,
}

impl ImportReport {
    /// Grows the bounds by the object-space box `(lo, hi)` placed by `m`.
    pub fn include_box(&mut self, (lo, hi): (Vec3, Vec3), m: Affine3A) {
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let p = m.transform_point3(corner);
            self.bounds = Some(match self.bounds {
                None => (p, p),
                Some((a, b)) => (a.min(p), b.max(p)),
            });
        }
    }

    /// Centre and radius (half the diagonal) of the bounds; the origin and 0 when empty.
    pub fn centre_radius(&self) -> (Vec3, f32) {
        match self.bounds {
            Some((lo, hi)) => (0.5 * (lo + hi), 0.5 * (hi - lo).length()),
            None => (Vec3::ZERO, 0.0),
        }
    }
}

/// Object-space bounds of a mesh's vertices (zero box when it has none).
pub fn mesh_bounds(m: &MeshData) -> (Vec3, Vec3) {
    let mut it = m.vertices.iter().map(|v| v.position);
    let first = it.next().unwrap_or(Vec3::ZERO);
    it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// Whether `path` names a model file glint imports (by extension).
pub fn is_model_file(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("gltf" | "glb" | "obj")
    )
}

/// Imports a glTF (`.gltf`, `.glb`) or OBJ file into `world`, by extension.
pub fn import_model(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf" | "glb") => super::gltf::import_gltf(world, path, options, warnings),
        Some("obj") => super::obj::import_obj(world, path, options, warnings),
        _ => Err(GlintError::Asset {
            path: path.to_owned(),
            message: "unknown model format (use .gltf, .glb or .obj)".into(),
        }),
    }
}

/// A camera that frames a sphere of `radius` around `centre`, seen from the front,
/// a little from the right and above (+y up, as in glTF).
pub fn framing_camera(centre: Vec3, radius: f32, width: u32, height: u32) -> Camera {
    let aspect = width as f32 / height.max(1) as f32;
    let half_y = (0.5 * AUTO_FOV_Y).to_radians();
    let half_x = (half_y.tan() * aspect).atan();
    let radius = radius.max(1e-6);
    let distance = radius / half_y.min(half_x).sin() * 1.05;
    let dir = Vec3::new(0.35, 0.3, 1.0).normalize();
    Camera {
        position: centre + dir * distance,
        look_at: centre,
        up: Vec3::Y,
        fov_y_degrees: AUTO_FOV_Y,
        width,
        height,
    }
}

impl Renderer {
    /// Renders a model file directly: the file's first perspective camera or an automatic
    /// one framing the bounds, the file's lights or one default point light; the choices
    /// are recorded as notes in [`SceneSource`] for the summary line.
    pub fn from_model(path: &Path, overrides: &Overrides) -> Result<Self> {
        let mut world = World::new();
        let mut warnings = Vec::new();
        let report = import_model(&mut world, path, &ImportOptions::default(), &mut warnings)?;
        let Some(_) = report.bounds else {
            return Err(GlintError::Asset {
                path: path.to_owned(),
                message: "the file has no triangles to render".into(),
            });
        };
        // Apply the command line through the scene-file path, so it behaves the same.
        let mut file = SceneFile {
            camera: CameraDesc {
                position: Vec3::Z,
                look_at: Vec3::ZERO,
                up: Vec3::Y,
                fov_y: AUTO_FOV_Y,
                width: DEFAULT_SIDE,
                height: DEFAULT_SIDE,
            },
            settings: Settings::default(),
            materials: BTreeMap::new(),
            entities: Vec::new(),
        };
        overrides.apply(&mut file)?;
        validate_settings(&file.settings, path)?;
        let mut notes = Vec::new();
        let (centre, radius) = report.centre_radius();
        let width = file.camera.width;
        let camera = match report.cameras.first() {
            Some(c) => {
                let height = match (overrides.height, c.aspect_ratio) {
                    (Some(h), _) => h,
                    (None, Some(a)) => ((width as f32 / a).round() as u32).clamp(1, MAX_IMAGE_SIDE),
                    (None, None) => file.camera.height,
                };
                notes.push(format!("camera: the file's \"{}\"", c.name));
                CameraDesc {
                    position: c.position,
                    look_at: c.look_at,
                    up: c.up,
                    fov_y: c.fov_y_degrees,
                    width,
                    height,
                }
            }
            None => {
                notes.push("camera: automatic, framing the bounds".to_owned());
                let c = framing_camera(centre, radius, width, file.camera.height);
                CameraDesc {
                    position: c.position,
                    look_at: c.look_at,
                    up: c.up,
                    fov_y: c.fov_y_degrees,
                    width: c.width,
                    height: c.height,
                }
            }
        };
        let camera = validate_camera(&camera, path)?;
        if report.lights == 0 {
            // Above and to the left of the eye, so shapes read and shadows fall behind them.
            let eye = camera.position - centre;
            let up_left = Vec3::new(-0.5, 1.0, 0.0) * eye.length();
            let position = centre + (eye + up_left) * 1.2;
            world.spawn((
                Name::new("default light"),
                PointLight {
                    position,
                    color: Vec3::ONE,
                },
            ));
            notes.push("light: one default point light (the file has none)".to_owned());
        } else {
            notes.push(format!("lights: {} from the file", report.lights));
        }
        world.spawn((Name::new("camera"), camera));
        world.insert_resource(file.settings);
        world.insert_resource(SceneSource {
            path: path.to_owned(),
            warnings,
            notes,
        });
        Ok(Renderer::from_world(world))
    }
}
