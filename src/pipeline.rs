//! The time step as a pipeline of named sub-steps (seed 000 §3, seed 003 §4:
//! hyperbolic → friction or viscous → projection), each timed. A model builds its
//! pipeline from the scenario with only the stages the scene needs (a hydrostatic run
//! has no projection stage); the run loop applies it without knowing what is inside.

use std::time::{Duration, Instant};

use crate::mesh::Mesh;
use crate::numerics::{Stage, StageError};

/// The stages of one model's time step, with their accumulated wall times.
pub struct Pipeline<S> {
    stages: Vec<Box<dyn Stage<S>>>,
    times: Vec<Duration>,
}

impl<S> Pipeline<S> {
    pub fn new(stages: Vec<Box<dyn Stage<S>>>) -> Self {
        let times = vec![Duration::ZERO; stages.len()];
        Pipeline { stages, times }
    }

    /// Names of the stages, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.stages.iter().map(|s| s.name()).collect()
    }

    /// Advances `state` by `dt`: every stage's `prepare` with the state at t^n, then
    /// every stage's `apply` in order. On error the stages leave the state as it was
    /// before the failing stage; the caller retries from its own copy if it needs one.
    pub fn advance(&mut self, mesh: &Mesh, dt: f64, state: &mut S) -> Result<(), StageError> {
        for (stage, time) in self.stages.iter_mut().zip(&mut self.times) {
            let start = Instant::now();
            stage.prepare(mesh, state);
            *time += start.elapsed();
        }
        for (stage, time) in self.stages.iter_mut().zip(&mut self.times) {
            let start = Instant::now();
            stage.apply(mesh, dt, state)?;
            *time += start.elapsed();
        }
        Ok(())
    }

    /// Per-stage wall times (s), in pipeline order.
    pub fn times(&self) -> Vec<(String, f64)> {
        self.stages
            .iter()
            .zip(&self.times)
            .map(|(s, t)| (s.name().to_string(), t.as_secs_f64()))
            .collect()
    }
}
