//! The material table the hot loops read: gathered from material entities once per render.

use std::collections::HashMap;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

use crate::error::GlintError;
use crate::scene::{Material, Settings, TextureSource};
use crate::shade::texture::{Texture, WrapMode};
use crate::stats::{RenderStats, Stage, StageErrors};

/// A material as the tracer reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialData {
    /// Diffuse colour.
    pub kd: Vec3,
    /// Specular colour and reflection weight.
    pub ks: Vec3,
    /// Specular exponent.
    pub shininess: f32,
    /// Alpha: 1 = opaque.
    pub alpha: f32,
    /// Index into [`Materials::textures`], when texture mapping applies.
    pub texture: Option<u32>,
    /// Wrap modes along u and v.
    pub wrap: [WrapMode; 2],
}

/// Dense material and texture tables, indexed by the `u32` material ids in the geometry.
#[derive(Resource, Clone, Debug, Default)]
pub struct Materials {
    /// Materials in gather order.
    pub list: Vec<MaterialData>,
    /// Decoded textures (empty unless the texture stage ran).
    pub textures: Vec<Arc<Texture>>,
    /// Material entity to index.
    pub index_of: HashMap<Entity, u32>,
    /// Where each texture comes from, decoded by [`decode_textures`].
    pub sources: Vec<TextureSource>,
    /// The name of the material each texture source belongs to, for error messages.
    pub source_materials: Vec<String>,
    /// Whether lookups are bilinear.
    pub bilinear: bool,
}

impl Materials {
    /// The diffuse colour at a hit: the texture sample when there is one, else `kd`.
    // Inlined into shading, where it was a call through the GOT per hit.
    #[inline]
    pub fn kd_at(&self, material: u32, uv: Vec2) -> Vec3 {
        let m = &self.list[material as usize];
        match m.texture.and_then(|t| self.textures.get(t as usize)) {
            Some(tex) if self.bilinear => tex.sample_bilinear(uv, m.wrap),
            Some(tex) => tex.sample_nearest(uv, m.wrap),
            None => m.kd,
        }
    }
}

/// Gathers every material entity into the [`Materials`] table.
pub fn gather_materials(
    settings: Res<Settings>,
    query: Query<(Entity, &Material)>,
    mut materials: ResMut<Materials>,
    mut stats: ResMut<RenderStats>,
) {
    let mut table = Materials {
        bilinear: settings.bilinear_filtering,
        ..Default::default()
    };
    for (entity, m) in &query {
        let texture = match (&m.kd_texture, settings.texture_mapping) {
            (Some(source), true) => {
                table.sources.push(source.clone());
                table.source_materials.push(m.name.clone());
                Some(table.sources.len() as u32 - 1)
            }
            _ => None,
        };
        table.index_of.insert(entity, table.list.len() as u32);
        table.list.push(MaterialData {
            kd: m.kd,
            ks: m.ks,
            shininess: m.shininess,
            alpha: m.alpha,
            texture,
            wrap: m.wrap,
        });
    }
    stats.record(Stage::GatherMaterials, table.list.len() as u64);
    *materials = table;
}

/// Decodes every texture the materials use, once, into linear RGB.
pub fn decode_textures(
    mut materials: ResMut<Materials>,
    mut errors: ResMut<StageErrors>,
    mut stats: ResMut<RenderStats>,
) {
    let mut texels = 0;
    let mut textures = Vec::with_capacity(materials.sources.len());
    for (i, source) in materials.sources.iter().enumerate() {
        match source {
            TextureSource::Decoded(t) => textures.push(t.clone()),
            TextureSource::File(path) => match Texture::load(path, false) {
                Ok(t) => textures.push(Arc::new(t)),
                Err(e) => {
                    let material = materials.source_materials.get(i).map_or("", |n| n);
                    errors.0.push(GlintError::Invalid {
                        path: path.clone(),
                        entity: format!("material \"{material}\""),
                        field: "kd_texture".into(),
                        message: format!("cannot be decoded: {e}"),
                    });
                    textures.push(Arc::new(Texture {
                        width: 1,
                        height: 1,
                        texels: vec![Vec3::ZERO],
                    }));
                }
            },
        }
        texels += textures.last().map_or(0, |t| t.texels.len() as u64);
    }
    materials.textures = textures;
    stats.record(Stage::DecodeTextures, texels);
}
