//! Running one scenario to its output files: the piece shared by `granflow run` and
//! the sweep workers. It owns no global state, so runs can execute in parallel.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::output::csv::front_csv_path;
use crate::output::{create_run_sinks, OutputError, RunSummary};
use crate::scenario::Scenario;
use crate::setup::{build, Run};
use crate::simulation::{Progress, RunError};

/// Why a run did not produce a complete result.
#[derive(Debug, thiserror::Error)]
pub enum RunFailure {
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The solver stopped (NaN, negative thickness): the files hold what was valid.
    #[error("{error} (partial results in {path})")]
    Run { error: RunError, path: PathBuf },
}

/// What a finished run reports.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub summary: RunSummary,
    pub h5: PathBuf,
    pub front_csv: PathBuf,
    /// The gauge series, when the run has gauges.
    pub gauge_csv: Option<PathBuf>,
}

/// Builds the run without executing it (`granflow check`).
pub fn check(scn: &Scenario) -> Box<dyn Run> {
    build(scn)
}

/// Runs `scn`, writing the HDF5 file `h5` and its `_front.csv` companion.
pub fn run_to_files(
    scn: &Scenario,
    h5: &Path,
    progress: &mut dyn FnMut(Progress),
) -> Result<RunReport, RunFailure> {
    let mut sim = build(scn);
    let front_csv = front_csv_path(h5);
    let mut sink = create_run_sinks(h5)?;
    match sim.run(&mut sink, progress) {
        Ok(summary) => Ok(RunReport {
            summary,
            h5: h5.to_path_buf(),
            front_csv,
            gauge_csv: sink.b.b.path().map(Path::to_path_buf),
        }),
        Err(RunError::Output(e)) => Err(RunFailure::Output(e)),
        Err(error) => Err(RunFailure::Run {
            error,
            path: h5.to_path_buf(),
        }),
    }
}

impl fmt::Display for RunReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        writeln!(
            f,
            "granflow: {} at t = {:.4} s after {} steps ({:.3} s wall)",
            s.status, s.t_end, s.steps, s.wall_time_s
        )?;
        writeln!(f, "  runout        {:.4} m", s.runout)?;
        if s.stop_time.is_nan() {
            writeln!(f, "  stop time     not at rest")?;
        } else {
            writeln!(f, "  stop time     {:.4} s", s.stop_time)?;
        }
        writeln!(f, "  h_max final   {:.4} m", s.h_max_final)?;
        if let Some(a) = s.max_wave_amplitude {
            writeln!(f, "  max wave      {a:.4} m")?;
        }
        let stages: Vec<String> = s
            .stage_times
            .iter()
            .map(|(name, t)| format!("{name} {t:.3} s"))
            .collect();
        writeln!(f, "  stage times   {}", stages.join(", "))?;
        write!(
            f,
            "  output        {}, {}",
            self.h5.display(),
            self.front_csv.display()
        )?;
        match &self.gauge_csv {
            Some(g) => writeln!(f, ", {}", g.display()),
            None => writeln!(f),
        }
    }
}
