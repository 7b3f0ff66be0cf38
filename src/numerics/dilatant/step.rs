//! One time step of the dilatant model (Bouchut et al. 2021, §3): finite volumes (3.5) with the
//! Appendix B fluxes and the apparent-topography friction, the stabilisation
//! viscosity (3.20) sub-cycled, then the semi-implicit dilatancy step (3.17)/(3.18).
//!
//! Δt comes from the hyperbolic CFL condition alone, Δt ≤ CFL Δx / max(|v| + √(g_c h))
//! ([`DilatantScheme::max_dt`]); neither the stiff dilatancy source nor the viscosity
//! shortens it.
//!
//! Invariants, checked after every sub-step: φh ≥ 0 and 0 < φ < 1 in every cell. The
//! finite-volume step keeps φh ≥ 0 under the CFL condition (Theorem B.1 iv) and φ ≥
//! its minimum (viii), but not φ ≤ its maximum; a violation is returned as a
//! [`DilatantError`] naming the cell, x and t. [`DilatantScheme::step`], for a driver
//! of its own, then leaves the state as it was; the stage of a run does not copy it,
//! since the run loop restores the state of tⁿ. φh below zero by round-off only
//! (|φh| ≤ 1e-14 × the neighbouring φh) is set to 0.

use super::flux::{interface_flux, total_topography_jump, FaceGrid, FluxOptions};
use super::reconstruction::Side;
use super::source::{relax_fraction, DilatancyUpdate};
use super::stabilisation::{diffuse, Viscosity};
use crate::grid::Line;
use crate::numerics::{Stage, StageError, StepClock};
use crate::physics::dilatancy::{phi_from_ratio, DilatantLaw};
use crate::state::DilatantState;

/// A state that left the admissible set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DilatantError {
    #[error("negative grain mass φh = {m:e} in cell {cell} (x = {x} m) at t = {t} s")]
    NegativeMass { cell: usize, x: f64, t: f64, m: f64 },
    #[error("volume fraction φ = {phi} outside (0, 1) in cell {cell} (x = {x} m) at t = {t} s after the {stage} step")]
    FractionOutOfBounds {
        cell: usize,
        x: f64,
        t: f64,
        phi: f64,
        stage: &'static str,
    },
    #[error("non-finite value in cell {cell} (x = {x} m) at t = {t} s")]
    NonFinite { cell: usize, x: f64, t: f64 },
    #[error("the stabilisation would need {ratio:e} sub-steps in one step (dilatancy.xi too large) near x = {x} m at t = {t} s")]
    TooManySubsteps {
        cell: usize,
        x: f64,
        t: f64,
        ratio: f64,
    },
    #[error("interrupted (Ctrl-C or SIGTERM) during the stabilisation sub-steps")]
    Interrupted,
}

/// Which time step the dilatant model takes (`dilatancy.scheme`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SchemeKind {
    /// The Savage–Hutter μ(I) step with the φ-gradient pressure on its faces and φ
    /// carried by its mass fluxes, then the dilatant friction, dilatancy and
    /// stabilisation terms (`split.rs`).
    #[default]
    Split,
    /// Bouchut et al. 2021, §3 as printed: Appendix B fluxes with apparent-topography friction (this
    /// file).
    AppendixB,
}

/// Options of the scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DilatantOptions {
    pub scheme: SchemeKind,
    pub flux: FluxOptions,
    pub viscosity: Viscosity,
    pub update: DilatancyUpdate,
    pub cfl: f64,
    /// Thickness threshold (m) of Bouchut et al. 2021, §3.3 (split scheme): a layer thinner
    /// than this ("about tens of particles", below which the results are "physically
    /// meaningless") has no dilatancy: μ(I) friction without tan ψ and φ frozen. The
    /// scenario's default is [`DEFAULT_THIN_LAYER_GRAINS`] grain diameters; 0 here.
    pub h_thin: f64,
}

/// `dilatancy.thin_layer_grains` by default: the thickness threshold of Bouchut et al.
/// 2021, §3.3 ("about tens of particles") in grain diameters, the smallest such number.
pub const DEFAULT_THIN_LAYER_GRAINS: f64 = 10.0;

impl Default for DilatantOptions {
    fn default() -> Self {
        DilatantOptions {
            scheme: SchemeKind::default(),
            flux: FluxOptions::default(),
            viscosity: Viscosity::default(),
            update: DilatancyUpdate::Implicit,
            cfl: 0.5,
            h_thin: 0.0,
        }
    }
}

/// Counters of the last step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    pub viscosity_substeps: usize,
}

/// The dilatant stepper with its work arrays (allocated once).
#[derive(Debug)]
pub struct DilatantScheme {
    pub law: DilatantLaw,
    pub opt: DilatantOptions,
    /// Per face (nx + 1): left and right fluxes, Δz, v_interf.
    flux_left: Vec<[f64; 3]>,
    flux_right: Vec<[f64; 3]>,
    drive: Vec<f64>,
    rate: Vec<f64>,
    scratch: Vec<f64>,
    /// (m, q, w) at t^n, restored when a [`step`](Self::step) fails.
    backup: [Vec<f64>; 3],
}

impl DilatantScheme {
    pub fn new(law: DilatantLaw, opt: DilatantOptions, nx: usize) -> Self {
        DilatantScheme {
            law,
            opt,
            flux_left: vec![[0.0; 3]; nx + 1],
            flux_right: vec![[0.0; 3]; nx + 1],
            drive: vec![0.0; nx + 1],
            rate: vec![0.0; nx + 1],
            scratch: vec![0.0; nx + 1],
            backup: [vec![0.0; nx + 2], vec![0.0; nx + 2], vec![0.0; nx + 2]],
        }
    }

    /// The hyperbolic CFL bound CFL Δx / max(|v| + √(g_c h)) (∞ for a state at rest
    /// with no depth).
    pub fn max_dt(&self, mesh: &Line, s: &DilatantState) -> f64 {
        let speed = (1..=s.nx)
            .map(|j| s.v[j].abs() + (mesh.g_n * s.h[j]).sqrt())
            .fold(0.0, f64::max);
        if speed > 0.0 {
            self.opt.cfl * mesh.dx / speed
        } else {
            f64::INFINITY
        }
    }

    /// Advances `s` from t to t + dt. On error `s` is left as it was at t (for a driver
    /// without the run loop; the [`Stage`] advances without the copy).
    pub fn step(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        t: f64,
        dt: f64,
    ) -> Result<StepReport, DilatantError> {
        self.backup[0].copy_from_slice(&s.m);
        self.backup[1].copy_from_slice(&s.q);
        self.backup[2].copy_from_slice(&s.w);
        let result = self.advance(mesh, s, t, dt);
        if result.is_err() {
            s.m.copy_from_slice(&self.backup[0]);
            s.q.copy_from_slice(&self.backup[1]);
            s.w.copy_from_slice(&self.backup[2]);
            s.update_primitives(mesh);
        }
        result
    }

    fn advance(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        t: f64,
        dt: f64,
    ) -> Result<StepReport, DilatantError> {
        let t_end = t + dt;
        self.finite_volumes(mesh, s, dt);
        check_and_update(mesh, s, t_end, "finite-volume")?;
        let substeps = self.stabilise(mesh, s, dt).map_err(|ratio| {
            let Some(ratio) = ratio else {
                return DilatantError::Interrupted;
            };
            let k = self
                .drive
                .iter()
                .cloned()
                .enumerate()
                .fold((0, 0.0), |a, (k, d)| if d > a.1 { (k, d) } else { a });
            DilatantError::TooManySubsteps {
                cell: k.0.min(mesh.nx - 1),
                x: mesh.x[k.0.min(mesh.nx - 1)],
                t: t_end,
                ratio,
            }
        })?;
        if substeps > 0 {
            check_and_update(mesh, s, t_end, "stabilisation")?;
        }
        self.dilatancy(mesh, s, t_end, dt)?;
        s.fill_ghosts(mesh);
        for j in [0, s.nx + 1] {
            s.update_cell(j);
        }
        s.fill_dry_fractions();
        Ok(StepReport {
            viscosity_substeps: substeps,
        })
    }

    /// (3.5): U_i ← U_i − Δt/Δx (F_l(U_i, U_{i+1}, Δz_{i+1/2}) − F_r(U_{i−1}, U_i, Δz_{i−1/2})).
    fn finite_volumes(&mut self, mesh: &Line, s: &mut DilatantState, dt: f64) {
        let (nx, g_c, dx) = (s.nx, mesh.g_n, mesh.dx);
        let alpha = self.opt.flux.alpha;
        let side = |j: usize| Side {
            h: s.h[j],
            v: s.v[j],
            phi: s.phi[j],
        };
        for k in 0..=nx {
            let (l, r) = (side(k), side(k + 1));
            if l.h <= 0.0 && r.h <= 0.0 {
                self.flux_left[k] = [0.0; 3];
                self.flux_right[k] = [0.0; 3];
                self.drive[k] = 0.0;
                continue;
            }
            let db_hat = mesh.z[k + 1] - mesh.z[k];
            let grid = FaceGrid { g_c, dx, dt };
            let (dz, v) = total_topography_jump(&self.law, l, r, db_hat, grid, alpha);
            let f = interface_flux(l, r, dz, g_c, self.opt.flux);
            self.flux_left[k] = [f.left.m, f.left.q, f.left.w];
            self.flux_right[k] = [f.right.m, f.right.q, f.right.w];
            self.drive[k] = (v * dz).max(0.0);
        }
        let r = dt / dx;
        for i in 1..=nx {
            let (out, inn) = (self.flux_left[i], self.flux_right[i - 1]);
            s.m[i] -= r * (out[0] - inn[0]);
            s.q[i] -= r * (out[1] - inn[1]);
            s.w[i] -= r * (out[2] - inn[2]);
        }
    }

    /// (3.20)–(3.22), sub-cycled; returns the number of sub-steps (0 when off), or the
    /// stability ratio when it asks for too many (`None`: given up on Ctrl-C).
    fn stabilise(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
    ) -> Result<usize, Option<f64>> {
        let visc = self.opt.viscosity;
        if visc.is_off() {
            return Ok(0);
        }
        let drive = self.drive.iter().cloned().fold(0.0, f64::max);
        if drive == 0.0 {
            return Ok(0);
        }
        let n = visc.substeps(drive, dt, mesh.dx).map_err(Some)?;
        let r = dt / n as f64 / (mesh.dx * mesh.dx);
        for k in 0..n {
            if crate::numerics::interrupted_at(k) {
                return Err(None);
            }
            for (c, u) in [&mut s.m, &mut s.q, &mut s.w].into_iter().enumerate() {
                let xi = visc.xi[c];
                if xi == 0.0 {
                    continue;
                }
                for (rate, d) in self.rate.iter_mut().zip(&self.drive) {
                    *rate = r * xi * d;
                }
                diffuse(u, &self.rate, &mut self.scratch);
            }
            s.fill_ghosts(mesh);
        }
        Ok(n)
    }

    /// (3.15)–(3.19) in every wet cell; φ lands between φ* and φ_eq*, which is 0 only
    /// where f0 or f1 underflow (then the step is refused).
    fn dilatancy(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        t: f64,
        dt: f64,
    ) -> Result<(), DilatantError> {
        if self.law.k == 0.0 {
            return Ok(());
        }
        for j in 1..=s.nx {
            if s.m[j] <= 0.0 {
                continue;
            }
            let phi = relax_fraction(
                &self.law,
                self.opt.update,
                mesh.g_n,
                dt,
                s.h[j],
                s.v[j],
                s.phi[j],
            );
            if !(phi > 0.0 && phi < 1.0) {
                return Err(DilatantError::FractionOutOfBounds {
                    cell: j - 1,
                    x: mesh.x[j - 1],
                    t,
                    phi,
                    stage: "dilatancy",
                });
            }
            s.set_fraction(j, phi);
        }
        Ok(())
    }
}

/// φh ≥ 0 (round-off below zero is set to 0), 0 < φ < 1, all finite; updates (h, v, φ)
/// of the physical cells, the ghosts and the dry fractions (3.14).
fn check_and_update(
    mesh: &Line,
    s: &mut DilatantState,
    t: f64,
    stage: &'static str,
) -> Result<(), DilatantError> {
    let nx = s.nx;
    for j in 1..=nx {
        let x = mesh.x[j - 1];
        let (m, q, w) = (s.m[j], s.q[j], s.w[j]);
        if !(m.is_finite() && q.is_finite() && w.is_finite()) {
            return Err(DilatantError::NonFinite { cell: j - 1, x, t });
        }
        if m <= 0.0 {
            let scale = s.m[j - 1].abs().max(s.m[j + 1].abs());
            if m < -1e-14 * scale {
                return Err(DilatantError::NegativeMass {
                    cell: j - 1,
                    x,
                    t,
                    m,
                });
            }
            s.m[j] = 0.0;
            s.q[j] = 0.0;
            s.w[j] = 0.0;
        } else {
            let phi = phi_from_ratio(w / m, s.alpha);
            if !(phi > 0.0 && phi < 1.0) {
                return Err(DilatantError::FractionOutOfBounds {
                    cell: j - 1,
                    x,
                    t,
                    phi,
                    stage,
                });
            }
        }
        s.update_cell(j);
    }
    s.fill_ghosts(mesh);
    for j in [0, nx + 1] {
        s.update_cell(j);
    }
    s.fill_dry_fractions();
    Ok(())
}

/// The whole dilatant time step as one stage of the run loop. The loop does not pass
/// the time, so the error carries the cell, the quantity and its value; the loop adds
/// the position and t.
impl Stage<Line, DilatantState> for DilatantScheme {
    fn name(&self) -> &'static str {
        "dilatant"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut DilatantState,
    ) -> Result<(), StageError> {
        // On error the run loop restores the state of tⁿ: no copy of it here.
        match self.advance(mesh, state, clock.t, clock.dt) {
            Ok(_) => Ok(()),
            Err(DilatantError::NegativeMass { cell, m, .. }) => Err(StageError::Inadmissible {
                cell,
                quantity: "grain mass φh",
                value: m,
            }),
            Err(DilatantError::FractionOutOfBounds {
                cell, phi, stage, ..
            }) => Err(StageError::Inadmissible {
                cell,
                quantity: match stage {
                    "finite-volume" => "volume fraction φ (finite-volume step)",
                    "stabilisation" => "volume fraction φ (stabilisation step)",
                    _ => "volume fraction φ (dilatancy step)",
                },
                value: phi,
            }),
            Err(DilatantError::NonFinite { cell, .. }) => Err(StageError::Inadmissible {
                cell,
                quantity: "non-finite value",
                value: f64::NAN,
            }),
            Err(DilatantError::Interrupted) => Err(StageError::Interrupted),
            Err(DilatantError::TooManySubsteps { cell, ratio, .. }) => {
                Err(StageError::Inadmissible {
                    cell,
                    quantity: "stabilisation sub-steps needed in one step (dilatancy.xi too large)",
                    value: ratio,
                })
            }
        }
    }
}
