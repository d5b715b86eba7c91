//! Parts of a render: a film of some sample indices over a window of the image, written
//! as EXR, and their merge into the film of the whole render.
//!
//! A part file holds, per pixel, the exact sum of its samples and their count. The sum is
//! the film's pair `(sum, err)` (see [`add_exact`]), each `f64` stored bit for bit as two
//! `u32` channels (`sum.R.hi`, `sum.R.lo`, ..., `err.B.lo`), since `f32` channels cannot
//! hold it; `R`, `G`, `B` (`f32`) carry the part's mean so that a viewer shows it. One
//! text attribute, [`PART_ATTRIBUTE`], holds the [`PartInfo`]: scene content hash,
//! settings, image size, sample range and crop.
//!
//! Because `sum + err` is the exact total of a pixel's samples, adding parts gives the
//! same total as one render whatever the split: a merge of parts whose sample ranges
//! tile `0..N` (any split, the block of samples is one sample) and whose crops tile the
//! image is bit-identical to the single render of `N` samples (`tests/parts.rs`).

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::DVec3;
use sha2::{Digest, Sha256};

use super::{Film, add_exact, write_atomically};
use crate::error::{GlintError, Result};
use crate::sampling::samples_per_pixel;
use crate::scene::Settings;
use crate::scene::format::{EntityDesc, GeometryDesc};
use crate::scene::model::SceneFormat;
use crate::scene::read_scene;

/// The EXR header attribute that marks a part and holds its [`PartInfo`].
pub const PART_ATTRIBUTE: &str = "glint.part";

/// The version of the part format this build reads and writes.
const PART_VERSION: u32 = 2;

/// A window of the image: columns `x0..x1`, rows `y0..y1` (row 0 at the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Crop {
    /// The whole of a `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Why the window is not a non-empty part of a `width` x `height` image, if it is not.
    pub fn check(&self, width: u32, height: u32) -> std::result::Result<(), String> {
        if self.x0 >= self.x1 || self.y0 >= self.y1 || self.x1 > width || self.y1 > height {
            return Err(format!(
                "the crop {self} is not a non-empty window of the {width}x{height} image"
            ));
        }
        Ok(())
    }

    /// The window's pixels as row-major index ranges of the image: one range when the
    /// window spans whole rows, else one per row.
    pub fn pixel_ranges(&self, width: u32) -> Vec<Range<u32>> {
        if self.x0 == 0 && self.x1 == width {
            return std::iter::once(self.y0 * width..self.y1 * width).collect();
        }
        (self.y0..self.y1)
            .map(|y| y * width + self.x0..y * width + self.x1)
            .collect()
    }
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// What a part is of: the merge refuses parts whose scene, settings or size differ.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartInfo {
    /// SHA-256 of the scene's content (see [`scene_hash`]), hex.
    pub scene_hash: String,
    /// The settings and camera the part was rendered with, as text.
    pub settings: String,
    /// Width of the whole image.
    pub width: u32,
    /// Height of the whole image.
    pub height: u32,
    /// The sample indices rendered.
    pub samples: Range<u32>,
    /// The window rendered.
    pub crop: Crop,
}

impl PartInfo {
    /// The settings the part was rendered with, read back from `settings`; None if
    /// that text does not parse.
    pub fn parsed_settings(&self) -> Option<Settings> {
        let (settings, _camera) = self.settings.rsplit_once(" camera ")?;
        ron::from_str(settings).ok()
    }

    /// The samples per pixel of a full render with the part's settings (the scene's
    /// `pixel_samples`, rounded as the render rounds it).
    pub fn full_samples(&self) -> Option<u32> {
        self.parsed_settings().map(|s| samples_per_pixel(&s))
    }

    /// The attribute text: one `key: value` line per field.
    fn to_text(&self) -> String {
        let s = &self.samples;
        format!(
            "version: {PART_VERSION}\nscene_hash: {}\nimage: {}x{}\nsamples: {}..{}\ncrop: {}\nsettings: {}\n",
            self.scene_hash, self.width, self.height, s.start, s.end, self.crop, self.settings
        )
    }

    /// Parses [`PartInfo::to_text`]; the error names the field.
    fn from_text(text: &str) -> std::result::Result<Self, String> {
        let field = |key: &str| -> std::result::Result<&str, String> {
            text.lines()
                .find_map(|l| l.strip_prefix(key)?.strip_prefix(": "))
                .ok_or_else(|| format!("the part attribute has no {key}"))
        };
        let numbers = |key: &str, sep: &str, n: usize| -> std::result::Result<Vec<u32>, String> {
            let v: Option<Vec<u32>> = field(key)?
                .split(sep)
                .map(|x| x.trim().parse().ok())
                .collect();
            v.filter(|v| v.len() == n)
                .ok_or_else(|| format!("the part attribute's {key} does not parse"))
        };
        let version = numbers("version", ",", 1)?[0];
        if version != PART_VERSION {
            return Err(format!(
                "part format version {version}, this glint reads version {PART_VERSION}"
            ));
        }
        let size = numbers("image", "x", 2)?;
        let samples = numbers("samples", "..", 2)?;
        let c = numbers("crop", ",", 4)?;
        let crop = Crop {
            x0: c[0],
            y0: c[1],
            x1: c[2],
            y1: c[3],
        };
        crop.check(size[0], size[1])?;
        if samples[0] >= samples[1] {
            return Err(format!(
                "the sample range {}..{} is empty",
                samples[0], samples[1]
            ));
        }
        Ok(Self {
            scene_hash: field("scene_hash")?.to_owned(),
            settings: field("settings")?.to_owned(),
            width: size[0],
            height: size[1],
            samples: samples[0]..samples[1],
            crop,
        })
    }
}

/// A part: its [`PartInfo`] and the film of its window (crop-sized).
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// What the part is of.
    pub info: PartInfo,
    /// The window's sums and counts, `crop.width()` x `crop.height()`.
    pub film: Film,
}

/// The window `crop` of `film`, as a film of its own.
pub fn crop_film(film: &Film, crop: Crop) -> Film {
    let mut out = Film::new(crop.width(), crop.height());
    let mut i = 0;
    for y in crop.y0..crop.y1 {
        let row = (y * film.width) as usize;
        for x in crop.x0 as usize..crop.x1 as usize {
            out.sum[i] = film.sum[row + x];
            out.err[i] = film.err[row + x];
            out.count[i] = film.count[row + x];
            out.m2[i] = film.m2[row + x];
            out.replica_sum[i] = film.replica_sum[row + x];
            out.replica_count[i] = film.replica_count[row + x];
            i += 1;
        }
    }
    out
}

/// SHA-256 of a scene's content: the scene file's bytes and, for a RON scene, the bytes
/// of each mesh and texture file it names, in order. (Files that a glTF names in turn,
/// its buffers and images, are not followed.)
pub fn scene_hash(path: &Path) -> Result<String> {
    let read = |p: &Path| {
        std::fs::read(p).map_err(|source| GlintError::Io {
            path: p.to_owned(),
            source,
        })
    };
    let mut hash = Sha256::new();
    hash.update(read(path)?);
    if matches!(SceneFormat::of(path), SceneFormat::Ron) {
        let file = read_scene(path)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut named: Vec<&str> = file
            .materials
            .values()
            .filter_map(|m| m.kd_texture.as_deref())
            .collect();
        for e in &file.entities {
            if let EntityDesc::Mesh(m) = e {
                match &m.geometry {
                    GeometryDesc::Gltf { path, .. } | GeometryDesc::Obj { path } => {
                        named.push(path)
                    }
                    _ => {}
                }
            }
        }
        for name in named {
            // A file the loader cannot read fails the render itself, with its own message.
            if let Ok(bytes) = std::fs::read(dir.join(name)) {
                hash.update((bytes.len() as u64).to_le_bytes());
                hash.update(bytes);
            }
        }
    }
    Ok(hash.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

fn part_error(path: &Path, message: impl std::fmt::Display) -> GlintError {
    GlintError::Part(format!("{}: {message}", path.display()))
}

/// Names of the `u32` channels holding the high and low halves of each `f64`.
const SUM_CHANNELS: [&str; 12] = [
    "sum.R.hi", "sum.R.lo", "sum.G.hi", "sum.G.lo", "sum.B.hi", "sum.B.lo", "err.R.hi", "err.R.lo",
    "err.G.hi", "err.G.lo", "err.B.hi", "err.B.lo",
];

/// The `f64` of channel `k` of `SUM_CHANNELS` order: sum then err, R, G, B.
fn component(v: &[DVec3; 2], k: usize) -> f64 {
    v[k / 3][k % 3]
}

/// Writes `part` as an EXR file (atomically, byte-reproducible).
pub fn write_part(path: &Path, part: &Part) -> Result<()> {
    use exr::prelude::*;
    let film = &part.film;
    let n = film.sum.len();
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for k in 0..6 {
        let bits: Vec<u64> = (0..n)
            .map(|i| component(&[film.sum[i], film.err[i]], k).to_bits())
            .collect();
        channels.push(AnyChannel::new(
            SUM_CHANNELS[2 * k],
            FlatSamples::U32(bits.iter().map(|b| (b >> 32) as u32).collect()),
        ));
        channels.push(AnyChannel::new(
            SUM_CHANNELS[2 * k + 1],
            FlatSamples::U32(bits.iter().map(|&b| b as u32).collect()),
        ));
    }
    channels.push(AnyChannel::new(
        "count",
        FlatSamples::U32(film.count.clone()),
    ));
    // The moments serve only the error estimate: f32 keeps them small.
    for (c, rgb) in ["R", "G", "B"].into_iter().enumerate() {
        for (name, values) in [("m2", &film.m2), ("replica", &film.replica_sum)] {
            let v = values.iter().map(|v| v[c] as f32).collect();
            channels.push(AnyChannel::new(
                format!("{name}.{rgb}").as_str(),
                FlatSamples::F32(v),
            ));
        }
    }
    channels.push(AnyChannel::new(
        "replica.count",
        FlatSamples::U32(film.replica_count.clone()),
    ));
    let image = film.image();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let mean = image.iter().map(|p| p[c]).collect();
        channels.push(AnyChannel::new(name, FlatSamples::F32(mean)));
    }
    let encoding = exr::image::Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let text = Text::new_or_none(part.info.to_text())
        .ok_or_else(|| part_error(path, "the settings hold characters EXR text cannot"))?;
    let mut attributes = LayerAttributes::named("glint part");
    attributes
        .other
        .insert(Text::from(PART_ATTRIBUTE), AttributeValue::Text(text));
    let size = (film.width as usize, film.height as usize);
    let layer = Layer::new(size, attributes, encoding, AnyChannels::sort(channels));
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(&mut bytes)
        .map_err(|e| part_error(path, e))?;
    write_atomically(path, bytes.get_ref())
}

/// Reads a part file; the error names the file and what is missing or wrong.
pub fn read_part(path: &Path) -> Result<Part> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| part_error(path, format!("not a readable EXR file ({e})")))?;
    let layer = &image.layer_data;
    let text = match layer.attributes.other.get(&Text::from(PART_ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        _ => {
            return Err(part_error(
                path,
                format!("not a glint part (no {PART_ATTRIBUTE} attribute)"),
            ));
        }
    };
    let info = PartInfo::from_text(&text).map_err(|m| part_error(path, m))?;
    let size = layer.size;
    if (size.x(), size.y()) != (info.crop.width() as usize, info.crop.height() as usize) {
        return Err(part_error(path, "the image size does not match its crop"));
    }
    let channel = |name: &str| -> crate::error::Result<&Vec<u32>> {
        let found = layer.channel_data.list.iter().find(|c| c.name == *name);
        match found.map(|c| &c.sample_data) {
            Some(FlatSamples::U32(v)) => Ok(v),
            _ => Err(part_error(path, format!("no u32 channel {name}"))),
        }
    };
    let mut film = Film::new(info.crop.width(), info.crop.height());
    for k in 0..6 {
        let (hi, lo) = (
            channel(SUM_CHANNELS[2 * k])?,
            channel(SUM_CHANNELS[2 * k + 1])?,
        );
        let target = if k < 3 { &mut film.sum } else { &mut film.err };
        for (i, v) in target.iter_mut().enumerate() {
            v[k % 3] = f64::from_bits((hi[i] as u64) << 32 | lo[i] as u64);
        }
    }
    film.count.clone_from(channel("count")?);
    film.replica_count.clone_from(channel("replica.count")?);
    for (c, rgb) in ["R", "G", "B"].into_iter().enumerate() {
        for (name, target) in [("m2", &mut film.m2), ("replica", &mut film.replica_sum)] {
            let name = format!("{name}.{rgb}");
            let found = layer.channel_data.list.iter().find(|ch| ch.name == *name);
            let Some(FlatSamples::F32(v)) = found.map(|ch| &ch.sample_data) else {
                return Err(part_error(path, format!("no f32 channel {name}")));
            };
            for (t, &x) in target.iter_mut().zip(v) {
                t[c] = f64::from(x);
            }
        }
    }
    Ok(Part { info, film })
}

/// Merges parts into the film of the whole image, after checking that they are of one
/// scene, settings and size and that, at every pixel, their sample ranges tile `A..N`
/// for one `A` (the lowest start) and one `N`; returns the film and `A..N`. Each error
/// names the offending file.
pub fn merge_parts(parts: &[(PathBuf, Part)]) -> Result<(Film, Range<u32>)> {
    let Some((first_path, first)) = parts.first() else {
        return Err(GlintError::Part("no parts to merge".into()));
    };
    let first = &first.info;
    for (path, part) in parts {
        let p = &part.info;
        let other = |what: &str| {
            part_error(
                path,
                format!("{what} differ from those of {}", first_path.display()),
            )
        };
        if p.scene_hash != first.scene_hash {
            return Err(other("the scene's contents"));
        }
        if p.settings != first.settings {
            return Err(other("the settings"));
        }
        if (p.width, p.height) != (first.width, first.height) {
            return Err(other("the image size"));
        }
    }
    let (w, h) = (first.width as usize, first.height as usize);
    let mut film = Film::new(first.width, first.height);
    // Which part last added to each pixel, to name it when the next one overlaps.
    let mut owner: Vec<Option<usize>> = vec![None; w * h];
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&i| parts[i].1.info.samples.start);
    let from = parts[order[0]].1.info.samples.start;
    let mut next: Vec<u32> = vec![from; w * h];
    for i in order {
        let (path, part) = &parts[i];
        let (samples, crop) = (&part.info.samples, part.info.crop);
        let mut j = 0;
        for y in crop.y0..crop.y1 {
            for x in crop.x0..crop.x1 {
                let p = y as usize * w + x as usize;
                if next[p] > samples.start {
                    let other = &parts[owner[p].expect("a pixel with samples has a part")].0;
                    return Err(part_error(
                        path,
                        format!(
                            "samples {}..{} of pixel {x},{y} overlap those of {}",
                            samples.start,
                            samples.end,
                            other.display()
                        ),
                    ));
                }
                if next[p] < samples.start {
                    return Err(part_error(
                        path,
                        format!(
                            "pixel {x},{y} starts at sample {} but no part has its samples {}..{}",
                            samples.start, next[p], samples.start
                        ),
                    ));
                }
                next[p] = samples.end;
                owner[p] = Some(i);
                merge_moments(&mut film, p, &part.film, j);
                add_exact(&mut film.sum[p], &mut film.err[p], part.film.sum[j]);
                film.err[p] += part.film.err[j];
                film.count[p] += part.film.count[j];
                film.replica_sum[p] += part.film.replica_sum[j];
                film.replica_count[p] += part.film.replica_count[j];
                j += 1;
            }
        }
    }
    let total = next.iter().copied().max().unwrap_or(0);
    if let Some(p) = next.iter().position(|&n| n != total) {
        let (x, y) = (p % w, p / w);
        let message = format!(
            "no part has samples {}..{total} of pixel {x},{y} (the crops do not tile the image)",
            next[p]
        );
        return Err(match owner[p] {
            Some(i) => part_error(&parts[i].0, message),
            None => GlintError::Part(message),
        });
    }
    Ok((film, from..total))
}

/// Adds the squared deviations of pixel `j` of `part` to those of pixel `p` of `film`,
/// before their sums and counts are merged: Chan, Golub and LeVeque's pairwise update,
/// `m2 = m2_a + m2_b + (mean_b - mean_a)^2 n_a n_b / (n_a + n_b)`.
fn merge_moments(film: &mut Film, p: usize, part: &Film, j: usize) {
    let (na, nb) = (f64::from(film.count[p]), f64::from(part.count[j]));
    if na == 0.0 || nb == 0.0 {
        film.m2[p] += part.m2[j];
        return;
    }
    let delta = (part.sum[j] + part.err[j]) / nb - (film.sum[p] + film.err[p]) / na;
    film.m2[p] += part.m2[j] + delta * delta * (na * nb / (na + nb));
}

/// Merges parts (see [`merge_parts`]) into one part of the whole image, which merges
/// with others as exactly as its parts would: merges can form a tree.
pub fn merge_into_part(parts: &[(PathBuf, Part)]) -> Result<Part> {
    let (film, samples) = merge_parts(parts)?;
    let first = &parts[0].1.info;
    Ok(Part {
        info: PartInfo {
            samples,
            crop: Crop::full(film.width, film.height),
            ..first.clone()
        },
        film,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn info_text_round_trips() {
        let info = PartInfo {
            scene_hash: "ab12".into(),
            settings: "(seed: 3)".into(),
            width: 8,
            height: 6,
            samples: 4..12,
            crop: Crop {
                x0: 1,
                y0: 2,
                x1: 8,
                y1: 5,
            },
        };
        assert_eq!(PartInfo::from_text(&info.to_text()), Ok(info));
    }

    #[test]
    fn exact_sums_do_not_depend_on_the_order() {
        let xs = [1.0, 1e-12, 3.5e-9, -0.7, 1e-15, 2.0 / 3.0];
        let total = |order: &[usize]| {
            let (mut s, mut e) = (DVec3::ZERO, DVec3::ZERO);
            for &i in order {
                add_exact(&mut s, &mut e, DVec3::splat(xs[i]));
            }
            s + e
        };
        assert_eq!(total(&[0, 1, 2, 3, 4, 5]), total(&[5, 4, 3, 2, 1, 0]));
        assert_eq!(total(&[0, 1, 2, 3, 4, 5]), total(&[3, 0, 5, 1, 4, 2]));
    }
}
