//! Render settings: every toggle of SPEC "Settings", per scene and overridable per run.

use bevy_ecs::prelude::*;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::gradient::Gradient;

/// How a hit is shaded (SPEC "Shading").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShadingModel {
    /// `light * kd * max(n.l, 0)`.
    Lambertian,
    /// Lambertian plus `light * ks * max(r.v, 0)^shininess`.
    #[default]
    Phong,
    /// Lambertian plus `light * ks * max(n.h, 0)^shininess`.
    BlinnPhong,
    /// Lambertian with `kd` replaced by the gradient sampled at `n.l`.
    LinearGradient,
    /// Colour-codes the signed difference between Phong and Blinn-Phong.
    LinearGradientComparison,
}

/// Which acceleration structure traces the rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Acceleration {
    /// A bounding volume hierarchy.
    #[default]
    Bvh,
    /// Test every primitive (a one-leaf hierarchy), for comparison.
    None,
}

/// How the BVH chooses its splits.
///
/// This mirrors `accel::SplitMethod` because scene sits below accel and must not import
/// it; the one mapping between the two is `split_method` in src/trace/geometry.rs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BvhSplit {
    /// Surface area heuristic over binned centroids.
    #[default]
    SahBinned,
    /// Object median along the widest centroid axis.
    Median,
}

/// Where camera samples fall inside their pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PixelSampling {
    /// Independent uniform offsets.
    #[default]
    Uniform,
    /// One jittered offset per cell of a `k x k` grid.
    Stratified,
}

/// Which points estimate the pixel and light integrals (docs/sampling.md).
///
/// All three are unbiased and pure functions of (seed, pixel, sample index, dimension).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// Independent random numbers (SPEC "Multisampling": uniform offsets are independent).
    #[default]
    Independent,
    /// Independent across passes; the light samples of one shading point are stratified.
    Stratified,
    /// Owen-scrambled Sobol' points over passes for every dimension, in two replicas.
    Sobol,
}

/// Every render setting, with SPEC's defaults.
#[derive(Resource, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Shading on; off gives `light * kd`.
    pub shading: bool,
    /// The shading model.
    pub shading_model: ShadingModel,
    /// Gradient of the linear-gradient model, sampled at `cos_theta`.
    pub gradient: Gradient,
    /// Gradient of the comparison model, sampled at the signed Phong/Blinn-Phong difference.
    pub comparison_gradient: Gradient,
    /// Recursive reflections weighted by `ks`.
    pub reflections: bool,
    /// Recursive transparency blended by alpha, and transparent shadows.
    pub transparency: bool,
    /// Shadow rays; off means every light sample is visible.
    pub shadows: bool,
    /// Barycentric normal interpolation; off uses the geometric normal.
    pub normal_interpolation: bool,
    /// Diffuse textures replace `kd`.
    pub texture_mapping: bool,
    /// Bilinear texture filtering; off is nearest.
    pub bilinear_filtering: bool,
    /// Acceleration structure.
    pub acceleration: Acceleration,
    /// BVH split method.
    pub bvh_split: BvhSplit,
    /// Camera samples per pixel.
    pub pixel_samples: u32,
    /// Pixel sample pattern.
    pub pixel_sampling: PixelSampling,
    /// Samples per segment or parallelogram light.
    pub shadow_samples: u32,
    /// Which points estimate the pixel and light integrals.
    pub sampler: SamplerKind,
    /// Maximum ray depth: camera rays have depth 0.
    pub max_depth: u32,
    /// Seed of every random number.
    pub seed: u64,
    /// Radiance of rays that hit nothing.
    pub background: Vec3,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            shading: true,
            shading_model: ShadingModel::Phong,
            gradient: Gradient::default_shading(),
            comparison_gradient: Gradient::default_comparison(),
            reflections: true,
            transparency: true,
            shadows: true,
            normal_interpolation: true,
            texture_mapping: true,
            bilinear_filtering: true,
            acceleration: Acceleration::Bvh,
            bvh_split: BvhSplit::SahBinned,
            pixel_samples: 1,
            pixel_sampling: PixelSampling::Uniform,
            shadow_samples: 4,
            sampler: SamplerKind::Independent,
            max_depth: 6,
            seed: 0,
            background: Vec3::ZERO,
        }
    }
}

impl Settings {
    /// The names accepted by [`Settings::set`], in declaration order.
    pub const KEYS: [&'static str; 19] = [
        "shading",
        "shading_model",
        "gradient",
        "comparison_gradient",
        "reflections",
        "transparency",
        "shadows",
        "normal_interpolation",
        "texture_mapping",
        "bilinear_filtering",
        "acceleration",
        "bvh_split",
        "pixel_samples",
        "pixel_sampling",
        "shadow_samples",
        "sampler",
        "max_depth",
        "seed",
        "background",
    ];

    /// Sets one field from its RON text, e.g. `("shading_model", "blinn_phong")`.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), String> {
        fn parse<T: serde::de::DeserializeOwned>(key: &str, value: &str) -> Result<T, String> {
            ron::from_str(value).map_err(|e| format!("{key}={value}: {}", e.code))
        }
        macro_rules! fields {
            ($($field:ident),*) => {
                match key {
                    $(stringify!($field) => self.$field = parse(key, value)?,)*
                    _ => {
                        return Err(format!(
                            "unknown setting \"{key}\" (known: {})",
                            Self::KEYS.join(", ")
                        ))
                    }
                }
            };
        }
        fields!(
            shading,
            shading_model,
            gradient,
            comparison_gradient,
            reflections,
            transparency,
            shadows,
            normal_interpolation,
            texture_mapping,
            bilinear_filtering,
            acceleration,
            bvh_split,
            pixel_samples,
            pixel_sampling,
            shadow_samples,
            sampler,
            max_depth,
            seed,
            background
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_parses_each_kind_of_value() {
        let mut s = Settings::default();
        s.set("shading_model", "blinn_phong").unwrap();
        s.set("shadows", "false").unwrap();
        s.set("pixel_samples", "16").unwrap();
        s.set("background", "(0.1, 0.2, 0.3)").unwrap();
        s.set("gradient", "[(1, (0, 1, 0)), (0, (1, 0, 0))]")
            .unwrap();
        assert_eq!(s.shading_model, ShadingModel::BlinnPhong);
        assert!(!s.shadows);
        assert_eq!(s.pixel_samples, 16);
        assert_eq!(s.background, Vec3::new(0.1, 0.2, 0.3));
        assert_eq!(s.gradient.components()[0].0, 0.0);
    }

    #[test]
    fn set_rejects_unknown_keys_and_bad_values() {
        let mut s = Settings::default();
        assert!(
            s.set("shadow", "true")
                .unwrap_err()
                .contains("unknown setting")
        );
        assert!(s.set("pixel_samples", "many").is_err());
        assert!(s.set("shading_model", "toon").is_err());
    }

    #[test]
    fn keys_list_every_field() {
        let ron = ron::to_string(&Settings::default()).unwrap();
        for key in Settings::KEYS {
            assert!(ron.contains(&format!("{key}:")), "{key} missing");
        }
        assert_eq!(ron.matches(':').count(), Settings::KEYS.len());
    }
}
