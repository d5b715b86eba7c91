//! Tracing: the material and light tables, the render plan, and the wavefront loop.

pub mod lights;
pub mod materials;
pub mod plan;
pub mod stats;
pub mod surface;
pub mod wavefront;

use bevy_ecs::prelude::*;

use crate::error::GlintError;
use crate::schedule::Bounce;

/// Errors raised inside systems (e.g. an undecodable texture), checked by the driver
/// after each schedule run.
#[derive(Resource, Debug, Default)]
pub struct StageErrors(pub Vec<GlintError>);

/// Runs the [`Bounce`] schedule once per depth level until no rays remain.
pub fn trace_wavefronts(world: &mut World) {
    while wavefront::rays_pending(world.resource::<wavefront::Wavefront>()) {
        world.run_schedule(Bounce);
    }
}
