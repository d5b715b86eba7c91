//! glTF materials and their textures: the metallic-roughness to Phong mapping
//! (docs/materials.md), base-colour textures decoded once per image and scale, and the
//! texture coordinates a material reads.

use std::path::Path;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use gltf::texture::WrappingMode;

use super::Importer;
use crate::error::{AssetError, Result};
use crate::scene::components::*;
use crate::scene::import::asset_err;
use crate::scene::texture::{Texture, WrapMode};

/// Dielectric reflectance at normal incidence (the glTF metallic-roughness model's F0).
pub const DIELECTRIC_F0: f32 = 0.04;
/// Largest shininess the roughness mapping produces (roughness 0).
pub const MAX_SHININESS: f32 = 10_000.0;

/// Phong-style material parameters of a glTF metallic-roughness material.
///
/// `base` is the base colour factor (linear RGB). Returns `(kd scale, ks, shininess)`:
/// the diffuse colour is `base * kd_scale`. The share of a metal that is smooth becomes
/// a coloured mirror (`ks`), the rest stays diffuse in the base colour, since a Whitted
/// tracer has no glossy reflection to show a rough metal with.
pub fn metallic_roughness_to_phong(base: Vec3, metallic: f32, roughness: f32) -> (f32, Vec3, f32) {
    let m = metallic.clamp(0.0, 1.0);
    let r = roughness.clamp(0.0, 1.0);
    let f0 = Vec3::splat(DIELECTRIC_F0).lerp(base, m);
    let ks = f0 * (1.0 - r);
    let kd_scale = 1.0 - m * (1.0 - r);
    // Blinn-Phong exponent matching a GGX lobe of alpha = roughness^2 (2/alpha^2 - 2).
    let alpha = r * r;
    let shininess = if alpha <= 0.0 {
        MAX_SHININESS
    } else {
        (2.0 / (alpha * alpha) - 2.0).clamp(1.0, MAX_SHININESS)
    };
    (kd_scale, ks, shininess)
}

fn wrap_mode(m: WrappingMode) -> WrapMode {
    match m {
        WrappingMode::ClampToEdge => WrapMode::Clamp,
        WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        WrappingMode::Repeat => WrapMode::Repeat,
    }
}

/// The encoded bytes of a glTF image (a buffer view, a `data:` URI or a file beside the
/// glTF), read here rather than by the `gltf` crate so that glint decodes them itself,
/// with its memory check, and no index is followed before it is checked.
fn encoded_image<'a>(
    source: gltf::image::Source<'_>,
    base: &Path,
    buffers: &'a [gltf::buffer::Data],
) -> std::result::Result<std::borrow::Cow<'a, [u8]>, String> {
    use std::borrow::Cow;
    match source {
        gltf::image::Source::View { view, .. } => {
            let end = view.offset().saturating_add(view.length());
            buffers
                .get(view.buffer().index())
                .and_then(|b| b.0.get(view.offset()..end))
                .map(Cow::Borrowed)
                .ok_or_else(|| "lies outside its buffer".to_owned())
        }
        gltf::image::Source::Uri { uri, .. } => {
            if let Some(data) = uri.strip_prefix("data:") {
                let payload = data.split_once(";base64,").map_or(data, |(_, p)| p);
                return base64::decode(payload)
                    .map(Cow::Owned)
                    .map_err(|e| format!("has a data URI that is not base64: {e}"));
            }
            let relative = uri
                .strip_prefix("file://")
                .or_else(|| uri.strip_prefix("file:"))
                .map(Cow::Borrowed)
                .unwrap_or_else(|| urlencoding::decode(uri).unwrap_or(Cow::Borrowed(uri)));
            let file = base.join(&*relative);
            std::fs::read(&file)
                .map(Cow::Owned)
                .map_err(|e| format!("cannot be read from {}: {e}", file.display()))
        }
    }
}

/// The KHR_texture_transform matrix (glTF's uv convention): translation * rotation * scale.
fn texture_transform(t: &gltf::texture::TextureTransform) -> glam::Affine2 {
    let [ox, oy] = t.offset();
    let [sx, sy] = t.scale();
    let (s, c) = t.rotation().sin_cos();
    // The extension's rotation matrix is [c s; -s c] (row-major), i.e. columns (c, -s), (s, c).
    let rotation = glam::Mat2::from_cols(Vec2::new(c, -s), Vec2::new(s, c));
    glam::Affine2::from_mat2_translation(
        rotation * glam::Mat2::from_diagonal(Vec2::new(sx, sy)),
        Vec2::new(ox, oy),
    )
}

/// What a primitive needs from its material to build its vertices.
pub(super) struct UvChoice {
    pub(super) set: u32,
    pub(super) transform: Option<glam::Affine2>,
}

impl Importer<'_> {
    /// Which texture coordinate set (and transform) the base colour texture reads.
    pub(super) fn uv_choice(&self, material: &gltf::Material) -> UvChoice {
        if self.options.material.is_some() {
            return UvChoice {
                set: 0,
                transform: None,
            };
        }
        match material.pbr_metallic_roughness().base_color_texture() {
            Some(info) => {
                let t = info.texture_transform();
                UvChoice {
                    set: t
                        .as_ref()
                        .and_then(|t| t.tex_coord())
                        .unwrap_or(info.tex_coord()),
                    transform: t.as_ref().map(texture_transform),
                }
            }
            None => UvChoice {
                set: 0,
                transform: None,
            },
        }
    }

    pub(super) fn material(&mut self, world: &mut World, m: &gltf::Material) -> Result<Entity> {
        if let Some(&e) = self.materials.get(&m.index()) {
            return Ok(e);
        }
        let name = match (m.name(), m.index()) {
            (Some(n), _) => n.to_owned(),
            (None, Some(i)) => format!("material {i}"),
            (None, None) => "glTF default material".to_owned(),
        };
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let base = Vec3::new(r, g, b).max(Vec3::ZERO);
        let (kd_scale, ks, shininess) =
            metallic_roughness_to_phong(base, pbr.metallic_factor(), pbr.roughness_factor());
        let alpha = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => 1.0,
            gltf::material::AlphaMode::Blend => a.clamp(0.0, 1.0),
            gltf::material::AlphaMode::Mask => {
                if a >= m.alpha_cutoff().unwrap_or(0.5) {
                    1.0
                } else {
                    0.0
                }
            }
        };
        if Vec3::from_array(m.emissive_factor()).max_element() > 0.0 {
            self.emissive.push(format!("\"{name}\""));
        }
        let kd = base * kd_scale;
        let (kd_texture, wrap) = match pbr.base_color_texture() {
            Some(info) => {
                let texture = info.texture();
                let sampler = texture.sampler();
                let wrap = [wrap_mode(sampler.wrap_s()), wrap_mode(sampler.wrap_t())];
                (
                    Some(self.texture(&name, texture.source().index(), kd)?),
                    wrap,
                )
            }
            None => (None, [WrapMode::Repeat; 2]),
        };
        let e = world
            .spawn((
                Name::new(name.clone()),
                Material {
                    name,
                    kd,
                    ks,
                    shininess,
                    alpha,
                    kd_texture,
                    wrap,
                },
            ))
            .id();
        self.materials.insert(m.index(), e);
        Ok(e)
    }

    /// The base colour texture of material `material` times `scale` (the factor and the
    /// metallic share), decoded from sRGB once per (image, scale). An image that is
    /// missing or cannot be decoded is an error naming the material and the image, as a
    /// missing texture in a RON scene is: a model must not render untextured in silence.
    fn texture(&mut self, material: &str, image: usize, scale: Vec3) -> Result<TextureSource> {
        let key = (image, scale.to_array().map(f32::to_bits));
        if let Some(t) = self.textures.get(&key) {
            return Ok(TextureSource::Decoded(t.clone()));
        }
        let fail = |what: String| {
            asset_err(
                self.path,
                AssetError::Invalid {
                    item: format!("material \"{material}\""),
                    problem: what,
                },
            )
        };
        let img = self
            .document
            .images()
            .nth(image)
            .ok_or_else(|| fail(format!("base colour image {image} does not exist")))?;
        let label = match img.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                format!("image {image} (\"{uri}\")")
            }
            _ => format!("image {image}"),
        };
        let base = self.path.parent().unwrap_or(Path::new("."));
        let bytes = encoded_image(img.source(), base, self.buffers)
            .map_err(|e| fail(format!("base colour {label} {e}")))?;
        let mut texture = Texture::decode(&bytes, true)
            .map_err(|e| fail(format!("base colour {label} cannot be decoded: {e}")))?;
        if scale != Vec3::ONE {
            for t in &mut texture.texels {
                *t *= scale;
            }
        }
        let texture = Arc::new(texture);
        self.textures.insert(key, texture.clone());
        Ok(TextureSource::Decoded(texture))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mapping_extremes() {
        let base = Vec3::new(0.8, 0.4, 0.2);
        // Rough dielectric: diffuse base colour, no specular.
        let (s, ks, n) = metallic_roughness_to_phong(base, 0.0, 1.0);
        assert_eq!((s, ks, n), (1.0, Vec3::ZERO, 1.0));
        // Smooth metal: a mirror in the base colour.
        let (s, ks, n) = metallic_roughness_to_phong(base, 1.0, 0.0);
        assert_eq!((s, ks, n), (0.0, base, MAX_SHININESS));
        // Smooth dielectric: 4 % grey mirror.
        let (_, ks, _) = metallic_roughness_to_phong(base, 0.0, 0.0);
        assert_eq!(ks, Vec3::splat(DIELECTRIC_F0));
        // Half roughness: alpha = 1/4, n = 2/(1/16) - 2 = 30.
        let (_, _, n) = metallic_roughness_to_phong(base, 0.0, 0.5);
        assert!((n - 30.0).abs() < 1e-4);
    }

    #[test]
    fn rotation_matrix() {
        // KHR_texture_transform rotates uv (1, 0) by +90 degrees to (0, -1).
        let (s, c) = std::f32::consts::FRAC_PI_2.sin_cos();
        let r = glam::Mat2::from_cols(Vec2::new(c, -s), Vec2::new(s, c));
        assert!((r * Vec2::X).abs_diff_eq(Vec2::new(0.0, -1.0), 1e-6));
    }
}
