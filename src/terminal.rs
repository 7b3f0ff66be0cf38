//! The process's face to the terminal: its exit codes and its writes to stdout and
//! stderr. A lowest layer: it imports nothing of the crate, so every module (the lock,
//! the interrupt handler, the sweep, the progress display) can print without depending
//! on the command line.
//!
//! Writes never fail a run: a reader that went away (`granflow run … | head -1`, or
//! `2>&1 | head -1`) gets nothing more and the run goes on.

use std::io::Write;

/// Exit code of a solver or output failure (a run, or a sweep or merge with failures).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code for bad input: scenario, sweep file, options.
pub const EXIT_BAD_INPUT: u8 = 2;

/// Writes `text` to stdout. A reader that went away (`granflow run … | head -3`) is not
/// an error of the run: the output is dropped quietly instead of panicking as `print!`
/// does. Other write errors are reported on stderr.
pub fn print_out(text: &str) {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
        Err(e) => print_err(&format!("granflow: cannot write to stdout: {e}\n")),
    }
}

/// Writes `text` to stderr, ignoring failures (there is nowhere left to report them).
pub fn print_err(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}
