//! `glint converge`: the options from the flags, progress lines and the summary table.

use std::time::Duration;

use glint::converge::{ConvergeOptions, ConvergeReport, ReferenceSource};

use crate::cli::ConvergeArgs;
use crate::{CliError, CliResult, Interrupted, check_settings, ctrl_c_flag, set_threads};

/// Measures every configuration, prints progress to stderr and the table to stdout.
pub fn run(args: &ConvergeArgs) -> CliResult<Option<Interrupted>> {
    set_threads(args.threads)?;
    if args.max_spp == Some(0) {
        return Err(CliError::Flag("--max-spp must be at least 1".into()));
    }
    check_settings("--set", args.scene.set.iter().map(|(k, v)| (k, v)))?;
    check_settings(
        "--compare",
        args.compare
            .iter()
            .flat_map(|(k, values)| values.iter().map(move |v| (k, v))),
    )?;
    let options = ConvergeOptions {
        scene: args.scene.scene.clone(),
        overrides: args.scene.overrides(),
        reference: match &args.reference {
            Some(path) => ReferenceSource::File(path.clone()),
            None => ReferenceSource::Render {
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
    let report = glint::converge::run(&options, &mut |line| say!("{line}"))?;
    crate::print_stdout(&table(&report));
    if report.interrupted {
        say!("interrupted: the table, CSV and plot hold the passes measured so far");
    }
    Ok(report.interrupted.then_some(Interrupted))
}

/// One line per configuration: passes, spp, seconds, last error and the fitted slopes.
fn table(report: &ConvergeReport) -> String {
    let slope = |s: Option<f64>| s.map_or_else(|| "n/a".into(), |s| format!("{s:+.2}"));
    let mut out = format!(
        "{:<44} {:>6} {:>6} {:>8} {:>10} {:>10} {:>10} {:>10} {:>9}\n",
        "configuration",
        "passes",
        "spp",
        "seconds",
        "RMSE",
        "relMSE",
        "slope/s",
        "slope/spp",
        "est/true"
    );
    for c in &report.curves {
        let Some(last) = c.passes.last() else {
            out += &format!("{:<44} no complete pass\n", c.label());
            continue;
        };
        out += &format!(
            "{:<44} {:>6} {:>6} {:>8.2} {:>10.3e} {:>10.3e} {:>10} {:>10} {:>9}\n",
            c.label(),
            c.passes.len(),
            last.spp,
            last.seconds,
            last.error.rmse,
            last.error.rel_mse,
            slope(c.slope_time()),
            slope(c.slope_spp()),
            c.estimate_ratio()
                .map_or_else(|| "n/a".into(), |r| format!("{r:.2}"))
        );
    }
    out
}
