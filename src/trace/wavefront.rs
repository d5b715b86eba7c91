//! The wavefront bounce loop: the recursion of SPEC "Radiance of a camera ray" as
//! queues of rays carrying throughput weights, processed a depth level at a time.
//!
//! Both recursive terms are linear in the recursive result, so weighting works exactly:
//! with `a = alpha` where the pass-through blend applies (else 1), a hit adds
//! `w * a * direct`, spawns a reflection ray of weight `w * a * ks` and a pass-through
//! ray of weight `w * (1 - alpha)`.

use bevy_ecs::prelude::*;
use glam::Vec3;
use rayon::prelude::*;

use super::lights::{LightSample, Lights};
use super::materials::Materials;
use super::plan::RenderPlan;
use super::surface::{SHADOW_EPSILON, Surface, surface_at};
use crate::accel::Ray;
use crate::debug::log::{DebugTrace, TraversalLog};
use crate::sampling::{Sampler, pixel_sample_offset, samples_taken};
use crate::scene::{Camera, Settings};
use crate::shade::{Shading, ShadingInput};
use crate::stats::{RenderStats, Stage};
use crate::trace::geometry::SceneGeometry;

/// Rays per rayon task: large enough to amortise scheduling, small enough to balance.
const CHUNK: usize = 1024;

/// A ray waiting to be traced, with where its radiance goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueuedRay {
    /// The ray.
    pub ray: Ray,
    /// Throughput: what one unit of radiance along this ray adds to its sample.
    pub weight: Vec3,
    /// Index of the camera sample (within the current region) it belongs to.
    pub slot: u32,
    /// Branch id within the sample's ray tree (root 0; children 2k+1, 2k+2).
    pub path: u32,
}

/// A shadow ray: `contribution` reaches ray `owner`'s radiance if the path is clear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    /// From the shading point to the light sample; traced over `(0, 1 - SHADOW_EPSILON)`.
    pub ray: Ray,
    /// Unoccluded contribution, already weighted.
    pub contribution: Vec3,
    /// Index of the queued ray whose hit cast it.
    pub owner: u32,
}

/// What a pass covers: one sample index over a range of pixels.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassRegion {
    /// Sample index (the pass number).
    pub sample: u32,
    /// First pixel (row-major index).
    pub first_pixel: u32,
    /// Number of pixels.
    pub pixels: u32,
}

/// The queues and buffers of the wavefront in flight.
#[derive(Resource, Clone, Debug, Default)]
pub struct Wavefront {
    /// Depth of the rays in `rays` (camera rays are 0).
    pub depth: u32,
    /// Rays of the current depth.
    pub rays: Vec<QueuedRay>,
    /// Closest hit of each ray, and its shading point.
    pub hits: Vec<Option<Surface>>,
    /// Radiance gathered by each ray at this depth (direct light, background).
    pub ray_radiance: Vec<Vec3>,
    /// Shadow rays cast this depth.
    pub shadow_rays: Vec<ShadowRay>,
    /// Rays for the next depth.
    pub next: Vec<QueuedRay>,
}

/// What a region's tracing hands the film: the radiance of each camera sample.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct SampleRadiance {
    /// Pixel (row-major index) of the first sample; the others follow in order.
    pub first_pixel: u32,
    /// Radiance of each camera sample of the region, one per pixel.
    pub values: Vec<Vec3>,
}

/// The camera's ray through image-plane position `(x, y)` in pixels (row 0 at the top).
pub fn camera_ray(camera: &Camera, x: f32, y: f32) -> Ray {
    CameraBasis::new(camera).ray(x, y)
}

/// A camera's frame, computed once per pass rather than once per ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraBasis {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

impl CameraBasis {
    /// The frame of `camera`.
    pub fn new(camera: &Camera) -> Self {
        let forward = (camera.look_at - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        Self {
            origin: camera.position,
            forward,
            right,
            up: right.cross(forward),
            tan: (camera.fov_y_degrees.to_radians() * 0.5).tan(),
            aspect: camera.width as f32 / camera.height as f32,
            width: camera.width as f32,
            height: camera.height as f32,
        }
    }

    /// The ray through image-plane position `(x, y)` in pixels (row 0 at the top).
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.tan * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height) * self.tan;
        Ray {
            origin: self.origin,
            dir: (self.forward + sx * self.right + sy * self.up).normalize(),
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
    debug: Option<ResMut<DebugTrace>>,
) {
    let Some(camera) = cameras.iter().next() else {
        return;
    };
    let sampler = Sampler::new(settings.seed);
    let n = samples_taken(settings.pixel_samples, settings.pixel_sampling);
    let (mode, patterns) = (settings.pixel_sampling, plan.pixel_patterns);
    let width = camera.width;
    let basis = CameraBasis::new(camera);
    let offset_of = |slot: u32| {
        if patterns {
            pixel_sample_offset(&sampler, region.first_pixel + slot, region.sample, n, mode)
        } else {
            glam::Vec2::splat(0.5)
        }
    };
    let rays: Vec<QueuedRay> = (0..region.pixels)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|slot| {
            let pixel = region.first_pixel + slot;
            let offset = offset_of(slot);
            let (x, y) = ((pixel % width) as f32, (pixel / width) as f32);
            QueuedRay {
                ray: basis.ray(x + offset.x, y + offset.y),
                weight: Vec3::ONE,
                slot,
                path: 0,
            }
        })
        .collect();
    if let Some(mut log) = debug {
        log.record_camera_samples(region.sample, &rays, offset_of);
    }
    stats.record(Stage::GenerateCameraSamples, rays.len() as u64);
    stats.rays.camera += rays.len() as u64;
    wf.depth = 0;
    radiance.first_pixel = region.first_pixel;
    radiance.values = vec![Vec3::ZERO; rays.len()];
    wf.rays = rays;
}

/// Finds each ray's closest hit and builds its shading point.
pub fn intersect_rays(
    settings: Res<Settings>,
    geometry: Res<SceneGeometry>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    debug: Option<ResMut<DebugTrace>>,
) {
    let interpolate = settings.normal_interpolation;
    let hits = match debug {
        None => wf
            .rays
            .par_iter()
            .with_min_len(CHUNK)
            .map(|q| {
                geometry
                    .intersect(&q.ray, f32::INFINITY, &mut ())
                    .map(|h| surface_at(&geometry, &q.ray, &h, interpolate))
            })
            .collect(),
        // The same query, with a visitor that records the traversal.
        Some(mut log) => {
            let traced: Vec<_> = wf
                .rays
                .iter()
                .map(|q| {
                    let mut visits = TraversalLog::default();
                    let hit = geometry
                        .intersect(&q.ray, f32::INFINITY, &mut visits)
                        .map(|h| (h, surface_at(&geometry, &q.ray, &h, interpolate)));
                    (hit, visits)
                })
                .collect();
            let hits = traced.iter().map(|(h, _)| h.map(|(_, s)| s)).collect();
            log.record_rays(wf.depth, &wf.rays, traced);
            hits
        }
    };
    wf.hits = hits;
    stats.record(Stage::IntersectRays, wf.rays.len() as u64);
}

/// Weight of a hit's own colour in the pass-through blend: alpha where SPEC blends, else 1.
pub fn blend_alpha(settings: &Settings, alpha: f32, depth: u32) -> f32 {
    if settings.transparency && alpha != 1.0 && depth < settings.max_depth {
        alpha
    } else {
        1.0
    }
}

/// What shading one hit needs besides the ray and its hit.
struct ShadeContext<'a> {
    settings: &'a Settings,
    shading: Shading<'a>,
    sampler: Sampler,
    lights: &'a Lights,
    materials: &'a Materials,
    region: &'a PassRegion,
    depth: u32,
    queue_shadows: bool,
}

/// Direct light at ray `i`'s hit (or the background on a miss); its shadow rays are
/// appended to `shadows`. `seen(sample, contribution, shadow ray index within this ray's
/// rays)` observes every light sample (a no-op in a render, the trace log in a debug run).
fn shade_ray(
    cx: &ShadeContext,
    i: usize,
    q: &QueuedRay,
    hit: &Option<Surface>,
    shadows: &mut Vec<ShadowRay>,
    mut seen: impl FnMut(LightSample, Vec3, Option<u32>),
) -> Vec3 {
    let s = cx.settings;
    let Some(surface) = hit else {
        return q.weight * s.background;
    };
    let first_shadow = shadows.len();
    let m = &cx.materials.list[surface.material as usize];
    let w = q.weight * blend_alpha(s, m.alpha, cx.depth);
    let kd = cx.materials.kd_at(surface.material, surface.uv);
    let v = -q.ray.dir.normalize();
    let mut direct = Vec3::ZERO;
    let key = (
        cx.region.first_pixel + q.slot,
        cx.region.sample,
        cx.depth,
        q.path,
    );
    cx.lights
        .for_each_sample(&cx.sampler, key, s.shadow_samples, |ls| {
            let Some(l) = (ls.position - surface.p).try_normalize() else {
                return;
            };
            let c = cx.shading.shade(&ShadingInput {
                n: surface.n,
                l,
                v,
                light_color: ls.color,
                kd,
                ks: m.ks,
                shininess: m.shininess,
            }) * w;
            if c == Vec3::ZERO {
                seen(ls, c, None);
                return;
            }
            if cx.queue_shadows {
                seen(ls, c, Some((shadows.len() - first_shadow) as u32));
                shadows.push(ShadowRay {
                    ray: surface.shadow_ray_to(ls.position),
                    contribution: c,
                    owner: i as u32,
                });
            } else {
                seen(ls, c, None);
                direct += c;
            }
        });
    direct
}

/// Shades every hit: direct light from every light sample, either added at once
/// (shadows off) or queued as shadow rays; misses get the background.
#[allow(clippy::too_many_arguments)] // Because each is a resource the stage reads.
pub fn shade_hits(
    settings: Res<Settings>,
    plan: Res<RenderPlan>,
    lights: Res<Lights>,
    materials: Res<Materials>,
    region: Res<PassRegion>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    debug: Option<ResMut<DebugTrace>>,
) {
    let s = &*settings;
    let cx = ShadeContext {
        settings: s,
        shading: Shading {
            enabled: s.shading,
            model: s.shading_model,
            gradient: &s.gradient,
            comparison_gradient: &s.comparison_gradient,
        },
        sampler: Sampler::new(s.seed),
        lights: &lights,
        materials: &materials,
        region: &region,
        depth: wf.depth,
        queue_shadows: plan.shadow_rays,
    };
    let (radiance, shadow_rays) = match debug {
        // Chunks, not rays, own the shadow-ray vectors: no allocation per ray, and the
        // concatenation in chunk order keeps the queue deterministic.
        None => {
            let chunks: Vec<(Vec<Vec3>, Vec<ShadowRay>)> = wf
                .rays
                .par_chunks(CHUNK)
                .zip(wf.hits.par_chunks(CHUNK))
                .enumerate()
                .map(|(c, (rays, hits))| {
                    let mut shadows = Vec::new();
                    let radiance = rays
                        .iter()
                        .zip(hits)
                        .enumerate()
                        .map(|(k, (q, hit))| {
                            shade_ray(&cx, c * CHUNK + k, q, hit, &mut shadows, |_, _, _| {})
                        })
                        .collect();
                    (radiance, shadows)
                })
                .collect();
            let mut radiance = Vec::with_capacity(wf.rays.len());
            let mut shadow_rays = Vec::new();
            for (r, s) in chunks {
                radiance.extend(r);
                shadow_rays.extend(s);
            }
            (radiance, shadow_rays)
        }
        // The same shading, one ray after another, logging every light sample.
        Some(mut log) => {
            log.begin_light_samples();
            let mut shadow_rays = Vec::new();
            let mut radiance = Vec::with_capacity(wf.rays.len());
            for (i, (q, hit)) in wf.rays.iter().zip(&wf.hits).enumerate() {
                let queued = shadow_rays.len() as u32;
                radiance.push(shade_ray(
                    &cx,
                    i,
                    q,
                    hit,
                    &mut shadow_rays,
                    |ls, c, shadow| {
                        log.record_light_sample(i, ls, c, shadow.map(|k| queued + k));
                    },
                ));
            }
            (radiance, shadow_rays)
        }
    };
    stats.record(
        Stage::ShadeHits,
        wf.hits.iter().filter(|h| h.is_some()).count() as u64,
    );
    wf.ray_radiance = radiance;
    wf.shadow_rays = shadow_rays;
}

/// Tests every shadow ray and adds the visible part of its contribution: binary
/// visibility, or the product of transparent tints when the plan says so.
pub fn trace_shadow_rays(
    plan: Res<RenderPlan>,
    geometry: Res<SceneGeometry>,
    materials: Res<Materials>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    debug: Option<ResMut<DebugTrace>>,
) {
    let t_max = 1.0 - SHADOW_EPSILON;
    let transparent = plan.transparent_shadows;
    let visible: Vec<Vec3> = wf
        .shadow_rays
        .par_iter()
        .with_min_len(CHUNK)
        .map(|s| {
            if transparent {
                s.contribution * geometry.transmittance(&s.ray, t_max, &materials, &mut ())
            } else if geometry.occluded(&s.ray, t_max, &mut ()) {
                Vec3::ZERO
            } else {
                s.contribution
            }
        })
        .collect();
    if let Some(mut log) = debug {
        log.record_shadow_results(&visible);
    }
    let wf = &mut *wf;
    for (s, c) in wf.shadow_rays.iter().zip(visible) {
        wf.ray_radiance[s.owner as usize] += c;
    }
    stats.record(Stage::TraceShadowRays, wf.shadow_rays.len() as u64);
    stats.rays.shadow += wf.shadow_rays.len() as u64;
}

/// Adds each ray's radiance into its camera sample, in queue order (deterministic).
pub fn gather_radiance(
    wf: Res<Wavefront>,
    mut radiance: ResMut<SampleRadiance>,
    debug: Option<ResMut<DebugTrace>>,
) {
    if let Some(mut log) = debug {
        log.record_radiance(&wf.ray_radiance);
    }
    for (q, c) in wf.rays.iter().zip(&wf.ray_radiance) {
        radiance.values[q.slot as usize] += *c;
    }
}

/// The child rays of every hit for which `make` gives a ray and a weight, in queue
/// order; `branch` (1 reflection, 2 pass-through) numbers the child in the ray tree.
fn spawn_children(
    wf: &Wavefront,
    branch: u32,
    make: impl Fn(&QueuedRay, &Surface) -> Option<(Ray, Vec3)>,
) -> Vec<QueuedRay> {
    wf.rays
        .iter()
        .zip(&wf.hits)
        .filter_map(|(q, hit)| {
            let (ray, weight) = make(q, hit.as_ref()?)?;
            Some(QueuedRay {
                ray,
                weight,
                slot: q.slot,
                path: q.path.wrapping_mul(2).wrapping_add(branch),
            })
        })
        .collect()
}

/// Queues `ks`-weighted reflection rays for the next depth.
pub fn spawn_reflection_rays(
    settings: Res<Settings>,
    materials: Res<Materials>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
) {
    if wf.depth >= settings.max_depth {
        return;
    }
    let depth = wf.depth;
    let spawned = spawn_children(&wf, 1, |q, surface| {
        let m = &materials.list[surface.material as usize];
        let weight = q.weight * blend_alpha(&settings, m.alpha, depth) * m.ks;
        (weight != Vec3::ZERO).then(|| (surface.reflection_ray(q.ray.dir), weight))
    });
    stats.record(Stage::SpawnReflectionRays, spawned.len() as u64);
    stats.rays.reflection += spawned.len() as u64;
    wf.next.extend(spawned);
}

/// Queues `(1 - alpha)`-weighted pass-through rays for the next depth.
pub fn spawn_pass_through_rays(
    settings: Res<Settings>,
    materials: Res<Materials>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
) {
    if wf.depth >= settings.max_depth {
        return;
    }
    let spawned = spawn_children(&wf, 2, |q, surface| {
        let alpha = materials.list[surface.material as usize].alpha;
        let weight = q.weight * (1.0 - alpha);
        (alpha != 1.0 && weight != Vec3::ZERO)
            .then(|| (surface.pass_through_ray(q.ray.dir), weight))
    });
    stats.record(Stage::SpawnPassThroughRays, spawned.len() as u64);
    stats.rays.pass_through += spawned.len() as u64;
    wf.next.extend(spawned);
}

/// Makes the next depth's rays current.
pub fn advance_depth(mut wf: ResMut<Wavefront>) {
    let wf = &mut *wf;
    wf.rays = std::mem::take(&mut wf.next);
    wf.depth += 1;
}

/// Whether rays remain to be traced.
pub fn rays_pending(wf: &Wavefront) -> bool {
    !wf.rays.is_empty()
}
