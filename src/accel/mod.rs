//! Acceleration structures and ray/primitive intersection: pure geometry.
//!
//! Everything here takes slices of primitives (boxes, vertex positions, sphere centres)
//! and knows nothing of materials, settings, statistics or the `World`; the scene's
//! tables and the systems that build them are in [`crate::trace::geometry`].
//!
//! - [`aabb`]: axis-aligned boxes and the robust slab test (Ize 2013).
//! - [`triangle`]: watertight ray/triangle intersection (Woop, Benthin, Wald 2013).
//! - [`sphere`]: precise ray/sphere intersection (Haines et al., Ray Tracing Gems ch. 7).
//! - [`bvh`] and [`build`]: a flat depth-first BVH with binned-SAH and median builders.
//! - [`traverse`]: closest-hit and any-hit traversal of that BVH.
//! - [`wide`]: that BVH collapsed to 8-wide nodes with triangles in leaf order, for the render.
//! - `wide_collapse`: the choice of the wide nodes and leaves, by a surface-area cost.
//! - `wide_query`: the wide BVH's closest-hit and any-hit queries, one clone per instruction set.
//! - `wide_packet`: the queries for packets of up to eight rays, one ray per SIMD lane.
//! - `ray_lanes`: a packet's rays side by side ([`RayLanes`]), as those queries read them,
//!   and their closest hits ([`HitLanes`]), as the closest-hit query keeps them.
//! - [`huge`]: `HugeVec`, the BVHs' and their builds' arrays in huge-page-advised memory
//!   when large.
//! - [`leaf`]: the wide BVH's leaf triangles in SIMD groups, with a vectorised prefilter.
//! - [`instance`]: a two-level BVH, one wide BVH per mesh shared by its instances.

use glam::Vec3;

pub mod aabb;
pub mod build;
pub mod bvh;
pub mod huge;
pub mod instance;
pub mod leaf;
mod ray_lanes;
mod segment_box;
pub mod sphere;
pub mod traverse;
pub mod triangle;
pub mod wide;
mod wide_collapse;
pub mod wide_node;
mod wide_packet;
mod wide_query;

pub use aabb::Aabb;
pub use bvh::{Bvh, BvhNode, SplitMethod};
pub use instance::{Instance, TwoLevelBvh};
pub use ray_lanes::{HitLanes, RayLanes};
pub use sphere::intersect_sphere;
pub use traverse::{TraversalStats, TraversalVisitor};
pub use triangle::{RayShear, TriangleHit, intersect_triangle, intersect_triangle_sheared};
pub use wide::WideBvh;
pub use wide_packet::{PACKET, PacketHits};

/// A ray; `dir` need not be unit length (t is in units of `dir`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (t = 0).
    pub origin: Vec3,
    /// Direction; the point at parameter t is `origin + t * dir`.
    pub dir: Vec3,
}

impl Ray {
    /// Creates a ray from an origin and a direction.
    pub fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray { origin, dir }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// Ize's enlargement of a box's exit distance, so that rounding never culls a box the
/// exact ray meets; the traversals also keep it when comparing a box with a hit.
pub(crate) const BOX_MARGIN: f32 = 1.0 + 2.0 * gamma(3);

/// Bound on the relative rounding error of `n` chained f32 operations (PBRT's gamma(n)).
pub const fn gamma(n: u32) -> f32 {
    // Unit roundoff is half of f32::EPSILON (round-to-nearest).
    let u = f32::EPSILON * 0.5;
    (n as f32 * u) / (1.0 - n as f32 * u)
}
