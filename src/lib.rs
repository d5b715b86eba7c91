//! glint: a small CPU ray tracer built as a data-oriented ECS.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod sampling;
pub mod scene;
pub mod shade;
pub mod error;

pub use error::{GlintError, Result};
