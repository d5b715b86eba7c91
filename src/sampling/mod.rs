//! Deterministic sampling: pixel patterns and light samples, independent, stratified
//! or Owen-scrambled Sobol' (docs/sampling.md).
//!
//! Every random number is a pure function of (seed, pixel, sample index,
//! dimension) (SPEC "Multisampling"), so an image does not depend on the
//! thread count or on the order in which pixels are rendered.

pub mod light;
pub mod pixel;
pub mod sampler;
pub mod sobol;

pub use light::{sample_parallelogram_light, sample_segment_light};
pub use pixel::{
    offset_of_jitter, pixel_mode, pixel_sample_offset, samples_per_pixel, samples_taken,
};
pub use sampler::{
    DIM_PIXEL, LightSlot, PackedSlots, PointSampler, SLOT_LANES, Sampler, SlotLanes, SlotSampler,
    light_dim,
};
