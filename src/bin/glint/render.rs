//! `glint render`: a progress bar over [`Renderer::render`], the image, a summary line.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use glint::Renderer;
use glint::film::{Encoding, write_image};
use indicatif::{ProgressBar, ProgressStyle};

use crate::cli::RenderArgs;
use crate::{CliError, CliResult, Interrupted, check_settings, ctrl_c_flag, set_threads};

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from(format!("{stem}.png"))
}

/// Renders, writes the image and prints the summary (or why the image is partial).
pub fn run(args: &RenderArgs) -> CliResult<Option<Interrupted>> {
    set_threads(args.threads)?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene.scene));
    // Fail on a bad output name before spending time on the render.
    match output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr") => {}
        _ => {
            return Err(CliError::Flag(format!(
                "{}: unknown output format (use .png or .exr)",
                output.display()
            )));
        }
    }
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(CliError::Flag(format!(
            "{}: the output folder {} does not exist",
            output.display(),
            dir.display()
        )));
    }
    check_settings("--set", args.scene.set.iter().map(|(k, v)| (k, v)))?;
    let mut renderer = Renderer::from_file(&args.scene.scene, &args.scene.overrides())?;
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
