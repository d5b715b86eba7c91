//! Where camera samples fall inside their pixel (SPEC "Multisampling").

use glam::Vec2;

use super::sampler::Sampler;
use crate::scene::{PixelSampling, SamplerKind, Settings};

/// The largest `f32` below 1: offsets stay strictly inside their pixel.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// The side of the stratified grid for `n` requested samples: `round(sqrt(n))`, at least 1.
fn grid_side(n: u32) -> u32 {
    ((f64::from(n)).sqrt().round() as u32).max(1)
}

/// Number of samples actually taken for `n` requested: n for uniform, k*k with k = round(sqrt(n)) (at least 1) for stratified.
///
/// `n = 0` is treated as 1 in both modes so that averaging never divides by zero.
pub fn samples_taken(n: u32, mode: PixelSampling) -> u32 {
    match mode {
        PixelSampling::Uniform => n.max(1),
        PixelSampling::Stratified => {
            let k = grid_side(n);
            k.saturating_mul(k)
        }
    }
}

/// The pixel pattern the settings call for: Sobol' points cover the pixel themselves,
/// so under `sampler: sobol` the pattern is the sampler's, whatever `pixel_sampling` says.
pub fn pixel_mode(settings: &Settings) -> PixelSampling {
    match settings.sampler {
        SamplerKind::Sobol => PixelSampling::Uniform,
        SamplerKind::Independent | SamplerKind::Stratified => settings.pixel_sampling,
    }
}

/// Samples per pixel a full render with these settings takes.
pub fn samples_per_pixel(settings: &Settings) -> u32 {
    samples_taken(settings.pixel_samples, pixel_mode(settings))
}

/// Offset in [0,1)^2 within the pixel of sample `sample` of `n` (n = samples_taken).
///
/// A single sample (`n <= 1`) is the pixel centre (0.5, 0.5) in both modes
/// (SPEC "Camera"). Uniform: the sampler's point (independent, or Sobol'). Stratified: a
/// random point inside cell `(sample % k, sample / k)` of the `k x k` grid
/// with `k = round(sqrt(n))`; sample indices past `k*k` wrap around the grid.
pub fn pixel_sample_offset(
    sampler: &Sampler,
    pixel: u32,
    sample: u32,
    n: u32,
    mode: PixelSampling,
) -> Vec2 {
    if n <= 1 {
        return Vec2::splat(0.5);
    }
    offset_of_jitter(sampler.pixel2(pixel, sample), sample, n, mode)
}

/// [`pixel_sample_offset`] of `n > 1` samples once the sampler gave its point `jitter`.
pub fn offset_of_jitter(jitter: Vec2, sample: u32, n: u32, mode: PixelSampling) -> Vec2 {
    match mode {
        PixelSampling::Uniform => jitter.min(Vec2::splat(BELOW_ONE)),
        PixelSampling::Stratified => {
            let k = grid_side(n);
            let cell_x = sample % k;
            let cell_y = (sample / k) % k;
            Vec2::new(in_cell(cell_x, jitter.x, k), in_cell(cell_y, jitter.y, k))
        }
    }
}

/// `(cell + jitter) / k`, kept inside the cell despite rounding.
fn in_cell(cell: u32, jitter: f32, k: u32) -> f32 {
    // f64 holds cell + jitter exactly (24-bit jitter, 32-bit cell); the only
    // rounding is the final cast, which could land on the next cell's edge.
    let x = (f64::from(cell) + f64::from(jitter)) / f64::from(k);
    let upper = f64::from(cell + 1) / f64::from(k);
    let mut y = x as f32;
    if f64::from(y) >= upper {
        y = f32::from_bits(y.to_bits() - 1);
    }
    y.min(BELOW_ONE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::DIM_PIXEL;

    #[test]
    fn samples_taken_counts() {
        assert_eq!(samples_taken(10, PixelSampling::Stratified), 9);
        assert_eq!(samples_taken(10, PixelSampling::Uniform), 10);
        assert_eq!(samples_taken(2, PixelSampling::Stratified), 1);
        assert_eq!(samples_taken(3, PixelSampling::Stratified), 4);
        assert_eq!(samples_taken(64, PixelSampling::Stratified), 64);
        assert_eq!(samples_taken(0, PixelSampling::Stratified), 1);
        assert_eq!(samples_taken(0, PixelSampling::Uniform), 1);
        assert_eq!(samples_taken(1, PixelSampling::Stratified), 1);
    }

    #[test]
    fn single_sample_is_centre() {
        let s = Sampler::new(3);
        for mode in [PixelSampling::Uniform, PixelSampling::Stratified] {
            for pixel in 0..10 {
                assert_eq!(pixel_sample_offset(&s, pixel, 0, 1, mode), Vec2::splat(0.5));
            }
        }
    }

    #[test]
    fn samples_inside_pixel() {
        let s = Sampler::new(9);
        for mode in [PixelSampling::Uniform, PixelSampling::Stratified] {
            for n in [2, 4, 9, 16, 100] {
                let n = samples_taken(n, mode);
                for pixel in 0..50 {
                    for i in 0..n {
                        let o = pixel_sample_offset(&s, pixel, i, n, mode);
                        assert!(
                            (0.0..1.0).contains(&o.x) && (0.0..1.0).contains(&o.y),
                            "{o}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn stratified_one_per_cell() {
        let s = Sampler::new(5);
        for pixel in 0..200 {
            let mut cells = [0u32; 64];
            for i in 0..64 {
                let o = pixel_sample_offset(&s, pixel, i, 64, PixelSampling::Stratified);
                let cx = (f64::from(o.x) * 8.0).floor() as usize;
                let cy = (f64::from(o.y) * 8.0).floor() as usize;
                cells[cy * 8 + cx] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "pixel {pixel}: {cells:?}");
        }
    }

    #[test]
    fn uniform_is_sampler_pair() {
        let s = Sampler::new(11);
        let o = pixel_sample_offset(&s, 4, 2, 8, PixelSampling::Uniform);
        assert_eq!(o, s.get2(4, 2, DIM_PIXEL));
    }

    #[test]
    fn in_cell_stays_below_edge() {
        // The largest jitter must not round into the next cell.
        let j = 1.0 - f32::EPSILON / 2.0;
        for k in [3, 7, 8, 1000, 4096] {
            for cell in [0, k / 2, k - 1] {
                let y = in_cell(cell, j, k);
                assert!(f64::from(y) < f64::from(cell + 1) / f64::from(k));
                assert!(f64::from(y) >= f64::from(cell) / f64::from(k));
                assert!(y < 1.0);
            }
        }
    }
}
