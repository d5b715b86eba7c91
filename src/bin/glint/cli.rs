//! Every clap type of the `glint` command line and its value parsers.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use glint::Overrides;
use glint::debug::Feature;

/// glint: a small CPU ray tracer that explains itself.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to a PNG (8-bit) or EXR (32-bit float) image.
    Render(RenderArgs),
    /// Show what a scene holds and which pipeline stages a render of it runs, and why.
    Info(SceneArgs),
    /// Measure error against a reference per pass, for configurations at equal time.
    Converge(ConvergeArgs),
    /// Explain one pixel: a debug image of its rays, BVH, lights, texture and samples.
    Debug(DebugCmd),
    /// Merge parts of a split render (`glint render --samples/--crop -o part.exr`) into
    /// one image, bit-identical to a single render of all their samples.
    Merge(MergeArgs),
    /// Open a window on a scene or model: progressive render, camera, settings, and
    /// pixel tracing in 3D (the `view` feature, on by default).
    View(SceneArgs),
    /// Run the numerical stress suite (extreme scales, edges, grazing rays, degenerate
    /// input...) and print a table of measurements; fails if any case fails.
    Stress(StressArgs),
}

#[derive(Args, Debug)]
pub struct DebugCmd {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub debug: DebugArgs,
}

/// Options of `glint debug` beyond the scene's.
#[derive(Args, Debug, Clone)]
pub struct DebugArgs {
    /// The pixel to explain, `X,Y` (row 0 at the top).
    #[arg(long, value_parser = parse_pixel)]
    pub pixel: [u32; 2],
    /// Output image (PNG).
    #[arg(short, long, default_value = "debug.png")]
    pub output: PathBuf,
    /// Features to explain, comma separated: pixel (its rays, hit and colour; always
    /// shown), reflections, transparency, bvh, textures, lights, samples (default: all
    /// that are on in the scene).
    #[arg(long, value_delimiter = ',', value_parser = parse_feature)]
    pub features: Option<Vec<Feature>>,
    /// View the scene from this point, `X,Y,Z` (default: an oblique viewpoint framing the scene and the path).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub view_from: Option<Vec3>,
    /// Size of the debug image, `WxH`.
    #[arg(long, default_value = "800x600", value_parser = parse_size)]
    pub view_size: [u32; 2],
    /// Fade the parts of primitives that the scene hides from the view.
    #[arg(long)]
    pub depth_test: bool,
    /// Also show every BVH node at this level, for the whole scene.
    #[arg(long)]
    pub bvh_level: Option<u32>,
    /// Also write the debug entities as RON to this file.
    #[arg(long)]
    pub dump: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Small images and ray counts (what the test suite runs).
    #[arg(long)]
    pub quick: bool,
    /// Also write the measurements as CSV to this file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Run only the cases whose name contains this text.
    #[arg(long = "case", value_name = "NAME")]
    pub case: Option<String>,
    /// Worker threads (default or 0: all cores; at most 4 per core).
    #[arg(long)]
    pub threads: Option<usize>,
}

#[derive(Args, Debug)]
pub struct SceneArgs {
    /// The scene: a RON scene file, or a glTF (.gltf, .glb) or OBJ model rendered directly.
    pub scene: PathBuf,
    /// Image width in pixels (overrides the scene's camera).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels (overrides the scene's camera).
    #[arg(long)]
    pub height: Option<u32>,
    /// Random seed (overrides the scene's settings).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Override a setting, e.g. `--set shading_model=blinn_phong --set pixel_samples=16`
    /// (values in RON syntax; see docs/scene-format.md for the keys).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_key_value)]
    pub set: Vec<(String, String)>,
}

impl SceneArgs {
    /// The library's overrides for these flags.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            seed: self.seed,
            set: self.set.clone(),
        }
    }
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output image; `.png` or `.exr`. Defaults to the scene's name with `.png`.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Worker threads (default or 0: all cores; at most 4 per core). Output is identical for any count.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Stop after the pass that exceeds this time budget, e.g. `30s`, `2m`, `500ms`.
    #[arg(long, value_parser = parse_duration)]
    pub time: Option<Duration>,
    /// Stop when the estimated RMSE of the image reaches this, e.g. `0.005` (passes go
    /// on past the scene's pixel_samples; --time still bounds the run).
    #[arg(long, value_parser = parse_target)]
    pub target_error: Option<f64>,
    /// Stop when the estimated relative error, sqrt(relMSE), reaches this, e.g. `0.02`.
    #[arg(long, value_parser = parse_target)]
    pub target_rel_error: Option<f64>,
    /// Encode PNG output with the sRGB curve instead of clamped linear values.
    #[arg(long)]
    pub srgb: bool,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
    /// Render only sample indices A..B (B excluded) and write a part for `glint merge`
    /// (EXR output).
    #[arg(long, value_name = "A..B", value_parser = parse_samples, conflicts_with = "time")]
    pub samples: Option<std::ops::Range<u32>>,
    /// Render only the window X0,Y0,X1,Y1 (columns X0..X1, rows Y0..Y1, row 0 at the
    /// top) and write a part for `glint merge` (EXR output).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_crop, conflicts_with = "time")]
    pub crop: Option<glint::film::part::Crop>,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The part files (EXR) written by `glint render --samples/--crop`.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output image; `.png` or `.exr`.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Encode PNG output with the sRGB curve instead of clamped linear values.
    #[arg(long)]
    pub srgb: bool,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
    /// Write the merge as a part (EXR) instead of an image, to merge again with others:
    /// merges can form a tree, exactly.
    #[arg(long)]
    pub part: bool,
}

#[derive(Args, Debug)]
pub struct ConvergeArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Reference image (EXR, same size as the render).
    #[arg(long, conflicts_with = "reference_spp")]
    pub reference: Option<PathBuf>,
    /// Render the reference with this many samples per pixel (Owen-scrambled Sobol')
    /// and cache it, with its estimated error, in `.glint-cache/` beside the scene.
    /// 4096 spp of the Cornell box take minutes: the time left is printed as it goes.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Time budget per configuration (render time only, error measurement excluded).
    /// Default 10s when --max-spp is absent.
    #[arg(long, value_parser = parse_duration)]
    pub time: Option<Duration>,
    /// Stop each configuration at this many samples per pixel.
    #[arg(long)]
    pub max_spp: Option<u32>,
    /// Compare values of a setting, e.g. `--compare shadow_samples=1,4,16`. Several
    /// flags give the cross product of their values.
    #[arg(long, value_name = "KEY=V1,V2,...", value_parser = parse_compare)]
    pub compare: Vec<(String, Vec<String>)>,
    /// Write one row per (configuration, measured pass) to this CSV file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Plot RMSE against seconds and against spp (log-log) into this PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Worker threads (default or 0: all cores; at most 4 per core).
    #[arg(long)]
    pub threads: Option<usize>,
}

fn parse_target(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive number, got \"{s}\"")),
    }
}

fn parse_compare(s: &str) -> Result<(String, Vec<String>), String> {
    let (k, v) = parse_key_value(s)?;
    let values: Vec<String> = v.split(',').map(|x| x.trim().to_owned()).collect();
    if values.iter().any(String::is_empty) {
        return Err(format!(
            "expected KEY=V1,V2,... with no empty value, got \"{s}\""
        ));
    }
    Ok((k, values))
}

fn parse_key_value(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY=VALUE, got \"{s}\""))?;
    Ok((k.trim().to_owned(), v.trim().to_owned()))
}

fn parse_duration(s: &str) -> Result<Duration, String> {
    let s = s.trim();
    let split = s.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(s.len());
    let (num, unit) = s.split_at(split);
    let v: f64 = num
        .parse()
        .map_err(|_| format!("expected a duration like 30s, 2m or 500ms, got \"{s}\""))?;
    let secs = match unit {
        "" | "s" => v,
        "ms" => v / 1000.0,
        "m" | "min" => v * 60.0,
        "h" => v * 3600.0,
        _ => return Err(format!("unknown time unit \"{unit}\" (use ms, s, m or h)")),
    };
    if !(secs.is_finite() && secs > 0.0) {
        return Err(format!("the time budget must be positive, got \"{s}\""));
    }
    Ok(Duration::from_secs_f64(secs))
}

fn parse_numbers<T: std::str::FromStr>(
    s: &str,
    sep: char,
    n: usize,
    what: &str,
) -> Result<Vec<T>, String> {
    let parts: Vec<&str> = s.split(sep).map(str::trim).collect();
    let values: Option<Vec<T>> = parts.iter().map(|p| p.parse().ok()).collect();
    match values {
        Some(v) if v.len() == n => Ok(v),
        _ => Err(format!("expected {what}, got \"{s}\"")),
    }
}

fn parse_samples(s: &str) -> Result<std::ops::Range<u32>, String> {
    let v = s
        .split_once("..")
        .and_then(|(a, b)| Some((a.trim().parse::<u32>().ok()?, b.trim().parse::<u32>().ok()?)));
    match v {
        Some((a, b)) if a < b => Ok(a..b),
        Some(_) => Err(format!("the sample range must not be empty, got \"{s}\"")),
        None => Err(format!(
            "expected A..B (sample indices A to B-1), got \"{s}\""
        )),
    }
}

fn parse_crop(s: &str) -> Result<glint::film::part::Crop, String> {
    let v = parse_numbers::<u32>(s, ',', 4, "X0,Y0,X1,Y1")?;
    if v[0] >= v[2] || v[1] >= v[3] {
        return Err(format!(
            "the crop must have X0 < X1 and Y0 < Y1, got \"{s}\""
        ));
    }
    Ok(glint::film::part::Crop {
        x0: v[0],
        y0: v[1],
        x1: v[2],
        y1: v[3],
    })
}

fn parse_pixel(s: &str) -> Result<[u32; 2], String> {
    let v = parse_numbers::<u32>(s, ',', 2, "X,Y")?;
    Ok([v[0], v[1]])
}

fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let v = parse_numbers::<u32>(&s.to_ascii_lowercase(), 'x', 2, "WxH")?;
    if v[0] == 0 || v[1] == 0 || v[0] > 8192 || v[1] > 8192 {
        return Err(format!("the view size must be within 1..8192, got \"{s}\""));
    }
    Ok([v[0], v[1]])
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v = parse_numbers::<f32>(s, ',', 3, "X,Y,Z")?;
    let p = Vec3::new(v[0], v[1], v[2]);
    if !p.is_finite() {
        return Err(format!("expected finite numbers, got \"{s}\""));
    }
    Ok(p)
}

fn parse_feature(s: &str) -> Result<Feature, String> {
    Feature::parse(s).ok_or_else(|| {
        let names: Vec<&str> = Feature::ALL.iter().map(|f| f.name()).collect();
        format!("unknown feature \"{s}\" (known: {})", names.join(", "))
    })
}
