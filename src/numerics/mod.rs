//! Numerics: loops over the grid. The time step is a pipeline of [`Stage`]s built
//! from the scenario (seed 000 §3, seed 003 §4): hyperbolic → friction (→ projection).

pub mod cfl;
pub mod friction;
pub mod hydrostatic;
pub mod linalg;
pub mod nonhydrostatic;
pub mod projection;

use crate::mesh::Mesh;
use crate::state::State;

/// Why a stage could not complete a step.
#[derive(Debug, Clone, PartialEq)]
pub enum StageError {
    /// The step would make h negative at x: retry with a smaller Δt.
    NegativeThickness { x: f64, h: f64 },
}

/// One sub-step of the splitting scheme.
pub trait Stage: Send {
    /// Stable name, used for the stage timers (`time_<name>_s`).
    fn name(&self) -> &'static str;
    /// Advances `state` by `dt`. On error the state must be left unchanged.
    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError>;
}
