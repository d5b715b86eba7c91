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

pub use super::camera_samples::{CameraSampleOffsets, generate_camera_samples};
use super::lane_models::LANES;
use super::lights::{LightSample, Lights};
use super::log::{HitObserver, LightObserver, RayTrace, TraceLog};
use super::materials::Materials;
use super::packet_hits::PacketSceneHits;
use super::plan::RenderPlan;
use super::shade_lanes::{LaneModel, shade_chunks_in_lanes};
pub use super::shadow::{CHUNK, ShadowPacket, ShadowPackets, ShadowQueue, ShadowRay};
use super::surface::{SHADOW_EPSILON, Surface, offset_ray_origin_towards, surface_at};
use super::surface_lanes::{TriangleLanes, surfaces_at};
use super::surface_queue::SurfaceBlock;
pub use super::surface_queue::SurfaceQueue;
use crate::accel::Ray;
use crate::sampling::Sampler;
use crate::scene::Settings;
use crate::shade::{Model, Shading, ShadingInput, WithModel};
use crate::stats::{RenderStats, Stage};
use crate::trace::geometry::SceneGeometry;

/// A ray waiting to be traced, with where its radiance goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueuedRay {
    /// The ray.
    pub ray: Ray,
    /// Throughput: what one unit of radiance along this ray adds to its sample.
    pub weight: Vec3,
    /// Index of the camera sample (within the current region) it belongs to.
    pub slot: u32,
    /// Branch id within the sample's ray tree (see [`Branch`]).
    pub path: u32,
}

impl QueuedRay {
    /// The branch id of this ray's child along `branch`.
    pub fn child_path(&self, branch: Branch) -> u32 {
        branch.child_of(self.path)
    }
}

/// A child in a sample's ray tree. Branch ids number the tree: the camera ray is 0, the
/// reflection child of ray `k` is `2k + 1`, its pass-through child `2k + 2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Branch {
    /// The reflected ray (odd ids).
    Reflection,
    /// The ray through a transparent surface (even ids above 0).
    PassThrough,
}

impl Branch {
    /// The branch id of the child along `self` of the ray with branch id `path`.
    pub fn child_of(self, path: u32) -> u32 {
        let step = match self {
            Branch::Reflection => 1,
            Branch::PassThrough => 2,
        };
        path.wrapping_mul(2).wrapping_add(step)
    }

    /// The branch that led to the ray with branch id `path`; `None` for the camera ray.
    pub fn of_path(path: u32) -> Option<Branch> {
        match path {
            0 => None,
            p if p % 2 == 1 => Some(Branch::Reflection),
            _ => Some(Branch::PassThrough),
        }
    }
}

/// How a traced ray came to be, read from its branch id in the sample's ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RayKind {
    /// From the camera (the root).
    Camera,
    /// A reflection.
    Reflection,
    /// A pass-through ray.
    PassThrough,
}

impl RayKind {
    /// The kind of the ray with branch id `path` (see [`Branch`]).
    pub fn of_path(path: u32) -> RayKind {
        match Branch::of_path(path) {
            None => RayKind::Camera,
            Some(Branch::Reflection) => RayKind::Reflection,
            Some(Branch::PassThrough) => RayKind::PassThrough,
        }
    }
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
    pub hits: SurfaceQueue,
    /// Radiance gathered by each ray at this depth (direct light, background).
    pub ray_radiance: Vec<Vec3>,
    /// Shadow rays cast this depth, held by the shading chunks that cast them, and
    /// after tracing what each let through: its contribution times visibility (or tint).
    pub shadow_rays: ShadowQueue,
    /// Rays for the next depth.
    pub next: Vec<QueuedRay>,
    /// Whether ray `i` of `rays` is camera sample `i`'s one ray (the camera rays, as
    /// `generate_camera_samples` queues them): `gather_radiance` then runs in parallel.
    pub by_sample: bool,
}

/// What a region's tracing hands the film: the radiance of each camera sample.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct SampleRadiance {
    /// Pixel (row-major index) of the first sample; the others follow in order.
    pub first_pixel: u32,
    /// Radiance of each camera sample of the region, one per pixel.
    pub values: Vec<Vec3>,
}

/// Each ray's closest hit and shading point into `surfaces`, in queue order; returns what
/// `O` observed of each query (nothing for `()`).
fn closest_hits<O: HitObserver>(
    geometry: &SceneGeometry,
    rays: &[QueuedRay],
    interpolate: bool,
    surfaces: &mut SurfaceQueue,
) -> Vec<O> {
    // One observer slot per ray, filled in place: for `()` the slots take no memory and
    // the loop is the plain query.
    let mut observers: Vec<O> = std::iter::repeat_with(O::default)
        .take(rays.len())
        .collect();
    surfaces.resize(rays.len());
    surfaces
        .blocks_mut()
        .par_iter_mut()
        .zip(rays.par_chunks(LANES).zip(observers.par_chunks_mut(LANES)))
        .with_min_len(CHUNK / LANES)
        .for_each(|(block, (rays, observers))| {
            for (j, (q, observer)) in rays.iter().zip(observers).enumerate() {
                let hit = geometry.intersect(&q.ray, f32::INFINITY, observer);
                observer.closest(hit.as_ref());
                block.set(
                    j,
                    hit.map(|h| surface_at(geometry, &q.ray, &h, interpolate)),
                );
            }
        });
    observers
}

/// [`closest_hits`] unobserved, with consecutive rays (of neighbouring pixels) traced
/// as packets (`SceneGeometry::intersect_packet_lanes`): the same hits.
fn closest_hits_in_packets(
    geometry: &SceneGeometry,
    rays: &[QueuedRay],
    interpolate: bool,
    surfaces: &mut SurfaceQueue,
) {
    use crate::accel::PACKET;
    // A packet's shading points are one block of the queue.
    const _: () = assert!(PACKET == LANES);
    // Every block is written below: only the length is set here, so the buffer is not
    // filled on one thread first (it keeps its length from depth to depth).
    surfaces.resize(rays.len());
    surfaces
        .blocks_mut()
        .par_iter_mut()
        .zip(rays.par_chunks(PACKET))
        .with_min_len(CHUNK / PACKET)
        // One buffer of hits and one of triangle lanes per task, overwritten packet by
        // packet.
        .for_each_init(
            || (PacketSceneHits::default(), TriangleLanes::default()),
            |(hits, lanes), (surfaces, rays)| {
                // Only the packet's rays are copied (the rest stay zero, never read).
                let mut packet = [Ray::new(Vec3::ZERO, Vec3::ZERO); PACKET];
                for (p, q) in packet.iter_mut().zip(rays) {
                    *p = q.ray;
                }
                let n = rays.len();
                geometry.intersect_packet_lanes_into(&packet[..n], f32::INFINITY, hits);
                surfaces_at(geometry, &packet[..n], hits, interpolate, lanes, surfaces);
            },
        );
}

/// Finds each ray's closest hit and builds its shading point; with a [`TraceLog`], also
/// keeps each ray's traversal.
pub fn intersect_rays(
    settings: Res<Settings>,
    geometry: Res<SceneGeometry>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    log: Option<ResMut<TraceLog>>,
) {
    let interpolate = settings.normal_interpolation;
    let wf = &mut *wf;
    // Into the last depth's buffer: its allocation is reused.
    match log {
        None => {
            closest_hits_in_packets(&geometry, &wf.rays, interpolate, &mut wf.hits);
        }
        Some(mut log) => {
            log.rays = closest_hits::<RayTrace>(&geometry, &wf.rays, interpolate, &mut wf.hits);
        }
    }
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
pub(super) struct ShadeContext<'a> {
    pub(super) settings: &'a Settings,
    pub(super) shading: Shading<'a>,
    pub(super) sampler: Sampler,
    pub(super) lights: &'a Lights,
    pub(super) materials: &'a Materials,
    pub(super) region: &'a PassRegion,
    pub(super) depth: u32,
    pub(super) queue_shadows: bool,
}

/// Where one shading point's shadow rays start: [`Surface::shadow_ray_to`]'s origin, the
/// same for every light sample, so it is offset once per point, not once per sample.
pub(super) struct ShadowOrigin(Vec3);

impl ShadowOrigin {
    pub(super) fn of(surface: &Surface) -> Self {
        // `offset_ray_origin(.., ng, w = ng)` without its test of the side (always `ng`).
        Self(offset_ray_origin_towards(
            surface.p,
            surface.p_error,
            surface.ng,
            surface.ng,
        ))
    }

    /// `surface.shadow_ray_to(target)`, bit for bit.
    pub(super) fn ray_to(&self, target: Vec3) -> Ray {
        Ray {
            origin: self.0,
            dir: target - self.0,
        }
    }
}

/// Direct light at ray `i`'s hit (or the background on a miss); its shadow rays are
/// appended to `shadows`. `seen(sample, contribution, index in shadows)` observes every
/// light sample (a no-op in a render, the trace log in a debug run).
fn shade_ray<M: Model>(
    cx: &ShadeContext,
    model: M,
    i: usize,
    q: &QueuedRay,
    hit: &Option<Surface>,
    shadows: &mut ShadowPackets,
    mut seen: impl FnMut(LightSample, Vec3, Option<u32>),
) -> Vec3 {
    let s = cx.settings;
    let Some(surface) = hit else {
        return q.weight * s.background;
    };
    let m = &cx.materials.list[surface.material as usize];
    let w = q.weight * blend_alpha(s, m.alpha, cx.depth);
    let kd = cx.materials.kd_at(surface.material, surface.uv);
    let v = -q.ray.dir.normalize();
    let mut direct = Vec3::ZERO;
    let mut origin = None;
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
            let c = model.shade(&ShadingInput {
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
                seen(ls, c, Some(shadows.len() as u32));
                let origin = origin.get_or_insert_with(|| ShadowOrigin::of(surface));
                shadows.push(ShadowRay {
                    ray: origin.ray_to(ls.position),
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

/// Runs `shade(scratch, c, rays, hits, radiance, shadows)` on each [`CHUNK`] of rays and
/// their hits' blocks in parallel, with the chunk's part of `radiance` and its shadow-ray
/// buffer; returns each chunk's result in order. Both are the last depth's buffers,
/// refilled so that their allocations are reused. Chunks, not rays, own the shadow-ray
/// buffers: no allocation per ray, and a deterministic queue. `scratch` is one value
/// of `init()` per task, reused by the task's chunks.
pub(super) fn for_each_shading_chunk<T: Send, S>(
    rays: &[QueuedRay],
    hits: &SurfaceQueue,
    radiance: &mut Vec<Vec3>,
    shadow_rays: &mut ShadowQueue,
    init: impl Fn() -> S + Sync + Send,
    shade: impl Fn(&mut S, usize, &[QueuedRay], &[SurfaceBlock], &mut [Vec3], &mut ShadowPackets) -> T
    + Sync
    + Send,
) -> Vec<T> {
    // A chunk's rays are whole blocks.
    const _: () = assert!(CHUNK.is_multiple_of(LANES));
    assert_eq!(hits.len(), rays.len());
    // Every entry is written by `shade`: only entries the buffer lacks are made (and zeroed).
    radiance.resize(rays.len(), Vec3::ZERO);
    let chunk_shadows = shadow_rays.start(rays.len().div_ceil(CHUNK));
    rays.par_chunks(CHUNK)
        .zip(hits.blocks().par_chunks(CHUNK / LANES))
        .zip(radiance.par_chunks_mut(CHUNK))
        .zip(chunk_shadows.par_iter_mut())
        .enumerate()
        .map_init(init, |scratch, (c, (((rays, hits), out), shadows))| {
            shade(scratch, c, rays, hits, out, shadows)
        })
        .collect()
}

/// Shades rays and hits chunk by chunk, in parallel, into `radiance` (each ray's) and
/// `shadow_rays`, both in queue order ([`for_each_shading_chunk`]); returns what `O`
/// observed.
pub(super) fn shade_chunks<O: LightObserver, M: Model>(
    cx: &ShadeContext,
    model: M,
    rays: &[QueuedRay],
    hits: &SurfaceQueue,
    radiance: &mut Vec<Vec3>,
    shadow_rays: &mut ShadowQueue,
) -> O {
    let observers: Vec<O> = for_each_shading_chunk(
        rays,
        hits,
        radiance,
        shadow_rays,
        || (),
        |_, c, rays, hits, out, shadows| {
            let mut observer = O::default();
            for (k, (q, r)) in rays.iter().zip(out).enumerate() {
                let i = c * CHUNK + k;
                let hit = hits[k / LANES].get(k % LANES);
                *r = shade_ray(cx, model, i, q, &hit, shadows, |ls, c, shadow| {
                    observer.seen(i as u32, ls, c, shadow)
                });
            }
            observer
        },
    );
    // Only the observers are joined (nothing for `()`): the shadow rays stay in chunks.
    let mut observed = O::default();
    let mut before = 0;
    for (s, o) in shadow_rays.chunks().iter().zip(observers) {
        observed.join(o, before as u32);
        before += s.len();
    }
    observed
}

/// [`shade_chunks`] of a render (nothing observed), run with the settings' [`Model`].
struct ShadeRun<'a> {
    cx: &'a ShadeContext<'a>,
    rays: &'a [QueuedRay],
    hits: &'a SurfaceQueue,
    radiance: &'a mut Vec<Vec3>,
    shadows: &'a mut ShadowQueue,
}

impl WithModel for ShadeRun<'_> {
    type Output = ();
    fn run<M: Model>(self, model: M) {
        shade_chunks::<(), M>(
            self.cx,
            model,
            self.rays,
            self.hits,
            self.radiance,
            self.shadows,
        );
    }
}

/// Shades every hit: direct light from every light sample, either added at once
/// (shadows off) or queued as shadow rays; misses get the background. With a
/// [`TraceLog`], also keeps every light sample.
#[allow(clippy::too_many_arguments)] // Because each is a resource the stage reads.
pub fn shade_hits(
    settings: Res<Settings>,
    plan: Res<RenderPlan>,
    lights: Res<Lights>,
    materials: Res<Materials>,
    region: Res<PassRegion>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    log: Option<ResMut<TraceLog>>,
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
        sampler: Sampler::with_kind(s.seed, s.sampler),
        lights: &lights,
        materials: &materials,
        region: &region,
        depth: wf.depth,
        queue_shadows: plan.shadow_rays,
    };
    let wf = &mut *wf;
    let (rays, hits) = (&wf.rays, &wf.hits);
    let (radiance, shadows) = (&mut wf.ray_radiance, &mut wf.shadow_rays);
    let hit_count = match (log, LaneModel::of(&cx.shading)) {
        // Lambertian (the render benchmark's model), Phong and Blinn-Phong: hits in lanes.
        (None, Some(model)) => shade_chunks_in_lanes(&cx, model, rays, hits, radiance, shadows),
        // The other models' loop reads the model per sample (see `Shading::dispatch`).
        (None, None) => {
            cx.shading.dispatch(ShadeRun {
                cx: &cx,
                rays,
                hits,
                radiance,
                shadows,
            });
            hits.hit_count()
        }
        // The debug's reads the model per sample (one copy of the loop).
        (Some(mut log), _) => {
            log.light_samples = shade_chunks(&cx, cx.shading, rays, hits, radiance, shadows);
            hits.hit_count()
        }
    };
    stats.record(Stage::ShadeHits, hit_count as u64);
}

/// Tests every shadow ray and adds the visible part of its contribution: binary
/// visibility, or the product of transparent tints when the plan says so.
pub fn trace_shadow_rays(
    plan: Res<RenderPlan>,
    geometry: Res<SceneGeometry>,
    materials: Res<Materials>,
    mut wf: ResMut<Wavefront>,
    mut stats: ResMut<RenderStats>,
    log: Option<Res<TraceLog>>,
) {
    let t_max = 1.0 - SHADOW_EPSILON;
    let wf = &mut *wf;
    // One closure per mode, chosen once: with the transmittance walk (and its crossings
    // buffer) in the same closure, every binary shadow ray paid its 6 KB stack frame.
    if plan.transparent_shadows {
        wf.shadow_rays.trace(&mut wf.ray_radiance, |s| {
            s.contribution * geometry.transmittance(&s.ray, t_max, &materials, &mut ())
        });
    } else {
        // The queue's packets as they are (the lanes shading's: sample k of eight
        // neighbouring hits, to the same light), read in lanes by the packet query.
        // What arrived is kept for the debug recorder only (a run with a trace log).
        let keep_arrived = log.is_some();
        wf.shadow_rays
            .trace_blocked(&mut wf.ray_radiance, keep_arrived, |packet| {
                geometry.occluded_lanes(&packet.rays, t_max)
            });
    }
    let n = wf.shadow_rays.len() as u64;
    stats.record(Stage::TraceShadowRays, n);
    stats.rays.shadow += n;
}

/// Adds each ray's radiance into its camera sample, in queue order (deterministic).
pub fn gather_radiance(wf: Res<Wavefront>, mut radiance: ResMut<SampleRadiance>) {
    // The slice taken once: indexing through the `ResMut` reloaded the vector's pointer
    // and length on every ray (the stores might have aliased them).
    let values = &mut radiance.values[..];
    if wf.by_sample {
        // One ray per sample, in sample order: chunk by chunk in parallel, the same sums
        // (the serial loop was 1% of the Cornell render, with the other threads idle).
        assert_eq!(values.len(), wf.ray_radiance.len());
        values
            .par_chunks_mut(CHUNK)
            .zip(wf.ray_radiance.par_chunks(CHUNK))
            .for_each(|(values, radiance)| {
                for (v, c) in values.iter_mut().zip(radiance) {
                    *v += *c;
                }
            });
        return;
    }
    for (q, c) in wf.rays.iter().zip(&wf.ray_radiance) {
        values[q.slot as usize] += *c;
    }
}

/// Appends to `wf.next` a child ray of every hit for which `weight(ray, material)` gives
/// a weight, `ray(ray, surface)`, in queue order, as children along `branch` in the ray
/// tree; returns how many. The weight needs only the hit's material, read from its lane:
/// the shading point is gathered from the lanes only for the hits that spawn (a fifth
/// of the Cornell scene's camera rays), where gathering every hit's took 4.9% of its
/// render on one thread. (In parallel chunks appended in order it took 458 rather than
/// 451 instructions per ray of that scene, the collection costing about half of what
/// the loop does: no gain on two threads, a loss on one.)
fn spawn_children(
    wf: &mut Wavefront,
    branch: Branch,
    weight: impl Fn(&QueuedRay, u32) -> Option<Vec3>,
    ray: impl Fn(&QueuedRay, &Surface) -> Ray,
) -> usize {
    let Wavefront {
        rays, hits, next, ..
    } = wf;
    let before = next.len();
    // Blocks of LANES rays, lanes in order: the queue's order. No hit bit is set past
    // the queue's end, which is the rays'.
    debug_assert_eq!(rays.len(), hits.len());
    for (block, rays) in hits.blocks().iter().zip(rays.chunks(LANES)) {
        let mut lanes = block.hit;
        while lanes != 0 {
            let j = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let Some(q) = rays.get(j) else { break };
            let Some(weight) = weight(q, block.material[j]) else {
                continue;
            };
            let surface = block.get(j).expect("a lane with its hit bit set");
            next.push(QueuedRay {
                ray: ray(q, &surface),
                weight,
                slot: q.slot,
                path: q.child_path(branch),
            });
        }
    }
    next.len() - before
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
    let spawned = spawn_children(
        &mut wf,
        Branch::Reflection,
        |q, material| {
            let m = &materials.list[material as usize];
            let weight = q.weight * blend_alpha(&settings, m.alpha, depth) * m.ks;
            (weight != Vec3::ZERO).then_some(weight)
        },
        |q, surface| surface.reflection_ray(q.ray.dir),
    );
    stats.record(Stage::SpawnReflectionRays, spawned as u64);
    stats.rays.reflection += spawned as u64;
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
    let spawned = spawn_children(
        &mut wf,
        Branch::PassThrough,
        |q, material| {
            let alpha = materials.list[material as usize].alpha;
            let weight = q.weight * (1.0 - alpha);
            (alpha != 1.0 && weight != Vec3::ZERO).then_some(weight)
        },
        |q, surface| surface.pass_through_ray(q.ray.dir),
    );
    stats.record(Stage::SpawnPassThroughRays, spawned as u64);
    stats.rays.pass_through += spawned as u64;
}

/// Makes the next depth's rays current.
pub fn advance_depth(mut wf: ResMut<Wavefront>) {
    let wf = &mut *wf;
    // Swapped, not moved: the spent queue's allocation becomes the next depth's.
    std::mem::swap(&mut wf.rays, &mut wf.next);
    wf.next.clear();
    wf.depth += 1;
    wf.by_sample = false;
}

/// Whether rays remain to be traced.
pub fn rays_pending(wf: &Wavefront) -> bool {
    !wf.rays.is_empty()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn shadow_origin_gives_the_surfaces_shadow_rays() {
        let bits = |r: Ray| [r.origin.to_array(), r.dir.to_array()].map(|v| v.map(f32::to_bits));
        for (p, p_error, ng) in [
            (Vec3::new(0.3, 2.0, -1.0), Vec3::splat(1e-7), Vec3::Y),
            (
                Vec3::new(-1e4, 0.0, 5.5),
                Vec3::new(1e-3, 0.0, 2e-6),
                Vec3::new(0.6, -0.8, 0.0),
            ),
            (Vec3::ZERO, Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0)),
            // A NaN normal (bad input): its side is still `ng`, as `offset_ray_origin` finds.
            (Vec3::ONE, Vec3::ZERO, Vec3::new(f32::NAN, -1.0, 0.0)),
        ] {
            let surface = Surface {
                p,
                p_error,
                ng,
                n: ng,
                uv: Vec2::ZERO,
                material: 0,
            };
            let origin = ShadowOrigin::of(&surface);
            for target in [Vec3::new(0.0, 1.99, 0.1), Vec3::new(-3.0, -7.0, 2.0), p] {
                assert_eq!(
                    bits(origin.ray_to(target)),
                    bits(surface.shadow_ray_to(target))
                );
            }
        }
    }
}
