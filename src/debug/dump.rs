//! The dump: debug entities as RON, for tests and tools.

use glam::Vec3;
use serde::Serialize;

use super::DebugRequest;
use super::primitives::{DebugPrimitive, Feature, Shape, Values};
use crate::error::{GlintError, Result};

/// One entity as dumped.
#[derive(Serialize)]
struct Entry<'a> {
    kind: &'static str,
    feature: Feature,
    color: Vec3,
    shape: &'a Shape,
    values: &'a Values,
}

/// The whole dump.
#[derive(Serialize)]
struct Dump<'a> {
    pixel: [u32; 2],
    color: Vec3,
    entities: Vec<Entry<'a>>,
}

/// The primitives as pretty RON: the pixel, its colour, then each entity's kind,
/// feature, colour, geometry and values.
pub fn to_ron(request: &DebugRequest, color: Vec3, prims: &[DebugPrimitive]) -> Result<String> {
    let dump = Dump {
        pixel: request.pixel,
        color,
        entities: prims
            .iter()
            .map(|p| Entry {
                kind: p.shape.kind(),
                feature: p.feature,
                color: p.color,
                shape: &p.shape,
                values: &p.values,
            })
            .collect(),
    };
    let config = ron::ser::PrettyConfig::new()
        .depth_limit(4)
        .extensions(ron::extensions::Extensions::IMPLICIT_SOME);
    ron::ser::to_string_pretty(&dump, config).map_err(|e| GlintError::Dump(e.to_string()))
}
