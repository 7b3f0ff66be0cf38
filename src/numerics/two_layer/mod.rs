//! The two-layer submarine-avalanche scheme of seed 004 §4.1, one time step:
//!
//! 1. W*_i = W_i − Δt/Δx (𝒟𝓕⁺_{i−1/2} + 𝒟𝓕⁻_{i+1/2})  (eq. 72–83, [`face`]);
//! 2. Q₂ⁿ⁺¹_i from Q₂*_i by the Coulomb stopping rule (eq. 84–85, [`coulomb`]).
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
pub mod geometry;

pub use geometry::TwoLayerGeometry;

use crate::mesh::BoundaryKind;
use crate::physics::two_layer::{TwoLayerParams, H_DRY_TWO_LAYER};
use face::{face_flux, face_speeds, CellView, FaceOut};

/// Two-layer state with one ghost cell on each side (length nx + 2).
#[derive(Debug, Clone, PartialEq)]
pub struct TwoLayerState {
    pub h1: Vec<f64>,
    pub q1: Vec<f64>,
    pub h2: Vec<f64>,
    pub q2: Vec<f64>,
}

impl TwoLayerState {
    pub fn zeros(nx: usize) -> Self {
        TwoLayerState {
            h1: vec![0.0; nx + 2],
            q1: vec![0.0; nx + 2],
            h2: vec![0.0; nx + 2],
            q2: vec![0.0; nx + 2],
        }
    }

    pub fn nx(&self) -> usize {
        self.h1.len() - 2
    }

    /// Fills the ghosts: a wall mirrors thicknesses and reverses discharges; a free
    /// boundary copies the edge state (zero gradient).
    pub fn fill_ghosts(&mut self, geom: &TwoLayerGeometry) {
        let nx = self.nx();
        for (ghost, edge, kind) in [(0, 1, geom.left), (nx + 1, nx, geom.right)] {
            let sign = match kind {
                BoundaryKind::Wall => -1.0,
                BoundaryKind::Outflow => 1.0,
            };
            self.h1[ghost] = self.h1[edge];
            self.h2[ghost] = self.h2[edge];
            self.q1[ghost] = sign * self.q1[edge];
            self.q2[ghost] = sign * self.q2[edge];
        }
    }

    /// Volume Σ H_k Δx of layer k ∈ {1, 2} over the physical cells.
    pub fn volume(&self, layer: usize, dx: f64) -> f64 {
        let h = if layer == 1 { &self.h1 } else { &self.h2 };
        h[1..=self.nx()].iter().sum::<f64>() * dx
    }

    /// Water free surface η = b + (H₁ + H₂) cos²θ at physical cell i (1-based).
    pub fn eta(&self, geom: &TwoLayerGeometry, i: usize) -> f64 {
        geom.b[i] + (self.h1[i] + self.h2[i]) * geom.cos2[i]
    }

    /// Interface ζ = b + H₂ cos²θ at physical cell i (1-based).
    pub fn interface(&self, geom: &TwoLayerGeometry, i: usize) -> f64 {
        geom.b[i] + self.h2[i] * geom.cos2[i]
    }
}

/// The two-layer hyperbolic + Coulomb step, with its face buffers.
#[derive(Debug)]
pub struct TwoLayerSolver {
    pub params: TwoLayerParams,
    pub cfl: f64,
    /// Per cell with ghosts (nx + 2): the cells as the faces see them, built once per
    /// step by [`Self::max_speed`].
    views: Vec<CellView>,
    /// Per face (nx + 1): speed bounds and the face outputs.
    s_l: Vec<f64>,
    s_r: Vec<f64>,
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

impl TwoLayerSolver {
    pub fn new(params: TwoLayerParams, cfl: f64, nx: usize) -> Self {
        TwoLayerSolver {
            params,
            cfl,
            s_l: vec![0.0; nx + 1],
            s_r: vec![0.0; nx + 1],
            faces: vec![FaceOut::default(); nx + 1],
            views: Vec::with_capacity(nx + 2),
            drain: vec![1.0; nx + 2],
            limited_steps: 0,
            film: FILM_THICKNESS,
        }
    }

    /// Computes the face speed bounds of `state` (ghosts filled) and returns the
    /// largest |λ| (0 when both layers are absent everywhere).
    pub fn max_speed(&mut self, geom: &TwoLayerGeometry, state: &TwoLayerState) -> f64 {
        let p = &self.params;
        self.views.clear();
        self.views.extend((0..geom.nx + 2).map(|i| {
            CellView::new(
                p,
                state.h1[i],
                state.q1[i],
                state.h2[i],
                state.q2[i],
                geom.b[i],
                geom.cos[i],
                geom.cos2[i],
                geom.sin[i],
            )
        }));
        let mut smax = 0.0f64;
        for ((pair, sl), sr) in self.views.windows(2).zip(&mut self.s_l).zip(&mut self.s_r) {
            let (a, b) = face_speeds(p, &pair[0], &pair[1]);
            *sl = a;
            *sr = b;
            smax = smax.max(a.abs()).max(b.abs());
        }
        smax
    }

    /// Advances `state` by one step of at most `dt_max` and returns the Δt taken
    /// (CFL-limited). Ghosts are filled on entry and on exit.
    pub fn step(&mut self, geom: &TwoLayerGeometry, state: &mut TwoLayerState, dt_max: f64) -> f64 {
        state.fill_ghosts(geom);
        let smax = self.max_speed(geom, state);
        let dt = if smax > 0.0 {
            (self.cfl * geom.dx / smax).min(dt_max)
        } else {
            dt_max
        };
        self.advance(geom, state, dt);
        dt
    }

    /// Advances `state` by exactly `dt` (the caller has chosen it from the CFL
    /// condition on the same speed bounds, [`crate::model::submarine::signal_speed`]).
    pub fn step_with(&mut self, geom: &TwoLayerGeometry, state: &mut TwoLayerState, dt: f64) {
        state.fill_ghosts(geom);
        self.max_speed(geom, state);
        self.advance(geom, state, dt);
    }

    /// Both sub-steps with a given Δt (speed bounds from [`Self::max_speed`] on this state).
    fn advance(&mut self, geom: &TwoLayerGeometry, state: &mut TwoLayerState, dt: f64) {
        let nx = geom.nx;
        let dx = geom.dx;
        for (j, pair) in self.views.windows(2).enumerate() {
            self.faces[j] = face_flux(
                &self.params,
                &pair[0],
                &pair[1],
                self.s_l[j],
                self.s_r[j],
                dt,
                dx,
            );
        }
        let lam = dt / dx;
        let limited_1 = self.limit_layer(&state.h1, lam, nx, true);
        let limited_2 = self.limit_layer(&state.h2, lam, nx, false);
        if limited_1 || limited_2 {
            self.limited_steps += 1;
        }
        for i in 1..=nx {
            let (fl, fr) = (&self.faces[i - 1], &self.faces[i]);
            let h1 = state.h1[i] - lam * (fr.phi1 - fl.phi1);
            let h2 = state.h2[i] - lam * (fr.phi2 - fl.phi2);
            // The limiter leaves at most a round-off negative residue.
            state.h1[i] = h1.max(0.0);
            state.h2[i] = h2.max(0.0);
            state.q1[i] = if state.h1[i] > H_DRY_TWO_LAYER {
                desingularise(
                    state.h1[i],
                    state.q1[i] - lam * (fl.d2_plus + fr.d2_minus),
                    self.film,
                )
            } else {
                0.0
            };
            state.q2[i] = if state.h2[i] > H_DRY_TWO_LAYER {
                desingularise(
                    state.h2[i],
                    state.q2[i] - lam * (fl.d4_plus + fr.d4_minus),
                    self.film,
                )
            } else {
                0.0
            };
        }
        state.fill_ghosts(geom);
        coulomb::coulomb_step(&self.params, geom, state, dt);
        state.fill_ghosts(geom);
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
    pub geometry: TwoLayerGeometry,
}

impl crate::numerics::Stage<TwoLayerState> for TwoLayerStage {
    fn name(&self) -> &'static str {
        "two_layer"
    }

    fn apply(
        &mut self,
        _mesh: &crate::mesh::Mesh,
        dt: f64,
        state: &mut TwoLayerState,
    ) -> Result<(), crate::numerics::StageError> {
        // Both sub-steps keep H ≥ 0 by construction (draining limiter): no retry needed.
        self.solver.step_with(&self.geometry, state, dt);
        Ok(())
    }
}
