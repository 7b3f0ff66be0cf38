//! The two-layer submarine-avalanche scheme of Fernández-Nieto et al. 2008, §4.1, one time step:
//!
//! 1. W*_i = W_i − Δt/Δx (𝒟𝓕⁺_{i−1/2} + 𝒟𝓕⁻_{i+1/2})  (eq. 72–83, [`face`]);
//! 2. Q₂ⁿ⁺¹_i from Q₂*_i by the Coulomb stopping rule (eq. 84–85, [`coulomb`]).
//!
//! Two passes over the mesh per step: the faces (each cell's view — velocities, √H,
//! its speed bounds — built once and carried to its second face, the face speed
//! bounds and fluxes in the same sweep), then the cell updates with step 2 applied to
//! each cell as soon as its Q₂* is known. The CFL speed ([`max_face_speed`]) is one
//! more sweep of the same views, done by the caller (the model's diagnostics, or
//! [`TwoLayerSolver::step`]).
//!
//! Δt from the CFL condition max |λ| Δt/Δx ≤ γ with the proven eigenvalue bounds of
//! [`crate::physics::two_layer::speed_bounds`].
//!
//! Positivity of both layers: if a step would take more of a layer out of a cell than
//! it holds (possible at wet/dry fronts, where the hydrostatic reconstruction and the
//! speed bounds stop matching), that layer's outgoing fluxes from the cell are scaled
//! to what it holds (draining-time limiter of Bollermann, Chen, Kurganov & Noelle
//! 2013), as in the monolayer scheme. Each face flux serves both neighbours, so each
//! layer's volume Σ H_k Δx stays exactly conserved.
//!
//! Hot loops are allocation-free: the solver owns its face buffers.

pub mod coulomb;
pub mod face;

use crate::grid::CurvedLine;
use crate::state::TwoLayerState;

use crate::physics::two_layer::{max_num, speed_bounds, TwoLayerParams, H_DRY_TWO_LAYER};
use face::{face_flux, face_speeds_with, roe_velocities, CellView, FaceOut, StepTerms};

/// The two-layer hyperbolic + Coulomb step, with its face buffers.
#[derive(Debug)]
pub struct TwoLayerSolver {
    pub params: TwoLayerParams,
    pub cfl: f64,
    /// Per face (nx + 1): the face outputs.
    faces: Vec<FaceOut>,
    /// Per cell with ghosts: draining factors (1 = no limiting).
    drain: Vec<f64>,
    /// Steps in which the positivity limiter acted (diagnostics).
    pub limited_steps: u64,
    /// Film thickness ε (m) of the velocity desingularisation ([`desingularise`]).
    pub film: f64,
}

/// Default film thickness ε of [`desingularise`] (m).
pub const FILM_THICKNESS: f64 = 1e-4;

/// Kurganov–Petrova desingularisation of the velocity of a layer thinner than ε:
/// Q ← H u_ε with u_ε = 2HQ/(H² + max(H², ε²)), i.e. Q · 2H²/(H² + ε²) below ε and Q
/// unchanged above. A film of a layer that lost its mass to a neighbour (the tail of a
/// slide, water pushed off the grains) otherwise keeps a momentum out of proportion
/// with its mass, and its speed (hundreds of m/s in
/// `fast_slide_into_shallow_water_and_film_over_moving_grains_stay_sane`) collapses Δt.
#[inline(always)]
pub fn desingularise(h: f64, q: f64, film: f64) -> f64 {
    if h >= film {
        q
    } else {
        q * 2.0 * h * h / (h * h + film * film)
    }
}

/// The per-cell arrays of a state and its geometry, cut to the same length nx + 2 up
/// front (no bounds checks in the loops).
struct Cells<'a> {
    h1: &'a [f64],
    q1: &'a [f64],
    h2: &'a [f64],
    q2: &'a [f64],
    b: &'a [f64],
    cos: &'a [f64],
    cos2: &'a [f64],
}

impl<'a> Cells<'a> {
    #[inline(always)]
    fn new(geom: &'a CurvedLine, s: &'a TwoLayerState) -> Self {
        let n = geom.line.nx + 2;
        Cells {
            h1: &s.h1[..n],
            q1: &s.q1[..n],
            h2: &s.h2[..n],
            q2: &s.q2[..n],
            b: &geom.line.b_ghost[..n],
            cos: &geom.cos[..n],
            cos2: &geom.cos2[..n],
        }
    }

    #[inline(always)]
    fn view(&self, p: &TwoLayerParams, i: usize) -> CellView {
        CellView::new(
            p,
            self.h1[i],
            self.q1[i],
            self.h2[i],
            self.q2[i],
            self.b[i],
            self.cos[i],
            self.cos2[i],
        )
    }
}

/// Calls `per_face(j, left, right, roe, s_l, s_r)` for every face j = 0..=nx of
/// `state` (ghosts filled) in order, with the cells' views built once each (carried
/// from a face to the next), the face's Roe velocities and its speed bounds S_L, S_R
/// (those of [`face::face_speeds`]).
#[inline(always)]
pub fn for_each_face(
    p: &TwoLayerParams,
    geom: &CurvedLine,
    state: &TwoLayerState,
    mut per_face: impl FnMut(usize, &CellView, &CellView, (f64, f64), f64, f64),
) {
    let n = geom.line.nx + 2;
    let faces = &geom.faces()[..n - 1];
    let cells = Cells::new(geom, state);
    let mut left = cells.view(p, 0);
    for (j, fg) in faces.iter().enumerate() {
        let right = cells.view(p, j + 1);
        let roe = roe_velocities(&left, &right);
        let (s_l, s_r) = face_speeds_with(p, fg.cos, &left, &right, roe.0, roe.1);
        per_face(j, &left, &right, roe, s_l, s_r);
        left = right;
    }
}

/// The largest |λ| of the face speed bounds of `state` (ghosts filled; 0 when both
/// layers are absent everywhere): the CFL speed of the scheme.
pub fn max_face_speed(p: &TwoLayerParams, geom: &CurvedLine, state: &TwoLayerState) -> f64 {
    sweep_speeds(p, geom, state, |_, _| {})
}

/// [`max_face_speed`], calling `per_cell(i, view)` for each physical cell i = 1..=nx on
/// the way (the model's diagnostics).
///
/// The face bounds are S_L = min(λ⁻_L, λ⁻_R, e), S_R = max(λ⁺_L, λ⁺_R, f) with (λ⁻, λ⁺)
/// the cells' bounds and (e, f) those at the face means ([`face::face_speeds`]). Since
/// λ⁻ ≤ λ⁺ and e ≤ f (also in floating point: c ≥ 0 and cos θ > 0), S_L ≤ S_R and
/// max(|S_L|, |S_R|) = max(−S_L, S_R) = max(−λ⁻_L, −λ⁻_R, −e, λ⁺_L, λ⁺_R, f): the largest
/// |λ| is the largest of −λ⁻, λ⁺ over the cells and of −e, f over the faces, the same
/// number without forming S_L, S_R.
#[inline(always)]
pub fn sweep_speeds(
    p: &TwoLayerParams,
    geom: &CurvedLine,
    state: &TwoLayerState,
    mut per_cell: impl FnMut(usize, &CellView),
) -> f64 {
    let nx = geom.line.nx;
    let faces = &geom.faces()[..nx + 1];
    let cells = Cells::new(geom, state);
    let mut left = cells.view(p, 0);
    let mut smax = max_num(max_num(0.0, -left.lo), left.hi);
    for (j, fg) in faces.iter().enumerate() {
        let right = cells.view(p, j + 1);
        smax = max_num(max_num(smax, -right.lo), right.hi);
        let (u1, u2) = roe_velocities(&left, &right);
        let (e, f) = speed_bounds(
            p,
            fg.cos,
            0.5 * (left.h1 + right.h1),
            0.5 * (left.h2 + right.h2),
            u1,
            u2,
        );
        smax = max_num(max_num(smax, -e), f);
        if j < nx {
            per_cell(j + 1, &right);
        }
        left = right;
    }
    smax
}

impl TwoLayerSolver {
    pub fn new(params: TwoLayerParams, cfl: f64, nx: usize) -> Self {
        TwoLayerSolver {
            params,
            cfl,
            faces: vec![FaceOut::default(); nx + 1],
            drain: vec![1.0; nx + 2],
            limited_steps: 0,
            film: FILM_THICKNESS,
        }
    }

    /// The largest |λ| of the face speed bounds of `state` (ghosts filled; 0 when both
    /// layers are absent everywhere), [`max_face_speed`].
    pub fn max_speed(&self, geom: &CurvedLine, state: &TwoLayerState) -> f64 {
        max_face_speed(&self.params, geom, state)
    }

    /// Advances `state` by one step of at most `dt_max` and returns the Δt taken
    /// (CFL-limited). Ghosts are filled on entry and on exit.
    pub fn step(&mut self, geom: &CurvedLine, state: &mut TwoLayerState, dt_max: f64) -> f64 {
        state.fill_ghosts(geom);
        let smax = self.max_speed(geom, state);
        let dt = if smax > 0.0 {
            (self.cfl * geom.line.dx / smax).min(dt_max)
        } else {
            dt_max
        };
        self.advance(geom, state, dt);
        dt
    }

    /// Advances `state` by exactly `dt` (the caller has chosen it from the CFL
    /// condition on the same speed bounds, [`max_face_speed`], as the submarine model's
    /// diagnostics do).
    pub fn step_with(&mut self, geom: &CurvedLine, state: &mut TwoLayerState, dt: f64) {
        state.fill_ghosts(geom);
        self.advance(geom, state, dt);
    }

    /// Both sub-steps with a given Δt, in two passes: the faces (views, speed bounds
    /// and fluxes in one sweep, with the check whether any cell would be drained),
    /// then the cell updates with the Coulomb rule of each cell applied as soon as its
    /// Q₂* is known (the rule is local to the cell).
    fn advance(&mut self, geom: &CurvedLine, state: &mut TwoLayerState, dt: f64) {
        let nx = geom.line.nx;
        let dx = geom.line.dx;
        let lam = dt / dx;
        let p = self.params;
        let film = self.film;
        let face_geom = &geom.faces()[..nx + 1];
        let faces = &mut self.faces[..nx + 1];
        let (h1, h2) = (&state.h1[..nx + 2], &state.h2[..nx + 2]);
        // Whether some cell would lose more of a layer than it holds (the draining
        // limiter's test, done for each cell as soon as both its faces are known).
        let terms = StepTerms::new(&p, dt, dx);
        let mut drained = false;
        // Φ₁, Φ₂ of the previous face (the left face of cell j).
        let mut phi_left = (0.0, 0.0);
        for_each_face(&p, geom, state, |j, l, r, roe, s_l, s_r| {
            let f = face_flux(&p, &face_geom[j], l, r, roe, s_l, s_r, &terms);
            if j > 0 {
                let out1 = lam * (max_num(f.phi1, 0.0) + max_num(-phi_left.0, 0.0));
                let out2 = lam * (max_num(f.phi2, 0.0) + max_num(-phi_left.1, 0.0));
                drained |= out1 > h1[j] || out2 > h2[j];
            }
            phi_left = (f.phi1, f.phi2);
            faces[j] = f;
        });
        if drained {
            let limited_1 = self.limit_layer(&state.h1, lam, nx, true);
            let limited_2 = self.limit_layer(&state.h2, lam, nx, false);
            if limited_1 || limited_2 {
                self.limited_steps += 1;
            }
        }
        let (cos_mean, dsin_dx) = geom.coulomb_terms();
        let s = state;
        let cells = s.h1[1..=nx]
            .iter_mut()
            .zip(&mut s.q1[1..=nx])
            .zip(s.h2[1..=nx].iter_mut().zip(&mut s.q2[1..=nx]))
            .zip(cos_mean[1..=nx].iter().zip(&dsin_dx[1..=nx]));
        for ((((h1, q1), (h2, q2)), (&cos_mean, &dsin_dx)), pair) in
            cells.zip(self.faces[..nx + 1].windows(2))
        {
            let (fl, fr) = (&pair[0], &pair[1]);
            let h1n = *h1 - lam * (fr.phi1 - fl.phi1);
            let h2n = *h2 - lam * (fr.phi2 - fl.phi2);
            // The limiter leaves at most a round-off negative residue.
            let (h1n, h2n) = (max_num(h1n, 0.0), max_num(h2n, 0.0));
            *h1 = h1n;
            *h2 = h2n;
            *q1 = if h1n > H_DRY_TWO_LAYER {
                desingularise(h1n, *q1 - lam * (fl.d2_plus + fr.d2_minus), film)
            } else {
                0.0
            };
            let q2n = if h2n > H_DRY_TWO_LAYER {
                desingularise(h2n, *q2 - lam * (fl.d4_plus + fr.d4_minus), film)
            } else {
                0.0
            };
            // Second step of §4.1 (eq. 84–85).
            *q2 = coulomb::coulomb_cell(&p, h1n, h2n, q2n, cos_mean, dsin_dx, dt);
        }
        s.fill_ghosts(geom);
    }

    /// Draining-time limiter for one layer: scales the face outputs of that layer
    /// where a donor cell would be emptied. Returns whether anything was scaled.
    fn limit_layer(&mut self, h: &[f64], lam: f64, nx: usize, water: bool) -> bool {
        let phi = |f: &FaceOut| if water { f.phi1 } else { f.phi2 };
        let mut any = false;
        self.drain[0] = 1.0;
        self.drain[nx + 1] = 1.0;
        for ((d, &hi), pair) in self.drain[1..=nx]
            .iter_mut()
            .zip(&h[1..=nx])
            .zip(self.faces.windows(2))
        {
            let out = lam * (phi(&pair[1]).max(0.0) + (-phi(&pair[0])).max(0.0));
            *d = if out > hi {
                any = true;
                (hi / out).max(0.0)
            } else {
                1.0
            };
        }
        if !any {
            return false;
        }
        for j in 0..=nx {
            let f = &mut self.faces[j];
            let donor = if phi(f) > 0.0 { j } else { j + 1 };
            let s = self.drain[donor];
            if s < 1.0 {
                if water {
                    f.phi1 *= s;
                    f.d2_minus *= s;
                    f.d2_plus *= s;
                } else {
                    f.phi2 *= s;
                    f.d4_minus *= s;
                    f.d4_plus *= s;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests;

/// The two-layer step as a pipeline stage: Δt comes from the simulation (CFL on the
/// model's signal speed, the same face bounds), both sub-steps of §4.1 run inside.
#[derive(Debug)]
pub struct TwoLayerStage {
    pub solver: TwoLayerSolver,
}

impl crate::numerics::Stage<CurvedLine, TwoLayerState> for TwoLayerStage {
    fn name(&self) -> &'static str {
        "two_layer"
    }

    fn apply(
        &mut self,
        grid: &CurvedLine,
        clock: crate::numerics::StepClock,
        state: &mut TwoLayerState,
    ) -> Result<(), crate::numerics::StageError> {
        // Both sub-steps keep H ≥ 0 by construction (draining limiter): no retry needed.
        self.solver.step_with(grid, state, clock.dt);
        Ok(())
    }
}
