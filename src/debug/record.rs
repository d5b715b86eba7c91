//! Recorders: systems that copy what the render's own stages did for the debugged pixel
//! into the [`DebugTrace`]. They only read the [`Wavefront`] and trace's [`TraceLog`],
//! and run after the stage they watch; [`add_recorders`] puts them into the render's
//! schedules for a debug run only, so a normal render schedules none of them.

use std::any::TypeId;

use bevy_ecs::prelude::*;

use super::log::DebugTrace;
use crate::scene::Settings;
use crate::schedule::{Bounce, BounceSystems, PassSystems, RenderPass};
use crate::trace::log::TraceLog;
use crate::trace::plan::RenderPlan;
use crate::trace::wavefront::{CameraSampleOffsets, PassRegion, Wavefront};

/// Records the region's camera rays with their offsets within the pixel.
pub fn record_camera_samples(
    settings: Res<Settings>,
    plan: Res<RenderPlan>,
    region: Res<PassRegion>,
    wf: Res<Wavefront>,
    mut trace: ResMut<DebugTrace>,
) {
    let offsets = CameraSampleOffsets::new(&settings, &plan);
    let offsets: Vec<_> = wf
        .rays
        .iter()
        .map(|q| offsets.of(region.first_pixel + q.slot, region.sample))
        .collect();
    trace.record_camera_samples(region.sample, &wf.rays, &offsets);
}

/// Records the rays of the current depth with their hits and BVH traversals.
pub fn record_rays(
    region: Res<PassRegion>,
    wf: Res<Wavefront>,
    mut log: ResMut<TraceLog>,
    mut trace: ResMut<DebugTrace>,
) {
    let traces = std::mem::take(&mut log.rays);
    trace.record_rays(region.sample, wf.depth, &wf.rays, &wf.hits, traces);
}

/// Records the light samples shading saw at the current depth.
pub fn record_light_samples(mut log: ResMut<TraceLog>, mut trace: ResMut<DebugTrace>) {
    let seen = std::mem::take(&mut log.light_samples);
    trace.record_light_samples(&seen);
}

/// Records what each shadow ray of the current depth let through.
pub fn record_shadow_results(wf: Res<Wavefront>, mut trace: ResMut<DebugTrace>) {
    trace.record_shadow_results(&wf.shadow_rays.arrived());
}

/// Records the radiance each ray of the current depth gathered.
pub fn record_radiance(wf: Res<Wavefront>, mut trace: ResMut<DebugTrace>) {
    trace.record_radiance(&wf.ray_radiance);
}

/// The system types of every recorder, for tests that check where they are scheduled.
pub fn recorder_types() -> Vec<TypeId> {
    vec![
        record_camera_samples.system_type_id(),
        record_rays.system_type_id(),
        record_light_samples.system_type_id(),
        record_shadow_results.system_type_id(),
        record_radiance.system_type_id(),
    ]
}

/// Switches recording on in `world`: inserts the [`TraceLog`] and an empty
/// [`DebugTrace`], and adds the recorders to the [`RenderPass`] and [`Bounce`] schedules.
pub fn add_recorders(world: &mut World) {
    world.insert_resource(TraceLog::default());
    world.insert_resource(DebugTrace::default());
    world.schedule_scope(RenderPass, |_, s| {
        s.add_systems(
            record_camera_samples
                .run_if(resource_exists::<TraceLog>)
                // Because tracing replaces the camera rays with the next depth's.
                .after(PassSystems::GenerateSamples)
                .before(PassSystems::Trace),
        );
    });
    world.schedule_scope(Bounce, |_, s| {
        use BounceSystems::*;
        s.add_systems(
            (
                // Because each reads what the stage before it wrote, and the next
                // stage may overwrite it: hits, light samples, shadow results, radiance.
                record_rays.after(Intersect).before(Shade),
                record_light_samples.after(Shade).before(ShadowRays),
                record_shadow_results.after(ShadowRays).before(Gather),
                record_radiance.after(Gather).before(Spawn),
            )
                .run_if(resource_exists::<TraceLog>),
        );
    });
}
