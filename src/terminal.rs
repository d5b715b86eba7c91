//! Standard output as command-line tools use it: the `glint` binary's and the bench
//! examples' one writer.

use std::io::Write;

/// Writes `text` to standard output. A reader that has gone away (`glint info | head -1`)
/// ends the process quietly (status 0), as it does for other command-line tools, instead
/// of the panic `print!` raises on a closed pipe; any other failure ends it with status 1
/// and a line on standard error. For command-line front ends only: it may end the
/// process.
pub fn print_stdout(text: &str) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        // Standard error may be closed too: the status says it.
        let _ = writeln!(
            std::io::stderr(),
            "error: cannot write to standard output: {e}"
        );
        std::process::exit(1);
    }
}
