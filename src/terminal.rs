//! The process's face to the terminal: its exit codes and its writes to stdout and
//! stderr. A lowest layer: it imports nothing of the crate, so every module (the lock,
//! the interrupt handler, the sweep, the progress display) can print without depending
//! on the command line.
//!
//! Writes never stop a run: a reader that went away (`granflow run … | head -1`, or
//! `2>&1 | head -1`) gets nothing more and the run goes on. But stdout that cannot be
//! written (`> /dev/full`, a closed stdout) is reported on stderr and the command then
//! exits 1, never 0 ([`stdout_failed`]): what it printed is lost. (A stdout closed
//! before the process started cannot be told from `> /dev/null`: the Rust runtime
//! opens `/dev/null` in its place before `main`.)
//!
//! Lines on stderr are cut to [`LINE_LIMIT`] characters (head and tail kept): an error
//! that quotes a key or value of a megabyte names it without repeating it.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once a write to stdout failed (other than a reader that went away).
static STDOUT_FAILED: AtomicBool = AtomicBool::new(false);

/// The longest line written to stderr, in characters; longer ones keep their first
/// and last characters around a note of what was cut.
pub const LINE_LIMIT: usize = 1000;

/// Exit code of a solver or output failure (a run, or a sweep or merge with failures).
pub const EXIT_FAILURE: u8 = 1;
/// Exit code for bad input: scenario, sweep file, options.
pub const EXIT_BAD_INPUT: u8 = 2;

/// Writes `text` to stdout. A reader that went away (`granflow run … | head -3`) is not
/// an error of the run: the output is dropped quietly instead of panicking as `print!`
/// does. Other write errors are reported on stderr.
pub fn print_out(text: &str) {
    if STDOUT_FAILED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    let written = out.write_all(text.as_bytes()).and_then(|()| out.flush());
    match written {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
        Err(e) => {
            STDOUT_FAILED.store(true, Ordering::Relaxed);
            print_err(&format!("granflow: cannot write to stdout: {e}\n"));
        }
    }
}

/// Whether a write to stdout failed (other than a reader that went away): the command
/// then exits 1.
pub fn stdout_failed() -> bool {
    STDOUT_FAILED.load(Ordering::Relaxed)
}

/// Writes `text` to stderr, its long lines cut ([`clip`]), ignoring failures (there is
/// nowhere left to report them).
pub fn print_err(text: &str) {
    let _ = std::io::stderr().lock().write_all(clip(text).as_bytes());
}

/// `text` with every line longer than [`LINE_LIMIT`] characters cut to its first and
/// last characters around `… [N characters cut] …`.
pub fn clip(text: &str) -> std::borrow::Cow<'_, str> {
    if text.len() <= LINE_LIMIT {
        return text.into();
    }
    let mut out = String::with_capacity(text.len().min(4 * LINE_LIMIT));
    for line in text.split_inclusive('\n') {
        let chars = line.chars().count();
        if chars <= LINE_LIMIT {
            out.push_str(line);
            continue;
        }
        let (head, tail) = (LINE_LIMIT / 2, LINE_LIMIT * 2 / 5);
        out.extend(line.chars().take(head));
        out.push_str(&format!(" … [{} characters cut] … ", chars - head - tail));
        out.extend(line.chars().skip(chars - tail));
    }
    out.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lines_keep_their_head_and_tail() {
        let short = "error: a short line\nand another\n";
        assert_eq!(clip(short), short);
        let long = format!("error: key '{}' is unknown\nhint\n", "é".repeat(1_000_000));
        let cut = clip(&long);
        assert!(cut.chars().count() < LINE_LIMIT + 100, "{}", cut.len());
        assert!(cut.starts_with("error: key 'é") && cut.ends_with("é' is unknown\nhint\n"));
        assert!(cut.contains("characters cut"), "{cut}");
    }
}
