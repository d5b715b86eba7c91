//! The light table and light sampling for direct illumination.

use bevy_ecs::prelude::*;
use glam::Vec3;

use crate::sampling::{Sampler, sample_parallelogram_light, sample_segment_light};
use crate::scene::{ParallelogramLight, PointLight, SegmentLight};
use crate::stats::{RenderStats, Stage};

/// Every light, by kind, in a fixed order (points, segments, parallelograms).
#[derive(Resource, Clone, Debug, Default)]
pub struct Lights {
    /// Point lights.
    pub points: Vec<PointLight>,
    /// Segment lights.
    pub segments: Vec<SegmentLight>,
    /// Parallelogram lights.
    pub parallelograms: Vec<ParallelogramLight>,
}

/// One sample point on a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Position.
    pub position: Vec3,
    /// Colour, already divided by the light's sample count.
    pub color: Vec3,
    /// Global light index (points, then segments, then parallelograms).
    pub light: u32,
}

impl Lights {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.points.len() + self.segments.len() + self.parallelograms.len()
    }

    /// Whether there are no lights.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Calls `f` for every light sample seen from one shading point: one per point
    /// light and `shadow_samples` per area light, colours pre-divided so that the
    /// contributions simply sum (SPEC: area light samples are averaged).
    pub fn for_each_sample(
        &self,
        sampler: &Sampler,
        key: (u32, u32, u32, u32),
        shadow_samples: u32,
        mut f: impl FnMut(LightSample),
    ) {
        let (pixel, sample, depth, path) = key;
        let point = sampler.at(pixel, sample);
        let mut light = 0u32;
        for p in &self.points {
            f(LightSample {
                position: p.position,
                color: p.color,
                light,
            });
            light += 1;
        }
        let n = shadow_samples.max(1);
        let inv = 1.0 / n as f32;
        for s in &self.segments {
            let slot = point.slot((depth, path, light), n);
            for k in 0..n {
                let u = slot.light1(k);
                let (position, color) = sample_segment_light(s, u);
                f(LightSample {
                    position,
                    color: color * inv,
                    light,
                });
            }
            light += 1;
        }
        for q in &self.parallelograms {
            let slot = point.slot((depth, path, light), n);
            for k in 0..n {
                let uv = slot.light2(k);
                let (position, color) = sample_parallelogram_light(q, uv);
                f(LightSample {
                    position,
                    color: color * inv,
                    light,
                });
            }
            light += 1;
        }
    }
}

/// Gathers every light entity into the [`Lights`] table.
pub fn gather_lights(
    points: Query<&PointLight>,
    segments: Query<&SegmentLight>,
    parallelograms: Query<&ParallelogramLight>,
    mut lights: ResMut<Lights>,
    mut stats: ResMut<RenderStats>,
) {
    *lights = Lights {
        points: points.iter().copied().collect(),
        segments: segments.iter().copied().collect(),
        parallelograms: parallelograms.iter().copied().collect(),
    };
    stats.record(Stage::GatherLights, lights.len() as u64);
}
