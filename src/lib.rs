//! glint: a small CPU ray tracer built as a data-oriented ECS.
//!
//! A RON scene is spawned into a `bevy_ecs::World` ([`scene`]); the schedules of
//! [`schedule`] build the acceleration structures ([`accel`]), generate camera samples
//! ([`sampling`]), trace wavefronts ([`trace`]) with the shading models of [`shade`],
//! and accumulate the [`film`]. [`render::Renderer`] drives a render.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod converge;
pub mod debug;
pub mod error;
pub mod film;
pub mod info;
pub mod memory;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod schedule;
pub mod shade;
pub mod stats;
pub mod terminal;
pub mod test_util;
pub mod trace;

pub use error::{GlintError, Result};
pub use render::{RenderSummary, Renderer};
pub use scene::Overrides;
