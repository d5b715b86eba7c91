//! Pipeline-wide bookkeeping every stage writes into: which stages ran and how much
//! work they did ([`RenderStats`]), and errors raised inside systems ([`StageErrors`]).
//!
//! It sits below every stage so that `accel` users, `trace` and `film` can record
//! without importing each other; `schedule.rs` inserts both resources.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;

use crate::error::GlintError;

/// A stage of the pipeline that records its work, named as its system.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// `gather_materials`: the material table.
    GatherMaterials,
    /// `decode_textures`: texels decoded.
    DecodeTextures,
    /// `gather_lights`: the light table.
    GatherLights,
    /// `build_triangle_bvh`: triangles put in a BVH.
    BuildTriangleBvh,
    /// `build_sphere_bvh`: spheres put in a BVH.
    BuildSphereBvh,
    /// `generate_camera_samples`: camera rays queued.
    GenerateCameraSamples,
    /// `intersect_rays`: rays intersected.
    IntersectRays,
    /// `shade_hits`: hits shaded.
    ShadeHits,
    /// `trace_shadow_rays`: shadow rays tested.
    TraceShadowRays,
    /// `spawn_reflection_rays`: reflection rays queued.
    SpawnReflectionRays,
    /// `spawn_pass_through_rays`: pass-through rays queued.
    SpawnPassThroughRays,
    /// `accumulate_film`: samples added to the film.
    AccumulateFilm,
}

impl Stage {
    /// The system's function name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::GatherMaterials => "gather_materials",
            Stage::DecodeTextures => "decode_textures",
            Stage::GatherLights => "gather_lights",
            Stage::BuildTriangleBvh => "build_triangle_bvh",
            Stage::BuildSphereBvh => "build_sphere_bvh",
            Stage::GenerateCameraSamples => "generate_camera_samples",
            Stage::IntersectRays => "intersect_rays",
            Stage::ShadeHits => "shade_hits",
            Stage::TraceShadowRays => "trace_shadow_rays",
            Stage::SpawnReflectionRays => "spawn_reflection_rays",
            Stage::SpawnPassThroughRays => "spawn_pass_through_rays",
            Stage::AccumulateFilm => "accumulate_film",
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Work done by one stage over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageStats {
    /// Times the stage's system ran.
    pub runs: u64,
    /// Items it processed (rays, triangles, texels... as the stage defines).
    pub items: u64,
}

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Rays from the camera.
    pub camera: u64,
    /// Reflection rays.
    pub reflection: u64,
    /// Pass-through (transparency) rays.
    pub pass_through: u64,
    /// Shadow (visibility) rays.
    pub shadow: u64,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.reflection + self.pass_through + self.shadow
    }
}

/// What a run did; tests assert on it, `glint render` summarises it.
#[derive(Resource, Clone, Debug, Default)]
pub struct RenderStats {
    /// Each stage that ran, with its work.
    pub stages: BTreeMap<Stage, StageStats>,
    /// Rays traced by kind.
    pub rays: RayCounts,
    /// Samples dropped because their radiance was NaN or infinite.
    pub nonfinite_samples: u64,
}

impl RenderStats {
    /// Records one run of `stage` that processed `items`.
    pub fn record(&mut self, stage: Stage, items: u64) {
        let s = self.stages.entry(stage).or_default();
        s.runs += 1;
        s.items += items;
    }

    /// Whether `stage` ran at least once.
    pub fn ran(&self, stage: Stage) -> bool {
        self.stages.get(&stage).is_some_and(|s| s.runs > 0)
    }

    /// Items `stage` processed (0 if it never ran).
    pub fn items(&self, stage: Stage) -> u64 {
        self.stages.get(&stage).map_or(0, |s| s.items)
    }
}

/// Errors raised inside systems (e.g. an undecodable texture), checked by the driver
/// after each schedule run.
#[derive(Resource, Debug, Default)]
pub struct StageErrors(pub Vec<GlintError>);

impl StageErrors {
    /// The first error raised since the last call, if any; clears the list.
    pub fn take_first(&mut self) -> Option<GlintError> {
        self.0.drain(..).next()
    }
}
