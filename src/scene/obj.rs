//! Wavefront OBJ/MTL import (the `tobj` crate): each group/material run becomes a mesh
//! entity, each MTL material a material entity (mapping in docs/materials.md).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use super::components::*;
use super::import::{ImportOptions, ImportReport, asset_err, guarded, mesh_bounds};
use super::shapes;
use super::texture::WrapMode;
use crate::error::{AssetError, Result};

/// Finds `name` (relative to `dir`, `\` or `/` separated) as written, or else by a
/// case-insensitive match of each path component (MTL files from Windows tools often
/// differ in letter case from the files they name).
pub fn find_file_case_insensitive(dir: &Path, name: &str) -> Option<PathBuf> {
    let name = name.trim().replace('\\', "/");
    let exact = dir.join(&name);
    if exact.is_file() {
        return Some(exact);
    }
    let mut current = dir.to_owned();
    for part in name.split('/').filter(|p| !p.is_empty()) {
        let candidate = current.join(part);
        if candidate.exists() {
            current = candidate;
            continue;
        }
        let lower = part.to_lowercase();
        let found = std::fs::read_dir(&current)
            .ok()?
            .filter_map(|e| e.ok())
            .find(|e| e.file_name().to_string_lossy().to_lowercase() == lower)?;
        current = found.path();
    }
    current.is_file().then_some(current)
}

/// Loads an OBJ file (and its MTL files) and spawns its meshes and materials into `world`;
/// a panic inside `tobj` on a malformed file becomes an error naming the file.
pub fn import_obj(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    guarded(path, "OBJ", || {
        import_obj_unguarded(world, path, options, warnings)
    })
}

fn import_obj_unguarded(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    let load = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &load).map_err(|e| asset_err(path, e))?;
    let materials = materials.unwrap_or_else(|e| {
        warnings.push(format!(
            "{}: material library not loaded ({e}); using a default material",
            path.display()
        ));
        Vec::new()
    });
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut entities: HashMap<Option<usize>, Entity> = HashMap::new();
    let mut emissive = Vec::new();
    let mut report = ImportReport::default();
    for (index, model) in models.iter().enumerate() {
        let mesh = &model.mesh;
        if mesh.indices.is_empty() {
            continue;
        }
        let label = if model.name.is_empty() {
            format!("object {index}")
        } else {
            format!("\"{}\"", model.name)
        };
        let data = mesh_data(mesh).map_err(|problem| {
            asset_err(
                path,
                AssetError::Invalid {
                    item: label.clone(),
                    problem,
                },
            )
        })?;
        let material = match options.material {
            Some(e) => e,
            None => {
                let id = mesh.material_id.filter(|&i| i < materials.len());
                match entities.get(&id) {
                    Some(&e) => e,
                    None => {
                        let m = match id {
                            Some(i) => {
                                let mtl = &materials[i];
                                if mtl.emissive.is_some_and(|k| k.iter().any(|&c| c > 0.0)) {
                                    emissive.push(format!("\"{}\"", mtl.name));
                                }
                                material(mtl, dir, path, warnings)
                            }
                            None => Material::default(),
                        };
                        let e = world.spawn((Name::new(m.name.clone()), m)).id();
                        entities.insert(id, e);
                        e
                    }
                }
            }
        };
        report.triangles += data.triangles.len() as u64;
        report.include_box(mesh_bounds(&data), options.world_from_file);
        world.spawn((
            Name::new(format!("{}/{label}", path.display())),
            Mesh {
                data: Arc::new(data),
            },
            Transform {
                world_from_object: options.world_from_file,
            },
            MaterialRef(material),
        ));
    }
    report.unique_triangles = report.triangles;
    if !emissive.is_empty() {
        warnings.push(format!(
            "{}: emissive material(s) {} imported without emission (glint surfaces do not emit; add a light)",
            path.display(),
            emissive.join(", ")
        ));
    }
    Ok(report)
}

fn mesh_data(mesh: &tobj::Mesh) -> std::result::Result<MeshData, String> {
    let n = mesh.positions.len() / 3;
    let positions: Vec<Vec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {bad} is not finite"));
    }
    if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} out of range ({n} vertices)"));
    }
    let triangles: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let derived = shapes::smooth_normals(&positions, &triangles);
    let has_normals = mesh.normals.len() == 3 * n;
    let has_uv = mesh.texcoords.len() == 2 * n;
    let vertices = (0..n)
        .map(|i| Vertex {
            position: positions[i],
            normal: if has_normals {
                Vec3::from_slice(&mesh.normals[3 * i..3 * i + 3])
                    .try_normalize()
                    .unwrap_or(derived[i])
            } else {
                derived[i]
            },
            // OBJ's v already runs up the image, as glint's does.
            texcoord: if has_uv {
                Vec2::from_slice(&mesh.texcoords[2 * i..2 * i + 2])
            } else {
                Vec2::ZERO
            },
        })
        .collect();
    Ok(MeshData {
        vertices,
        triangles,
    })
}

fn material(mtl: &tobj::Material, dir: &Path, path: &Path, warnings: &mut Vec<String>) -> Material {
    let colour = |c: Option<[f32; 3]>, default: Vec3| {
        c.map(Vec3::from_array)
            .filter(|v| v.is_finite())
            .map_or(default, |v| v.max(Vec3::ZERO))
    };
    // `d` is alpha; some exporters write only `Tr` (= 1 - d).
    let tr = mtl
        .unknown_param
        .get("Tr")
        .and_then(|s| s.trim().parse::<f32>().ok())
        .map(|t| 1.0 - t);
    let alpha = mtl.dissolve.or(tr).filter(|a| a.is_finite()).unwrap_or(1.0);
    let kd_texture = mtl.diffuse_texture.as_deref().and_then(|name| {
        // Options such as `-s 1 1 1` come before the file name; the name is the last word.
        let file = name.split_whitespace().last().unwrap_or(name);
        match find_file_case_insensitive(dir, file) {
            Some(p) => Some(TextureSource::File(p)),
            None => {
                warnings.push(format!(
                    "{}: material \"{}\": texture {file} not found; using Kd",
                    path.display(),
                    mtl.name
                ));
                None
            }
        }
    });
    Material {
        name: mtl.name.clone(),
        kd: colour(mtl.diffuse, Vec3::splat(0.8)),
        ks: colour(mtl.specular, Vec3::ZERO),
        shininess: mtl
            .shininess
            .filter(|s| s.is_finite() && *s >= 0.0)
            .unwrap_or(1.0),
        alpha: alpha.clamp(0.0, 1.0),
        kd_texture,
        wrap: [WrapMode::Repeat; 2],
    }
}
