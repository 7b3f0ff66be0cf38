//! Progress of one `granflow run` on stderr: a bar on a terminal, plain lines every few
//! seconds in a pipe or a batch log, and a warning near the start when the run will
//! clearly take very long.
//!
//! The cost estimate is the pace of the first steps extrapolated to `t_end`:
//! wall ≈ elapsed · t_end / t, i.e. (estimated steps t_end/Δt̄) × (cost per step). It is
//! an upper bound for runs that stop at rest, and a lower bound when the flow speeds up
//! (the CFL step shrinks), so it only warns when the estimate is far above the limit.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::ProgressMode;
use crate::simulation::Progress;

/// A run whose estimate exceeds this many seconds gets a warning.
pub const LONG_RUN_S: f64 = 1800.0;
/// The estimate is made once this much wall time has passed…
const ESTIMATE_AFTER_S: f64 = 1.0;
/// …or after this many steps, whichever comes first.
const ESTIMATE_AFTER_STEPS: u64 = 200;

enum Display {
    Bar(ProgressBar),
    Lines { every: Duration, last: Instant },
    Hidden,
}

/// The progress display of one run.
pub struct RunProgress {
    display: Display,
    start: Instant,
    cells: usize,
    estimated: bool,
    last_draw: u64,
}

impl RunProgress {
    /// `quiet` hides the display (not the long-run warning); `every_s` is the interval of
    /// progress lines; `cells` only goes into the warning.
    pub fn new(mode: ProgressMode, quiet: bool, every_s: f64, cells: usize) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let now = Instant::now();
        let lines = || Display::Lines {
            every: Duration::from_secs_f64(every_s.max(0.0)),
            last: now,
        };
        let display = match (quiet, mode) {
            (true, _) | (_, ProgressMode::None) => Display::Hidden,
            (_, ProgressMode::Bar) => Display::Bar(bar()),
            (_, ProgressMode::Lines) => lines(),
            (_, ProgressMode::Auto) if terminal => Display::Bar(bar()),
            (_, ProgressMode::Auto) => lines(),
        };
        RunProgress {
            display,
            start: now,
            cells,
            estimated: false,
            last_draw: 0,
        }
    }

    /// Called after every time step.
    pub fn update(&mut self, p: &Progress) {
        let elapsed = self.start.elapsed().as_secs_f64();
        if !self.estimated && (elapsed >= ESTIMATE_AFTER_S || p.steps >= ESTIMATE_AFTER_STEPS) {
            self.estimated = true;
            if let Some(w) = long_run_warning(elapsed, p, self.cells) {
                match &self.display {
                    Display::Bar(bar) => bar.suspend(|| eprintln!("{w}")),
                    _ => eprintln!("{w}"),
                }
            }
        }
        match &mut self.display {
            Display::Bar(bar) => {
                // Touch the bar every 64 steps: cheap, and smooth enough for a human.
                if p.steps - self.last_draw >= 64 {
                    self.last_draw = p.steps;
                    bar.set_position((1000.0 * p.t / p.t_end) as u64);
                    bar.set_message(format!(
                        "t = {:.4} s / {} s, {} steps",
                        p.t, p.t_end, p.steps
                    ));
                }
            }
            Display::Lines { every, last } => {
                let now = Instant::now();
                if now.duration_since(*last) >= *every {
                    *last = now;
                    eprintln!("{}", progress_line(elapsed, p));
                }
            }
            Display::Hidden => {}
        }
    }

    /// Removes the bar (lines stay in the log).
    pub fn finish(self) {
        if let Display::Bar(bar) = self.display {
            bar.finish_and_clear();
        }
    }
}

fn bar() -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{bar:40.cyan/blue} {msg} [{elapsed_precise}, ETA {eta}]")
            .expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// Wall time still needed to reach `t_end` at the pace so far (None before any progress).
pub fn remaining_s(elapsed_s: f64, p: &Progress) -> Option<f64> {
    (p.t > 0.0 && p.t_end > p.t).then(|| elapsed_s * (p.t_end - p.t) / p.t)
}

/// One line for a log: simulated time, steps, elapsed and remaining wall time.
pub fn progress_line(elapsed_s: f64, p: &Progress) -> String {
    let left = remaining_s(elapsed_s, p)
        .map(|r| format!(", about {} to t_end", hms(r)))
        .unwrap_or_default();
    format!(
        "granflow: t = {:.4} s of {} s ({:.1} %), {} steps, {} elapsed{left}",
        p.t,
        p.t_end,
        100.0 * p.t / p.t_end,
        p.steps,
        hms(elapsed_s)
    )
}

/// The warning for a run whose pace so far puts it beyond [`LONG_RUN_S`].
pub fn long_run_warning(elapsed_s: f64, p: &Progress, cells: usize) -> Option<String> {
    let total = elapsed_s + remaining_s(elapsed_s, p)?;
    (total > LONG_RUN_S).then(|| {
        let dt = p.t / p.steps.max(1) as f64;
        format!(
            "warning: this run will take about {} ({cells} cells, Δt ≈ {dt:.3e} s so about \
             {:.3e} steps to t_end = {} s, {:.3e} s per step so far); \
             a coarser grid (--set domain.cells=…) or a shorter time (--set time.t_end=…) \
             is much cheaper",
            hms(total),
            p.t_end / dt,
            p.t_end,
            elapsed_s / p.steps.max(1) as f64,
        )
    })
}

/// `1:02:03`, or `2 d 03:04:05` beyond a day.
fn hms(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    let (d, h, m, sec) = (s / 86400, s / 3600 % 24, s / 60 % 60, s % 60);
    if d > 0 {
        format!("{d} d {h:02}:{m:02}:{sec:02}")
    } else {
        format!("{h}:{m:02}:{sec:02}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(t: f64, t_end: f64, steps: u64) -> Progress {
        Progress { t, t_end, steps }
    }

    #[test]
    fn remaining_extrapolates_the_pace() {
        // 2 s of wall time for the first 10 % of the run: 18 s more.
        assert_eq!(remaining_s(2.0, &p(1.0, 10.0, 5)), Some(18.0));
        assert_eq!(remaining_s(2.0, &p(0.0, 10.0, 0)), None);
    }

    #[test]
    fn warns_only_beyond_the_limit() {
        // 5 million cells: 4 steps of Δt = 1e-5 s took 2 s; 10 s need 1e6 steps of
        // 0.5 s, 5e5 s = 5 d 18:53:20.
        let w = long_run_warning(2.0, &p(4e-5, 10.0, 4), 5_000_000).unwrap();
        assert!(w.contains("5 d 18:53:20"), "{w}");
        assert!(
            w.contains("5000000 cells") && w.contains("1.000e6 steps"),
            "{w}"
        );
        assert_eq!(long_run_warning(1.0, &p(0.1, 10.0, 100), 640), None);
    }

    #[test]
    fn a_line_says_where_the_run_is() {
        let l = progress_line(65.0, &p(2.5, 10.0, 1234));
        assert_eq!(
            l,
            "granflow: t = 2.5000 s of 10 s (25.0 %), 1234 steps, 0:01:05 elapsed, \
             about 0:03:15 to t_end"
        );
    }
}
