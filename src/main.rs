//! The `glint` command line: parses arguments, calls the library, maps errors to exit codes.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use glint::film::{Encoding, write_image};
use glint::{GlintError, Overrides, Renderer, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// glint: a small CPU ray tracer that explains itself.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to a PNG (8-bit) or EXR (32-bit float) image.
    Render(RenderArgs),
    /// Show what a scene holds and which pipeline stages a render of it runs, and why.
    Info(SceneArgs),
    /// Run the numerical stress suite (extreme scales, edges, grazing rays, degenerate
    /// input...) and print a table of measurements; fails if any case fails.
    Stress(StressArgs),
}

#[derive(Args, Debug)]
struct StressArgs {
    /// Small images and ray counts (what the test suite runs).
    #[arg(long)]
    quick: bool,
    /// Also write the measurements as CSV to this file.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Run only the cases whose name contains this text.
    #[arg(long = "case", value_name = "NAME")]
    case: Option<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Args, Debug)]
struct SceneArgs {
    /// The scene file (RON).
    scene: PathBuf,
    /// Image width in pixels (overrides the scene's camera).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's camera).
    #[arg(long)]
    height: Option<u32>,
    /// Random seed (overrides the scene's settings).
    #[arg(long)]
    seed: Option<u64>,
    /// Override a setting, e.g. `--set shading_model=blinn_phong --set pixel_samples=16`
    /// (values in RON syntax; see docs/scene-format.md for the keys).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_key_value)]
    set: Vec<(String, String)>,
}

#[derive(Args, Debug)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output image; `.png` or `.exr`. Defaults to the scene's name with `.png`.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Worker threads (default: all cores). Output is identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Stop after the pass that exceeds this time budget, e.g. `30s`, `2m`, `500ms`.
    #[arg(long, value_parser = parse_duration)]
    time: Option<Duration>,
    /// Encode PNG output with the sRGB curve instead of clamped linear values.
    #[arg(long)]
    srgb: bool,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    quiet: bool,
}

fn parse_key_value(s: &str) -> std::result::Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY=VALUE, got \"{s}\""))?;
    Ok((k.trim().to_owned(), v.trim().to_owned()))
}

fn parse_duration(s: &str) -> std::result::Result<Duration, String> {
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

fn overrides(a: &SceneArgs) -> Overrides {
    Overrides {
        width: a.width,
        height: a.height,
        seed: a.seed,
        set: a.set.clone(),
    }
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from(format!("{stem}.png"))
}

fn render(args: &RenderArgs) -> Result<()> {
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| GlintError::Usage(format!("--threads: {e}")))?;
    }
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene.scene));
    // Fail on a bad output name before spending time on the render.
    match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr") => {}
        _ => {
            return Err(GlintError::Usage(format!(
                "{}: unknown output format (use .png or .exr)",
                output.display()
            )));
        }
    }
    let mut renderer = Renderer::from_file(&args.scene.scene, &overrides(&args.scene))?;
    for w in renderer.warnings() {
        eprintln!("warning: {w}");
    }
    let camera = renderer.camera().expect("a loaded scene has a camera");
    let total = camera.width as u64 * camera.height as u64 * renderer.samples_per_pixel() as u64;
    let bar = if args.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent}% (eta {eta})",
            )
            .expect("valid template"),
        );
        bar
    };
    let summary = renderer.render(args.time, &mut |n| bar.inc(n))?;
    bar.finish_and_clear();
    let film = renderer.film();
    let encoding = if args.srgb {
        Encoding::Srgb
    } else {
        Encoding::Linear
    };
    write_image(&output, film.width, film.height, &film.image(), encoding)?;
    if !args.quiet {
        eprintln!("{}: {summary}", output.display());
    }
    Ok(())
}

fn info(args: &SceneArgs) -> Result<()> {
    let mut renderer = Renderer::from_file(&args.scene, &overrides(args))?;
    print!("{}", glint::info::describe(&mut renderer)?);
    Ok(())
}

fn stress(args: &StressArgs) -> Result<()> {
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| GlintError::Usage(format!("--threads: {e}")))?;
    }
    if glint::stress::run(args.quick, args.csv.as_deref(), args.case.as_deref())? {
        Ok(())
    } else {
        Err(GlintError::Usage(
            "some stress cases failed (see the table)".into(),
        ))
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(a) => render(a),
        Command::Info(a) => info(a),
        Command::Stress(a) => stress(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
