//! The trace log: what the render's own tracing systems did for the debugged pixel.
//!
//! The systems of [`crate::trace::wavefront`] write here only when a [`DebugTrace`]
//! resource exists (an `Option<ResMut<DebugTrace>>` parameter), so a normal render
//! neither allocates nor records anything. The emitters of [`super::emit`] read it.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::accel::{Ray, TraversalVisitor};
use crate::trace::geometry::{GeometryVisitor, Hit, PrimKind};
use crate::trace::lights::LightSample;
use crate::trace::surface::Surface;
use crate::trace::wavefront::QueuedRay;

/// How a traced ray came to be, read from its branch id in the sample's ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RayKind {
    /// From the camera (branch 0).
    Camera,
    /// A reflection (odd branch ids: 2k + 1).
    Reflection,
    /// A pass-through ray (even non-zero branch ids: 2k + 2).
    PassThrough,
}

impl RayKind {
    /// The kind of the ray with branch id `path` (see `QueuedRay::path`).
    pub fn of_path(path: u32) -> RayKind {
        match path {
            0 => RayKind::Camera,
            p if p % 2 == 1 => RayKind::Reflection,
            _ => RayKind::PassThrough,
        }
    }
}

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

/// A BVH node or primitive as a traversal met it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Visit {
    /// Which hierarchy (triangles or spheres).
    pub kind: PrimKind,
    /// Node index (for nodes) or primitive index (for primitive tests).
    pub index: u32,
    /// Depth of the node (root 0); 0 for primitive tests.
    pub depth: u32,
}

/// Records a traversal: every node entered and every primitive tested, in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TraversalLog {
    /// Nodes whose boxes the ray entered.
    pub nodes: Vec<Visit>,
    /// Primitives tested.
    pub prims: Vec<Visit>,
    current: PrimKind,
}

impl Default for TraversalLog {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            prims: Vec::new(),
            current: PrimKind::Triangle,
        }
    }
}

impl TraversalVisitor for TraversalLog {
    fn visit_node(&mut self, node: u32, depth: u32) {
        self.nodes.push(Visit {
            kind: self.current,
            index: node,
            depth,
        });
    }
    fn test_prim(&mut self, prim: u32) {
        self.prims.push(Visit {
            kind: self.current,
            index: prim,
            depth: 0,
        });
    }
}

impl GeometryVisitor for TraversalLog {
    fn begin_hierarchy(&mut self, kind: PrimKind) {
        self.current = kind;
    }
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

/// The trace log of the debugged pixel. Its presence switches recording on.
#[derive(Resource, Clone, Debug, Default)]
pub struct DebugTrace {
    /// The pixel's camera samples.
    pub camera_samples: Vec<CameraSampleRecord>,
    /// Every ray traced, in trace order (by sample, then depth, then queue order).
    pub rays: Vec<RayRecord>,
    /// Every light sample evaluated, in trace order.
    pub lights: Vec<LightSampleRecord>,
    sample: u32,
    depth_start: usize,
    light_start: usize,
}

impl DebugTrace {
    /// Starts a new sample (called by `generate_camera_samples`).
    pub fn record_camera_samples(
        &mut self,
        sample: u32,
        rays: &[QueuedRay],
        offset: impl Fn(u32) -> Vec2,
    ) {
        self.sample = sample;
        for q in rays {
            self.camera_samples.push(CameraSampleRecord {
                sample,
                offset: offset(q.slot),
                ray: q.ray,
            });
        }
    }

    /// Records the rays of one depth level with their hits (called by `intersect_rays`).
    pub fn record_rays(
        &mut self,
        depth: u32,
        rays: &[QueuedRay],
        hits: impl IntoIterator<Item = (Option<(Hit, Surface)>, TraversalLog)>,
    ) {
        self.depth_start = self.rays.len();
        for (q, (hit, traversal)) in rays.iter().zip(hits) {
            self.rays.push(RayRecord {
                sample: self.sample,
                depth,
                path: q.path,
                ray: q.ray,
                weight: q.weight,
                hit,
                traversal,
                radiance: Vec3::ZERO,
            });
        }
    }

    /// Starts recording the light samples of one depth level (called by `shade_hits`).
    pub fn begin_light_samples(&mut self) {
        self.light_start = self.lights.len();
    }

    /// Records one light sample of queued ray `ray` of the current depth.
    pub fn record_light_sample(
        &mut self,
        ray: usize,
        light: LightSample,
        contribution: Vec3,
        shadow_ray: Option<u32>,
    ) {
        self.lights.push(LightSampleRecord {
            ray: (self.depth_start + ray) as u32,
            light,
            contribution,
            shadow_ray,
            // Without a shadow ray the contribution arrives whole (shadows off) or is zero.
            arrived: contribution,
        });
    }

    /// Records what each shadow ray of the current depth let through (called by `trace_shadow_rays`).
    pub fn record_shadow_results(&mut self, arrived: &[Vec3]) {
        for l in &mut self.lights[self.light_start..] {
            if let Some(c) = l.shadow_ray.and_then(|s| arrived.get(s as usize)) {
                l.arrived = *c;
            }
        }
    }

    /// Records the radiance each ray of the current depth gathered (called by `gather_radiance`).
    pub fn record_radiance(&mut self, radiance: &[Vec3]) {
        for (r, c) in self.rays[self.depth_start..].iter_mut().zip(radiance) {
            r.radiance = *c;
        }
    }
}
