//! Per-run statistics: which stages ran, how often, and how much work they did.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;

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
    /// Stage name (the system's function name) to its work.
    pub stages: BTreeMap<&'static str, StageStats>,
    /// Rays traced by kind.
    pub rays: RayCounts,
    /// Samples dropped because their radiance was NaN or infinite.
    pub nonfinite_samples: u64,
}

impl RenderStats {
    /// Records one run of `stage` that processed `items`.
    pub fn record(&mut self, stage: &'static str, items: u64) {
        let s = self.stages.entry(stage).or_default();
        s.runs += 1;
        s.items += items;
    }

    /// Whether `stage` ran at least once.
    pub fn ran(&self, stage: &str) -> bool {
        self.stages.get(stage).is_some_and(|s| s.runs > 0)
    }

    /// Items `stage` processed (0 if it never ran).
    pub fn items(&self, stage: &str) -> u64 {
        self.stages.get(stage).map_or(0, |s| s.items)
    }
}
