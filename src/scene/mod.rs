//! The scene: components, settings, the RON format and its loader, the glTF and OBJ
//! importers, and per-run overrides. The bottom layer: it imports only `crate::error`,
//! and within it `load` and `model` use the importers, never the reverse.

pub mod components;
pub mod format;
pub mod gltf;
pub mod gradient;
pub mod import;
pub mod load;
pub mod model;
pub mod obj;
pub mod overrides;
pub mod settings;
pub mod shapes;
pub mod texture;
pub mod validate;

pub use components::*;
pub use load::{SceneSource, parse_scene, read_scene, spawn_scene};
pub use overrides::Overrides;
pub use settings::*;
