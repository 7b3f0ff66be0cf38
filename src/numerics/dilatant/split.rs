//! The default time step of the dilatant model (`dilatancy.scheme = "split"`): the
//! Savage–Hutter μ(I) step of the monolayer model with the volume fraction carried by
//! its mass fluxes, then the terms of seed 002 that vanish for K = 0 and uniform φ.
//!
//! In the variables (h, hv, φ) the system (2.2)–(2.5) of seed 002 reads
//!
//!   ∂_t h + ∂_x(hv) = h γ̇ tan ψ                                              (2.5)
//!   ∂_t(hv) + ∂_x(hv² + ½ g_c h²) = −g_c h ∂_x b̂ − g_c h²/(2φ) ∂_x φ − μ_eff g_c h sgn(v)
//!                                   + hv γ̇ tan ψ                             (2.4 × h)
//!   ∂_t(φh) + ∂_x(φhv) = 0                                                   (2.3)
//!
//! i.e. shallow water in (h, hv) with three extra terms: the φ-gradient pressure, the
//! dilatant friction μ_eff = μ(I) + tan ψ (2.13–2.14) and the dilatancy source. One step:
//!
//! 1. **hyperbolic**: the monolayer's [`HydrostaticStep`] (seed 000 §3 step 1: HLL/PVM,
//!    hydrostatic reconstruction, Coulomb-aware ΔC) on (h, hv), called, not copied. For
//!    K = 0 its ΔC uses the Savage–Hutter μ(I) law (φ = `material.phi`). For K > 0 it
//!    takes the threshold per face ([`HydrostaticStep::apply_with_friction`]):
//!    μ_eff = μ(I) + μ_w h/W + tan ψ at the face's Roe speed and mean depth, with the
//!    mass-weighted φ of the two cells at t^n. The reconstruction and the cell friction
//!    below then hold the same masses: a layer at rest stays at rest (to round-off) iff
//!    its surface slope is below the static threshold μ_1 + K(φ − φ_stat) of (2.16),
//!    and moves above it (`tests/dilatant.rs`,
//!    `split_scheme::static_thresholds_follow_the_dilatant_friction`).
//! 2. **volume fraction** (2.3): φ rides the step's mass fluxes 𝓕 with the upwind
//!    value, written for φ rather than φh,
//!
//!      φ_i ← φ_i − Δt/Δx (𝓕_{i+1/2}(φ^up_{i+1/2} − φ_i) − 𝓕_{i−1/2}(φ^up_{i−1/2} − φ_i)) / h_i^{n+1},
//!
//!    which is the conservative upwind update of φh (h^{n+1} = h − Δt/Δx (𝓕_{i+1/2} −
//!    𝓕_{i−1/2})) rearranged: ∫φh is conserved to round-off, φ_i^{n+1} is a convex
//!    combination of φ_{i−1}, φ_i, φ_{i+1} while the outflow of a cell does not exceed
//!    its content, and a uniform φ stays uniform bit for bit (every difference is 0).
//!    Cells left with h = 0 keep their φ (seed 002 eq. 3.14 is not needed: the
//!    hyperbolic step never asks a dry cell for φ).
//! 3. **cell pass**: the φ-gradient pressure −g_c h²/(2φ) (φ_{i+1} − φ_{i−1})/(2Δx)
//!    (a neighbour with h ≤ 10⁻¹⁰ m counts with the cell's own φ); the friction step of
//!    the monolayer (`friction.rs`: the impulse Δt μ g_c h stops but never reverses) at
//!    the velocity after step 1 ([`cell_friction`]): μ(I) + μ_w h/W (4.1) for K = 0,
//!    μ_eff = μ(I) + μ_w h/W + tan ψ (2.13–2.14, cut at 0) for K > 0 (I of 2.10–2.11
//!    with the cell's φ). Taking μ after the gravity push is the Savage–Hutter step's
//!    O(Δt) splitting error: a uniform 28° flow (Δx = 5 mm) settles at I = 0.0486
//!    (K = 0) and 0.016 (K = 4.09, dense) against I* = 0.0728 (docs/numerics.md);
//!    then for K > 0 the semi-implicit dilatancy step (3.15)–(3.19) at the state after
//!    friction: φ from (3.17) or (3.18), φh and v kept, so h ← φh/φ and hv ← h v.
//! 4. **stabilisation** (K > 0 and ξ ≠ 0 only; off in the scenarios, the split scheme
//!    needs none; seed 002 §3.3 introduces it for its own scheme): (φh, φhv, φ^α h)
//!    diffuse with ι = max(0, ξ v Δz) (3.20–3.21), Δz = Δb̂ + Δx Proj_μ(X, v/(g_c Δt))
//!    (3.6–3.12), μ the mean of the two cells' μ_eff, on faces whose two cells are wet
//!    (h > 10⁻¹⁰ m): the viscosity never wets a dry cell, so it cannot spread films
//!    ahead of a deposit. Sub-cycled to meet (3.22).
//!
//! Steps 2–4 run over the cells that hold mass after step 1 only.
//!
//! With K = 0 and uniform φ, steps 2–4 change nothing (every φ difference is exactly 0,
//! tan ψ is not added, no dilatancy, no stabilisation) and step 3's friction performs
//! the operations of the monolayer's friction step with the same μ(I): the run is the
//! Savage–Hutter μ(I) run bit for bit (`tests/dilatant.rs`).
//!
//! Errors: a step that would make h negative is refused as the Savage–Hutter one is
//! (the run retries with a smaller Δt); φ outside (0, 1) after a sub-step is an error
//! naming the place and the stage. Either way the state is left as it was at t^n.

use super::flux::proj_friction;
use super::source::relax_towards;
use super::stabilisation::diffuse;
use super::state::DilatantState;
use super::step::DilatantOptions;
use crate::mesh::Mesh;
use crate::model::granular::state::LayeredState;
use crate::numerics::friction::coulomb_update;
use crate::numerics::hydrostatic::{FaceFriction, HydrostaticStep};
use crate::numerics::{Stage, StageError};
use crate::physics::dilatancy::{phi_from_ratio, phi_power, DilatantLaw};
use crate::physics::rheology::{inertial_number, BasalFriction, MuI};
use crate::physics::shallow::{velocity, H_DRY};
use std::ops::RangeInclusive;

/// The split dilatant stepper with its work arrays (allocated once).
#[derive(Debug)]
pub struct SplitScheme {
    pub law: DilatantLaw,
    pub opt: DilatantOptions,
    hyperbolic: HydrostaticStep<MuI>,
    /// A one-layer state whose h and hv are the dilatant state's, swapped in and out.
    shell: LayeredState,
    /// φ after the transport (nx + 2).
    phi_new: Vec<f64>,
    /// (h, hv) at t^n, restored when a later sub-step fails.
    backup: [Vec<f64>; 2],
    /// Stabilisation: per face drive max(0, vΔz) and rate; (φh, φhv, φ^α h).
    drive: Vec<f64>,
    rate: Vec<f64>,
    /// μ_eff of every wet cell after the friction step (nx + 2), K > 0 only.
    mu: Vec<f64>,
    /// K > 0: the volume fraction each face's friction threshold sees (nx + 1).
    phi_face: Vec<f64>,
    scratch: Vec<f64>,
    cons: [Vec<f64>; 3],
}

/// The μ(I) law of the hyperbolic step's Coulomb-aware reconstruction: the
/// Savage–Hutter law (φ = `phi_ref`, the material's), whatever K.
pub fn reconstruction_law(law: &DilatantLaw, phi_ref: f64) -> MuI {
    MuI {
        mu_s: law.mu_1,
        mu_2: law.mu_2,
        i0: law.i0,
        d_s: law.d,
        phi: phi_ref,
    }
}

/// The dilatant friction coefficient μ_eff = μ(I) + μ_w h/W + tan ψ (seed 002 eq.
/// 2.13–2.14 and 4.1; tan ψ = K(φ − φ_eq(I)) cut so that μ_eff ≥ 0) of a layer of
/// depth h > 0, speed |v| and fraction φ under p/ρ = g_c h. At rest (I = 0) it is the
/// static threshold μ_1 + K(φ − φ_stat) (+ walls) of seed 002 §2.4 (2.16).
#[inline(always)]
pub fn mu_eff(law: &DilatantLaw, speed: f64, h: f64, p_over_rho: f64, phi: f64) -> (f64, f64) {
    let i = inertial_number(law.d, phi, speed, h, p_over_rho);
    let mut mu = law.mu_of_i(i);
    if law.mu_w > 0.0 {
        mu += law.mu_w * h / law.width;
    }
    let tan_psi = law.tan_psi(phi, law.phi_eq(i)).max(-mu);
    (mu + tan_psi, i)
}

/// The friction threshold of the hyperbolic step's Coulomb-aware reconstruction for
/// K > 0: μ_eff (2.13–2.14) at the face's Roe speed and mean depth with the
/// mass-weighted φ of its two cells, so that the reconstruction holds exactly what the
/// cell friction holds (a mass at rest with a surface slope below μ_1 + K(φ − φ_stat))
/// and lets through what it does not.
struct DilatantFaces<'a> {
    law: &'a DilatantLaw,
    phi: &'a [f64],
}

impl FaceFriction for DilatantFaces<'_> {
    #[inline(always)]
    fn mu(&self, face: usize, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        mu_eff(self.law, speed, h, p_over_rho, self.phi[face]).0
    }
}

/// The friction step of a cell with discharge `q`, thickness h > 0 and fraction φ: the
/// monolayer's Coulomb impulse (`friction.rs`) at the velocity q/h. K = 0: with μ(I) +
/// μ_w h/W (4.1) (I of eq. 2.10–2.11 with the cell's φ, the operations of `MuI::mu`
/// with p/ρ = g_c h). K > 0: with μ_eff = μ(I) + μ_w h/W + tan ψ ([`mu_eff`],
/// 2.13–2.14, cut at 0), one impulse; a mass is stopped when it exceeds its momentum,
/// so a mass is held iff its drive is below μ_eff (at rest, the static threshold 2.16).
///
/// Returns the new discharge, the inertial number I of the incoming discharge and the
/// μ applied.
#[inline(always)]
pub fn cell_friction(
    law: &DilatantLaw,
    g_c: f64,
    dt: f64,
    h: f64,
    q: f64,
    phi: f64,
) -> (f64, f64, f64) {
    if law.k == 0.0 {
        // Without dilatancy: the monolayer's own backward-Euler μ(I) step (issue 13 item
        // 1, `MuI::friction_update`), the walls' μ_w h/W a constant added to μ_1 and μ_2,
        // so that K = 0 stays the Savage–Hutter μ(I) run bit for bit. (K > 0 keeps μ at
        // the incoming speed; I and μ are returned for the dilatant part only.)
        let wall = if law.mu_w > 0.0 {
            law.mu_w * h / law.width
        } else {
            0.0
        };
        let savage_hutter = MuI {
            mu_s: law.mu_1 + wall,
            mu_2: law.mu_2 + wall,
            i0: law.i0,
            d_s: law.d,
            phi,
        };
        return (savage_hutter.friction_update(q, h, dt, g_c), 0.0, f64::NAN);
    }
    let (mu, i) = mu_eff(law, velocity(h, q).abs(), h, g_c * h, phi);
    (coulomb_update(q, dt * mu * g_c * h), i, mu)
}

impl SplitScheme {
    /// `phi_ref`: the material's φ (the Savage–Hutter law's).
    pub fn new(law: DilatantLaw, opt: DilatantOptions, nx: usize, phi_ref: f64) -> Self {
        let shell = LayeredState {
            nx,
            layers: 1,
            l: vec![1.0],
            h: Vec::new(),
            hu: Vec::new(),
            tracers: Vec::new(),
            nh: None,
        };
        SplitScheme {
            law,
            opt,
            hyperbolic: HydrostaticStep::new(reconstruction_law(&law, phi_ref), nx),
            shell,
            phi_new: vec![0.0; nx + 2],
            backup: [vec![0.0; nx + 2], vec![0.0; nx + 2]],
            drive: vec![0.0; nx + 1],
            mu: vec![0.0; nx + 2],
            phi_face: vec![0.0; nx + 1],
            rate: vec![0.0; nx + 1],
            scratch: vec![0.0; nx + 1],
            cons: [vec![0.0; nx + 2], vec![0.0; nx + 2], vec![0.0; nx + 2]],
        }
    }

    /// Advances `s` by `dt`; on error `s` is as it was.
    pub fn step(&mut self, mesh: &Mesh, s: &mut DilatantState, dt: f64) -> Result<(), StageError> {
        std::mem::swap(&mut self.shell.h, &mut s.h);
        std::mem::swap(&mut self.shell.hu, &mut s.hu);
        self.backup[0].copy_from_slice(&self.shell.h);
        self.backup[1].copy_from_slice(&self.shell.hu);
        let result = self.advance(mesh, s, dt);
        if result.is_err() {
            self.shell.h.copy_from_slice(&self.backup[0]);
            self.shell.hu.copy_from_slice(&self.backup[1]);
        }
        std::mem::swap(&mut self.shell.h, &mut s.h);
        std::mem::swap(&mut self.shell.hu, &mut s.hu);
        if result.is_ok() {
            std::mem::swap(&mut self.phi_new, &mut s.phi);
        }
        result
    }

    fn advance(&mut self, mesh: &Mesh, s: &DilatantState, dt: f64) -> Result<(), StageError> {
        if self.law.k == 0.0 {
            // The Savage–Hutter μ(I) threshold (bit for bit the monolayer's step).
            self.hyperbolic.apply(mesh, dt, &mut self.shell)?;
        } else {
            // μ_eff with the mass-weighted φ of each face's two cells at t^n (a dry
            // side counts with the other's φ; both dry, the face is never asked).
            let h = &self.shell.h;
            for (k, out) in self.phi_face.iter_mut().enumerate() {
                let (hl, hr) = (h[k].max(0.0), h[k + 1].max(0.0));
                let (pl, pr) = (s.phi[k], s.phi[k + 1]);
                *out = if hl + hr > 0.0 {
                    (hl * pl + hr * pr) / (hl + hr)
                } else {
                    0.5 * (pl + pr)
                };
            }
            let faces = DilatantFaces {
                law: &self.law,
                phi: &self.phi_face,
            };
            self.hyperbolic
                .apply_with_friction(mesh, dt, &mut self.shell, &faces)?;
        }
        let r = dt / mesh.dx;
        self.phi_new.copy_from_slice(&s.phi);
        // Cells holding mass after the step: every pass below is restricted to them (a
        // cell outside keeps h = 0, hv = 0 and its φ).
        let nx = mesh.nx;
        let h = &self.shell.h[1..=nx];
        let Some(first) = h.iter().position(|&h| h > 0.0) else {
            return Ok(());
        };
        let last = nx - 1 - h.iter().rev().position(|&h| h > 0.0).unwrap_or(0);
        let wet = first + 1..=last + 1;
        self.transport(mesh, &s.phi, r, wet.clone())?;
        fill_fraction_ghosts(&mut self.phi_new);
        self.cells(mesh, dt, wet.clone())?;
        self.shell.fill_ghosts(mesh);
        if self.law.k != 0.0 && !self.opt.viscosity.is_off() {
            self.stabilise(mesh, dt, wet)?;
        }
        Ok(())
    }

    /// Step 2: φ^{n+1} from the mass fluxes of the hyperbolic step.
    fn transport(
        &mut self,
        mesh: &Mesh,
        phi: &[f64],
        r: f64,
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (lo, hi) = (*wet.start(), *wet.end());
        // Faces lo − 1..=hi, cells lo − 1..=hi + 1: equal-length windows, no bounds checks.
        let flux = &self.hyperbolic.mass_flux()[lo - 1..=hi];
        let phi = &phi[lo - 1..=hi + 1];
        let h = &self.shell.h[lo..=hi];
        let out = &mut self.phi_new[lo..=hi];
        let faces = flux.windows(2).zip(phi.windows(3));
        for (j, ((f, p3), (&hj, next))) in faces.zip(h.iter().zip(out)).enumerate() {
            let p = p3[1];
            if hj <= 0.0 {
                continue;
            }
            let up_out = if f[1] > 0.0 { p } else { p3[2] };
            let up_in = if f[0] > 0.0 { p3[0] } else { p };
            let change = f[1] * (up_out - p) - f[0] * (up_in - p);
            let value = p - r * change / hj;
            if !(value > 0.0 && value < 1.0) {
                return Err(StageError::Inadmissible {
                    x: mesh.x[lo + j - 1],
                    quantity: "volume fraction φ (transport)",
                    value,
                });
            }
            *next = value;
        }
        Ok(())
    }

    /// Step 3: φ-gradient pressure, friction, dilatancy, cell by cell.
    fn cells(
        &mut self,
        mesh: &Mesh,
        dt: f64,
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (nx, g_c, dx) = (self.shell.nx, mesh.g_n, mesh.dx);
        let law = &self.law;
        let dilatant = law.k != 0.0;
        let stabilise = !self.opt.viscosity.is_off();
        let (h, hu, phi) = (&mut self.shell.h, &mut self.shell.hu, &mut self.phi_new);
        let gradient_factor = 0.5 * g_c * dt / (2.0 * dx);
        // φ and wetness of the left neighbour before its dilatancy step.
        let mut left = (phi[wet.start() - 1], h[wet.start() - 1] > H_DRY);
        for i in wet {
            let hi = h[i];
            let p = phi[i];
            let wet = hi > H_DRY;
            let mut q = hu[i];
            if wet {
                let phi_l = if left.1 { left.0 } else { p };
                let phi_r = if h[i + 1] > H_DRY { phi[i + 1] } else { p };
                let dphi = phi_r - phi_l;
                if dphi != 0.0 {
                    q -= gradient_factor * hi * hi / p * dphi;
                }
            }
            left = (p, wet);
            // The friction step of the monolayer (friction.rs), with μ_eff.
            let q_in = q;
            let (mut i_in, mut mu) = (0.0, f64::NAN);
            if q != 0.0 {
                if !wet {
                    q = 0.0;
                } else {
                    (q, i_in, mu) = cell_friction(law, g_c, dt, hi, q, p);
                }
            }
            hu[i] = q;
            if dilatant && wet {
                if stabilise {
                    if mu.is_nan() {
                        // At rest: μ_eff = μ_1 + K(φ − φ_stat) (I = 0), plus the walls.
                        mu = (law.mu_1 + law.tan_psi(p, law.phi_stat)).max(0.0);
                        if law.mu_w > 0.0 {
                            mu += law.mu_w * hi / law.width;
                        }
                    }
                    // μ_eff at the incoming state, for the stabilisation's faces.
                    self.mu[i] = mu;
                }
                if q == 0.0 {
                    continue;
                }
                // I scales with |v| at fixed h and φ (eq. 2.10, 2.15).
                let i_out = i_in * (q / q_in).abs();
                let phi_eq = law.phi_eq(i_out);
                // (3.15)–(3.19) with γ̇* = (5/2)|v*|/h*, φ_eq* = φ_eq(I*).
                let inv_h = 1.0 / hi;
                let v = q * inv_h;
                let rate = 2.5 * v.abs() * inv_h;
                let next = relax_towards(law, self.opt.update, dt, rate, p, phi_eq);
                if !(next > 0.0 && next < 1.0) {
                    return Err(StageError::Inadmissible {
                        x: mesh.x[i - 1],
                        quantity: "volume fraction φ (dilatancy step)",
                        value: next,
                    });
                }
                if next != p {
                    let h_next = p * hi / next;
                    phi[i] = next;
                    h[i] = h_next;
                    hu[i] = h_next * v;
                }
            }
        }
        fill_fraction_ghosts(phi);
        self.mu[0] = self.mu[1];
        self.mu[nx + 1] = self.mu[nx];
        Ok(())
    }

    /// Step 4: the viscosity (3.20)–(3.22) on wet–wet faces.
    fn stabilise(
        &mut self,
        mesh: &Mesh,
        dt: f64,
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (nx, g_c, dx) = (self.shell.nx, mesh.g_n, mesh.dx);
        let alpha = self.opt.flux.alpha;
        let (h, hu, phi) = (&self.shell.h, &self.shell.hu, &self.phi_new);
        let mut largest: f64 = 0.0;
        let (mut first, mut last) = (usize::MAX, 0);
        let alpha_term = 0.5 / (alpha - 1.0);
        // Faces next to the wet range have no drive; those inside may.
        self.drive[wet.start() - 1] = 0.0;
        self.drive[*wet.end()] = 0.0;
        for k in *wet.start()..*wet.end() {
            self.drive[k] = 0.0;
            let (hl, hr) = (h[k], h[k + 1]);
            if hl <= H_DRY || hr <= H_DRY || (hu[k] == 0.0 && hu[k + 1] == 0.0) {
                continue;
            }
            // v_interf (3.8), X_interf Δx (3.12), μ_eff^interf as the mean of the cells'.
            let (ml, mr) = (phi[k] * hl, phi[k + 1] * hr);
            let v = (phi[k] * hu[k] + phi[k + 1] * hu[k + 1]) / (ml + mr);
            let db_hat = mesh.z[k + 1] - mesh.z[k];
            let (al, ar) = (phi_power(phi[k], alpha), phi_power(phi[k + 1], alpha));
            let x = (hl - hr - db_hat + alpha_term * (hl + hr) * (al - ar) / (al + ar)) / dx;
            let mu = 0.5 * (self.mu[k] + self.mu[k + 1]);
            let dz = db_hat + dx * proj_friction(mu, x, v / (g_c * dt));
            let d = (v * dz).max(0.0);
            if d > 0.0 {
                self.drive[k] = d;
                largest = largest.max(d);
                first = first.min(k);
                last = k;
            }
        }
        if largest == 0.0 {
            return Ok(());
        }
        // Faces s0..=e0 − 2 (zero drive outside first..=last) and cells s0..e0: every
        // cell next to an active face is interior to that range.
        let (s0, e0) = (first.saturating_sub(1), (last + 3).min(nx + 2));
        {
            let [m, q, w] = &mut self.cons;
            for j in s0..e0 {
                let mj = phi[j] * h[j];
                m[j] = mj;
                q[j] = phi[j] * hu[j];
                w[j] = mj * phi_power(phi[j], alpha);
            }
        }
        let visc = self.opt.viscosity;
        let n = visc.substeps(largest, dt, dx);
        let r = dt / n as f64 / (dx * dx);
        for _ in 0..n {
            for (c, u) in self.cons.iter_mut().enumerate() {
                let xi = visc.xi[c];
                if xi == 0.0 {
                    continue;
                }
                for k in s0..e0 - 1 {
                    self.rate[k] = r * xi * self.drive[k];
                }
                let faces = s0..e0 - 1;
                diffuse(
                    &mut u[s0..e0],
                    &self.rate[faces.clone()],
                    &mut self.scratch[faces],
                );
            }
        }
        let [m, q, w] = &self.cons;
        for j in (s0 + 1).max(1)..=(e0 - 2).min(nx) {
            if self.shell.h[j] <= H_DRY {
                // Not next to an active face (those join two wet cells): unchanged.
                continue;
            }
            let p = phi_from_ratio(w[j] / m[j], alpha);
            if !(p > 0.0 && p < 1.0) {
                return Err(StageError::Inadmissible {
                    x: mesh.x[j - 1],
                    quantity: "volume fraction φ (stabilisation step)",
                    value: p,
                });
            }
            self.phi_new[j] = p;
            self.shell.h[j] = m[j] / p;
            self.shell.hu[j] = q[j] / p;
        }
        fill_fraction_ghosts(&mut self.phi_new);
        self.shell.fill_ghosts(mesh);
        Ok(())
    }
}

/// Ghost fractions copy the edge cells (walls and outflow alike).
fn fill_fraction_ghosts(phi: &mut [f64]) {
    let n = phi.len();
    phi[0] = phi[1];
    phi[n - 1] = phi[n - 2];
}

impl Stage<DilatantState> for SplitScheme {
    fn name(&self) -> &'static str {
        "dilatant"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut DilatantState) -> Result<(), StageError> {
        self.step(mesh, state, dt)
    }
}
