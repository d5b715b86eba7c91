//! Multisampling: the pixel's sample offsets on its grid.

use bevy_ecs::prelude::*;

use super::{SAMPLE_POINT, Spawner, prim};
use crate::debug::log::DebugTrace;
use crate::debug::primitives::{Feature, Shape, Values};
use crate::sampling::pixel_mode;
use crate::scene::{PixelSampling, SamplerKind, Settings};

/// Multisampling: the pixel's sample offsets on its grid, with strata when stratified,
/// labelled by the pattern that placed them.
pub fn emit_samples(mut spawner: Spawner, log: Res<DebugTrace>, settings: Res<Settings>) {
    let strata = match pixel_mode(&settings) {
        PixelSampling::Uniform => None,
        PixelSampling::Stratified => {
            Some((log.camera_samples.len() as f64).sqrt().round().max(1.0) as u32)
        }
    };
    let points = log.camera_samples.iter().map(|s| s.offset).collect();
    spawner.spawn(vec![prim(
        Feature::Samples,
        SAMPLE_POINT,
        Shape::SampleGrid { strata, points },
        Values {
            what: match (strata, settings.sampler) {
                (Some(_), _) => "stratified samples",
                (None, SamplerKind::Sobol) => "Sobol' samples",
                (None, _) => "uniform samples",
            },
            ..Default::default()
        },
    )]);
}
