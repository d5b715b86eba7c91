//! The RON scene format (documented in docs/scene-format.md): plain serde structs,
//! parsed strictly (unknown fields are errors) and validated in `load.rs`.

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use serde::Deserialize;

use super::settings::Settings;
use super::texture::WrapMode;

/// A whole scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The camera.
    pub camera: CameraDesc,
    /// Render settings; missing fields take SPEC defaults.
    #[serde(default)]
    pub settings: Settings,
    /// Named materials; a name given twice is an error, not a silent overwrite.
    #[serde(default, deserialize_with = "unique_names")]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Geometry and lights.
    #[serde(default)]
    pub entities: Vec<EntityDesc>,
}

/// Reads a map of named materials, refusing a name that appears twice (serde's own map
/// keeps the last one without a word).
fn unique_names<'de, D>(d: D) -> Result<BTreeMap<String, MaterialDesc>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    struct Names;
    impl<'de> serde::de::Visitor<'de> for Names {
        type Value = BTreeMap<String, MaterialDesc>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map of material names to materials")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut names = BTreeMap::new();
            while let Some((name, material)) = map.next_entry::<String, MaterialDesc>()? {
                if names.contains_key(&name) {
                    return Err(serde::de::Error::custom(format!(
                        "material \"{name}\" is defined twice"
                    )));
                }
                names.insert(name, material);
            }
            Ok(names)
        }
    }
    d.deserialize_map(Names)
}

/// The camera as written in RON.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub position: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
    /// Up direction.
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov_y: f32,
    /// Image width.
    #[serde(default = "default_size")]
    pub width: u32,
    /// Image height.
    #[serde(default = "default_size")]
    pub height: u32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}
fn default_fov() -> f32 {
    40.0
}
fn default_size() -> u32 {
    512
}

/// A material as written in RON.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialDesc {
    /// Diffuse colour.
    pub kd: Vec3,
    /// Specular colour.
    pub ks: Vec3,
    /// Specular exponent.
    pub shininess: f32,
    /// Alpha (1 = opaque); written `transparency` in RON, as the course's format names it.
    #[serde(rename = "transparency")]
    pub alpha: f32,
    /// Diffuse texture file, relative to the scene file.
    pub kd_texture: Option<String>,
    /// Wrap modes along u and v.
    pub wrap: (WrapMode, WrapMode),
}

impl Default for MaterialDesc {
    fn default() -> Self {
        Self {
            kd: Vec3::splat(0.8),
            ks: Vec3::ZERO,
            shininess: 1.0,
            alpha: 1.0,
            kd_texture: None,
            wrap: (WrapMode::Clamp, WrapMode::Clamp),
        }
    }
}

/// Placement: scale, then rotate (degrees about x, then y, then z), then translate.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransformDesc {
    /// Translation.
    pub translate: Vec3,
    /// Euler angles in degrees, applied x then y then z.
    pub rotate_degrees: Vec3,
    /// Per-axis scale.
    pub scale: Vec3,
}

impl Default for TransformDesc {
    fn default() -> Self {
        Self {
            translate: Vec3::ZERO,
            rotate_degrees: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

/// One entity of the scene.
#[derive(Clone, Debug, Deserialize)]
pub enum EntityDesc {
    /// A triangle mesh.
    Mesh(MeshDesc),
    /// An analytic sphere.
    Sphere(SphereDesc),
    /// A point light.
    PointLight(PointLightDesc),
    /// A segment light.
    SegmentLight(SegmentLightDesc),
    /// A parallelogram light.
    ParallelogramLight(ParallelogramLightDesc),
}

/// A mesh entity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// Name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// Where the triangles come from.
    pub geometry: GeometryDesc,
    /// Material name (required unless the geometry brings its own materials).
    #[serde(default)]
    pub material: Option<String>,
    /// Placement.
    #[serde(default)]
    pub transform: TransformDesc,
}

/// A vertex written inline.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VertexDesc {
    /// Position.
    pub position: Vec3,
    /// Normal; derived from the triangles when absent.
    #[serde(default)]
    pub normal: Option<Vec3>,
    /// Texture coordinate (v = 0 at the image's bottom).
    #[serde(default)]
    pub texcoord: Vec2,
}

/// Where a mesh's triangles come from.
#[derive(Clone, Debug, Deserialize)]
pub enum GeometryDesc {
    /// Vertices and triangles written in the file.
    Inline {
        /// The vertices.
        vertices: Vec<VertexDesc>,
        /// Vertex index triples, counter-clockwise from the front.
        triangles: Vec<[u32; 3]>,
    },
    /// The unit square [-0.5, 0.5]^2 in the xy plane, facing +z.
    Quad,
    /// A parallelogram `origin + s*edge_u + t*edge_v`, facing `edge_u x edge_v`.
    Parallelogram {
        /// First corner.
        origin: Vec3,
        /// First edge (texture u).
        edge_u: Vec3,
        /// Second edge (texture v).
        edge_v: Vec3,
    },
    /// The unit cube [-0.5, 0.5]^3, two triangles per face, outward normals.
    Cube,
    /// The unit square in the xz plane facing +y, split into `subdivisions^2` cells.
    Plane {
        /// Cells along each side.
        subdivisions: u32,
    },
    /// A unit-radius sphere of `segments` x `rings` quads.
    UvSphere {
        /// Divisions around the axis.
        segments: u32,
        /// Divisions from pole to pole.
        rings: u32,
    },
    /// A unit-radius icosphere.
    Icosphere {
        /// Times each face is split in four.
        subdivisions: u32,
    },
    /// Meshes of a glTF 2.0 file (path relative to the scene file).
    Gltf {
        /// The file.
        path: String,
        /// Scene index; the file's default scene when absent.
        #[serde(default)]
        scene: Option<usize>,
    },
    /// Meshes of a Wavefront OBJ file (path relative to the scene file).
    Obj {
        /// The file.
        path: String,
    },
}

/// A sphere entity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    /// Name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
    /// Material name.
    pub material: String,
}

/// A point light entity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLightDesc {
    /// Name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// Position.
    pub position: Vec3,
    /// Colour.
    #[serde(default = "white")]
    pub color: Vec3,
}

/// A segment light entity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentLightDesc {
    /// Name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// First endpoint.
    pub endpoint0: Vec3,
    /// Second endpoint.
    pub endpoint1: Vec3,
    /// Colour at the first endpoint.
    #[serde(default = "white")]
    pub color0: Vec3,
    /// Colour at the second endpoint.
    #[serde(default = "white")]
    pub color1: Vec3,
}

/// A parallelogram light entity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParallelogramLightDesc {
    /// Name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// First corner.
    pub v0: Vec3,
    /// First edge.
    pub edge01: Vec3,
    /// Second edge.
    pub edge02: Vec3,
    /// Colour at `v0`.
    #[serde(default = "white")]
    pub color0: Vec3,
    /// Colour at `v0 + edge01`.
    #[serde(default = "white")]
    pub color1: Vec3,
    /// Colour at `v0 + edge02`.
    #[serde(default = "white")]
    pub color2: Vec3,
    /// Colour at `v0 + edge01 + edge02`.
    #[serde(default = "white")]
    pub color3: Vec3,
}

fn white() -> Vec3 {
    Vec3::ONE
}

impl From<&super::components::Camera> for CameraDesc {
    /// The RON form of a validated camera (to save a view, or to re-validate a built one).
    fn from(c: &super::components::Camera) -> Self {
        CameraDesc {
            position: c.position,
            look_at: c.look_at,
            up: c.up,
            fov_y: c.fov_y_degrees,
            width: c.width,
            height: c.height,
        }
    }
}
