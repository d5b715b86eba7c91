//! The film's own estimate of its error: per-pixel moments, or two independent replicas.
//!
//! Every pixel is a mean of samples; its error is the variance of that mean. With
//! samples independent across passes (the `independent` and `stratified` samplers with
//! uniform pixel offsets) the sample variance `s^2 / n` estimates it without bias. With
//! Sobol' points the samples of a pixel are negatively correlated by design and `s^2 / n`
//! overstates the error many times, so the sampler draws two independently scrambled
//! replicas (even and odd sample indices) and the squared difference of their means
//! estimates the variance of the pixel (randomised quasi-Monte Carlo). The image's MSE
//! is the mean of the pixels' variances over pixels and channels (docs/sampling.md).

use glam::{DVec3, Vec3};

use super::Film;
use super::metrics::REL_MSE_EPSILON;
use crate::scene::{PixelSampling, SamplerKind, Settings};

/// How the film estimates its error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimateMethod {
    /// The sample variance of each pixel over `n`: honest for samples independent
    /// across passes, an overestimate for a stratified pixel grid.
    Moments,
    /// The squared difference of two independent replicas' means (even and odd samples).
    Replicas,
}

impl std::fmt::Display for ErrorEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "RMSE {:.3e}, relMSE {:.3e} ({})",
            self.rmse,
            self.rel_mse,
            self.method.name()
        )
    }
}

impl EstimateMethod {
    /// The honest method for these settings.
    pub fn for_settings(settings: &Settings) -> Self {
        match settings.sampler {
            SamplerKind::Sobol => Self::Replicas,
            SamplerKind::Independent | SamplerKind::Stratified => Self::Moments,
        }
    }

    /// Whether the estimate is an upper bound rather than unbiased (a stratified pixel
    /// grid correlates the passes within a grid).
    pub fn is_upper_bound(settings: &Settings) -> bool {
        Self::for_settings(settings) == Self::Moments
            && settings.pixel_sampling == PixelSampling::Stratified
            && settings.pixel_samples > 1
    }

    /// The name shown in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Moments => "per-pixel variance",
            Self::Replicas => "two scrambled replicas",
        }
    }
}

/// An estimate of the image's error against the true pixel integrals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// Estimated root mean squared error over pixels and channels.
    pub rmse: f64,
    /// Estimated relative MSE, `mean(var / (mean^2 + REL_MSE_EPSILON))`.
    pub rel_mse: f64,
    /// How it was estimated.
    pub method: EstimateMethod,
}

/// Welford's update of a pixel's `m2` for the finite sample `x`, given the pixel's
/// `sum` and `count` before it (the film adds the sample after, in
/// [`super::accumulate_film`]).
#[inline]
pub fn add_moment(m2: &mut DVec3, sum: DVec3, count: u32, x: DVec3) {
    if count > 0 {
        let before = sum / f64::from(count);
        let after = (sum + x) / f64::from(count + 1);
        *m2 += (x - before) * (x - after);
    }
}

impl Film {
    /// The variance of each channel of pixel `i`'s mean, or `None` when the method
    /// needs more samples than the pixel has (2 for moments, 1 per replica).
    pub fn pixel_variance(&self, i: usize, method: EstimateMethod) -> Option<DVec3> {
        let n = self.count[i];
        match method {
            EstimateMethod::Moments => {
                (n >= 2).then(|| self.m2[i] / (f64::from(n) * f64::from(n - 1)))
            }
            EstimateMethod::Replicas => {
                let n1 = self.replica_count[i];
                let n0 = n.checked_sub(n1).filter(|&n0| n0 > 0 && n1 > 0)?;
                let m0 = (self.sum[i] - self.replica_sum[i]) / f64::from(n0);
                let m1 = self.replica_sum[i] / f64::from(n1);
                let d = m0 - m1;
                // E[d^2] = V0 + V1; the mean of all n samples has variance
                // (n0^2 V0 + n1^2 V1) / n^2, taking V0 = V1 = V.
                let (n0, n1, n) = (f64::from(n0), f64::from(n1), f64::from(n));
                Some(d * d * (n0 * n0 + n1 * n1) / (2.0 * n * n))
            }
        }
    }

    /// The estimated error of the image, over the pixels with enough samples; `None`
    /// when no pixel has enough.
    pub fn error_estimate(&self, method: EstimateMethod) -> Option<ErrorEstimate> {
        let (mut mse, mut rel, mut pixels) = (0.0f64, 0.0f64, 0usize);
        for i in 0..self.sum.len() {
            let Some(var) = self.pixel_variance(i, method) else {
                continue;
            };
            let mean = self.sum[i] / f64::from(self.count[i]);
            mse += var.element_sum();
            rel += (var / (mean * mean + REL_MSE_EPSILON)).element_sum();
            pixels += 1;
        }
        let n = 3.0 * pixels as f64;
        (pixels > 0).then(|| ErrorEstimate {
            rmse: (mse / n).sqrt(),
            rel_mse: rel / n,
            method,
        })
    }

    /// Each pixel's estimated standard error (the root of its channels' mean
    /// variance), row-major; 0 where there are too few samples. For error images.
    pub fn error_image(&self, method: EstimateMethod) -> Vec<Vec3> {
        (0..self.sum.len())
            .map(|i| {
                self.pixel_variance(i, method)
                    .map_or(Vec3::ZERO, |v| v.max(DVec3::ZERO).as_vec3().map(f32::sqrt))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::wavefront::{PassRegion, SampleRadiance};
    use bevy_ecs::prelude::*;
    use bevy_ecs::system::RunSystemOnce;

    /// A one-pixel film fed `samples` in pass order, through the moments and the sum.
    fn film_of(samples: &[Vec3]) -> Film {
        let mut film = Film::new(1, 1);
        for (k, &x) in samples.iter().enumerate() {
            let mut world = World::new();
            world.insert_resource(std::mem::take(&mut film));
            world.insert_resource(SampleRadiance {
                first_pixel: 0,
                values: vec![x],
            });
            world.insert_resource(PassRegion {
                sample: k as u32,
                first_pixel: 0,
                pixels: 1,
            });
            world.init_resource::<crate::stats::RenderStats>();
            world
                .run_system_once(super::super::accumulate_film)
                .expect("film runs");
            film = world.remove_resource::<Film>().expect("film");
        }
        film
    }

    #[test]
    fn constant_samples_have_zero_variance_exactly() {
        let film = film_of(&[Vec3::new(0.3, 0.7, 1.9); 37]);
        for method in [EstimateMethod::Moments, EstimateMethod::Replicas] {
            assert_eq!(film.pixel_variance(0, method), Some(DVec3::ZERO));
            assert_eq!(film.error_estimate(method).unwrap().rmse, 0.0);
        }
    }

    #[test]
    fn moments_match_the_sample_variance() {
        let xs = [1.0f32, 2.0, 4.0, 7.0, 11.0];
        let film = film_of(&xs.map(Vec3::splat));
        let mean = xs.iter().sum::<f32>() as f64 / 5.0;
        let s2 = xs
            .iter()
            .map(|&x| (f64::from(x) - mean).powi(2))
            .sum::<f64>()
            / 4.0;
        let v = film.pixel_variance(0, EstimateMethod::Moments).unwrap();
        assert!((v.x - s2 / 5.0).abs() < 1e-12, "{} vs {}", v.x, s2 / 5.0);
        // Replicas: even samples 1, 4, 11 (mean 16/3), odd 2, 7 (mean 4.5).
        let r = film.pixel_variance(0, EstimateMethod::Replicas).unwrap();
        let d: f64 = 16.0 / 3.0 - 4.5;
        assert!((r.x - d * d * 13.0 / 50.0).abs() < 1e-12);
    }

    #[test]
    fn too_few_samples_give_no_estimate() {
        let film = film_of(&[Vec3::ONE]);
        assert_eq!(film.error_estimate(EstimateMethod::Moments), None);
        assert_eq!(film.error_estimate(EstimateMethod::Replicas), None);
        let film = film_of(&[Vec3::ONE, Vec3::ZERO]);
        assert!(film.error_estimate(EstimateMethod::Replicas).is_some());
    }

    #[test]
    fn non_finite_samples_are_left_out() {
        let film = film_of(&[Vec3::ONE, Vec3::NAN, Vec3::ONE]);
        assert_eq!(film.count[0], 2);
        assert_eq!(
            film.pixel_variance(0, EstimateMethod::Moments),
            Some(DVec3::ZERO)
        );
    }
}
