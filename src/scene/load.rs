//! Reads a RON scene, validates every value, and spawns it into a `World`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::components::*;
use super::format::*;
use super::gltf::import_gltf;
use super::import::ImportOptions;
use super::obj::import_obj;
use super::shapes;
use super::validate::{Check, existing_file, validate_material, validate_transform};
pub use super::validate::{resolve, validate_camera, validate_settings};
use crate::error::{AssetError, GlintError, Result};
use crate::memory;

/// Largest accepted image side, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 32768;
/// Largest accepted ray depth.
pub const MAX_DEPTH_LIMIT: u32 = 1024;
/// Largest accepted sample counts (per pixel and per area light).
pub const MAX_SAMPLES: u32 = 1 << 16;

/// The scene file a world was loaded from, for resolving relative paths and for messages.
#[derive(Resource, Clone, Debug, Default)]
pub struct SceneSource {
    /// The scene file.
    pub path: PathBuf,
    /// Non-fatal problems found while loading (each already repaired).
    pub warnings: Vec<String>,
    /// Choices the loader made for the user (e.g. an automatic camera), for the summary line.
    pub notes: Vec<String>,
}

/// Reads and parses a scene file (no validation yet).
pub fn read_scene(path: &Path) -> Result<SceneFile> {
    let ext = path.extension().and_then(|e| e.to_str());
    if ext.is_some_and(|e| !e.eq_ignore_ascii_case("ron")) {
        return Err(GlintError::Asset {
            path: path.to_owned(),
            source: AssetError::UnknownFormat,
        });
    }
    let text = std::fs::read_to_string(path).map_err(|source| GlintError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_scene(&text, path)
}

/// Parses scene text; `path` is only used in messages.
pub fn parse_scene(text: &str, path: &Path) -> Result<SceneFile> {
    ron::Options::default()
        .from_str(text)
        .map_err(|e: ron::error::SpannedError| GlintError::Syntax {
            path: path.to_owned(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })
}

fn inline_mesh(
    c: &Check,
    vertices: &[VertexDesc],
    triangles: &[[u32; 3]],
    warnings: &mut Vec<String>,
) -> Result<MeshData> {
    for (i, v) in vertices.iter().enumerate() {
        c.finite(&format!("vertices[{i}].position"), v.position)?;
        if !v.texcoord.is_finite() {
            return Err(c.err(
                &format!("vertices[{i}].texcoord"),
                format!("must be finite, got {}", v.texcoord),
            ));
        }
        if let Some(n) = v.normal {
            c.finite(&format!("vertices[{i}].normal"), n)?;
        }
    }
    for (i, t) in triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&k| k as usize >= vertices.len()) {
            return Err(c.err(
                &format!("triangles[{i}]"),
                format!(
                    "vertex index {bad} out of range ({} vertices)",
                    vertices.len()
                ),
            ));
        }
    }
    let positions: Vec<Vec3> = vertices.iter().map(|v| v.position).collect();
    let derived = shapes::smooth_normals(&positions, triangles);
    let mut repaired = 0;
    let vertices = vertices
        .iter()
        .zip(derived)
        .map(|(v, derived)| {
            let normal = match v.normal {
                None => derived,
                Some(n) => n.try_normalize().unwrap_or_else(|| {
                    repaired += 1;
                    derived
                }),
            };
            Vertex {
                position: v.position,
                normal,
                texcoord: v.texcoord,
            }
        })
        .collect();
    if repaired > 0 {
        warnings.push(format!(
            "{}: {}: {repaired} zero-length normal(s) replaced by normals derived from the triangles",
            c.path.display(),
            c.entity
        ));
    }
    Ok(MeshData {
        vertices,
        triangles: triangles.to_vec(),
    })
}

fn shape_mesh(c: &Check, g: &GeometryDesc, warnings: &mut Vec<String>) -> Result<MeshData> {
    let positive = |field: &str, v: u32, max: u32| {
        if v == 0 || v > max {
            Err(c.err(field, format!("must be in [1, {max}], got {v}")))
        } else {
            Ok(v)
        }
    };
    Ok(match g {
        GeometryDesc::Inline {
            vertices,
            triangles,
        } => inline_mesh(c, vertices, triangles, warnings)?,
        GeometryDesc::Quad => shapes::quad(),
        GeometryDesc::Parallelogram {
            origin,
            edge_u,
            edge_v,
        } => {
            c.finite("geometry.origin", *origin)?;
            c.finite("geometry.edge_u", *edge_u)?;
            c.finite("geometry.edge_v", *edge_v)?;
            if edge_u.cross(*edge_v).length() == 0.0 {
                return Err(c.err("geometry", "edges must not be parallel or zero"));
            }
            shapes::parallelogram(*origin, *edge_u, *edge_v)
        }
        GeometryDesc::Cube => shapes::cube(),
        GeometryDesc::Plane { subdivisions } => {
            let n = positive("geometry.subdivisions", *subdivisions, 4096)? as u64;
            ensure_mesh_fits(c, (n + 1) * (n + 1), 2 * n * n)?;
            shapes::plane(n as u32)
        }
        GeometryDesc::UvSphere { segments, rings } => {
            let segments = positive("geometry.segments", *segments, 1 << 14)?.max(3);
            let rings = positive("geometry.rings", *rings, 1 << 14)?.max(2);
            let (s, r) = (segments as u64, rings as u64);
            ensure_mesh_fits(c, (s + 1) * (r + 1), 2 * s * r)?;
            shapes::uv_sphere(segments, rings)
        }
        GeometryDesc::Icosphere { subdivisions } => {
            if *subdivisions > 9 {
                return Err(c.err(
                    "geometry.subdivisions",
                    format!("must be at most 9, got {subdivisions}"),
                ));
            }
            shapes::icosphere(*subdivisions)
        }
        GeometryDesc::Gltf { .. } | GeometryDesc::Obj { .. } => unreachable!("handled by caller"),
    })
}

/// Refuses a generated shape the machine could not hold once prepared for rendering.
fn ensure_mesh_fits(c: &Check, vertices: u64, triangles: u64) -> Result<()> {
    let bytes = vertices * memory::BYTES_PER_VERTEX
        + triangles * (memory::BYTES_PER_TRIANGLE + memory::BYTES_PER_PREPARED_TRIANGLE);
    memory::ensure_fits(&[(format!("{triangles} triangles"), bytes)])
        .map_err(|e| c.err("geometry", e.to_string()))
}

/// Rejects a mesh whose vertices overflow f32 once placed in the world (finite in the
/// file, infinite after the transform).
fn check_world_positions(c: &Check, data: &MeshData, transform: &Transform) -> Result<()> {
    let m = transform.world_from_object;
    match data
        .vertices
        .iter()
        .position(|v| !m.transform_point3(v.position).is_finite())
    {
        Some(i) => Err(c.err(
            &format!("vertices[{i}].position"),
            format!(
                "{} overflows f32 after the transform",
                data.vertices[i].position
            ),
        )),
        None => Ok(()),
    }
}

fn entity_label(kind: &str, index: usize, name: &Option<String>) -> String {
    match name {
        Some(n) => format!("entities[{index}] ({kind} \"{n}\")"),
        None => format!("entities[{index}] ({kind})"),
    }
}

/// Validates a parsed scene and spawns it: materials, camera, geometry and lights become
/// entities, the settings a resource. On error nothing is left half-spawned in a way
/// that matters: the caller discards the world.
pub fn spawn_scene(world: &mut World, file: &SceneFile, path: &Path) -> Result<()> {
    validate_settings(&file.settings, path)?;
    let camera = validate_camera(&file.camera, path)?;
    let mut spawner = Spawner {
        path,
        materials: spawn_materials(world, file, path)?,
        warnings: Vec::new(),
    };
    world.spawn((Name::new("camera"), camera));
    for (index, entity) in file.entities.iter().enumerate() {
        match entity {
            EntityDesc::Mesh(d) => spawner.spawn_mesh(world, index, d)?,
            EntityDesc::Sphere(d) => spawner.spawn_sphere(world, index, d)?,
            EntityDesc::PointLight(d) => {
                spawner.spawn_light(world, "PointLight", index, &d.name, |c| {
                    Ok(PointLight {
                        position: c.finite("position", d.position)?,
                        color: c.colour("color", d.color)?,
                    })
                })?
            }
            EntityDesc::SegmentLight(d) => {
                spawner.spawn_light(world, "SegmentLight", index, &d.name, |c| {
                    Ok(SegmentLight {
                        endpoint0: c.finite("endpoint0", d.endpoint0)?,
                        endpoint1: c.finite("endpoint1", d.endpoint1)?,
                        color0: c.colour("color0", d.color0)?,
                        color1: c.colour("color1", d.color1)?,
                    })
                })?
            }
            EntityDesc::ParallelogramLight(d) => {
                spawner.spawn_light(world, "ParallelogramLight", index, &d.name, |c| {
                    Ok(ParallelogramLight {
                        v0: c.finite("v0", d.v0)?,
                        edge01: c.finite("edge01", d.edge01)?,
                        edge02: c.finite("edge02", d.edge02)?,
                        color0: c.colour("color0", d.color0)?,
                        color1: c.colour("color1", d.color1)?,
                        color2: c.colour("color2", d.color2)?,
                        color3: c.colour("color3", d.color3)?,
                    })
                })?
            }
        }
    }
    let has = |light: bool| {
        file.entities.iter().any(|e| {
            let is_light = !matches!(e, EntityDesc::Mesh(_) | EntityDesc::Sphere(_));
            is_light == light
        })
    };
    if !has(false) {
        spawner.warnings.push(format!(
            "{}: the scene has no geometry: the image will be the background",
            path.display()
        ));
    } else if !has(true) && file.settings.shading {
        spawner.warnings.push(format!(
            "{}: the scene has no lights: every surface will render black",
            path.display()
        ));
    }
    world.insert_resource(file.settings.clone());
    world.insert_resource(SceneSource {
        path: path.to_owned(),
        warnings: spawner.warnings,
        notes: Vec::new(),
    });
    Ok(())
}

/// Spawns one entity per material, in name order; the map finds them by name.
fn spawn_materials<'f>(
    world: &mut World,
    file: &'f SceneFile,
    path: &Path,
) -> Result<HashMap<&'f str, Entity>> {
    let mut materials = HashMap::new();
    for (name, desc) in &file.materials {
        let m = validate_material(name, desc, path)?;
        let e = world.spawn((Name::new(name.clone()), m)).id();
        materials.insert(name.as_str(), e);
    }
    Ok(materials)
}

/// What spawning the scene's entities needs: the file, its materials by name, and the
/// warnings collected so far.
struct Spawner<'a> {
    path: &'a Path,
    materials: HashMap<&'a str, Entity>,
    warnings: Vec<String>,
}

impl<'a> Spawner<'a> {
    /// The validation context of entity `index` of `kind`.
    fn check(&self, kind: &str, index: usize, name: &Option<String>) -> Check<'a> {
        Check {
            path: self.path,
            entity: entity_label(kind, index, name),
        }
    }

    /// The material entity `name` refers to; an entity must name one.
    fn material_ref(&self, c: &Check, name: &Option<String>) -> Result<MaterialRef> {
        let name = name
            .as_deref()
            .ok_or_else(|| c.err("material", "missing"))?;
        self.materials
            .get(name)
            .map(|&e| MaterialRef(e))
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.keys().copied().collect();
                c.err(
                    "material",
                    format!(
                        "unknown material \"{name}\" (defined: {})",
                        known.join(", ")
                    ),
                )
            })
    }

    /// The material that replaces an imported model's own: none unless the entity names one.
    fn import_material(&self, c: &Check, name: &Option<String>) -> Result<Option<Entity>> {
        match name {
            None => Ok(None),
            Some(_) => self.material_ref(c, name).map(|m| Some(m.0)),
        }
    }

    /// A mesh: a built-in shape or inline triangles become one entity; a glTF or OBJ file
    /// is imported with the entity's transform.
    fn spawn_mesh(&mut self, world: &mut World, index: usize, d: &MeshDesc) -> Result<()> {
        let c = self.check("Mesh", index, &d.name);
        let transform = validate_transform(&c, &d.transform)?;
        let path = self.path;
        match &d.geometry {
            GeometryDesc::Gltf { path: file, scene } => {
                let options = ImportOptions {
                    world_from_file: transform.world_from_object,
                    material: self.import_material(&c, &d.material)?,
                    scene: *scene,
                };
                let file = existing_file(&c, "geometry", resolve(path, file))?;
                import_gltf(world, &file, &options, &mut self.warnings)?;
            }
            GeometryDesc::Obj { path: file } => {
                let options = ImportOptions {
                    world_from_file: transform.world_from_object,
                    material: self.import_material(&c, &d.material)?,
                    scene: None,
                };
                let file = existing_file(&c, "geometry", resolve(path, file))?;
                import_obj(world, &file, &options, &mut self.warnings)?;
            }
            g => {
                let data = shape_mesh(&c, g, &mut self.warnings)?;
                check_world_positions(&c, &data, &transform)?;
                let material = self.material_ref(&c, &d.material)?;
                world.spawn((
                    Name::new(d.name.clone().unwrap_or_else(|| format!("mesh {index}"))),
                    Mesh {
                        data: Arc::new(data),
                    },
                    transform,
                    material,
                ));
            }
        }
        Ok(())
    }

    fn spawn_sphere(&self, world: &mut World, index: usize, d: &SphereDesc) -> Result<()> {
        let c = self.check("Sphere", index, &d.name);
        let center = c.finite("center", d.center)?;
        if !(d.radius.is_finite() && d.radius > 0.0) {
            return Err(c.err(
                "radius",
                format!("must be positive and finite, got {}", d.radius),
            ));
        }
        // The intersection test squares the radius: it must stay a normal f32.
        if !(d.radius * d.radius).is_normal() {
            return Err(c.err(
                "radius",
                format!(
                    "{} is out of range: its square over- or underflows f32 (use 1e-18 .. 1e18)",
                    d.radius
                ),
            ));
        }
        let material = self.material_ref(&c, &Some(d.material.clone()))?;
        world.spawn((
            Name::new(d.name.clone().unwrap_or_else(|| format!("sphere {index}"))),
            Sphere {
                center,
                radius: d.radius,
            },
            material,
        ));
        Ok(())
    }

    /// A light of any kind: `light` validates its fields against the entity's label.
    fn spawn_light<L: Component>(
        &self,
        world: &mut World,
        kind: &str,
        index: usize,
        name: &Option<String>,
        light: impl FnOnce(&Check) -> Result<L>,
    ) -> Result<()> {
        let light = light(&self.check(kind, index, name))?;
        world.spawn((
            Name::new(name.clone().unwrap_or_else(|| format!("light {index}"))),
            light,
        ));
        Ok(())
    }
}
