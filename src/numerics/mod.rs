//! Numerics: loops over the grid. The time step is a pipeline of [`Stage`]s built
//! from the scenario (Garres-Díaz et al. 2021, §3, Escalante et al. 2023, §4): hyperbolic → friction or viscous
//! (→ projection).
//!
//! A stage is written for one grid type and one state type (`Stage<Line,
//! LayeredState>`, `Stage<CurvedLine, TwoLayerState>`): its face loops are that grid's.
//! This module imports the grid floor (`grid/`), the states (`state/`) and `physics/`,
//! never `model/` or `scenario/`; long inner loops also read the Ctrl-C flag
//! ([`crate::interrupt`]) and give up the step with [`StageError::Interrupted`].

pub mod banded;
pub mod bed_normal;
pub mod dilatant;
pub mod face;
pub mod friction;
pub mod friction_2d;
pub mod hydrostatic;
pub mod hydrostatic_2d;
pub mod layers_2d;
pub mod linalg;
pub mod line_bed_normal;
pub mod muscl;
pub mod muscl_2d;
pub mod nh_heun;
pub mod nh_multilayer;

pub mod nonhydrostatic;
pub mod projection;
pub mod ssp_rk2;
pub mod tracer;
pub mod two_layer;
pub mod viscous;
pub mod viscous_2d;
pub mod viscous_columns;
pub mod water_nh;
pub mod workers;

/// Why a stage could not complete a step. The place is a physical cell index (0-based,
/// as [`crate::grid::Grid::centre`] takes it); the run loop turns it into a position.
#[derive(Debug, Clone, PartialEq)]
pub enum StageError {
    /// The step would make h negative in `cell`: retry with a smaller Δt.
    NegativeThickness { cell: usize, h: f64 },
    /// The step would leave the model's admissible states in `cell` (e.g. a volume
    /// fraction outside (0, 1)): the run fails, naming the place and the quantity.
    Inadmissible {
        cell: usize,
        quantity: &'static str,
        value: f64,
    },
    /// Ctrl-C or SIGTERM arrived inside a long step (e.g. thousands of stabilisation
    /// sub-steps): the run loop restores the state of t^n and ends the run as
    /// interrupted, without waiting for the step to finish.
    Interrupted,
}

/// How many iterations of a long inner loop run between two looks at the Ctrl-C flag
/// (one atomic load each time).
pub const INTERRUPT_CHECK_EVERY: usize = 64;

/// Whether a long inner loop at iteration `k` should give up its step: every
/// [`INTERRUPT_CHECK_EVERY`] iterations, whether Ctrl-C or SIGTERM was received.
#[inline]
pub fn interrupted_at(k: usize) -> bool {
    k % INTERRUPT_CHECK_EVERY == INTERRUPT_CHECK_EVERY - 1 && crate::interrupt::requested()
}

/// One sub-step of the splitting scheme, on grid `G`, acting on a model's state `S`.
pub trait Stage<G, S>: Send {
    /// Stable name, used for the stage timers (`time_<name>_s`).
    fn name(&self) -> &'static str;
    /// Called once per time step, before any stage is applied, with the state at t^n
    /// (again when a step is retried). Stages whose coefficients are frozen at t^n
    /// (the multilayer viscous step) compute them here; the default does nothing.
    fn prepare(&mut self, _grid: &G, _state: &S) {}
    /// Called once per step attempt, before [`prepare`](Self::prepare), with the step
    /// `dt_full` that the stability condition allows: the step applied is shorter when it
    /// was shortened to land on an output time (`dt_full` = the applied step otherwise).
    /// A stage that turns an increment of the step into a rate uses it (the projection's
    /// pressure, [`projection::ProjectionStage`]); the default ignores it.
    fn full_step(&mut self, _dt_full: f64) {}
    /// Advances `state` by `dt`. On error the state may be left part-way: the run loop
    /// restores the state of t^n before it retries or fails.
    fn apply(&mut self, grid: &G, dt: f64, state: &mut S) -> Result<(), StageError>;
}
