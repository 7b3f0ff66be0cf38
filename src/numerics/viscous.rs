//! Step 2 of the splitting for N > 1 layers: the implicit viscous step of the
//! multilayer μ(I) model (Escalante et al. 2023, eq. 23–25, Fernández-Nieto et al. 2016, eq. 25–28), with the total
//! thickness h fixed:
//!
//!   l_α (h u_α − (hu)*_α) = Δt (K_{α−1/2} − K_{α+1/2}) / ρ,     α = 1 … N,
//!   K_{α+1/2}/ρ = −ν_{α+1/2} (u_{α+1} − u_α) / h_{α+1/2},     h_{α+1/2} = ½(l_α + l_{α+1}) h,
//!   K_{N+1/2} = 0,
//!
//! where the new velocities u_α are implicit and the viscosities ν = η/ρ are frozen at
//! t^n (Escalante et al. 2023, "Step 2"), so each cell solves one N×N symmetric tridiagonal system
//! (Thomas algorithm). The shear stress is τ = ν ∂_z u with
//!
//!   ν = μ(I) p / R(s),   I = d_s s / √(p/ρ_s),   p/ρ = g_n h Σ_{β>α} l_β,
//!
//! s the strain rate: |∂_z u| = |u_{α+1} − u_α| / h_{α+1/2} (Fernández-Nieto et al. 2016, eq. 24–26), or with
//! the C-MSM correction √((∂_z u)² + (∂_X(u_α + u_{α+1}))²) (Fernández-Nieto et al. 2016, eq. 32). R is the
//! regularisation: R = √(s² + 4δ²) (Escalante et al. 2023, eq. 10, where ‖D‖ = s/2), or
//! R = max(s, μ p/ν_M), ν_M = 250 √(g h³) (Fernández-Nieto et al. 2016, eq. 6 and 25, η_M = ρ ν_M).
//!
//! At the bed, either
//! - Coulomb friction K_{1/2}/ρ = −μ(I_{1/2}) g_n ĥ sgn(u_1) with the basal shear rate
//!   u_1/h_1 (Fernández-Nieto et al. 2016, eq. 26 and 28). The solve eliminates the layers from the top down
//!   to one equation d u_1 = r − Δt σ s, s ∈ Sgn(u_1), which is solved exactly: u_1 = 0 if
//!   |r| ≤ Δt σ (friction stops the bottom layer but never reverses it), as in the
//!   monolayer friction step; or
//! - no slip: K_{1/2}/ρ = −ν_{1/2} 2u_1/h_1 (Fernández-Nieto et al. 2016, end of §3.3).
//!
//! The column's weight — the pressures p in ν and the basal friction — is that of its
//! own depth h_i: step 1 gives each cell the pressure source g_n h_i Δη/2 of each face
//! (`hydrostatic.rs`), so a column at rest below the repose slope is held by its basal
//! friction and its layers by their strength μ p without Escalante et al. 2023's ĥ of eq. (25)
//! (see `friction.rs` and docs/numerics.md).
//!
//! Sidewall friction in a channel of width W (optional): Jop's term μ_w (H − z)/W added
//! to μ at every interface and at the bed (Fernández-Nieto et al. 2016, eq. 30), or the layer force
//! −l_α h (2/W) μ_w p_α u_α / √(u_α² + δ_u²) with u_α^n in the denominator, which only
//! adds to the diagonal (Escalante et al. 2023, eq. 36).
//!
//! With the non-hydrostatic pressure of Escalante et al. 2023 (a state carrying `nh`), the pressures
//! are the total ones, p_{α+1/2}/ρ = g_n h Σ_{β>α} l_β + p^nh_{α+1/2} (Escalante et al. 2023, after
//! eq. 10), in the viscosities, the inertial numbers, the basal friction (eq. 11) and
//! the sidewall force (eq. 36), with p^nh at t^n averaged from the two faces of the
//! cell; a negative total pressure (grains lifted) gives no stress. Hydrostatic states
//! take the code path above unchanged.
//!
//! With `rheology.viscosity = "implicit"` ([`ViscosityTime::Implicit`]) every coefficient
//! above — ν_{α+1/2}, the inertial numbers, the basal μ_b and the layer sidewall term —
//! is taken at the new velocities instead of t^n: per column, R(u) = 0 with
//! R_α = l_α h u_α − l_α q*_α + Δt(σ_{α−1/2} − σ_{α+1/2}) [+ Δt μ_b p_b sgn(u_1)],
//! σ = ν(s) ∂_z u, the gradient of a convex column energy. It is solved from the frozen
//! solution by damped Newton (tangent couplings Δt σ'/h_{α+1/2}, the Coulomb bed
//! linearised inside the exact set-valued bottom solve, a line search on the energy,
//! Picard steps after a cut Newton step; with the δ form, a primal–dual tangent that
//! linearises R(s) σ̂ = μ p γ in a stress variable σ̂ carried along the iterations)
//! until every |R_α|/(l_α h) is within the
//! tolerance (m/s, plus round-off) or a full Newton correction is; a column that does
//! not get there within the iteration limit fails the step (docs/numerics.md).
//!
//! Cells thinner than [`THIN_LAYER`] are treated as one layer with Coulomb friction
//! (Escalante et al. 2023, Remark 2): the depth-averaged discharge gets the monolayer friction update
//! of `friction.rs` — μ at the new speed (backward Euler), whatever `rheology.viscosity`
//! is — and every layer moves with it. A cell dry at t^n and wetted by step 1 freezes its
//! coefficients from the state after step 1.

use super::viscous_columns::{column_fractions, eliminate_down, substitute_up, ColumnRheology};
use super::{Stage, StageError, StepClock};
use crate::grid::Line;
use crate::physics::rheology::coulomb_update;
use crate::physics::rheology::{BasalFriction, LocalFriction};
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::layered::LayeredState;

/// Thickness (m) below which a cell is solved as a monolayer (Escalante et al. 2023, Remark 2).
pub const THIN_LAYER: f64 = 1e-6;

/// Velocity regularisation (m/s) of the layer sidewall force when the viscosity is
/// regularised by the bound η_M (with δ regularisation, δ is used).
pub const SIDEWALL_DELTA_U: f64 = 1e-5;

/// Columns solved together (see `solve_columns`).
const LANES: usize = 4;

// The options are defined beside the column kernel that reads them (`viscous_columns`,
// which the line and the raster both call) and are the step's options here.
pub use super::viscous_columns::{
    BasalCondition, Regularization, Sidewall, SidewallForm, ViscosityTime, ViscousOptions,
};

/// The implicit viscous step, generic over the rheology (a constant μ or μ(I)).
#[derive(Debug)]
pub struct MultilayerViscousStep<L: BasalFriction + LocalFriction> {
    law: L,
    opts: ViscousOptions,
    layers: usize,
    /// Frozen at t^n, per cell (nx + 2) and slot (N), cell-major: slot 0 the bed
    /// (μ_b for Coulomb, ν_{1/2} for no slip), slot α the interface ν_{α+1/2}.
    frozen: Vec<f64>,
    /// Frozen layer sidewall coefficients (2/W) μ_w (p_α/ρ) / √(u_α² + δ_u²) (layer form).
    side: Vec<f64>,
    /// Σ_{β ≥ a} l_β for a = 0 … N (0-based layers): depth fraction above interface a,
    /// and 1/√ of it (a < N).
    above: Vec<f64>,
    inv_sqrt_above: Vec<f64>,
    /// 2/(l_{a−1} + l_a): 1/h_{α+1/2} in units of 1/h (a ≥ 1).
    inv_gap: Vec<f64>,
    /// Non-hydrostatic pressure over density at t^n at the interfaces α − 1/2 of each
    /// cell (mean of its faces), cell-major like `frozen`; empty for hydrostatic states.
    p_nh: Vec<f64>,
    /// Per-column scratch (N): velocities; per layer and lane, couplings
    /// Δt ν / h_{α+1/2}, reduced diagonal and rhs.
    velocity: Vec<f64>,
    coupling: Vec<[f64; LANES]>,
    diag: Vec<[f64; LANES]>,
    rhs: Vec<[f64; LANES]>,
    /// The discharges entering the step (`ViscosityTime::Implicit` only, else empty).
    saved: Vec<f64>,
    /// Implicit step only (else empty), per column (N): tangents dσ/dγ at the slots of
    /// `frozen`, the last accepted iterate, the solution of the linear solve, and the
    /// couplings, diagonal and right-hand side of that solve.
    tangent: Vec<f64>,
    current: Vec<f64>,
    trial: Vec<f64>,
    col_c: Vec<f64>,
    col_d: Vec<f64>,
    col_r: Vec<f64>,
    /// The residuals R_α of the last `evaluate` without the basal friction, and its
    /// basal friction impulse (the line search's directional derivatives).
    resid: Vec<f64>,
    bed_impulse: f64,
    /// The Newton direction (trial − current).
    direction: Vec<f64>,
    /// Implicit step only (else empty), per interface of the column: the stress
    /// variable σ̂ (over density), and at the last linearisation the shear γᵏ, the
    /// stress σ(γᵏ), the coupling coefficient used and the bound μ p.
    dual: Vec<f64>,
    dual_shear: Vec<f64>,
    dual_stress: Vec<f64>,
    dual_coef: Vec<f64>,
    dual_cap: Vec<f64>,
    stats: ImplicitStats,
}

/// Iteration counts of the implicit viscous step since construction
/// ([`MultilayerViscousStep::stats`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ImplicitStats {
    /// Columns solved (h ≥ [`THIN_LAYER`]), summed over the steps.
    pub columns: u64,
    /// Linear column solves, the first (frozen) one included.
    pub solves: u64,
    /// Most solves of one column in one step.
    pub max_solves: usize,
    /// Extra residual evaluations of the line search (beyond one per Newton step).
    pub line_search: u64,
    /// Picard steps taken where the line search failed.
    pub picard_steps: u64,
    /// Columns stopped by a Newton correction within the tolerance (the others by
    /// their residual).
    pub newton_stops: u64,
}

impl<L: BasalFriction + LocalFriction> MultilayerViscousStep<L> {
    pub fn new(law: L, nx: usize, l: &[f64], opts: ViscousOptions) -> Self {
        let n = l.len();
        assert!(n >= 2, "the viscous step is for N > 1 layers");
        let (above, inv_sqrt_above, inv_gap) = column_fractions(l);
        let implicit = |v: Vec<f64>| match opts.viscosity {
            ViscosityTime::Frozen | ViscosityTime::Lagged => Vec::new(),
            ViscosityTime::Implicit { .. } => v,
        };
        let layer_sidewall = matches!(
            opts.sidewall,
            Some(Sidewall {
                form: SidewallForm::Layer,
                ..
            })
        );
        MultilayerViscousStep {
            law,
            opts,
            layers: n,
            frozen: vec![0.0; (nx + 2) * n],
            side: if layer_sidewall {
                vec![0.0; (nx + 2) * n]
            } else {
                Vec::new()
            },
            above,
            inv_sqrt_above,
            inv_gap,
            p_nh: Vec::new(),
            velocity: vec![0.0; n],
            coupling: vec![[0.0; LANES]; n],
            diag: vec![[0.0; LANES]; n],
            rhs: vec![[0.0; LANES]; n],
            saved: implicit(vec![0.0; (nx + 2) * n]),
            tangent: implicit(vec![0.0; n]),
            current: implicit(vec![0.0; n]),
            trial: implicit(vec![0.0; n]),
            col_c: implicit(vec![0.0; n]),
            col_d: implicit(vec![0.0; n]),
            col_r: implicit(vec![0.0; n]),
            resid: implicit(vec![0.0; n]),
            bed_impulse: 0.0,
            direction: implicit(vec![0.0; n]),
            dual: implicit(vec![0.0; n]),
            dual_shear: implicit(vec![0.0; n]),
            dual_stress: implicit(vec![0.0; n]),
            dual_coef: implicit(vec![0.0; n]),
            dual_cap: implicit(vec![0.0; n]),
            stats: ImplicitStats::default(),
        }
    }

    /// Iteration counts of the implicit step so far (zero when frozen).
    pub fn stats(&self) -> ImplicitStats {
        self.stats
    }

    /// The column-local rheology shared with the raster (`viscous_columns.rs`).
    #[inline(always)]
    fn rheology(&self) -> ColumnRheology<'_, L> {
        ColumnRheology {
            law: self.law,
            opts: self.opts,
            above: &self.above,
            inv_sqrt_above: &self.inv_sqrt_above,
        }
    }

    /// Jop's sidewall friction μ_w (H − z)/W at depth `depth` below the surface.
    #[inline(always)]
    fn jop(&self, depth: f64) -> f64 {
        self.rheology().jop(depth)
    }

    /// ν = μ p / R(s): the frozen viscosity over density for strain rate `s`, friction
    /// `mu` and pressure over density `p`; `nu_max` = ν_M of the bound regularisation.
    #[inline(always)]
    fn viscosity(&self, mu: f64, p: f64, s: f64, nu_max: f64) -> f64 {
        self.rheology().viscosity(mu, p, s, nu_max)
    }

    /// The tangent dσ/dγ of the interface stress σ = ν(s) γ (over density) with respect
    /// to the shear γ = ∂_z u, for the viscosity `nu` = μ p / R(s) at the strain rate
    /// s = |γ| (or the C-MSM norm, s ≥ |γ|), `mu` = μ(I(s)) and `dmu_ds` = dμ/ds:
    /// ν + (γ²/s) dν/ds, with dν/ds = (p/R)(dμ/ds − μ s/R²) for the δ regularisation
    /// and (p/s)(dμ/ds − μ/s) or 0 (on the bound ν = ν_M) for the bound.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn tangent_of(
        &self,
        nu: f64,
        mu: f64,
        dmu_ds: f64,
        p: f64,
        s: f64,
        shear: f64,
        nu_max: f64,
    ) -> f64 {
        if s <= 0.0 || nu == 0.0 {
            return nu;
        }
        let dnu = match self.opts.regularization {
            Regularization::Delta { delta } => {
                let r2 = s * s + 4.0 * delta * delta;
                p * (dmu_ds - mu * s / r2) / r2.sqrt()
            }
            Regularization::Bound => {
                if s >= mu * p / nu_max {
                    p * (dmu_ds - mu / s) / s
                } else {
                    0.0
                }
            }
        };
        (nu + shear * shear / s * dnu).max(0.0)
    }

    /// Freezes the coefficients of one wet cell `i` at the state t^n, with the layer
    /// discharges `hu` (those of `state`, or of the last viscous solve for the
    /// non-hydrostatic model's lagged freezing).
    fn freeze_cell(&mut self, mesh: &Line, state: &LayeredState, hu: &[f64], i: usize) {
        let n = self.layers;
        let inv_h = 1.0 / state.h[i];
        for (u, q) in self.velocity.iter_mut().zip(&hu[i * n..(i + 1) * n]) {
            *u = q * inv_h;
        }
        self.freeze_loaded(mesh, &state.h, &state.l, hu, i);
    }

    /// [`Stage::prepare`] with the discharges `hu` in place of `state.hu` (h, the layer
    /// fractions and p^nh are those of `state`): the lagged freezing of
    /// [`crate::numerics::nh_multilayer::NhViscousProjection`].
    pub fn prepare_with_discharges(&mut self, mesh: &Line, state: &LayeredState, hu: &[f64]) {
        debug_assert_eq!(state.layers, self.layers);
        debug_assert_eq!(hu.len(), state.hu.len());
        let n = self.layers;
        if let Some(nh) = &state.nh {
            // p^nh at t^n at the cell centres: the mean of the two faces.
            self.p_nh.resize((mesh.nx + 2) * n, 0.0);
            for i in 1..=mesh.nx {
                // Slices of length n: no bounds check per layer (the loop vectorises).
                let (left, right) = (&nh.p[(i - 1) * n..][..n], &nh.p[i * n..][..n]);
                let cell = &mut self.p_nh[i * n..][..n];
                for ((p, &pl), &pr) in cell.iter_mut().zip(left).zip(right) {
                    *p = 0.5 * (pl + pr);
                }
            }
        }
        for i in 1..=mesh.nx {
            if state.h[i] > H_DRY {
                self.freeze_cell(mesh, state, hu, i);
            } else {
                // Dry at t^n: frozen when step 1 has wetted it (see `apply`).
                self.frozen[i * n] = f64::NAN;
            }
        }
    }

    /// Computes the coefficients of cell `i` (thicknesses `hs`, layer fractions `l`)
    /// for the velocities in `self.velocity`; the C-MSM x-derivative takes the
    /// neighbours' discharges from `around`.
    fn freeze_loaded(&mut self, mesh: &Line, hs: &[f64], l: &[f64], around: &[f64], i: usize) {
        let n = self.layers;
        let g_n = mesh.g_n;
        let h = hs[i];
        let inv_h = 1.0 / h;
        let base = i * n;
        // Pressures are those of the column's own depth, as the pressure force of step 1.
        let p_b = g_n * h;
        let scale = self.law.inertial_scale(p_b);
        let nu_max = self.rheology().nu_max(h);
        if !self.p_nh.is_empty() {
            self.freeze_cell_nonhydrostatic(mesh, hs, l, around, i, nu_max);
            return;
        }
        let u = &self.velocity;

        // The bed.
        let inv_h1 = inv_h / l[0];
        self.frozen[base] = match self.opts.basal {
            BasalCondition::Coulomb => {
                let shear = (u[0] * inv_h1).abs();
                if !self.tangent.is_empty() {
                    // dμ_b/d|u_1|.
                    self.tangent[0] = self.law.mu_slope_at(shear * scale) * scale * inv_h1;
                }
                self.rheology().bed(h, p_b, scale, nu_max, shear)
            }
            BasalCondition::NoSlip => {
                let shear = (2.0 * u[0] * inv_h1).abs();
                let nu = self.rheology().bed(h, p_b, scale, nu_max, shear);
                if !self.tangent.is_empty() {
                    let mu = self.law.mu_at(shear * scale) + self.jop(h);
                    let slope = self.law.mu_slope_at(shear * scale) * scale;
                    self.tangent[0] = self.tangent_of(nu, mu, slope, p_b, shear, shear, nu_max);
                }
                nu
            }
        };

        // Interfaces α + 1/2 between 0-based layers a − 1 and a.
        let inv_2dx = 0.5 / mesh.dx;
        for a in 1..n {
            let shear = (u[a] - u[a - 1]) * inv_h * self.inv_gap[a];
            let s = if self.opts.c_msm {
                let pair = |j: usize| {
                    let hj = hs[j];
                    velocity(hj, around[j * n + a - 1]) + velocity(hj, around[j * n + a])
                };
                let dx_sum = (pair(i + 1) - pair(i - 1)) * inv_2dx;
                (shear * shear + dx_sum * dx_sum).sqrt()
            } else {
                shear.abs()
            };
            let p = p_b * self.above[a];
            let (mu, nu) = self.rheology().interface(a, (h, p_b, scale, nu_max), s);
            self.frozen[base + a] = nu;
            if !self.tangent.is_empty() {
                let ds = scale * self.inv_sqrt_above[a];
                let slope = self.law.mu_slope_at(s * scale * self.inv_sqrt_above[a]) * ds;
                self.tangent[a] = self.tangent_of(nu, mu, slope, p, s, shear, nu_max);
            }
        }

        if let Some(Sidewall {
            mu_w,
            width,
            form: SidewallForm::Layer,
        }) = self.opts.sidewall
        {
            let du = match self.opts.regularization {
                Regularization::Delta { delta } => delta,
                Regularization::Bound => SIDEWALL_DELTA_U,
            };
            let side = &mut self.side[base..base + n];
            for (a, (side, l_a)) in side.iter_mut().zip(l).enumerate() {
                let p_mid = p_b * (self.above[a] - 0.5 * l_a);
                let ua = self.velocity[a];
                *side = 2.0 / width * mu_w * p_mid / (ua * ua + du * du).sqrt();
            }
        }
    }

    /// [`freeze_cell`](Self::freeze_cell) with the total pressures g_n h Σ_{β>α} l_β +
    /// p^nh_{α+1/2} (module documentation); `velocity` holds u^n.
    fn freeze_cell_nonhydrostatic(
        &mut self,
        mesh: &Line,
        hs: &[f64],
        l: &[f64],
        around: &[f64],
        i: usize,
        nu_max: f64,
    ) {
        let n = self.layers;
        let g_n = mesh.g_n;
        let h = hs[i];
        let inv_h = 1.0 / h;
        let base = i * n;
        let p_hydro = g_n * h;
        let pressure = |a: usize, p_nh: &[f64]| (p_hydro * self.above[a] + p_nh[base + a]).max(0.0);
        let u = &self.velocity;
        let inv_h1 = inv_h / l[0];
        let p_b = pressure(0, &self.p_nh);
        self.frozen[base] = match self.opts.basal {
            BasalCondition::Coulomb => {
                let shear = (u[0] * inv_h1).abs();
                if !self.tangent.is_empty() {
                    let ds = self.law.inertial_scale(p_b);
                    self.tangent[0] = self.law.mu_slope_at(shear * ds) * ds * inv_h1;
                }
                self.law.mu_at(shear * self.law.inertial_scale(p_b)) + self.jop(h)
            }
            BasalCondition::NoSlip => {
                let shear = (2.0 * u[0] * inv_h1).abs();
                let mu = self.law.mu_at(shear * self.law.inertial_scale(p_b)) + self.jop(h);
                let nu = self.viscosity(mu, p_b, shear, nu_max);
                if !self.tangent.is_empty() {
                    let ds = self.law.inertial_scale(p_b);
                    let slope = self.law.mu_slope_at(shear * ds) * ds;
                    self.tangent[0] = self.tangent_of(nu, mu, slope, p_b, shear, shear, nu_max);
                }
                nu
            }
        };
        let inv_2dx = 0.5 / mesh.dx;
        for a in 1..n {
            let shear = (u[a] - u[a - 1]) * inv_h * self.inv_gap[a];
            let s = if self.opts.c_msm {
                let pair = |j: usize| {
                    let hj = hs[j];
                    velocity(hj, around[j * n + a - 1]) + velocity(hj, around[j * n + a])
                };
                let dx_sum = (pair(i + 1) - pair(i - 1)) * inv_2dx;
                (shear * shear + dx_sum * dx_sum).sqrt()
            } else {
                shear.abs()
            };
            let p = pressure(a, &self.p_nh);
            let mu = self.law.mu_at(s * self.law.inertial_scale(p)) + self.jop(h * self.above[a]);
            let nu = self.viscosity(mu, p, s, nu_max);
            self.frozen[base + a] = nu;
            if !self.tangent.is_empty() {
                let ds = self.law.inertial_scale(p);
                let slope = self.law.mu_slope_at(s * ds) * ds;
                self.tangent[a] = self.tangent_of(nu, mu, slope, p, s, shear, nu_max);
            }
        }
        if let Some(Sidewall {
            mu_w,
            width,
            form: SidewallForm::Layer,
        }) = self.opts.sidewall
        {
            let du = match self.opts.regularization {
                Regularization::Delta { delta } => delta,
                Regularization::Bound => SIDEWALL_DELTA_U,
            };
            for (a, l_a) in l.iter().enumerate() {
                let top = if a + 1 < n {
                    self.p_nh[base + a + 1]
                } else {
                    0.0
                };
                let p_mid = (p_hydro * (self.above[a] - 0.5 * l_a)
                    + 0.5 * (self.p_nh[base + a] + top))
                    .max(0.0);
                let ua = self.velocity[a];
                self.side[base + a] = 2.0 / width * mu_w * p_mid / (ua * ua + du * du).sqrt();
            }
        }
    }

    /// Solves the columns of the cells `cells[..count]` (thickness h ≥ [`THIN_LAYER`])
    /// with the basal friction impulses Δt μ_b g_n ĥ (Coulomb) `impulses`. The columns
    /// are independent; solving [`LANES`] together interleaves their sequential Thomas
    /// recurrences (each layer waits for a division), which the processor then
    /// overlaps. Unused lanes repeat the last column and are not written back.
    fn solve_columns(
        &mut self,
        state: &mut LayeredState,
        cells: [usize; LANES],
        impulses: [f64; LANES],
        count: usize,
        dt: f64,
    ) {
        let n = self.layers;
        let l = &state.l;
        let (c, d, r) = (&mut self.coupling, &mut self.diag, &mut self.rhs);
        let h: [f64; LANES] = std::array::from_fn(|k| state.h[cells[k]]);
        let base: [usize; LANES] = std::array::from_fn(|k| cells[k] * n);
        let dt_over_h: [f64; LANES] = std::array::from_fn(|k| dt / h[k]);

        // c[a] couples layers a − 1 and a (c[0] unused). d[a] first holds the diagonal
        // without the couplings: the layer's own mass l_a h plus sidewall and no-slip
        // terms, all positive.
        c[0] = [0.0; LANES];
        for (a, (c, gap)) in c.iter_mut().zip(&self.inv_gap).enumerate().skip(1) {
            for k in 0..LANES {
                c[k] = dt_over_h[k] * self.frozen[base[k] + a] * gap;
            }
        }
        for a in 0..n {
            for k in 0..LANES {
                d[a][k] = l[a] * h[k];
                r[a][k] = l[a] * state.hu[base[k] + a];
            }
        }
        if !self.side.is_empty() {
            for a in 0..n {
                for k in 0..LANES {
                    d[a][k] += dt * l[a] * h[k] * self.side[base[k] + a];
                }
            }
        }
        if self.opts.basal == BasalCondition::NoSlip {
            for k in 0..LANES {
                d[0][k] += dt_over_h[k] * self.frozen[base[k]] * 2.0 / l[0];
            }
        }

        let hu = &mut state.hu;
        eliminate_column(c, d, r, self.opts.basal, impulses, |a, u| {
            for k in 0..count {
                hu[base[k] + a] = h[k] * u[k];
            }
        });
    }
}

/// Solves K column systems at once (lanes): couplings `c` (c[0] unused), diagonals `d`
/// without the couplings and right-hand sides `r`, per layer, with the bed condition
/// (`impulses`: the Coulomb threshold Δt σ of each column); `put(a, u)` receives the
/// new velocities of layer a, bottom first. `d` and `r` are overwritten.
///
/// Eliminates from the top down, to one equation for the bottom layer. The reduced
/// diagonal of layer a is e_a + c_a, with e_{a−1} = d_{a−1} + c_a e_a/(e_a + c_a):
/// written so, no coupling is subtracted from another, and a rigid column (couplings
/// ≫ l_a h, e.g. δ → 0 at rest) keeps its mass e ≈ Σ l h to round-off. d[a] then holds
/// 1/(e_a + c_a) for the back-substitution. The bottom equation d u_1 = r − Δt σ s,
/// s ∈ Sgn(u_1), is solved exactly ([`coulomb_update`]).
#[inline(always)]
fn eliminate_column<const K: usize>(
    c: &[[f64; K]],
    d: &mut [[f64; K]],
    r: &mut [[f64; K]],
    basal: BasalCondition,
    impulses: [f64; K],
    put: impl FnMut(usize, [f64; K]),
) {
    eliminate_down(c, d, r);
    let u_below: [f64; K] = std::array::from_fn(|k| match basal {
        BasalCondition::Coulomb => coulomb_update(r[0][k], impulses[k]) / d[0][k],
        BasalCondition::NoSlip => r[0][k] / d[0][k],
    });
    substitute_up(c, d, r, u_below, put);
}

impl<L: BasalFriction + LocalFriction> Stage<Line, LayeredState> for MultilayerViscousStep<L> {
    fn name(&self) -> &'static str {
        "viscous"
    }

    fn prepare(&mut self, mesh: &Line, _: StepClock, state: &LayeredState) {
        self.prepare_with_discharges(mesh, state, &state.hu);
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        let n = self.layers;
        let g_n = mesh.g_n;
        let implicit = match self.opts.viscosity {
            ViscosityTime::Frozen | ViscosityTime::Lagged => None,
            ViscosityTime::Implicit {
                tolerance,
                max_iterations,
            } => Some((tolerance, max_iterations)),
        };
        if implicit.is_some() {
            self.saved.copy_from_slice(&state.hu);
        }
        // Columns waiting to be solved together.
        let (mut cells, mut impulses, mut count) = ([0usize; LANES], [0.0; LANES], 0);
        for i in 1..=mesh.nx {
            let h = state.h[i];
            if h <= H_DRY {
                state.hu[i * n..(i + 1) * n].fill(0.0);
                continue;
            }
            if h < THIN_LAYER {
                let q = &mut state.hu[i * n..(i + 1) * n];
                let q_mean: f64 = q.iter().zip(&state.l).map(|(q, l)| q * l).sum();
                // The monolayer's friction step (`friction.rs`): μ at the new speed
                // whatever `rheology.viscosity` says for the columns (a film's μ(I)
                // at its incoming speed is μ_2, which overshoots and stops it).
                q.fill(self.law.friction_update(q_mean, h, dt, g_n));
                continue;
            }
            if self.frozen[i * n].is_nan() {
                // Dry at t^n, wetted by step 1: its coefficients come from this state.
                self.freeze_cell(mesh, state, &state.hu, i);
            }
            cells[count] = i;
            impulses[count] = self.impulse(i, h, g_n, dt);
            count += 1;
            if count == LANES {
                self.solve_columns(state, cells, impulses, count, dt);
                count = 0;
            }
        }
        if count > 0 {
            for k in count..LANES {
                (cells[k], impulses[k]) = (cells[count - 1], impulses[count - 1]);
            }
            self.solve_columns(state, cells, impulses, count, dt);
        }
        if let Some((tolerance, max_iterations)) = implicit {
            // Iterate every column to the equations with the coefficients at u^{n+1}.
            let saved = std::mem::take(&mut self.saved);
            let result = self.iterate(mesh, dt, state, &saved, tolerance, max_iterations);
            if result.is_err() {
                // A failed step leaves the state as it found it.
                state.hu.copy_from_slice(&saved);
            }
            self.saved = saved;
            result?;
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}

impl<L: BasalFriction + LocalFriction> MultilayerViscousStep<L> {
    /// The basal friction impulse Δt μ_b p_b of cell `i` (Coulomb bed) for the
    /// coefficients in `frozen`.
    #[inline(always)]
    fn impulse(&self, i: usize, h: f64, g_n: f64, dt: f64) -> f64 {
        let n = self.layers;
        if self.p_nh.is_empty() {
            dt * self.frozen[i * n] * g_n * h
        } else {
            dt * self.frozen[i * n] * (g_n * h + self.p_nh[i * n]).max(0.0)
        }
    }

    /// Computes the coefficients of cell `i` at the velocities in `velocity` and the
    /// residual of its column equations with them. Returns the largest over the layers
    /// of |R_α| / (l_α h) (m/s), whether every |R_α| ≤ `tolerance` l_α h + 8ε Σ|terms
    /// of R_α| (the tolerance plus the round-off of evaluating R_α), and
    /// Σ_α l_α (R_α / (l_α h))² for the line search. `q_star` holds the discharges
    /// entering the step.
    ///
    ///   R_α = d_α u_α + c_α (u_α − u_{α−1}) + c_{α+1} (u_α − u_{α+1}) − l_α q*_α
    ///         [+ Δt μ_b p_b sgn(u_1) for α = 1 with a Coulomb bed],
    ///
    /// with d_α = l_α h (1 + Δt s_α) (+ 2Δt ν_{1/2}/(l_1 h) for no slip),
    /// c_α = Δt ν_{α−1/2}/h_{α−1/2}, c_1 = c_{N+1} = 0. A Coulomb bed at rest (u_1 = 0)
    /// is in equilibrium when the rest of R_1 is within the friction impulse.
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
        &mut self,
        mesh: &Line,
        dt: f64,
        hs: &[f64],
        l: &[f64],
        q_star: &[f64],
        i: usize,
        tolerance: f64,
    ) -> (f64, bool, f64) {
        if self.opts.basal == BasalCondition::Coulomb && self.velocity[0].abs() <= tolerance {
            // A bottom layer slower than the tolerance is at rest (the line search
            // approaches a stop λ by λ, never reaching u_1 = 0 exactly).
            self.velocity[0] = 0.0;
        }
        self.freeze_loaded(mesh, hs, l, q_star, i);
        let n = self.layers;
        let h = hs[i];
        let base = i * n;
        let u = &self.velocity;
        let dt_over_h = dt / h;
        self.bed_impulse = 0.0;
        let coupling = |a: usize| {
            if a == 0 || a == n {
                0.0
            } else {
                dt_over_h * self.frozen[base + a] * self.inv_gap[a]
            }
        };
        let (mut worst, mut ok, mut norm) = (0.0f64, true, 0.0);
        for a in 0..n {
            let mut d = l[a] * h;
            if !self.side.is_empty() {
                d += dt * l[a] * h * self.side[base + a];
            }
            if a == 0 && self.opts.basal == BasalCondition::NoSlip {
                d += dt_over_h * self.frozen[base] * 2.0 / l[0];
            }
            let below = if a > 0 { u[a] - u[a - 1] } else { 0.0 };
            let above = if a + 1 < n { u[a] - u[a + 1] } else { 0.0 };
            let terms = [
                d * u[a],
                coupling(a) * below,
                coupling(a + 1) * above,
                -l[a] * q_star[base + a],
            ];
            let mut r: f64 = terms.iter().sum();
            let mut size: f64 = terms.iter().map(|t| t.abs()).sum();
            if !self.resid.is_empty() {
                self.resid[a] = r;
            }
            if a == 0 && self.opts.basal == BasalCondition::Coulomb {
                let impulse = self.impulse(i, h, mesh.g_n, dt);
                self.bed_impulse = impulse;
                size += impulse;
                r = if u[0] != 0.0 {
                    r + impulse * u[0].signum()
                } else {
                    r.signum() * (r.abs() - impulse).max(0.0)
                };
            }
            let scale = l[a] * h;
            worst = worst.max(r.abs() / scale);
            norm += l[a] * (r / scale) * (r / scale);
            ok &= r.abs() <= tolerance * scale + 8.0 * f64::EPSILON * size;
        }
        (worst, ok, norm)
    }

    /// φ'(λ) = R·Δ at the last `evaluate`, with the basal friction's one-sided
    /// derivative where the bottom layer is at rest.
    fn slope(&self) -> f64 {
        let mut g: f64 = self
            .resid
            .iter()
            .zip(&self.direction)
            .map(|(r, d)| r * d)
            .sum();
        let (u0, d0) = (self.velocity[0], self.direction[0]);
        let s = if u0 != 0.0 {
            u0.signum()
        } else if d0 != 0.0 {
            d0.signum()
        } else {
            0.0
        };
        g += self.bed_impulse * s * d0;
        g
    }

    /// The stress variable σ̂ after a step to `velocity` from the linearisation of
    /// the last `solve_single`: σ̂ = σ(γᵏ) + t (γ − γᵏ) (t the coupling coefficient
    /// of that solve: the tangent for Newton, ν for Picard), within ±μ p.
    fn update_dual(&mut self, h: f64) {
        let n = self.layers;
        let inv_h = 1.0 / h;
        for a in 1..n {
            let shear = (self.velocity[a] - self.velocity[a - 1]) * inv_h * self.inv_gap[a];
            let s = self.dual_stress[a] + self.dual_coef[a] * (shear - self.dual_shear[a]);
            self.dual[a] = s.clamp(-self.dual_cap[a], self.dual_cap[a]);
        }
    }

    /// `velocity` = current + λ direction.
    fn set_along(&mut self, lambda: f64) {
        for ((u, c), d) in self
            .velocity
            .iter_mut()
            .zip(&self.current)
            .zip(&self.direction)
        {
            *u = c + lambda * d;
        }
    }

    /// One linear solve of column `i` for the coefficients at the velocities in
    /// `velocity`, into `trial`: a Newton step (`newton`: the couplings are the
    /// tangents dσ/dγ and the linearisation σ(γ) ≈ σ(γᵏ) + σ'(γᵏ)(γ − γᵏ) leaves the
    /// explicit forces Δt (ν − σ') γᵏ), or a Picard step (the secant viscosities ν).
    /// The basal friction coefficient and the sidewall coefficients are those of the
    /// last iterate in both. The elimination is that of `solve_columns`.
    #[allow(clippy::too_many_arguments)]
    fn solve_single(
        &mut self,
        i: usize,
        h: f64,
        l: &[f64],
        q_star: &[f64],
        dt: f64,
        g_n: f64,
        newton: bool,
    ) {
        let n = self.layers;
        let base = i * n;
        let mut impulse = self.impulse(i, h, g_n, dt);
        // Newton on the Coulomb bed too: Δt p_b μ_b(|u_1|) ≈ impulse + k_b (|u_1| − |u_1ᵏ|),
        // k_b = Δt p_b dμ_b/d|u_1|, i.e. k_b on the diagonal and a lower threshold.
        let mut bed_stiffness = 0.0;
        if newton && self.opts.basal == BasalCondition::Coulomb {
            let p_b = if self.p_nh.is_empty() {
                g_n * h
            } else {
                (g_n * h + self.p_nh[base]).max(0.0)
            };
            bed_stiffness = dt * p_b * self.tangent[0];
            impulse = (impulse - bed_stiffness * self.velocity[0].abs()).max(0.0);
        }
        let inv_h = 1.0 / h;
        let dt_over_h = dt * inv_h;
        let Self {
            col_c: c,
            col_d: d,
            col_r: r,
            velocity: u,
            trial,
            tangent,
            frozen,
            dual,
            dual_shear,
            dual_stress,
            dual_coef,
            dual_cap,
            side,
            inv_gap,
            opts,
            ..
        } = self;
        let delta = match opts.regularization {
            Regularization::Delta { delta } if !opts.c_msm => Some(delta),
            _ => None,
        };
        for a in 1..n {
            let shear = (u[a] - u[a - 1]) * inv_h * inv_gap[a];
            let nu = frozen[base + a];
            let mut t = if newton { tangent[a] } else { nu };
            let stress = nu * shear;
            let mut cap = f64::INFINITY;
            if let Some(delta) = delta {
                let r2 = shear * shear + 4.0 * delta * delta;
                cap = nu * r2.sqrt();
                if newton {
                    // Primal-dual tangent: −γ σ(γ)/R² of dσ/dγ with σ̂ for σ(γ).
                    t = (t + shear * (stress - dual[a]) / r2).max(0.0);
                    tangent[a] = t;
                }
            }
            dual_shear[a] = shear;
            dual_stress[a] = stress;
            dual_coef[a] = t;
            dual_cap[a] = cap;
        }
        let coef = |a: usize| {
            if newton {
                tangent[a]
            } else {
                frozen[base + a]
            }
        };
        c[0] = 0.0;
        for a in 1..n {
            c[a] = dt_over_h * coef(a) * inv_gap[a];
        }
        for a in 0..n {
            d[a] = l[a] * h;
            if !side.is_empty() {
                d[a] += dt * l[a] * h * side[base + a];
            }
            r[a] = l[a] * q_star[base + a];
        }
        if newton {
            for a in 1..n {
                let shear = (u[a] - u[a - 1]) * inv_h * inv_gap[a];
                let force = dt * (frozen[base + a] - tangent[a]) * shear;
                r[a] -= force;
                r[a - 1] += force;
            }
        }
        d[0] += bed_stiffness;
        if opts.basal == BasalCondition::NoSlip {
            d[0] += dt_over_h * coef(0) * 2.0 / l[0];
            if newton {
                let shear = 2.0 * u[0] * inv_h / l[0];
                r[0] -= dt * (frozen[base] - tangent[0]) * shear;
            }
        }
        eliminate_column(
            c.as_chunks::<1>().0,
            d.as_chunks_mut::<1>().0,
            r.as_chunks_mut::<1>().0,
            opts.basal,
            [impulse],
            |a, u| trial[a] = u[0],
        );
    }

    /// The iterations of the implicit step on every column (h ≥ [`THIN_LAYER`]), from
    /// the first (frozen) solve that `apply` left in `state`: damped Newton on the
    /// column equations (module documentation), a Picard step when the line search
    /// fails, until [`evaluate`](Self::evaluate) accepts the iterate.
    fn iterate(
        &mut self,
        mesh: &Line,
        dt: f64,
        state: &mut LayeredState,
        q_star: &[f64],
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<(), StageError> {
        const LINE_SEARCH: usize = 12;
        let n = self.layers;
        let g_n = mesh.g_n;
        for i in 1..=mesh.nx {
            let h = state.h[i];
            if h < THIN_LAYER {
                continue;
            }
            let base = i * n;
            let inv_h = 1.0 / h;
            for (u, q) in self.velocity.iter_mut().zip(&state.hu[base..base + n]) {
                *u = q * inv_h;
            }
            let (hs, l) = (&state.h, &state.l);
            let (mut worst, mut ok, mut norm) =
                self.evaluate(mesh, dt, hs, l, q_star, i, tolerance);
            if !ok {
                // The stress variable starts at σ(γ) of the first iterate.
                for a in 1..n {
                    let shear = (self.velocity[a] - self.velocity[a - 1]) * inv_h * self.inv_gap[a];
                    self.dual[a] = self.frozen[base + a] * shear;
                }
            }
            let mut solves = 1;
            let mut newton = true;
            while !ok {
                if solves >= max_iterations {
                    return Err(StageError::Inadmissible {
                        cell: i - 1,
                        quantity: "residual (m/s) of the implicit viscous step after \
                                   rheology.viscosity_iterations solves (rheology.viscosity = \"implicit\")",
                        value: worst,
                    });
                }
                self.current.copy_from_slice(&self.velocity);
                self.solve_single(i, h, l, q_star, dt, g_n, newton);
                // Line search on the column's energy E (convex, ∇E = R): along the
                // Newton direction Δ, E(u + λΔ) is convex in λ with derivative
                // φ'(λ) = R(u + λΔ)·Δ, negative at 0 for a descent direction. The full
                // step is taken when φ'(1) ≤ 0; else φ' is bracketed (regula falsi)
                // until |φ'(λ)| ≤ |φ'(0)|/2.
                let mut step = 0.0f64;
                for ((d, t), c) in self
                    .direction
                    .iter_mut()
                    .zip(&self.trial)
                    .zip(&self.current)
                {
                    *d = t - c;
                    step = step.max(d.abs());
                }
                if newton && step <= tolerance {
                    // The full Newton correction is within the tolerance: take it and
                    // stop (where the shear is within δ of 0, the residual in m/s is
                    // that of a velocity difference amplified by Δt ν/(h_{α+1/2} l_α h),
                    // which for thin columns can exceed 10⁷).
                    self.velocity.copy_from_slice(&self.trial);
                    solves += 1;
                    self.stats.newton_stops += 1;
                    break;
                }
                let g0 = self.slope();
                let mut accepted = false;
                if g0 < 0.0 {
                    let (mut lo, mut g_lo, mut hi, mut g_hi) = (0.0, g0, 1.0, f64::NAN);
                    let mut lambda: f64 = 1.0;
                    for step in 0..=LINE_SEARCH {
                        self.set_along(lambda);
                        let (w, o, m) = self.evaluate(mesh, dt, hs, l, q_star, i, tolerance);
                        let g = self.slope();
                        if o || (step == 0 && g <= 0.0) || g.abs() <= 0.5 * g0.abs() {
                            (worst, ok, norm, accepted) = (w, o, m, true);
                            // A Newton step cut below 1/2 is followed by a Picard one.
                            newton = !newton || lambda >= 0.5;
                            break;
                        }
                        self.stats.line_search += 1;
                        if g < 0.0 {
                            (lo, g_lo) = (lambda, g);
                        } else {
                            (hi, g_hi) = (lambda, g);
                        }
                        let width = hi - lo;
                        lambda = if g_hi.is_nan() {
                            hi
                        } else {
                            (lo + width * g_lo / (g_lo - g_hi))
                                .clamp(lo + 0.05 * width, hi - 0.05 * width)
                        };
                    }
                    if !accepted && lo > 0.0 {
                        // E decreased up to λ = lo (φ' < 0 on [0, lo]).
                        self.set_along(lo);
                        (worst, ok, norm) = self.evaluate(mesh, dt, hs, l, q_star, i, tolerance);
                        accepted = true;
                        newton = !newton;
                    }
                }
                let _ = norm;
                if accepted {
                    self.update_dual(h);
                }
                if !accepted {
                    // Picard from the last iterate: re-freeze there, solve with ν.
                    self.velocity.copy_from_slice(&self.current);
                    self.evaluate(mesh, dt, hs, l, q_star, i, tolerance);
                    self.solve_single(i, h, l, q_star, dt, g_n, false);
                    self.velocity.copy_from_slice(&self.trial);
                    (worst, ok, norm) = self.evaluate(mesh, dt, hs, l, q_star, i, tolerance);
                    self.stats.picard_steps += 1;
                    newton = true;
                    self.update_dual(h);
                }
                solves += 1;
            }
            for (q, u) in state.hu[base..base + n].iter_mut().zip(&self.velocity) {
                *q = h * u;
            }
            self.stats.columns += 1;
            self.stats.solves += solves as u64;
            self.stats.max_solves = self.stats.max_solves.max(solves);
        }
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // index arithmetic mirrors the equations
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Coordinates};
    use crate::grid::{Line, LineSpec};
    use crate::physics::rheology::{Coulomb, MonolayerShear, MuI};
    use crate::physics::GRAVITY;

    fn mesh(cells: usize, slope_deg: f64) -> Line {
        let spec = LineSpec {
            x_min: 0.0,
            x_max: cells as f64 * 0.01,
            cells,
            slope_deg,
            coordinates: Coordinates::Local,
            left: BoundaryKind::Outflow,
            right: BoundaryKind::Outflow,
        };
        Line::new(&spec, vec![0.0; cells])
    }

    fn options(basal: BasalCondition) -> ViscousOptions {
        ViscousOptions {
            basal,
            regularization: Regularization::Delta { delta: 1e-5 },
            sidewall: None,
            c_msm: false,
            viscosity: ViscosityTime::Frozen,
        }
    }

    /// Dense Gaussian elimination of the column system written out in full.
    fn dense_solve(a: &mut [Vec<f64>], b: &mut [f64]) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            for i in k + 1..n {
                let m = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= m * a[k][j];
                }
                b[i] -= m * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
            x[i] = (b[i] - s) / a[i][i];
        }
        x
    }

    /// With no slip at the bed, the column solve is the linear system of the module
    /// docs; checked against a dense solve for uneven layers and sheared velocities.
    #[test]
    fn no_slip_column_matches_dense_solve() {
        let law = MuI {
            mu_s: 0.38,
            mu_2: 0.62,
            i0: 0.279,
            d_s: 0.04,
            phi: 0.62,
            shear: MonolayerShear::Bagnold,
        };
        let l = [0.1, 0.2, 0.3, 0.25, 0.15];
        let n = l.len();
        let m = mesh(3, 20.0);
        let h0 = 0.8;
        let u: Vec<f64> = (0..n).map(|a| 0.3 + 0.2 * a as f64 * a as f64).collect();
        let mut state = LayeredState::from_profiles(&m, &l, &[h0; 3], &[0.0; 3]);
        for j in 0..5 {
            for a in 0..n {
                state.hu[j * n + a] = h0 * u[a];
            }
        }
        let mut step = MultilayerViscousStep::new(law, 3, &l, options(BasalCondition::NoSlip));
        let dt = 0.01;
        let clock = StepClock::at(0.0, dt);
        step.prepare(&m, clock, &state);
        let frozen = step.frozen[2 * n..3 * n].to_vec();
        let q0: Vec<f64> = state.hu[2 * n..3 * n].to_vec();
        step.apply(&m, clock, &mut state).unwrap();

        let mut a = vec![vec![0.0; n]; n];
        let mut b = vec![0.0; n];
        for k in 0..n {
            a[k][k] = l[k] * h0;
            b[k] = l[k] * q0[k];
        }
        for k in 1..n {
            let c = dt * frozen[k] / (0.5 * (l[k - 1] + l[k]) * h0);
            a[k][k] += c;
            a[k - 1][k - 1] += c;
            a[k][k - 1] -= c;
            a[k - 1][k] -= c;
        }
        a[0][0] += dt * frozen[0] * 2.0 / (l[0] * h0);
        let exact = dense_solve(&mut a, &mut b);
        for k in 0..n {
            let got = state.hu[2 * n + k] / h0;
            assert!(
                (got - exact[k]).abs() < 1e-13,
                "layer {k}: {got} vs {}",
                exact[k]
            );
        }
        // Viscosity slows the fast top layer; the bed takes momentum out.
        assert!(state.hu[2 * n + n - 1] < q0[n - 1]);
        let total = |q: &[f64]| -> f64 { q.iter().zip(&l).map(|(q, l)| q * l).sum() };
        assert!(total(&state.hu[2 * n..3 * n]) < total(&q0));
    }

    /// Coulomb at the bed: a column whose impulse is below the friction threshold
    /// stops at the bed exactly; a faster one loses exactly the friction impulse
    /// Δt μ g_n h in its total momentum (viscous terms only exchange momentum).
    #[test]
    fn coulomb_bed_stops_or_brakes_exactly() {
        let law = Coulomb { mu: 0.5 };
        let l = [0.25; 4];
        let m = mesh(3, 0.0);
        let g_n = m.g_n;
        let h0 = 0.1;
        for (speed, stops) in [(1e-3, true), (2.0, false)] {
            let mut state = LayeredState::from_profiles(&m, &l, &[h0; 3], &[speed; 3]);
            // A sheared profile at t^n.
            for a in 0..4 {
                state.hu[2 * 4 + a] = h0 * speed * (1.0 + a as f64);
            }
            let mut step = MultilayerViscousStep::new(law, 3, &l, options(BasalCondition::Coulomb));
            let dt = 0.01;
            let clock = StepClock::at(0.0, dt);
            step.prepare(&m, clock, &state);
            let before: f64 = (0..4).map(|a| l[a] * state.hu[2 * 4 + a]).sum();
            step.apply(&m, clock, &mut state).unwrap();
            let after: f64 = (0..4).map(|a| l[a] * state.hu[2 * 4 + a]).sum();
            if stops {
                assert_eq!(state.hu[2 * 4], 0.0, "the bottom layer stops");
                assert!(after < before && after >= 0.0);
            } else {
                let lost = before - after;
                let impulse = dt * 0.5 * g_n * h0;
                assert!(
                    (lost - impulse).abs() < 1e-12 * before,
                    "{lost} vs {impulse}"
                );
                assert!(state.hu[2 * 4] > 0.0, "friction never reverses the flow");
            }
        }
    }

    /// The column residual (m/s per layer, |R_α| / (l_α h)) of the step's equations
    /// (module documentation) with every coefficient — the interface viscosities, the
    /// inertial numbers and the basal friction — at the velocities `u`, written out
    /// from the equations independently of the step's code, with the round-off bound
    /// 16ε Σ|terms| / (l_α h) of each.
    #[allow(clippy::too_many_arguments)]
    fn residual_at_new_speed(
        law: &MuI,
        l: &[f64],
        h: f64,
        g_n: f64,
        dt: f64,
        regularization: Regularization,
        basal: BasalCondition,
        q_star: &[f64],
        u: &[f64],
    ) -> Vec<(f64, f64)> {
        let n = l.len();
        // μ p / R(s): Escalante et al. 2023, eq. 10 or the bound of Fernández-Nieto et al. 2016, eq. 6.
        let nu = |mu: f64, p: f64, s: f64| match regularization {
            Regularization::Delta { delta } => mu * p / (s * s + 4.0 * delta * delta).sqrt(),
            Regularization::Bound => {
                let nu_max = 250.0 * (GRAVITY * h * h * h).sqrt();
                mu * p / s.max(mu * p / nu_max)
            }
        };
        // σ_a: stress over density on the interface below layer a (a ≥ 1).
        let sigma = |a: usize| -> f64 {
            let gap = 0.5 * (l[a - 1] + l[a]) * h;
            let gamma = (u[a] - u[a - 1]) / gap;
            let p = g_n * h * l[a..].iter().sum::<f64>();
            let mu = law.mu_local(gamma.abs(), p);
            nu(mu, p, gamma.abs()) * gamma
        };
        (0..n)
            .map(|a| {
                let mut terms = vec![l[a] * h * u[a], -l[a] * q_star[a]];
                if a > 0 {
                    terms.push(dt * sigma(a));
                }
                if a + 1 < n {
                    terms.push(-dt * sigma(a + 1));
                }
                let mut r: f64 = terms.iter().sum();
                let mut size: f64 = terms.iter().map(|t| t.abs()).sum();
                if a == 0 {
                    let h1 = l[0] * h;
                    match basal {
                        BasalCondition::Coulomb => {
                            let impulse = dt * law.mu_local(u[0].abs() / h1, g_n * h) * g_n * h;
                            size += impulse;
                            r = if u[0] != 0.0 {
                                r + impulse * u[0].signum()
                            } else {
                                (r.abs() - impulse).max(0.0)
                            };
                        }
                        BasalCondition::NoSlip => {
                            let gamma = 2.0 * u[0] / h1;
                            let p = g_n * h;
                            let mu = law.mu_local(gamma.abs(), p);
                            let t = dt * nu(mu, p, gamma.abs()) * gamma;
                            r += t;
                            size += t.abs();
                        }
                    }
                }
                let scale = l[a] * h;
                (r.abs() / scale, 16.0 * f64::EPSILON * size / scale)
            })
            .collect()
    }

    /// `rheology.viscosity = "implicit"`: the new velocities satisfy the column
    /// equations with the viscosities, inertial numbers and basal friction at the new
    /// speed to the tolerance (plus round-off), for a Coulomb and a no-slip bed, a
    /// sliding and a stopping bottom layer; the frozen step (coefficients at t^n)
    /// misses them by far on the same columns.
    #[test]
    fn implicit_step_satisfies_the_column_equations_at_the_new_speed() {
        let law = MuI {
            mu_s: 0.38,
            mu_2: 0.62,
            i0: 0.279,
            d_s: 0.7e-3,
            phi: 0.62,
            shear: MonolayerShear::Bagnold,
        };
        let l = [0.1, 0.2, 0.3, 0.25, 0.15];
        let n = l.len();
        let m = mesh(3, 20.0);
        let (h0, dt, tolerance) = (0.1, 5e-3, 1e-12);
        type Profile = fn(usize) -> f64;
        let profiles: [(&str, Profile); 2] = [
            ("sheared, sliding", |a| 0.3 + 0.2 * (a * a) as f64),
            ("slow, stopping", |a| 1e-3 * (1.0 + a as f64)),
        ];
        let cases = [
            (
                BasalCondition::Coulomb,
                Regularization::Delta { delta: 1e-5 },
            ),
            (
                BasalCondition::NoSlip,
                Regularization::Delta { delta: 1e-5 },
            ),
            (BasalCondition::Coulomb, Regularization::Bound),
        ];
        for (basal, regularization) in cases {
            for (name, profile) in profiles {
                let mut worst = [0.0f64; 2];
                for (k, viscosity) in [
                    ViscosityTime::Implicit {
                        tolerance,
                        max_iterations: 50,
                    },
                    ViscosityTime::Frozen,
                ]
                .into_iter()
                .enumerate()
                {
                    let mut state = LayeredState::from_profiles(&m, &l, &[h0; 3], &[0.0; 3]);
                    for j in 0..5 {
                        for a in 0..n {
                            state.hu[j * n + a] = h0 * profile(a);
                        }
                    }
                    let opts = ViscousOptions {
                        viscosity,
                        regularization,
                        ..options(basal)
                    };
                    let mut step = MultilayerViscousStep::new(law, 3, &l, opts);
                    let clock = StepClock::at(0.0, dt);
                    step.prepare(&m, clock, &state);
                    let q0 = state.hu[2 * n..3 * n].to_vec();
                    step.apply(&m, clock, &mut state).unwrap();
                    let u: Vec<f64> = state.hu[2 * n..3 * n].iter().map(|q| q / h0).collect();
                    let res = residual_at_new_speed(
                        &law,
                        &l,
                        h0,
                        m.g_n,
                        dt,
                        regularization,
                        basal,
                        &q0,
                        &u,
                    );
                    for (a, &(r, round_off)) in res.iter().enumerate() {
                        if k == 0 {
                            assert!(
                                r <= tolerance + round_off,
                                "{basal:?}, {regularization:?}, {name}, layer {a}: residual {r:e} (round-off {round_off:e})"
                            );
                        }
                        worst[k] = worst[k].max(r);
                    }
                    if k == 0 {
                        let stats = step.stats();
                        assert!(stats.solves > stats.columns, "{stats:?}: iterated");
                        println!("{basal:?}, {regularization:?}, {name}: {stats:?}, u = {u:.6?}");
                    }
                }
                println!(
                    "{basal:?}, {name}: residuals implicit {:e}, frozen {:e}",
                    worst[0], worst[1]
                );
                assert!(
                    worst[1] > 1e-6,
                    "{basal:?}, {name}: the frozen step differs ({worst:?})"
                );
            }
        }
    }

    /// A thin cell under μ(I) takes the monolayer's friction step (`friction.rs`, μ at
    /// the new speed) although the columns' coefficients are frozen at t^n. A 0.5 µm
    /// film has I = I_0 at ~1e-7 m/s; with Δt = 1e-8 s a film at 1.5e-7 m/s loses a
    /// third of its speed, and μ at the incoming speed (before: I = 0.32) overstates
    /// the friction of the speed it leaves with (I ≈ 0.22). The result is exactly what
    /// the monolayer step leaves for the same depth and mean discharge.
    #[test]
    fn thin_cells_take_the_monolayer_friction_step_at_the_new_speed() {
        use crate::numerics::friction::CoulombFrictionStep;
        let law = MuI {
            mu_s: 25.5f64.to_radians().tan(),
            mu_2: 36.0f64.to_radians().tan(),
            i0: 0.279,
            d_s: 0.7e-3,
            phi: 0.62,
            shear: MonolayerShear::Bagnold,
        };
        let l = [0.25, 0.75];
        let m = mesh(3, 30.0);
        let h0 = 0.5 * THIN_LAYER;
        let dt = 1e-8;
        let mut state = LayeredState::from_profiles(&m, &l, &[h0; 3], &[0.0; 3]);
        state.hu[2 * 2] = h0 * 0.6e-7;
        state.hu[2 * 2 + 1] = h0 * 1.8e-7;
        let q_mean = 0.25 * state.hu[2 * 2] + 0.75 * state.hu[2 * 2 + 1];
        let mut step = MultilayerViscousStep::new(law, 3, &l, options(BasalCondition::Coulomb));
        let clock = StepClock::at(0.0, dt);
        step.prepare(&m, clock, &state);
        step.apply(&m, clock, &mut state).unwrap();
        let mut mono = LayeredState::from_profiles(&m, &[1.0], &[h0; 3], &[0.0; 3]);
        mono.hu[2] = q_mean;
        CoulombFrictionStep::new(law)
            .apply(&m, clock, &mut mono)
            .unwrap();
        println!(
            "film {h0:e} m at {:.4} m/s: leaves at {:.6e} m/s (monolayer {:.6e})",
            q_mean / h0,
            state.hu[2 * 2] / h0,
            mono.hu[2] / h0
        );
        assert!(mono.hu[2] > 0.0, "the monolayer film keeps moving");
        assert_eq!(state.hu[2 * 2], mono.hu[2]);
        assert_eq!(state.hu[2 * 2 + 1], mono.hu[2]);
    }

    /// A thin cell is one Coulomb layer: every layer leaves with the mean discharge.
    #[test]
    fn thin_cells_fall_back_to_the_monolayer() {
        let law = Coulomb { mu: 0.1 };
        let l = [0.5, 0.5];
        let m = mesh(3, 0.0);
        let h0 = 0.5 * THIN_LAYER;
        let mut state = LayeredState::from_profiles(&m, &l, &[h0; 3], &[0.0; 3]);
        state.hu[2 * 2] = h0 * 1.0;
        state.hu[2 * 2 + 1] = h0 * 3.0;
        let mut step = MultilayerViscousStep::new(law, 3, &l, options(BasalCondition::Coulomb));
        let clock = StepClock::at(0.0, 1e-3);
        step.prepare(&m, clock, &state);
        step.apply(&m, clock, &mut state).unwrap();
        let expected = coulomb_update(h0 * 2.0, 1e-3 * 0.1 * m.g_n * h0);
        assert_eq!(state.hu[2 * 2], expected);
        assert_eq!(state.hu[2 * 2 + 1], expected);
    }
}
