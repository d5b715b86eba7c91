//! Split renders: `glint render --samples A..B --crop X0,Y0,X1,Y1 -o part.exr` writes a
//! part, `glint merge part*.exr -o image.png` checks and merges parts (see
//! [`glint::film::part`]).

use std::path::PathBuf;

use glint::Renderer;
use glint::film::estimate::EstimateMethod;
use glint::film::part::{Crop, merge_into_part, merge_parts, read_part, scene_hash, write_part};
use glint::film::{Encoding, write_image};

use crate::cli::{MergeArgs, RenderArgs};
use crate::render::{check_output, default_output, progress_bar};
use crate::{CliError, CliResult, Interrupted, check_settings, ctrl_c_flag, set_threads};

/// Renders the part `--samples` x `--crop` of a scene and writes it as EXR. An
/// interrupted part writes nothing: its file would claim samples it does not hold.
pub fn render_part(args: &RenderArgs) -> CliResult<Option<Interrupted>> {
    set_threads(args.threads)?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene.scene).with_extension("exr"));
    let is_exr = output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Err(CliError::Flag(format!(
            "{}: a part (--samples, --crop) is written as EXR: name it .exr",
            output.display()
        )));
    }
    check_output(&output)?;
    check_settings("--set", args.scene.set.iter().map(|(k, v)| (k, v)))?;
    let mut renderer = Renderer::from_file(&args.scene.scene, &args.scene.overrides())?;
    for w in renderer.warnings() {
        say!("warning: {w}");
    }
    let camera = renderer.camera().expect("a loaded scene has a camera");
    let spp = renderer.samples_per_pixel();
    let samples = args.samples.clone().unwrap_or(0..spp);
    if samples.end > spp {
        return Err(CliError::Flag(format!(
            "--samples {}..{}: the render takes samples 0..{spp} (pixel_samples)",
            samples.start, samples.end
        )));
    }
    let crop = args
        .crop
        .unwrap_or_else(|| Crop::full(camera.width, camera.height));
    crop.check(camera.width, camera.height)
        .map_err(|m| CliError::Flag(format!("--crop {crop}: {m}")))?;
    let hash = scene_hash(&args.scene.scene)?;
    renderer.set_interrupt(ctrl_c_flag()?);
    let total = crop.width() as u64 * crop.height() as u64 * samples.len() as u64;
    let bar = progress_bar(args.quiet, total);
    let summary = renderer.render_part(samples.clone(), crop, &mut |n| bar.inc(n))?;
    bar.finish_and_clear();
    if summary.interrupted {
        say!("interrupted: no part written");
        return Ok(Some(Interrupted));
    }
    write_part(&output, &renderer.part(hash, samples.clone(), crop))?;
    if !args.quiet {
        say!(
            "{}: part of samples {}..{}, crop {crop}: {summary}",
            output.display(),
            samples.start,
            samples.end
        );
    }
    Ok(None)
}

/// Reads, checks and merges the parts, and writes the image.
pub fn run(args: &MergeArgs) -> CliResult<()> {
    check_output(&args.output)?;
    let is_exr = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if args.part && !is_exr {
        return Err(CliError::Flag(format!(
            "{}: --part writes a part, which is EXR: name it .exr",
            args.output.display()
        )));
    }
    let parts = args
        .parts
        .iter()
        .map(|p| Ok((p.clone(), read_part(p)?)))
        .collect::<CliResult<Vec<(PathBuf, _)>>>()?;
    if args.part {
        write_part(&args.output, &merge_into_part(&parts)?)?;
        if !args.quiet {
            say!(
                "{}: a part merged from {} parts",
                args.output.display(),
                parts.len()
            );
        }
        return Ok(());
    }
    let (film, samples) = merge_parts(&parts)?;
    if samples.start > 0 {
        return Err(CliError::Flag(format!(
            "no part has samples 0..{} (an image needs them; --part writes a part of samples {}..{})",
            samples.start, samples.start, samples.end
        )));
    }
    let total = samples.end;
    let settings = parts[0].1.info.parsed_settings();
    if let Some(full) = parts[0].1.info.full_samples().filter(|&full| total < full) {
        say!(
            "warning: the parts hold samples 0..{total} of the {full} a full render takes (pixel_samples): the image is noisier than a single render's"
        );
    }
    let encoding = if args.srgb {
        Encoding::Srgb
    } else {
        Encoding::Linear
    };
    write_image(
        &args.output,
        film.width,
        film.height,
        &film.image(),
        encoding,
    )?;
    if !args.quiet {
        let estimate = settings
            .and_then(|s| film.error_estimate(EstimateMethod::for_settings(&s)))
            .map(|e| format!("; estimated error: {e}"))
            .unwrap_or_default();
        say!(
            "{}: {}x{}, {total} spp, merged from {} parts{estimate}",
            args.output.display(),
            film.width,
            film.height,
            parts.len()
        );
    }
    Ok(())
}
