//! `glint render`: a progress bar over [`Renderer::render`], the image, a summary line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use glint::Renderer;
use glint::film::{Encoding, write_image};
use glint::render::StopRule;
use indicatif::{ProgressBar, ProgressStyle};

use crate::cli::RenderArgs;
use crate::{CliError, CliResult, Interrupted, check_settings, ctrl_c_flag, set_threads};

pub fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from(format!("{stem}.png"))
}

/// Fails on an output glint could not write, before any time is spent on the render:
/// an unknown format, a folder in its place, a missing or unwritable folder.
pub fn check_output(output: &Path) -> CliResult<()> {
    let flag = |why: String| Err(CliError::Flag(format!("{}: {why}", output.display())));
    match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr") => {}
        _ => return flag("unknown output format (use .png or .exr)".into()),
    }
    if output.is_dir() {
        return flag("is a folder, not an image file".into());
    }
    let dir = match output.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(d) if !d.is_dir() => {
            return flag(format!("the output folder {} does not exist", d.display()));
        }
        Some(d) => d,
        None => Path::new("."),
    };
    // The image is written through a temporary file in the same folder: try one now.
    if let Err(e) = tempfile::tempfile_in(dir) {
        return flag(format!("cannot write in the folder {}: {e}", dir.display()));
    }
    Ok(())
}

/// Where an interrupted render with unfinished pixels goes: beside the output
/// (`name.partial.png`), so that a complete image of the same name is never replaced
/// by one whose unfinished pixels are black.
fn partial_path(output: &Path) -> PathBuf {
    let stem = output.file_stem().unwrap_or_default().to_string_lossy();
    let ext = output.extension().unwrap_or_default().to_string_lossy();
    output.with_file_name(format!("{stem}.partial.{ext}"))
}

/// A progress bar over `total` pixel samples on a terminal, hidden otherwise.
pub fn progress_bar(quiet: bool, total: u64) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent}% (eta {eta})",
        )
        .expect("valid template"),
    );
    bar
}

/// Renders, writes the image and prints the summary (or why the image is partial).
pub fn run(args: &RenderArgs) -> CliResult<Option<Interrupted>> {
    if args.samples.is_some() || args.crop.is_some() {
        return crate::merge::render_part(args);
    }
    set_threads(args.threads)?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene.scene));
    check_output(&output)?;
    check_settings("--set", args.scene.set.iter().map(|(k, v)| (k, v)))?;
    let mut renderer = Renderer::from_file(&args.scene.scene, &args.scene.overrides())?;
    for w in renderer.warnings() {
        say!("warning: {w}");
    }
    renderer.set_interrupt(ctrl_c_flag()?);
    let camera = renderer.camera().expect("a loaded scene has a camera");
    let total = camera.width as u64 * camera.height as u64 * renderer.samples_per_pixel() as u64;
    let rule = StopRule {
        time: args.time,
        target_rmse: args.target_error,
        target_rel_error: args.target_rel_error,
    };
    let targeted = rule.target_rmse.is_some() || rule.target_rel_error.is_some();
    let bar = if targeted && !args.quiet && std::io::stderr().is_terminal() {
        // The number of passes is not known in advance: count pixel samples instead.
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {pos} pixel samples")
                .expect("valid template"),
        );
        bar
    } else {
        progress_bar(args.quiet, total)
    };
    let summary = renderer.render_until(&rule, &mut |n| bar.inc(n))?;
    bar.finish_and_clear();
    let film = renderer.film();
    let (least, most) = (
        film.count.iter().copied().min().unwrap_or(0),
        film.count.iter().copied().max().unwrap_or(0),
    );
    if summary.interrupted && most == 0 {
        say!("interrupted before the first sample: no image written");
        return Ok(Some(Interrupted));
    }
    let encoding = if args.srgb {
        Encoding::Srgb
    } else {
        Encoding::Linear
    };
    // Some pixels have no sample only when the first pass was cut short.
    let output = if summary.interrupted && least == 0 {
        partial_path(&output)
    } else {
        output
    };
    write_image(&output, film.width, film.height, &film.image(), encoding)?;
    if summary.interrupted {
        // Counts exclude dropped non-finite samples, so state the passes too.
        let held = if least == most {
            format!("{least} samples per pixel")
        } else if least == 0 {
            format!("pixels with up to {most} samples and unfinished (black) pixels")
        } else {
            format!("{least} to {most} samples per pixel (the last pass was cut short)")
        };
        say!(
            "interrupted: {} holds {held}, {} complete passes of {}",
            output.display(),
            summary.samples,
            renderer.samples_per_pixel()
        );
        return Ok(Some(Interrupted));
    }
    if !args.quiet {
        say!("{}: {summary}", output.display());
    }
    Ok(None)
}
