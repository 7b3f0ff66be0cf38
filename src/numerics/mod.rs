//! Numerics: loops over the grid. The time step is a pipeline of [`Stage`]s built
//! from the scenario (seed 000 §3, seed 003 §4): hyperbolic → friction or viscous
//! (→ projection).

pub mod dilatant;
pub mod friction;
pub mod hydrostatic;
pub mod linalg;
pub mod nonhydrostatic;
pub mod projection;
pub mod tracer;
pub mod two_layer;
pub mod viscous;

use crate::mesh::Mesh;

/// Why a stage could not complete a step.
#[derive(Debug, Clone, PartialEq)]
pub enum StageError {
    /// The step would make h negative at x: retry with a smaller Δt.
    NegativeThickness { x: f64, h: f64 },
    /// The step would leave the model's admissible states at x (e.g. a volume fraction
    /// outside (0, 1)): the run fails, naming the place and the quantity.
    Inadmissible {
        x: f64,
        quantity: &'static str,
        value: f64,
    },
}

/// One sub-step of the splitting scheme, acting on a model's state `S`.
pub trait Stage<S>: Send {
    /// Stable name, used for the stage timers (`time_<name>_s`).
    fn name(&self) -> &'static str;
    /// Called once per time step, before any stage is applied, with the state at t^n
    /// (again when a step is retried). Stages whose coefficients are frozen at t^n
    /// (the multilayer viscous step) compute them here; the default does nothing.
    fn prepare(&mut self, _mesh: &Mesh, _state: &S) {}
    /// Advances `state` by `dt`. On error the state must be left unchanged.
    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut S) -> Result<(), StageError>;
}
