//! The render pipeline, stage by stage: the table of contents of glint.
//!
//! ```text
//! Prepare (once):  analyse_scene
//!                  -> gather_materials, gather_lights -> decode_textures?
//!                  -> build_triangle_bvh?, build_sphere_bvh?
//! RenderPass (per sample index and image region):
//!                  generate_camera_samples -> trace_wavefronts -> accumulate_film
//! Bounce (per depth level, run by trace_wavefronts while rays remain):
//!                  intersect_rays -> shade_hits -> trace_shadow_rays? -> gather_radiance
//!                  -> spawn_reflection_rays?, spawn_pass_through_rays? -> advance_depth
//! ```
//! A `?` stage has a run condition read from the [`RenderPlan`] that `analyse_scene`
//! decides once; `glint info` prints that plan with its reasons.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

use crate::accel::scene::{SceneGeometry, build_sphere_bvh, build_triangle_bvh};
use crate::film::{Film, accumulate_film};
use crate::trace::lights::{Lights, gather_lights};
use crate::trace::materials::{Materials, decode_textures, gather_materials};
use crate::trace::plan::{RenderPlan, analyse_scene};
use crate::trace::stats::RenderStats;
use crate::trace::wavefront::*;
use crate::trace::{StageErrors, trace_wavefronts};

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

/// Inserts the render schedules and the resources they use into `world`.
pub fn add_render_schedules(world: &mut World) {
    world.init_resource::<RenderPlan>();
    world.init_resource::<RenderStats>();
    world.init_resource::<Materials>();
    world.init_resource::<Lights>();
    world.init_resource::<SceneGeometry>();
    world.init_resource::<Wavefront>();
    world.init_resource::<PassRegion>();
    world.init_resource::<Film>();
    world.init_resource::<StageErrors>();
    world.add_schedule(prepare_schedule());
    world.add_schedule(pass_schedule());
    world.add_schedule(bounce_schedule());
}
