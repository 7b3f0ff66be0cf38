//! Step 3 of the splitting: the non-hydrostatic pressure correction (seed 000 §3
//! step 3, eq. 25–28; seed 003 §4 step 3, eq. 26–33).
//!
//! An incremental projection: with the pressure increment p̃ = p^{n+1} − p^n at the
//! staggered faces, the discharges are corrected by the implicit pressure force and p̃
//! is chosen so that the incompressibility constraint holds at t^{n+1}:
//!
//!   U^{n+1} = U^{n+2/3} + Δt 𝒯(p̃),   𝒞(U^{n+1}) = 0   at every face.
//!
//! The unknown is the impulse Π = Δt p̃, so the matrix does not depend on Δt. The stage
//! is generic over two parts, so the multilayer model (seed 003) reuses it:
//!
//! - a [`ProjectionOperator`]: the discrete constraint and the discrete correction of
//!   one model. It assembles A Π = −𝒞(U^{n+2/3}) as a [`BlockTridiagonal`] system with
//!   one block of unknowns per face (m = 1 for the monolayer of seed 000, m = N for the
//!   N-layer model, whose matrix (32) is block-tridiagonal when ordered face-major), and
//!   applies the correction of a solution;
//! - a [`PressureSolver`] for that system: [`ThomasSolver`] for m = 1 (exact, O(nx));
//!   a block-Thomas or block Gauss–Seidel solver (seed 003 §4) implements the same trait
//!   for m > 1.
//!
//! A is assembled as the product of the discrete constraint and the discrete correction
//! ("discrete projection"), so after the correction the discrete constraint holds to
//! round-off — see `docs/numerics.md` for how this relates to the printed stencil of
//! eq. (28).

pub mod monolayer;

use super::linalg::{thomas_two_sided, BlockTridiagonal};
use super::{Stage, StageError};
use crate::mesh::Mesh;
use crate::state::State;

/// Solves the (block-)tridiagonal pressure system of one projection.
pub trait PressureSolver: Send + std::fmt::Debug {
    /// Writes the solution of `system · x = system.rhs` into `x`
    /// (`system.rows · system.block` entries; 0 outside `system.active`).
    fn solve(&mut self, system: &BlockTridiagonal, x: &mut [f64]);
}

/// Exact O(n) solve of a scalar tridiagonal system (Thomas algorithm, run from both
/// ends, on the active rows only).
#[derive(Debug, Default)]
pub struct ThomasSolver {
    scratch: Vec<f64>,
}

impl PressureSolver for ThomasSolver {
    fn solve(&mut self, system: &BlockTridiagonal, x: &mut [f64]) {
        assert_eq!(system.block, 1, "the Thomas solver needs scalar blocks");
        let r = system.active.clone();
        self.scratch.resize(system.rows, 0.0);
        x[..r.start].fill(0.0);
        x[r.end..].fill(0.0);
        thomas_two_sided(
            &system.lower[r.clone()],
            &system.diag[r.clone()],
            &system.upper[r.clone()],
            &system.rhs[r.clone()],
            &mut x[r.clone()],
            &mut self.scratch[r],
        );
    }
}

/// The discrete constraint and correction of one non-hydrostatic model.
pub trait ProjectionOperator: Send + std::fmt::Debug {
    /// Unknowns per face (the number of layers whose base pressure is unknown).
    fn block(&self) -> usize;

    /// Assembles A Π = −𝒞(U) for the impulses Π = Δt p̃ at the nx + 1 faces from the
    /// state after friction. Rows that carry no constraint (dry faces, outflow
    /// boundaries) are replaced by conditions on Π.
    fn assemble(&mut self, mesh: &Mesh, state: &State, system: &mut BlockTridiagonal);

    /// Applies the correction of the impulses `pi` to the discharges (hu, hw) of
    /// `state`, with the coefficients of the last [`assemble`](Self::assemble) (h has
    /// not changed in between), and advances the pressure, p ← p + Π/Δt, resetting it
    /// to 0 on faces without a constraint.
    fn correct(&mut self, mesh: &Mesh, state: &mut State, pi: &[f64], dt: f64);
}

/// The "projection" stage: assemble, solve, correct.
#[derive(Debug)]
pub struct ProjectionStage<O: ProjectionOperator, S: PressureSolver> {
    operator: O,
    solver: S,
    system: BlockTridiagonal,
    pi: Vec<f64>,
}

impl<O: ProjectionOperator, S: PressureSolver> ProjectionStage<O, S> {
    pub fn new(operator: O, solver: S, nx: usize) -> Self {
        let m = operator.block();
        ProjectionStage {
            operator,
            solver,
            system: BlockTridiagonal::new(nx + 1, m),
            pi: vec![0.0; (nx + 1) * m],
        }
    }

    /// The impulses Π = Δt p̃ of the last projection (face-major).
    pub fn last_impulse(&self) -> &[f64] {
        &self.pi
    }
}

impl<O: ProjectionOperator, S: PressureSolver> Stage for ProjectionStage<O, S> {
    fn name(&self) -> &'static str {
        "projection"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError> {
        self.operator.assemble(mesh, state, &mut self.system);
        self.solver.solve(&self.system, &mut self.pi);
        self.operator.correct(mesh, state, &self.pi, dt);
        Ok(())
    }
}
