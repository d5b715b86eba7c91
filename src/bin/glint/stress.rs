//! `glint stress`: runs the suite and fails if any case fails.

use crate::cli::StressArgs;
use crate::{CliError, CliResult, set_threads};

/// Runs the selected cases; an error when any row fails.
pub fn run(args: &StressArgs) -> CliResult<()> {
    set_threads(args.threads)?;
    if glint::stress::run(args.quick, args.csv.as_deref(), args.case.as_deref())? {
        Ok(())
    } else {
        Err(CliError::Failed(
            "some stress cases failed (see the table)".into(),
        ))
    }
}
