//! Shading models and texture lookup.

pub mod gradient;
pub mod texture;
