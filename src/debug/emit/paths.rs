//! The pixel's ray paths: camera rays and first hits, reflections, transparency.

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::{
    CAMERA_RAY, FIRST_HIT, NORMAL, Spawner, displayable, has_child, hit_values, prim, ray_end,
    reflection_color, scene_size,
};
use crate::debug::DebugRequest;
use crate::debug::log::DebugTrace;
use crate::debug::primitives::{Feature, Shape, Values};
use crate::film::Film;
use crate::scene::Settings;
use crate::trace::geometry::SceneGeometry;
use crate::trace::materials::Materials;
use crate::trace::wavefront::{Branch, RayKind};

/// The pixel: each camera ray, its first hit and the pixel's colour as a caption.
pub fn emit_pixel(
    mut spawner: Spawner,
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
    spawner.spawn(out);
}

/// Reflections: each reflection level in its own colour, the normal at each bounce point.
pub fn emit_reflections(
    mut spawner: Spawner,
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
            && has_child(&log, i, Branch::Reflection)
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
    spawner.spawn(out);
}

/// Transparency: pass-through segments and hit markers in the colour of what they hit,
/// and at each transparent surface the normal: first part in kd, next in grey by alpha.
pub fn emit_transparency(
    mut spawner: Spawner,
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
        let spawned = has_child(&log, i, Branch::PassThrough);
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
    spawner.spawn(out);
}
