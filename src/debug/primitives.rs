//! Debug primitives: the entities the emitters spawn and the overlay and dump read.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use serde::Serialize;

/// The feature that emitted a primitive (also the names accepted by `--features`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Feature {
    /// The pixel itself: camera rays, the first hit, the pixel's colour (always shown).
    Pixel,
    /// Reflection rays by depth and the normals at bounce points.
    Reflections,
    /// Pass-through rays in the colour of what they hit, markers and split normals.
    Transparency,
    /// The BVH nodes a traversal visited, the tested primitives and the hit.
    Bvh,
    /// The texture panel with the looked-up texel(s).
    Textures,
    /// Rays from light samples to shaded points, coloured by visibility; area light samples.
    Lights,
    /// The pixel's sample positions on its grid.
    Samples,
}

impl Feature {
    /// The features a user can ask for, in legend order.
    pub const ALL: [Feature; 7] = [
        Feature::Pixel,
        Feature::Reflections,
        Feature::Transparency,
        Feature::Bvh,
        Feature::Textures,
        Feature::Lights,
        Feature::Samples,
    ];

    /// The name used on the command line and in the dump.
    pub fn name(self) -> &'static str {
        match self {
            Feature::Pixel => "pixel",
            Feature::Reflections => "reflections",
            Feature::Transparency => "transparency",
            Feature::Bvh => "bvh",
            Feature::Textures => "textures",
            Feature::Lights => "lights",
            Feature::Samples => "samples",
        }
    }

    /// Parses a `--features` name (singular forms accepted).
    pub fn parse(name: &str) -> Option<Feature> {
        let n = name.trim().to_ascii_lowercase();
        Feature::ALL
            .into_iter()
            .find(|f| f.name() == n || f.name().trim_end_matches('s') == n)
    }
}

/// What a debug primitive looks like, in world space (or as a 2D inset).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Shape {
    /// A line segment between two world points.
    Segment {
        /// Start.
        a: Vec3,
        /// End.
        b: Vec3,
    },
    /// A point or small sphere marker.
    Marker {
        /// Centre.
        center: Vec3,
        /// Radius in world units (the overlay keeps it a few pixels wide at least).
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
    /// A 2D inset showing a texture with looked-up texels marked.
    TexturePanel {
        /// Index into the material table's textures.
        texture: u32,
        /// Texture size in texels.
        size: [u32; 2],
        /// The texture coordinate looked up.
        uv: Vec2,
        /// Texels read (column, row from the top) with their weights.
        texels: Vec<([u32; 2], f32)>,
    },
    /// A 2D inset showing the pixel's sample positions in [0, 1)^2 (y down, like the image).
    SampleGrid {
        /// Side of the stratified grid (`None` for uniform sampling).
        strata: Option<u32>,
        /// Sample offsets within the pixel.
        points: Vec<Vec2>,
    },
    /// A text label at a world point, or in the caption when `at` is `None`.
    Label {
        /// Anchor.
        at: Option<Vec3>,
        /// The text.
        text: String,
    },
}

impl Shape {
    /// The kind's name, as the dump writes it.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Segment { .. } => "segment",
            Shape::Marker { .. } => "marker",
            Shape::Box { .. } => "box",
            Shape::TexturePanel { .. } => "texture_panel",
            Shape::SampleGrid { .. } => "sample_grid",
            Shape::Label { .. } => "label",
        }
    }
}

/// The numbers a primitive explains; absent ones are left out of the dump.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Values {
    /// What the primitive is (e.g. "camera ray", "bvh node", "shadow ray").
    pub what: &'static str,
    /// Sample index.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample: Option<u32>,
    /// Ray depth or BVH node depth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth: Option<u32>,
    /// Ray parameter of a hit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<f32>,
    /// Barycentric coordinates of a triangle hit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barycentrics: Option<Vec3>,
    /// Primitive index (triangle or sphere) or BVH node index.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index: Option<u32>,
    /// Material alpha.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f32>,
    /// Light index (points, then segments, then parallelograms).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<u32>,
    /// Whether the light sample reaches the point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub visible: Option<bool>,
    /// Light that arrives (contribution times visibility or transparent tint).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arrived: Option<Vec3>,
    /// Texture coordinate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uv: Option<Vec2>,
    /// Radiance (of a ray at its depth, or of the pixel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radiance: Option<Vec3>,
}

/// A debug primitive's place in spawn order: the dump and the legend list primitives so.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct DebugOrder(pub u32);

/// A debug primitive: one entity each, with its colour and the feature that emitted it.
#[derive(Component, Clone, Debug, PartialEq, Serialize)]
pub struct DebugPrimitive {
    /// The feature that emitted it.
    pub feature: Feature,
    /// Display colour (linear RGB).
    pub color: Vec3,
    /// Geometry.
    pub shape: Shape,
    /// What it explains.
    pub values: Values,
}
