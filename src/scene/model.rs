//! Model files (glTF, OBJ) as scenes: which file is which format, importing a model into
//! a world, and a whole scene from a model alone (`glint render model.glb`) with an
//! automatic camera and light when it has none.

use std::collections::BTreeMap;
use std::path::Path;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::components::*;
use super::format::{CameraDesc, SceneFile};
use super::gltf::import_gltf;
use super::import::asset_err;
use super::load::{MAX_IMAGE_SIDE, SceneSource, validate_camera, validate_settings};
use super::obj::import_obj;
use super::overrides::Overrides;
use super::settings::Settings;
use crate::error::{AssetError, GlintError, Result};

// The importers' options and report, also reachable here, where models are imported.
pub use super::import::{ImportOptions, ImportReport};

/// Vertical field of view of the automatic camera, in degrees.
pub const AUTO_FOV_Y: f32 = 40.0;
/// Image side used when neither the command line nor the file's camera gives one.
pub const DEFAULT_SIDE: u32 = 512;

/// The kinds of file glint opens as a scene, told apart by extension (the one place that
/// looks at it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// A RON scene file: any extension not listed below.
    Ron,
    /// glTF 2.0: `.gltf` or `.glb`.
    Gltf,
    /// Wavefront OBJ: `.obj`.
    Obj,
}

impl SceneFormat {
    /// The format of `path`, by its extension (case-insensitive).
    pub fn of(path: &Path) -> SceneFormat {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("gltf" | "glb") => SceneFormat::Gltf,
            Some("obj") => SceneFormat::Obj,
            _ => SceneFormat::Ron,
        }
    }
}

/// Imports a glTF (`.gltf`, `.glb`) or OBJ file into `world`, by extension.
pub fn import_model(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    match SceneFormat::of(path) {
        SceneFormat::Gltf => import_gltf(world, path, options, warnings),
        SceneFormat::Obj => import_obj(world, path, options, warnings),
        SceneFormat::Ron => Err(asset_err(path, AssetError::UnknownFormat)),
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

/// The name of the point light added to a model that has none.
pub const DEFAULT_LIGHT_NAME: &str = "default light";

/// Spawns a model file as a whole scene: the file's first perspective camera or an
/// automatic one framing the bounds, the file's lights or one default point light; the
/// choices are recorded as notes in [`SceneSource`] for the summary line.
pub fn spawn_model(world: &mut World, path: &Path, overrides: &Overrides) -> Result<()> {
    let mut warnings = Vec::new();
    let report = import_model(world, path, &ImportOptions::default(), &mut warnings)?;
    let Some(_) = report.bounds else {
        return Err(asset_err(path, AssetError::NoTriangles));
    };
    // Apply the overrides through the scene-file path, so they behave the same.
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
            if !c.position.is_finite() {
                return Err(too_large_to_frame(path, &report, "an automatic camera"));
            }
            CameraDesc::from(&c)
        }
    };
    let camera = validate_camera(&camera, path)?;
    if report.lights == 0 {
        // Above and to the left of the eye, so shapes read and shadows fall behind them.
        let eye = camera.position - centre;
        let up_left = Vec3::new(-0.5, 1.0, 0.0) * eye.length();
        let position = centre + (eye + up_left) * 1.2;
        if !position.is_finite() {
            return Err(too_large_to_frame(path, &report, "a default light"));
        }
        world.spawn((
            Name::new(DEFAULT_LIGHT_NAME),
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
    Ok(())
}

/// The error for a model whose bounds overflow f32 once a camera or light is placed
/// around them (coordinates near ±3e38 are finite, their distances are not).
fn too_large_to_frame(path: &Path, report: &ImportReport, what: &str) -> GlintError {
    let (lo, hi) = report.bounds.unwrap_or_default();
    asset_err(
        path,
        AssetError::Invalid {
            item: "bounds".to_owned(),
            problem: format!(
                "the model spans {lo} to {hi}, too far to place {what} around it \
                 (coordinates must stay within about ±1e37)"
            ),
        },
    )
}
