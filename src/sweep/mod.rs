//! `granflow sweep`: many runs of one scenario over a grid of parameter values.
//!
//! Pipeline (user documentation in `docs/sweeps.md`):
//!
//! 1. [`spec`] reads the sweep file: base scenario, base overrides, axes (product) and
//!    zipped groups, with errors naming key and line.
//! 2. [`expand`] lists the runs in sweep order and names each from its parameters
//!    ([`naming`]); `--shard K/N` keeps the runs with index ≡ K (mod N).
//! 3. Every run's scenario is loaded and checked *before any run starts* (bad input:
//!    exit code 2, naming the run and the axis).
//! 4. The run list goes to `DIR/sweep-plan.toml` ([`plan`]), identical for every shard.
//! 5. Runs already done (their result file and HDF5 file say so, for the same scenario)
//!    are skipped unless `--force` ([`record`]).
//! 6. The others execute, the expected-longest first ([`order`]), on a local rayon pool of `--jobs` threads, one run per worker,
//!    each run single-threaded ([`exec`]); each writes its HDF5 file, front CSV and,
//!    when it ends, its result file (atomically).
//! 7. The summary ([`summary`]) is written to `DIR/summary.csv` (a shard writes
//!    `DIR/summary.shard-K-of-N.csv`); `sweep merge DIR` rebuilds `DIR/summary.csv`
//!    from the plan and the result files of all shards.
//!
//! A failed run is recorded with its error and the others go on; the exit code is 1 if
//! any run of the invocation failed, 0 otherwise.

pub mod args;
pub mod error;
pub mod exec;
pub mod expand;
pub mod naming;
pub mod order;
pub mod plan;
pub mod record;
pub mod sample;
pub mod spec;
pub mod summary;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use rayon::prelude::*;

pub use args::{MergeArgs, SweepArgs, SweepCommand};
pub use error::{SweepError, EXIT_BAD_INPUT, EXIT_FAILURE};
pub use expand::{RunPoint, Shard};

use exec::{Prepared, Ui};
use plan::{Plan, PlanRun, PLAN_FORMAT};
use record::write_atomic;
use spec::SweepSpec;
use summary::{summary_file_name, to_csv, to_table, Row, SUMMARY_FILE};

use crate::output::budget::{self, OUTPUT_LIMIT};
use crate::scenario::{self, ScenarioError};
use crate::terminal::{print_err, print_out};

/// What `granflow sweep` was asked to do.
#[derive(Debug, Clone)]
pub struct SweepOptions {
    pub sweep: PathBuf,
    pub jobs: usize,
    pub output: Option<PathBuf>,
    pub force: bool,
    pub shard: Shard,
    /// `--set` overrides, applied to every run after the sweep file's `set`.
    pub set: Vec<String>,
    pub quiet: bool,
    /// Wait for another sweep holding the directory's lock instead of failing.
    pub wait: bool,
}

/// What a sweep (or a merge) ended with.
#[derive(Debug, Clone)]
pub struct SweepReport {
    pub dir: PathBuf,
    /// Axis keys (summary columns).
    pub axes: Vec<String>,
    /// The rows of this invocation's summary, in sweep order.
    pub rows: Vec<Row>,
    /// The summary file written.
    pub summary: PathBuf,
    /// Runs executed now.
    pub ran: usize,
    /// Runs skipped because they were already done.
    pub skipped: usize,
    pub wall_time_s: f64,
}

impl SweepReport {
    /// Rows that did not complete (failed, missing, stale, …).
    pub fn failed(&self) -> usize {
        self.rows.iter().filter(|r| !r.is_ok()).count()
    }

    pub fn table(&self) -> String {
        to_table(&self.axes, &self.rows)
    }
}

/// The default number of jobs: the cores this process may use.
pub fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn normalized_key(set: &str) -> String {
    let key = set.split_once('=').map_or(set, |(k, _)| k);
    key.split('.').map(str::trim).collect::<Vec<_>>().join(".")
}

/// Base overrides (`set` of the sweep file, then `--set`); none may touch an axis.
fn base_overrides(spec: &SweepSpec, cli: &[String]) -> Result<Vec<String>, SweepError> {
    for (i, o) in spec.set.iter().chain(cli).enumerate() {
        let key = normalized_key(o);
        if let Some(axis) = spec.axis_touching(&key) {
            let line = axis.line.map_or("?".into(), |l| l.to_string());
            let why = format!(
                "'{o}' sets '{key}', which the axis '{}' (line {line}) varies; remove one of them",
                axis.key
            );
            return Err(if i < spec.set.len() {
                SweepError::file(&spec.path, spec.set_line, Some("set"), why)
            } else {
                SweepError::Input(format!("--set {why}"))
            });
        }
    }
    Ok(spec.set.iter().chain(cli).cloned().collect())
}

/// Explains a scenario error of one run, pointing at the axis when its value is the cause,
/// else at the override (`base`: sweep-file `set`, then `--set`) or the base scenario.
fn run_error(spec: &SweepSpec, base: &[String], point: &RunPoint, e: &ScenarioError) -> String {
    let run = format!("run {} ({})", point.index, point.name);
    let axis = e
        .key()
        .filter(|_| e.is_from_set())
        .and_then(|k| spec.axis_touching(k));
    match axis {
        Some(axis) => {
            let value = point
                .params
                .iter()
                .find(|(k, _)| *k == axis.key)
                .map_or(String::new(), |(_, v)| v.toml.clone());
            format!(
                "{run}: axis '{}' = {value} (line {} of '{}'), key '{}': {}",
                axis.key,
                axis.line.map_or("?".into(), |l| l.to_string()),
                spec.path.display(),
                e.key().unwrap_or(&axis.key),
                e.message()
            )
        }
        None if e.is_from_set() => {
            let key = e.key().unwrap_or("?");
            // The last override of the key wins: sweep-file `set` first, then `--set`.
            let last = base
                .iter()
                .rposition(|o| spec::is_under(key, &normalized_key(o)));
            let from = if last.is_some_and(|i| i < spec.set.len()) {
                format!(
                    "set = [...] (line {} of '{}')",
                    spec.set_line.map_or("?".into(), |l| l.to_string()),
                    spec.path.display()
                )
            } else {
                "--set".to_string()
            };
            format!("{run}: key '{key}' from {from}: {}", e.message())
        }
        None => format!("{run}: in '{}': {e}", spec.scenario.display()),
    }
}

/// Most runs a sweep makes without `--force`.
pub const MAX_RUNS: f64 = 10_000.0;
/// Most runs a sweep makes at all: beyond, the list of runs alone would not fit in
/// memory.
pub const MAX_RUNS_FORCED: f64 = 10_000_000.0;

/// Counts the runs before listing them: refuses more than [`MAX_RUNS`] (without
/// `force`) or [`MAX_RUNS_FORCED`], saying how much they would write.
fn check_run_count(spec: &SweepSpec, base: &[String], force: bool) -> Result<(), SweepError> {
    let count: f64 = spec.dims.iter().map(|d| d.len() as f64).product();
    let limit = if force { MAX_RUNS_FORCED } else { MAX_RUNS };
    if count <= limit {
        return Ok(());
    }
    // The size of one run: the base scenario's (without the axes' values).
    let each = scenario::read_bounded(&spec.scenario, scenario::MAX_SCENARIO_BYTES)
        .ok()
        .and_then(|text| {
            let base_dir = spec.scenario.parent().unwrap_or(Path::new("."));
            scenario::load_str_within(&text, base_dir, base, None).ok()
        })
        .map(|s| s.output_estimate().bytes());
    let size = match each {
        Some(b) => format!(
            ", writing about {} ({} per run of the base scenario)",
            budget::size(b * count),
            budget::size(b)
        ),
        None => String::new(),
    };
    let what = if count >= 1e15 {
        format!("{count:.3e}")
    } else {
        format!("{count}")
    };
    let advice = if force {
        format!("at most {MAX_RUNS_FORCED:e} runs even with --force; split the sweep")
    } else {
        format!("more than {MAX_RUNS} runs needs --force; or use fewer values")
    };
    Err(SweepError::file(
        &spec.path,
        None,
        Some("axes"),
        format!("the axes make {what} runs{size}: {advice}"),
    ))
}

/// Loads and checks every run's scenario. All errors are collected.
fn prepare(
    spec: &SweepSpec,
    points: &[RunPoint],
    base: &[String],
    pool: &rayon::ThreadPool,
    force: bool,
) -> Result<Vec<Prepared>, SweepError> {
    let limit = (!force).then_some(OUTPUT_LIMIT);
    let text =
        scenario::read_bounded(&spec.scenario, scenario::MAX_SCENARIO_BYTES).map_err(|e| {
            SweepError::file(
                &spec.path,
                spec.scenario_line,
                Some("scenario"),
                format!(
                    "cannot read the base scenario '{}': {e}",
                    spec.scenario.display()
                ),
            )
        })?;
    let base_dir = match spec.scenario.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let results: Vec<Result<Prepared, String>> = pool.install(|| {
        points
            .par_iter()
            .map(|point| {
                let mut overrides = base.to_vec();
                overrides.extend(point.overrides());
                let scenario = scenario::load_str_within(&text, &base_dir, &overrides, limit)
                    .map_err(|e| run_error(spec, base, point, &e))?;
                let hash = format!("{:016x}", naming::fnv1a(scenario.source_toml.as_bytes()));
                Ok(Prepared {
                    point: point.clone(),
                    scenario,
                    hash,
                })
            })
            .collect()
    });
    let errors: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    if !errors.is_empty() {
        const SHOWN: usize = 5;
        let mut msg = format!(
            "{} of {} runs of '{}' are invalid; nothing was run:",
            errors.len(),
            points.len(),
            spec.path.display()
        );
        for e in errors.iter().take(SHOWN) {
            msg.push_str("\n  ");
            msg.push_str(e);
        }
        if errors.len() > SHOWN {
            msg.push_str(&format!("\n  … and {} more", errors.len() - SHOWN));
        }
        return Err(SweepError::Scenario(msg));
    }
    Ok(results.into_iter().map(Result::unwrap).collect())
}

/// The output directory: `--output`, else the sweep file's `output`, else its stem.
fn output_dir(spec: &SweepSpec, cli: Option<&Path>) -> PathBuf {
    if let Some(dir) = cli {
        return dir.to_path_buf();
    }
    if let Some(dir) = &spec.output {
        return dir.clone();
    }
    let stem = spec
        .path
        .file_stem()
        .map_or_else(|| "sweep".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(stem)
}

fn row_for(p: &Prepared, record: Option<record::RunRecord>, note: &str) -> Row {
    Row {
        index: p.point.index,
        name: p.point.name.clone(),
        values: p
            .point
            .params
            .iter()
            .map(|(_, v)| v.display.clone())
            .collect(),
        record,
        note: note.to_owned(),
    }
}

fn write_summary(path: &Path, axes: &[String], rows: &[Row]) -> Result<(), SweepError> {
    write_atomic(path, &to_csv(axes, rows))
        .map_err(|e| SweepError::Io(format!("cannot write {}: {e}", path.display())))
}

/// The run list written to `DIR/sweep-plan.toml` (identical for every shard).
fn plan_of(spec: &SweepSpec, base: &[String], axes: &[String], prepared: &[Prepared]) -> Plan {
    Plan {
        format: PLAN_FORMAT,
        granflow_version: env!("CARGO_PKG_VERSION").to_string(),
        sweep_file: spec.path.display().to_string(),
        scenario: spec.scenario.display().to_string(),
        base_overrides: base.to_vec(),
        axes: axes.to_vec(),
        sweep_toml: spec.text.clone(),
        runs: prepared
            .iter()
            .map(|p| PlanRun {
                index: p.point.index,
                name: p.point.name.clone(),
                scenario_hash: p.hash.clone(),
                values: p
                    .point
                    .params
                    .iter()
                    .map(|(_, v)| v.display.clone())
                    .collect(),
                overrides: p.point.overrides(),
            })
            .collect(),
    }
}

/// Runs `mine[slot]` for every slot in `todo` on `jobs` workers of `pool`, each taking
/// the next run in the order of `todo` (the expected-longest first, [`order`]). `records` holds the results known so far (one per run of
/// `mine`) and is completed in place; the summary at `summary_path` is rewritten at most
/// once a second on the way.
#[allow(clippy::too_many_arguments)]
fn execute(
    pool: &rayon::ThreadPool,
    jobs: usize,
    mine: &[&Prepared],
    todo: &[usize],
    records: &mut [Option<record::RunRecord>],
    dir: &Path,
    axes: &[String],
    summary_path: &Path,
    ui: &Ui,
    force: bool,
) {
    let rows_of = |records: &[Option<record::RunRecord>], pending: &str| -> Vec<Row> {
        mine.iter()
            .zip(records)
            .map(|(p, r)| row_for(p, r.clone(), pending))
            .collect()
    };
    let live = Mutex::new((records, Instant::now()));
    let next = AtomicUsize::new(0);
    pool.scope(|s| {
        for _ in 0..jobs.min(todo.len()) {
            s.spawn(|_| loop {
                // After Ctrl-C no new run starts; running ones stop by their own rule.
                if crate::interrupt::requested() {
                    break;
                }
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(&slot) = todo.get(i) else { break };
                let run = mine[slot];
                let name = &run.point.name;
                let bar = ui.start(name);
                let mut drawn = 0u64;
                let record = exec::run_one(run, dir, force, &mut |p| {
                    if p.steps >= drawn + 64 {
                        drawn = p.steps;
                        Ui::advance(&bar, name, &p);
                    }
                });
                ui.finish(bar, &record);
                let mut live = live.lock().unwrap_or_else(|e| e.into_inner());
                let (records, last_write) = &mut *live;
                records[slot] = Some(record);
                if last_write.elapsed() >= Duration::from_secs(1) {
                    *last_write = Instant::now();
                    // Best effort: the caller's final write reports errors.
                    let _ = write_summary(summary_path, axes, &rows_of(records, "pending"));
                }
            });
        }
    });
}

/// Locks the output directory for this sweep: `DIR/sweep.lock`, exclusively for a
/// whole sweep; a shard holds it shared, so that the shards of a job array run side by
/// side but never beside the whole sweep, and holds `DIR/sweep.shard-K-of-N.lock`
/// exclusively, so that one shard does not run twice.
fn lock_dir(dir: &Path, opts: &SweepOptions) -> Result<Vec<crate::lock::Lock>, SweepError> {
    use crate::lock::{acquire, acquire_shared, LockError};
    let whole = format!("the sweep directory {}", dir.display());
    let on_wait = |what: &str, holder: &str| {
        if !opts.quiet {
            print_err(&format!("waiting: {what} is in use ({holder})\n"));
        }
    };
    let error = |e: LockError| match e {
        LockError::Busy { .. } | LockError::NotOurs { .. } => SweepError::Input(e.to_string()),
        LockError::Io { .. } => SweepError::Io(e.to_string()),
    };
    let path = dir.join("sweep.lock");
    if !opts.shard.is_partial() {
        let lock = acquire(&path, &whole, opts.wait, &mut |h| on_wait(&whole, h));
        return lock.map(|l| vec![l]).map_err(error);
    }
    let (k, n) = (opts.shard.k, opts.shard.n);
    let shard = format!("shard {k}/{n} of the sweep directory {}", dir.display());
    let dir_lock =
        acquire_shared(&path, &whole, opts.wait, &mut |h| on_wait(&whole, h)).map_err(error)?;
    let shard_lock = acquire(
        &dir.join(format!("sweep.shard-{k}-of-{n}.lock")),
        &shard,
        opts.wait,
        &mut |h| on_wait(&shard, h),
    )
    .map_err(error)?;
    Ok(vec![dir_lock, shard_lock])
}

/// Runs a sweep (or one shard of it).
pub fn run(opts: &SweepOptions) -> Result<SweepReport, SweepError> {
    let started = Instant::now();
    let spec = spec::load(&opts.sweep)?;
    let base = base_overrides(&spec, &opts.set)?;
    check_run_count(&spec, &base, opts.force)?;
    let points = expand::expand_spec(&spec)
        .map_err(|m| SweepError::file(&spec.path, None, Some("axes"), m))?;
    // No more workers than runs (a pool thread per worker, see `run`'s loop below).
    let jobs = opts.jobs.clamp(1, points.len().max(1));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(|i| format!("granflow-sweep-{i}"))
        .build()
        .map_err(|e| SweepError::Io(format!("cannot start {jobs} worker threads: {e}")))?;
    let prepared = prepare(&spec, &points, &base, &pool, opts.force)?;
    let axes: Vec<String> = spec.axes().map(|a| a.key.clone()).collect();

    let dir = output_dir(&spec, opts.output.as_deref());
    std::fs::create_dir_all(&dir).map_err(|e| {
        SweepError::Io(format!(
            "cannot create the output directory {}: {e}",
            dir.display()
        ))
    })?;
    // Held to the end: a second sweep into `dir` would corrupt every file (module docs
    // of crate::lock).
    let _lock = lock_dir(&dir, opts)?;
    let plan = plan_of(&spec, &base, &axes, &prepared);
    let replaced = plan.write(&dir).map_err(SweepError::Io)?;

    let mine: Vec<&Prepared> = prepared
        .iter()
        .filter(|p| opts.shard.contains(p.point.index))
        .collect();
    let done: Vec<Option<record::RunRecord>> = mine
        .iter()
        .map(|p| {
            if opts.force {
                None
            } else {
                record::done(&dir, &p.point.name, &p.hash)
            }
        })
        .collect();
    let todo: Vec<usize> = (0..mine.len()).filter(|&i| done[i].is_none()).collect();
    let skipped = mine.len() - todo.len();
    // The expected-longest first; results keep their slots, so the summary's order and
    // the names do not depend on it.
    let todo = order::longest_first(&mine, &todo);
    let summary_path = dir.join(summary_file_name(opts.shard));

    let ui = Ui::new(todo.len() as u64, opts.quiet);
    let mut notes: Vec<&String> = prepared.iter().flat_map(|p| &p.scenario.notes).collect();
    notes.sort();
    notes.dedup();
    for note in notes {
        ui.println(&format!("note: {note}"));
    }
    if replaced {
        ui.println(&format!(
            "note: {} described a different sweep; it now describes this one",
            dir.join(plan::PLAN_FILE).display()
        ));
    }
    let shard_note = if opts.shard.is_partial() {
        format!(", shard {} ({} runs)", opts.shard, mine.len())
    } else {
        String::new()
    };
    ui.println(&format!(
        "sweep {}: {} runs{shard_note}, {} already done, running {} with {jobs} job(s) into {}",
        spec.path.display(),
        prepared.len(),
        skipped,
        todo.len(),
        dir.display()
    ));

    let mut records = done;
    execute(
        &pool,
        jobs,
        &mine,
        &todo,
        &mut records,
        &dir,
        &axes,
        &summary_path,
        &ui,
        opts.force,
    );
    ui.done();

    let rows: Vec<Row> = mine
        .iter()
        .zip(records)
        .map(|(p, r)| row_for(p, r, "not run"))
        .collect();
    write_summary(&summary_path, &axes, &rows)?;
    Ok(SweepReport {
        dir,
        axes,
        rows,
        summary: summary_path,
        ran: todo.len(),
        skipped,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

/// Rebuilds `DIR/summary.csv` from `DIR/sweep-plan.toml` and the result files.
pub fn merge(dir: &Path) -> Result<SweepReport, SweepError> {
    let started = Instant::now();
    let plan = Plan::read(dir).map_err(SweepError::Input)?;
    let rows: Vec<Row> = plan
        .runs
        .iter()
        .map(|r| {
            let (record, note) = match record::read(dir, &r.name) {
                Ok(Some(rec)) if rec.scenario_hash == r.scenario_hash => (Some(rec), String::new()),
                Ok(Some(_)) => (
                    None,
                    "stale: its result is from a different scenario; run the sweep again"
                        .to_string(),
                ),
                Ok(None) => (None, "missing".to_string()),
                Err(e) => (None, format!("unreadable: {e}")),
            };
            Row {
                index: r.index,
                name: r.name.clone(),
                values: r.values.clone(),
                record,
                note,
            }
        })
        .collect();
    let path = dir.join(SUMMARY_FILE);
    write_summary(&path, &plan.axes, &rows)?;
    Ok(SweepReport {
        dir: dir.to_path_buf(),
        axes: plan.axes,
        rows,
        summary: path,
        ran: 0,
        skipped: 0,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

fn finish(report: &SweepReport, quiet: bool, merged: bool) -> u8 {
    let failed = report.failed();
    if !quiet {
        print_out(&report.table());
        let counts = if merged {
            format!("{} runs", report.rows.len())
        } else {
            format!(
                "{} runs ({} run now, {} already done)",
                report.rows.len(),
                report.ran,
                report.skipped
            )
        };
        print_out(&format!(
            "{}: {counts}, {failed} not ok, {:.2} s; summary in {}\n",
            if merged { "merge" } else { "sweep" },
            report.wall_time_s,
            report.summary.display()
        ));
    }
    if failed > 0 {
        print_err(&format!(
            "error: {failed} of {} runs did not complete (see the status column of {})\n",
            report.rows.len(),
            report.summary.display()
        ));
        EXIT_FAILURE
    } else {
        0
    }
}

/// `granflow sweep …`: returns the exit code.
pub fn main(args: &SweepArgs) -> u8 {
    crate::interrupt::install();
    let result = match &args.command {
        Some(SweepCommand::Merge(m)) => merge(&m.dir).map(|r| (r, m.quiet, true)),
        None => {
            let opts = SweepOptions {
                sweep: args.sweep.clone().expect("required by clap"),
                jobs: args.jobs.map_or_else(default_jobs, |j| j as usize),
                output: args.output.clone(),
                force: args.force,
                shard: args.shard.unwrap_or(Shard::ALL),
                set: args.set.clone(),
                quiet: args.quiet,
                wait: args.wait,
            };
            run(&opts).map(|r| (r, args.quiet, false))
        }
    };
    match result {
        Ok((report, _, _)) if crate::interrupt::requested() => {
            print_err(&format!(
                "granflow: sweep interrupted; finished runs and the summary so far are in {} (rerun the same command to resume)\n",
                report.dir.display()
            ));
            crate::interrupt::EXIT_INTERRUPTED
        }
        Ok((report, quiet, merged)) => finish(&report, quiet, merged),
        Err(e) => {
            print_err(&format!("error: {e}\n"));
            e.exit_code()
        }
    }
}
