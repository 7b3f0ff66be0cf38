//! Step 3 of the splitting: the non-hydrostatic pressure correction (Garres-Díaz et al. 2021, §3
//! step 3, eq. 25–28; Escalante et al. 2023, §4 step 3, eq. 26–33).
//!
//! An incremental projection: with the pressure increment p̃ = p^{n+1} − p^n at the
//! staggered faces, the discharges are corrected by the implicit pressure force and p̃
//! is chosen so that the incompressibility constraint holds at t^{n+1}:
//!
//!   U^{n+1} = U^{n+2/3} + Δt 𝒯(p̃),   𝒞(U^{n+1}) = 0   at every face.
//!
//! The unknown is the impulse Π = Δt p̃, so the matrix does not depend on Δt. The stage
//! is generic over two parts, so the multilayer model (Escalante et al. 2023) reuses it:
//!
//! - a [`ProjectionOperator`]: the discrete constraint and the discrete correction of
//!   one model. It forms A Π = −𝒞(U^{n+2/3}), one block of unknowns per face (m = 1 for
//!   the monolayer of Garres-Díaz et al. 2021, m = N for the N-layer model, whose matrix (32) is
//!   block-tridiagonal when ordered face-major), hands it row by row
//!   ([`PressureRows`]) to the solver, and applies the correction of the solution;
//! - a [`PressureSolver`] for that row type: [`ThomasSolver`] for scalar rows (exact,
//!   O(nx)); a block-Thomas or the block Gauss–Seidel solver of Escalante et al. 2023, §4 implements
//!   the same trait for N×N blocks (it may store the rows first, e.g. in a
//!   [`BlockTridiagonal`](super::linalg::BlockTridiagonal), to sweep them repeatedly).
//!
//! A is assembled as the product of the discrete constraint and the discrete correction
//! ("discrete projection"), so after the correction the discrete constraint holds to
//! round-off — see `docs/numerics.md` for how this relates to the printed stencil of
//! eq. (28).

pub mod monolayer;
pub mod multilayer;

use super::linalg::{thomas_rows, PressureRows, ScalarRow};
use super::{Stage, StageError};
use crate::grid::Line;
use crate::state::layered::LayeredState;

/// Solves the (block-)tridiagonal pressure system of one projection, given row by row.
pub trait PressureSolver: Send + std::fmt::Debug {
    /// The row type it solves ([`ScalarRow`] for one unknown per face).
    type Row;
    /// Writes the solution into `x` (one block per face, 0 outside `rows.active()`).
    fn solve<R: PressureRows<Row = Self::Row>>(&mut self, rows: &R, x: &mut [f64]);
}

/// Exact O(n) solve of a scalar tridiagonal system: the Thomas algorithm run from both
/// ends, on the active rows only, forming each row as it eliminates it.
#[derive(Debug, Default)]
pub struct ThomasSolver {
    scratch: Vec<f64>,
}

impl PressureSolver for ThomasSolver {
    type Row = ScalarRow;

    fn solve<R: PressureRows<Row = ScalarRow>>(&mut self, rows: &R, x: &mut [f64]) {
        self.scratch.resize(x.len(), 0.0);
        thomas_rows(rows, x, &mut self.scratch);
    }
}

/// The discrete constraint and correction of one non-hydrostatic model.
pub trait ProjectionOperator: Send + std::fmt::Debug {
    /// Row type of its system (what its [`PressureSolver`] must solve).
    type Row;

    /// Unknowns per face (the number of layers whose base pressure is unknown).
    fn block(&self) -> usize;

    /// Forms the system A Π = −𝒞(U) for the impulses Π = Δt p̃ at the nx + 1 faces
    /// from the state after friction, and solves it with `solver` into `pi`. Rows that
    /// carry no constraint (dry faces, outflow boundaries) are conditions on Π instead.
    fn solve<S: PressureSolver<Row = Self::Row>>(
        &mut self,
        mesh: &Line,
        state: &LayeredState,
        solver: &mut S,
        pi: &mut [f64],
    );

    /// Applies the correction of the impulses `pi` to the discharges (hu, hw) of
    /// `state` (h has not changed since [`solve`](Self::solve)), and advances the
    /// pressure, p ← p + Π/Δt, resetting it to 0 on faces without a constraint.
    fn correct(&mut self, mesh: &Line, state: &mut LayeredState, pi: &[f64], dt: f64);
}

/// The "projection" stage: form and solve the pressure system, correct.
#[derive(Debug)]
pub struct ProjectionStage<O: ProjectionOperator, S: PressureSolver<Row = O::Row>> {
    operator: O,
    solver: S,
    pi: Vec<f64>,
}

impl<O: ProjectionOperator, S: PressureSolver<Row = O::Row>> ProjectionStage<O, S> {
    pub fn new(operator: O, solver: S, nx: usize) -> Self {
        let m = operator.block();
        ProjectionStage {
            operator,
            solver,
            pi: vec![0.0; (nx + 1) * m],
        }
    }

    /// The impulses Π = Δt p̃ of the last projection (face-major).
    pub fn last_impulse(&self) -> &[f64] {
        &self.pi
    }
}

impl<O: ProjectionOperator, S: PressureSolver<Row = O::Row>> Stage<Line, LayeredState>
    for ProjectionStage<O, S>
{
    fn name(&self) -> &'static str {
        "projection"
    }

    fn apply(&mut self, mesh: &Line, dt: f64, state: &mut LayeredState) -> Result<(), StageError> {
        self.operator
            .solve(mesh, state, &mut self.solver, &mut self.pi);
        self.operator.correct(mesh, state, &self.pi, dt);
        Ok(())
    }
}
