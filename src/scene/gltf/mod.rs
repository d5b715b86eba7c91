//! glTF 2.0 import (the `gltf` crate): nodes, meshes, materials, cameras and
//! KHR_lights_punctual lights become glint entities. The material mapping is documented
//! in docs/materials.md.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Mat4, Vec2, Vec3};
use gltf::khr_lights_punctual::Kind as LightKind;
use gltf::mesh::Mode;

use super::components::*;
use super::import::{ImportOptions, ImportReport, ImportedCamera, asset_err, guarded, mesh_bounds};
use super::shapes;
use super::texture::Texture;
use crate::error::{AssetError, GlintError, Result};

mod material;

pub use material::{DIELECTRIC_F0, MAX_SHININESS, metallic_roughness_to_phong};

/// Required extensions glint understands; any other in `extensionsRequired` is refused.
pub const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 3] = [
    "KHR_texture_transform",
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
];

/// Irradiance-equivalent colour of a punctual light of `intensity` (candela) seen from
/// `distance`: glint lights have no fall-off, so the inverse-square law is applied once,
/// at the centre of the imported model.
pub fn point_light_colour(color: Vec3, intensity: f32, distance: f32) -> Vec3 {
    color * intensity / (distance * distance).max(1e-12)
}

/// Import state: the document, its buffers and the caches that make instancing share data.
struct Importer<'a> {
    path: &'a Path,
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    options: &'a ImportOptions,
    /// Geometry per (mesh, primitive, mirrored): every node that instances it shares it.
    meshes: HashMap<(usize, usize, bool), Arc<MeshData>>,
    /// Object-space bounds per cached mesh.
    mesh_bounds: HashMap<(usize, usize, bool), (Vec3, Vec3)>,
    /// Every distinct geometry read, by a hash of its contents: primitives of different
    /// meshes that read the same accessors (the same sphere in 98 materials) share one.
    by_content: HashMap<u64, Vec<Arc<MeshData>>>,
    /// Material entity per glTF material index (`None` = the glTF default material).
    materials: HashMap<Option<usize>, Entity>,
    /// Decoded base-colour textures per (image, kd scale bits).
    textures: HashMap<(usize, [u32; 3]), Arc<Texture>>,
    warned_modes: Vec<usize>,
    warned_colors: bool,
    emissive: Vec<String>,
    lights: Vec<(gltf::khr_lights_punctual::Light<'a>, Affine3A)>,
    report: ImportReport,
}

/// Deepest nesting of nodes accepted; real files nest a few dozen levels at most.
const MAX_NODE_DEPTH: usize = 1024;

/// Loads a glTF 2.0 file (`.gltf`, `.glb`, embedded) and spawns its scene into `world`.
///
/// A panic inside the `gltf` crate on a malformed file becomes an error naming the file
/// (see [`guarded`]).
pub fn import_gltf(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    guarded(path, "glTF", || {
        import_gltf_unguarded(world, path, options, warnings)
    })
}

fn import_gltf_unguarded(
    world: &mut World,
    path: &Path,
    options: &ImportOptions,
    warnings: &mut Vec<String>,
) -> Result<ImportReport> {
    let bytes = std::fs::read(path).map_err(|source| GlintError::Io {
        path: path.to_owned(),
        source,
    })?;
    // Check the required extensions first: the crate's own refusal does not name them.
    let unvalidated =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| asset_err(path, e))?;
    for ext in unvalidated.extensions_required() {
        if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext) {
            return Err(asset_err(
                path,
                AssetError::UnsupportedExtension(ext.to_owned()),
            ));
        }
    }
    drop(unvalidated);
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(&bytes).map_err(|e| asset_err(path, e))?;
    drop(bytes);
    let base = path.parent().unwrap_or(Path::new("."));
    // The crate's own error for a missing buffer file names neither the buffer nor the file.
    for buffer in document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source()
            && !uri.starts_with("data:")
            // Percent-encoded names are left to the crate, which decodes them.
            && !uri.contains('%')
            && !base.join(uri).is_file()
        {
            return Err(asset_err(
                path,
                AssetError::Invalid {
                    item: format!("buffer {}", buffer.index()),
                    problem: format!("file not found: {}", base.join(uri).display()),
                },
            ));
        }
    }
    let buffers = gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| asset_err(path, AssetError::GltfBuffer(e)))?;

    let scene = match options.scene {
        Some(index) => document.scenes().nth(index).ok_or_else(|| {
            asset_err(
                path,
                AssetError::NoSuchScene {
                    index,
                    count: document.scenes().len(),
                },
            )
        })?,
        None => match document
            .default_scene()
            .or_else(|| document.scenes().next())
        {
            Some(s) => s,
            None => return Err(asset_err(path, AssetError::NoScene)),
        },
    };

    let mut imp = Importer {
        path,
        document: &document,
        buffers: &buffers,
        options,
        meshes: HashMap::new(),
        mesh_bounds: HashMap::new(),
        by_content: HashMap::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        warned_modes: Vec::new(),
        warned_colors: false,
        emissive: Vec::new(),
        lights: Vec::new(),
        report: ImportReport::default(),
    };
    imp.visit_scene(world, scene.nodes(), warnings)?;
    imp.spawn_lights(world, warnings);
    if !imp.emissive.is_empty() {
        warnings.push(format!(
            "{}: emissive material(s) {} imported without emission (glint surfaces do not emit; add a light)",
            path.display(),
            imp.emissive.join(", ")
        ));
    }
    let mut report = imp.report;
    report.unique_triangles = imp
        .meshes
        .iter()
        .filter(|((_, _, mirrored), _)| !mirrored)
        .map(|(_, m)| m.triangles.len() as u64)
        .sum();
    Ok(report)
}

impl<'a> Importer<'a> {
    /// Walks the scene's node trees depth first, children in order (the order entities
    /// are spawned in), with an explicit stack: a file's nesting cannot overflow the call
    /// stack, and a node reached twice (a cycle, or two parents) is an error naming it.
    fn visit_scene(
        &mut self,
        world: &mut World,
        roots: impl Iterator<Item = gltf::Node<'a>>,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        let mut reached = vec![false; self.document.nodes().len()];
        let mut stack: Vec<(gltf::Node<'a>, Mat4, usize)> =
            roots.map(|n| (n, Mat4::IDENTITY, 0)).collect();
        stack.reverse();
        while let Some((node, parent, depth)) = stack.pop() {
            let invalid = |problem: String| {
                asset_err(
                    self.path,
                    AssetError::Invalid {
                        item: format!("node {}", node_label(&node)),
                        problem,
                    },
                )
            };
            match reached.get_mut(node.index()) {
                Some(true) => {
                    return Err(invalid(
                        "is reached twice from the scene (a cycle, or a node with two parents)"
                            .into(),
                    ));
                }
                Some(r) => *r = true,
                None => return Err(invalid("does not exist".into())),
            }
            if depth >= MAX_NODE_DEPTH {
                return Err(invalid(format!(
                    "is nested more than {MAX_NODE_DEPTH} levels deep"
                )));
            }
            let file_from_node = self.visit(world, &node, parent, warnings)?;
            let children: Vec<_> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, file_from_node, depth + 1));
            }
        }
        Ok(())
    }

    /// Spawns what one node holds; returns its file-from-node transform for its children.
    fn visit(
        &mut self,
        world: &mut World,
        node: &gltf::Node<'a>,
        parent: Mat4,
        warnings: &mut Vec<String>,
    ) -> Result<Mat4> {
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let file_from_node = parent * local;
        if !file_from_node.is_finite() {
            return Err(asset_err(
                self.path,
                AssetError::Invalid {
                    item: format!("node {}", node_label(node)),
                    problem: "transform is not finite".into(),
                },
            ));
        }
        let world_from_node = self.options.world_from_file * Affine3A::from_mat4(file_from_node);
        if let Some(mesh) = node.mesh() {
            self.spawn_mesh(world, node, &mesh, world_from_node, warnings)?;
        }
        if let Some(camera) = node.camera() {
            self.add_camera(&camera, world_from_node, warnings);
        }
        if let Some(light) = node.light() {
            self.lights.push((light, world_from_node));
        }
        Ok(file_from_node)
    }

    fn spawn_mesh(
        &mut self,
        world: &mut World,
        node: &gltf::Node<'a>,
        mesh: &gltf::Mesh<'a>,
        world_from_object: Affine3A,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        // A mirroring transform turns counter-clockwise triangles clockwise: reverse them.
        let mirrored = world_from_object.matrix3.determinant() < 0.0;
        for primitive in mesh.primitives() {
            let key = (mesh.index(), primitive.index(), mirrored);
            if !matches!(
                primitive.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                if !self.warned_modes.contains(&mesh.index()) {
                    self.warned_modes.push(mesh.index());
                    warnings.push(format!(
                        "{}: mesh {}: point and line primitives skipped (glint draws triangles only)",
                        self.path.display(),
                        mesh_label(mesh)
                    ));
                }
                continue;
            }
            let data = match self.meshes.get(&key) {
                Some(d) => d.clone(),
                None => {
                    let data = self.read_primitive(mesh, &primitive, mirrored, warnings)?;
                    let d = self.share(data);
                    self.mesh_bounds.insert(key, mesh_bounds(&d));
                    self.meshes.insert(key, d.clone());
                    d
                }
            };
            let material = match self.options.material {
                Some(e) => e,
                None => self.material(world, &primitive.material())?,
            };
            self.report.triangles += data.triangles.len() as u64;
            self.report
                .include_box(self.mesh_bounds[&key], world_from_object);
            world.spawn((
                Name::new(format!(
                    "{}/{}#{}",
                    node_label(node),
                    mesh_label(mesh),
                    primitive.index()
                )),
                Mesh { data },
                Transform { world_from_object },
                MaterialRef(material),
            ));
        }
        Ok(())
    }

    /// The geometry already read with the same contents as `data`, else `data`.
    fn share(&mut self, data: MeshData) -> Arc<MeshData> {
        let mut h = std::hash::DefaultHasher::new();
        for v in &data.vertices {
            let bits = [v.position, v.normal].map(|p| p.to_array().map(f32::to_bits));
            std::hash::Hash::hash(&(bits, v.texcoord.to_array().map(f32::to_bits)), &mut h);
        }
        std::hash::Hash::hash(&data.triangles, &mut h);
        let same = self
            .by_content
            .entry(std::hash::Hasher::finish(&h))
            .or_default();
        if let Some(d) = same.iter().find(|d| ***d == data) {
            return d.clone();
        }
        let d = Arc::new(data);
        same.push(d.clone());
        d
    }

    fn read_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        mirrored: bool,
        warnings: &mut Vec<String>,
    ) -> Result<MeshData> {
        let label = format!("mesh {} primitive {}", mesh_label(mesh), primitive.index());
        let err = |problem: &str| {
            asset_err(
                self.path,
                AssetError::Invalid {
                    item: label.clone(),
                    problem: problem.to_owned(),
                },
            )
        };
        let buffers = self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| err("has no readable POSITION attribute"))?
            .map(Vec3::from_array)
            .collect();
        if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
            return Err(err(&format!("POSITION {bad} is not finite")));
        }
        let n = positions.len();
        let normals: Option<Vec<Vec3>> = reader
            .read_normals()
            .map(|it| it.map(Vec3::from_array).collect());
        let uv = self.uv_choice(&primitive.material());
        let texcoords: Vec<Vec2> = match reader.read_tex_coords(uv.set) {
            Some(it) => it.into_f32().map(Vec2::from_array).collect(),
            None => vec![Vec2::ZERO; n],
        };
        if normals.as_ref().is_some_and(|v| v.len() != n) || texcoords.len() != n {
            return Err(err("attribute counts differ from the POSITION count"));
        }
        if reader.read_colors(0).is_some() && !self.warned_colors {
            self.warned_colors = true;
            warnings.push(format!(
                "{}: vertex colours (COLOR_0) ignored (glint materials have no per-vertex colour)",
                self.path.display()
            ));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(it) => it.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(err(&format!("index {bad} out of range ({n} vertices)")));
        }
        let mut triangles: Vec<[u32; 3]> = match primitive.mode() {
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    // Every other strip triangle swaps its first two vertices to keep the winding.
                    if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    }
                })
                .collect(),
            Mode::TriangleFan => (1..indices.len().saturating_sub(1))
                .map(|i| [indices[i], indices[i + 1], indices[0]])
                .collect(),
            _ => indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        };
        // glTF's v runs down the image; glint's runs up. Transform first (glTF convention).
        let texcoords: Vec<Vec2> = texcoords
            .into_iter()
            .map(|t| {
                let t = uv.transform.map_or(t, |m| m.transform_point2(t));
                Vec2::new(t.x, 1.0 - t.y)
            })
            .collect();
        let mut data = match normals {
            Some(normals) => {
                let derived = shapes::smooth_normals(&positions, &triangles);
                MeshData {
                    vertices: (0..n)
                        .map(|i| Vertex {
                            position: positions[i],
                            normal: normals[i].try_normalize().unwrap_or(derived[i]),
                            texcoord: texcoords[i],
                        })
                        .collect(),
                    triangles: std::mem::take(&mut triangles),
                }
            }
            // The glTF spec asks for flat normals when NORMAL is absent.
            None => flat_mesh(&positions, &texcoords, &triangles),
        };
        if mirrored {
            for t in &mut data.triangles {
                t.swap(1, 2);
            }
        }
        Ok(data)
    }

    fn add_camera(
        &mut self,
        camera: &gltf::Camera,
        world_from_node: Affine3A,
        warnings: &mut Vec<String>,
    ) {
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                // A glTF camera looks down its node's -z with +y up.
                let position = world_from_node.transform_point3(Vec3::ZERO);
                let forward = world_from_node.transform_vector3(Vec3::NEG_Z);
                let up = world_from_node.transform_vector3(Vec3::Y);
                let fov = p.yfov().to_degrees();
                if forward.length() > 0.0 && up.length() > 0.0 && fov > 0.0 && fov < 180.0 {
                    self.report.cameras.push(ImportedCamera {
                        name: camera
                            .name()
                            .map_or_else(|| format!("camera {}", camera.index()), str::to_owned),
                        position,
                        look_at: position + forward.normalize(),
                        up: up.normalize(),
                        fov_y_degrees: fov,
                        aspect_ratio: p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0),
                    });
                }
            }
            gltf::camera::Projection::Orthographic(_) => warnings.push(format!(
                "{}: orthographic camera {} skipped (glint cameras are perspective)",
                self.path.display(),
                camera.name().unwrap_or("unnamed")
            )),
        }
    }

    fn spawn_lights(&mut self, world: &mut World, warnings: &mut Vec<String>) {
        let (centre, radius) = self.report.centre_radius();
        for (light, world_from_node) in std::mem::take(&mut self.lights) {
            let color = Vec3::from_array(light.color()).max(Vec3::ZERO);
            let intensity = light.intensity().max(0.0);
            let name = light.name().unwrap_or("unnamed").to_owned();
            let position = world_from_node.transform_point3(Vec3::ZERO);
            let (position, color) = match light.kind() {
                LightKind::Point => (
                    position,
                    point_light_colour(color, intensity, position.distance(centre)),
                ),
                LightKind::Spot { .. } => {
                    warnings.push(format!(
                        "{}: spot light \"{name}\" imported as a point light (cone ignored)",
                        self.path.display()
                    ));
                    (
                        position,
                        point_light_colour(color, intensity, position.distance(centre)),
                    )
                }
                LightKind::Directional => {
                    // Lux is already irradiance; a far point light has nearly parallel rays.
                    let dir = world_from_node
                        .transform_vector3(Vec3::NEG_Z)
                        .normalize_or(Vec3::NEG_Y);
                    warnings.push(format!(
                        "{}: directional light \"{name}\" imported as a distant point light",
                        self.path.display()
                    ));
                    (centre - dir * radius.max(1e-3) * 1000.0, color * intensity)
                }
            };
            if position.is_finite() && color.is_finite() {
                world.spawn((Name::new(name), PointLight { position, color }));
                self.report.lights += 1;
            }
        }
    }
}

/// One vertex per triangle corner with the face normal (glTF's rule without NORMAL).
fn flat_mesh(positions: &[Vec3], texcoords: &[Vec2], triangles: &[[u32; 3]]) -> MeshData {
    let mut vertices = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or(Vec3::Z);
        for &i in t {
            vertices.push(Vertex {
                position: positions[i as usize],
                normal,
                texcoord: texcoords[i as usize],
            });
        }
    }
    let triangles = (0..triangles.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    MeshData {
        vertices,
        triangles,
    }
}

fn node_label(node: &gltf::Node) -> String {
    node.name()
        .map_or_else(|| format!("node {}", node.index()), str::to_owned)
}

fn mesh_label(mesh: &gltf::Mesh) -> String {
    mesh.name()
        .map_or_else(|| format!("{}", mesh.index()), |n| format!("\"{n}\""))
}
