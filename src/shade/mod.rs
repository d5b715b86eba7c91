//! Shading models and texture lookup.

pub mod gradient;
pub mod models;
pub mod texture;

pub use models::{
    Model, Shading, ShadingInput, WithModel, blinn_phong, lambertian, linear_gradient,
    linear_gradient_comparison, phong,
};
