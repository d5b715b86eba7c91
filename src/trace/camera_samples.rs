//! The first stage of a pass: one camera ray per pixel of the region, at its sample
//! offset, [`SLOT_LANES`] pixels at a time.

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::camera::CameraBasis;
use super::plan::RenderPlan;
use super::shadow::CHUNK;
use super::wavefront::{PassRegion, QueuedRay, SampleRadiance, Wavefront};
use crate::accel::Ray;
use crate::sampling::{
    SLOT_LANES, Sampler, offset_of_jitter, pixel_mode, pixel_sample_offset, samples_taken,
};
use crate::scene::{Camera, PixelSampling, Settings};
use crate::stats::{RenderStats, Stage};

/// Where in its pixel each camera sample goes: the pixel centre unless the plan asks for
/// sample patterns. The render and the debug recorder both ask it, so they agree.
#[derive(Clone, Copy, Debug)]
pub struct CameraSampleOffsets {
    sampler: Sampler,
    samples: u32,
    mode: PixelSampling,
    patterns: bool,
}

impl CameraSampleOffsets {
    /// The offsets the settings and the plan call for.
    pub fn new(settings: &Settings, plan: &RenderPlan) -> Self {
        let mode = pixel_mode(settings);
        Self {
            sampler: Sampler::with_kind(settings.seed, settings.sampler),
            samples: samples_taken(settings.pixel_samples, mode),
            mode,
            patterns: plan.pixel_patterns,
        }
    }

    /// [`Self::of`] of `pixels[j]` in each lane `j`, as x and y.
    pub fn of_lanes(
        &self,
        pixels: &[u32; SLOT_LANES],
        sample: u32,
    ) -> ([f32; SLOT_LANES], [f32; SLOT_LANES]) {
        let mut u = [0.5; SLOT_LANES];
        let mut v = [0.5; SLOT_LANES];
        // `pixel_sample_offset` gives the centre for one sample, without the sampler.
        if self.patterns && self.samples > 1 {
            self.sampler.pixel2_lanes(pixels, sample, &mut u, &mut v);
            for (u, v) in u.iter_mut().zip(v.iter_mut()) {
                let offset = offset_of_jitter(Vec2::new(*u, *v), sample, self.samples, self.mode);
                (*u, *v) = (offset.x, offset.y);
            }
        }
        (u, v)
    }

    /// Offset within `pixel` of its camera sample `sample`, in [0, 1)^2.
    pub fn of(&self, pixel: u32, sample: u32) -> Vec2 {
        if self.patterns {
            pixel_sample_offset(&self.sampler, pixel, sample, self.samples, self.mode)
        } else {
            Vec2::splat(0.5)
        }
    }
}

/// Generates one camera ray per pixel of the region, at its sample offset.
pub fn generate_camera_samples(
    settings: Res<Settings>,
    plan: Res<RenderPlan>,
    cameras: Query<&Camera>,
    region: Res<PassRegion>,
    mut wf: ResMut<Wavefront>,
    mut radiance: ResMut<SampleRadiance>,
    mut stats: ResMut<RenderStats>,
) {
    let Some(camera) = cameras.iter().next() else {
        return;
    };
    let width = camera.width;
    let basis = CameraBasis::new(camera);
    let offsets = CameraSampleOffsets::new(&settings, &plan);
    let wf = &mut *wf;
    let n = region.pixels as usize;
    // The directions of the SLOT_LANES pixels from the region's pixel `first` on, their
    // sampler hashes and directions in lanes (lanes past the region's end compute
    // something unused).
    let directions = |first: u32| {
        let pixels: [u32; SLOT_LANES] = std::array::from_fn(|j| {
            region
                .first_pixel
                .wrapping_add(first)
                .wrapping_add(j as u32)
        });
        let (ox, oy) = offsets.of_lanes(&pixels, region.sample);
        let x = std::array::from_fn(|j| (pixels[j] % width) as f32 + ox[j]);
        let y = std::array::from_fn(|j| (pixels[j] / width) as f32 + oy[j]);
        let mut dir = [[0.0; SLOT_LANES]; 3];
        basis.dirs_lanes(&x, &y, &mut dir);
        dir
    };
    // Collected into the last pass's buffer: its allocation is reused, and no entry is
    // written twice (the queue is empty when a pass starts: filling it before writing
    // each ray in place cost 1.75% of the render). Each split of the range keeps its
    // current group of SLOT_LANES pixels and computes the group's directions at its
    // first ray (again where a split starts mid-group: the same numbers).
    (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map_init(
            || (usize::MAX, [[0.0; SLOT_LANES]; 3]),
            |(group, dir), i| {
                let j = i % SLOT_LANES;
                if i / SLOT_LANES != *group {
                    *group = i / SLOT_LANES;
                    *dir = directions((i - j) as u32);
                }
                QueuedRay {
                    ray: Ray {
                        origin: basis.origin,
                        dir: Vec3::new(dir[0][j], dir[1][j], dir[2][j]),
                    },
                    weight: Vec3::ONE,
                    slot: i as u32,
                    path: 0,
                }
            },
        )
        .collect_into_vec(&mut wf.rays);
    let n = wf.rays.len();
    stats.record(Stage::GenerateCameraSamples, n as u64);
    stats.rays.camera += n as u64;
    wf.depth = 0;
    wf.by_sample = true;
    wf.next.clear();
    radiance.first_pixel = region.first_pixel;
    radiance.values.clear();
    radiance.values.resize(n, Vec3::ZERO);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SamplerKind;
    use bevy_ecs::system::RunSystemOnce;

    #[test]
    fn camera_rays_are_each_pixels_scalar_ray_across_splits() {
        let camera = Camera {
            position: Vec3::new(0.0, 1.0, 3.9),
            look_at: Vec3::new(0.1, 0.9, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
            width: 97,
            height: 61,
        };
        let settings = Settings {
            pixel_samples: 4,
            pixel_sampling: PixelSampling::Uniform,
            seed: 5,
            ..Settings::default()
        };
        let plan = RenderPlan {
            pixel_patterns: true,
            ..RenderPlan::default()
        };
        // 2,100 rays from pixel 13: split in two halves of 1,050 (not a multiple of
        // SLOT_LANES) by a pool of several threads, so a split starts mid-group.
        let region = PassRegion {
            sample: 2,
            first_pixel: 13,
            pixels: 2100,
        };
        let mut world = World::new();
        world.insert_resource(settings.clone());
        world.insert_resource(plan.clone());
        world.insert_resource(region);
        world.insert_resource(Wavefront::default());
        world.insert_resource(SampleRadiance::default());
        world.insert_resource(RenderStats::default());
        world.spawn(camera.clone());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        pool.install(|| world.run_system_once(generate_camera_samples))
            .expect("the system runs");
        let basis = CameraBasis::new(&camera);
        let offsets = CameraSampleOffsets::new(&settings, &plan);
        let rays = &world.resource::<Wavefront>().rays;
        assert_eq!(rays.len(), 2100);
        for (i, q) in rays.iter().enumerate() {
            let pixel = 13 + i as u32;
            let o = offsets.of(pixel, 2);
            let want = basis.ray((pixel % 97) as f32 + o.x, (pixel / 97) as f32 + o.y);
            assert_eq!(
                q.ray.dir.to_array().map(f32::to_bits),
                want.dir.to_array().map(f32::to_bits)
            );
            assert_eq!(q.ray.origin, want.origin);
            assert_eq!((q.weight, q.slot, q.path), (Vec3::ONE, i as u32, 0));
        }
    }

    #[test]
    fn offsets_and_directions_in_lanes_are_the_scalar_ones() {
        let camera = Camera {
            position: Vec3::new(0.0, 1.0, 3.9),
            look_at: Vec3::new(0.1, 0.9, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
            width: 37,
            height: 23,
        };
        let basis = CameraBasis::new(&camera);
        let bits = |v: Vec2| v.to_array().map(f32::to_bits);
        for kind in [
            SamplerKind::Independent,
            SamplerKind::Stratified,
            SamplerKind::Sobol,
        ] {
            for mode in [PixelSampling::Uniform, PixelSampling::Stratified] {
                for (pixel_samples, patterns) in [(1, true), (4, true), (9, true), (16, false)] {
                    let settings = Settings {
                        sampler: kind,
                        pixel_sampling: mode,
                        pixel_samples,
                        seed: 11,
                        ..Settings::default()
                    };
                    let plan = RenderPlan {
                        pixel_patterns: patterns,
                        ..RenderPlan::default()
                    };
                    let offsets = CameraSampleOffsets::new(&settings, &plan);
                    for sample in [0, 3, 7] {
                        // The image's pixels and some past its end (a region's tail lanes).
                        for first in (0..37 * 23 + 16).step_by(SLOT_LANES) {
                            let pixels = std::array::from_fn(|j| (first + j) as u32);
                            let (ox, oy) = offsets.of_lanes(&pixels, sample);
                            let x = std::array::from_fn(|j| (pixels[j] % 37) as f32 + ox[j]);
                            let y = std::array::from_fn(|j| (pixels[j] / 37) as f32 + oy[j]);
                            let mut dir = [[0.0; SLOT_LANES]; 3];
                            basis.dirs_lanes(&x, &y, &mut dir);
                            for (j, &pixel) in pixels.iter().enumerate() {
                                let offset = offsets.of(pixel, sample);
                                assert_eq!(bits(Vec2::new(ox[j], oy[j])), bits(offset));
                                let ray = basis.ray(x[j], y[j]);
                                let lane = [dir[0][j], dir[1][j], dir[2][j]].map(f32::to_bits);
                                assert_eq!(lane, ray.dir.to_array().map(f32::to_bits));
                            }
                        }
                    }
                }
            }
        }
    }
}
