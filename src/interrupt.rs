//! Ctrl-C (SIGINT) and SIGTERM: stop cleanly instead of dying mid-write.
//!
//! The handler only raises a flag. The run loop consults it after every step through
//! the [`Interrupted`](crate::stop::Interrupted) stop rule, and long loops inside a
//! step (the dilatant model's stabilisation sub-steps, up to 10 000 of them) look at it
//! every [`INTERRUPT_CHECK_EVERY`](crate::numerics::INTERRUPT_CHECK_EVERY) iterations and
//! give the step up, the state going back to the last accepted step ([`StageError::Interrupted`](crate::numerics::StageError::Interrupted)). So an interrupted run writes
//! a last snapshot, flushes its step records and finishes its file with the status
//! `interrupted`; `granflow run` then says where the partial results are and exits with
//! 130 (128 + SIGINT, the shell convention). A sweep starts no new run and lets the
//! running ones stop the same way. A second Ctrl-C exits at once (the files keep what
//! their last snapshot wrote, as after a kill).
//!
//! Library users (tests, benchmarks) never install the handler: the flag then stays
//! down and the rule never fires.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Exit code of a run or sweep ended by Ctrl-C.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Installs the handler (once per process; later calls do nothing).
pub fn install() {
    // An error means a handler is already installed (by an earlier call): fine.
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        crate::terminal::print_err(
            "\ninterrupt: stopping at the end of the current step, or inside it if it is long (press Ctrl-C again to quit at once)\n",
        );
    });
}

/// Whether Ctrl-C (or SIGTERM) has been received.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}
