//! Running one scenario to its output files: the piece shared by `granflow run` and
//! the sweep workers. It owns no global state, so runs can execute in parallel.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::output::budget::{Budgeted, OUTPUT_LIMIT};
use crate::output::csv::front_csv_path;
pub use crate::output::stop_reason::sig;
use crate::output::stop_reason::stop_reason;
use crate::output::{create_run_sinks, OutputError, RunSummary};
use crate::scenario::Scenario;
use crate::setup::{build, build_threads, Run};
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
    /// The XDMF description of the HDF5 file (ParaView, VisIt), written for raster
    /// runs.
    pub xmf: Option<PathBuf>,
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
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<RunReport, RunFailure> {
    run_to_files_within(scn, h5, Some(OUTPUT_LIMIT), progress)
}

/// [`run_to_files`] with the output limit `limit` in bytes (`None`: no limit).
pub fn run_to_files_within(
    scn: &Scenario,
    h5: &Path,
    limit: Option<u64>,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<RunReport, RunFailure> {
    run_to_files_threads(scn, h5, limit, 1, progress)
}

/// [`run_to_files_within`] on `threads` threads (raster runs; a line runs on one).
pub fn run_to_files_threads(
    scn: &Scenario,
    h5: &Path,
    limit: Option<u64>,
    threads: usize,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<RunReport, RunFailure> {
    let mut sim = build_threads(scn, threads);
    let front_csv = front_csv_path(h5);
    let mut sink = Budgeted::new(create_run_sinks(h5)?, limit, h5).watching_pace(scn.time.t_end);
    match sim.run(&mut sink, progress) {
        Ok(summary) => Ok(RunReport {
            summary,
            h5: h5.to_path_buf(),
            front_csv,
            gauge_csv: sink.inner.b.b.path().map(Path::to_path_buf),
            xmf: Some(crate::output::xdmf::xdmf_path(h5))
                .filter(|x| scn.domain.plane.is_some() && x.is_file()),
        }),
        Err(RunError::Output(e)) => Err(RunFailure::Output(e)),
        Err(error) => Err(RunFailure::Run {
            error,
            path: h5.to_path_buf(),
        }),
    }
}

/// Outflow above this fraction of the initial mass is warned about.
pub const OUTFLOW_WARNING_FRACTION: f64 = 0.01;

/// Outflow below this fraction of the initial mass is round-off (or a film of 1e-10 m
/// at the boundary) and is not reported.
const ROUND_OFF_FRACTION: f64 = 1e-9;

impl RunReport {
    /// The report's first line: the status, its one time and why the run ended there
    /// ([`stop_reason`], also `/summary` `stop_reason`).
    pub fn status_line(&self) -> String {
        let s = &self.summary;
        let why = stop_reason(s);
        let sep = if why.is_empty() { "" } else { ": " };
        format!("granflow: {} at t = {} s{sep}{why}", s.status, sig(s.t_end))
    }

    /// Warnings on the result: mass lost through outflow boundaries, a front that
    /// reached the end of the domain (its runout is then the domain's). One per line.
    pub fn warnings(&self) -> Vec<String> {
        let s = &self.summary;
        let mut out = Vec::new();
        if s.outflowed_fraction > OUTFLOW_WARNING_FRACTION && s.status != "outflowed" {
            out.push(format!(
                "warning: {} % of the initial mass left the domain through an outflow boundary; the deposit and the runout are those of what stayed",
                pct(s.outflowed_fraction)
            ));
        }
        if !s.front_at_end_time.is_nan() && s.status != "outflowed" {
            out.push(format!(
                "warning: the front reached the end of the domain at t = {} s: the runout is bounded by the domain, extend domain.x_max",
                sig(s.front_at_end_time)
            ));
        }
        out
    }
}

/// A fraction as a percentage with at most 3 significant digits (`76.7`, `0.0123`).
fn pct(f: f64) -> String {
    let p = 100.0 * f;
    if p == 0.0 || !p.is_finite() {
        return format!("{p}");
    }
    let decimals = (2 - p.abs().log10().floor() as i32).max(0) as usize;
    format!("{p:.decimals$}")
}

impl fmt::Display for RunReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        writeln!(f, "{}", self.status_line())?;
        writeln!(
            f,
            "  steps         {} ({} s wall)",
            s.steps,
            sig(s.wall_time_s)
        )?;
        if let Some(w) = &s.wet {
            writeln!(
                f,
                "  wet cells     {} % of {} on average, {} % at most; {:.3e} wet-cell updates/s ({:.3e} on the cells stepped)",
                pct(w.mean_fraction),
                w.flow_cells,
                pct(w.peak_fraction),
                w.wet_updates_per_s,
                w.cell_updates_per_s
            )?;
        }
        match (s.status.as_str(), s.spread) {
            ("no_mass", _) => {
                writeln!(f, "  runout        none (the initial state holds no mass)")?
            }
            ("outflowed", _) => writeln!(
                f,
                "  runout        none (all the mass left through an outflow boundary)"
            )?,
            // A raster run: the runout along the flow (not the front's advance in x).
            (_, Some(sp)) => {
                if sp.runout_length.is_nan() {
                    writeln!(f, "  runout        none (no cell reached)")?;
                } else {
                    writeln!(
                        f,
                        "  runout        {} m along the flow from the top of the release, travel angle {}°",
                        sig(sp.runout_length),
                        sig(sp.travel_angle_deg)
                    )?;
                }
                writeln!(f, "  area reached  {} m²", sig(sp.area_reached))?;
                match (sp.path_runout_length, sp.path_runout_angle_deg) {
                    (Some(l), Some(a)) if l.is_finite() => writeln!(
                        f,
                        "  path runout   {} m along output.path from the top of the release, runout angle {}°",
                        sig(l),
                        sig(a)
                    )?,
                    (Some(_), _) => writeln!(
                        f,
                        "  path runout   none (no cell over the threshold of output.path)"
                    )?,
                    (None, _) => {}
                }
                if let Some([pft, pfv, ppr]) = sp.path_max {
                    writeln!(
                        f,
                        "  path maxima   pft {} m, pfv {} m/s, ppr {} kPa (largest along output.path, /path in the HDF5 file)",
                        sig(pft),
                        sig(pfv),
                        sig(ppr / 1000.0)
                    )?;
                }
            }
            _ if s.runout.is_nan() => writeln!(f, "  runout        none (no front)")?,
            // Wet or periodic domains have no front that moves: say so rather than
            // print a runout of "0.0000 m" as if it were measured.
            _ if s.runout == 0.0 => writeln!(f, "  runout        0 m (the front did not move)")?,
            _ if !s.front_at_end_time.is_nan() => writeln!(
                f,
                "  runout        {} m (at least: the front reached the end of the domain at t = {} s)",
                sig(s.runout),
                sig(s.front_at_end_time)
            )?,
            _ => writeln!(f, "  runout        {} m", sig(s.runout))?,
        }
        writeln!(f, "  h_max final   {} m", sig(s.h_max_final))?;
        if s.outflowed_fraction > ROUND_OFF_FRACTION {
            writeln!(
                f,
                "  outflowed     {} % of the initial mass",
                pct(s.outflowed_fraction)
            )?;
        }
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
        if let Some(g) = &self.gauge_csv {
            write!(f, ", {}", g.display())?;
        }
        match &self.xmf {
            Some(x) => writeln!(f, ", {} (for ParaView)", x.display()),
            None => writeln!(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(status: &str, stop: f64, settled: f64, speed: f64) -> RunReport {
        let mut summary = RunSummary::not_run(status.to_owned(), 0.5);
        summary.t_end = 2.0;
        summary.steps = 196;
        summary.runout = 0.0;
        summary.h_max_final = 0.6;
        summary.stop_time = stop;
        summary.settled_time = settled;
        summary.max_speed_final = speed;
        summary.outflowed_fraction = 0.0;
        RunReport {
            summary,
            h5: "run.h5".into(),
            front_csv: "run_front.csv".into(),
            gauge_csv: None,
            xmf: None,
        }
    }

    /// One status line with one time and the reason; no line contradicting it.
    #[test]
    fn the_report_says_one_status_with_its_time_and_reason() {
        let lake = report("completed", f64::NAN, f64::NAN, 3.2e-15).to_string();
        let first = lake.lines().next().unwrap();
        assert!(
            first.starts_with("granflow: completed at t = 2.000 s: reached time.t_end")
                && first.contains("at rest to round-off"),
            "{lake}"
        );
        let settled = report("settled", f64::NAN, 1.949, 0.016).to_string();
        assert!(
            settled.starts_with("granflow: settled at t = 2.000 s: the kinetic energy fell"),
            "{settled}"
        );
        let moving = report("completed", f64::NAN, f64::NAN, 0.3).to_string();
        assert!(
            moving.contains("still moving (largest speed 0.3000 m/s)"),
            "{moving}"
        );
        let rest = report("completed", 1.25, 1.0, 0.0).to_string();
        assert!(rest.contains("at rest since t = 1.250 s"), "{rest}");
        for text in [lake, settled, moving, rest] {
            assert!(
                !text.contains("not at rest") && !text.contains("not settled"),
                "{text}"
            );
            assert_eq!(text.matches(" at t = ").count(), 1, "{text}");
        }
    }

    /// The reason names the fraction of the peak kinetic energy the run stopped at (or
    /// settled below), the interruption or the failure.
    #[test]
    fn the_report_says_why_the_run_stopped() {
        let mut settled = report("settled", f64::NAN, 1.949, 0.016);
        settled.summary.settle_fraction = 0.01;
        assert_eq!(
            settled.status_line(),
            "granflow: settled at t = 2.000 s: the kinetic energy fell to 0.01 × its peak \
             (time.settle_fraction, time.stop_when_settled); largest speed 0.01600 m/s"
        );
        let mut completed = report("completed", f64::NAN, 1.949, 0.016);
        completed.summary.settle_fraction = 1e-6;
        assert_eq!(
            completed.status_line(),
            "granflow: completed at t = 2.000 s: reached time.t_end; settled since t = 1.949 s \
             (kinetic energy at most 1e-6 × its peak, time.settle_fraction), largest speed \
             0.01600 m/s"
        );
        let interrupted = report("interrupted", f64::NAN, f64::NAN, 0.3);
        assert_eq!(
            interrupted.status_line(),
            "granflow: interrupted at t = 2.000 s: stopped by Ctrl-C or SIGTERM; still moving \
             (largest speed 0.3000 m/s)"
        );
        let failed = report("failed: time step collapsed", f64::NAN, f64::NAN, 0.3);
        assert_eq!(
            stop_reason(&failed.summary),
            "time step collapsed",
            "the reason of a failure is the failure's"
        );
    }

    #[test]
    fn outflow_and_a_front_at_the_domain_end_are_reported() {
        let mut r = report("stopped_at_rest", 1.5, 1.0, 0.0);
        r.summary.runout = 1700.0;
        r.summary.outflowed_fraction = 0.767;
        r.summary.front_at_end_time = 41.0;
        let text = r.to_string();
        assert!(
            text.contains("outflowed     76.7 % of the initial mass"),
            "{text}"
        );
        assert!(
            text.contains(
                "1700 m (at least: the front reached the end of the domain at t = 41.00 s)"
            ),
            "{text}"
        );
        let w = r.warnings();
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].contains("76.7 % of the initial mass left the domain"),
            "{w:?}"
        );
        // Below 1 %: reported, not warned about; round-off: neither.
        r.summary.outflowed_fraction = 0.005;
        r.summary.front_at_end_time = f64::NAN;
        assert!(r.warnings().is_empty());
        assert!(r.to_string().contains("outflowed     0.500 %"));
        r.summary.outflowed_fraction = 1e-16;
        assert!(!r.to_string().contains("outflowed"));
    }

    /// A raster run's report says where its time went: 2 % of its cells wet on average.
    #[test]
    fn the_report_says_the_wet_fraction_and_the_rate_on_wet_cells() {
        let mut r = report("completed", f64::NAN, f64::NAN, 0.3);
        assert!(!r.to_string().contains("wet cells"));
        r.summary.wet = Some(crate::output::WetCells {
            flow_cells: 40_000,
            mean_fraction: 0.0213,
            peak_fraction: 0.045,
            wet_updates_per_s: 1.5e6,
            cell_updates_per_s: 7.04e7,
        });
        let text = r.to_string();
        assert!(
            text.contains(
                "  wet cells     2.13 % of 40000 on average, 4.50 % at most; 1.500e6 \
                 wet-cell updates/s (7.040e7 on the cells stepped)"
            ),
            "{text}"
        );
    }

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
