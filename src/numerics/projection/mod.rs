//! Step 3 of the splitting: the non-hydrostatic pressure correction (Garres-Díaz et al. 2021, §3
//! step 3, eq. 25–28; Escalante et al. 2023, §4 step 3, eq. 26–33).
//!
//! An incremental projection: with the pressure increment p̃ = p^{n+1} − p^n at the
//! staggered faces, the discharges are corrected by the implicit pressure force and p̃
//! is chosen so that the incompressibility constraint holds at t^{n+1}:
//!
//!   U^{n+1} = U^{n+2/3} + Δt 𝒯(p̃),   𝒞(U^{n+1}) = 0   at every face.
//!
//! The unknown is the impulse Π = Δt p̃, so the matrix does not depend on Δt. A
//! projection has two parts ([`ProjectionStage`] runs any pair as a stage: the
//! monolayer's; the N-layer model of Escalante et al. 2023 runs its pair inside the
//! stage of its steps 2 and 3, [`super::nh_multilayer`], whose explicit terms use the
//! same operator):
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
//! **Shortened steps.** The impulse Π is not O(Δt) in general: the step before the
//! projection changes the discharges by amounts that do not shrink with Δt (the
//! implicit μ(I) viscous step of the multilayer model removes, whatever Δt, the shear
//! that the previous projection gave a column held by its friction; the friction step
//! of the monolayer stops cells and zeroes their hw), and the projection answers with
//! an impulse of the same size. Over steps of one length the stored p^{n+1} = p^n + Π/Δt
//! is the paper's; but a step shortened by 10³ to land on an output time turned that
//! impulse into a pressure 10³ times too large, which the next (full) step applied
//! explicitly, Δt p^{n+1}, and through the friction: the 10-layer run of Escalante et
//! al. 2023, §5.4 with snapshots every 4 ms failed after a step of 3.4 µs (Π/Δt = 39
//! where |p| ≤ 0.35 m²/s² elsewhere). So the pressure of a shortened step is p^n +
//! Π/Δt_full, with Δt_full the step the CFL condition allowed
//! ([`StepClock::rate_step`]): it is the paper's for a step of full length, and a step
//! shortened towards 0 leaves the pressure as it was. A pressure that evolves smoothly
//! then lags by at most one step's increment, which the next projection restores
//! (the increment is incremental), an O(Δt) error as the splitting's own.
//!
//! A is assembled as the product of the discrete constraint and the discrete correction
//! ("discrete projection"), so after the correction the discrete constraint holds to
//! round-off — see `docs/numerics.md` for how this relates to the printed stencil of
//! eq. (28).

pub mod monolayer;
pub mod multilayer;

use super::linalg::{thomas_rows, PressureRows, ScalarRow};
use super::{Stage, StageError, StepClock};

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

/// The shape of a projection's system, whatever its grid: the row type its
/// [`PressureSolver`] must solve and the unknowns per site.
pub trait PressureBlocks {
    /// Row type of its system (what its [`PressureSolver`] must solve).
    type Row;

    /// Unknowns per face (the number of layers whose base pressure is unknown).
    fn block(&self) -> usize;
}

/// The discrete constraint and correction of one non-hydrostatic model on grid `G`
/// with state `S`. The line's operators (`monolayer`, `multilayer`) give scalar and
/// block-tridiagonal rows; an operator on a raster implements this trait for
/// `Raster2d` with rows of its 2-D stencil (five blocks per face), and a solver for
/// them (multigrid or a sparse Cholesky) implements [`PressureSolver`] for that row
/// type: [`ProjectionStage`] runs either unchanged.
pub trait ProjectionOperator<G, S>: PressureBlocks + Send + std::fmt::Debug {
    /// Forms the system A Π = −𝒞(U) for the impulses Π = Δt p̃ at the faces
    /// from the state after friction, and solves it with `solver` into `pi`. Rows that
    /// carry no constraint (dry faces, outflow boundaries) are conditions on Π instead.
    fn solve<P: PressureSolver<Row = Self::Row>>(
        &mut self,
        grid: &G,
        state: &S,
        solver: &mut P,
        pi: &mut [f64],
    );

    /// Applies the correction of the impulses `pi` to the discharges (hu, hw) of
    /// `state` (h has not changed since [`solve`](Self::solve)), and advances the
    /// pressure, p ← p + Π/Δt_p, resetting it to 0 on faces without a constraint.
    /// `dt_p` is the step of the rate ([`StepClock::rate_step`]: the step taken, or the
    /// full step when the step taken was shortened to land on an output time).
    fn correct(&mut self, grid: &G, state: &mut S, pi: &[f64], dt_p: f64);
}

/// The "projection" stage: form and solve the pressure system, correct.
#[derive(Debug)]
pub struct ProjectionStage<O: PressureBlocks, P: PressureSolver<Row = O::Row>> {
    operator: O,
    solver: P,
    pi: Vec<f64>,
}

impl<O: PressureBlocks, P: PressureSolver<Row = O::Row>> ProjectionStage<O, P> {
    /// The stage on a line of `nx` cells (unknowns at its nx + 1 faces).
    pub fn new(operator: O, solver: P, nx: usize) -> Self {
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

impl<G, S, O, P> Stage<G, S> for ProjectionStage<O, P>
where
    O: ProjectionOperator<G, S>,
    P: PressureSolver<Row = O::Row>,
{
    fn name(&self) -> &'static str {
        "projection"
    }

    fn apply(&mut self, grid: &G, clock: StepClock, state: &mut S) -> Result<(), StageError> {
        self.operator
            .solve(grid, state, &mut self.solver, &mut self.pi);
        self.operator
            .correct(grid, state, &self.pi, clock.rate_step());
        Ok(())
    }
}
