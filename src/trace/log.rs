//! The trace log: what only the hot loops themselves can see, kept when a [`TraceLog`]
//! resource exists. Everything else a debug run wants it reads from the [`Wavefront`]
//! after the stage that wrote it.
//!
//! The loops are written once, generic over an observer: [`HitObserver`] for each
//! ray's closest-hit query, [`LightObserver`] for the light samples of shading. `()`
//! observes nothing and compiles away, so a render pays nothing for the log.
//!
//! [`Wavefront`]: super::wavefront::Wavefront

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::geometry::{GeometryVisitor, Hit, PrimKind};
use super::lights::LightSample;
use crate::accel::TraversalVisitor;

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

/// What a closest-hit query can keep besides its answer: nothing (`()`) in a render.
pub trait HitObserver: GeometryVisitor + Default + Send {
    /// Told the closest hit the query found.
    fn closest(&mut self, _hit: Option<&Hit>) {}
}

impl HitObserver for () {}

/// One ray's closest-hit query as the trace log keeps it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayTrace {
    /// Every node entered and primitive tested.
    pub traversal: TraversalLog,
    /// The closest hit.
    pub hit: Option<Hit>,
}

impl TraversalVisitor for RayTrace {
    fn visit_node(&mut self, node: u32, depth: u32) {
        self.traversal.visit_node(node, depth);
    }
    fn test_prim(&mut self, prim: u32) {
        self.traversal.test_prim(prim);
    }
}

impl GeometryVisitor for RayTrace {
    fn begin_hierarchy(&mut self, kind: PrimKind) {
        self.traversal.begin_hierarchy(kind);
    }
}

impl HitObserver for RayTrace {
    fn closest(&mut self, hit: Option<&Hit>) {
        self.hit = hit.copied();
    }
}

/// One light sample as shading saw it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleSeen {
    /// Index of the shaded ray in its depth's queue.
    pub ray: u32,
    /// The light sample (position, colour, light index).
    pub light: LightSample,
    /// Unoccluded contribution (zero when the light is behind the surface).
    pub contribution: Vec3,
    /// Index of its shadow ray in its depth's queue, when one was cast.
    pub shadow_ray: Option<u32>,
}

/// What shading can keep of its light samples: nothing (`()`) in a render. Each chunk
/// of rays has its own observer; they are joined in chunk order.
pub trait LightObserver: Default + Send {
    /// Told one light sample of ray `ray`; `shadow_ray` indexes the chunk's shadow rays.
    fn seen(
        &mut self,
        _ray: u32,
        _light: LightSample,
        _contribution: Vec3,
        _shadow_ray: Option<u32>,
    ) {
    }
    /// Appends a later chunk's samples, whose shadow rays follow the first `shadow_offset`.
    fn join(&mut self, _later: Self, _shadow_offset: u32) {}
}

impl LightObserver for () {}

impl LightObserver for Vec<LightSampleSeen> {
    fn seen(&mut self, ray: u32, light: LightSample, contribution: Vec3, shadow_ray: Option<u32>) {
        self.push(LightSampleSeen {
            ray,
            light,
            contribution,
            shadow_ray,
        });
    }
    fn join(&mut self, later: Self, shadow_offset: u32) {
        self.extend(later.into_iter().map(|l| LightSampleSeen {
            shadow_ray: l.shadow_ray.map(|s| s + shadow_offset),
            ..l
        }));
    }
}

/// The trace log of the current depth. Its presence switches recording on.
#[derive(Resource, Clone, Debug, Default)]
pub struct TraceLog {
    /// Each ray's closest-hit query, in queue order (written by `intersect_rays`).
    pub rays: Vec<RayTrace>,
    /// Every light sample evaluated, in queue order (written by `shade_hits`).
    pub light_samples: Vec<LightSampleSeen>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(ray: u32, shadow_ray: Option<u32>) -> LightSampleSeen {
        LightSampleSeen {
            ray,
            light: LightSample {
                position: Vec3::ZERO,
                color: Vec3::ONE,
                light: 0,
            },
            contribution: Vec3::ONE,
            shadow_ray,
        }
    }

    #[test]
    fn joined_chunks_index_the_joined_shadow_queue() {
        let mut first = vec![seen(0, Some(0)), seen(0, None), seen(1, Some(1))];
        let later = vec![seen(2, Some(0)), seen(3, None), seen(3, Some(1))];
        LightObserver::join(&mut first, later, 2);
        let shadow: Vec<_> = first.iter().map(|l| l.shadow_ray).collect();
        assert_eq!(shadow, [Some(0), None, Some(1), Some(2), None, Some(3)]);
        let rays: Vec<_> = first.iter().map(|l| l.ray).collect();
        assert_eq!(rays, [0, 0, 1, 2, 3, 3]);
    }
}
