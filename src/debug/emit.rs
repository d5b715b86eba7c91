//! Emitter systems: one per feature, each turning the trace log into debug-primitive
//! entities. They run only in a debug run, and only for features that are both on in
//! the scene and asked for (see [`super::debug_emit_schedule`]).

use std::collections::HashSet;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::DebugRequest;
use super::log::{DebugTrace, RayKind, RayRecord};
use super::primitives::{DebugPrimitive, Feature, Shape, Values};
use crate::accel::Bvh;
use crate::film::Film;
use crate::scene::{PixelSampling, Settings};
use crate::trace::geometry::{PrimKind, SceneGeometry};
use crate::trace::lights::Lights;
use crate::trace::materials::Materials;

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
fn displayable(c: Vec3) -> Vec3 {
    let m = c.max_element();
    if m > 1.0 { c / m } else { c.max(Vec3::ZERO) }
}

fn prim(feature: Feature, color: Vec3, shape: Shape, values: Values) -> DebugPrimitive {
    DebugPrimitive {
        feature,
        color,
        shape,
        values,
    }
}

fn hit_values(what: &'static str, r: &RayRecord) -> Values {
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

/// Whether record `i` spawned a child of `kind` (same sample, next depth, child branch id).
fn has_child(log: &DebugTrace, i: usize, kind: RayKind) -> bool {
    let r = &log.rays[i];
    let branch = match kind {
        RayKind::Reflection => r.path.wrapping_mul(2).wrapping_add(1),
        RayKind::PassThrough => r.path.wrapping_mul(2).wrapping_add(2),
        RayKind::Camera => return false,
    };
    log.rays[i + 1..]
        .iter()
        .any(|c| c.sample == r.sample && c.depth == r.depth + 1 && c.path == branch)
}

/// The pixel: each camera ray, its first hit and the pixel's colour as a caption.
pub fn emit_pixel(
    mut commands: Commands,
    log: Res<DebugTrace>,
    request: Res<DebugRequest>,
    geometry: Res<SceneGeometry>,
    film: Res<Film>,
) {
    let size = scene_size(&geometry);
    let mut out = Vec::new();
    for r in log.rays.iter().filter(|r| r.kind() == RayKind::Camera) {
        out.push(prim(
            Feature::Pixel,
            CAMERA_RAY,
            Shape::Segment {
                a: r.ray.origin,
                b: ray_end(r, size),
            },
            hit_values("camera ray", r),
        ));
        if let Some((_, s)) = &r.hit {
            out.push(prim(
                Feature::Pixel,
                FIRST_HIT,
                Shape::Marker {
                    center: s.p,
                    radius: size * 0.006,
                },
                hit_values("first hit", r),
            ));
        }
    }
    let [x, y] = request.pixel;
    let c = film.pixel(x, y);
    out.push(prim(
        Feature::Pixel,
        displayable(c),
        Shape::Label {
            at: None,
            text: format!(
                "pixel ({x}, {y}) = ({:.3}, {:.3}, {:.3}), {} samples",
                c.x,
                c.y,
                c.z,
                log.camera_samples.len()
            ),
        },
        Values {
            what: "pixel colour",
            radiance: Some(c),
            ..Default::default()
        },
    ));
    commands.spawn_batch(out);
}

/// Reflections: each reflection level in its own colour, the normal at each bounce point.
pub fn emit_reflections(
    mut commands: Commands,
    log: Res<DebugTrace>,
    settings: Res<Settings>,
    geometry: Res<SceneGeometry>,
) {
    let size = scene_size(&geometry);
    let mut out = Vec::new();
    for (i, r) in log.rays.iter().enumerate() {
        if r.kind() == RayKind::Reflection {
            out.push(prim(
                Feature::Reflections,
                reflection_color(r.depth, settings.max_depth),
                Shape::Segment {
                    a: r.ray.origin,
                    b: ray_end(r, size),
                },
                hit_values("reflection ray", r),
            ));
        }
        if let Some((_, s)) = &r.hit
            && has_child(&log, i, RayKind::Reflection)
        {
            out.push(prim(
                Feature::Reflections,
                NORMAL,
                Shape::Segment {
                    a: s.p,
                    b: s.p + s.n * size * 0.08,
                },
                hit_values("normal at reflection", r),
            ));
        }
    }
    commands.spawn_batch(out);
}

/// Transparency: pass-through segments and hit markers in the colour of what they hit,
/// and at each transparent surface the normal: first part in kd, next in grey by alpha.
pub fn emit_transparency(
    mut commands: Commands,
    log: Res<DebugTrace>,
    settings: Res<Settings>,
    materials: Res<Materials>,
    geometry: Res<SceneGeometry>,
) {
    let size = scene_size(&geometry);
    let mut out = Vec::new();
    for (i, r) in log.rays.iter().enumerate() {
        let hit_color = match &r.hit {
            Some((_, s)) => materials.kd_at(s.material, s.uv),
            None => settings.background,
        };
        let spawned = has_child(&log, i, RayKind::PassThrough);
        if r.kind() != RayKind::PassThrough && !spawned {
            continue;
        }
        if r.kind() == RayKind::PassThrough {
            out.push(prim(
                Feature::Transparency,
                displayable(hit_color),
                Shape::Segment {
                    a: r.ray.origin,
                    b: ray_end(r, size),
                },
                hit_values("pass-through ray", r),
            ));
        }
        let Some((_, s)) = &r.hit else { continue };
        let alpha = materials.list[s.material as usize].alpha;
        out.push(prim(
            Feature::Transparency,
            displayable(hit_color),
            Shape::Marker {
                center: s.p,
                radius: size * 0.005,
            },
            Values {
                alpha: Some(alpha),
                ..hit_values("transparency hit", r)
            },
        ));
        if spawned {
            let len = size * 0.05;
            let mid = s.p + s.n * len;
            out.push(prim(
                Feature::Transparency,
                displayable(hit_color),
                Shape::Segment { a: s.p, b: mid },
                Values {
                    alpha: Some(alpha),
                    ..hit_values("normal (kd part)", r)
                },
            ));
            out.push(prim(
                Feature::Transparency,
                Vec3::splat(alpha),
                Shape::Segment {
                    a: mid,
                    b: mid + s.n * len,
                },
                Values {
                    alpha: Some(alpha),
                    ..hit_values("normal (alpha part)", r)
                },
            ));
        }
    }
    commands.spawn_batch(out);
}

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
pub fn emit_bvh(mut commands: Commands, log: Res<DebugTrace>, geometry: Res<SceneGeometry>) {
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
            PrimKind::Triangle => geometry.tri_positions[v.index as usize].to_vec(),
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
            let [a, b, c] = geometry.tri_positions[h.prim as usize];
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
    commands.spawn_batch(out);
}

/// Every node at level `--bvh-level` of each hierarchy, for the whole scene.
pub fn emit_bvh_level(
    mut commands: Commands,
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
    commands.spawn_batch(out);
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

/// Textures: for each textured hit of the first sample, the texture as a panel with the
/// looked-up texel (nearest) or four texels (bilinear) marked, and the hit in that colour.
pub fn emit_textures(
    mut commands: Commands,
    log: Res<DebugTrace>,
    materials: Res<Materials>,
    geometry: Res<SceneGeometry>,
) {
    let size = scene_size(&geometry);
    let mut out = Vec::new();
    let first = log.rays.first().map_or(0, |r| r.sample);
    for r in log.rays.iter().filter(|r| r.sample == first) {
        let Some((_, s)) = &r.hit else { continue };
        let m = &materials.list[s.material as usize];
        let Some(ti) = m.texture else { continue };
        let Some(tex) = materials.textures.get(ti as usize) else {
            continue;
        };
        let texels: Vec<([u32; 2], f32)> = if materials.bilinear {
            tex.bilinear_texels(s.uv, m.wrap)
                .iter()
                .map(|&((i, j), w)| ([i, j], w))
                .collect()
        } else {
            let (i, j) = tex.nearest_texel(s.uv, m.wrap);
            vec![([i, j], 1.0)]
        };
        let kd = materials.kd_at(s.material, s.uv);
        let values = Values {
            uv: Some(s.uv),
            ..hit_values("texture lookup", r)
        };
        out.push(prim(
            Feature::Textures,
            displayable(kd),
            Shape::Marker {
                center: s.p,
                radius: size * 0.006,
            },
            values.clone(),
        ));
        out.push(prim(
            Feature::Textures,
            displayable(kd),
            Shape::TexturePanel {
                texture: ti,
                size: [tex.width, tex.height],
                uv: s.uv,
                texels,
            },
            values,
        ));
    }
    commands.spawn_batch(out);
}

/// Lights: a segment from each light sample to the shaded point, in the light's colour
/// if it arrives and black if blocked (or facing away); the sample points on area
/// lights; and the lights themselves.
pub fn emit_lights(
    mut commands: Commands,
    log: Res<DebugTrace>,
    lights: Res<Lights>,
    settings: Res<Settings>,
    geometry: Res<SceneGeometry>,
) {
    let size = scene_size(&geometry);
    // Area light samples carry colour / sample count; show the light's own colour.
    let per_sample = settings.shadow_samples.max(1) as f32;
    let mut out = Vec::new();
    let points = lights.points.len() as u32;
    for p in &lights.points {
        out.push(prim(
            Feature::Lights,
            displayable(p.color),
            Shape::Marker {
                center: p.position,
                radius: size * 0.012,
            },
            Values {
                what: "point light",
                ..Default::default()
            },
        ));
    }
    for s in &lights.segments {
        out.push(prim(
            Feature::Lights,
            displayable(s.color0 + s.color1),
            Shape::Segment {
                a: s.endpoint0,
                b: s.endpoint1,
            },
            Values {
                what: "segment light",
                ..Default::default()
            },
        ));
    }
    for q in &lights.parallelograms {
        let c = [
            q.v0,
            q.v0 + q.edge01,
            q.v0 + q.edge01 + q.edge02,
            q.v0 + q.edge02,
        ];
        for k in 0..4 {
            out.push(prim(
                Feature::Lights,
                displayable(q.color0 + q.color1 + q.color2 + q.color3),
                Shape::Segment {
                    a: c[k],
                    b: c[(k + 1) % 4],
                },
                Values {
                    what: "parallelogram light",
                    ..Default::default()
                },
            ));
        }
    }
    for l in &log.lights {
        let r = &log.rays[l.ray as usize];
        let Some((_, s)) = &r.hit else { continue };
        let visible = l.arrived != Vec3::ZERO;
        let facing = l.contribution != Vec3::ZERO;
        let values = Values {
            what: if facing {
                "light sample"
            } else {
                "light sample (faces away)"
            },
            sample: Some(r.sample),
            depth: Some(r.depth),
            light: Some(l.light.light),
            visible: Some(visible),
            arrived: Some(l.arrived),
            ..Default::default()
        };
        let light_color = if l.light.light >= points {
            l.light.color * per_sample
        } else {
            l.light.color
        };
        let color = if visible {
            displayable(light_color)
        } else {
            BLOCKED
        };
        out.push(prim(
            Feature::Lights,
            color,
            Shape::Segment {
                a: l.light.position,
                b: s.p,
            },
            values.clone(),
        ));
        if l.light.light >= points {
            out.push(prim(
                Feature::Lights,
                displayable(light_color),
                Shape::Marker {
                    center: l.light.position,
                    radius: size * 0.004,
                },
                Values {
                    what: "area light sample",
                    ..values
                },
            ));
        }
    }
    commands.spawn_batch(out);
}

/// Multisampling: the pixel's sample offsets on its grid, with strata when stratified.
pub fn emit_samples(mut commands: Commands, log: Res<DebugTrace>, settings: Res<Settings>) {
    let strata = match settings.pixel_sampling {
        PixelSampling::Uniform => None,
        PixelSampling::Stratified => {
            Some((log.camera_samples.len() as f64).sqrt().round().max(1.0) as u32)
        }
    };
    let points = log.camera_samples.iter().map(|s| s.offset).collect();
    commands.spawn(prim(
        Feature::Samples,
        SAMPLE_POINT,
        Shape::SampleGrid { strata, points },
        Values {
            what: match strata {
                Some(_) => "stratified samples",
                None => "uniform samples",
            },
            ..Default::default()
        },
    ));
}
