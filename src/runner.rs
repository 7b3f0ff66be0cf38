//! Running one scenario to its output files: the piece shared by `granflow run` and
//! the sweep workers. It owns no global state, so runs can execute in parallel.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::output::budget::{Budgeted, OUTPUT_LIMIT};
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

/// Runs `scn`, writing the HDF5 file `h5` and its `_front.csv` companion, within the
/// output limit ([`OUTPUT_LIMIT`]).
pub fn run_to_files(
    scn: &Scenario,
    h5: &Path,
    progress: &mut dyn FnMut(Progress),
) -> Result<RunReport, RunFailure> {
    run_to_files_within(scn, h5, Some(OUTPUT_LIMIT), progress)
}

/// [`run_to_files`] with the output limit `limit` in bytes (`None`: no limit).
pub fn run_to_files_within(
    scn: &Scenario,
    h5: &Path,
    limit: Option<u64>,
    progress: &mut dyn FnMut(Progress),
) -> Result<RunReport, RunFailure> {
    let mut sim = build(scn);
    let front_csv = front_csv_path(h5);
    let mut sink = Budgeted::new(create_run_sinks(h5)?, limit, h5);
    match sim.run(&mut sink, progress) {
        Ok(summary) => Ok(RunReport {
            summary,
            h5: h5.to_path_buf(),
            front_csv,
            gauge_csv: sink.inner.b.b.path().map(Path::to_path_buf),
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
            "granflow: {} at t = {} s after {} steps ({} s wall)",
            s.status,
            sig(s.t_end),
            s.steps,
            sig(s.wall_time_s)
        )?;
        match s.status.as_str() {
            "no_mass" => writeln!(f, "  runout        none (the initial state holds no mass)")?,
            "outflowed" => writeln!(
                f,
                "  runout        none (all the mass left through an outflow boundary)"
            )?,
            _ if s.runout.is_nan() => writeln!(f, "  runout        none (no front)")?,
            // Wet or periodic domains have no front that moves: say so rather than
            // print a runout of "0.0000 m" as if it were measured.
            _ if s.runout == 0.0 => writeln!(f, "  runout        0 m (the front did not move)")?,
            _ => writeln!(f, "  runout        {} m", sig(s.runout))?,
        }
        if s.stop_time.is_nan() {
            writeln!(f, "  stop time     not at rest")?;
        } else {
            writeln!(f, "  stop time     {} s", sig(s.stop_time))?;
        }
        if s.settled_time.is_nan() {
            writeln!(f, "  settled       not settled")?;
        } else {
            writeln!(f, "  settled       {} s", sig(s.settled_time))?;
        }
        writeln!(f, "  h_max final   {} m", sig(s.h_max_final))?;
        if let Some(a) = s.max_wave_amplitude {
            writeln!(f, "  max wave      {} m", sig(a))?;
        }
        let stages: Vec<String> = s
            .stage_times
            .iter()
            .map(|(name, t)| format!("{name} {} s", sig(*t)))
            .collect();
        writeln!(f, "  stage times   {}", stages.join(", "))?;
        let what = if s.status == "interrupted" {
            "partial results"
        } else {
            "output"
        };
        write!(
            f,
            "  {what:<13} {}, {}",
            self.h5.display(),
            self.front_csv.display()
        )?;
        match &self.gauge_csv {
            Some(g) => writeln!(f, ", {}", g.display()),
            None => writeln!(f),
        }
    }
}

/// `v` with four significant digits: plain decimals between 1e-3 and 1e5, exponent
/// form outside (so t_end = 1e-5 s is not printed as 0.0000).
pub fn sig(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_owned();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::sig;

    #[test]
    fn four_significant_digits() {
        assert_eq!(sig(1e-5), "1.000e-5");
        assert_eq!(sig(1.89), "1.890");
        assert_eq!(sig(0.0123456), "0.01235");
        assert_eq!(sig(2.65), "2.650");
        assert_eq!(sig(1234.5678), "1235");
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(-0.5), "-0.5000");
        assert_eq!(sig(3.2e7), "3.200e7");
        assert_eq!(sig(f64::NAN), "NaN");
    }
}
