//! The debug trace: what the render's own tracing systems did for the debugged pixel,
//! over all its samples and depths.
//!
//! The recorders of [`super::record`] fill it from the wavefront and from trace's
//! [`TraceLog`](crate::trace::log::TraceLog), after the stages they watch; the emitters
//! of [`super::emit`] read it.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::accel::Ray;
use crate::trace::geometry::Hit;
use crate::trace::lights::LightSample;
use crate::trace::log::{LightSampleSeen, RayTrace, TraversalLog};
use crate::trace::surface::Surface;
use crate::trace::wavefront::{QueuedRay, RayKind, SurfaceQueue};

/// One camera sample of the pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSampleRecord {
    /// Sample index.
    pub sample: u32,
    /// Offset within the pixel, in [0, 1)^2.
    pub offset: Vec2,
    /// The camera ray.
    pub ray: Ray,
}

/// One ray traced for the pixel, with what it hit.
#[derive(Clone, Debug, PartialEq)]
pub struct RayRecord {
    /// Sample index it belongs to.
    pub sample: u32,
    /// Depth (camera rays 0).
    pub depth: u32,
    /// Branch id in the sample's ray tree.
    pub path: u32,
    /// The ray.
    pub ray: Ray,
    /// Its throughput weight.
    pub weight: Vec3,
    /// The closest hit and its shading point.
    pub hit: Option<(Hit, Surface)>,
    /// The BVH traversal of its closest-hit query.
    pub traversal: TraversalLog,
    /// Radiance it added to its sample at this depth (weighted direct light or background).
    pub radiance: Vec3,
}

impl RayRecord {
    /// Camera, reflection or pass-through.
    pub fn kind(&self) -> RayKind {
        RayKind::of_path(self.path)
    }
}

/// One light sample seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleRecord {
    /// Index into [`DebugTrace::rays`] of the ray whose hit is shaded.
    pub ray: u32,
    /// The light sample (position, colour, light index).
    pub light: LightSample,
    /// Unoccluded contribution (zero when the light is behind the surface).
    pub contribution: Vec3,
    /// Index of its shadow ray within its depth's queue, when one was cast.
    pub shadow_ray: Option<u32>,
    /// What arrived: the contribution times visibility (or transparent tint).
    pub arrived: Vec3,
}

/// The trace of the debugged pixel, filled by the recorders.
#[derive(Resource, Clone, Debug, Default)]
pub struct DebugTrace {
    /// The pixel's camera samples.
    pub camera_samples: Vec<CameraSampleRecord>,
    /// Every ray traced, in trace order (by sample, then depth, then queue order).
    pub rays: Vec<RayRecord>,
    /// Every light sample evaluated, in trace order.
    pub lights: Vec<LightSampleRecord>,
    depth_start: usize,
    light_start: usize,
}

impl DebugTrace {
    /// Records the camera samples of one pass, each with its offset within the pixel.
    pub fn record_camera_samples(&mut self, sample: u32, rays: &[QueuedRay], offsets: &[Vec2]) {
        for (q, offset) in rays.iter().zip(offsets) {
            self.camera_samples.push(CameraSampleRecord {
                sample,
                offset: *offset,
                ray: q.ray,
            });
        }
    }

    /// Records the rays of one depth level with their hits and traversals.
    pub fn record_rays(
        &mut self,
        sample: u32,
        depth: u32,
        rays: &[QueuedRay],
        hits: &SurfaceQueue,
        traces: Vec<RayTrace>,
    ) {
        self.depth_start = self.rays.len();
        for ((q, surface), trace) in rays.iter().zip(hits.iter()).zip(traces) {
            self.rays.push(RayRecord {
                sample,
                depth,
                path: q.path,
                ray: q.ray,
                weight: q.weight,
                hit: trace.hit.zip(surface),
                traversal: trace.traversal,
                radiance: Vec3::ZERO,
            });
        }
    }

    /// Records the light samples shading saw at the current depth.
    pub fn record_light_samples(&mut self, seen: &[LightSampleSeen]) {
        self.light_start = self.lights.len();
        for l in seen {
            self.lights.push(LightSampleRecord {
                ray: self.depth_start as u32 + l.ray,
                light: l.light,
                contribution: l.contribution,
                shadow_ray: l.shadow_ray,
                // Without a shadow ray the contribution arrives whole (shadows off) or is zero.
                arrived: l.contribution,
            });
        }
    }

    /// Records what each shadow ray of the current depth let through.
    pub fn record_shadow_results(&mut self, arrived: &[Vec3]) {
        for l in &mut self.lights[self.light_start..] {
            if let Some(c) = l.shadow_ray.and_then(|s| arrived.get(s as usize)) {
                l.arrived = *c;
            }
        }
    }

    /// Records the radiance each ray of the current depth gathered.
    pub fn record_radiance(&mut self, radiance: &[Vec3]) {
        for (r, c) in self.rays[self.depth_start..].iter_mut().zip(radiance) {
            r.radiance = *c;
        }
    }
}
