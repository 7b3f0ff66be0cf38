//! One run of any [`Model`]: owns the grid, the model, its state and its pipeline, and
//! advances them to the end time, reporting snapshots and per-step records to an
//! output sink.
//!
//! Time stepping: Δt = CFL Δx / s, s the model's signal speed (a bound on the wave
//! speeds its fluxes use, from the diagnostics of the state), shortened to land exactly
//! on every output time and on t_end; a step that would make h negative (possible only
//! if the CFL bound is violated) is retried with half the Δt from the state before the
//! step, whichever stage refused it (the loop keeps a copy of the state of t^n in a
//! buffer allocated once). After every step the
//! [stop rules](crate::stop) decide whether the run goes on, ends or fails; a failure
//! names where and when, and what was written stays valid: the sink is always
//! finished, whatever ends the run.

use std::time::Instant;

use crate::gauges::Gauges;
use crate::grid::Grid;
use crate::model::tracker::Tracker;
use crate::model::{Diagnostics, Model};
use crate::numerics::{StageError, StepClock};
use crate::output::{
    GridData, OutputError, OutputSink, RunInfo, RunSummary, Spread, StepRecord, WetCells,
};
use crate::pipeline::Pipeline;
use crate::stop::{FailureReason, SolverFailure, StepContext, StopRule, Verdict};

/// Time-loop settings.
#[derive(Debug, Clone, PartialEq)]
pub struct RunConfig {
    pub t_end: f64,
    pub cfl: f64,
    pub output_every: f64,
    /// Gauge positions (m); empty: no gauges ([`crate::gauges`]).
    pub gauges: Vec<f64>,
    /// The gauges' y on a raster (one per gauge); empty on a line.
    pub gauges_y: Vec<f64>,
    /// Gauge interval (s); `None`: every step.
    pub gauge_every: Option<f64>,
    /// Fraction of the peak kinetic energy below which the run counts as settled
    /// (`settled_time`).
    pub settle_fraction: f64,
}

/// Reported to the progress callback after every step.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub t: f64,
    pub t_end: f64,
    pub steps: u64,
    /// The kinetic energy over its peak so far (NaN before any motion): how near the
    /// run is to `time.stop_when_settled`'s end.
    pub energy: f64,
    /// Cells holding material after the step (`None`: the model does not count them).
    pub wet_cells: Option<usize>,
    /// Cells material can occupy ([`Grid::flow_cells`]): the wet fraction's denominator.
    pub flow_cells: usize,
    /// Wet-cell updates so far: over the steps taken, the sum of the cells wet at the
    /// start of each (NaN when the model does not count them).
    pub wet_updates: f64,
}

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("solver failure: {0}")]
    Solver(SolverFailure),
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Largest number of Δt halvings before a step is declared failed.
const MAX_RETRIES: usize = 12;

pub struct Simulation<M: Model> {
    pub grid: M::Grid,
    pub model: M,
    pub state: M::State,
    /// The state at the start of the current step, restored when a stage refuses it
    /// (allocated once, copied into with `clone_from`).
    backup: M::State,
    pipeline: Pipeline<M::Grid, M::State>,
    rules: Vec<Box<dyn StopRule>>,
    pub config: RunConfig,
    pub info: RunInfo,
    pub t: f64,
    pub steps: u64,
    /// Signal speed of the current state when the run loop has already computed it
    /// with the diagnostics (saves a pass); None when stale.
    signal_speed: Option<f64>,
    /// Whether `backup` already holds the current state (copied with the diagnostics,
    /// [`Model::diagnose_and_save`]); false when stale.
    saved: bool,
    /// What the run gathers over its steps (maps of a raster run), if anything.
    tracker: Option<Box<dyn Tracker<M::Grid, M::State>>>,
}

/// The state of the loop that the summary needs.
struct Tally {
    wall: Instant,
    front0: f64,
    last: Diagnostics,
    /// First time of the current period at rest.
    rest_since: Option<f64>,
    /// Largest wave amplitude so far, for models with a water surface.
    max_wave: Option<f64>,
    /// Mass of the initial state, for the stop rules.
    mass0: f64,
    /// Peak kinetic energy so far.
    ke_peak: f64,
    /// First time of the current period with kinetic energy ≤ settle_fraction × peak.
    settled_since: Option<f64>,
    /// First time the front stood in the last cell (the domain's downstream end).
    front_at_end: Option<f64>,
    /// Wet-cell updates so far (see [`Progress::wet_updates`]).
    wet_updates: f64,
    /// Most cells wet at once.
    wet_peak: usize,
}

impl Tally {
    /// Updates the peak kinetic energy and the settled period with the state at `t`
    /// (the same test as [`crate::stop::Settled`]).
    fn settle(&mut self, d: &Diagnostics, t: f64, fraction: f64) {
        self.ke_peak = self.ke_peak.max(d.kinetic_energy);
        self.settled_since = if crate::stop::settled(d.kinetic_energy, self.ke_peak, fraction) {
            self.settled_since.or(Some(t))
        } else {
            None
        };
    }

    /// Records the first time the front stands in the last cell, centred at `x_last`,
    /// when it did not at t = 0 (a domain wet to its end has no front that moves).
    fn front_end(&mut self, d: &Diagnostics, t: f64, x_last: f64) {
        if self.front_at_end.is_none() && self.front0 < x_last && d.front_x >= x_last {
            self.front_at_end = Some(t);
        }
    }
}

impl<M: Model> Simulation<M> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grid: M::Grid,
        model: M,
        state: M::State,
        pipeline: Pipeline<M::Grid, M::State>,
        rules: Vec<Box<dyn StopRule>>,
        config: RunConfig,
        info: RunInfo,
    ) -> Simulation<M> {
        Simulation {
            grid,
            model,
            backup: state.clone(),
            state,
            pipeline,
            rules,
            config,
            info,
            t: 0.0,
            steps: 0,
            signal_speed: None,
            saved: false,
            tracker: None,
        }
    }

    /// Gathers over the run with `tracker` (it sees the initial state and every
    /// accepted one, and writes to the sink before it is finished).
    pub fn set_tracker(&mut self, tracker: Box<dyn Tracker<M::Grid, M::State>>) {
        self.tracker = Some(tracker);
    }

    /// Adds a stop rule, consulted after the others.
    pub fn add_rule(&mut self, rule: Box<dyn StopRule>) {
        self.rules.push(rule);
    }

    /// Appends a stage to the run's step, after the model's (a sub-step of one's own,
    /// e.g. a test's).
    pub fn push_stage(&mut self, stage: Box<dyn crate::numerics::Stage<M::Grid, M::State>>) {
        self.pipeline.push(stage);
    }

    /// Names of the stages, in order.
    pub fn stage_names(&self) -> Vec<&'static str> {
        self.pipeline.names()
    }

    pub fn diagnostics(&self) -> Diagnostics {
        self.model.diagnose(&self.grid, &self.state)
    }

    /// Diagnostics of the current state, remembering its signal speed for the next Δt;
    /// the state is copied into the backup of the next step in the same pass.
    fn diagnose_for_next_step(&mut self) -> Diagnostics {
        let d = self
            .model
            .diagnose_and_save(&self.grid, &self.state, &mut self.backup);
        self.signal_speed = Some(d.signal_speed);
        self.saved = true;
        d
    }

    /// The CFL step for the signal speed `s` (∞ when nothing moves).
    fn cfl_dt(&self, s: f64) -> f64 {
        if s > 0.0 {
            self.config.cfl * self.grid.cfl_length() / s
        } else {
            f64::INFINITY
        }
    }

    /// Advances one step of at most `dt_max`; returns the Δt taken.
    ///
    /// The step is transactional: if a stage refuses it, the state of t^n is restored
    /// before the retry with half the Δt (or before the run fails), whichever stage
    /// refused and whatever the stages before it changed.
    ///
    /// Returns 0 (the state left at t^n) when a stage gave the step up on Ctrl-C
    /// ([`StageError::Interrupted`]); any step taken is longer than 0.
    pub fn step(&mut self, dt_max: f64) -> Result<f64, RunError> {
        let s = match self.signal_speed.take() {
            Some(s) => s,
            None => self.diagnostics().signal_speed,
        };
        // The step the stability condition allows, and the step taken: shorter when it
        // lands on an output time (stages that turn an increment into a rate use the
        // former, `StepClock::rate_step`).
        let dt_full = self.cfl_dt(s);
        let mut clock = StepClock::new(self.t, dt_full.min(dt_max), dt_full);
        let mut last_failure = None;
        if !std::mem::take(&mut self.saved) {
            self.model.save_state(&mut self.backup, &self.state);
        }
        for _ in 0..=MAX_RETRIES {
            let attempt = self.pipeline.advance(&self.grid, clock, &mut self.state);
            match attempt {
                Ok(()) => {
                    self.steps += 1;
                    return Ok(clock.dt);
                }
                Err(StageError::NegativeThickness { cell, h }) => {
                    self.state.clone_from(&self.backup);
                    last_failure = Some((cell, h, clock.dt));
                    clock = clock.halved();
                }
                Err(StageError::Inadmissible {
                    cell,
                    quantity,
                    value,
                }) => {
                    self.state.clone_from(&self.backup);
                    let reason = FailureReason::Inadmissible { quantity, value };
                    return Err(self.failure(reason, Some(cell)));
                }
                Err(StageError::Interrupted) => {
                    self.state.clone_from(&self.backup);
                    return Ok(0.0);
                }
            }
        }
        let (cell, h, dt) = last_failure.expect("at least one attempt");
        Err(self.failure(FailureReason::NegativeThickness { h, dt }, Some(cell)))
    }

    /// A failure of the speed bound (whose rule sees the diagnostics, not the state)
    /// placed at the centre of the fastest cell, when the model names it; any other
    /// failure as it is.
    fn placed(&self, mut failure: SolverFailure) -> SolverFailure {
        if matches!(failure.reason, FailureReason::SpeedBound { .. }) && failure.x.is_none() {
            if let Some(cell) = self.model.fastest_cell(&self.grid, &self.state) {
                (failure.x, failure.y) = self.centre(cell);
            }
        }
        failure
    }

    /// The centre of physical cell `cell` (0-based) for a failure: x, and y on a raster.
    fn centre(&self, cell: usize) -> (Option<f64>, Option<f64>) {
        let c = self.grid.centre(cell);
        (Some(c.x), (self.grid.axis_names().len() > 1).then_some(c.y))
    }

    /// The failure `reason` in physical cell `cell` (0-based), placed at its centre.
    fn failure(&self, reason: FailureReason, cell: Option<usize>) -> RunError {
        let (x, y) = cell.map_or((None, None), |i| self.centre(i));
        RunError::Solver(SolverFailure {
            reason,
            x,
            y,
            t: self.t,
            step: self.steps,
        })
    }

    fn record(&self, d: &Diagnostics, dt: f64) -> StepRecord {
        StepRecord {
            t: self.t,
            dt,
            mass: d.mass,
            kinetic_energy: d.kinetic_energy,
            max_speed: d.max_speed,
            front_x: d.front_x,
        }
    }

    fn snapshot(&self, sink: &mut dyn OutputSink) -> Result<(), OutputError> {
        self.model.snapshot(&self.grid, &self.state, self.t, sink)?;
        match &self.tracker {
            Some(tracker) => tracker.write_so_far(&self.grid, &self.state, sink),
            None => Ok(()),
        }
    }

    /// Runs to `t_end` (or until a stop rule ends it), writing to `sink`. The sink is
    /// always finished, also on failure, with the status in the summary.
    pub fn run(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<RunSummary, RunError> {
        let wall = Instant::now();
        let spec = self.grid.grid_spec();
        let grid = GridData {
            spec: &spec,
            x: self.grid.axis(0),
            y: (self.grid.axis_names().len() > 1).then(|| self.grid.axis(1)),
            shape: self.grid.shape(),
            b: self.grid.bed(),
            h_bed: self.model.bed_layer(),
        };
        sink.begin(&self.info, &grid)?;
        let d0 = self.diagnose_for_next_step();
        let mut tally = Tally {
            wall,
            front0: d0.front_x,
            last: d0,
            rest_since: (d0.max_speed <= self.model.rest_speed()).then_some(0.0),
            max_wave: self.model.wave_amplitude(&self.grid, &self.state),
            mass0: d0.mass,
            ke_peak: d0.kinetic_energy,
            settled_since: None,
            front_at_end: None,
            wet_updates: if d0.wet_cells.is_some() {
                0.0
            } else {
                f64::NAN
            },
            wet_peak: d0.wet_cells.unwrap_or(0),
        };
        tally.settle(&d0, 0.0, self.config.settle_fraction);
        tally.front_end(&d0, 0.0, self.x_last());
        let result = match self.model.workers().cloned() {
            Some(workers) => workers.install(|| self.run_loop(sink, progress, &mut tally, d0)),
            None => self.run_loop(sink, progress, &mut tally, d0),
        };
        // The state may be changed between runs: the next step copies it.
        (self.signal_speed, self.saved) = (None, false);
        let status = match &result {
            Ok(status) => status.to_string(),
            Err(e) => format!("failed: {}", failure_message(e)),
        };
        let summary = self.summary(&tally, status);
        // The sink is finished whatever ended the run; an output error of the loop
        // takes precedence over one of `finish`.
        let maps = match &self.tracker {
            Some(tracker) => tracker.write(&self.grid, &self.state, sink),
            None => Ok(()),
        };
        let finished = sink.finish(&summary);
        let finished = maps.and(finished);
        match result {
            Ok(_) => finished.map(|()| summary).map_err(RunError::from),
            Err(e @ RunError::Output(_)) => Err(e),
            Err(e) => Err(finished.err().map_or(e, RunError::from)),
        }
    }

    /// The time loop proper; returns the final status.
    fn run_loop(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut (dyn FnMut(Progress) + Send),
        tally: &mut Tally,
        d0: Diagnostics,
    ) -> Result<&'static str, RunError> {
        if let Some(i) = d0.non_finite_at {
            return Err(self.failure(FailureReason::NonFinite, Some(i)));
        }
        if let Some(quantity) = crate::stop::total_overflow(&d0) {
            return Err(self.failure(FailureReason::TotalOverflow { quantity }, None));
        }
        sink.step(&self.record(&d0, 0.0))?;
        if let Some(tracker) = self.tracker.as_mut() {
            tracker.observe(&self.grid, &self.state, self.t);
        }
        let mut gauges = (!self.config.gauges.is_empty()).then(|| {
            let c = &self.config;
            Gauges::new(&self.grid, &c.gauges, &c.gauges_y, c.gauge_every)
        });
        if let Some(g) = gauges.as_mut() {
            g.begin(&self.model, &self.grid, &self.state, sink)?;
        }
        self.snapshot(sink)?;
        let status = self.time_loop(sink, progress, tally, gauges.as_mut());
        // A run that ends (not one that fails, whose state may hold NaN) records its
        // last state.
        if let (Ok(_), Some(g)) = (&status, gauges.as_mut()) {
            g.end(self.t, sink)?;
        }
        status
    }

    /// The steps of [`Simulation::run_loop`] after t = 0.
    fn time_loop(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut (dyn FnMut(Progress) + Send),
        tally: &mut Tally,
        mut gauges: Option<&mut Gauges>,
    ) -> Result<&'static str, RunError> {
        let cfg = self.config.clone();
        let mut next_output = cfg.output_every.min(cfg.t_end);
        let mut output_index = 1u64;
        // Time of the last snapshot written (run_loop wrote the one of t = 0).
        let mut snapshot_t = self.t;
        while self.t < cfg.t_end {
            // The cells this step updates where the material is.
            let wet_before = tally.last.wet_cells.unwrap_or(0) as f64;
            let dt = self.step(next_output - self.t)?;
            if dt == 0.0 {
                // Ctrl-C inside the step: the state is that of the last accepted step,
                // which gets its snapshot (unless it has one) as at any interrupt.
                if snapshot_t < self.t {
                    self.snapshot(sink)?;
                }
                return Ok("interrupted");
            }
            let at_output = self.t + dt >= next_output * (1.0 - 1e-14);
            self.t = if at_output { next_output } else { self.t + dt };
            let d = self.diagnose_for_next_step();
            let at_rest = d.max_speed <= self.model.rest_speed();
            let ctx = StepContext {
                t: self.t,
                t_end: cfg.t_end,
                steps: self.steps,
                diagnostics: &d,
                next_dt: self.cfl_dt(d.signal_speed),
                x: self.grid.axis(0),
                y: if self.grid.axis_names().len() > 1 {
                    self.grid.axis(1)
                } else {
                    &[]
                },
                at_rest,
                mass0: tally.mass0,
            };
            let mut stop = None;
            for rule in &mut self.rules {
                match rule.check(&ctx) {
                    Verdict::Continue => {}
                    Verdict::Stop(status) => {
                        stop.get_or_insert(status);
                    }
                    Verdict::Fail(failure) => return Err(RunError::Solver(self.placed(failure))),
                }
            }
            sink.step(&self.record(&d, dt))?;
            if let Some(tracker) = self.tracker.as_mut() {
                tracker.observe(&self.grid, &self.state, self.t);
            }
            if let Some(g) = gauges.as_deref_mut() {
                g.after_step(&self.model, &self.grid, &self.state, self.t, sink)?;
            }
            if let Some(a) = self.model.wave_amplitude(&self.grid, &self.state) {
                tally.max_wave = Some(tally.max_wave.map_or(a, |m| m.max(a)));
            }
            tally.rest_since = if at_rest {
                tally.rest_since.or(Some(self.t))
            } else {
                None
            };
            tally.settle(&d, self.t, cfg.settle_fraction);
            tally.front_end(&d, self.t, self.x_last());
            tally.wet_updates += wet_before;
            tally.wet_peak = tally.wet_peak.max(d.wet_cells.unwrap_or(0));
            tally.last = d;
            if at_output || stop.is_some() {
                self.snapshot(sink)?;
                snapshot_t = self.t;
            }
            if at_output {
                output_index += 1;
                next_output = (output_index as f64 * cfg.output_every).min(cfg.t_end);
            }
            progress(Progress {
                t: self.t,
                t_end: cfg.t_end,
                steps: self.steps,
                energy: if tally.ke_peak > 0.0 {
                    tally.last.kinetic_energy / tally.ke_peak
                } else {
                    f64::NAN
                },
                wet_cells: d.wet_cells,
                flow_cells: self.grid.flow_cells(),
                wet_updates: tally.wet_updates,
            });
            if let Some(status) = stop {
                return Ok(status);
            }
        }
        Ok("completed")
    }

    /// Centre of the last cell.
    fn x_last(&self) -> f64 {
        let n = self.grid.cells();
        if n == 0 {
            f64::NAN
        } else {
            self.grid.centre(n - 1).x
        }
    }

    /// Fraction of the initial mass that has left through outflow boundaries: 1 −
    /// mass / initial mass, 0 for a domain closed by walls (whose mass can only change
    /// by erosion or deposition) and for a gain; NaN for a run without mass.
    fn outflowed_fraction(&self, tally: &Tally) -> f64 {
        let open = self.grid.has_outflow();
        if tally.mass0.is_nan() || tally.mass0 <= 0.0 {
            f64::NAN
        } else if open {
            (1.0 - tally.last.mass / tally.mass0).max(0.0)
        } else {
            0.0
        }
    }

    /// Where the run's work went: its wet fraction and its cell updates per second of
    /// `wall_s`, for a model that counts its wet cells.
    fn wet_summary(&self, tally: &Tally, wall_s: f64) -> Option<WetCells> {
        tally.last.wet_cells?;
        let flow = self.grid.flow_cells() as f64;
        let steps = self.steps as f64;
        Some(WetCells {
            flow_cells: self.grid.flow_cells(),
            mean_fraction: if self.steps > 0 {
                tally.wet_updates / (steps * flow)
            } else {
                f64::NAN
            },
            peak_fraction: tally.wet_peak as f64 / flow,
            wet_updates_per_s: tally.wet_updates / wall_s,
            cell_updates_per_s: self
                .model
                .cell_updates(&self.state)
                .map_or(steps * flow, |u| u as f64)
                / wall_s,
        })
    }

    fn summary(&self, tally: &Tally, status: String) -> RunSummary {
        let wall_time_s = tally.wall.elapsed().as_secs_f64();
        RunSummary {
            outflowed_fraction: self.outflowed_fraction(tally),
            front_at_end_time: tally.front_at_end.unwrap_or(f64::NAN),
            max_speed_final: tally.last.max_speed,
            runout: tally.last.front_x - tally.front0,
            stop_time: tally.rest_since.unwrap_or(f64::NAN),
            settled_time: tally.settled_since.unwrap_or(f64::NAN),
            settle_fraction: self.config.settle_fraction,
            h_max_final: tally.last.h_max,
            t_end: self.t,
            steps: self.steps,
            wall_time_s,
            status,
            wet: self.wet_summary(tally, wall_time_s),
            max_wave_amplitude: tally.max_wave,
            spread: self
                .tracker
                .as_ref()
                .and_then(|t| Spread::from_scalars(&t.scalars(&self.grid, &self.state))),
            stage_times: self.stage_times(),
        }
    }

    /// Per-stage wall times (s), in pipeline order.
    pub fn stage_times(&self) -> Vec<(String, f64)> {
        self.pipeline.times()
    }
}

fn failure_message(e: &RunError) -> String {
    match e {
        RunError::Solver(f) => f.to_string(),
        RunError::Output(o) => o.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Coordinates, Line, LineSpec};
    use crate::model::granular::Granular;
    use crate::numerics::Stage;
    use crate::state::LayeredState;

    /// Adds `dt` to h of the first physical cell.
    struct Grow;

    impl Stage<Line, LayeredState> for Grow {
        fn name(&self) -> &'static str {
            "grow"
        }
        fn apply(
            &mut self,
            _: &Line,
            clock: StepClock,
            s: &mut LayeredState,
        ) -> Result<(), StageError> {
            s.h[1] += clock.dt;
            Ok(())
        }
    }

    /// Refuses the first `failures` steps it sees with `error`, then does nothing.
    struct Refuse {
        failures: usize,
        error: StageError,
    }

    impl Stage<Line, LayeredState> for Refuse {
        fn name(&self) -> &'static str {
            "refuse"
        }
        fn apply(
            &mut self,
            _: &Line,
            _: StepClock,
            _: &mut LayeredState,
        ) -> Result<(), StageError> {
            if self.failures > 0 {
                self.failures -= 1;
                return Err(self.error.clone());
            }
            Ok(())
        }
    }

    /// Accepts `accepted` steps, then gives the next one up as on Ctrl-C.
    struct GiveUpAfter {
        accepted: usize,
    }

    impl Stage<Line, LayeredState> for GiveUpAfter {
        fn name(&self) -> &'static str {
            "give_up"
        }
        fn apply(
            &mut self,
            _: &Line,
            _: StepClock,
            _: &mut LayeredState,
        ) -> Result<(), StageError> {
            if self.accepted == 0 {
                return Err(StageError::Interrupted);
            }
            self.accepted -= 1;
            Ok(())
        }
    }

    /// A layer at rest on a flat bed (signal speed √(g h) > 0), with `second` as the
    /// pipeline's second stage after [`Grow`].
    fn simulation(second: impl Stage<Line, LayeredState> + 'static) -> Simulation<Granular> {
        let spec = LineSpec {
            x_min: 0.0,
            x_max: 1.0,
            cells: 10,
            slope_deg: 0.0,
            coordinates: Coordinates::Cartesian,
            left: BoundaryKind::Wall,
            right: BoundaryKind::Wall,
        };
        let line = Line::new(&spec, vec![0.0; 10]);
        let state = LayeredState::from_profiles(&line, &[1.0], &[0.1; 10], &[0.0; 10]);
        let model = Granular {
            h_bed: vec![0.0; 10],
            front_threshold: 1e-3,
            static_threshold: 1e-3,
            rest_speed: 0.0,
        };
        let config = RunConfig {
            t_end: 1.0,
            cfl: 0.5,
            output_every: 1.0,
            gauges: Vec::new(),
            gauges_y: Vec::new(),
            gauge_every: None,
            settle_fraction: 0.0,
        };
        let info = RunInfo {
            granflow_version: String::new(),
            model: "granular".into(),
            pressure: "hydrostatic".into(),
            layers: 1,
            coordinates: "cartesian".into(),
            slope_deg: 0.0,
            scenario_toml: String::new(),
            front_threshold: 1e-3,
            raster: None,
        };
        let pipeline = Pipeline::new(vec![Box::new(Grow), Box::new(second)]);
        Simulation::new(line, model, state, pipeline, Vec::new(), config, info)
    }

    #[test]
    fn a_step_refused_by_a_later_stage_is_retried_from_the_state_before_it() {
        let refuse = Refuse {
            failures: 1,
            error: StageError::NegativeThickness { cell: 3, h: -1.0 },
        };
        let mut sim = simulation(refuse);
        let h0 = sim.state.h[1];
        let cfl_dt = sim.cfl_dt(sim.diagnostics().signal_speed);
        let dt = sim.step(1.0).expect("the retry succeeds");
        assert_eq!(dt, 0.5 * cfl_dt);
        // Only the accepted (halved) step has grown the cell: the growth of the refused
        // attempt was undone with the rest of that step.
        assert_eq!(sim.state.h[1], h0 + dt);
        assert_eq!(sim.steps, 1);
    }

    #[test]
    fn a_failed_step_leaves_the_state_of_its_start_and_names_the_cell_centre() {
        let refuse = Refuse {
            failures: 1,
            error: StageError::Inadmissible {
                cell: 3,
                quantity: "test quantity",
                value: 2.0,
            },
        };
        let mut sim = simulation(refuse);
        let before = sim.state.clone();
        let Err(RunError::Solver(failure)) = sim.step(1.0) else {
            panic!("the step fails");
        };
        assert_eq!(sim.state, before);
        let x = sim.grid.x[3];
        assert_eq!(failure.x, Some(x));
        assert!(
            failure.to_string().contains(&format!("x = {x} m")),
            "{failure}"
        );
    }

    #[test]
    fn a_step_given_up_on_ctrl_c_ends_the_run_at_the_last_accepted_state() {
        let mut sim = simulation(GiveUpAfter { accepted: 3 });
        let h0 = sim.state.h[1];
        let mut sink = crate::output::memory::MemorySink::default();
        let summary = sim
            .run(&mut sink, &mut |_| {})
            .expect("an interrupt is no failure");
        assert_eq!(summary.status, "interrupted");
        assert_eq!(sim.steps, 3);
        // The growth of the abandoned attempt was undone: h grew by the three steps.
        let dts: Vec<f64> = sink.steps.iter().map(|r| r.dt).collect();
        assert_eq!(dts.len(), 4, "t = 0 and three steps: {dts:?}");
        assert_eq!(sim.state.h[1], dts.iter().fold(h0, |h, dt| h + dt));
        // The last accepted state is the last snapshot, once.
        let t: Vec<f64> = sink.snapshots.iter().map(|s| s.t).collect();
        assert_eq!(t, vec![0.0, sim.t]);
        assert!(sim.t > 0.0 && sim.t < 1.0);
    }
}
