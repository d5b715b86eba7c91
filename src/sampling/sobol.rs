//! Owen-scrambled Sobol' points in one and two dimensions, after Burley 2020,
//! "Practical Hash-based Owen Scrambling" (JCGT 9(4)).
//!
//! Only the first two Sobol' dimensions are used: their 2D projection is a
//! (0,2)-sequence, so every aligned block of 2^m points has exactly one point in each
//! elementary interval of area 2^-m. Higher dimensions are *padded* (as pbrt-v4's
//! `PaddedSobolSampler` does): each dimension pair of a sample gets its own seed, which
//! both Owen-scrambles the points and shuffles the sample index, so distinct pairs are
//! decorrelated. A shuffled index keeps its low bits' block structure (Burley, sec. 4),
//! so the first 2^m shuffled points are still stratified.

/// Bits of a coordinate; a point's value is `bits / 2^32`.
const SCALE: f32 = 1.0 / 4_294_967_296.0;

/// The largest `f32` below 1: values never reach 1.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// Sobol' dimension 1 of `index`: the generator matrix is Pascal's triangle mod 2,
/// whose column k is `v[k] = v[k-1] ^ (v[k-1] >> 1)`, `v[0] = 2^31`.
fn sobol_dim1(index: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut x = 0u32;
    let mut i = index;
    while i != 0 {
        if i & 1 != 0 {
            x ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    x
}

/// Burley's improved Laine-Karras hash: bit k of the result depends only on bits <= k
/// of `x`, which makes it a nested (Owen) permutation of the bit-reversed value.
fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scrambling of a 32-bit fixed-point value in [0, 1): each bit is flipped by a
/// hash of the bits above it.
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// A 32-bit hash for deriving independent seeds (the lowbias32 mixer).
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

fn to_unit(bits: u32) -> f32 {
    // Rounding to f32 can reach 1.0 from the top 2^-25 of the range.
    (bits as f32 * SCALE).min(BELOW_ONE)
}

/// The three hashes a sequence's `seed` gives (index shuffle, scramble of each
/// dimension): computed once for the many points of one seed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SobolSeeds {
    shuffle: u32,
    dim0: u32,
    dim1: u32,
}

impl SobolSeeds {
    /// The hashes of `seed`.
    pub fn new(seed: u32) -> Self {
        Self {
            shuffle: hash32(seed),
            dim0: hash32(seed ^ 0x5bd1_e995),
            dim1: hash32(seed ^ 0x68e3_1da4),
        }
    }
}

/// Point `index` of the 1D Owen-scrambled Sobol' (van der Corput) sequence for `seed`, in [0, 1).
pub fn sobol_1d(index: u32, seed: u32) -> f32 {
    sobol_1d_seeded(index, &SobolSeeds::new(seed))
}

/// Point `index` of the 2D Owen-scrambled Sobol' sequence for `seed`, in [0, 1)^2.
pub fn sobol_2d(index: u32, seed: u32) -> [f32; 2] {
    sobol_2d_seeded(index, &SobolSeeds::new(seed))
}

/// [`sobol_1d`] with the seed's hashes given.
#[inline]
pub fn sobol_1d_seeded(index: u32, seeds: &SobolSeeds) -> f32 {
    let i = nested_uniform_scramble(index, seeds.shuffle);
    to_unit(nested_uniform_scramble(i.reverse_bits(), seeds.dim0))
}

/// [`sobol_2d`] with the seed's hashes given.
#[inline]
pub fn sobol_2d_seeded(index: u32, seeds: &SobolSeeds) -> [f32; 2] {
    let i = nested_uniform_scramble(index, seeds.shuffle);
    [
        to_unit(nested_uniform_scramble(i.reverse_bits(), seeds.dim0)),
        to_unit(nested_uniform_scramble(sobol_dim1(i), seeds.dim1)),
    ]
}

/// Whether `points` (2^m of them) put exactly one point in every elementary interval
/// `[a 2^-i, (a+1) 2^-i) x [b 2^-(m-i), (b+1) 2^-(m-i))`, for tests.
#[cfg(test)]
pub(crate) fn is_net(points: &[[f32; 2]], m: u32) -> bool {
    (0..=m).all(|i| {
        let (nx, ny) = (1usize << i, 1usize << (m - i));
        let mut cells = vec![0u32; nx * ny];
        for p in points {
            let cx = (f64::from(p[0]) * nx as f64) as usize;
            let cy = (f64::from(p[1]) * ny as f64) as usize;
            cells[cy * nx + cx] += 1;
        }
        cells.iter().all(|&c| c == 1)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unscrambled_dimensions_are_the_known_sequence() {
        // Sobol' dimension 1 in index (not Gray-code) order: 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8.
        let expected = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, e) in expected.iter().enumerate() {
            assert_eq!(sobol_dim1(i as u32) as f64 / 4_294_967_296.0, *e, "{i}");
        }
    }

    #[test]
    fn first_points_are_stratified_in_every_elementary_interval() {
        // Several seeds stand for several dimension pairs of a sample (pixel, lights).
        for seed in [0, 1, 7, 0xdead_beef, 123_456_789] {
            for m in 0..=10 {
                let n = 1u32 << m;
                let points: Vec<[f32; 2]> = (0..n).map(|i| sobol_2d(i, seed)).collect();
                assert!(is_net(&points, m), "seed {seed}, 2^{m} points");
                // The next block of 2^m points is a net too (progressive passes).
                let next: Vec<[f32; 2]> = (n..2 * n).map(|i| sobol_2d(i, seed)).collect();
                assert!(is_net(&next, m), "seed {seed}, second block of 2^{m}");
            }
        }
    }

    #[test]
    fn one_dimension_is_stratified() {
        for seed in [3, 99] {
            let mut cells = [0u32; 256];
            for i in 0..256 {
                cells[(sobol_1d(i, seed) * 256.0) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1));
        }
    }

    #[test]
    fn seeds_give_different_points() {
        assert_ne!(sobol_2d(5, 1), sobol_2d(5, 2));
        assert_ne!(sobol_1d(5, 1), sobol_1d(5, 2));
        // The index is shuffled: point 0 is not the same corner for every seed.
        let firsts: Vec<[f32; 2]> = (0..8).map(|s| sobol_2d(0, s)).collect();
        assert!(firsts.windows(2).all(|w| w[0] != w[1]));
    }

    #[test]
    fn scrambled_replicas_agree_in_mean() {
        // f(x, y) = x y^2 + sin(3x): integral 1/6 + (1 - cos 3)/3.
        let truth = 1.0 / 6.0 + (1.0 - 3f64.cos()) / 3.0;
        let f = |p: [f32; 2]| {
            let (x, y) = (f64::from(p[0]), f64::from(p[1]));
            x * y * y + (3.0 * x).sin()
        };
        let replicas: Vec<f64> = (0..200u32)
            .map(|seed| (0..16).map(|i| f(sobol_2d(i, seed))).sum::<f64>() / 16.0)
            .collect();
        let n = replicas.len() as f64;
        let mean = replicas.iter().sum::<f64>() / n;
        let var = replicas.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        assert!(
            (mean - truth).abs() < 4.0 * se,
            "{mean} vs {truth} (se {se})"
        );
        // And far better than independent points: plain Monte Carlo with 16 points has
        // a standard deviation of about 0.09 here.
        assert!(var.sqrt() < 0.02, "replica spread {}", var.sqrt());
    }

    #[test]
    fn values_in_unit_interval() {
        for seed in 0..50 {
            for i in [0, 1, 2, 1000, u32::MAX] {
                let p = sobol_2d(i, seed);
                assert!((0.0..1.0).contains(&p[0]) && (0.0..1.0).contains(&p[1]));
                assert!((0.0..1.0).contains(&sobol_1d(i, seed)));
            }
        }
    }
}
