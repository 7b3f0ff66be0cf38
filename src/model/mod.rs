//! Models: what is simulated, apart from how the time loop runs it.
//!
//! A [`Model`] names its grid (the associated `Grid`, from `grid/`) and its conserved
//! variables (the associated `State`, from `state/`), and owns its diagnostics
//! (masses, energy, front, the signal speed of the CFL step) and its output fields.
//! Its physics (pointwise fluxes, wave speeds, sources) lives in `physics/`, its loops
//! over the grid are [`Stage`](crate::numerics::Stage)s of `numerics/` acting on its
//! state, and its scenario keys are validated by its own module (`scenario/` asks the
//! model, never the reverse). The run loop, [`Simulation`](crate::simulation::Simulation),
//! is generic over the model: adding a model is adding a module here (see
//! `docs/architecture.md`, "How to add a model").
//!
//! - [`granular`]: the layered family of Garres-Díaz et al. 2021, Fernández-Nieto et al. 2016 and Escalante et al. 2023 (Savage–Hutter with
//!   Coulomb or μ(I) friction, the multilayer μ(I) model, the weakly non-hydrostatic
//!   monolayer model).
//! - [`granular_2d`]: the Savage–Hutter model on a raster (x, y), Coulomb, μ(I) or
//!   Voellmy friction.
//! - [`submarine`]: the two-layer water-over-grains model of Fernández-Nieto et al. 2008, on a
//!   [`CurvedLine`](crate::grid::CurvedLine).
//! - [`dilatant`]: the compressible μ(I)–φ model of Bouchut et al. 2021 (volume fraction φ).

pub(crate) mod band_sums;
pub mod dilatant;
pub mod granular;
pub mod granular_2d;
pub mod layers_2d;
pub mod raster_maps;
pub mod submarine;
pub mod tracker;

use crate::grid::Grid;
use crate::numerics::workers::Workers;
use crate::output::{OutputError, OutputSink};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// The layered family: Savage–Hutter, multilayer, non-hydrostatic.
    Granular,
    /// Fernández-Nieto et al. 2008's two-layer water-over-grains model.
    Submarine,
    /// The compressible μ(I)–φ model with dilatancy (Bouchut et al. 2021).
    Dilatant,
}

impl ModelKind {
    /// The name of `model.kind` in scenarios and output files.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Granular => "granular",
            ModelKind::Submarine => "submarine",
            ModelKind::Dilatant => "dilatant",
        }
    }
}

/// What the run loop needs to know of a state after each step, from one pass over the
/// cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diagnostics {
    /// Volume of the main phase, ∫ h dx (m²).
    pub mass: f64,
    /// ∫ ½ h |u|² dx per unit density (m⁴/s²).
    pub kinetic_energy: f64,
    /// Largest speed of the material (m/s), for the rest test.
    pub max_speed: f64,
    /// Bound on the wave speeds that the hyperbolic step's fluxes use (m/s): the CFL
    /// step is CFL Δx / `signal_speed`.
    pub signal_speed: f64,
    /// Front position (m), NaN when no cell exceeds the front threshold.
    pub front_x: f64,
    pub h_max: f64,
    /// First cell (physical index) holding a non-finite value, if any.
    pub non_finite_at: Option<usize>,
    /// The cells holding material (h > [`H_DRY`](crate::physics::shallow::H_DRY)),
    /// for the wet fraction and the wet-cell rate of the progress line and the summary;
    /// `None` for a model that does not count them (the 1-D models).
    pub wet_cells: Option<usize>,
}

/// A simulated model: its grid, its state, its diagnostics and its output.
pub trait Model: Send + 'static {
    /// The grid its stages loop over.
    type Grid: Grid;
    /// The conserved variables (cell averages with ghost cells). `Clone` so that the
    /// run loop can keep the state of t^n (copied with `clone_from` into one buffer)
    /// and restore it when a step is refused.
    type State: Clone + Send;

    /// `model.kind`, as written to the output file.
    fn kind(&self) -> &'static str;

    /// Diagnostics of `state` in one pass over the cells.
    fn diagnose(&self, grid: &Self::Grid, state: &Self::State) -> Diagnostics;

    /// Copies `state` into `backup`, the run loop's state of t^n (kept every step, in
    /// case a stage refuses the step). The default is `clone_from`; a model whose
    /// state is large copies it on its run's threads.
    fn save_state(&self, backup: &mut Self::State, state: &Self::State) {
        backup.clone_from(state);
    }

    /// [`Self::diagnose`] of `state` and [`Self::save_state`] of it into `backup`: the
    /// run loop calls it after every accepted step, whose state is the next step's
    /// t^n, so that a model whose passes over the cells are parallel does both in one.
    /// The default does one after the other.
    fn diagnose_and_save(
        &self,
        grid: &Self::Grid,
        state: &Self::State,
        backup: &mut Self::State,
    ) -> Diagnostics {
        self.save_state(backup, state);
        self.diagnose(grid, state)
    }

    /// Largest speed (m/s) of a mass that counts as at rest (0: exactly at rest).
    fn rest_speed(&self) -> f64 {
        0.0
    }

    /// The cell updates of the run's steps so far, where a model's steps visit only part
    /// of its cells (a raster's active tiles, `state::tiles`); `None`: every step updates
    /// every cell.
    fn cell_updates(&self, _state: &Self::State) -> Option<u64> {
        None
    }

    /// Thickness of the initial erodible bed per cell (`/grid/h_bed`), zeros if none.
    fn bed_layer(&self) -> &[f64];

    /// The threads the model's stages run on, when it has more than one: the run loop
    /// then runs on one of them ([`Workers::install`]), so that a stage's parallel pass
    /// starts from a thread of the pool (no hand-off to the pool and no wake-up of the
    /// caller at its end). `None` (the default): the caller's thread.
    fn workers(&self) -> Option<&Workers> {
        None
    }

    /// Gauge values of physical cell `i` (0-based): (free-surface elevation, grain
    /// depth), in m. The run loop interpolates them linearly between cell centres
    /// ([`crate::gauges`]). `None` (the default): the model records no gauges, and a
    /// run that asks for them fails before its first step.
    fn gauge_cell(
        &self,
        _grid: &Self::Grid,
        _state: &Self::State,
        _i: usize,
    ) -> Option<(f64, f64)> {
        None
    }

    /// The cell (physical index, the first in cell order) where the speed counted in
    /// [`Diagnostics::max_speed`] is largest, or `None` (the default: the model does
    /// not say). Asked only when a run fails its speed bound
    /// ([`crate::stop::SpeedBound`]), to name the cell in the failure.
    fn fastest_cell(&self, _grid: &Self::Grid, _state: &Self::State) -> Option<usize> {
        None
    }

    /// For models with a water surface: the largest |η − η₀| over the cells wet now and
    /// at t = 0 (m), η₀ the initial surface. The run loop reports its maximum over time
    /// as the summary's `max_wave_amplitude`. `None` (the default): no water surface.
    fn wave_amplitude(&self, _grid: &Self::Grid, _state: &Self::State) -> Option<f64> {
        None
    }

    /// Hands the snapshot of `state` at time `t` to `sink`.
    fn snapshot(
        &self,
        grid: &Self::Grid,
        state: &Self::State,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError>;
}

/// The index of the first largest of `values` (NaN never counts), `None` when there
/// is none: the cell of [`Model::fastest_cell`].
pub fn first_maximum(values: impl Iterator<Item = f64>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (k, v) in values.enumerate() {
        if best.is_none_or(|(_, b)| v > b) && !v.is_nan() {
            best = Some((k, v));
        }
    }
    best.map(|(k, _)| k)
}
