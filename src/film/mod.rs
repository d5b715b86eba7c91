//! The film: accumulated radiance per pixel, image output, and error metrics.

pub mod estimate;
pub mod metrics;
pub mod part;
pub mod text;

use std::io::Write;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::{DVec3, Vec3};
use multiversion::multiversion;
use rayon::prelude::*;

use crate::error::{GlintError, Result};
use crate::stats::{RenderStats, Stage};
use crate::trace::wavefront::{PassRegion, SampleRadiance};

/// Accumulated radiance: a sum and a sample count per pixel, row 0 at the top, and the
/// moments its error estimate needs (see [`estimate`]).
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
    /// Sum of squared deviations from the mean of each pixel's samples (Welford).
    pub m2: Vec<DVec3>,
    /// Sum of the finite samples of odd sample index (the second replica).
    pub replica_sum: Vec<DVec3>,
    /// Number of finite samples of odd sample index.
    pub replica_count: Vec<u32>,
    /// The rounding error of each `sum` (`sum + err` is the exact sum of the samples):
    /// it makes the mean independent of the order samples were added in, so a render
    /// split into parts merges bit-identically (see [`part`]).
    pub err: Vec<DVec3>,
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
            m2: vec![DVec3::ZERO; n],
            replica_sum: vec![DVec3::ZERO; n],
            replica_count: vec![0; n],
            err: vec![DVec3::ZERO; n],
        }
    }

    /// Bytes a render holds per pixel: the film's six buffers and the image written
    /// from it.
    pub const BYTES_PER_PIXEL: u64 = (4 * size_of::<DVec3>() + 2 * size_of::<u32>() + 16) as u64;

    /// An empty film, allocated fallibly: [`GlintError::Memory`] rather than an abort
    /// when the allocator refuses (the estimate is checked before, in `Renderer::prepare`).
    pub fn try_new(width: u32, height: u32) -> Result<Self> {
        // Zeroed by the allocator: fresh pages come zeroed from the OS, and only those of
        // the pixels a render traces become the process's (see `write_zeros`).
        fn zeroed<T: bytemuck::Zeroable>(n: usize) -> Option<Vec<T>> {
            bytemuck::allocation::try_zeroed_slice_box(n)
                .ok()
                .map(Vec::from)
        }
        let n = width as usize * height as usize;
        let film = (|| {
            Some(Self {
                width,
                height,
                sum: zeroed(n)?,
                count: zeroed(n)?,
                m2: zeroed(n)?,
                replica_sum: zeroed(n)?,
                replica_count: zeroed(n)?,
                err: zeroed(n)?,
            })
        })();
        film.ok_or_else(|| {
            GlintError::from(crate::memory::MemoryError::Refused {
                what: format!("a {width}x{height} film"),
                needed: n as u64 * Self::BYTES_PER_PIXEL,
            })
        })
    }

    /// Writes zeros over the pixels `ranges` (row-major indices, in order, disjoint) of a
    /// film that holds no sample there yet, in parallel. A fresh film comes zeroed from
    /// the allocator, but left to the first pass, each of its pages was read first
    /// (mapping the shared zero page) and then written: a copy-on-write fault whose TLB
    /// flush interrupts every other thread of the render (10-15% of a two-thread Cornell
    /// render's CPU time went to those interrupts). A page written first takes one plain
    /// fault. Only the pixels a render traces: a part of a split render writes its
    /// crop's rows alone. Panics when the ranges are out of order or past the film.
    pub fn write_zeros(&mut self, ranges: &[std::ops::Range<usize>]) {
        fn zeros<T: bytemuck::Zeroable + Copy + Send>(
            v: &mut [T],
            ranges: &[std::ops::Range<usize>],
        ) {
            let (mut rest, mut offset) = (v, 0);
            let mut parts = Vec::with_capacity(ranges.len());
            for r in ranges {
                assert!(offset <= r.start, "film ranges out of order");
                let (part, tail) = rest[r.start - offset..].split_at_mut(r.len());
                parts.push(part);
                (rest, offset) = (tail, r.end);
            }
            parts
                .into_par_iter()
                .flat_map(|p| p.par_chunks_mut(FILM_CHUNK))
                .for_each(|c| c.fill(T::zeroed()));
        }
        zeros(&mut self.sum, ranges);
        zeros(&mut self.count, ranges);
        zeros(&mut self.m2, ranges);
        zeros(&mut self.replica_sum, ranges);
        zeros(&mut self.replica_count, ranges);
        zeros(&mut self.err, ranges);
    }

    /// The mean radiance of pixel `(x, y)` (black before any sample).
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        self.mean(y as usize * self.width as usize + x as usize)
    }

    fn mean(&self, i: usize) -> Vec3 {
        match self.count[i] {
            0 => Vec3::ZERO,
            n => ((self.sum[i] + self.err[i]) / n as f64).as_vec3(),
        }
    }

    /// Every pixel's mean radiance, row-major.
    pub fn image(&self) -> Vec<Vec3> {
        (0..self.sum.len()).map(|i| self.mean(i)).collect()
    }
}

/// Adds the region's finite samples to the film and to its moments (see [`estimate`]);
/// counts and drops the others. One pass over the region's pixels: each pixel's sum and
/// count are read once (two passes, moments then sum, cost 7% of the Cornell render).
pub fn accumulate_film(
    radiance: Res<SampleRadiance>,
    region: Res<PassRegion>,
    mut film: ResMut<Film>,
    mut stats: ResMut<RenderStats>,
) {
    let start = radiance.first_pixel as usize;
    let end = start + radiance.values.len();
    let odd = region.sample & 1 == 1;
    let film = &mut *film;
    // Chunks of pixels, each added by one call of a clone for the CPU's instruction set:
    // as a closure over single pixels it was compiled for SSE2 alone.
    let dropped: u64 = (
        film.sum[start..end].par_chunks_mut(FILM_CHUNK),
        film.err[start..end].par_chunks_mut(FILM_CHUNK),
        film.count[start..end].par_chunks_mut(FILM_CHUNK),
        film.m2[start..end].par_chunks_mut(FILM_CHUNK),
        film.replica_sum[start..end].par_chunks_mut(FILM_CHUNK),
        film.replica_count[start..end].par_chunks_mut(FILM_CHUNK),
        radiance.values.par_chunks(FILM_CHUNK),
    )
        .into_par_iter()
        .map(|(sum, err, count, m2, rsum, rcount, values)| {
            let pixels = FilmPixels {
                sum,
                err,
                count,
                m2,
                rsum,
                rcount,
            };
            add_samples(pixels, values, odd)
        })
        .sum();
    stats.nonfinite_samples += dropped;
    stats.record(Stage::AccumulateFilm, radiance.values.len() as u64);
}

/// Pixels a parallel task of [`accumulate_film`] adds to.
const FILM_CHUNK: usize = 4096;

/// One chunk of the film's per-pixel arrays, each of the chunk's length.
struct FilmPixels<'a> {
    sum: &'a mut [DVec3],
    err: &'a mut [DVec3],
    count: &'a mut [u32],
    m2: &'a mut [DVec3],
    rsum: &'a mut [DVec3],
    rcount: &'a mut [u32],
}

/// Adds one sample per pixel of `pixels` (`values`, of the same length) and its moment;
/// `odd` samples go to the replica too. Returns how many were dropped as not finite.
#[multiversion(targets("x86_64+avx2+fma", "x86_64+sse4.2"))]
fn add_samples(mut pixels: FilmPixels, values: &[Vec3], odd: bool) -> u64 {
    // Every slice cut to the samples' length, so that the loop has no bounds checks.
    let n = values.len();
    let p = &mut pixels;
    let (sum, err, count) = (&mut p.sum[..n], &mut p.err[..n], &mut p.count[..n]);
    let (m2, rsum, rcount) = (&mut p.m2[..n], &mut p.rsum[..n], &mut p.rcount[..n]);
    let mut dropped = 0;
    for i in 0..n {
        let c = values[i];
        if !c.is_finite() {
            dropped += 1;
            continue;
        }
        let x = c.as_dvec3();
        // The moment before the sum: Welford's update reads the pixel's mean before
        // the sample, so a pixel of constant samples keeps `m2` exactly 0.
        estimate::add_moment(&mut m2[i], sum[i], count[i], x);
        if odd {
            rsum[i] += x;
            rcount[i] += 1;
        }
        add_exact(&mut sum[i], &mut err[i], x);
        count[i] += 1;
    }
    dropped
}

/// Adds `x` to the sum `(sum, err)` without losing a bit: `sum` is rounded as a plain
/// `+=` would be (Knuth's two-sum), `err` collects what the rounding lost. While `err`'s
/// own additions are exact, which holds unless one pixel's samples span more than about
/// 80 binades, `sum + err` is the exact total whatever the order of the additions.
pub fn add_exact(sum: &mut DVec3, err: &mut DVec3, x: DVec3) {
    let s = *sum + x;
    let b = s - *sum;
    *err += (*sum - (s - b)) + (x - b);
    *sum = s;
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
        return write_atomically(path, &encode_exr(path, width, height, pixels)?);
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

/// 32-bit float RGB EXR bytes of `pixels`. Written by the `exr` crate itself, one
/// block after another in increasing order, because its parallel writer (which the
/// `image` crate uses) stores blocks in completion order: the same image would give
/// different bytes from run to run.
fn encode_exr(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (width as usize, height as usize);
    if pixels.len() != w * h {
        return Err(GlintError::Image {
            path: path.to_owned(),
            source: image::ImageError::Parameter(image::error::ParameterError::from_kind(
                image::error::ParameterErrorKind::DimensionMismatch,
            )),
        });
    }
    let encoding = exr::image::Encoding {
        compression: Compression::RLE,
        blocks: Blocks::Tiles(Vec2(64, 64)),
        line_order: LineOrder::Increasing,
    };
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = pixels[p.y() * w + p.x()];
        (c.x, c.y, c.z)
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_encoded_channels((w, h), encoding, channels)
        .write()
        .non_parallel()
        .to_buffered(&mut bytes)
        .map_err(|e| GlintError::Image {
            path: path.to_owned(),
            source: image::ImageError::Encoding(image::error::EncodingError::new(
                image::ImageFormat::OpenExr.into(),
                e,
            )),
        })?;
    Ok(bytes.into_inner())
}

/// Writes `bytes` to `path` via a temporary sibling file and a rename. The temporary
/// file has a random name and is created exclusively, so a planted symlink cannot
/// redirect the write; an existing output keeps its permissions.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| GlintError::Io {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".glint-")
        .suffix(".tmp")
        .tempfile_in(&dir)
        .map_err(io)?;
    tmp.write_all(bytes).map_err(io)?;
    if let Ok(meta) = std::fs::metadata(path) {
        tmp.as_file()
            .set_permissions(meta.permissions())
            .map_err(io)?;
    }
    tmp.as_file().sync_all().map_err(io)?;
    // On failure the temporary file is removed when `persist`'s error is dropped.
    tmp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `write_zeros` writes zeros over its ranges in every array and leaves every other
    /// pixel as it was: ranges of one pixel, of several chunks, next to each other.
    #[test]
    fn write_zeros_writes_its_ranges_alone() {
        let n = 3 * FILM_CHUNK + 40;
        let mut film = Film::new(n as u32, 1);
        let one = DVec3::ONE;
        for v in [
            &mut film.sum,
            &mut film.m2,
            &mut film.replica_sum,
            &mut film.err,
        ] {
            v.fill(one);
        }
        film.count.fill(1);
        film.replica_count.fill(1);
        let ranges = [
            3..4,
            10..10 + 2 * FILM_CHUNK + 7,
            10 + 2 * FILM_CHUNK + 7..n - 5,
        ];
        film.write_zeros(&ranges);
        for i in 0..n {
            let inside = ranges.iter().any(|r| r.contains(&i));
            let (v, c) = if inside { (DVec3::ZERO, 0) } else { (one, 1) };
            for a in [&film.sum, &film.m2, &film.replica_sum, &film.err] {
                assert_eq!(a[i], v, "pixel {i}");
            }
            assert_eq!((film.count[i], film.replica_count[i]), (c, c), "pixel {i}");
        }
    }

    /// A region of several of `accumulate_film`'s chunks, not starting at pixel 0, with
    /// non-finite samples on both sides of a chunk's edge: every pixel gets its own
    /// sample, none outside the region changes, and the dropped ones are counted.
    #[test]
    fn accumulate_film_adds_each_pixel_of_a_region_across_chunks() {
        use crate::trace::wavefront::{PassRegion, SampleRadiance};
        use bevy_ecs::system::RunSystemOnce;
        let (first, n) = (37, 3 * FILM_CHUNK + 5);
        let value = |i: usize| Vec3::new(i as f32, 0.5, 2.0);
        let mut values: Vec<Vec3> = (0..n).map(value).collect();
        let nan = [FILM_CHUNK - 1, FILM_CHUNK];
        for &i in &nan {
            values[i] = Vec3::new(f32::NAN, 0.0, 0.0);
        }
        let mut world = World::new();
        world.insert_resource(Film::new(100, 150));
        world.insert_resource(SampleRadiance {
            first_pixel: first as u32,
            values,
        });
        world.insert_resource(PassRegion {
            sample: 1,
            first_pixel: first as u32,
            pixels: n as u32,
        });
        world.init_resource::<RenderStats>();
        world.run_system_once(accumulate_film).expect("film runs");
        let film = world.resource::<Film>();
        for p in 0..film.sum.len() {
            let (count, sum) = match p.checked_sub(first) {
                Some(i) if i < n && !nan.contains(&i) => (1, value(i).as_dvec3()),
                _ => (0, DVec3::ZERO),
            };
            assert_eq!((film.count[p], film.sum[p]), (count, sum), "pixel {p}");
            // Sample 1 is odd: the replica holds it too.
            assert_eq!((film.replica_count[p], film.replica_sum[p]), (count, sum));
        }
        assert_eq!(world.resource::<RenderStats>().nonfinite_samples, 2);
    }

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
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bmpx");
        assert!(write_image(&path, 1, 1, &[Vec3::ONE], Encoding::Linear).is_err());
        assert!(!path.exists());
    }

    #[test]
    fn atomic_write_does_not_follow_a_symlink_at_the_old_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"keep me").unwrap();
        let out = dir.path().join("out.png");
        // The name the temporary file had before it was random.
        let planted = dir
            .path()
            .join(format!(".out.png.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &planted).unwrap();
        write_atomically(&out, b"image").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"keep me");
        assert_eq!(std::fs::read(&out).unwrap(), b"image");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| n.starts_with(".glint-"))
            .collect();
        assert!(left.is_empty(), "temporary files left behind: {left:?}");
    }

    #[test]
    fn atomic_write_keeps_the_outputs_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.png");
        std::fs::write(&out, b"old").unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomically(&out, b"new").unwrap();
        let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
    }

    #[test]
    fn exr_output_is_byte_reproducible() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (67, 45);
        let pixels: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::new(i as f32 / 100.0, (i % 7) as f32, 1.0 / (1 + i) as f32))
            .collect();
        let bytes = |name: &str| {
            let p = dir.path().join(name);
            write_image(&p, w, h, &pixels, Encoding::Linear).unwrap();
            std::fs::read(p).unwrap()
        };
        let first = bytes("a.exr");
        for name in ["b.exr", "c.exr", "d.exr"] {
            assert!(first == bytes(name), "{name} differs from a.exr");
        }
    }

    #[test]
    fn exr_output_reads_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.exr");
        let pixels: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.25, -1e-3)).collect();
        write_image(&p, 3, 2, &pixels, Encoding::Linear).unwrap();
        let back = image::open(&p).unwrap().into_rgb32f();
        assert_eq!((back.width(), back.height()), (3, 2));
        let read: Vec<Vec3> = back.pixels().map(|q| Vec3::from(q.0)).collect();
        assert_eq!(read, pixels);
    }
}
