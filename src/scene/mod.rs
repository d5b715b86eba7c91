//! The scene: components, settings, the RON format and its loader.

pub mod components;
pub mod settings;

pub use components::*;
pub use settings::*;
