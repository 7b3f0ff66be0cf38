//! The commands that help a user find their way: `granflow scenarios`, `granflow init`
//! and `granflow completions`. Each returns the process exit code.

use std::fmt::Write;

use clap::CommandFactory;

use crate::catalog::{self, InitError};
use crate::cli::{Cli, CompletionsArgs, InitArgs, ScenariosArgs};
use crate::terminal::{print_out, EXIT_BAD_INPUT, EXIT_FAILURE};

/// `granflow scenarios [--show NAME]`.
pub fn scenarios(args: &ScenariosArgs) -> u8 {
    if let Some(name) = &args.show {
        let Some(b) = catalog::find(name) else {
            crate::terminal::print_err(&format!(
                "error: no bundled scenario named '{name}' (see `granflow scenarios`)\n"
            ));
            return EXIT_BAD_INPUT;
        };
        print_out(b.toml);
        return 0;
    }
    let width = catalog::BUNDLED
        .iter()
        .map(|b| b.name.len())
        .max()
        .unwrap_or(0);
    let mut out = String::new();
    for b in catalog::BUNDLED {
        let _ = writeln!(out, "{:width$}  {}", b.name, b.description());
    }
    let _ = writeln!(
        out,
        "\nCopy one to edit and run it:  granflow init my_run --from collapse\n\
         Print one:                    granflow scenarios --show collapse"
    );
    print_out(&out);
    0
}

/// `granflow init NAME [--from SCENARIO] [--force]`.
pub fn init(args: &InitArgs) -> u8 {
    match catalog::init(&args.name, args.from.as_deref(), args.force) {
        Ok(written) => {
            print_out(&format!(
                "{written}\nrun it:  granflow run {}\n",
                written.scenario.display()
            ));
            0
        }
        Err(e @ (InitError::Unknown(_) | InitError::Exists(_))) => {
            crate::terminal::print_err(&format!("error: {e}\n"));
            EXIT_BAD_INPUT
        }
        Err(e) => {
            crate::terminal::print_err(&format!("error: {e}\n"));
            EXIT_FAILURE
        }
    }
}

/// `granflow completions SHELL`: the script on stdout.
pub fn completions(args: &CompletionsArgs) -> u8 {
    let mut cmd = Cli::command();
    // Into a buffer first: clap_complete panics when its writer fails, e.g. on a closed
    // pipe (`granflow completions bash | head`).
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut cmd, "granflow", &mut script);
    print_out(&String::from_utf8_lossy(&script));
    0
}
