//! Shading models and texture lookup.

pub mod gradient;
pub mod models;
pub mod texture;

pub use models::{
    Shading, ShadingInput, blinn_phong, lambertian, linear_gradient, linear_gradient_comparison,
    phong,
};
