//! The film: accumulated radiance per pixel, image output, and error metrics.

pub mod metrics;
pub mod text;

use std::io::Write;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::error::{GlintError, Result};
use crate::stats::{RenderStats, Stage};
use crate::trace::wavefront::SampleRadiance;

/// Accumulated radiance: a sum and a sample count per pixel, row 0 at the top.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Sum of the finite samples of each pixel.
    pub sum: Vec<DVec3>,
    /// Number of finite samples of each pixel.
    pub count: Vec<u32>,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![DVec3::ZERO; n],
            count: vec![0; n],
        }
    }

    /// The mean radiance of pixel `(x, y)` (black before any sample).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.mean(y as usize * self.width as usize + x as usize)
    }

    fn mean(&self, i: usize) -> Vec3 {
        match self.count[i] {
            0 => Vec3::ZERO,
            n => (self.sum[i] / n as f64).as_vec3(),
        }
    }

    /// Every pixel's mean radiance, row-major.
    pub fn image(&self) -> Vec<Vec3> {
        (0..self.sum.len()).map(|i| self.mean(i)).collect()
    }
}

/// Adds the region's finite samples to the film; counts and drops the others.
pub fn accumulate_film(
    radiance: Res<SampleRadiance>,
    mut film: ResMut<Film>,
    mut stats: ResMut<RenderStats>,
) {
    let start = radiance.first_pixel as usize;
    let end = start + radiance.values.len();
    let film = &mut *film;
    let dropped: u64 = film.sum[start..end]
        .par_iter_mut()
        .zip(&mut film.count[start..end])
        .zip(&radiance.values)
        .map(|((sum, count), c)| {
            if c.is_finite() {
                *sum += c.as_dvec3();
                *count += 1;
                0
            } else {
                1
            }
        })
        .sum();
    stats.nonfinite_samples += dropped;
    stats.record(Stage::AccumulateFilm, radiance.values.len() as u64);
}

/// How 8-bit outputs encode linear values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// Clamp to [0, 1] and scale (the course's convention).
    #[default]
    Linear,
    /// The sRGB transfer curve.
    Srgb,
}

fn srgb_encode(v: f32) -> f32 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit RGB bytes of an image of linear values.
pub fn to_rgb8(pixels: &[Vec3], encoding: Encoding) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(|v| {
            let v = if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            };
            let v = match encoding {
                Encoding::Linear => v,
                Encoding::Srgb => srgb_encode(v),
            };
            (v * 255.0 + 0.5) as u8
        })
        .collect()
}

/// Writes `pixels` (linear, row-major) as PNG or EXR by the extension of `path`,
/// through a temporary file in the same folder renamed at the end, so that a failed
/// run never leaves a half-written image.
pub fn write_image(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    encoding: Encoding,
) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("png") => image::ImageFormat::Png,
        Some("exr") => image::ImageFormat::OpenExr,
        _ => {
            return Err(GlintError::Output {
                path: path.to_owned(),
                message: "unknown output format (use .png or .exr)".into(),
            });
        }
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    let encoded = if format == image::ImageFormat::Png {
        image::RgbImage::from_raw(width, height, to_rgb8(pixels, encoding))
            .map(|img| img.write_to(&mut bytes, format))
    } else {
        let raw = pixels.iter().flat_map(|p| p.to_array()).collect();
        image::Rgb32FImage::from_raw(width, height, raw).map(|img| img.write_to(&mut bytes, format))
    };
    match encoded {
        Some(Ok(())) => {}
        Some(Err(source)) => {
            return Err(GlintError::Image {
                path: path.to_owned(),
                source,
            });
        }
        None => {
            return Err(GlintError::Output {
                path: path.to_owned(),
                message: format!("image buffer does not match {width}x{height}"),
            });
        }
    }
    write_atomically(path, bytes.get_ref())
}

/// Writes `bytes` to `path` via a temporary sibling file and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| GlintError::Io {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = std::fs::File::create(&tmp)
        .and_then(|mut f| {
            f.write_all(bytes)?;
            f.sync_all()
        })
        .and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_encoding_clamps_and_rounds() {
        let px = [Vec3::new(-1.0, 0.5, 2.0), Vec3::new(f32::NAN, 1.0, 0.0)];
        assert_eq!(to_rgb8(&px, Encoding::Linear), vec![0, 128, 255, 0, 255, 0]);
    }

    #[test]
    fn srgb_encoding_brightens_midtones() {
        let px = [Vec3::splat(0.5)];
        assert_eq!(to_rgb8(&px, Encoding::Srgb)[0], 188);
    }

    #[test]
    fn unknown_extension_is_an_error_and_writes_nothing() {
        let dir = std::env::temp_dir().join(format!("glint-film-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.bmpx");
        assert!(write_image(&path, 1, 1, &[Vec3::ONE], Encoding::Linear).is_err());
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
