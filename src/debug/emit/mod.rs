//! Emitter systems: one per feature, each turning the debug trace into debug-primitive
//! entities. They run only in a debug run, and only for features that are both on in
//! the scene and asked for (see [`super::debug_emit_schedule`]). One file per feature
//! group: the ray paths (pixel, reflections, transparency), the BVH, lights, textures
//! and samples.

mod bvh;
mod lights;
mod paths;
mod samples;
mod textures;

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use glam::Vec3;

use super::log::{DebugTrace, RayRecord};
use super::primitives::{DebugOrder, DebugPrimitive, Feature, Shape, Values};
use crate::trace::geometry::{PrimKind, SceneGeometry};
use crate::trace::wavefront::Branch;

pub use bvh::{emit_bvh, emit_bvh_level, node_depths};
pub use lights::emit_lights;
pub use paths::{emit_pixel, emit_reflections, emit_transparency};
pub use samples::emit_samples;
pub use textures::emit_textures;

/// Colour of camera rays.
pub const CAMERA_RAY: Vec3 = Vec3::new(0.2, 0.45, 1.0);
/// Colour of the first hit marker.
pub const FIRST_HIT: Vec3 = Vec3::new(1.0, 0.85, 0.1);
/// Colour of the first reflection level.
pub const REFLECTION_FIRST: Vec3 = Vec3::new(1.0, 0.1, 0.1);
/// Colour the reflection levels move towards with depth.
pub const REFLECTION_DEEP: Vec3 = Vec3::new(0.6, 0.85, 1.0);
/// Colour of normals at reflection points.
pub const NORMAL: Vec3 = Vec3::new(0.1, 0.9, 0.2);
/// Colour of the BVH root level.
pub const BVH_SHALLOW: Vec3 = Vec3::new(1.0, 0.0, 0.0);
/// Colour of the deepest BVH level.
pub const BVH_DEEP: Vec3 = Vec3::new(0.0, 1.0, 0.0);
/// Colour of the final leaf, the hit triangle.
pub const BVH_FINAL: Vec3 = Vec3::ONE;
/// Colour of tested vertices and the BVH hit point.
pub const BVH_TESTED: Vec3 = Vec3::new(0.15, 0.3, 1.0);
/// Colour of blocked light samples.
pub const BLOCKED: Vec3 = Vec3::ZERO;
/// Colour of sample points.
pub const SAMPLE_POINT: Vec3 = Vec3::new(0.15, 0.3, 1.0);

/// How many debug primitives have been spawned: the next one's [`DebugOrder`].
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpawnedPrimitives(pub u32);

/// Spawns debug primitives, each numbered in spawn order.
#[derive(SystemParam)]
pub struct Spawner<'w, 's> {
    commands: Commands<'w, 's>,
    spawned: ResMut<'w, SpawnedPrimitives>,
}

impl Spawner<'_, '_> {
    /// Spawns `prims` as entities, numbered after those spawned before.
    pub fn spawn(&mut self, prims: Vec<DebugPrimitive>) {
        let first = self.spawned.0;
        self.spawned.0 += prims.len() as u32;
        self.commands.spawn_batch(
            prims
                .into_iter()
                .zip(first..)
                .map(|(p, n)| (DebugOrder(n), p))
                .collect::<Vec<_>>(),
        );
    }
}

/// Size of the scene: the diagonal of the geometry's bounds (1 when empty).
pub fn scene_size(geometry: &SceneGeometry) -> f32 {
    let b = geometry.bounds();
    if b.is_empty() {
        1.0
    } else {
        b.extent().length().max(1e-6)
    }
}

/// Where a logged ray's segment ends: its hit, or a scene-sized distance on a miss.
pub fn ray_end(r: &RayRecord, miss_length: f32) -> Vec3 {
    match &r.hit {
        Some((_, s)) => s.p,
        None => r.ray.origin + r.ray.dir.normalize_or(Vec3::Z) * miss_length,
    }
}

/// Colour of reflection level `depth` (1 = first) of at most `max_depth`.
pub fn reflection_color(depth: u32, max_depth: u32) -> Vec3 {
    let t = (depth.saturating_sub(1)) as f32 / (max_depth.max(2) - 1) as f32;
    REFLECTION_FIRST.lerp(REFLECTION_DEEP, t.clamp(0.0, 1.0))
}

/// Colour of BVH depth `depth` in a tree of `tree_depth` levels (red at the root, green deepest).
pub fn bvh_color(depth: u32, tree_depth: u32) -> Vec3 {
    let t = depth as f32 / tree_depth.saturating_sub(1).max(1) as f32;
    BVH_SHALLOW.lerp(BVH_DEEP, t.clamp(0.0, 1.0))
}

/// A colour scaled to display range (largest component at most 1).
pub(super) fn displayable(c: Vec3) -> Vec3 {
    let m = c.max_element();
    if m > 1.0 { c / m } else { c.max(Vec3::ZERO) }
}

pub(super) fn prim(feature: Feature, color: Vec3, shape: Shape, values: Values) -> DebugPrimitive {
    DebugPrimitive {
        feature,
        color,
        shape,
        values,
    }
}

pub(super) fn hit_values(what: &'static str, r: &RayRecord) -> Values {
    let (t, bary, index) = match &r.hit {
        Some((h, _)) => (
            Some(h.t),
            (h.kind == PrimKind::Triangle).then_some(h.bary),
            Some(h.prim),
        ),
        None => (None, None, None),
    };
    Values {
        what,
        sample: Some(r.sample),
        depth: Some(r.depth),
        t,
        barycentrics: bary,
        index,
        radiance: Some(r.radiance),
        ..Default::default()
    }
}

/// Whether record `i` spawned a child along `branch` (same sample, next depth, child branch id).
pub(super) fn has_child(log: &DebugTrace, i: usize, branch: Branch) -> bool {
    let r = &log.rays[i];
    let child = branch.child_of(r.path);
    log.rays[i + 1..]
        .iter()
        .any(|c| c.sample == r.sample && c.depth == r.depth + 1 && c.path == child)
}
