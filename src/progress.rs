//! Progress of one `granflow run` on stderr: a bar on a terminal, plain lines every few
//! seconds in a pipe or a batch log, and a warning near the start when the run will
//! clearly take very long.
//!
//! The cost estimate is the pace of the first steps extrapolated to `t_end`:
//! remaining wall ≈ (t_end − t) · Δwall/Δt over the steps after the first one (the
//! first step also pays for the initial snapshot, 10× a step on a large grid), i.e.
//! (estimated steps t_end/Δt̄) × (cost per step). It overestimates runs that stop at
//! rest and underestimates flows that speed up (the CFL step shrinks), so it only
//! warns when the estimate is far above the limit.
//!
//! A single slow step (a fine multilayer non-hydrostatic grid, many sub-steps) does
//! not leave the display silent: a heartbeat thread ([`Heartbeat`]) says, every
//! progress interval, how long the current step has been running, and warns once when
//! one step alone runs past [`SLOW_STEP_S`], with what that pace means to t_end.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::ProgressMode;
use crate::simulation::Progress;

/// A run whose estimate exceeds this many seconds gets a warning.
pub const LONG_RUN_S: f64 = 1800.0;
/// The estimate is made once this much wall time has passed since the first step…
const ESTIMATE_AFTER_S: f64 = 1.0;
/// …or after this many steps, whichever comes first.
const ESTIMATE_AFTER_STEPS: u64 = 200;

enum Display {
    Bar(ProgressBar),
    Lines { every: Duration, last: Instant },
    Hidden,
}

/// The heartbeat speaks once no step has finished for this long (s), and at most
/// every progress interval.
pub const HEARTBEAT_AFTER_S: f64 = 5.0;

/// A step running longer than this (s) gets a warning from the heartbeat.
pub const SLOW_STEP_S: f64 = 60.0;

/// What the heartbeat thread shares with [`RunProgress::update`].
#[derive(Debug)]
struct Beat {
    /// When the last step ended (or the run started), and where the run was then.
    since: Instant,
    last: Progress,
    /// When the heartbeat last printed.
    printed: Instant,
    warned: bool,
    done: bool,
}

/// The heartbeat of a run: a thread that reports a step running for long.
pub struct Heartbeat {
    beat: Arc<Mutex<Beat>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Heartbeat {
    /// Starts the thread: with `lines`, a line every `every` while a step runs longer
    /// than that; always, the slow-step warning.
    fn start(every: Duration, lines: bool, bar: Option<ProgressBar>, t_end: f64) -> Heartbeat {
        let now = Instant::now();
        let beat = Arc::new(Mutex::new(Beat {
            since: now,
            last: Progress {
                t: 0.0,
                t_end,
                steps: 0,
                energy: f64::NAN,
                wet_cells: None,
                flow_cells: 0,
                wet_updates: f64::NAN,
            },
            printed: now,
            warned: false,
            done: false,
        }));
        let shared = Arc::clone(&beat);
        let every = every.max(Duration::from_millis(200));
        let thread = std::thread::Builder::new()
            .name("granflow-heartbeat".into())
            .spawn(move || loop {
                std::thread::sleep(Duration::from_millis(200));
                let mut b = shared.lock().unwrap_or_else(|e| e.into_inner());
                if b.done {
                    return;
                }
                let now = Instant::now();
                let running = now.duration_since(b.since).as_secs_f64();
                let mut out = Vec::new();
                if !b.warned && running >= SLOW_STEP_S {
                    b.warned = true;
                    out.push(slow_step_warning(running, &b.last));
                }
                let quiet_for = Duration::from_secs_f64(HEARTBEAT_AFTER_S).max(every);
                if lines
                    && now.duration_since(b.since) >= quiet_for
                    && now.duration_since(b.printed) >= quiet_for
                {
                    b.printed = now;
                    out.push(step_running_line(running, &b.last));
                }
                if let Some(bar) = &bar {
                    if running >= HEARTBEAT_AFTER_S {
                        bar.set_message(step_running_line(running, &b.last));
                    }
                }
                drop(b);
                for line in out {
                    match &bar {
                        Some(bar) => {
                            bar.suspend(|| crate::terminal::print_err(&format!("{line}\n")))
                        }
                        None => crate::terminal::print_err(&format!("{line}\n")),
                    }
                }
            })
            .ok();
        Heartbeat { beat, thread }
    }

    /// A step ended at `p`.
    fn beat(&self, p: &Progress, printed: bool) {
        let mut b = self.beat.lock().unwrap_or_else(|e| e.into_inner());
        b.since = Instant::now();
        b.last = *p;
        if printed {
            b.printed = b.since;
        }
    }

    fn stop(&mut self) {
        self.beat.lock().unwrap_or_else(|e| e.into_inner()).done = true;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The heartbeat's line when no step has finished for `running_s` since `last` (step
/// `last.steps + 1` is running, or the output is being finished).
pub fn step_running_line(running_s: f64, last: &Progress) -> String {
    if !last.t_end.is_finite() {
        return format!(
            "granflow: t = 0 s, {} steps, no step finished for {}",
            last.steps,
            hms(running_s)
        );
    }
    format!(
        "granflow: t = {:.4e} s of {} s ({:.1} %), {} steps, no step finished for {}",
        last.t,
        last.t_end,
        100.0 * last.t / last.t_end,
        last.steps,
        hms(running_s)
    )
}

/// The warning for one step running `running_s`: with the mean Δt of the steps so
/// far, what that pace per step means to t_end.
pub fn slow_step_warning(running_s: f64, last: &Progress) -> String {
    let pace = if last.steps > 0 && last.t > 0.0 {
        let steps_left = (last.t_end - last.t) / (last.t / last.steps as f64);
        format!(
            "; at that pace the {:.3e} steps to t_end = {} s take about {}",
            steps_left,
            last.t_end,
            hms(steps_left * running_s)
        )
    } else {
        String::new()
    };
    format!(
        "warning: step {} has been running for {}{pace}; a coarser grid (--set domain.cells=…) \
         is much cheaper, and Ctrl-C stops the run after this step",
        last.steps + 1,
        hms(running_s)
    )
}

/// The progress display of one run.
pub struct RunProgress {
    heartbeat: Option<Heartbeat>,
    display: Display,
    start: Instant,
    /// Wall clock, time and steps at the first step: the pace is measured from there.
    first: Option<(Instant, Progress)>,
    cells: usize,
    estimated: bool,
    last_draw: u64,
    /// `time.settle_fraction` when the run ends once settled (`time.stop_when_settled`):
    /// the time left to t_end is then a bound, not an estimate.
    settle: Option<f64>,
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
        let heartbeat = match &display {
            Display::Bar(bar) => Some(Heartbeat::start(
                Duration::from_secs_f64(every_s.max(0.0)),
                false,
                Some(bar.clone()),
                f64::NAN,
            )),
            Display::Lines { every, .. } => Some(Heartbeat::start(*every, true, None, f64::NAN)),
            Display::Hidden => Some(Heartbeat::start(Duration::MAX, false, None, f64::NAN)),
        };
        RunProgress {
            heartbeat,
            display,
            start: now,
            first: None,
            cells,
            estimated: false,
            last_draw: 0,
            settle: None,
        }
    }

    /// For a run that ends once its kinetic energy falls to `fraction` of its peak
    /// (`time.stop_when_settled`; `None` otherwise): the display says that the time
    /// to t_end is at most that, and how near the run is to settling.
    pub fn with_settle(mut self, fraction: Option<f64>) -> Self {
        self.settle = fraction;
        if let (Some(_), Display::Bar(bar)) = (fraction, &self.display) {
            bar.set_style(bar_style("at most {eta} to t_end"));
        }
        self
    }

    /// Called after every time step.
    pub fn update(&mut self, p: &Progress) {
        let now = Instant::now();
        let elapsed = now.duration_since(self.start).as_secs_f64();
        let (t0, p0) = *self.first.get_or_insert((now, *p));
        // The pace since the first step, once there is one; until then, since the start.
        let pace = if p.t > p0.t {
            Pace {
                wall_s: now.duration_since(t0).as_secs_f64(),
                sim_s: p.t - p0.t,
                steps: p.steps - p0.steps,
                wet_updates: p.wet_updates - p0.wet_updates,
            }
        } else {
            Pace {
                wall_s: elapsed,
                sim_s: p.t,
                steps: p.steps,
                wet_updates: p.wet_updates,
            }
        };
        if !self.estimated
            && ((pace.wall_s >= ESTIMATE_AFTER_S && p.t > p0.t) || p.steps >= ESTIMATE_AFTER_STEPS)
        {
            self.estimated = true;
            if let Some(w) = long_run_warning(elapsed, &pace, p, self.cells) {
                match &self.display {
                    Display::Bar(bar) => {
                        bar.suspend(|| crate::terminal::print_err(&format!("{w}\n")))
                    }
                    _ => crate::terminal::print_err(&format!("{w}\n")),
                }
            }
        }
        let mut printed = false;
        match &mut self.display {
            Display::Bar(bar) => {
                // Touch the bar every 64 steps: cheap, and smooth enough for a human.
                if p.steps - self.last_draw >= 64 {
                    self.last_draw = p.steps;
                    bar.set_position((1000.0 * p.t / p.t_end) as u64);
                    let wet = p
                        .wet_cells
                        .map(|w| format!(", wet {} %", percent(w as f64 / p.flow_cells as f64)))
                        .unwrap_or_default();
                    bar.set_message(format!(
                        "t = {:.4} s / {} s, {} steps{wet}{}",
                        p.t,
                        p.t_end,
                        p.steps,
                        settle_note(p, self.settle)
                    ));
                }
            }
            Display::Lines { every, last } => {
                let now = Instant::now();
                if now.duration_since(*last) >= *every {
                    *last = now;
                    printed = true;
                    let line = progress_line(elapsed, &pace, p, self.settle);
                    crate::terminal::print_err(&format!("{line}\n"));
                }
            }
            Display::Hidden => {}
        }
        if let Some(h) = &self.heartbeat {
            h.beat(p, printed);
        }
    }

    /// Removes the bar (lines stay in the log).
    pub fn finish(mut self) {
        if let Some(mut h) = self.heartbeat.take() {
            h.stop();
        }
        if let Display::Bar(bar) = self.display {
            bar.finish_and_clear();
        }
    }
}

fn bar() -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
    bar.set_style(bar_style("ETA {eta}"));
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// The bar's style, `eta` saying what the time left is.
fn bar_style(eta: &str) -> ProgressStyle {
    ProgressStyle::with_template(&format!(
        "{{bar:40.cyan/blue}} {{msg}} [{{elapsed_precise}}, {eta}]"
    ))
    .expect("valid template")
}

/// How near a run that ends once settled is to its end: `, kinetic energy 3.2 % of
/// its peak (ends at 1 %)`; empty for a run without that end, or before any motion.
pub fn settle_note(p: &Progress, settle: Option<f64>) -> String {
    match settle {
        Some(f) if p.energy.is_finite() => format!(
            ", kinetic energy {} % of its peak (ends at {} %)",
            percent(p.energy),
            percent(f)
        ),
        _ => String::new(),
    }
}

/// A fraction as a percentage with 2 significant digits (`3.2`, `0.0001`).
fn percent(f: f64) -> String {
    let v = 100.0 * f;
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (1 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Wall time spent on `sim_s` of simulated time in `steps` steps.
#[derive(Debug, Clone, Copy)]
pub struct Pace {
    pub wall_s: f64,
    pub sim_s: f64,
    pub steps: u64,
    /// The wet-cell updates of those steps ([`Progress::wet_updates`]; NaN when the
    /// model does not count its wet cells).
    pub wet_updates: f64,
}

/// Where the time goes, for a model that counts its wet cells: `, wet 2.3 % of 400401
/// cells, 1.234e6 wet-cell updates/s` (the rate over `pace`); empty otherwise.
pub fn wet_note(pace: &Pace, p: &Progress) -> String {
    let Some(wet) = p.wet_cells else {
        return String::new();
    };
    let rate = if pace.wall_s > 0.0 && pace.steps > 0 && pace.wet_updates.is_finite() {
        format!(
            ", {:.3e} wet-cell updates/s",
            pace.wet_updates / pace.wall_s
        )
    } else {
        String::new()
    };
    format!(
        ", wet {} % of {} cells{rate}",
        percent(wet as f64 / p.flow_cells as f64),
        p.flow_cells
    )
}

/// Wall time still needed to reach `t_end` at `pace` (None before any progress).
pub fn remaining_s(pace: &Pace, p: &Progress) -> Option<f64> {
    (pace.sim_s > 0.0 && p.t_end > p.t).then(|| pace.wall_s * (p.t_end - p.t) / pace.sim_s)
}

/// One line for a log: simulated time, steps, elapsed and remaining wall time; for a
/// run that ends once settled (`settle`, the fraction), the time to t_end is a bound
/// and the line says how near the run is to settling.
pub fn progress_line(elapsed_s: f64, pace: &Pace, p: &Progress, settle: Option<f64>) -> String {
    let bound = if settle.is_some() { "at most" } else { "about" };
    let left = remaining_s(pace, p)
        .map(|r| format!(", {bound} {} to t_end", hms(r)))
        .unwrap_or_default();
    let note = settle_note(p, settle);
    let wet = wet_note(pace, p);
    let t = if p.t != 0.0 && p.t.abs() < 1e-2 {
        format!("{:.3e}", p.t)
    } else {
        format!("{:.4}", p.t)
    };
    format!(
        "granflow: t = {t} s of {} s ({:.1} %), {} steps, {} elapsed{left}{wet}{note}",
        p.t_end,
        100.0 * p.t / p.t_end,
        p.steps,
        hms(elapsed_s)
    )
}

/// The warning for a run whose pace puts it beyond [`LONG_RUN_S`] in all.
pub fn long_run_warning(elapsed_s: f64, pace: &Pace, p: &Progress, cells: usize) -> Option<String> {
    let total = elapsed_s + remaining_s(pace, p)?;
    (total > LONG_RUN_S).then(|| {
        let steps = pace.steps.max(1) as f64;
        let dt = pace.sim_s / steps;
        format!(
            "warning: this run will take about {} ({cells} cells, Δt ≈ {dt:.3e} s so about \
             {:.3e} steps to t_end = {} s, {:.3e} s per step); \
             a coarser grid (--set domain.cells=…) or a shorter time (--set time.t_end=…) \
             is much cheaper",
            hms(total),
            p.t_end / dt,
            p.t_end,
            pace.wall_s / steps,
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
        Progress {
            t,
            t_end,
            steps,
            energy: f64::NAN,
            wet_cells: None,
            flow_cells: 0,
            wet_updates: f64::NAN,
        }
    }

    fn pace(wall_s: f64, sim_s: f64, steps: u64) -> Pace {
        Pace {
            wall_s,
            sim_s,
            steps,
            wet_updates: f64::NAN,
        }
    }

    #[test]
    fn remaining_extrapolates_the_pace() {
        // 2 s of wall time for 1 s of the 10 s run, 9 s left: 18 s more.
        assert_eq!(
            remaining_s(&pace(2.0, 1.0, 5), &p(1.0, 10.0, 5)),
            Some(18.0)
        );
        assert_eq!(remaining_s(&pace(2.0, 0.0, 0), &p(0.0, 10.0, 0)), None);
    }

    #[test]
    fn warns_only_beyond_the_limit() {
        // 5 million cells: 4 steps of Δt = 1e-5 s took 2 s; 10 s need 1e6 steps of
        // 0.5 s, 5e5 s = 5 d 18:53:20 (plus the 3 s already spent).
        let w = long_run_warning(3.0, &pace(2.0, 4e-5, 4), &p(5e-5, 10.0, 5), 5_000_000).unwrap();
        assert!(w.contains("5 d 18:53:"), "{w}");
        assert!(
            w.contains("5000000 cells") && w.contains("1.000e6 steps"),
            "{w}"
        );
        let short = long_run_warning(1.0, &pace(1.0, 0.1, 100), &p(0.1, 10.0, 100), 640);
        assert_eq!(short, None);
    }

    #[test]
    fn a_slow_step_is_reported_with_its_pace_to_t_end() {
        let line = step_running_line(75.0, &p(2.5, 10.0, 100));
        assert_eq!(
            line,
            "granflow: t = 2.5000e0 s of 10 s (25.0 %), 100 steps, no step finished for 0:01:15"
        );
        // 100 steps of 0.025 s so far: 300 more, each at 75 s, take 22 500 s.
        let w = slow_step_warning(75.0, &p(2.5, 10.0, 100));
        assert!(w.contains("step 101 has been running for 0:01:15"), "{w}");
        assert!(w.contains("3.000e2 steps") && w.contains("6:15:00"), "{w}");
        let first = slow_step_warning(61.0, &p(0.0, 10.0, 0));
        assert!(
            first.contains("step 1 has been running for 0:01:01;"),
            "{first}"
        );
    }

    #[test]
    fn a_line_says_where_the_run_is() {
        let l = progress_line(65.0, &pace(65.0, 2.5, 1234), &p(2.5, 10.0, 1234), None);
        assert_eq!(
            l,
            "granflow: t = 2.5000 s of 10 s (25.0 %), 1234 steps, 0:01:05 elapsed, \
             about 0:03:15 to t_end"
        );
        let early = progress_line(5.0, &pace(2.0, 1e-5, 10), &p(2e-5, 10.0, 11), None);
        assert!(
            early.starts_with("granflow: t = 2.000e-5 s of 10 s"),
            "{early}"
        );
    }

    /// A raster run says how much of it is wet and how fast the wet cells are updated:
    /// 2 % of 10⁴ cells over 50 steps is 10⁴ wet-cell updates, in 4 s.
    #[test]
    fn a_raster_run_says_its_wet_fraction_and_its_rate_on_wet_cells() {
        let mut now = p(2.5, 10.0, 51);
        (now.wet_cells, now.flow_cells, now.wet_updates) = (Some(250), 10_000, 1.2e4);
        let mut window = pace(4.0, 2.4, 50);
        window.wet_updates = 1e4;
        let l = progress_line(5.0, &window, &now, None);
        assert!(
            l.ends_with("to t_end, wet 2.5 % of 10000 cells, 2.500e3 wet-cell updates/s"),
            "{l}"
        );
        // Before any step has a pace, the fraction alone; a line run, nothing.
        let first = progress_line(0.1, &pace(0.1, 0.0, 0), &now, None);
        assert!(first.ends_with(", wet 2.5 % of 10000 cells"), "{first}");
        let line = progress_line(5.0, &window, &p(2.5, 10.0, 51), None);
        assert!(!line.contains("wet"), "{line}");
    }

    /// A run that ends once settled: the time to t_end is a bound, and the line says
    /// how far the kinetic energy is from the fraction that ends the run.
    #[test]
    fn a_run_that_ends_when_settled_says_its_time_left_is_a_bound() {
        let mut now = p(2.5, 10.0, 1234);
        now.energy = 0.032;
        let l = progress_line(65.0, &pace(65.0, 2.5, 1234), &now, Some(0.01));
        assert_eq!(
            l,
            "granflow: t = 2.5000 s of 10 s (25.0 %), 1234 steps, 0:01:05 elapsed, \
             at most 0:03:15 to t_end, kinetic energy 3.2 % of its peak (ends at 1.0 %)"
        );
        now.energy = f64::NAN;
        let still = progress_line(65.0, &pace(65.0, 2.5, 1234), &now, Some(1e-6));
        assert!(still.ends_with("at most 0:03:15 to t_end"), "{still}");
    }
}
