//! `granflow` binary: parse the command line, run, map errors to exit codes
//! (0 success, 1 solver or output failure, 2 bad input).

use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use granflow::cli::{Cli, Command, RunArgs, ScenarioArgs, EXIT_BAD_INPUT, EXIT_FAILURE};
use granflow::runner;
use granflow::scenario::{self, Scenario};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

fn load(args: &ScenarioArgs) -> Result<Scenario, ExitCode> {
    scenario::load_file(&args.scenario, &args.set).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

fn check(args: &ScenarioArgs) -> ExitCode {
    match load(args).map(|s| runner::check(&s)) {
        Ok(run) => {
            println!(
                "{}: ok ({} model, {} cells, {} layer(s), stages: {})",
                args.scenario.display(),
                run.info().model,
                run.cells(),
                run.info().layers,
                run.stage_names().join(" → ")
            );
            ExitCode::SUCCESS
        }
        Err(code) => code,
    }
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{bar:40.cyan/blue} {msg} [{elapsed_precise}, ETA {eta}]")
            .expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

fn run(args: &RunArgs) -> ExitCode {
    let scn = match load(&args.scenario) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| scn.output.file.clone());
    let bar = progress_bar(args.quiet);
    let mut last_draw = 0u64;
    let result = runner::run_to_files(&scn, &output, &mut |p| {
        // Touch the bar every 64 steps: cheap, and smooth enough for a human.
        if p.steps - last_draw >= 64 {
            last_draw = p.steps;
            bar.set_position((1000.0 * p.t / p.t_end) as u64);
            bar.set_message(format!(
                "t = {:.4} s / {} s, {} steps",
                p.t, p.t_end, p.steps
            ));
        }
    });
    bar.finish_and_clear();
    match result {
        Ok(report) => {
            if !args.quiet {
                print!("{report}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match &cli.command {
        Command::Run(args) => run(args),
        Command::Check(args) => check(args),
        Command::Sweep(args) => ExitCode::from(granflow::sweep::main(args)),
    }
}
