//! The render's shading with hits in lanes (Lambertian, Phong, Blinn-Phong): [`LANES`]
//! hits at a time, their positions, normals and weights side by side (SoA), each light
//! sample made for all of them at once, per light kind, and `l = normalize(sample - p)`
//! and the model (`lane_models.rs`) done as `[f32; LANES]` loops (which the AVX2 clone
//! turns into ymm code). The scalar loop in `wavefront.rs` handled every light and
//! sampler kind per sample, one hit at a time.
//!
//! Same values bit for bit: every lane does the scalar code's f32 operations in the
//! same order (Rust never contracts them into FMAs). The shadow rays are written as
//! packets, one per light sample of the group (lane j: hit j's ray), in light and
//! sample order: each hit's rays come in the scalar loop's order (light by light, then
//! sample by sample), so its radiance sums the same values in the same order.

// Lane loops index several arrays by the same lane, the form the vectoriser wants.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;
use multiversion::multiversion;
use wide::u32x8;

pub(super) use super::lane_models::LaneModel;
use super::lane_models::{
    HitLanes, LANES, Lanes, Lanes3, SampleLanes, blinn_phong_sample, lambertian_lanes,
    phong_sample, shade_sample,
};
use super::shadow::{CHUNK, ShadowPacket, ShadowPackets, ShadowQueue};
use super::surface::MIN_OFFSET_COORDINATE;
use super::surface_lanes::SurfaceLanes;
use super::surface_queue::{SurfaceBlock, SurfaceQueue};
use super::wavefront::{QueuedRay, ShadeContext, blend_alpha, for_each_shading_chunk};
use crate::sampling::{PackedSlots, SlotLanes};

// A group's lanes are one shadow packet's.
const _: () = assert!(LANES == crate::accel::PACKET);

/// What a task's groups reuse, neither zeroed nor allocated per group.
#[derive(Debug, Default)]
struct Scratch {
    lanes: HitLanes,
    samples: Vec<SampleLanes>,
}

/// What a task's chunks reuse: their groups' [`Scratch`] and the chunk's pixels,
/// [`LANES`] per group.
#[derive(Debug, Default)]
struct ChunkScratch {
    groups: Scratch,
    pixels: Vec<u32>,
}

/// `x` clamped to [0, 1], NaN to 0: `sampling::light`'s `unit`, the same comparisons.
#[inline(always)]
fn unit(x: f32) -> f32 {
    if x > 0.0 {
        if x < 1.0 { x } else { 1.0 }
    } else {
        0.0
    }
}

/// Each lane's shadow-ray origin, `ShadowOrigin::of` bit for bit: `p` pushed out of its
/// error box along `ng` (`offset_ray_origin_towards(p, p_error, ng, ng)`), then rounded
/// one float away from the surface, with `f32::next_up` / `next_down` and the
/// subnormal guard written as selects so that the lanes need no branch.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn shadow_origins(p: &Lanes3, p_error: &Lanes3, ng: &Lanes3, out: &mut Lanes3) {
    for j in 0..LANES {
        let offset = (ng[0][j].abs() * p_error[0][j])
            + (ng[1][j].abs() * p_error[1][j])
            + (ng[2][j].abs() * p_error[2][j]);
        for a in 0..3 {
            let (x, side) = (p[a][j] + offset * ng[a][j], ng[a][j]);
            out[a][j] = away_from_surface(x, side);
        }
    }
}

/// One coordinate of `offset_ray_origin_towards`'s rounding: `x` moved one float
/// towards `side`'s sign, or to the least offset coordinate if it is below that.
#[inline(always)]
fn away_from_surface(x: f32, side: f32) -> f32 {
    let least = side != 0.0 && x.abs() < MIN_OFFSET_COORDINATE;
    let (up, down) = (side > 0.0, side < 0.0);
    // Past `least`, x is NaN or not 0: `next_up` adds one to the bits of a positive x
    // and takes one from a negative one, `next_down` the other way round; each keeps
    // NaN and the infinity it moves towards.
    let grow = (x > 0.0) == up;
    let keep = x.is_nan() || (grow && x.is_infinite());
    let bits = x.to_bits();
    let stepped = f32::from_bits(if grow {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    });
    if least {
        MIN_OFFSET_COORDINATE.copysign(side)
    } else if (up || down) && !keep {
        stepped
    } else {
        x
    }
}

/// Point `(u, v)` of parallelogram light `q` in each lane, as `sample_parallelogram_light`
/// with the colour times `inv`.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn parallelogram_lanes(
    q: &crate::scene::ParallelogramLight,
    u: &Lanes,
    v: &Lanes,
    inv: f32,
    position: &mut Lanes3,
    color: &mut Lanes3,
) {
    parallelogram_points(q, u, v, inv, position, color);
}

/// The loop of [`parallelogram_lanes`], inlined into its callers' clones.
#[inline(always)]
fn parallelogram_points(
    q: &crate::scene::ParallelogramLight,
    u: &Lanes,
    v: &Lanes,
    inv: f32,
    position: &mut Lanes3,
    color: &mut Lanes3,
) {
    let (v0, e1, e2) = (q.v0.to_array(), q.edge01.to_array(), q.edge02.to_array());
    let cs = [
        q.color0.to_array(),
        q.color1.to_array(),
        q.color2.to_array(),
        q.color3.to_array(),
    ];
    for j in 0..LANES {
        let (u, v) = (unit(u[j]), unit(v[j]));
        let (a, b, c, d) = ((1.0 - u) * (1.0 - v), u * (1.0 - v), (1.0 - u) * v, u * v);
        for k in 0..3 {
            position[k][j] = v0[k] + u * e1[k] + v * e2[k];
            color[k][j] = (a * cs[0][k] + b * cs[1][k] + c * cs[2][k] + d * cs[3][k]) * inv;
        }
    }
}

/// The Lambertian samples of parallelogram light `q` at the group's hits, sample `k`
/// into `samples[k]`, with packed sampler slots: `shade_group`'s loop of `light2`,
/// [`parallelogram_lanes`] and [`shade_sample`] in one AVX2 clone, so that no lane
/// array crosses a call and the samples' chains (a square root and a division each)
/// overlap.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn lambertian_parallelogram_samples(
    q: &crate::scene::ParallelogramLight,
    slots: &PackedSlots,
    inv: f32,
    surface: &SurfaceLanes,
    hits: &HitLanes,
    samples: &mut [SampleLanes],
) {
    for (k, sample) in samples.iter_mut().enumerate() {
        let (mut u, mut v) = (Lanes::default(), Lanes::default());
        slots.light2(k as u32, &mut u, &mut v);
        let mut color = Lanes3::default();
        parallelogram_points(q, &u, &v, inv, &mut sample.position, &mut color);
        lambertian_lanes(surface, hits, &color, sample);
    }
}

/// Point `s` of segment light `l` in each lane, as `sample_segment_light` with the
/// colour times `inv`.
fn segment_lanes(
    l: &crate::scene::SegmentLight,
    s: &Lanes,
    inv: f32,
    position: &mut Lanes3,
    color: &mut Lanes3,
) {
    let (e0, e1) = (l.endpoint0.to_array(), l.endpoint1.to_array());
    let (c0, c1) = (l.color0.to_array(), l.color1.to_array());
    for j in 0..LANES {
        let s = unit(s[j]);
        for k in 0..3 {
            position[k][j] = e0[k] * (1.0 - s) + e1[k] * s;
            color[k][j] = (c0[k] * (1.0 - s) + c1[k] * s) * inv;
        }
    }
}

/// Shades the group of up to [`LANES`] rays starting at queue index `first`, with their
/// pixels in `pixels` (0 past the group) and their shading points in `hits`: each ray's
/// direct light into `out`, its shadow rays appended to `shadows`, exactly as
/// `shade_ray` with `model` and nothing observed.
#[allow(clippy::too_many_arguments)] // The group, its outputs, the model and the scratch.
fn shade_group(
    cx: &ShadeContext,
    model: LaneModel,
    first: usize,
    rays: &[QueuedRay],
    pixels: &[u32; LANES],
    hits: &SurfaceBlock,
    out: &mut [Vec3],
    shadows: &mut ShadowPackets,
    scratch: &mut Scratch,
) {
    let Scratch { lanes, samples } = scratch;
    let s = cx.settings;
    let at = cx.sampler.at_lanes(pixels, cx.region.sample);
    let surface = &hits.lanes;
    for (j, q) in rays.iter().enumerate() {
        if hits.hit & (1 << j) == 0 {
            continue;
        }
        let material = hits.material[j];
        let m = &cx.materials.list[material as usize];
        let w = q.weight * blend_alpha(s, m.alpha, cx.depth);
        let uv = glam::Vec2::new(surface.uv[0][j], surface.uv[1][j]);
        let kd = cx.materials.kd_at(material, uv);
        for a in 0..3 {
            lanes.kd[a][j] = kd[a];
            lanes.w[a][j] = w[a];
        }
        if model != LaneModel::Lambertian {
            let v = -q.ray.dir.normalize();
            for a in 0..3 {
                lanes.v[a][j] = v[a];
                lanes.ks[a][j] = m.ks[a];
            }
            lanes.shininess[j] = m.shininess;
        }
    }
    let lights = cx.lights;
    let n = s.shadow_samples.max(1);
    let inv = 1.0 / n as f32;
    let path = |j: usize| rays.get(j).map_or(0, |q| q.path);
    // Each lane's sample numbers of one area light (zeros in lanes without a hit).
    let slots =
        |light: usize| SlotLanes::new(&at, hits.hit, |j| (cx.depth, path(j), light as u32), n);
    // The group's samples, light by light, into `samples` (its entries are overwritten:
    // it keeps its length from group to group, so nothing is zeroed or copied twice).
    let mut count = 0;
    let shade = |samples: &mut Vec<SampleLanes>,
                 count: &mut usize,
                 position: &Lanes3,
                 color: &Lanes3| {
        if samples.len() == *count {
            samples.push(SampleLanes::default());
        }
        let sample = &mut samples[*count];
        match model {
            LaneModel::Lambertian => shade_sample(surface, lanes, position, color, sample),
            LaneModel::Phong => phong_sample(surface, lanes, position, color, sample),
            LaneModel::BlinnPhong => blinn_phong_sample(surface, lanes, position, color, sample),
        }
        *count += 1;
    };
    let mut position = Lanes3::default();
    let mut color = Lanes3::default();
    let (mut u, mut v) = (Lanes::default(), Lanes::default());
    for p in &lights.points {
        let (pp, pc) = (p.position.to_array(), p.color.to_array());
        let position = pp.map(|x| [x; LANES]);
        let color = pc.map(|x| [x; LANES]);
        shade(samples, &mut count, &position, &color);
    }
    let base = lights.points.len();
    for (i, l) in lights.segments.iter().enumerate() {
        let slots = slots(base + i);
        for k in 0..n {
            slots.light1(k, &mut u);
            segment_lanes(l, &u, inv, &mut position, &mut color);
            shade(samples, &mut count, &position, &color);
        }
    }
    let base = base + lights.segments.len();
    for (i, q) in lights.parallelograms.iter().enumerate() {
        let light = (base + i) as u32;
        // Packed slots are looked for only where they are used: `slots` below looks
        // again (through `SlotLanes::new`) for the other models.
        if model == LaneModel::Lambertian
            && let Some(packed) = PackedSlots::new(&at, hits.hit, |j| (cx.depth, path(j), light), n)
        {
            // The render's case: all samples in one call.
            let end = count + n as usize;
            if samples.len() < end {
                samples.resize(end, SampleLanes::default());
            }
            let group = &mut samples[count..end];
            lambertian_parallelogram_samples(q, &packed, inv, surface, lanes, group);
            count = end;
            continue;
        }
        let slots = slots(base + i);
        for k in 0..n {
            slots.light2(k, &mut u, &mut v);
            parallelogram_lanes(q, &u, &v, inv, &mut position, &mut color);
            shade(samples, &mut count, &position, &color);
        }
    }
    let samples = &samples[..count];
    if cx.queue_shadows {
        let mut origins = Lanes3::default();
        shadow_origins(&surface.p, &surface.p_error, &surface.ng, &mut origins);
        for sample in samples {
            shadows
                .push_packet_with(|p| shadow_packet(&origins, sample, hits.hit, first as u32, p));
        }
    }
    for (j, (q, r)) in rays.iter().zip(out).enumerate() {
        *r = if hits.hit & (1 << j) == 0 {
            q.weight * s.background
        } else if cx.queue_shadows {
            // The light arrives through the shadow rays.
            Vec3::ZERO
        } else {
            // Each hit's samples in light order, as the scalar loop adds them.
            let mut direct = Vec3::ZERO;
            for sample in samples.iter().filter(|sample| sample.keep[j] != 0) {
                direct += Vec3::new(sample.c[0][j], sample.c[1][j], sample.c[2][j]);
            }
            direct
        };
    }
}

/// The shadow rays of one light sample of a group into `packet`, already in lanes:
/// lane `j` from `origins` to the sample's position on hit `j`'s behalf (owner
/// `first + j`), active where `hit_lanes` has a hit and the sample a contribution.
/// Whole lanes are written, no ray is moved one float at a time (the packet query
/// reads them as they are).
#[inline(always)]
fn shadow_packet(
    origins: &Lanes3,
    sample: &SampleLanes,
    hit_lanes: u32,
    first: u32,
    packet: &mut ShadowPacket,
) {
    packet.contribution = sample.c;
    let rays = &mut packet.rays;
    rays.origin = *origins;
    for a in 0..3 {
        for j in 0..LANES {
            // `ShadowOrigin::ray_to`'s `target - origin`.
            rays.dir[a][j] = sample.position[a][j] - origins[a][j];
        }
    }
    for j in 0..LANES {
        packet.owner[j] = first + j as u32;
    }
    // The kept lanes as one compare and a move mask (a loop of shifts and ors cost 28
    // instructions per packet).
    let keep = !u32x8::from(sample.keep).simd_eq(u32x8::ZERO).to_bitmask();
    rays.active = keep & hit_lanes & ((1 << LANES) - 1);
}

/// `shade_chunks` of a render with `model`: chunk by chunk in parallel,
/// [`LANES`] rays at a time within a chunk, into `radiance` and `shadow_rays` (the last
/// depth's buffers, refilled); returns how many rays hit (`hits.hit_count()`), counted
/// by the chunks rather than in a serial pass over the queue after them.
pub(super) fn shade_chunks_in_lanes(
    cx: &ShadeContext,
    model: LaneModel,
    rays: &[QueuedRay],
    hits: &SurfaceQueue,
    radiance: &mut Vec<Vec3>,
    shadow_rays: &mut ShadowQueue,
) -> usize {
    let hit_counts = for_each_shading_chunk(
        rays,
        hits,
        radiance,
        shadow_rays,
        ChunkScratch::default,
        |scratch, c, rays, hits, out, shadows| {
            let ChunkScratch {
                groups: scratch,
                pixels,
            } = scratch;
            // The chunk's pixels, written before its first group: each group's hash
            // loop reads its eight as one vector, which waited on eight fresh stores
            // when the group wrote them itself. In the task's buffer, not zeroed first:
            // a stack array of `CHUNK` zeroed per chunk cost 4,100 instructions a chunk.
            pixels.clear();
            pixels.extend(
                rays.iter()
                    .map(|q| cx.region.first_pixel.wrapping_add(q.slot)),
            );
            pixels.resize(rays.len().next_multiple_of(LANES), 0);
            let groups = rays.chunks(LANES).zip(pixels.as_chunks().0);
            let groups = groups.zip(hits).zip(out.chunks_mut(LANES));
            for (g, (((rays, pixels), hits), out)) in groups.enumerate() {
                let first = c * CHUNK + g * LANES;
                shade_group(cx, model, first, rays, pixels, hits, out, shadows, scratch);
            }
            hits.iter().map(|b| b.hit.count_ones() as usize).sum()
        },
    );
    hit_counts.iter().sum()
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;
    use crate::accel::Ray;
    use crate::sampling::Sampler;
    use crate::scene::{ParallelogramLight, PointLight, SamplerKind, SegmentLight, Settings};
    use crate::shade::Shading;
    use crate::trace::lights::Lights;
    use crate::trace::materials::{MaterialData, Materials};
    use crate::trace::shadow::ShadowRay;
    use crate::trace::surface::Surface;
    use crate::trace::wavefront::{PassRegion, ShadowOrigin, shade_chunks};

    /// A small deterministic generator (xorshift), numbers in [-1, 1).
    struct Numbers(u64);

    impl Numbers {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        }
        fn vec3(&mut self, scale: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * scale
        }
    }

    /// `count` rays with hits (about one in five missing) in a box around the lights,
    /// some facing away from them, one sitting on the point light and one with a huge
    /// `kd` (non-finite contributions) or an infinite weight.
    fn scene(count: usize, seed: u64) -> (Vec<QueuedRay>, SurfaceQueue) {
        let mut r = Numbers(seed);
        let rays = (0..count)
            .map(|i| QueuedRay {
                ray: Ray {
                    origin: r.vec3(3.0),
                    dir: r.vec3(1.0),
                },
                weight: if i % 97 == 13 {
                    Vec3::new(f32::INFINITY, 0.5, 1.0)
                } else {
                    r.vec3(1.0).abs()
                },
                slot: (i * 7 % 1000) as u32,
                path: (i % 3) as u32,
            })
            .collect();
        let hits = (0..count)
            .map(|i| {
                (r.next() > -0.6).then(|| Surface {
                    p: if i % 50 == 7 {
                        Vec3::new(0.5, 1.5, -0.25)
                    } else {
                        r.vec3(2.0)
                    },
                    p_error: r.vec3(1e-6).abs(),
                    ng: r.vec3(1.0).normalize(),
                    n: r.vec3(1.0).normalize(),
                    uv: Vec2::ZERO,
                    material: (i % 5) as u32,
                })
            })
            .collect();
        (rays, hits)
    }

    fn lights(points: usize, segments: usize, parallelograms: usize) -> Lights {
        Lights {
            points: (0..points)
                .map(|i| PointLight {
                    // The first one sits on a hit point (its direction cannot be normalized).
                    position: Vec3::new(0.5, 1.5, -0.25) + i as f32 * Vec3::X,
                    color: Vec3::new(1.0, 0.5, 0.25),
                })
                .collect(),
            segments: (0..segments)
                .map(|i| SegmentLight {
                    endpoint0: Vec3::new(-1.0, 2.0, i as f32),
                    endpoint1: Vec3::new(1.0, 2.5, -1.0),
                    color0: Vec3::new(0.0, 1.0, 2.0),
                    color1: Vec3::new(3.0, 0.5, 0.0),
                })
                .collect(),
            parallelograms: (0..parallelograms)
                .map(|i| ParallelogramLight {
                    v0: Vec3::new(-0.2, 1.99 - i as f32, -0.2),
                    edge01: Vec3::new(0.4, 0.0, 0.1),
                    edge02: Vec3::new(0.0, 0.2, 0.4),
                    color0: Vec3::new(1.0, 0.0, 0.0),
                    color1: Vec3::new(0.0, 1.0, 0.0),
                    color2: Vec3::new(0.0, 0.0, 1.0),
                    color3: Vec3::new(0.0, 1.0, 1.0),
                })
                .collect(),
        }
    }

    /// Materials without a highlight (`ks = 0`, no `powf`), with one, with a huge `kd`,
    /// with a negative `ks` and NaN shininess, and with shininess 0.
    fn materials() -> Materials {
        let material = |kd: Vec3, ks: Vec3, shininess: f32| MaterialData {
            kd,
            ks,
            shininess,
            alpha: 1.0,
            texture: None,
            wrap: Default::default(),
        };
        Materials {
            list: vec![
                material(Vec3::new(0.75, 0.1, 0.1), Vec3::ZERO, 1.0),
                material(Vec3::splat(0.5), Vec3::splat(0.3), 16.0),
                material(Vec3::new(3e38, 0.2, 0.0), Vec3::new(0.0, 0.9, 0.1), 4.0),
                material(Vec3::splat(0.2), Vec3::new(-0.5, 0.0, 0.7), f32::NAN),
                material(Vec3::splat(0.6), Vec3::new(0.0, 0.4, 0.0), 0.0),
            ],
            ..Default::default()
        }
    }

    /// Radiance and shadow rays as bits (NaN compares equal to itself), the shadow rays
    /// owner by owner, each owner's in queue order: the lanes queue holds a group's rays
    /// sample by sample, the scalar loop's hit by hit.
    fn bits(radiance: &[Vec3], shadows: &ShadowQueue) -> (Vec<[u32; 3]>, Vec<[u32; 10]>) {
        let v = |v: Vec3| v.to_array().map(f32::to_bits);
        let mut shadows = shadows.to_vec();
        shadows.sort_by_key(|s| s.owner);
        let shadows = shadows
            .iter()
            .map(|s| {
                let [a, b, c] = v(s.ray.origin);
                let [d, e, f] = v(s.ray.dir);
                let [g, h, i] = v(s.contribution);
                [a, b, c, d, e, f, g, h, i, s.owner]
            })
            .collect();
        (radiance.iter().map(|&r| v(r)).collect(), shadows)
    }

    #[test]
    fn shadow_origins_in_lanes_are_the_scalar_ones() {
        // Coordinates and normals around every case of the rounding: zero, below and at
        // the least offset coordinate, ordinary, the largest float, infinities, NaN.
        let m = MIN_OFFSET_COORDINATE;
        let values = [
            0.0,
            -0.0,
            1e-40,
            -1e-40,
            m,
            -m,
            m.next_down(),
            -m.next_down(),
            m.next_up(),
            0.3,
            -2.5,
            1e6,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut surfaces = Vec::new();
        for &x in &values {
            for &side in &values {
                for e in [0.0, 1e-7, f32::INFINITY] {
                    surfaces.push(Surface {
                        p: Vec3::new(x, -x, 0.5),
                        p_error: Vec3::new(e, 0.0, 1e-8),
                        ng: Vec3::new(side, 0.6, -side),
                        n: Vec3::Y,
                        uv: Vec2::ZERO,
                        material: 0,
                    });
                }
            }
        }
        for group in surfaces.chunks(LANES) {
            let mut block = SurfaceBlock::default();
            for (j, s) in group.iter().enumerate() {
                block.set(j, Some(*s));
            }
            let lanes = &block.lanes;
            let mut origins = Lanes3::default();
            shadow_origins(&lanes.p, &lanes.p_error, &lanes.ng, &mut origins);
            for (j, s) in group.iter().enumerate() {
                let lane = [0, 1, 2].map(|a| origins[a][j].to_bits());
                let scalar = ShadowOrigin::of(s).ray_to(Vec3::ZERO).origin;
                assert_eq!(lane, scalar.to_array().map(f32::to_bits), "{s:?}");
            }
        }
    }

    #[test]
    fn lanes_give_the_scalar_loops_radiance_and_shadow_rays() {
        use crate::scene::ShadingModel;
        for model in [
            ShadingModel::Lambertian,
            ShadingModel::Phong,
            ShadingModel::BlinnPhong,
        ] {
            lanes_give_the_scalar_loops_values(model);
        }
    }

    /// `shade_chunks_in_lanes` against `shade_chunks` with `model`, every bit.
    fn lanes_give_the_scalar_loops_values(model: crate::scene::ShadingModel) {
        let materials = materials();
        let mut compared = 0;
        for (count, seed) in [(1, 1), (7, 2), (8, 3), (13, 4), (2 * CHUNK + 21, 5)] {
            let (rays, hits) = scene(count, seed);
            for (points, segments, parallelograms) in
                [(1, 0, 0), (0, 1, 0), (0, 0, 1), (2, 1, 2), (0, 0, 0)]
            {
                let lights = lights(points, segments, parallelograms);
                for kind in [
                    SamplerKind::Independent,
                    SamplerKind::Stratified,
                    SamplerKind::Sobol,
                ] {
                    for (shadow_samples, queue_shadows, depth) in
                        [(4, true, 0), (1, true, 1), (0, false, 0), (3, false, 2)]
                    {
                        let settings = Settings {
                            shadow_samples,
                            background: Vec3::new(0.1, 0.2, 0.3),
                            ..Settings::default()
                        };
                        let region = PassRegion {
                            sample: 5,
                            first_pixel: 40,
                            pixels: count as u32,
                        };
                        let cx = ShadeContext {
                            settings: &settings,
                            shading: Shading {
                                enabled: true,
                                model,
                                gradient: &settings.gradient,
                                comparison_gradient: &settings.comparison_gradient,
                            },
                            sampler: Sampler::with_kind(9, kind),
                            lights: &lights,
                            materials: &materials,
                            region: &region,
                            depth,
                            queue_shadows,
                        };
                        let (mut r0, mut s0) = (Vec::new(), ShadowQueue::default());
                        // The scalar loop with the model read per sample.
                        shade_chunks::<(), _>(&cx, cx.shading, &rays, &hits, &mut r0, &mut s0);
                        let (mut r1, mut s1) = (Vec::new(), ShadowQueue::default());
                        let lane_model = LaneModel::of(&cx.shading).unwrap();
                        let hit_count =
                            shade_chunks_in_lanes(&cx, lane_model, &rays, &hits, &mut r1, &mut s1);
                        assert_eq!(hit_count, hits.hit_count());
                        assert_eq!(
                            bits(&r1, &s1),
                            bits(&r0, &s0),
                            "{model:?}, {count} rays, lights {points}/{segments}/{parallelograms}, \
                             {kind:?}, {shadow_samples} samples, queue {queue_shadows}"
                        );
                        // Traced, each ray gets its shadow rays' contributions in the
                        // same order: the same sums, bit for bit.
                        let visible = |s: &ShadowRay| {
                            if s.ray.dir.x > 0.0 {
                                s.contribution
                            } else {
                                Vec3::ZERO
                            }
                        };
                        s0.trace(&mut r0, visible);
                        s1.trace(&mut r1, visible);
                        assert_eq!(bits(&r1, &s1), bits(&r0, &s0), "traced");
                        assert_eq!(s1.arrived().len(), s1.len());
                        compared += s0.len();
                    }
                }
            }
        }
        assert!(compared > 10_000, "{compared} shadow rays compared");
    }
}
