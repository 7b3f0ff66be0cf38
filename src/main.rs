//! `granflow` binary: parse the command line, run, map errors to exit codes
//! (0 success, 1 solver or output failure, 2 bad input).

use std::path::Path;
use std::process::ExitCode;

use clap::Parser;
use granflow::cli::{Cli, Command, RunArgs, ScenarioArgs};
use granflow::discover;
use granflow::interrupt;
use granflow::lock::{self, LockError, OutputLock};
use granflow::output::budget::OUTPUT_LIMIT;
use granflow::progress::RunProgress;
use granflow::runner;
use granflow::scenario::{self, Scenario};
use granflow::terminal::{print_err, print_out, EXIT_BAD_INPUT, EXIT_FAILURE};

/// Loads the scenario, refusing one whose run would write more than the output limit
/// unless `force`.
fn load(args: &ScenarioArgs, force: bool) -> Result<Scenario, ExitCode> {
    let limit = (!force).then_some(OUTPUT_LIMIT);
    let scn = scenario::load_file_within(&args.scenario, &args.set, limit).map_err(|e| {
        print_err(&format!("error: {e}\n"));
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    for note in &scn.notes {
        print_err(&format!("note: {note}\n"));
    }
    if let Some(release) = &scn.release {
        print_err(&format!("release: {}\n", release.describe()));
    }
    Ok(scn)
}

fn check(args: &ScenarioArgs) -> ExitCode {
    match load(args, false).map(|s| runner::check(&s)) {
        Ok(run) => {
            print_out(&format!(
                "{}: ok ({} model, {} cells, {} layer(s), stages: {})\n",
                args.scenario.display(),
                run.info().model,
                run.cells(),
                run.info().layers,
                run.stage_names().join(" → ")
            ));
            if run.mass() <= 0.0 {
                print_err(&format!(
                    "warning: {}: the initial state holds no mass (initial.h is 0 everywhere); a run will end at once with status no_mass\n",
                    args.scenario.display()
                ));
            }
            ExitCode::SUCCESS
        }
        Err(code) => code,
    }
}

/// Locks the output file for the whole run (see `granflow::lock::lock_output`): by the
/// name it resolves to and by its device and inode, so that no two names of one file
/// are written at once.
fn lock_output(output: &Path, wait: bool) -> Result<OutputLock, ExitCode> {
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        // The sink would create it anyway; the lock file needs it first.
        if let Err(e) = std::fs::create_dir_all(dir) {
            print_err(&format!("error: cannot create {}: {e}\n", dir.display()));
            return Err(ExitCode::from(EXIT_FAILURE));
        }
    }
    let what = format!("the output file {}", output.display());
    lock::lock_output(output, &what, wait, &mut |holder| {
        print_err(&format!("waiting: {what} is in use ({holder})\n"));
    })
    .map_err(|e| {
        print_err(&format!("error: {e}\n"));
        match e {
            LockError::Busy { .. } | LockError::NotOurs { .. } => ExitCode::from(EXIT_BAD_INPUT),
            LockError::Io { .. } => ExitCode::from(EXIT_FAILURE),
        }
    })
}

fn run(args: &RunArgs) -> ExitCode {
    let scn = match load(&args.scenario, args.force) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| scn.output.file.clone());
    if let Err(e) = granflow::overwrite::check_outputs(
        &args.scenario.scenario,
        &output,
        !scn.output.gauges.is_empty(),
        scn.domain.plane.is_some(),
        args.force,
    ) {
        print_err(&format!("error: {e}\n"));
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let lock = match lock_output(&output, args.wait) {
        Ok(lock) => lock,
        Err(code) => return code,
    };
    interrupt::install();
    let mut progress = RunProgress::new(
        args.progress,
        args.quiet,
        args.progress_every,
        scn.domain.cell_count(),
    )
    .with_settle(
        scn.time
            .stop_when_settled
            .then_some(scn.time.settle_fraction),
    );
    let limit = (!args.force).then_some(OUTPUT_LIMIT);
    let (threads, note) =
        granflow::cli::bounded_threads(args.threads, granflow::cli::default_threads());
    if let Some(note) = note {
        print_err(&format!("{note}\n"));
    }
    let result =
        runner::run_to_files_threads(&scn, &output, limit, threads, &mut |p| progress.update(&p));
    progress.finish();
    if let Ok(report) = &result {
        for w in report.warnings() {
            print_err(&format!("{w}\n"));
        }
    }
    match result {
        Ok(report) if report.summary.status == "interrupted" => {
            // Said even with --quiet: the user asked for the stop and needs to know
            // what was kept.
            print_err(&format!(
                "granflow: interrupted at t = {} s; partial results in {} and {}\n",
                runner::sig(report.summary.t_end),
                report.h5.display(),
                report.front_csv.display()
            ));
            if !args.quiet {
                print_out(&report.to_string());
            }
            ExitCode::from(interrupt::EXIT_INTERRUPTED)
        }
        Ok(report) => {
            if !args.quiet {
                print_out(&report.to_string());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            lock.remove_if_unwritten();
            print_err(&format!("error: {e}\n"));
            ExitCode::from(EXIT_FAILURE)
        }
    }
}

/// `granflow export`: the files written, one per line (unless `--quiet`).
fn export(args: &granflow::results::ExportArgs) -> ExitCode {
    match granflow::results::export::export(args) {
        Ok(exported) => {
            if let Some(warning) = &exported.warning {
                // Said even with --quiet: the files are not what their names promise.
                print_err(&format!("{warning}\n"));
            }
            if !args.quiet {
                for f in exported.files {
                    print_out(&format!("{}\n", f.display()));
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            print_err(&format!("error: {e}\n"));
            ExitCode::from(e.exit_code())
        }
    }
}

/// `granflow maps`: the runs (ranked against an observed footprint) and the files.
fn maps(args: &granflow::results::MapsArgs) -> ExitCode {
    match granflow::results::maps::maps(args) {
        Ok(report) => {
            if !report.left_out.is_empty() {
                print_err(&format!(
                    "note: {} runs not done were left out (--partial): {}\n",
                    report.left_out.len(),
                    report.left_out.join(", ")
                ));
            }
            if !args.quiet {
                print_out(&report.table());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            print_err(&format!("error: {e}\n"));
            ExitCode::from(e.exit_code())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let code = match &cli.command {
        Command::Run(args) => run(args),
        Command::Check(args) => check(args),
        Command::Sweep(args) => ExitCode::from(granflow::sweep::main(args)),
        Command::Scenarios(args) => ExitCode::from(discover::scenarios(args)),
        Command::Init(args) => ExitCode::from(discover::init(args)),
        Command::Export(args) => export(args),
        Command::Maps(args) => maps(args),
        Command::Completions(args) => ExitCode::from(discover::completions(args)),
    };
    if granflow::terminal::stdout_failed() && code == ExitCode::SUCCESS {
        // What the command printed is lost: not a success (already said on stderr).
        return ExitCode::from(EXIT_FAILURE);
    }
    code
}
