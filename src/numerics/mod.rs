//! Numerics: loops over the grid. The time step is a pipeline of [`Stage`]s built
//! from the scenario (Garres-Díaz et al. 2021, §3, Escalante et al. 2023, §4): hyperbolic → friction or viscous
//! (→ projection).
//!
//! A stage is written for one grid type and one state type (`Stage<Line,
//! LayeredState>`, `Stage<CurvedLine, TwoLayerState>`): its face loops are that grid's.
//! This module imports the grid floor (`grid/`), the states (`state/`) and `physics/`,
//! never `model/` or `scenario/`; long inner loops also read the Ctrl-C flag
//! ([`crate::interrupt`]) and give up the step with [`StageError::Interrupted`].

use std::time::Duration;

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

/// The times of one attempt at a time step, which every stage of it is given.
///
/// A step may be shorter than the stability condition allows: the run loop shortens it
/// to land on an output time or on t_end, and halves both on a retry. A stage that
/// turns an increment of the step into a rate takes the rate over `dt_full`
/// ([`rate_step`](Self::rate_step)); everything else advances by `dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepClock {
    /// tⁿ, the time at the start of the step (of the whole step, for the sub-steps of a
    /// stage made of several).
    pub t: f64,
    /// Δt, the step applied.
    pub dt: f64,
    /// The step the stability condition allows for this attempt: dt_full ≥ dt, equal
    /// when the step was not shortened (∞ when nothing moves).
    pub dt_full: f64,
}

impl StepClock {
    /// A step of `dt` from `t`, shortened from `dt_full`.
    pub fn new(t: f64, dt: f64, dt_full: f64) -> Self {
        StepClock { t, dt, dt_full }
    }

    /// A step of full length `dt` from `t` (`dt_full` = `dt`).
    pub fn at(t: f64, dt: f64) -> Self {
        StepClock::new(t, dt, dt)
    }

    /// The same step with `dt` and `dt_full` halved (a retry, or the second stage of
    /// Heun's method, R_{Δt/2}).
    pub fn halved(self) -> Self {
        StepClock::new(self.t, 0.5 * self.dt, 0.5 * self.dt_full)
    }

    /// The step to divide an impulse of this step by to make it a rate: `dt_full` when
    /// `dt` was shortened from it, else `dt` (also when `dt_full` is infinite: a mass
    /// at rest is no step to take a rate over).
    pub fn rate_step(&self) -> f64 {
        if self.dt_full > self.dt && self.dt_full.is_finite() {
            self.dt_full
        } else {
            self.dt
        }
    }
}

/// One sub-step of the splitting scheme, on grid `G`, acting on a model's state `S`.
///
/// Every call of one step attempt gets the same [`StepClock`]; anything that decides
/// the next step lives in the state `S`, so that the run loop's copy of the state of
/// tⁿ is all a refused step needs to be undone.
pub trait Stage<G, S>: Send {
    /// Stable name, used for the stage timers (`time_<name>_s`).
    fn name(&self) -> &'static str;
    /// Called once per step attempt, before any stage is applied, with the state at tⁿ.
    /// Stages whose coefficients are frozen at tⁿ (the multilayer viscous step) compute
    /// them here; the default does nothing.
    fn prepare(&mut self, _grid: &G, _clock: StepClock, _state: &S) {}
    /// Advances `state` by `clock.dt`. On error the state may be left part-way: the run
    /// loop restores the state of tⁿ before it retries or fails.
    fn apply(&mut self, grid: &G, clock: StepClock, state: &mut S) -> Result<(), StageError>;
    /// The stage's wall time in named parts, for a stage made of steps worth timing
    /// apart (the steps 2 and 3 of the N-layer non-hydrostatic model): the pipeline
    /// reports these instead of its own timer of the stage. The default: none.
    fn part_times(&self) -> Vec<(&'static str, Duration)> {
        Vec::new()
    }
}
