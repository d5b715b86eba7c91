//! The `glint` command line: parses arguments, calls the library, maps errors to exit codes.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
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
    /// Measure error against a reference per pass, for configurations at equal time.
    Converge(ConvergeArgs),
    /// Explain one pixel: a debug image of its rays, BVH, lights, texture and samples.
    Debug(DebugCmd),
    /// Run the numerical stress suite (extreme scales, edges, grazing rays, degenerate
    /// input...) and print a table of measurements; fails if any case fails.
    Stress(StressArgs),
}

#[derive(Args, Debug)]
struct DebugCmd {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    debug: glint::debug::DebugArgs,
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
    /// The scene: a RON scene file, or a glTF (.gltf, .glb) or OBJ model rendered directly.
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

#[derive(Args, Debug)]
struct ConvergeArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Reference image (EXR, same size as the render).
    #[arg(long, conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Render the reference with this many samples per pixel (stratified, rounded to a
    /// square) and cache it in `.glint-cache/` beside the scene.
    #[arg(long, default_value_t = 4096)]
    reference_spp: u32,
    /// Time budget per configuration (render time only, error measurement excluded).
    /// Default 10s when --max-spp is absent.
    #[arg(long, value_parser = parse_duration)]
    time: Option<Duration>,
    /// Stop each configuration at this many samples per pixel.
    #[arg(long)]
    max_spp: Option<u32>,
    /// Compare values of a setting, e.g. `--compare shadow_samples=1,4,16`. Several
    /// flags give the cross product of their values.
    #[arg(long, value_name = "KEY=V1,V2,...", value_parser = parse_compare)]
    compare: Vec<(String, Vec<String>)>,
    /// Write one row per (configuration, measured pass) to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Plot RMSE against seconds and against spp (log-log) into this PNG.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

fn parse_compare(s: &str) -> std::result::Result<(String, Vec<String>), String> {
    let (k, v) = parse_key_value(s)?;
    let values: Vec<String> = v.split(',').map(|x| x.trim().to_owned()).collect();
    if values.iter().any(String::is_empty) {
        return Err(format!(
            "expected KEY=V1,V2,... with no empty value, got \"{s}\""
        ));
    }
    Ok((k, values))
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

fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| GlintError::Usage(format!("--threads: {e}")))?;
    }
    Ok(())
}

/// A flag set by the first Ctrl-C; a second Ctrl-C exits at once.
fn ctrl_c_flag() -> Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    ctrlc::set_handler(move || {
        if handler_flag.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the region in flight (Ctrl-C again to quit now)");
    })
    .map_err(|e| GlintError::Usage(format!("cannot install the Ctrl-C handler: {e}")))?;
    Ok(flag)
}

/// Why `main` exits unsuccessfully although nothing failed.
struct Interrupted;

fn render(args: &RenderArgs) -> Result<Option<Interrupted>> {
    set_threads(args.threads)?;
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
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(GlintError::Usage(format!(
            "{}: the output folder {} does not exist",
            output.display(),
            dir.display()
        )));
    }
    let mut renderer = Renderer::from_file(&args.scene.scene, &overrides(&args.scene))?;
    for w in renderer.warnings() {
        eprintln!("warning: {w}");
    }
    renderer.set_interrupt(ctrl_c_flag()?);
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
    let (least, most) = (
        film.count.iter().copied().min().unwrap_or(0),
        film.count.iter().copied().max().unwrap_or(0),
    );
    if summary.interrupted && most == 0 {
        eprintln!("interrupted before the first sample: no image written");
        return Ok(Some(Interrupted));
    }
    let encoding = if args.srgb {
        Encoding::Srgb
    } else {
        Encoding::Linear
    };
    write_image(&output, film.width, film.height, &film.image(), encoding)?;
    if summary.interrupted {
        // Counts exclude dropped non-finite samples, so state the passes too.
        let held = if least == most {
            format!("{least} samples per pixel")
        } else {
            format!("{least} to {most} samples per pixel (the last pass was cut short)")
        };
        eprintln!(
            "interrupted: {} holds {held}, {} complete passes of {}",
            output.display(),
            summary.samples,
            renderer.samples_per_pixel()
        );
        return Ok(Some(Interrupted));
    }
    if !args.quiet {
        eprintln!("{}: {summary}", output.display());
    }
    Ok(None)
}

fn converge(args: &ConvergeArgs) -> Result<Option<Interrupted>> {
    set_threads(args.threads)?;
    let options = glint::converge::ConvergeOptions {
        scene: args.scene.scene.clone(),
        overrides: overrides(&args.scene),
        reference: match &args.reference {
            Some(path) => glint::converge::ReferenceSource::File(path.clone()),
            None => glint::converge::ReferenceSource::Render {
                spp: args.reference_spp,
            },
        },
        time: match (args.time, args.max_spp) {
            (None, None) => Some(Duration::from_secs(10)),
            (t, _) => t,
        },
        max_spp: args.max_spp,
        compare: args.compare.clone(),
        csv: args.csv.clone(),
        plot: args.plot.clone(),
        interrupt: Some(ctrl_c_flag()?),
    };
    let report = glint::converge::run(&options, &mut |line| eprintln!("{line}"))?;
    print!("{report}");
    if report.interrupted {
        eprintln!("interrupted: the table, CSV and plot hold the passes measured so far");
    }
    Ok(report.interrupted.then_some(Interrupted))
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
        Command::Info(a) => info(a).map(|()| None),
        Command::Converge(a) => converge(a),
        Command::Debug(a) => {
            glint::debug::run(&a.scene.scene, &overrides(&a.scene), &a.debug).map(|()| None)
        }
        Command::Stress(a) => stress(a).map(|()| None),
    };
    match result {
        Ok(None) => ExitCode::SUCCESS,
        // The conventional status of a process stopped by SIGINT.
        Ok(Some(Interrupted)) => ExitCode::from(130),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
