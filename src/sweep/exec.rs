//! Running one run of a sweep to its files, and showing progress.
//!
//! A run is the same as `granflow run`: the HDF5 file and the front CSV, written
//! progressively. In addition its summary is captured from the sink calls and, once the
//! run has ended (also when it failed, also when it panicked), stored in its result
//! file (see [`super::record`]). The result file of an earlier run of the same name is
//! removed first, so an interrupted run never looks finished.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::expand::RunPoint;
use super::record::{self, h5_path, RunRecord, RECORD_FORMAT};
use crate::output::budget::{Budgeted, OUTPUT_LIMIT};
use crate::output::memory::SummarySink;
use crate::output::{create_run_sinks, RunSummary, Tee};
use crate::scenario::Scenario;
use crate::setup::build;
use crate::simulation::Progress;

/// A run whose scenario has been loaded and checked.
#[derive(Debug, Clone)]
pub struct Prepared {
    pub point: RunPoint,
    pub scenario: Scenario,
    /// FNV-1a of the scenario text, 16 hex digits.
    pub hash: String,
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string())
}

/// Runs `run` into `dir` and stores its result file. Never fails: what went wrong is in
/// the record's status.
///
/// The run's output file is locked (`<run>.h5.lock`, as by `granflow run`) while it
/// runs. Shards of one sweep may overlap (`--shard 0/2` beside a full sweep); a run
/// another process is producing is waited for, and then taken as done when it is
/// (unless `force`).
pub fn run_one(
    run: &Prepared,
    dir: &Path,
    force: bool,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> RunRecord {
    let name = &run.point.name;
    let h5 = h5_path(dir, name);
    let start = Instant::now();
    let lock_path = dir.join(format!("{name}.h5.lock"));
    let what = format!("the run file {}", h5.display());
    let _lock = match crate::lock::acquire(&lock_path, &what, true, &mut |_| {}) {
        Ok(lock) => lock,
        Err(e) => return failed_before_start(run, format!("failed: {e}")),
    };
    if !force {
        if let Some(done) = record::done(dir, name, &run.hash) {
            return done;
        }
    }
    let mut record = failed_before_start(run, String::new());
    if let Err(e) = record::remove(dir, name) {
        record.summary.status = format!("failed: cannot remove the old result file: {e}");
        return record;
    }
    let outcome = catch_unwind(AssertUnwindSafe(|| -> Result<RunSummary, String> {
        let mut sim = build(&run.scenario);
        let limit = (!force).then_some(OUTPUT_LIMIT);
        let sinks = Budgeted::new(
            create_run_sinks(&h5).map_err(|e| e.to_string())?,
            limit,
            &h5,
        );
        let mut sink = Tee::new(sinks, SummarySink::default());
        let result = sim.run(&mut sink, progress);
        // The summary the sink saw (also written for a failed run); else the error.
        match (sink.b.0.take(), result) {
            (Some(summary), _) => Ok(summary),
            (None, Ok(summary)) => Ok(summary),
            (None, Err(e)) => Err(e.to_string()),
        }
    }));
    match outcome {
        Ok(Ok(s)) => record.summary = s,
        Ok(Err(message)) => {
            let wall = start.elapsed().as_secs_f64();
            record.summary = RunSummary::not_run(format!("failed: {message}"), wall);
        }
        Err(payload) => {
            let message = format!("failed: panic: {}", panic_message(payload.as_ref()));
            record.summary = RunSummary::not_run(message, start.elapsed().as_secs_f64());
        }
    }
    if let Err(e) = record::write(dir, &record) {
        record.summary.status = format!(
            "failed: cannot write {}: {e}",
            record::record_path(dir, name).display()
        );
    }
    record
}

/// The record of a run that could not start (also the blank record a run fills in).
fn failed_before_start(run: &Prepared, status: String) -> RunRecord {
    let name = &run.point.name;
    RunRecord {
        format: RECORD_FORMAT,
        index: run.point.index,
        name: name.clone(),
        scenario_hash: run.hash.clone(),
        summary: RunSummary::not_run(status, 0.0),
        h5: format!("{name}.h5"),
        parameters: run
            .point
            .params
            .iter()
            .map(|(k, v)| (k.clone(), v.display.clone()))
            .collect(),
    }
}

/// Progress display: an overall bar and one line per active run, on stderr when it is a
/// terminal; otherwise (and unless quiet) one plain line per finished run.
pub struct Ui {
    multi: MultiProgress,
    overall: ProgressBar,
    tty: bool,
    quiet: bool,
}

impl Ui {
    pub fn new(runs: u64, quiet: bool) -> Ui {
        use std::io::IsTerminal;
        let tty = !quiet && std::io::stderr().is_terminal();
        let target = if tty {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let multi = MultiProgress::with_draw_target(target);
        let overall = multi.add(ProgressBar::new(runs));
        overall.set_style(
            ProgressStyle::with_template(
                "{bar:40.cyan/blue} {pos}/{len} runs [{elapsed_precise}, ETA {eta}] {msg}",
            )
            .expect("valid template"),
        );
        if tty {
            overall.enable_steady_tick(Duration::from_millis(200));
        }
        Ui {
            multi,
            overall,
            tty,
            quiet,
        }
    }

    /// A line for a run that starts now.
    pub fn start(&self, name: &str) -> ProgressBar {
        if !self.tty {
            return ProgressBar::hidden();
        }
        let bar = self
            .multi
            .insert_before(&self.overall, ProgressBar::new(1000));
        bar.set_style(
            ProgressStyle::with_template("  {bar:20.green/white} {msg}").expect("valid template"),
        );
        bar.set_message(name.to_owned());
        bar
    }

    /// Updates a run's line (call sparingly).
    pub fn advance(bar: &ProgressBar, name: &str, p: &Progress) {
        if bar.is_hidden() {
            return;
        }
        bar.set_position((1000.0 * p.t / p.t_end).clamp(0.0, 1000.0) as u64);
        bar.set_message(format!("{name}  t = {:.3} s, {} steps", p.t, p.steps));
    }

    /// Removes a finished run's line and reports it.
    pub fn finish(&self, bar: ProgressBar, record: &RunRecord) {
        bar.finish_and_clear();
        self.multi.remove(&bar);
        self.overall.inc(1);
        if self.quiet {
            return;
        }
        let line = format!(
            "[{}/{}] {}: {} ({:.2} s)",
            self.overall.position(),
            self.overall.length().unwrap_or(0),
            record.name,
            record.summary.status,
            record.summary.wall_time_s
        );
        self.println(&line);
    }

    /// A message above the bars (or on stderr without them), unless quiet.
    pub fn println(&self, line: &str) {
        if self.quiet {
        } else if self.tty {
            let _ = self.multi.println(line);
        } else {
            crate::terminal::print_err(&format!("{line}\n"));
        }
    }

    pub fn done(&self) {
        self.overall.finish_and_clear();
    }
}
