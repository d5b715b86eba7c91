//! Validation of what a scene file says: every number finite and in range, every file
//! there, with errors naming the file, the entity and the field.

use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3};

use super::components::*;
use super::format::*;
use super::load::{MAX_DEPTH_LIMIT, MAX_IMAGE_SIDE, MAX_SAMPLES};
use super::settings::Settings;
use crate::error::{GlintError, Result};

/// Validation context: the file and the entity being checked.
pub(super) struct Check<'a> {
    /// The scene file.
    pub(super) path: &'a Path,
    /// The entity being checked, as messages name it.
    pub(super) entity: String,
}

impl Check<'_> {
    pub(super) fn err(&self, field: &str, message: impl Into<String>) -> GlintError {
        GlintError::Invalid {
            path: self.path.to_owned(),
            entity: self.entity.clone(),
            field: field.to_owned(),
            message: message.into(),
        }
    }

    pub(super) fn finite(&self, field: &str, v: Vec3) -> Result<Vec3> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(field, format!("must be finite, got {v}")))
        }
    }

    pub(super) fn colour(&self, field: &str, v: Vec3) -> Result<Vec3> {
        self.finite(field, v)?;
        if v.min_element() < 0.0 {
            return Err(self.err(field, format!("colour must not be negative, got {v}")));
        }
        Ok(v)
    }

    pub(super) fn scalar(&self, field: &str, v: f32, lo: f32, hi: f32) -> Result<f32> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(self.err(field, format!("must be in [{lo}, {hi}], got {v}")))
        }
    }
}

/// Checks the settings' numeric fields.
pub fn validate_settings(s: &Settings, path: &Path) -> Result<()> {
    let c = Check {
        path,
        entity: "settings".into(),
    };
    for (field, g) in [
        ("gradient", &s.gradient),
        ("comparison_gradient", &s.comparison_gradient),
    ] {
        if g.components().is_empty() {
            return Err(c.err(field, "a gradient needs at least one component"));
        }
        for &(t, col) in g.components() {
            c.scalar(field, t, f32::MIN, f32::MAX)?;
            c.colour(field, col)?;
        }
    }
    for (field, v) in [
        ("pixel_samples", s.pixel_samples),
        ("shadow_samples", s.shadow_samples),
    ] {
        if v == 0 || v > MAX_SAMPLES {
            return Err(c.err(field, format!("must be in [1, {MAX_SAMPLES}], got {v}")));
        }
    }
    if s.max_depth > MAX_DEPTH_LIMIT {
        return Err(c.err(
            "max_depth",
            format!("must be at most {MAX_DEPTH_LIMIT}, got {}", s.max_depth),
        ));
    }
    c.colour("background", s.background)?;
    Ok(())
}

/// Checks the camera and converts it to the component.
pub fn validate_camera(d: &CameraDesc, path: &Path) -> Result<Camera> {
    let c = Check {
        path,
        entity: "camera".into(),
    };
    let position = c.finite("position", d.position)?;
    let look_at = c.finite("look_at", d.look_at)?;
    let up = c.finite("up", d.up)?;
    let forward = (look_at - position)
        .try_normalize()
        .ok_or_else(|| c.err("look_at", "must differ from position"))?;
    let up_n = up
        .try_normalize()
        .ok_or_else(|| c.err("up", "must not be zero"))?;
    if forward.cross(up_n).length() < 1e-6 {
        return Err(c.err("up", "must not be parallel to the view direction"));
    }
    let fov = d.fov_y;
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        return Err(c.err("fov_y", format!("must be in (0, 180) degrees, got {fov}")));
    }
    for (field, v) in [("width", d.width), ("height", d.height)] {
        if v == 0 || v > MAX_IMAGE_SIDE {
            return Err(c.err(field, format!("must be in [1, {MAX_IMAGE_SIDE}], got {v}")));
        }
    }
    Ok(Camera {
        position,
        look_at,
        up,
        fov_y_degrees: fov,
        width: d.width,
        height: d.height,
    })
}

/// `file` if it is a file; else an error naming the entity and `field` (a model's own
/// read error would name only the missing file).
pub(super) fn existing_file(c: &Check, field: &str, file: PathBuf) -> Result<PathBuf> {
    if file.is_file() {
        Ok(file)
    } else {
        Err(c.err(field, format!("file not found: {}", file.display())))
    }
}

pub(super) fn validate_material(name: &str, d: &MaterialDesc, path: &Path) -> Result<Material> {
    let c = Check {
        path,
        entity: format!("material \"{name}\""),
    };
    let kd_texture = match &d.kd_texture {
        None => None,
        Some(file) => {
            let resolved = resolve(path, file);
            if resolved.is_dir() {
                return Err(c.err(
                    "kd_texture",
                    format!("{} is a folder, not an image file", resolved.display()),
                ));
            }
            if !resolved.is_file() {
                return Err(c.err(
                    "kd_texture",
                    format!("file not found: {}", resolved.display()),
                ));
            }
            if image::ImageFormat::from_path(&resolved).is_err() {
                return Err(c.err(
                    "kd_texture",
                    format!(
                        "{} is not an image glint reads (use .png, .jpg or .exr)",
                        resolved.display()
                    ),
                ));
            }
            Some(TextureSource::File(resolved))
        }
    };
    Ok(Material {
        name: name.to_owned(),
        kd: c.colour("kd", d.kd)?,
        ks: c.colour("ks", d.ks)?,
        shininess: c.scalar("shininess", d.shininess, 0.0, f32::MAX)?,
        alpha: c.scalar("transparency", d.alpha, 0.0, 1.0)?,
        kd_texture,
        wrap: [d.wrap.0, d.wrap.1],
    })
}

/// A path in a scene file, relative to the scene file's folder.
pub fn resolve(scene: &Path, file: &str) -> PathBuf {
    scene.parent().unwrap_or(Path::new(".")).join(file)
}

pub(super) fn validate_transform(c: &Check, d: &TransformDesc) -> Result<Transform> {
    let translate = c.finite("transform.translate", d.translate)?;
    let rotate = c.finite("transform.rotate_degrees", d.rotate_degrees)?;
    let scale = c.finite("transform.scale", d.scale)?;
    if scale.abs().min_element() == 0.0 {
        return Err(c.err("transform.scale", "must not be zero along any axis"));
    }
    let rotation = Quat::from_euler(
        EulerRot::ZYX,
        rotate.z.to_radians(),
        rotate.y.to_radians(),
        rotate.x.to_radians(),
    );
    Ok(Transform {
        world_from_object: Affine3A::from_scale_rotation_translation(scale, rotation, translate),
    })
}
