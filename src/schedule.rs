//! The render pipeline, stage by stage: the table of contents of glint.
//!
//! ```text
//! Prepare (once):  analyse_scene
//!                  -> gather_materials, gather_lights -> decode_textures?
//!                  -> build_triangle_bvh?, build_sphere_bvh?
//! for each pass (sample index)                                   run_passes
//!   for each region of at most REGION_PIXELS pixels              run_pass
//!     RenderPass:  generate_camera_samples -> trace_wavefronts
//!                  -> accumulate_film
//!     for each depth level while rays remain                     trace_wavefronts
//!       Bounce:    intersect_rays -> shade_hits -> trace_shadow_rays? -> gather_radiance
//!                  -> spawn_reflection_rays?, spawn_pass_through_rays? -> advance_depth
//! ```
//! A `?` stage has a run condition read from the [`RenderPlan`] that `analyse_scene`
//! decides once; `glint info` prints that plan with its reasons. Drivers (`render`,
//! `debug`, `converge`) call [`run_passes`] or [`run_pass`]; a debug run adds observer
//! systems to these schedules, a normal render has none.

use std::ops::Range;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

use crate::error::Result;
use crate::film::{Film, accumulate_film};
pub use crate::stats::{RenderStats, Stage, StageErrors};
use crate::trace::geometry::{SceneGeometry, build_sphere_bvh, build_triangle_bvh};
use crate::trace::lights::{Lights, gather_lights};
use crate::trace::materials::{Materials, decode_textures, gather_materials};
use crate::trace::plan::{RenderPlan, analyse_scene};
use crate::trace::wavefront::*;

/// Pixels traced per wavefront: bounds the queues' memory for large images. 2^14 keeps
/// a region's shadow-ray queue (4 samples per hit) within L2: the Cornell render at 512²
/// took 1.15-1.16 s on 1 thread against 1.19-1.21 s with 2^16 (2^12: 1.21-1.22 s, the
/// schedule's per-region runs then cost more than the cache saves).
pub const REGION_PIXELS: u32 = 1 << 14;

/// Runs once per render: analysis, tables, acceleration structures.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Prepare;

/// Runs once per sample index and image region.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct RenderPass;

/// Runs once per depth level of a wavefront.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Bounce;

/// Phases of [`Prepare`].
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub enum PrepareSystems {
    /// After this, the [`RenderPlan`] says which optional stages run.
    Analyse,
    /// After this, materials, textures and lights are in dense tables.
    Gather,
    /// After this, every triangle and sphere is in a BVH.
    BuildAccel,
}

/// Phases of [`RenderPass`].
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub enum PassSystems {
    /// After this, the wavefront holds one camera ray per pixel of the region.
    GenerateSamples,
    /// After this, every camera sample of the region has its radiance.
    Trace,
    /// After this, the film holds the region's samples.
    Accumulate,
}

/// Phases of [`Bounce`].
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub enum BounceSystems {
    /// After this, every ray has its closest hit.
    Intersect,
    /// After this, direct light is added or queued as shadow rays.
    Shade,
    /// After this, shadow rays have added what reaches the surface.
    ShadowRays,
    /// After this, each camera sample holds this depth's radiance.
    Gather,
    /// After this, the next depth's rays are queued.
    Spawn,
    /// After this, the next depth's rays are current.
    Advance,
}

/// A run condition reading one decision of the [`RenderPlan`].
fn planned(decision: fn(&RenderPlan) -> bool) -> impl FnMut(Res<RenderPlan>) -> bool + Clone {
    move |plan: Res<RenderPlan>| decision(&plan)
}

/// The [`Prepare`] schedule.
pub fn prepare_schedule() -> Schedule {
    use PrepareSystems::*;
    let mut s = Schedule::new(Prepare);
    s.configure_sets((Analyse, Gather, BuildAccel).chain());
    s.add_systems((
        analyse_scene.in_set(Analyse),
        (gather_materials, gather_lights).in_set(Gather),
        decode_textures
            .run_if(planned(|p| p.textures))
            .after(gather_materials)
            .in_set(Gather),
        build_triangle_bvh
            .run_if(planned(|p| p.triangle_bvh))
            .in_set(BuildAccel),
        build_sphere_bvh
            .run_if(planned(|p| p.sphere_bvh))
            .in_set(BuildAccel),
    ));
    s
}

/// The [`RenderPass`] schedule.
pub fn pass_schedule() -> Schedule {
    use PassSystems::*;
    let mut s = Schedule::new(RenderPass);
    s.configure_sets((GenerateSamples, Trace, Accumulate).chain());
    s.add_systems((
        generate_camera_samples.in_set(GenerateSamples),
        trace_wavefronts.in_set(Trace),
        accumulate_film.in_set(Accumulate),
    ));
    s
}

/// The [`Bounce`] schedule.
pub fn bounce_schedule() -> Schedule {
    use BounceSystems::*;
    let mut s = Schedule::new(Bounce);
    s.configure_sets((Intersect, Shade, ShadowRays, Gather, Spawn, Advance).chain());
    s.add_systems((
        intersect_rays.in_set(Intersect),
        shade_hits.in_set(Shade),
        trace_shadow_rays
            .run_if(planned(|p| p.shadow_rays))
            .in_set(ShadowRays),
        gather_radiance.in_set(Gather),
        // Because both push to the next queue, their order fixes the queue order.
        (
            spawn_reflection_rays.run_if(planned(|p| p.reflections)),
            spawn_pass_through_rays.run_if(planned(|p| p.pass_through)),
        )
            .chain()
            .in_set(Spawn),
        advance_depth.in_set(Advance),
    ));
    s
}

/// What the pass and region loops ask of the driver that runs them. `Send` because the
/// loops run on a rayon worker, so its methods may be called from another thread.
pub trait PassControl: Send {
    /// Asked before every region: `false` stops the loops (an interrupt). The region in
    /// flight always finishes, so the film stays consistent.
    fn proceed(&mut self) -> bool {
        true
    }
    /// Told after every region how many pixels it traced (a progress bar).
    fn region_done(&mut self, _pixels: u64) {}
    /// Asked after every complete pass: `false` ends the run there (a time budget).
    fn another_pass(&mut self) -> bool {
        true
    }
}

/// A driver that traces everything it is given.
impl PassControl for () {}

/// The pass loop: sample indices `samples` over the pixels `pixels` (row-major
/// indices), pass after pass; returns the passes completed.
pub fn run_passes(
    world: &mut World,
    samples: Range<u32>,
    pixels: Range<u32>,
    control: &mut dyn PassControl,
) -> Result<u32> {
    // The whole loop on one rayon worker: each region's parallel stages then start from
    // that worker, and the calling thread hands over once per render instead of once
    // per region (256 times for 16 passes of 16 regions), sleeping until it ends.
    rayon::scope(|_| {
        let mut done = 0;
        for sample in samples {
            if !run_pass(world, sample, pixels.clone(), control)? {
                break;
            }
            done += 1;
            if !control.another_pass() {
                break;
            }
        }
        Ok(done)
    })
}

/// The region loop: one sample index over `pixels`, [`REGION_PIXELS`] at a time;
/// returns whether every region was traced. An interrupt leaves the pass partial: the
/// first regions then hold one sample more than the others.
pub fn run_pass(
    world: &mut World,
    sample: u32,
    pixels: Range<u32>,
    control: &mut dyn PassControl,
) -> Result<bool> {
    let mut first = pixels.start;
    while first < pixels.end && control.proceed() {
        let count = REGION_PIXELS.min(pixels.end - first);
        world.insert_resource(PassRegion {
            sample,
            first_pixel: first,
            pixels: count,
        });
        // On a rayon worker: the region's parallel stages then start from that worker
        // (which takes its share) instead of each waking the pool from this thread and
        // sleeping until it ends. Already on a worker (from `run_passes`), this runs in
        // place.
        rayon::scope(|_| world.run_schedule(RenderPass));
        control.region_done(count as u64);
        first += count;
    }
    take_stage_errors(world)?;
    Ok(first >= pixels.end)
}

/// The depth loop: runs the [`Bounce`] schedule once per depth level until no rays remain.
pub fn trace_wavefronts(world: &mut World) {
    while rays_pending(world.resource::<Wavefront>()) {
        world.run_schedule(Bounce);
    }
}

/// Runs the [`Prepare`] schedule and reports the first error a stage raised.
pub fn run_prepare(world: &mut World) -> Result<()> {
    world.run_schedule(Prepare);
    take_stage_errors(world)
}

/// The first error a stage raised since the last call, as an `Err`.
fn take_stage_errors(world: &mut World) -> Result<()> {
    match world.resource_mut::<StageErrors>().take_first() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Inserts the render schedules and the resources they use into `world`.
pub fn add_render_schedules(world: &mut World) {
    world.init_resource::<RenderPlan>();
    world.init_resource::<RenderStats>();
    world.init_resource::<Materials>();
    world.init_resource::<Lights>();
    world.init_resource::<SceneGeometry>();
    world.init_resource::<Wavefront>();
    world.init_resource::<PassRegion>();
    world.init_resource::<SampleRadiance>();
    world.init_resource::<Film>();
    world.init_resource::<StageErrors>();
    world.add_schedule(prepare_schedule());
    world.add_schedule(pass_schedule());
    world.add_schedule(bounce_schedule());
}
