//! The light table and light sampling for direct illumination.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::sampling::{Sampler, SlotSampler, sample_parallelogram_light, sample_segment_light};
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
        let n = shadow_samples.max(1);
        let inv = 1.0 / n as f32;
        let (points, segments) = (self.points.len(), self.segments.len());
        // One loop over every light and one call of `f`, so that `f` (the shading of a
        // sample) is inlined; with a call per light kind it stayed a call per sample.
        for light in 0..self.len() {
            // Point lights take no sample numbers: no slot seed is hashed for them.
            let slot = (light >= points).then(|| point.slot((depth, path, light as u32), n));
            let count = if light < points { 1 } else { n };
            for k in 0..count {
                let (position, color) = if light < points {
                    let p = &self.points[light];
                    (p.position, p.color)
                } else if light < points + segments {
                    let (position, color) =
                        sample_segment_light(&self.segments[light - points], unit1(slot, k));
                    (position, color * inv)
                } else {
                    let q = &self.parallelograms[light - points - segments];
                    let (position, color) = sample_parallelogram_light(q, unit2(slot, k));
                    (position, color * inv)
                };
                f(LightSample {
                    position,
                    color,
                    light: light as u32,
                });
            }
        }
    }
}

/// Sample `k` of an area light's slot, 1D (every area light has a slot).
// Inlined into the light-sample loop (as `map_or`, it stayed a call per sample).
#[inline(always)]
fn unit1(slot: Option<SlotSampler>, k: u32) -> f32 {
    match slot {
        Some(s) => s.light1(k),
        None => 0.0,
    }
}

/// Sample `k` of an area light's slot, 2D.
#[inline(always)]
fn unit2(slot: Option<SlotSampler>, k: u32) -> Vec2 {
    match slot {
        Some(s) => s.light2(k),
        None => Vec2::ZERO,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SamplerKind;

    #[test]
    fn every_light_gives_its_samples_in_order() {
        let segment = SegmentLight {
            endpoint0: Vec3::ZERO,
            endpoint1: Vec3::X,
            color0: Vec3::ONE,
            color1: Vec3::splat(3.0),
        };
        let parallelogram = ParallelogramLight {
            v0: Vec3::Y,
            edge01: Vec3::X,
            edge02: Vec3::Z,
            color0: Vec3::ONE,
            color1: Vec3::X,
            color2: Vec3::Y,
            color3: Vec3::Z,
        };
        let point = PointLight {
            position: Vec3::splat(2.0),
            color: Vec3::splat(0.5),
        };
        let lights = Lights {
            points: vec![point],
            segments: vec![segment],
            parallelograms: vec![parallelogram],
        };
        for kind in [SamplerKind::Independent, SamplerKind::Stratified] {
            let sampler = Sampler::with_kind(3, kind);
            let mut seen = Vec::new();
            lights.for_each_sample(&sampler, (7, 2, 1, 0), 3, |s| seen.push(s));
            let at = sampler.at(7, 2);
            let mut expected = vec![LightSample {
                position: point.position,
                color: point.color,
                light: 0,
            }];
            for k in 0..3 {
                let (position, color) = sample_segment_light(&segment, at.light1((1, 0, 1), k, 3));
                let light = 1;
                expected.push(LightSample {
                    position,
                    color: color * (1.0 / 3.0),
                    light,
                });
            }
            for k in 0..3 {
                let uv = at.light2((1, 0, 2), k, 3);
                let (position, color) = sample_parallelogram_light(&parallelogram, uv);
                let light = 2;
                expected.push(LightSample {
                    position,
                    color: color * (1.0 / 3.0),
                    light,
                });
            }
            assert_eq!(seen, expected, "{kind:?}");
        }
    }
}
