//! Texture image data: linear RGB texels decoded once at load (SPEC "Textures"). The
//! lookups that read them are in `shade::texture`.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// What a lookup does outside `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrapMode {
    /// Clamp to the edge texel.
    #[default]
    Clamp,
    /// Tile.
    Repeat,
    /// Tile, mirroring every other copy.
    MirroredRepeat,
}

/// A decoded texture: linear RGB texels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` linear RGB texels, row 0 first.
    pub texels: Vec<Vec3>,
}

/// Decodes one sRGB-encoded value in [0, 1] to linear (the exact piecewise sRGB curve).
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// Decodes an image; `srgb` = true decodes sRGB-encoded 8-bit values to linear (glTF base colour), false takes values as linear (the course's convention for PNG/JPEG kd textures).
    ///
    /// Alpha is dropped. Any pixel format is accepted (via 32-bit float RGB).
    pub fn from_image(img: &image::DynamicImage, srgb: bool) -> Texture {
        let rgb = img.to_rgb32f();
        let (width, height) = rgb.dimensions();
        let texels = rgb
            .pixels()
            .map(|p| {
                let c = Vec3::from_array(p.0);
                if srgb {
                    Vec3::new(
                        srgb_to_linear(c.x),
                        srgb_to_linear(c.y),
                        srgb_to_linear(c.z),
                    )
                } else {
                    c
                }
            })
            .collect();
        Texture {
            width,
            height,
            texels,
        }
    }

    /// Loads and decodes a file (PNG or JPEG).
    pub fn load(path: &std::path::Path, srgb: bool) -> Result<Texture, TextureError> {
        let bytes = std::fs::read(path).map_err(image::ImageError::IoError)?;
        Texture::decode(&bytes, srgb)
    }

    /// Decodes an encoded image (PNG, JPEG, ...; the format is guessed from the content,
    /// so a misnamed file still loads), refusing one the machine could not hold: a small
    /// PNG can declare 20000x20000 texels, which take 12 bytes each here.
    pub fn decode(bytes: &[u8], srgb: bool) -> Result<Texture, TextureError> {
        use image::ImageDecoder;
        let decoder = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(image::ImageError::IoError)?
            .into_decoder()?;
        let (w, h) = decoder.dimensions();
        // The decoded image, its 32-bit float copy and the texels.
        let needed = decoder
            .total_bytes()
            .saturating_add(crate::memory::product(&[w as u64, h as u64, 24]));
        crate::memory::ensure_fits(&[(format!("a {w}x{h} texture"), needed)])?;
        let img = image::DynamicImage::from_decoder(decoder)?;
        Ok(Texture::from_image(&img, srgb))
    }
}

/// Why a texture could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file is not an image glint reads, or is corrupt.
    #[error(transparent)]
    Image(#[from] image::ImageError),
    /// The image is too large for the memory available.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    fn two_by_one() -> image::DynamicImage {
        let mut img = image::RgbImage::new(2, 1);
        img.put_pixel(0, 0, image::Rgb([255, 0, 128]));
        img.put_pixel(1, 0, image::Rgb([10, 20, 30]));
        image::DynamicImage::ImageRgb8(img)
    }

    #[test]
    fn decode_linear_and_srgb() {
        let img = two_by_one();
        let lin = Texture::from_image(&img, false);
        assert_eq!((lin.width, lin.height), (2, 1));
        assert!(close(lin.texels[0], Vec3::new(1.0, 0.0, 128.0 / 255.0)));
        assert!(close(lin.texels[1], Vec3::new(10.0, 20.0, 30.0) / 255.0));
        let srgb = Texture::from_image(&img, true);
        // sRGB 128 is linear 0.2158605; 10 is below the knee: 10 / 255 / 12.92.
        assert!(close(srgb.texels[0], Vec3::new(1.0, 0.0, 0.215_860_5)));
        assert!((srgb.texels[1].x - 10.0 / 255.0 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn load_png_round_trip() {
        let path = std::env::temp_dir().join(format!("glint-texture-{}.png", std::process::id()));
        two_by_one().save(&path).unwrap();
        let t = Texture::load(&path, false);
        let _ = std::fs::remove_file(&path);
        assert_eq!(t.unwrap(), Texture::from_image(&two_by_one(), false));
        assert!(Texture::load(std::path::Path::new("/nonexistent/x.png"), false).is_err());
    }
}
