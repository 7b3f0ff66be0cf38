//! `granflow` binary: parse the command line, run, map errors to exit codes
//! (0 success, 1 solver or output failure, 2 bad input).

use std::process::ExitCode;

use clap::Parser;
use granflow::cli::{Cli, Command, RunArgs, ScenarioArgs, EXIT_BAD_INPUT, EXIT_FAILURE};
use granflow::discover;
use granflow::progress::RunProgress;
use granflow::runner;
use granflow::scenario::{self, Scenario};

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

fn run(args: &RunArgs) -> ExitCode {
    let scn = match load(&args.scenario) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| scn.output.file.clone());
    let mut progress = RunProgress::new(
        args.progress,
        args.quiet,
        args.progress_every,
        scn.domain.cells,
    );
    let result = runner::run_to_files(&scn, &output, &mut |p| progress.update(&p));
    progress.finish();
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
        Command::Scenarios(args) => ExitCode::from(discover::scenarios(args)),
        Command::Init(args) => ExitCode::from(discover::init(args)),
        Command::Completions(args) => ExitCode::from(discover::completions(args)),
    }
}
