use super::*;
use std::collections::HashSet;

#[test]
fn deterministic() {
    let a = Sampler::new(7);
    let b = Sampler::new(7);
    for i in 0..100 {
        assert_eq!(a.get1(i, i * 3, i % 5), b.get1(i, i * 3, i % 5));
        assert_eq!(a.get2(i, 2, 0), b.get2(i, 2, 0));
    }
}

#[test]
fn inputs_change_the_value() {
    let s = Sampler::new(1);
    let base = s.get1(10, 20, 30);
    assert_ne!(base, s.get1(11, 20, 30), "pixel");
    assert_ne!(base, s.get1(10, 21, 30), "sample");
    assert_ne!(base, s.get1(10, 20, 31), "dim");
    assert_ne!(base, Sampler::new(2).get1(10, 20, 30), "seed");
    let v = s.get2(3, 4, DIM_PIXEL);
    assert_ne!(v.x, v.y);
    // Swapping pixel and sample must not give the same number.
    assert_ne!(s.get1(5, 9, 0), s.get1(9, 5, 0));
}

#[test]
fn values_in_unit_interval_and_mean_half() {
    let s = Sampler::new(42);
    let mut sum = 0.0f64;
    let n = 100_000u32;
    for i in 0..n {
        let x = s.get1(i / 16, i % 16, 3);
        assert!((0.0..1.0).contains(&x), "{x}");
        sum += f64::from(x);
    }
    let mean = sum / f64::from(n);
    // Standard error is 0.289 / sqrt(1e5) = 0.0009; 0.005 is > 5 sigma.
    assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
}

#[test]
fn chi_square_2d_pixel_samples() {
    let s = Sampler::new(0);
    let mut bins = [0u32; 64];
    let n = 100_000u32;
    for i in 0..n {
        let p = s.get2(i / 8, i % 8, DIM_PIXEL);
        let bx = (p.x * 8.0) as usize;
        let by = (p.y * 8.0) as usize;
        bins[by * 8 + bx] += 1;
    }
    let chi2 = crate::test_util::chi_square(&bins);
    // 63 degrees of freedom: the critical value at p = 1e-4 is about 113.6.
    assert!(chi2 < 113.6, "chi2 {chi2}");
    // And not suspiciously perfect (p = 1e-4 lower tail is about 29).
    assert!(chi2 > 29.0, "chi2 {chi2}");
}

#[test]
fn light_dims_distinct_and_not_pixel() {
    let mut seen = HashSet::new();
    for depth in 0..8 {
        for path in 0..4 {
            for light in 0..20 {
                for ls in 0..64 {
                    let d = light_dim(depth, path, light, ls);
                    assert!(d >= 2 && d.is_multiple_of(2), "{d}");
                    // get2 uses d and d + 1: neither may be shared.
                    assert!(seen.insert(d), "duplicate {d}");
                }
            }
        }
    }
}

#[test]
fn a_shading_points_light_samples_are_stratified() {
    use crate::sampling::sobol::is_net;
    let slot = (1, 0, 3);
    for seed in [0, 5] {
        for pixel in [0, 17, 4000] {
            for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
                let s = Sampler::with_kind(seed, kind);
                for sample in 0..4 {
                    let points: Vec<[f32; 2]> = (0..16)
                        .map(|k| s.light2(pixel, sample, slot, k, 16).to_array())
                        .collect();
                    assert!(is_net(&points, 4), "{kind:?} pixel {pixel} sample {sample}");
                    let line: Vec<f32> = (0..16)
                        .map(|k| s.light1(pixel, sample, slot, k, 16))
                        .collect();
                    let mut cells = [0; 16];
                    line.iter().for_each(|&u| cells[(u * 16.0) as usize] += 1);
                    assert!(cells.iter().all(|&c| c == 1), "{kind:?} 1D");
                }
            }
            // Sobol': the even passes (one replica) together are stratified too, and
            // so are their pixel offsets.
            let s = Sampler::with_kind(seed, SamplerKind::Sobol);
            let over_passes: Vec<[f32; 2]> = (0..8)
                .flat_map(|pass| (0..16).map(move |k| (2 * pass, k)))
                .map(|(sample, k)| s.light2(pixel, sample, slot, k, 16).to_array())
                .collect();
            assert!(is_net(&over_passes, 7));
            let offsets: Vec<[f32; 2]> = (0..32)
                .map(|j| s.pixel2(pixel, 2 * j + 1).to_array())
                .collect();
            assert!(is_net(&offsets, 5));
        }
    }
}

#[test]
fn independent_light_samples_are_the_old_dimensions() {
    let s = Sampler::new(4);
    assert_eq!(
        s.light1(3, 2, (1, 0, 5), 7, 9),
        s.get1(3, 2, light_dim(1, 0, 5, 7))
    );
    assert_eq!(
        s.light2(3, 2, (1, 0, 5), 7, 9),
        s.get2(3, 2, light_dim(1, 0, 5, 7))
    );
    assert_eq!(s.pixel2(3, 2), s.get2(3, 2, DIM_PIXEL));
}

#[test]
fn point_sampler_gives_the_per_call_numbers() {
    // The numbers as derived before the per-point hash was hoisted: every kind, every
    // input from scratch through `get1`, `get2` and `pattern_seed`.
    for kind in [
        SamplerKind::Independent,
        SamplerKind::Stratified,
        SamplerKind::Sobol,
    ] {
        let s = Sampler::with_kind(9, kind);
        for (pixel, sample) in [(0, 0), (5, 1), (4000, 6), (77, 13)] {
            let point = s.at(pixel, sample);
            // The edges of light_dim's packed fields too: the slot's first dimension
            // plus 2 k holds only inside them.
            for (slot, k, n) in [
                ((0, 0, 0), 0, 1),
                ((1, 2, 3), 3, 4),
                ((2, 5, 600), 7, 9),
                ((15, 255, 511), 511, 512),
                ((15, 255, 511), 512, 600),
                ((16, 0, 0), 1, 2),
                ((0, 256, 0), 1, 2),
                ((0, 0, 512), 1, 2),
            ] {
                let (depth, path, light) = slot;
                let (u, uv) = match kind {
                    SamplerKind::Independent => {
                        let dim = light_dim(depth, path, light, k);
                        (s.get1(pixel, sample, dim), s.get2(pixel, sample, dim))
                    }
                    _ => {
                        let (replica, index) = Sampler::sobol_replica(sample);
                        let (extra, index) = match kind {
                            SamplerKind::Sobol => (replica, index * n + k),
                            _ => (sample, k),
                        };
                        let dim = light_dim(depth, path, light, 0);
                        let seed = s.pattern_seed(pixel, dim, extra);
                        (sobol_1d(index, seed), Vec2::from(sobol_2d(index, seed)))
                    }
                };
                assert_eq!(point.light1(slot, k, n).to_bits(), u.to_bits(), "{kind:?}");
                let slotted = point.slot(slot, n);
                assert_eq!(slotted.light1(k).to_bits(), u.to_bits(), "{kind:?}");
                assert_eq!(slotted.light2(k), uv, "{kind:?}");
                assert_eq!(point.light2(slot, k, n), uv, "{kind:?}");
                assert_eq!(s.light2(pixel, sample, slot, k, n), uv, "{kind:?}");
                // The same numbers in lanes (lane 3 has no point: its number is unused).
                let points = s.at_lanes(&[pixel; SLOT_LANES], sample);
                let lanes = SlotLanes::new(&points, !(1 << 3), |_| slot, n);
                let (mut u1, mut u2, mut v2) = ([0.0; SLOT_LANES], [0.0; 8], [0.0; 8]);
                lanes.light1(k, &mut u1);
                lanes.light2(k, &mut u2, &mut v2);
                for j in (0..SLOT_LANES).filter(|&j| j != 3) {
                    let got = (u1[j].to_bits(), Vec2::new(u2[j], v2[j]));
                    assert_eq!(got, (u.to_bits(), uv), "{kind:?} {slot:?} {k} of {n}");
                }
                // Packed where the independent kind packs every sample below n.
                let packed = PackedSlots::new(&points, !(1 << 3), |_| slot, n);
                let packs = kind == SamplerKind::Independent
                    && packed_light_dim(depth, path, light).is_some()
                    && n <= 1 << LIGHT_SAMPLE_BITS;
                assert_eq!(packed.is_some(), packs, "{kind:?} {slot:?} {n}");
                if let Some(packed) = packed {
                    packed.light2(k, &mut u2, &mut v2);
                    for j in (0..SLOT_LANES).filter(|&j| j != 3) {
                        assert_eq!(Vec2::new(u2[j], v2[j]), uv, "{slot:?} {k} of {n}");
                    }
                }
            }
        }
    }
}

#[test]
fn numbers_are_the_chained_hash_of_seed_pixel_sample_and_dimension() {
    // From scratch: the mixer chained over seed, (pixel, sample) and dimension, with
    // nothing hashed ahead (the sampler keeps the seed's hash).
    for (seed, pixel, sample, dim) in [(0, 0, 0, 0), (7, 3, 5, 11), (u64::MAX, 4000, 15, 2)] {
        let h = mix64(mix64(mix64(seed) ^ (u64::from(pixel) << 32 | u64::from(sample))) ^ dim);
        let expected = (h >> 40) as f32 / 16_777_216.0;
        let s = Sampler::new(seed);
        assert_eq!(s.get1(pixel, sample, dim as u32), expected);
        assert_eq!(s.at(pixel, sample).get1(dim as u32), expected);
    }
}

#[test]
fn unit_values_stay_below_one_unclamped() {
    // The largest f32 below 1: what the all-ones hash gives, exactly.
    assert_eq!(unit_from_hash(u64::MAX), 1.0 - f32::EPSILON / 2.0);
    assert_eq!(unit_from_hash(0), 0.0);
    assert_eq!(unit_from_hash(1 << 40), 1.0 / 16_777_216.0);
}

#[test]
fn light_dims_outside_packed_range() {
    let a = light_dim(100, 0, 0, 0);
    let b = light_dim(0, 0, 100_000, 0);
    let c = light_dim(0, 0, 0, 100_000);
    for d in [a, b, c] {
        assert!(d >= 0x8000_0000 && d.is_multiple_of(2), "{d}");
    }
    assert!(a != b && b != c && a != c);
    assert_eq!(light_dim(u32::MAX, u32::MAX, u32::MAX, u32::MAX) & 1, 0);
}
