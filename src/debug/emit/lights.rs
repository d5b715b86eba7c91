//! Lights: the lights, their samples and what of each reaches the shaded points.

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::{BLOCKED, Spawner, displayable, prim, scene_size};
use crate::debug::log::DebugTrace;
use crate::debug::primitives::{Feature, Shape, Values};
use crate::scene::Settings;
use crate::trace::geometry::SceneGeometry;
use crate::trace::lights::Lights;

/// Lights: a segment from each light sample to the shaded point, in the light's colour
/// if it arrives and black if blocked (or facing away); the sample points on area
/// lights; and the lights themselves.
pub fn emit_lights(
    mut spawner: Spawner,
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
    spawner.spawn(out);
}
