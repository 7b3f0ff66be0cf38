//! The time step as a pipeline of named sub-steps (Garres-Díaz et al. 2021, §3, Escalante et al. 2023, §4:
//! hyperbolic → friction or viscous → projection), each timed. A model builds its
//! pipeline from the scenario with only the stages the scene needs (a hydrostatic run
//! has no projection stage); the run loop applies it without knowing what is inside.

use std::time::{Duration, Instant};

use crate::numerics::{Stage, StageError, StepClock};

/// The stages of one model's time step on grid `G`, acting on state `S`, with their
/// accumulated wall times.
pub struct Pipeline<G, S> {
    stages: Vec<Box<dyn Stage<G, S>>>,
    times: Vec<Duration>,
}

impl<G, S> Pipeline<G, S> {
    pub fn new(stages: Vec<Box<dyn Stage<G, S>>>) -> Self {
        let times = vec![Duration::ZERO; stages.len()];
        Pipeline { stages, times }
    }

    /// Appends `stage` after the others.
    pub fn push(&mut self, stage: Box<dyn Stage<G, S>>) {
        self.stages.push(stage);
        self.times.push(Duration::ZERO);
    }

    /// Names of the stages, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.stages.iter().map(|s| s.name()).collect()
    }

    /// Advances `state` by `clock.dt`: every stage's `prepare` with the state at tⁿ,
    /// then every stage's `apply` in order, each with `clock`. On error the state is
    /// part-way through the step (the stages before the failing one have been applied):
    /// the caller restores its copy of the state at tⁿ
    /// ([`crate::simulation::Simulation::step`] does).
    pub fn advance(&mut self, grid: &G, clock: StepClock, state: &mut S) -> Result<(), StageError> {
        for (stage, time) in self.stages.iter_mut().zip(&mut self.times) {
            let start = Instant::now();
            stage.prepare(grid, clock, state);
            *time += start.elapsed();
        }
        for (stage, time) in self.stages.iter_mut().zip(&mut self.times) {
            let start = Instant::now();
            stage.apply(grid, clock, state)?;
            *time += start.elapsed();
        }
        Ok(())
    }

    /// Per-stage wall times (s), in pipeline order; a stage that times its parts
    /// ([`Stage::part_times`]) gives one entry per part.
    pub fn times(&self) -> Vec<(String, f64)> {
        let mut times = Vec::with_capacity(self.stages.len());
        for (stage, &time) in self.stages.iter().zip(&self.times) {
            let parts = stage.part_times();
            if parts.is_empty() {
                times.push((stage.name().to_string(), time.as_secs_f64()));
            }
            for (name, time) in parts {
                times.push((name.to_string(), time.as_secs_f64()));
            }
        }
        times
    }
}
