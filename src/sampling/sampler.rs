//! A counter-based random number generator and the named dimensions it is indexed by.

use glam::Vec2;
use multiversion::multiversion;

use super::sobol::{SobolSeeds, sobol_1d, sobol_1d_seeded, sobol_2d, sobol_2d_seeded};
use crate::scene::SamplerKind;

/// The dimension of the pixel offset; the offset uses dimensions 0 and 1.
pub const DIM_PIXEL: u32 = 0;

/// Field widths of the packed light dimension (see [`light_dim`]).
const DEPTH_BITS: u32 = 4;
/// Bits for the path (branch) index.
const PATH_BITS: u32 = 8;
/// Bits for the light index.
const LIGHT_BITS: u32 = 9;
/// Bits for the light sample index.
const LIGHT_SAMPLE_BITS: u32 = 9;

/// Counter-based random numbers: every value is a pure function of (seed, pixel, sample index, dimension).
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    /// Which points the pixel and light samples use.
    pub kind: SamplerKind,
    /// The seed (from the settings), mixed: the first step of every hash, done once.
    seed_hash: u64,
}

/// Which light sample slot of a shading point: (depth, path, light) as in [`light_dim`].
pub type LightSlot = (u32, u32, u32);

/// The splitmix64 finaliser: a bijective 64-bit mixer with full avalanche.
#[inline(always)]
fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

impl Sampler {
    /// An independent sampler for the given seed.
    pub fn new(seed: u64) -> Self {
        Self::with_kind(seed, SamplerKind::Independent)
    }

    /// A sampler of the given kind.
    pub fn with_kind(seed: u64, kind: SamplerKind) -> Self {
        Self {
            kind,
            seed_hash: mix64(seed),
        }
    }

    /// Which of the two Sobol' replicas sample `sample` belongs to (0 or 1), and its
    /// index within it: even and odd samples are independently scrambled sequences, so
    /// their difference estimates the error (see `Film::error_estimate`).
    pub fn sobol_replica(sample: u32) -> (u32, u32) {
        (sample & 1, sample >> 1)
    }

    /// The 32-bit scramble seed of one dimension pair, for the low-discrepancy kinds.
    fn pattern_seed(&self, pixel: u32, dim: u32, extra: u32) -> u32 {
        let h = self.hash(pixel, extra, dim);
        (h >> 32) as u32 ^ h as u32
    }

    /// The pixel offset pair of `sample` in [0,1)^2 (dimensions `DIM_PIXEL`, +1).
    pub fn pixel2(&self, pixel: u32, sample: u32) -> Vec2 {
        match self.kind {
            SamplerKind::Sobol => {
                let (replica, index) = Self::sobol_replica(sample);
                Vec2::from(sobol_2d(
                    index,
                    self.pattern_seed(pixel, DIM_PIXEL, replica),
                ))
            }
            SamplerKind::Independent | SamplerKind::Stratified => {
                self.get2(pixel, sample, DIM_PIXEL)
            }
        }
    }

    /// `pixel2(pixels[j], sample)` in each lane `j`: for the independent and stratified
    /// kinds, the hashes of all lanes in one loop (vectorised in its AVX2 clone).
    pub fn pixel2_lanes(
        &self,
        pixels: &[u32; SLOT_LANES],
        sample: u32,
        u: &mut [f32; SLOT_LANES],
        v: &mut [f32; SLOT_LANES],
    ) {
        match self.kind {
            SamplerKind::Sobol => {
                for ((u, v), &pixel) in u.iter_mut().zip(v.iter_mut()).zip(pixels) {
                    (*u, *v) = self.pixel2(pixel, sample).into();
                }
            }
            SamplerKind::Independent | SamplerKind::Stratified => {
                let mut prefix = [0; SLOT_LANES];
                prefixes(self.seed_hash, pixels, sample, &mut prefix);
                units(&prefix, &[DIM_PIXEL; SLOT_LANES], 0, u);
                units(&prefix, &[DIM_PIXEL; SLOT_LANES], 1, v);
            }
        }
    }

    /// Sample `k` of `n` on a light, 1D. Independent: dimension `light_dim(.., k)`.
    /// Stratified: point k of a scrambled Sobol' set per (pixel, sample, slot), so the n
    /// samples of one shading point are stratified. Sobol': point `index * n + k` of the
    /// slot's sequence, so they are stratified across passes too.
    pub fn light1(&self, pixel: u32, sample: u32, slot: LightSlot, k: u32, n: u32) -> f32 {
        self.at(pixel, sample).light1(slot, k, n)
    }

    /// Sample `k` of `n` on a light, 2D; see [`Sampler::light1`].
    pub fn light2(&self, pixel: u32, sample: u32, slot: LightSlot, k: u32, n: u32) -> Vec2 {
        self.at(pixel, sample).light2(slot, k, n)
    }

    /// The light samples of camera sample `sample` in `pixel`: what every light sample
    /// of its shading points shares is hashed here, once.
    pub fn at(&self, pixel: u32, sample: u32) -> PointSampler {
        // The low-discrepancy kinds key their scramble by the Sobol' replica, not the
        // sample (see `light_point`); independent numbers by the sample.
        let extra = match self.kind {
            SamplerKind::Sobol => Self::sobol_replica(sample).0,
            SamplerKind::Independent | SamplerKind::Stratified => sample,
        };
        PointSampler {
            kind: self.kind,
            sample,
            prefix: self.prefix(pixel, extra),
        }
    }

    /// [`Self::at`] of `pixels[j]` in each lane `j`, the hashes in one loop.
    pub fn at_lanes(&self, pixels: &[u32; SLOT_LANES], sample: u32) -> [PointSampler; SLOT_LANES] {
        let extra = match self.kind {
            SamplerKind::Sobol => Self::sobol_replica(sample).0,
            SamplerKind::Independent | SamplerKind::Stratified => sample,
        };
        let mut prefix = [0; SLOT_LANES];
        prefixes(self.seed_hash, pixels, extra, &mut prefix);
        prefix.map(|prefix| PointSampler {
            kind: self.kind,
            sample,
            prefix,
        })
    }

    /// The running hash after (seed, pixel, sample): `hash` without the dimension.
    fn prefix(&self, pixel: u32, sample: u32) -> u64 {
        // Chain the mixer over the inputs: each step is a bijection of the
        // running state xor-ed with the next input, so nearby counters give
        // unrelated outputs and no input is lost.
        mix64(self.seed_hash ^ ((u64::from(pixel) << 32) | u64::from(sample)))
    }

    /// The 64-bit hash of (seed, pixel, sample, dim).
    fn hash(&self, pixel: u32, sample: u32, dim: u32) -> u64 {
        mix64(self.prefix(pixel, sample) ^ u64::from(dim))
    }

    /// A number in [0, 1).
    pub fn get1(&self, pixel: u32, sample: u32, dim: u32) -> f32 {
        unit_from_hash(self.hash(pixel, sample, dim))
    }

    /// Two numbers in [0,1)^2 (dimensions dim and dim+1).
    pub fn get2(&self, pixel: u32, sample: u32, dim: u32) -> Vec2 {
        Vec2::new(
            self.get1(pixel, sample, dim),
            self.get1(pixel, sample, dim.wrapping_add(1)),
        )
    }
}

/// A number in [0, 1) from a 64-bit hash.
#[inline(always)]
fn unit_from_hash(h: u64) -> f32 {
    // 24 bits fill an f32 mantissa exactly: the result is a multiple of
    // 2^-24 and at most 1 - 2^-24 (the largest f32 below 1), never 1.0, with no rounding and no
    // clamp (a `min(BELOW_ONE)` here changed nothing and cost a NaN-aware blend).
    let bits = (h >> 40) as u32;
    bits as f32 * (1.0 / 16_777_216.0)
}

/// The light samples of one camera sample ([`Sampler::at`]): the same numbers as
/// [`Sampler::light1`] and [`Sampler::light2`], with (seed, pixel, sample) hashed once.
#[derive(Clone, Copy, Debug)]
pub struct PointSampler {
    kind: SamplerKind,
    sample: u32,
    /// `Sampler::prefix` of (pixel, sample), or of (pixel, replica) for Sobol'.
    prefix: u64,
}

impl PointSampler {
    /// Sample `k` of `n` on a light, 1D; see [`Sampler::light1`].
    #[inline]
    pub fn light1(&self, slot: LightSlot, k: u32, n: u32) -> f32 {
        let (depth, path, light) = slot;
        match self.kind {
            SamplerKind::Independent => self.get1(light_dim(depth, path, light, k)),
            _ => {
                let (index, seed) = self.light_point(slot, k, n);
                sobol_1d(index, seed)
            }
        }
    }

    /// Sample `k` of `n` on a light, 2D; see [`Sampler::light1`].
    #[inline]
    pub fn light2(&self, slot: LightSlot, k: u32, n: u32) -> Vec2 {
        let (depth, path, light) = slot;
        match self.kind {
            SamplerKind::Independent => {
                let dim = light_dim(depth, path, light, k);
                Vec2::new(self.get1(dim), self.get1(dim.wrapping_add(1)))
            }
            _ => {
                let (index, seed) = self.light_point(slot, k, n);
                Vec2::from(sobol_2d(index, seed))
            }
        }
    }

    /// The `n` samples of light slot `slot`: for the low-discrepancy kinds their shared
    /// scramble seed is hashed here, once, instead of once per sample.
    #[inline]
    pub fn slot(&self, slot: LightSlot, n: u32) -> SlotSampler {
        let (base, seeds, first_dim) = match self.kind {
            SamplerKind::Independent => {
                let (depth, path, light) = slot;
                (
                    0,
                    SobolSeeds::default(),
                    packed_light_dim(depth, path, light),
                )
            }
            _ => {
                let (base, seed) = self.light_point(slot, 0, n);
                (base, SobolSeeds::new(seed), None)
            }
        };
        SlotSampler {
            point: *self,
            slot,
            base,
            seeds,
            first_dim,
        }
    }

    /// [`Sampler::get1`] of this pixel and sample.
    fn get1(&self, dim: u32) -> f32 {
        unit_from_hash(mix64(self.prefix ^ u64::from(dim)))
    }

    /// Point index and scramble seed of light sample `k` of `n` (low-discrepancy kinds):
    /// `Sampler::pattern_seed` of the slot's first dimension.
    fn light_point(&self, slot: LightSlot, k: u32, n: u32) -> (u32, u32) {
        let (depth, path, light) = slot;
        let dim = light_dim(depth, path, light, 0);
        let h = mix64(self.prefix ^ u64::from(dim));
        let seed = (h >> 32) as u32 ^ h as u32;
        match self.kind {
            SamplerKind::Sobol => {
                let (_, index) = Sampler::sobol_replica(self.sample);
                (index.wrapping_mul(n).wrapping_add(k), seed)
            }
            _ => (k, seed),
        }
    }
}

/// The samples of one light slot of one shading point ([`PointSampler::slot`]): the
/// same numbers as [`PointSampler::light1`] and [`PointSampler::light2`].
#[derive(Clone, Copy, Debug)]
pub struct SlotSampler {
    point: PointSampler,
    slot: LightSlot,
    /// Sobol' index of sample 0 (low-discrepancy kinds); sample k is `base + k`.
    base: u32,
    /// The hashes of the slot's scramble seed (low-discrepancy kinds), once per slot
    /// rather than once per sample.
    seeds: SobolSeeds,
    /// `light_dim(depth, path, light, 0)` when the slot's (depth, path, light) are
    /// packed exactly (independent kind): sample k's dimension is then `first + 2 k`.
    first_dim: Option<u32>,
}

impl SlotSampler {
    /// `light_dim` of sample `k` of the slot (independent kind).
    #[inline]
    fn dim(&self, k: u32) -> u32 {
        match self.first_dim {
            // Packed: k fills the low field, which is zero in `first`.
            Some(first) if k < 1 << LIGHT_SAMPLE_BITS => first + 2 * k,
            _ => {
                let (depth, path, light) = self.slot;
                light_dim(depth, path, light, k)
            }
        }
    }

    /// Sample `k` of the slot, 1D.
    // Always inlined into the light-sample loop: as a call, the slot went through memory.
    #[inline(always)]
    pub fn light1(&self, k: u32) -> f32 {
        match self.point.kind {
            SamplerKind::Independent => self.point.get1(self.dim(k)),
            _ => sobol_1d_seeded(self.base.wrapping_add(k), &self.seeds),
        }
    }

    /// Sample `k` of the slot, 2D.
    #[inline(always)]
    pub fn light2(&self, k: u32) -> Vec2 {
        match self.point.kind {
            SamplerKind::Independent => {
                let dim = self.dim(k);
                Vec2::new(self.point.get1(dim), self.point.get1(dim.wrapping_add(1)))
            }
            _ => Vec2::from(sobol_2d_seeded(self.base.wrapping_add(k), &self.seeds)),
        }
    }
}

/// Shading points side by side in [`SlotLanes`].
pub const SLOT_LANES: usize = 8;

/// One light slot's samples at [`SLOT_LANES`] shading points side by side (lanes
/// without a point give 0): the numbers of each lane's [`SlotSampler`], with the
/// independent kind's hashes done for all lanes in one loop (vectorised in its AVX2 clone).
#[derive(Clone, Copy, Debug)]
pub struct SlotLanes {
    slots: [Option<SlotSampler>; SLOT_LANES],
    /// Each lane's `PointSampler` prefix (0 without a slot).
    prefix: [u64; SLOT_LANES],
    /// Each lane's dimension of sample 0 (0 without a slot).
    first: [u32; SLOT_LANES],
    /// Whether every slot is of the independent kind with packed dimensions, so that
    /// sample k's dimension is `first + 2 k` (for k below the packed field's bound).
    packed: bool,
}

impl SlotLanes {
    /// The lanes of `points[j].slot(slot(j), n)` in each lane `j` set in `lanes` (the
    /// others without a slot), for samples `k < n`. The independent kind's packed slots
    /// need only their prefix and first dimension: no `SlotSampler` is made for them
    /// unless `n` reaches past the packed sample field.
    pub fn new(
        points: &[PointSampler; SLOT_LANES],
        lanes: u32,
        slot: impl Fn(usize) -> LightSlot,
        n: u32,
    ) -> Self {
        match PackedSlots::new(points, lanes, &slot, n) {
            Some(PackedSlots { prefix, first }) => Self {
                slots: [None; SLOT_LANES],
                prefix,
                first,
                packed: true,
            },
            None => Self {
                slots: std::array::from_fn(|j| {
                    (lanes & (1 << j) != 0).then(|| points[j].slot(slot(j), n))
                }),
                prefix: [0; SLOT_LANES],
                first: [0; SLOT_LANES],
                packed: false,
            },
        }
    }

    /// Sample `k` of each lane's slot, 1D ([`SlotSampler::light1`]).
    pub fn light1(&self, k: u32, out: &mut [f32; SLOT_LANES]) {
        if self.packed && k < 1 << LIGHT_SAMPLE_BITS {
            units(&self.prefix, &self.first, 2 * k, out);
        } else {
            for (o, s) in out.iter_mut().zip(&self.slots) {
                *o = s.map_or(0.0, |s| s.light1(k));
            }
        }
    }

    /// Sample `k` of each lane's slot, 2D ([`SlotSampler::light2`]).
    pub fn light2(&self, k: u32, u: &mut [f32; SLOT_LANES], v: &mut [f32; SLOT_LANES]) {
        if self.packed && k < 1 << LIGHT_SAMPLE_BITS {
            units(&self.prefix, &self.first, 2 * k, u);
            units(&self.prefix, &self.first, 2 * k + 1, v);
        } else {
            for ((u, v), s) in u.iter_mut().zip(v.iter_mut()).zip(&self.slots) {
                let uv = s.map_or(Vec2::ZERO, |s| s.light2(k));
                (*u, *v) = (uv.x, uv.y);
            }
        }
    }
}

/// [`SlotLanes`] whose samples `k < n` are all packed (the independent kind within the
/// packed fields): each lane's prefix and first dimension, all their numbers need. Made
/// without the lanes' `SlotSampler`s, and its numbers inline into a caller's own AVX2
/// clone.
#[derive(Clone, Copy, Debug)]
pub struct PackedSlots {
    /// Each lane's `PointSampler` prefix (0 without a slot).
    prefix: [u64; SLOT_LANES],
    /// Each lane's dimension of sample 0 (0 without a slot).
    first: [u32; SLOT_LANES],
}

impl PackedSlots {
    /// The slots [`SlotLanes::new`] makes of the same arguments, if they are all packed.
    pub fn new(
        points: &[PointSampler; SLOT_LANES],
        lanes: u32,
        slot: impl Fn(usize) -> LightSlot,
        n: u32,
    ) -> Option<Self> {
        if n > 1 << LIGHT_SAMPLE_BITS {
            return None;
        }
        let mut prefix = [0; SLOT_LANES];
        let mut first = [0; SLOT_LANES];
        for (j, p) in points.iter().enumerate() {
            if lanes & (1 << j) == 0 {
                continue;
            }
            let (depth, path, light) = slot(j);
            match (p.kind, packed_light_dim(depth, path, light)) {
                (SamplerKind::Independent, Some(d)) => (prefix[j], first[j]) = (p.prefix, d),
                _ => return None,
            }
        }
        Some(Self { prefix, first })
    }

    /// [`SlotLanes::light2`] of sample `k` (below the `n` they were made for).
    #[inline(always)]
    pub fn light2(&self, k: u32, u: &mut [f32; SLOT_LANES], v: &mut [f32; SLOT_LANES]) {
        unit_lanes(&self.prefix, &self.first, 2 * k, u);
        unit_lanes(&self.prefix, &self.first, 2 * k + 1, v);
    }
}

/// `Sampler::prefix(pixels[j], sample)` in each lane.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn prefixes(seed_hash: u64, pixels: &[u32; SLOT_LANES], sample: u32, out: &mut [u64; SLOT_LANES]) {
    for (o, &pixel) in out.iter_mut().zip(pixels) {
        *o = mix64(seed_hash ^ ((u64::from(pixel) << 32) | u64::from(sample)));
    }
}

/// `PointSampler::get1` of dimension `first + add` in each lane; lanes whose prefix and
/// first dimension are 0 get some number, unused.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn units(
    prefix: &[u64; SLOT_LANES],
    first: &[u32; SLOT_LANES],
    add: u32,
    out: &mut [f32; SLOT_LANES],
) {
    unit_lanes(prefix, first, add, out);
}

/// The loop of [`units`], inlined into its callers' clones.
#[inline(always)]
fn unit_lanes(
    prefix: &[u64; SLOT_LANES],
    first: &[u32; SLOT_LANES],
    add: u32,
    out: &mut [f32; SLOT_LANES],
) {
    for ((o, &p), &f) in out.iter_mut().zip(prefix).zip(first) {
        *o = unit_from_hash(mix64(p ^ u64::from(f + add)));
    }
}

/// The dimension of one light sample: distinct for distinct inputs in practical ranges, always even and never 0 or 1.
///
/// The result is meant for [`Sampler::get2`], which also uses `dim + 1`, so
/// it is even. Inputs within `depth < 16`, `path < 256`, `light < 512`,
/// `light_sample < 512` are packed exactly (no collisions at all) into
/// `[2, 2^31)`; anything larger is hashed into `[2^31, 2^32)`, where
/// collisions are possible but rare. The sampler hashes the dimension again,
/// so consecutive dimensions are as independent as any others.
pub fn light_dim(depth: u32, path: u32, light: u32, light_sample: u32) -> u32 {
    match packed_light_dim(depth, path, light) {
        // Light sample 0's packed field is zero: `light_sample` fills it.
        Some(first) if light_sample < (1 << LIGHT_SAMPLE_BITS) => first + 2 * light_sample,
        _ => hashed_light_dim(depth, path, light, light_sample),
    }
}

/// `light_dim(depth, path, light, 0)` when (depth, path, light) are packed exactly.
fn packed_light_dim(depth: u32, path: u32, light: u32) -> Option<u32> {
    let fits = depth < (1 << DEPTH_BITS) && path < (1 << PATH_BITS) && light < (1 << LIGHT_BITS);
    // packed < 2^30, so 2 + 2 * packed < 2^31: even, above the pixel dims.
    fits.then(|| 2 + 2 * (((depth << PATH_BITS | path) << LIGHT_BITS | light) << LIGHT_SAMPLE_BITS))
}

/// `light_dim` outside the packed range.
// Cold and out of line: inlined, LLVM hoisted part of its hash into every shading point.
#[cold]
#[inline(never)]
fn hashed_light_dim(depth: u32, path: u32, light: u32, light_sample: u32) -> u32 {
    let h = mix64(
        mix64((u64::from(depth) << 32) | u64::from(path))
            ^ ((u64::from(light) << 32) | u64::from(light_sample)),
    );
    // Top bit set keeps this range apart from the packed one; low bit clear keeps it even.
    ((h >> 32) as u32 | 0x8000_0000) & !1
}

#[cfg(test)]
#[path = "sampler_tests.rs"]
mod tests;
