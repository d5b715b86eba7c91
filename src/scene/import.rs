//! What the importers (glTF, OBJ) share: how a file is placed into the world, what an
//! import reports, and the one constructor of their errors.

use std::path::Path;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec3};

use super::components::MeshData;
use crate::error::{AssetError, GlintError, Result};

/// The error for what is wrong with the asset file at `path`.
pub fn asset_err(path: &Path, error: impl Into<AssetError>) -> GlintError {
    GlintError::Asset {
        path: path.to_owned(),
        source: error.into(),
    }
}

thread_local! {
    /// Whether a panic on this thread is expected and caught by [`guarded`].
    static QUIET_PANICS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Wraps the process's panic hook, once, so that it stays silent on a thread
/// inside [`guarded`] and behaves as before everywhere else.
fn install_quiet_hook() {
    static INSTALL: std::sync::Once = std::sync::Once::new();
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET_PANICS.get() {
                previous(info);
            }
        }));
    });
}

/// Runs an importer behind a guard: the `gltf` and `tobj` crates panic on some malformed
/// files (an attribute naming an accessor that does not exist, an MTL colour with two
/// components), and such a panic becomes an error naming the file instead of aborting.
pub fn guarded<T>(
    path: &Path,
    format: &'static str,
    import: impl FnOnce() -> Result<T>,
) -> Result<T> {
    // The hook would print the dependency's panic before our error line. It is
    // silenced for this thread only: swapping the process-wide hook per import would
    // race with imports (or panics) on other threads.
    install_quiet_hook();
    let was_quiet = QUIET_PANICS.replace(true);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(import));
    QUIET_PANICS.set(was_quiet);
    result.unwrap_or_else(|panic| {
        let why = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown error".into());
        Err(asset_err(path, AssetError::Malformed { format, why }))
    })
}

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
