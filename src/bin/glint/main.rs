//! The `glint` command line: parses arguments, calls the library, prints, maps errors to
//! exit codes. Every clap type is in [`cli`]; each command has its own module.

/// `eprintln!` through [`print_stderr`]: a closed standard error is ignored instead of
/// panicking. Defined before the modules, so that they can use it.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::print_stderr(&format!($($arg)*))
    };
}

mod cli;
mod converge;
mod debug;
mod merge;
mod render;
mod stress;
#[cfg(feature = "view")]
mod view;

use std::io::Write;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::Parser;
use glint::GlintError;

use cli::{Cli, Command};

/// Why the command failed: the library's error, or a flag the binary rejects itself.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// An error of the library.
    #[error(transparent)]
    Glint(#[from] GlintError),
    /// A command-line value that is not acceptable.
    #[error("{0}")]
    Flag(String),
    /// The command ran but its result is a failure (e.g. a failing stress case).
    #[error("{0}")]
    Failed(String),
}

/// Results of the commands.
pub type CliResult<T> = Result<T, CliError>;

/// Why `main` exits unsuccessfully although nothing failed.
pub struct Interrupted;

/// How many threads per core `--threads` may ask for: more only adds scheduling cost
/// (100,000 threads took minutes to start for a 16x16 image).
const MAX_THREADS_PER_CORE: usize = 4;

/// Sets the size of rayon's global pool; 0 means all cores, as no flag does.
pub fn set_threads(threads: Option<usize>) -> CliResult<()> {
    let Some(n) = threads else {
        return Ok(());
    };
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let most = MAX_THREADS_PER_CORE * cores;
    if n > most {
        return Err(CliError::Flag(format!(
            "--threads {n} is more than {MAX_THREADS_PER_CORE} per core of this machine's {cores} (at most {most}; 0 means all cores)"
        )));
    }
    // rayon reads 0 as "one thread per core".
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| CliError::Flag(format!("--threads: {e}")))
}

/// Checks each `KEY=VALUE` of `flag` against the settings before any file is read.
pub fn check_settings<'a>(
    flag: &str,
    pairs: impl IntoIterator<Item = (&'a String, &'a String)>,
) -> CliResult<()> {
    for (k, v) in pairs {
        glint::scene::Settings::default()
            .set(k, v)
            .map_err(|e| CliError::Flag(format!("{flag} {e}")))?;
    }
    Ok(())
}

/// A flag set by the first Ctrl-C; a second Ctrl-C exits at once.
pub fn ctrl_c_flag() -> CliResult<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    ctrlc::set_handler(move || {
        if handler_flag.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        say!("\ninterrupted: finishing the region in flight (Ctrl-C again to quit now)");
    })
    .map_err(|e| CliError::Failed(format!("cannot install the Ctrl-C handler: {e}")))?;
    Ok(flag)
}

#[cfg(feature = "view")]
fn view(args: &cli::SceneArgs) -> CliResult<()> {
    check_settings("--set", args.set.iter().map(|(k, v)| (k, v)))?;
    view::run(&args.scene, &args.overrides()).map_err(CliError::Failed)
}

#[cfg(not(feature = "view"))]
fn view(_: &cli::SceneArgs) -> CliResult<()> {
    Err(CliError::Failed(
        "this glint was built without the viewer (`--no-default-features`): run `cargo run --release --features view -- view SCENE`".into(),
    ))
}

fn info(args: &cli::SceneArgs) -> CliResult<()> {
    check_settings("--set", args.set.iter().map(|(k, v)| (k, v)))?;
    let mut renderer = glint::Renderer::from_file(&args.scene, &args.overrides())?;
    print_stdout(&glint::info::describe(&mut renderer)?);
    Ok(())
}

pub use glint::terminal::print_stdout;

/// Writes `text` and a newline to standard error (progress, warnings, summaries). These
/// are diagnostics: if their reader has gone away (`glint render 2>&1 | head -1`) the
/// work goes on and its file is still written, where `eprintln!` would panic (status 101).
pub fn print_stderr(text: &str) {
    let mut err = std::io::stderr().lock();
    let _ = writeln!(err, "{text}").and_then(|()| err.flush());
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(a) => render::run(a),
        Command::Info(a) => info(a).map(|()| None),
        Command::Converge(a) => converge::run(a),
        Command::Debug(a) => debug::run(a).map(|()| None),
        Command::Merge(a) => merge::run(a).map(|()| None),
        Command::Stress(a) => stress::run(a).map(|()| None),
        Command::View(a) => view(a).map(|()| None),
    };
    match result {
        Ok(None) => ExitCode::SUCCESS,
        // The conventional status of a process stopped by SIGINT.
        Ok(Some(Interrupted)) => ExitCode::from(130),
        Err(e) => {
            say!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
