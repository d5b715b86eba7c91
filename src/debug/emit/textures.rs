//! Textures: the looked-up texels of textured hits.

use bevy_ecs::prelude::*;

use super::{Spawner, displayable, hit_values, prim, scene_size};
use crate::debug::log::DebugTrace;
use crate::debug::primitives::{Feature, Shape, Values};
use crate::trace::geometry::SceneGeometry;
use crate::trace::materials::Materials;

/// Textures: for each textured hit of the first sample, the texture as a panel with the
/// looked-up texel (nearest) or four texels (bilinear) marked, and the hit in that colour.
pub fn emit_textures(
    mut spawner: Spawner,
    log: Res<DebugTrace>,
    materials: Res<Materials>,
    geometry: Res<SceneGeometry>,
) {
    let size = scene_size(&geometry);
    let mut out = Vec::new();
    let first = log.rays.first().map_or(0, |r| r.sample);
    for r in log.rays.iter().filter(|r| r.sample == first) {
        let Some((_, s)) = &r.hit else { continue };
        let m = &materials.list[s.material as usize];
        let Some(ti) = m.texture else { continue };
        let Some(tex) = materials.textures.get(ti as usize) else {
            continue;
        };
        let texels: Vec<([u32; 2], f32)> = if materials.bilinear {
            tex.bilinear_texels(s.uv, m.wrap)
                .iter()
                .map(|&((i, j), w)| ([i, j], w))
                .collect()
        } else {
            let (i, j) = tex.nearest_texel(s.uv, m.wrap);
            vec![([i, j], 1.0)]
        };
        let kd = materials.kd_at(s.material, s.uv);
        let values = Values {
            uv: Some(s.uv),
            ..hit_values("texture lookup", r)
        };
        out.push(prim(
            Feature::Textures,
            displayable(kd),
            Shape::Marker {
                center: s.p,
                radius: size * 0.006,
            },
            values.clone(),
        ));
        out.push(prim(
            Feature::Textures,
            displayable(kd),
            Shape::TexturePanel {
                texture: ti,
                size: [tex.width, tex.height],
                uv: s.uv,
                texels,
            },
            values,
        ));
    }
    spawner.spawn(out);
}
