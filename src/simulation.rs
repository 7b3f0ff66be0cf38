//! One run: owns the mesh, the state and the pipeline of sub-steps, and advances them
//! to the end time, reporting snapshots and per-step records to an output sink.
//!
//! Time stepping: Δt from the CFL number, shortened to land exactly on every output
//! time and on t_end; a step that would make h negative (possible only if the CFL
//! bound is violated) is retried with half the Δt. A non-finite value stops the run
//! with a failure naming where and when; what was written stays valid.

use std::time::{Duration, Instant};

use crate::diagnostics::{diagnose, Diagnostics};
use crate::mesh::Mesh;
use crate::numerics::cfl::cfl_dt;
use crate::numerics::{Stage, StageError};
use crate::output::{
    CellField, GridData, OutputError, OutputSink, RunInfo, RunSummary, SnapshotView, StepRecord,
};
use crate::physics::shallow::celerity;
use crate::profiles::{normal_velocities, static_interface};
use crate::state::State;

/// Time-loop settings.
#[derive(Debug, Clone, PartialEq)]
pub struct RunConfig {
    pub t_end: f64,
    pub cfl: f64,
    pub stop_at_rest: bool,
    pub output_every: f64,
    pub front_threshold: f64,
}

/// Reported to the progress callback after every step.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub t: f64,
    pub t_end: f64,
    pub steps: u64,
}

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("solver failure: {0}")]
    Solver(String),
    #[error(transparent)]
    Output(#[from] OutputError),
}

pub struct Simulation {
    pub mesh: Mesh,
    pub state: State,
    pub h_bed: Vec<f64>,
    pub config: RunConfig,
    pub info: RunInfo,
    pipeline: Vec<Box<dyn Stage>>,
    stage_times: Vec<Duration>,
    pub t: f64,
    pub steps: u64,
    /// max|u| + √(g_n h_max) of the current state when the run loop has already
    /// computed it with the diagnostics (saves the CFL pass); None when stale.
    signal_speed: Option<f64>,
    /// Layer speed (m/s) above which a layer counts as flowing, for the multilayer
    /// output `/snapshots/static_interface` (default 1e-3 m/s, seed 001 §4.2.5).
    pub static_threshold: f64,
    /// Largest speed (m/s) of a mass at rest, for the stop time and `stop_at_rest`: 0
    /// for the monolayer, which stops exactly; the multilayer model keeps regularised
    /// creep velocities (seed 003 Remark 2), so setup uses its static threshold.
    pub rest_speed: f64,
}

/// A CFL time step below this fraction of t_end stops the run as a solver failure.
const MIN_DT_FRACTION: f64 = 1e-10;

/// Largest number of Δt halvings before a step is declared failed.
const MAX_RETRIES: usize = 12;

impl Simulation {
    pub fn new(
        mesh: Mesh,
        state: State,
        h_bed: Vec<f64>,
        pipeline: Vec<Box<dyn Stage>>,
        config: RunConfig,
        info: RunInfo,
    ) -> Simulation {
        let stage_times = vec![Duration::ZERO; pipeline.len()];
        Simulation {
            mesh,
            state,
            h_bed,
            config,
            info,
            pipeline,
            stage_times,
            t: 0.0,
            steps: 0,
            signal_speed: None,
            static_threshold: 1e-3,
            rest_speed: 0.0,
        }
    }

    /// Names of the stages, in order.
    pub fn stage_names(&self) -> Vec<&'static str> {
        self.pipeline.iter().map(|s| s.name()).collect()
    }

    pub fn diagnostics(&self) -> Diagnostics {
        diagnose(
            &self.mesh,
            &self.state,
            &self.h_bed,
            self.config.front_threshold,
        )
    }

    /// Diagnostics of the current state, remembering its signal speed for the next Δt.
    fn diagnose_for_next_step(&mut self) -> Diagnostics {
        let d = self.diagnostics();
        // N > 1 needs the sheared wave speed of numerics::cfl; the monolayer's is
        // max|u| + √(g_n h_max), which the diagnostics already have.
        self.signal_speed =
            (self.state.layers == 1).then(|| d.max_speed + celerity(self.mesh.g_n, d.h_max));
        d
    }

    /// Advances one step of at most `dt_max`; returns the Δt taken.
    pub fn step(&mut self, dt_max: f64) -> Result<f64, RunError> {
        let cfl_dt = match self.signal_speed.take() {
            Some(s) => (s > 0.0).then(|| self.config.cfl * self.mesh.dx / s),
            None => cfl_dt(&self.mesh, &self.state, self.config.cfl),
        };
        let mut dt = cfl_dt.map_or(dt_max, |dt| dt.min(dt_max));
        for _ in 0..=MAX_RETRIES {
            match self.apply_pipeline(dt) {
                Ok(()) => {
                    self.steps += 1;
                    return Ok(dt);
                }
                Err(StageError::NegativeThickness { .. }) => dt *= 0.5,
            }
        }
        Err(RunError::Solver(format!(
            "thickness would become negative at t = {:.6e} s even with Δt = {dt:.3e} s",
            self.t
        )))
    }

    fn apply_pipeline(&mut self, dt: f64) -> Result<(), StageError> {
        for (stage, time) in self.pipeline.iter_mut().zip(&mut self.stage_times) {
            let start = Instant::now();
            stage.prepare(&self.mesh, &self.state);
            *time += start.elapsed();
        }
        for (stage, time) in self.pipeline.iter_mut().zip(&mut self.stage_times) {
            let start = Instant::now();
            stage.apply(&self.mesh, dt, &mut self.state)?;
            *time += start.elapsed();
        }
        Ok(())
    }

    fn snapshot(&self, sink: &mut dyn OutputSink) -> Result<(), OutputError> {
        let (nx, n) = (self.mesh.nx, self.state.layers);
        let mut u = vec![0.0; n * nx];
        for i in 0..nx {
            let h = self.state.h[i + 1];
            for a in 0..n {
                u[a * nx + i] =
                    crate::physics::shallow::velocity(h, self.state.hu[(i + 1) * n + a]);
            }
        }
        let nh = self
            .state
            .nh
            .as_ref()
            .map(|nh| nh.snapshot_fields(&self.state));
        // The multilayer model also reports its normal velocities (seed 001 eq. 20)
        // and the flow/no-flow interface.
        let (w_ml, interface) = if n > 1 {
            let mut w = vec![0.0; n * nx];
            normal_velocities(&self.mesh, &self.state, &mut w);
            let mut interface = vec![0.0; nx];
            static_interface(&self.state, self.static_threshold, &mut interface);
            (Some(w), interface)
        } else {
            (None, Vec::new())
        };
        let extra = [CellField {
            name: "static_interface",
            units: "m",
            data: &interface,
        }];
        sink.snapshot(&SnapshotView {
            t: self.t,
            h: self.state.h_interior(),
            u: &u,
            w: nh.as_ref().map(|(w, _)| w.as_slice()).or(w_ml.as_deref()),
            p_nh: nh.as_ref().map(|(_, p)| p.as_slice()),
            layers: n,
            extra: if n > 1 { &extra } else { &[] },
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

    /// Runs to `t_end` (or to rest), writing to `sink`. The sink is always finished,
    /// also on failure, with the status in the summary.
    pub fn run(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<RunSummary, RunError> {
        let wall = Instant::now();
        let grid = GridData {
            x: &self.mesh.x,
            b: &self.mesh.b,
            h_bed: &self.h_bed,
        };
        sink.begin(&self.info, &grid)?;
        let d0 = self.diagnose_for_next_step();
        if let Some(i) = d0.non_finite_at {
            let msg = format!("non-finite initial state at x = {}", self.mesh.x[i]);
            return Err(self.fail(sink, wall, &d0, d0.front_x, None, msg));
        }
        sink.step(&self.record(&d0, 0.0))?;
        self.snapshot(sink)?;

        let cfg = self.config.clone();
        let mut next_output = cfg.output_every.min(cfg.t_end);
        let mut output_index = 1u64;
        let mut rest_since: Option<f64> = (d0.max_speed <= self.rest_speed).then_some(0.0);
        let mut last = d0;
        let mut status = "completed";
        while self.t < cfg.t_end {
            let dt = match self.step(next_output - self.t) {
                Ok(dt) => dt,
                Err(e) => {
                    let msg = match e {
                        RunError::Solver(m) => m,
                        other => other.to_string(),
                    };
                    return Err(self.fail(sink, wall, &last, d0.front_x, rest_since, msg));
                }
            };
            let at_output = self.t + dt >= next_output * (1.0 - 1e-14);
            self.t = if at_output { next_output } else { self.t + dt };
            let d = self.diagnose_for_next_step();
            if let Some(i) = d.non_finite_at {
                let msg = format!(
                    "non-finite value at x = {} m, t = {:.6e} s (step {})",
                    self.mesh.x[i], self.t, self.steps
                );
                return Err(self.fail(sink, wall, &last, d0.front_x, rest_since, msg));
            }
            // A finite but absurd state (e.g. u = 1e154 m/s) would otherwise crawl on
            // with Δt near zero, filling memory with step records.
            let speed = d.max_speed + celerity(self.mesh.g_n, d.h_max);
            let next_dt = cfg.cfl * self.mesh.dx / speed;
            if next_dt < MIN_DT_FRACTION * cfg.t_end {
                let msg = format!(
                    "time step collapsed to {next_dt:.3e} s at t = {:.6e} s (step {}, max speed {:.3e} m/s)",
                    self.t, self.steps, d.max_speed
                );
                return Err(self.fail(sink, wall, &last, d0.front_x, rest_since, msg));
            }
            sink.step(&self.record(&d, dt))?;
            let at_rest = d.max_speed <= self.rest_speed;
            rest_since = if at_rest {
                rest_since.or(Some(self.t))
            } else {
                None
            };
            let stop = cfg.stop_at_rest && at_rest;
            if at_output || stop {
                self.snapshot(sink)?;
            }
            if at_output {
                output_index += 1;
                next_output = (output_index as f64 * cfg.output_every).min(cfg.t_end);
            }
            last = d;
            progress(Progress {
                t: self.t,
                t_end: cfg.t_end,
                steps: self.steps,
            });
            if stop {
                status = "stopped_at_rest";
                break;
            }
        }
        let summary = self.summary(wall, &last, d0.front_x, rest_since, status.to_string());
        sink.finish(&summary)?;
        Ok(summary)
    }

    fn summary(
        &self,
        wall: Instant,
        last: &Diagnostics,
        front0: f64,
        rest_since: Option<f64>,
        status: String,
    ) -> RunSummary {
        RunSummary {
            runout: last.front_x - front0,
            stop_time: rest_since.unwrap_or(f64::NAN),
            h_max_final: last.h_max,
            t_end: self.t,
            steps: self.steps,
            wall_time_s: wall.elapsed().as_secs_f64(),
            status,
            stage_times: self.stage_times(),
        }
    }

    /// Per-stage wall times (s), in pipeline order.
    pub fn stage_times(&self) -> Vec<(String, f64)> {
        self.pipeline
            .iter()
            .zip(&self.stage_times)
            .map(|(s, t)| (s.name().to_string(), t.as_secs_f64()))
            .collect()
    }

    fn fail(
        &self,
        sink: &mut dyn OutputSink,
        wall: Instant,
        last: &Diagnostics,
        front0: f64,
        rest_since: Option<f64>,
        message: String,
    ) -> RunError {
        let summary = self.summary(wall, last, front0, rest_since, format!("failed: {message}"));
        match sink.finish(&summary) {
            Ok(()) => RunError::Solver(message),
            Err(e) => RunError::Output(e),
        }
    }
}
