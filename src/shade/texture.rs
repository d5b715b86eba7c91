//! Textures decoded once at load to linear RGB, and their lookups (SPEC "Textures").

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// What a lookup does outside `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrapMode {
    /// Clamp to the edge texel.
    #[default]
    Clamp,
    /// Tile.
    Repeat,
    /// Tile, mirroring every other copy.
    MirroredRepeat,
}

/// A decoded texture: linear RGB texels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` linear RGB texels, row 0 first.
    pub texels: Vec<Vec3>,
}
