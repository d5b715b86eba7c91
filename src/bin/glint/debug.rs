//! `glint debug`: the options from the flags, the notes and the summary line.

use glint::GlintError;
use glint::debug::DebugOptions;

use crate::cli::DebugCmd;
use crate::{CliError, CliResult, check_settings};

/// Explains one pixel and prints what the library noted and found.
pub fn run(cmd: &DebugCmd) -> CliResult<()> {
    check_settings("--set", cmd.scene.set.iter().map(|(k, v)| (k, v)))?;
    let a = &cmd.debug;
    let options = DebugOptions {
        pixel: a.pixel,
        output: a.output.clone(),
        features: a.features.clone(),
        view_from: a.view_from,
        view_size: a.view_size,
        depth_test: a.depth_test,
        bvh_level: a.bvh_level,
        dump: a.dump.clone(),
    };
    let outcome = glint::debug::run(&cmd.scene.scene, &cmd.scene.overrides(), &options).map_err(
        |e| match e {
            // The library names the pixel; here it came from the --pixel flag.
            GlintError::PixelOutside { .. } => CliError::Flag(format!("--{e}")),
            e => e.into(),
        },
    )?;
    for note in &outcome.notes {
        say!("note: {note}");
    }
    let c = outcome.pixel_color;
    say!(
        "{}: pixel {},{} = ({:.4}, {:.4}, {:.4}), {} debug entities",
        a.output.display(),
        a.pixel[0],
        a.pixel[1],
        c.x,
        c.y,
        c.z,
        outcome.entities
    );
    Ok(())
}
