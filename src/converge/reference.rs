//! The reference image: read from an EXR, or rendered once and cached beside the scene.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use glam::Vec3;

use crate::error::{GlintError, Result};
use crate::film::{Encoding, write_image};
use crate::render::{Overrides, Renderer};
use crate::scene::parse_scene;

/// Folder, beside the scene file, that holds cached references.
pub const CACHE_DIR: &str = ".glint-cache";

/// Mixed into the scene seed so that the reference's random numbers are independent
/// of the compared configurations' (same seed would correlate their errors).
const REFERENCE_SEED_SALT: u64 = 0x5EED_0F4E_F32E_4C00;

/// How references are sampled (part of the cache key): Owen-scrambled Sobol' points
/// converge faster than stratified pixels at equal spp, and their two replicas give an
/// honest estimate of the reference's own error.
const REFERENCE_SAMPLER: &str = "sobol";

/// A reference image, linear RGB, row-major.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels.
    pub pixels: Vec<Vec3>,
    /// The reference's own estimated MSE, when glint rendered it: measured MSE is the
    /// true MSE plus this, so comparisons with an error estimate subtract it.
    pub mse: Option<f64>,
}

/// How a reference was obtained.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReferenceOrigin {
    /// Read from a file the user supplied.
    Supplied(PathBuf),
    /// Read from the cache.
    Cached(PathBuf),
    /// Rendered now and written to the cache.
    Rendered(PathBuf),
}

/// Reads an image file (EXR or any format `image` decodes) as linear RGB.
pub fn read_reference(path: &Path) -> Result<Reference> {
    let img = image::open(path).map_err(|source| GlintError::Image {
        path: path.to_owned(),
        source,
    })?;
    let rgb = img.into_rgb32f();
    let (width, height) = rgb.dimensions();
    let pixels = rgb
        .pixels()
        .map(|p| Vec3::new(p.0[0], p.0[1], p.0[2]))
        .collect();
    Ok(Reference {
        width,
        height,
        pixels,
        mse: None,
    })
}

/// The file beside a cached reference that holds its estimated MSE, as text.
fn mse_path(reference: &Path) -> PathBuf {
    let mut name = reference.as_os_str().to_owned();
    name.push(".mse");
    PathBuf::from(name)
}

/// FNV-1a, 64 bit: a stable hash (unlike `std`'s, which may change between
/// releases), good enough to key a cache that is only ever a speed-up.
fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        // Length-prefix each part so that ("ab", "c") and ("a", "bc") differ.
        for &b in (part.len() as u64).to_le_bytes().iter().chain(part.iter()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// The cache file of a reference: keyed by the scene bytes, the overrides, the
/// reference spp and the glint version.
pub fn cache_path(scene: &Path, scene_bytes: &[u8], overrides: &Overrides, spp: u32) -> PathBuf {
    let settings = format!(
        "{:?} {:?} {:?} {:?}",
        overrides.width, overrides.height, overrides.seed, overrides.set
    );
    let key = fnv1a(&[
        scene_bytes,
        settings.as_bytes(),
        &spp.to_le_bytes(),
        env!("CARGO_PKG_VERSION").as_bytes(),
        REFERENCE_SAMPLER.as_bytes(),
    ]);
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    let dir = scene.parent().unwrap_or(Path::new(""));
    dir.join(CACHE_DIR).join(format!("{stem}-{key:016x}.exr"))
}

/// The reference for `scene` at `spp`: the cached file when it exists and has the
/// expected size, otherwise a render (Sobol' samples, the scene's other settings, an
/// independent seed) written to the cache with its estimated MSE beside it.
///
/// Only the scene file's own bytes are hashed: editing a mesh or texture it
/// references does not invalidate the cache (delete `.glint-cache/` then).
pub fn cached_reference(
    scene: &Path,
    overrides: &Overrides,
    spp: u32,
    interrupt: Option<Arc<AtomicBool>>,
    log: &mut (dyn FnMut(&str) + Send),
) -> Result<(Reference, ReferenceOrigin)> {
    let bytes = std::fs::read(scene).map_err(|source| GlintError::Io {
        path: scene.to_owned(),
        source,
    })?;
    let path = cache_path(scene, &bytes, overrides, spp);
    let text = String::from_utf8_lossy(&bytes);
    let mut file = parse_scene(&text, scene)?;
    overrides.apply(&mut file)?;
    let (width, height) = (file.camera.width, file.camera.height);
    if path.exists() {
        match read_reference(&path) {
            Ok(mut r) if r.width == width && r.height == height => {
                r.mse = std::fs::read_to_string(mse_path(&path))
                    .ok()
                    .and_then(|t| t.trim().parse().ok());
                return Ok((r, ReferenceOrigin::Cached(path)));
            }
            _ => log(&format!(
                "{}: unusable cache entry, rebuilding",
                path.display()
            )),
        }
    }
    file.settings.pixel_samples = spp.max(1);
    file.settings.sampler = crate::scene::SamplerKind::Sobol;
    file.settings.seed ^= REFERENCE_SEED_SALT;
    let mut renderer = Renderer::from_scene(&file, scene)?;
    if let Some(flag) = interrupt {
        renderer.set_interrupt(flag);
    }
    log(&format!(
        "rendering the reference: {width}x{height}, {} spp (cached as {})",
        renderer.samples_per_pixel(),
        path.display()
    ));
    // A 4096-spp reference takes minutes: say how long, at every tenth of the way.
    let total = width as u64 * height as u64 * renderer.samples_per_pixel() as u64;
    let (start, mut done, mut next_tenth) = (std::time::Instant::now(), 0u64, 1u64);
    let summary = renderer.render(None, &mut |pixels| {
        done += pixels;
        if done * 10 >= next_tenth * total && done < total {
            next_tenth = done * 10 / total + 1;
            let seconds = start.elapsed().as_secs_f64();
            let left = seconds * (total - done) as f64 / done as f64;
            log(&format!(
                "reference: {}% done in {seconds:.0} s, about {} left",
                done * 100 / total,
                duration_words(left)
            ));
        }
    })?;
    if summary.interrupted {
        return Err(GlintError::Reference(
            "interrupted while rendering the reference; nothing cached".into(),
        ));
    }
    log(&format!("reference done in {:.1} s", summary.seconds));
    let mse = renderer.error_estimate().map(|e| e.rmse * e.rmse);
    let film = renderer.film();
    let pixels = film.image();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| GlintError::Io {
            path: dir.to_owned(),
            source,
        })?;
    }
    write_image(&path, width, height, &pixels, Encoding::Linear)?;
    if let Some(mse) = mse {
        crate::film::write_atomically(&mse_path(&path), format!("{mse:e}\n").as_bytes())?;
    }
    Ok((
        Reference {
            width,
            height,
            pixels,
            mse,
        },
        ReferenceOrigin::Rendered(path),
    ))
}

/// `42 s`, `3.5 min`, `1.2 h`.
fn duration_words(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.1} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_depends_on_every_input() {
        let scene = Path::new("scenes/box.ron");
        let o = Overrides::default();
        let base = cache_path(scene, b"a", &o, 64);
        assert_eq!(base, cache_path(scene, b"a", &o, 64));
        assert!(base.starts_with("scenes/.glint-cache"));
        assert!(base.to_string_lossy().contains("box-"));
        assert_ne!(base, cache_path(scene, b"b", &o, 64));
        assert_ne!(base, cache_path(scene, b"a", &o, 65));
        let o2 = Overrides {
            set: vec![("shadow_samples".into(), "2".into())],
            ..Overrides::default()
        };
        assert_ne!(base, cache_path(scene, b"a", &o2, 64));
    }

    #[test]
    fn durations_read_for_people() {
        assert_eq!(duration_words(42.4), "42 s");
        assert_eq!(duration_words(210.0), "3.5 min");
        assert_eq!(duration_words(4.0 * 3600.0), "4.0 h");
    }
}
