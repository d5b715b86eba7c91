//! The scene model as ECS components: what a scene file spawns.

use std::path::PathBuf;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Affine3A, Vec2, Vec3};

use super::texture::{Texture, WrapMode};

/// Object-to-world placement of a mesh (named destination-from-source).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Maps object-space points to world space.
    pub world_from_object: Affine3A,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            world_from_object: Affine3A::IDENTITY,
        }
    }
}

/// A pinhole camera; image row 0 is the top.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position in world space.
    pub position: Vec3,
    /// Point the camera looks at.
    pub look_at: Vec3,
    /// Approximate up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// Where a diffuse texture comes from.
#[derive(Clone, Debug)]
pub enum TextureSource {
    /// An image file, decoded by the texture-decode stage (only when the scene uses textures).
    File(PathBuf),
    /// An image already decoded by an importer (e.g. embedded in a glTF file).
    Decoded(Arc<Texture>),
}

/// Surface appearance; one entity per named material, referenced by [`MaterialRef`].
#[derive(Component, Clone, Debug)]
pub struct Material {
    /// The name used in the scene file (for messages).
    pub name: String,
    /// Diffuse colour.
    pub kd: Vec3,
    /// Specular colour; also the reflection weight.
    pub ks: Vec3,
    /// Specular exponent.
    pub shininess: f32,
    /// Alpha: 1 = opaque, 0 = fully transparent.
    pub alpha: f32,
    /// Optional diffuse texture replacing `kd` when texture mapping is on.
    pub kd_texture: Option<TextureSource>,
    /// Texture wrap modes along u and v.
    pub wrap: [WrapMode; 2],
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: String::from("default"),
            kd: Vec3::splat(0.8),
            ks: Vec3::ZERO,
            shininess: 1.0,
            alpha: 1.0,
            kd_texture: None,
            wrap: [WrapMode::Clamp; 2],
        }
    }
}

/// The material entity a mesh or sphere is made of.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialRef(pub Entity);

/// One mesh vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vertex {
    /// Object-space position.
    pub position: Vec3,
    /// Object-space normal (unit length).
    pub normal: Vec3,
    /// Texture coordinate; v = 0 is the bottom row of the image.
    pub texcoord: Vec2,
}

/// Vertex and index data, shared between every mesh entity that instances it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// The vertices.
    pub vertices: Vec<Vertex>,
    /// Triangles as three vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// A triangle mesh placed by its [`Transform`] and made of its [`MaterialRef`].
#[derive(Component, Clone, Debug)]
#[require(Transform)]
pub struct Mesh {
    /// The geometry; an `Arc` so instanced meshes share it.
    pub data: Arc<MeshData>,
}

/// An analytic sphere in world space.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre in world space.
    pub center: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

/// A point light (no fall-off).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position in world space.
    pub position: Vec3,
    /// Colour; may exceed 1.
    pub color: Vec3,
}

/// A segment light whose colour varies linearly from `endpoint0` to `endpoint1`.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct SegmentLight {
    /// First endpoint.
    pub endpoint0: Vec3,
    /// Second endpoint.
    pub endpoint1: Vec3,
    /// Colour at `endpoint0`.
    pub color0: Vec3,
    /// Colour at `endpoint1`.
    pub color1: Vec3,
}

/// A parallelogram light with bilinearly interpolated corner colours.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct ParallelogramLight {
    /// Corner the edges start from.
    pub v0: Vec3,
    /// First edge, from `v0` to the corner with `color1`.
    pub edge01: Vec3,
    /// Second edge, from `v0` to the corner with `color2`.
    pub edge02: Vec3,
    /// Colour at `v0`.
    pub color0: Vec3,
    /// Colour at `v0 + edge01`.
    pub color1: Vec3,
    /// Colour at `v0 + edge02`.
    pub color2: Vec3,
    /// Colour at `v0 + edge01 + edge02`.
    pub color3: Vec3,
}
