//! The BVH: the traversal of the first camera ray, and whole levels of the hierarchy.

use std::collections::HashSet;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::{BVH_FINAL, BVH_TESTED, Spawner, bvh_color, hit_values, prim, scene_size};
use crate::accel::Bvh;
use crate::debug::DebugRequest;
use crate::debug::log::DebugTrace;
use crate::debug::primitives::{Feature, Shape, Values};
use crate::trace::geometry::{PrimKind, SceneGeometry};
use crate::trace::wavefront::RayKind;

/// The hierarchy a visit refers to.
fn bvh_of(geometry: &SceneGeometry, kind: PrimKind) -> &Bvh {
    match kind {
        PrimKind::Triangle => &geometry.tri_bvh,
        PrimKind::Sphere => &geometry.sphere_bvh,
    }
}

/// BVH: for the first camera ray, every node box the traversal entered coloured by
/// depth, the tested triangles' vertices, the final leaf and hit triangle in white and
/// the hit point.
pub fn emit_bvh(mut spawner: Spawner, log: Res<DebugTrace>, geometry: Res<SceneGeometry>) {
    let Some(r) = log.rays.iter().find(|r| r.kind() == RayKind::Camera) else {
        return;
    };
    let size = scene_size(&geometry);
    let hit = r.hit.as_ref().map(|(h, _)| h);
    let mut out = Vec::new();
    for v in &r.traversal.nodes {
        let bvh = bvh_of(&geometry, v.kind);
        let node = &bvh.nodes[v.index as usize];
        let b = node.bounds();
        let holds_hit = hit.is_some_and(|h| {
            h.kind == v.kind
                && h.instance.is_none()
                && node.is_leaf()
                && bvh.prim_indices[node.offset as usize..(node.offset + node.count) as usize]
                    .contains(&h.prim)
        });
        let (color, what) = if holds_hit {
            (BVH_FINAL, "final bvh leaf")
        } else {
            (bvh_color(v.depth, bvh.depth()), "bvh node")
        };
        out.push(prim(
            Feature::Bvh,
            color,
            Shape::Box {
                min: b.min,
                max: b.max,
            },
            Values {
                what,
                depth: Some(v.depth),
                index: Some(v.index),
                ..Default::default()
            },
        ));
    }
    let mut seen = HashSet::new();
    for v in &r.traversal.prims {
        let points: Vec<Vec3> = match v.kind {
            PrimKind::Triangle => geometry.positions(v.index).to_vec(),
            PrimKind::Sphere => vec![geometry.spheres[v.index as usize].center],
        };
        for p in points {
            if seen.insert(p.to_array().map(f32::to_bits)) {
                out.push(prim(
                    Feature::Bvh,
                    BVH_TESTED,
                    Shape::Marker {
                        center: p,
                        radius: size * 0.004,
                    },
                    Values {
                        what: "tested primitive",
                        index: Some(v.index),
                        ..Default::default()
                    },
                ));
            }
        }
    }
    if let Some((h, s)) = &r.hit {
        if h.kind == PrimKind::Triangle {
            let [a, b, c] = geometry.triangle(h).positions;
            for (p, q) in [(a, b), (b, c), (c, a)] {
                out.push(prim(
                    Feature::Bvh,
                    BVH_FINAL,
                    Shape::Segment { a: p, b: q },
                    hit_values("hit triangle", r),
                ));
            }
        }
        out.push(prim(
            Feature::Bvh,
            BVH_TESTED,
            Shape::Marker {
                center: s.p,
                radius: size * 0.008,
            },
            hit_values("bvh hit point", r),
        ));
    }
    spawner.spawn(out);
}

/// Every node at level `--bvh-level` of each hierarchy, for the whole scene.
pub fn emit_bvh_level(
    mut spawner: Spawner,
    request: Res<DebugRequest>,
    geometry: Res<SceneGeometry>,
) {
    let Some(level) = request.bvh_level else {
        return;
    };
    let mut out = Vec::new();
    for bvh in [&geometry.tri_bvh, &geometry.sphere_bvh] {
        let tree_depth = bvh.depth();
        for (index, depth) in node_depths(bvh) {
            if depth != level {
                continue;
            }
            let b = bvh.nodes[index as usize].bounds();
            out.push(prim(
                Feature::Bvh,
                bvh_color(depth, tree_depth),
                Shape::Box {
                    min: b.min,
                    max: b.max,
                },
                Values {
                    what: "bvh level",
                    depth: Some(depth),
                    index: Some(index),
                    ..Default::default()
                },
            ));
        }
    }
    spawner.spawn(out);
}

/// Every node of `bvh` with its depth, in depth-first order.
pub fn node_depths(bvh: &Bvh) -> Vec<(u32, u32)> {
    let mut out = Vec::with_capacity(bvh.nodes.len());
    let mut stack = if bvh.nodes.is_empty() {
        vec![]
    } else {
        vec![(0u32, 0u32)]
    };
    while let Some((i, d)) = stack.pop() {
        out.push((i, d));
        let n = &bvh.nodes[i as usize];
        if !n.is_leaf() {
            stack.push((n.offset, d + 1));
            stack.push((i + 1, d + 1));
        }
    }
    out
}
