//! The default time step of the dilatant model (`dilatancy.scheme = "split"`): the
//! Savage–Hutter μ(I) step of the monolayer model with the volume fraction carried by
//! its mass fluxes, then the terms of Bouchut et al. 2021 that vanish for K = 0 and uniform φ.
//!
//! In the variables (h, hv, φ) the system (2.2)–(2.5) of Bouchut et al. 2021 reads
//!
//!   ∂_t h + ∂_x(hv) = h γ̇ tan ψ                                              (2.5)
//!   ∂_t(hv) + ∂_x(hv² + ½ g_c h²) = −g_c h ∂_x b̂ − g_c h²/(2φ) ∂_x φ − μ_eff g_c h sgn(v)
//!                                   + hv γ̇ tan ψ                             (2.4 × h)
//!   ∂_t(φh) + ∂_x(φhv) = 0                                                   (2.3)
//!
//! i.e. shallow water in (h, hv) with three extra terms: the φ-gradient pressure, the
//! dilatant friction μ_eff = μ(I) + tan ψ (2.13–2.14) and the dilatancy source. One step:
//!
//! The φ-gradient pressure is a potential: −g_c h²/(2φ) ∂_x φ = −g_c h ∂_x ζ with
//! ∂_x ζ = h/(2φ) ∂_x φ, and its jump across each face, Δζ = h̄ (φ_R − φ_L)/(φ_R + φ_L)
//! (h̄ the mean depth, 0 where a side is dry), enters the hyperbolic step like a bed
//! step ([`FaceFriction::potential_jump`]): in the face's pressure source and in its
//! Coulomb-aware reconstruction. A centred cell term −g_c h²/(2φ)(φ_{i+1} − φ_{i−1})/(2Δx)
//! cannot see an odd–even φ (it is 0 wherever φ_{i+1} = φ_{i−1}) and, added after the
//! step, was invisible to the faces: a face held by its Coulomb threshold carried no
//! mass while the cell pass still pushed its cell, so a cell next to a denser one kept
//! a speed without moving mass. Collapses grew an odd–even pattern in v and φ next to
//! the back wall and never came to rest (`tests/dilatant.rs`,
//! `split_scheme::an_odd_even_fraction_pattern_on_a_flat_layer_is_no_equilibrium`,
//! `split_scheme::dense_collapse_at_10_degrees_comes_to_rest`). On the faces, a mass at
//! rest stays at rest iff every face's |Δ(h + z + ζ)| is within its static threshold.
//!
//! 1. **hyperbolic**: the monolayer's [`HydrostaticStep`] (Garres-Díaz et al. 2021, §3 step 1: HLL/PVM,
//!    hydrostatic reconstruction, Coulomb-aware ΔC) on (h, hv), called, not copied. For
//!    K = 0 its ΔC uses the Savage–Hutter μ(I) law (φ = `material.phi`). For K > 0 it
//!    takes the threshold per face ([`HydrostaticStep::apply_with_friction`]):
//!    μ_eff = μ(I) + μ_w h/W + tan ψ of each cell at its own speed and depth, weighted
//!    by the depths (`physics::rheology::depth_weighted_mu`, as the Savage–Hutter
//!    face; the static threshold at Roe speed 0), with the smaller φ of the two cells at t^n (the weaker cell's threshold: a face holds only
//!    what both its cells would hold; with the mass-weighted φ a dilated cell beside a
//!    denser one kept moving while its faces, stronger than the cell, held its mass),
//!    and without tan ψ where the mean depth is below the thickness threshold
//!    `h_thin` of Bouchut et al. 2021, §3.3 (`dilatancy.thin_layer_grains`, 10 d by
//!    default). The reconstruction and the cell friction
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
//!    its content (a cell whose outflow exceeds it gives its faces the φ of all it held
//!    during the step, [`SplitScheme`]'s transport), and a uniform φ stays uniform bit for bit (every difference is 0).
//!    Cells left with h = 0 keep their φ (Bouchut et al. 2021, eq. 3.14 is not needed: the
//!    hyperbolic step never asks a dry cell for φ).
//! 3. **cell pass**: the friction step of
//!    the monolayer (`friction.rs`: friction stops but never reverses) in backward
//!    Euler in the speed ([`cell_friction`]): μ(I) + μ_w h/W (4.1) for K = 0 (the
//!    Savage–Hutter `MuI::friction_update`), μ_eff = μ(I) + μ_w h/W + tan ψ (2.13–2.14,
//!    cut at 0) for K > 0 with μ(I) and φ_eq(I) both at the new speed
//!    ([`backward_euler_speed`], I of 2.10–2.11 with the cell's φ); the mass stops iff
//!    its discharge is within the static impulse Δt g_c h (μ_1 + μ_w h/W + K(φ − φ_stat))
//!    of (2.16). Were μ_eff taken at the speed after the gravity push (explicit
//!    in I), a uniform 28° flow would settle at I = 0.0160, φ = 0.5789 (dense start)
//!    or nearly stop (loose, I = 2.0e-4) instead of
//!    I* = 0.0728, φ_eq(I*) = 0.5678, because the dilatancy step below relaxed φ
//!    towards φ_eq at the slower speed after friction while the friction used the
//!    faster one, so tan ψ would stay > 0 at the fixed point. Here the fixed point is
//!    exactly tan ψ = 0, μ(I) = tan θ (`tests/dilatant.rs`,
//!    `split_scheme::uniform_flow_on_an_incline_reaches_the_critical_state_split_scheme`);
//!    then for K > 0 the semi-implicit dilatancy step (3.15)–(3.19) at the state after
//!    friction (I* = the I at which μ_eff was taken): φ from (3.17) or (3.18), φh and v
//!    kept, so h ← φh/φ and hv ← h v. A cell thinner than `h_thin` (Bouchut et al. 2021, §3.3:
//!    "a threshold of about tens of particles", below which the results are
//!    "physically meaningless") takes the K = 0 friction μ(I) + μ_w h/W and keeps its φ:
//!    without it the fronts dilate to φ < 0.001 in films of µm and the early front and
//!    volume change change more with each refinement down to Δx = 0.625 mm; with it the
//!    peak volume change and the front holding 99 % of the grains converge from
//!    Δx = 5 mm (docs/validation.md, dil-thin-layer).
//! 4. **stabilisation** (K > 0 and ξ ≠ 0 only; off in the scenarios, the split scheme
//!    needs none; Bouchut et al. 2021, §3.3 introduces it for its own scheme): (φh, φhv, φ^α h)
//!    diffuse with ι = max(0, ξ v Δz) (3.20–3.21), Δz = Δb̂ + Δx Proj_μ(X, v/(g_c Δt))
//!    (3.6–3.12), μ the mean of the two cells' μ_eff, on faces whose two cells are wet
//!    (h > 10⁻¹⁰ m): the viscosity never wets a dry cell, so it cannot spread films
//!    ahead of a deposit. Sub-cycled to meet (3.22). Only the runs of faces with a
//!    drive and their cells are visited; the other cells keep their state.
//!
//! Steps 2–4 run over the cells that hold mass after step 1 only.
//!
//! With K = 0 and uniform φ, steps 2–4 change nothing (every φ difference is exactly 0,
//! tan ψ is not added, no dilatancy, no stabilisation) and step 3's friction performs
//! the operations of the monolayer's friction step with the same μ(I): the run is the
//! Savage–Hutter μ(I) run bit for bit (`tests/dilatant.rs`).
//!
//! Order 2 ([`SplitScheme::second_order`], run by [`super::heun`]): the hyperbolic
//! step with the reconstruction of [`crate::numerics::muscl`], the potential ζ
//! reconstructed as the surface (`split_potential`) and φ transported
//! with limited linear profiles in its donor cells (`transport_second_order`). Order 1
//! keeps every operation above.
//!
//! Errors: a step that would make h negative is refused as the Savage–Hutter one is
//! (the run retries with a smaller Δt); φ outside (0, 1) after a sub-step is an error
//! naming the place and the stage. [`SplitScheme::step`], for a driver of its own,
//! then leaves the state as it was at tⁿ; the stage of a run leaves it part-way, to
//! the run loop, which restores the state of tⁿ.

use super::flux::proj_friction;
use super::source::relax_towards;
use super::stabilisation::diffuse_run;
use super::step::DilatantOptions;
use crate::grid::Line;
use crate::numerics::hydrostatic::{FaceFriction, HydrostaticStep};
use crate::numerics::muscl::Limiter;
use crate::numerics::{Stage, StageError, StepClock};
use crate::physics::dilatancy::{phi_from_ratio, phi_power, DilatantLaw};
use crate::physics::rheology::{
    depth_weighted_mu, inertial_number, BasalFriction, MonolayerShear, MuI, STATIC_ROUNDOFF,
};
use crate::physics::shallow::H_DRY;
use crate::state::DilatantState;
use std::ops::RangeInclusive;

/// The split dilatant stepper with its work arrays (allocated once).
#[derive(Debug)]
pub struct SplitScheme {
    pub law: DilatantLaw,
    pub opt: DilatantOptions,
    hyperbolic: HydrostaticStep<MuI>,
    /// φ after the transport (nx + 2).
    phi_new: Vec<f64>,
    /// φ that each cell's outgoing mass carries in the transport (nx + 2).
    phi_donor: Vec<f64>,
    /// (h, hv) at tⁿ, which the sub-steps read (and [`step`](Self::step) restores
    /// when one fails).
    start: [Vec<f64>; 2],
    /// Stabilisation (K > 0, ξ ≠ 0): per face drive max(0, vΔz), set on the active
    /// faces only (nx + 1); the runs of consecutive active faces (first, last) in
    /// increasing order; (φh, φhv, φ^α h) (nx + 2).
    drive: Vec<f64>,
    active: Vec<(usize, usize)>,
    /// μ_eff after the friction step (nx + 2) of the cells that moved through it; −1
    /// marks a cell the friction held (its μ_eff is the static threshold at its h, φ).
    mu: Vec<f64>,
    cons: [Vec<f64>; 3],
    /// The material's φ (the Savage–Hutter law's, K = 0).
    phi_ref: f64,
    /// Order 2 ([`super::heun`]): the limiter of the hyperbolic step's reconstruction
    /// and of φ in the transport (`None` at order 1), and the west and east edge
    /// values of φ that each cell's outgoing mass carries (nx + 2; empty at order 1).
    limiter: Option<Limiter>,
    phi_west: Vec<f64>,
    phi_east: Vec<f64>,
    /// Order 2 (empty at order 1): per face (nx + 1) the part of the potential's jump
    /// that its two reconstructed cells take inside (`cut`), per cell (nx + 2) the rise
    /// of ζ inside the cell that its interior force −g_c h ∂_x ζ acts on (`interior`).
    cut: Vec<f64>,
    interior: Vec<f64>,
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
        shear: MonolayerShear::Bagnold,
    }
}

/// The dilatant friction coefficient μ_eff = μ(I) + μ_w h/W + tan ψ (Bouchut et al. 2021, eq.
/// 2.13–2.14 and 4.1; tan ψ = K(φ − φ_eq(I)) cut so that μ_eff ≥ 0) of a layer of
/// depth h > 0, speed |v| and fraction φ under p/ρ = g_c h. At rest (I = 0) it is the
/// static threshold μ_1 + K(φ − φ_stat) (+ walls) of Bouchut et al. 2021, §2.4 (2.16).
#[inline(always)]
pub fn mu_eff(law: &DilatantLaw, speed: f64, h: f64, p_over_rho: f64, phi: f64) -> (f64, f64) {
    let i = inertial_number(law.d, phi, speed, h, p_over_rho);
    let mu = law.mu_of_i(i) + wall(law, h);
    let tan_psi = law.tan_psi(phi, law.phi_eq(i)).max(-mu);
    (mu + tan_psi, i)
}

/// The friction threshold of the hyperbolic step's Coulomb-aware reconstruction for
/// K > 0: μ_eff (2.13–2.14) of the two cells at their own speeds and depths,
/// depth-weighted ([`FaceFriction::face_mu`]; the mean depth decides `h_thin`), with the
/// smaller φ of its two cells at t^n (a dry side counts with the other's φ; both
/// dry, the face is never asked), so that the reconstruction holds exactly what the
/// cell friction holds (a mass at rest with a surface slope below μ_1 + K(φ − φ_stat))
/// and lets through what it does not. φ of the face is formed where it is asked for
/// (no pass of its own), and a face at rest (Roe speed 0: I = 0) takes the static
/// threshold μ_1 + μ_w h/W + K(φ − φ_stat) without I, μ(I) and φ_eq(I): the same
/// value bit for bit (μ(0) = μ_1 + 0 and φ_eq(0) = φ_stat exactly), fewer operations.
struct DilatantFaces<'a> {
    law: &'a DilatantLaw,
    /// The thickness threshold of Bouchut et al. 2021, §3.3: below it (mean depth) no tan ψ.
    h_thin: f64,
    /// h and φ at t^n (nx + 2, ghosts included).
    h: &'a [f64],
    phi: &'a [f64],
    /// Order 2: the part of each face's jump moved into its cells' interiors (nx + 1;
    /// empty at order 1, [`SplitScheme::split_potential`]).
    cut: &'a [f64],
}

/// The jump ζ_R − ζ_L of the volume-fraction potential across a face, ∂_x ζ = h/(2φ) ∂_x φ
/// (the pressure term −g_c h²/(2φ) ∂_x φ of Bouchut et al. 2021, eq. 2.4, written as
/// −g_c h ∂_x ζ): h̄ (φ_R − φ_L)/(φ_R + φ_L) with h̄ the mean depth at t^n; 0 where a
/// side is dry (≤ `H_DRY`) and, exactly, where φ_L = φ_R.
#[inline(always)]
fn fraction_potential_jump(h: &[f64], phi: &[f64], face: usize) -> f64 {
    let (hl, hr) = (h[face], h[face + 1]);
    let (pl, pr) = (phi[face], phi[face + 1]);
    if hl <= H_DRY || hr <= H_DRY || pl == pr {
        return 0.0;
    }
    0.5 * (hl + hr) * (pr - pl) / (pr + pl)
}

/// The faces of the K = 0 step: the Savage–Hutter μ(I) threshold and the
/// volume-fraction potential (0 with uniform φ: then the monolayer's step bit for bit).
struct IncompressibleFaces<'a> {
    law: &'a MuI,
    h: &'a [f64],
    phi: &'a [f64],
    /// As [`DilatantFaces::cut`].
    cut: &'a [f64],
}

/// The face's jump of the potential: the whole jump between the cell centres at order
/// 1, less the parts inside reconstructed cells at order 2.
#[inline(always)]
fn face_potential(h: &[f64], phi: &[f64], cut: &[f64], face: usize) -> f64 {
    let jump = fraction_potential_jump(h, phi, face);
    if cut.is_empty() {
        jump
    } else {
        jump - cut[face]
    }
}

impl FaceFriction for IncompressibleFaces<'_> {
    #[inline(always)]
    fn mu(&self, _face: usize, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        BasalFriction::mu(self.law, speed, h, p_over_rho)
    }

    /// The Savage–Hutter face: the cells' own μ(I), depth-weighted (as the monolayer).
    #[inline(always)]
    fn face_mu(
        &self,
        _face: usize,
        left: (f64, f64),
        right: (f64, f64),
        speed: f64,
        h: f64,
        g_n: f64,
    ) -> f64 {
        BasalFriction::face_mu(self.law, left, right, speed, h, g_n)
    }

    #[inline(always)]
    fn potential_jump(&self, face: usize) -> f64 {
        face_potential(self.h, self.phi, self.cut, face)
    }
}

impl FaceFriction for DilatantFaces<'_> {
    #[inline(always)]
    fn potential_jump(&self, face: usize) -> f64 {
        face_potential(self.h, self.phi, self.cut, face)
    }

    #[inline(always)]
    fn mu(&self, face: usize, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        let law = self.law;
        let phi = self.face_fraction(face);
        if h < self.h_thin {
            return law.mu_of_i(inertial_number(law.d, phi, speed, h, p_over_rho)) + wall(law, h);
        }
        if speed == 0.0 {
            let mu = law.mu_1 + wall(law, h);
            return mu + law.tan_psi(phi, law.phi_stat).max(-mu);
        }
        mu_eff(law, speed, h, p_over_rho, phi).0
    }

    /// At Roe speed 0, [`Self::mu`] (the static threshold); moving, the cells' own
    /// μ_eff (or μ(I) + μ_w h/W below `h_thin`) at their speeds and depths with the
    /// face's φ, depth-weighted (`physics::rheology::depth_weighted_mu`, as the
    /// Savage–Hutter face).
    #[inline(always)]
    fn face_mu(
        &self,
        face: usize,
        left: (f64, f64),
        right: (f64, f64),
        speed: f64,
        h: f64,
        g_n: f64,
    ) -> f64 {
        if speed == 0.0 {
            return self.mu(face, speed, h, g_n * h);
        }
        moving_face(
            self.law,
            left,
            right,
            g_n,
            self.face_fraction(face),
            h < self.h_thin,
        )
    }
}

impl DilatantFaces<'_> {
    /// φ of a face: the smaller of its two cells' (a dry side counts with the other's).
    #[inline(always)]
    fn face_fraction(&self, face: usize) -> f64 {
        let (hl, hr) = (self.h[face].max(0.0), self.h[face + 1].max(0.0));
        let (pl, pr) = (self.phi[face], self.phi[face + 1]);
        if hl > 0.0 && hr > 0.0 {
            pl.min(pr)
        } else if hl > 0.0 {
            pl
        } else {
            pr
        }
    }
}

/// μ_eff of a moving face (without tan ψ if `thin`): the cells' own, depth-weighted.
/// Out of line: the face function stays small enough to be inlined into the
/// hyperbolic step's loop.
#[inline(never)]
fn moving_face(
    law: &DilatantLaw,
    left: (f64, f64),
    right: (f64, f64),
    g_n: f64,
    phi: f64,
    thin: bool,
) -> f64 {
    depth_weighted_mu(left, right, |speed, h| {
        if thin {
            law.mu_of_i(inertial_number(law.d, phi, speed, h, g_n * h)) + wall(law, h)
        } else {
            mu_eff(law, speed, h, g_n * h, phi).0
        }
    })
}

/// G(I) = μ(I) + μ_w h/W + K(φ − φ_eq(I)) (Bouchut et al. 2021, eq. 2.8, 2.13–2.14, 4.1; `wall`
/// = μ_w h/W) before the cut at 0, and dG/dI ≥ 0. G is increasing and concave in I:
/// μ(I) is, and every φ_eq of §2 (2.9, f0–f2) is convex and non-increasing
/// ([`DilatantLaw::phi_eq_and_slope`]). Needs I_0 > 0 (validated).
#[inline(always)]
fn friction_and_slope(law: &DilatantLaw, phi: f64, wall: f64, i: f64) -> (f64, f64) {
    let dmu = law.mu_2 - law.mu_1;
    let inv = 1.0 / (i + law.i0);
    let (phi_eq, phi_eq_slope) = law.phi_eq_and_slope(i);
    let g = law.mu_1 + dmu * i * inv + wall + law.k * (phi - phi_eq);
    (g, dmu * law.i0 * inv * inv - law.k * phi_eq_slope)
}

/// Backward Euler in the speed for the dilatant friction (K > 0): the speed u ≥ 0
/// after a friction step that solves
///
///   u + c μ_eff(k u) = u*,   μ_eff(I) = max(0, G(I)),  G = μ(I) + μ_w h/W + K(φ − φ_eq(I)),
///
/// for the speed u* ≥ 0 before it, c = Δt g_c (the impulse per unit μ per unit depth),
/// k = I/u = 2.5 d/(h √(φ g_c h)) (eq. 2.10–2.11, 2.15) and `wall` = μ_w h/W. The caller
/// has checked that the mass moves: u* > c μ_eff(0), with μ_eff(0) = max(0, μ_1 +
/// μ_w h/W + K(φ − φ_stat)) the static threshold of (2.16). Both μ(I) and φ_eq(I), hence tan ψ,
/// are taken at the new speed: taking them at u* (explicit in I) gave a uniform 28°
/// flow a spurious steady state (module documentation).
///
/// Solution: g(u) = u + c G(k u) − u* is increasing and concave (`friction_and_slope`)
/// with g(0) < 0. Where G(k u*) ≤ 0 (a loose mass, μ_eff = 0 on all of [0, u*]) the
/// answer is u*; otherwise the root of g lies where G > 0, so it is the root of the
/// equation with the cut, and Newton's method from u = 0 climbs to it monotonically
/// (the tangent of a concave function lies above it: no iterate passes the root).
/// Stopped after a step δ with |g''|max δ² ≤ ε u/4 (the error left is then below
/// ε u/2: quadratic convergence, g' ≥ 1), or δ ≤ 10⁻⁹ u where no bound on g'' is known
/// (f0's kink); checked against bisection to round-off in the unit tests. Returns
/// (u, I = k u); a NaN u* gives NaN.
#[inline(always)]
pub fn backward_euler_speed(
    law: &DilatantLaw,
    phi: f64,
    wall: f64,
    u_star: f64,
    c: f64,
    k: f64,
) -> (f64, f64) {
    if u_star.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    if law.mu_1 + wall + law.tan_psi(phi, law.phi_stat) < 0.0 {
        // The cut can bind: without friction up to u*?
        let i = k * u_star;
        if friction_and_slope(law, phi, wall, i).0 <= 0.0 {
            return (u_star, i);
        }
    }
    // The first Newton step from u = 0 in closed form: G(0) = μ_1 + μ_w h/W + K(φ −
    // φ_stat), G'(0) = (μ_2 − μ_1)/I_0 − K φ_eq'(0).
    let (g0, slope0) = friction_and_slope(law, phi, wall, 0.0);
    let mut u = (u_star - c * g0) / (1.0 + c * k * slope0);
    // |g''| ≤ c k² |G''|max: after a step δ from the left the error left is at most
    // 2 |g''| δ² (g' ≥ 1), so |g''| δ² ≤ ε u/4 means the root to round-off.
    let curvature = c * k * k * law.friction_curvature_bound();
    for _ in 0..MAX_NEWTON {
        let (g, slope) = friction_and_slope(law, phi, wall, k * u);
        let step = (u_star - u - c * g) / (1.0 + c * k * slope);
        if step.is_nan() || step <= 0.0 {
            // At the root to round-off.
            break;
        }
        u += step;
        if step <= NEWTON_TOLERANCE * u || curvature * step * step <= 0.25 * f64::EPSILON * u {
            break;
        }
    }
    let u = u.min(u_star);
    (u, k * u)
}

/// Relative size of the last Newton step of [`backward_euler_speed`].
const NEWTON_TOLERANCE: f64 = 1e-9;
/// A bound the monotone iteration never meets in practice (a guard, not a tolerance).
const MAX_NEWTON: usize = 100;

/// The friction step of a cell with discharge `q`, thickness h > 0 and fraction φ, the
/// monolayer's (`friction.rs`: friction stops the mass or slows it, never reverses it)
/// in backward Euler. K = 0: μ(I) + μ_w h/W (4.1) (I of eq. 2.10–2.11 with the cell's
/// φ), the monolayer's `MuI::friction_update`. K > 0: μ_eff = μ(I) + μ_w h/W + tan ψ
/// (2.13–2.14, cut at 0) at the new speed ([`backward_euler_speed`]); the mass is
/// stopped iff |q| ≤ Δt g_c h μ_eff(0) (up to `STATIC_ROUNDOFF`, as for μ(I)), so a mass
/// is held iff its drive is below the static threshold μ_1 + K(φ − φ_stat) of (2.16).
///
/// Returns the new discharge and its inertial number I (0 for K = 0: not needed).
#[inline(always)]
pub fn cell_friction(law: &DilatantLaw, g_c: f64, dt: f64, h: f64, q: f64, phi: f64) -> (f64, f64) {
    let wall = wall(law, h);
    if law.k == 0.0 {
        // Without dilatancy: the monolayer's own backward-Euler μ(I) step
        // (`MuI::friction_update`), the walls' μ_w h/W a constant added to μ_1 and μ_2,
        // so that K = 0 stays the Savage–Hutter μ(I) run bit for bit.
        let savage_hutter = MuI {
            mu_s: law.mu_1 + wall,
            mu_2: law.mu_2 + wall,
            i0: law.i0,
            d_s: law.d,
            phi,
            shear: MonolayerShear::Bagnold,
        };
        return (savage_hutter.friction_update(q, h, dt, g_c), 0.0);
    }
    dilatant_friction(law, g_c, dt, h, q, phi, wall)
}

/// The K > 0 part of [`cell_friction`] (`wall` = μ_w h/W).
#[inline(always)]
fn dilatant_friction(
    law: &DilatantLaw,
    g_c: f64,
    dt: f64,
    h: f64,
    q: f64,
    phi: f64,
    wall: f64,
) -> (f64, f64) {
    let weight = g_c * h;
    let at_rest = static_mu(law, h, phi);
    if dt * at_rest * weight * (1.0 + STATIC_ROUNDOFF) >= q.abs() {
        return (0.0, 0.0);
    }
    let k = inertial_number(law.d, phi, 1.0, h, weight);
    let (u, i) = backward_euler_speed(law, phi, wall, (q / h).abs(), dt * g_c, k);
    (u * h * q.signum(), i)
}

impl SplitScheme {
    /// `phi_ref`: the material's φ (the Savage–Hutter law's).
    pub fn new(law: DilatantLaw, opt: DilatantOptions, nx: usize, phi_ref: f64) -> Self {
        SplitScheme {
            law,
            opt,
            hyperbolic: HydrostaticStep::new(reconstruction_law(&law, phi_ref), nx),
            phi_new: vec![0.0; nx + 2],
            phi_donor: vec![0.0; nx + 2],
            start: [vec![0.0; nx + 2], vec![0.0; nx + 2]],
            drive: vec![0.0; nx + 1],
            active: Vec::with_capacity(nx + 1),
            mu: vec![0.0; nx + 2],
            cons: [vec![0.0; nx + 2], vec![0.0; nx + 2], vec![0.0; nx + 2]],
            phi_ref,
            limiter: None,
            phi_west: Vec::new(),
            phi_east: Vec::new(),
            cut: Vec::new(),
            interior: Vec::new(),
        }
    }

    /// The split step with the second-order reconstruction of `limiter` in its
    /// hyperbolic step and in the φ transport (the time integrator is the caller's:
    /// [`super::heun`]).
    pub fn second_order(
        law: DilatantLaw,
        opt: DilatantOptions,
        nx: usize,
        phi_ref: f64,
        limiter: Limiter,
    ) -> Self {
        let mut scheme = Self::new(law, opt, nx, phi_ref);
        scheme.hyperbolic =
            HydrostaticStep::second_order(reconstruction_law(&law, phi_ref), nx, limiter);
        scheme.limiter = Some(limiter);
        scheme.phi_west = vec![0.0; nx + 2];
        scheme.phi_east = vec![0.0; nx + 2];
        scheme.cut = vec![0.0; nx + 1];
        scheme.interior = vec![0.0; nx + 2];
        scheme
    }

    /// Advances `s` by `dt`; on error `s` is as it was (for a driver without the run
    /// loop: the stage of a run advances with `split_step`).
    pub fn step(&mut self, mesh: &Line, s: &mut DilatantState, dt: f64) -> Result<(), StageError> {
        let result = self.split_step(mesh, s, dt);
        if result.is_err() {
            // φ was not touched.
            s.h.copy_from_slice(&self.start[0]);
            s.hu.copy_from_slice(&self.start[1]);
        }
        result
    }

    /// Steps 1–4; on error `s` is part-way (φ untouched).
    pub(super) fn split_step(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
    ) -> Result<(), StageError> {
        self.run_from_start(s, |scheme, s| scheme.advance(mesh, s, dt))
    }

    /// Steps 1–2 alone (the hyperbolic step and the φ transport, H_Δt of
    /// [`super::heun`]); on error `s` is part-way (φ untouched).
    pub(super) fn hyperbolic_step(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
    ) -> Result<(), StageError> {
        self.run_from_start(s, |scheme, s| {
            scheme.hyperbolic_and_transport(mesh, s, dt).map(|_| ())
        })
    }

    /// Steps 3–4 alone (friction, dilatancy and stabilisation, C_Δt of
    /// [`super::heun`]) on the state's (h, hv, φ); on error `s` is part-way (φ
    /// untouched).
    pub(super) fn cell_step(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
    ) -> Result<(), StageError> {
        self.run_from_start(s, |scheme, s| {
            scheme.phi_new.copy_from_slice(&s.phi);
            match wet_cells(&s.h, mesh.nx) {
                Some(wet) => scheme.cell_pass(mesh, s, dt, wet),
                None => Ok(()),
            }
        })
    }

    /// Runs `sub_steps` on (h, hv) of `s` in place, with (h, hv) of its start in
    /// `start` and φ^{n+1} into `phi_new`, then moves φ^{n+1} into the state.
    fn run_from_start(
        &mut self,
        s: &mut DilatantState,
        sub_steps: impl FnOnce(&mut Self, &mut DilatantState) -> Result<(), StageError>,
    ) -> Result<(), StageError> {
        self.start[0].copy_from_slice(&s.h);
        self.start[1].copy_from_slice(&s.hu);
        let result = sub_steps(self, s);
        if result.is_ok() {
            std::mem::swap(&mut self.phi_new, &mut s.phi);
        }
        result
    }

    /// Steps 1–4 on (h, hv) of `s` in place, φ^{n+1} into `phi_new` (`s.phi` keeps
    /// φ^n).
    fn advance(&mut self, mesh: &Line, s: &mut DilatantState, dt: f64) -> Result<(), StageError> {
        match self.hyperbolic_and_transport(mesh, s, dt)? {
            Some(wet) => self.cell_pass(mesh, s, dt, wet),
            None => Ok(()),
        }
    }

    /// Steps 1–2 on (h, hv) of `s` in place, φ after the transport into `phi_new`
    /// (`s.phi` keeps φ^n); returns the cells that hold mass after them (`None`: none
    /// does). Needs h^n in `start[0]`.
    fn hyperbolic_and_transport(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
    ) -> Result<Option<RangeInclusive<usize>>, StageError> {
        if let Some(limiter) = self.limiter {
            self.split_potential(mesh, dt, &s.phi, limiter);
        }
        // The monolayer's hyperbolic step on the state's own (h, hv), ghosts as the
        // monolayer's.
        if self.law.k == 0.0 {
            // The Savage–Hutter μ(I) threshold (bit for bit the monolayer's step with
            // uniform φ).
            let law = reconstruction_law(&self.law, self.phi_ref);
            let faces = IncompressibleFaces {
                law: &law,
                h: &self.start[0],
                phi: &s.phi,
                cut: &self.cut,
            };
            self.hyperbolic
                .advance_monolayer(mesh, dt, &mut s.h, &mut s.hu, &faces)?;
        } else {
            // μ_eff with the smaller φ of each face's two cells at t^n; start[0]
            // holds h at t^n.
            let faces = DilatantFaces {
                law: &self.law,
                h_thin: self.opt.h_thin,
                h: &self.start[0],
                phi: &s.phi,
                cut: &self.cut,
            };
            self.hyperbolic
                .advance_monolayer(mesh, dt, &mut s.h, &mut s.hu, &faces)?;
        }
        let r = dt / mesh.dx;
        if self.limiter.is_some() {
            // The interior force −g_c h ∂_x ζ of the reconstructed cells, with h^n.
            let (h_old, g_c, nx) = (&self.start[0], mesh.g_n, mesh.nx);
            let cells = s.h[1..=nx].iter().zip(&mut s.hu[1..=nx]);
            for ((h, q), (h_old, rise)) in
                cells.zip(h_old[1..=nx].iter().zip(&self.interior[1..=nx]))
            {
                if *rise != 0.0 && *h > H_DRY {
                    *q -= r * g_c * h_old * rise;
                }
            }
        }
        s.fill_thickness_ghosts(mesh);
        self.phi_new.copy_from_slice(&s.phi);
        // Cells holding mass after the step: every pass below is restricted to them.
        let Some(wet) = wet_cells(&s.h, mesh.nx) else {
            return Ok(None);
        };
        // h^n (start[0]) lent to the transport without a copy.
        let h_old = std::mem::take(&mut self.start[0]);
        let moved = match self.limiter {
            None => self.transport(&h_old, &s.h, &s.phi, r, wet.clone()),
            Some(limiter) => {
                self.transport_second_order(&h_old, &s.h, &s.phi, r, wet.clone(), limiter)
            }
        };
        self.start[0] = h_old;
        moved?;
        fill_fraction_ghosts(&mut self.phi_new);
        Ok(Some(wet))
    }

    /// Order 2: the volume-fraction potential ζ (∂_x ζ = h/(2φ) ∂_x φ) reconstructed as
    /// the surface is ([`crate::numerics::muscl`]): a cell that moves faster than its
    /// static friction's impulse per step (|v| > Δt μ_1 g_c, the rule of the hyperbolic
    /// step's reconstruction) with both neighbours wet carries the rise
    /// ½ h_i/(2φ_i) σ_i^φ of ζ from its centre to each edge (σ^φ the limited slope of
    /// φ). Where both cells of a face carry it, the face's jump between the centres
    /// loses these two halves (`cut`) and each cell takes its half inside, as the force
    /// −g_c h_i^n × (its rise) (`interior`); other faces keep the whole jump, as at
    /// order 1. The sum of the forces is unchanged; what changes is that a face of a
    /// smooth flow sees a jump of O(Δx²) instead of O(Δx): the hydrostatic
    /// reconstruction's source g_c(h² − (h − Δζ)²)/2 carries an error of g_c Δζ²/2 per
    /// face, which with jumps of O(Δx) cost the scheme its second order (observed 1.7
    /// on a smooth wave with non-uniform φ, 2.0 with uniform φ). At rest every cell
    /// keeps the order-1 faces.
    fn split_potential(&mut self, mesh: &Line, dt: f64, phi: &[f64], limiter: Limiter) {
        let nx = mesh.nx;
        let (h, hu) = (&self.start[0], &self.start[1]);
        let law = reconstruction_law(&self.law, self.phi_ref);
        let g_c = mesh.g_n;
        // Per cell the half rise (NaN where not reconstructed), in `interior` first.
        let half = &mut self.interior;
        half[0] = f64::NAN;
        half[nx + 1] = f64::NAN;
        for j in 1..=nx {
            let wet = h[j - 1] > H_DRY && h[j] > H_DRY && h[j + 1] > H_DRY;
            half[j] = f64::NAN;
            if !wet {
                continue;
            }
            let speed = (hu[j] / h[j]).abs();
            if speed <= dt * g_c * BasalFriction::mu(&law, 0.0, h[j], g_c * h[j]) {
                continue;
            }
            let slope = limiter.slope(phi[j] - phi[j - 1], phi[j + 1] - phi[j]);
            half[j] = 0.25 * h[j] / phi[j] * slope;
        }
        for k in 0..=nx {
            let (l, r) = (half[k], half[k + 1]);
            self.cut[k] = if l.is_nan() || r.is_nan() { 0.0 } else { l + r };
        }
        // The rise inside each cell: its halves on the faces that cut them.
        let mut west_cut = false;
        for j in 1..=nx {
            let east_cut = !half[j].is_nan() && !half[j + 1].is_nan();
            let halves = west_cut as u8 + east_cut as u8;
            let own = half[j];
            half[j] = if halves == 0 {
                0.0
            } else {
                own * halves as f64
            };
            west_cut = east_cut;
        }
        (half[0], half[nx + 1]) = (0.0, 0.0);
    }

    /// Steps 3–4 on (h, hv) of `s` in place and on φ in `phi_new`, over the cells
    /// `wet`.
    fn cell_pass(
        &mut self,
        mesh: &Line,
        s: &mut DilatantState,
        dt: f64,
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        self.cells(mesh, dt, &mut s.h, &mut s.hu, wet.clone())?;
        s.fill_thickness_ghosts(mesh);
        if self.law.k != 0.0 && !self.opt.viscosity.is_off() {
            self.stabilise(mesh, dt, &mut s.h, &mut s.hu, wet)?;
            s.fill_thickness_ghosts(mesh);
        }
        Ok(())
    }

    /// Step 2: φ^{n+1} from the mass fluxes of the hyperbolic step (`h_old` = h^n, `h`
    /// = h^{n+1}).
    ///
    /// Each face carries the φ of its donor cell, except that a cell whose outflow
    /// exceeds its content h^n (mass that enters and leaves within the step: the
    /// hyperbolic step only limits fluxes that would make h negative) gives its faces
    /// the φ of everything it held during the step, (φ h^n + inflow φ)/(h^n + inflow):
    /// with its own φ the weights of the update were no longer a convex combination
    /// (a cell of 0.45 beside one of 0.60 reached φ = 1.96, `split_scheme::
    /// random_states_stay_admissible`). Such a cell ends with exactly that φ; the others
    /// are updated as before, bit for bit.
    fn transport(
        &mut self,
        h_old: &[f64],
        h: &[f64],
        phi: &[f64],
        r: f64,
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (lo, end) = (*wet.start(), *wet.end() + 1);
        let flux = self.hyperbolic.mass_flux();
        let out = &mut self.phi_new;
        let donor = &mut self.phi_donor;
        // Faces lo − 1..end, cells lo − 1..=end: checked once, not per cell.
        assert!(lo >= 1 && end < phi.len() && end <= flux.len());
        assert!(phi.len() == h.len() && h.len() == out.len() && h_old.len() == h.len());
        assert!(donor.len() == h.len());
        donor[lo - 1] = phi[lo - 1];
        donor[end] = phi[end];
        for j in lo..end {
            let (f_in, f_out) = (flux[j - 1], flux[j]);
            let leaving = r * (f_out.max(0.0) + (-f_in).max(0.0));
            donor[j] = if leaving > h_old[j].max(0.0) {
                let (from_left, from_right) = (r * f_in.max(0.0), r * (-f_out).max(0.0));
                let content = h_old[j].max(0.0);
                (phi[j] * content + from_left * phi[j - 1] + from_right * phi[j + 1])
                    / (content + from_left + from_right)
            } else {
                phi[j]
            };
        }
        // Each face carries its donor's φ: the west and east edges of a cell are the same.
        update_phi(out, h, flux, phi, r, lo..end, (donor, donor))
    }

    /// Step 2 at order 2: φ^{n+1} from the mass fluxes of the hyperbolic step with the
    /// φ of a limited linear profile in each donor cell (van Leer 1979),
    ///
    ///   φ_{i−1/2}⁺ = φ_i − ½σ_i,   φ_{i+1/2}⁻ = φ_i + ½σ_i,   σ_i = Φ(φ_i − φ_{i−1}, φ_{i+1} − φ_i),
    ///
    /// the face carrying the edge value of its upwind cell, in the same conservative
    /// update of φh as [`Self::transport`]. A cell is reconstructed where it and both
    /// neighbours hold mass at t^n (h > `H_DRY`) and where the outflow through each of
    /// its faces is at most half its content, r 𝓕 ≤ ½ h_i^n. Then
    ///
    ///   φ_i h_i^n − r(𝓕_E φ_{i+1/2}⁻ + 𝓕_W φ_{i−1/2}⁺) = (½h_i^n − r𝓕_E) φ_{i+1/2}⁻ + (½h_i^n − r𝓕_W) φ_{i−1/2}⁺
    ///
    /// (φ_i the mean of its two edges; 𝓕_E, 𝓕_W its outflows), and with the inflows'
    /// edge values φ_i^{n+1} h_i^{n+1} is a combination with non-negative weights of
    /// edge values, each between two neighbouring cell values: φ stays within the
    /// bounds of its neighbours (a discrete maximum principle) and in (0, 1). Elsewhere
    /// the cell gives the first-order donor value of [`Self::transport`] (content rule
    /// included) to both its faces. With a uniform φ every σ is 0 and φ stays uniform
    /// bit for bit.
    fn transport_second_order(
        &mut self,
        h_old: &[f64],
        h: &[f64],
        phi: &[f64],
        r: f64,
        wet: RangeInclusive<usize>,
        limiter: Limiter,
    ) -> Result<(), StageError> {
        let (lo, end) = (*wet.start(), *wet.end() + 1);
        let flux = self.hyperbolic.mass_flux();
        let out = &mut self.phi_new;
        let (west, east) = (&mut self.phi_west, &mut self.phi_east);
        // Faces lo − 1..end, cells lo − 1..=end: checked once, not per cell.
        assert!(lo >= 1 && end < phi.len() && end <= flux.len());
        assert!(phi.len() == h.len() && h.len() == out.len() && h_old.len() == h.len());
        assert!(west.len() == h.len() && east.len() == h.len());
        for j in [lo - 1, end] {
            (west[j], east[j]) = (phi[j], phi[j]);
        }
        for j in lo..end {
            let (f_in, f_out) = (flux[j - 1], flux[j]);
            let content = h_old[j].max(0.0);
            let (out_east, out_west) = (r * f_out.max(0.0), r * (-f_in).max(0.0));
            let wet = h_old[j - 1] > H_DRY && h_old[j] > H_DRY && h_old[j + 1] > H_DRY;
            if wet && out_east <= 0.5 * content && out_west <= 0.5 * content {
                let half = 0.5 * limiter.slope(phi[j] - phi[j - 1], phi[j + 1] - phi[j]);
                (west[j], east[j]) = (phi[j] - half, phi[j] + half);
            } else if out_east + out_west > content {
                // The first-order content rule ([`Self::transport`]).
                let (from_left, from_right) = (r * f_in.max(0.0), r * (-f_out).max(0.0));
                let donor = (phi[j] * content + from_left * phi[j - 1] + from_right * phi[j + 1])
                    / (content + from_left + from_right);
                (west[j], east[j]) = (donor, donor);
            } else {
                (west[j], east[j]) = (phi[j], phi[j]);
            }
        }
        update_phi(out, h, flux, phi, r, lo..end, (west, east))
    }

    /// Step 3: friction and dilatancy, cell by cell.
    fn cells(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &mut [f64],
        hu: &mut [f64],
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        match (self.law.k != 0.0, !self.opt.viscosity.is_off()) {
            (false, _) => self.cells_with::<false, false>(mesh, dt, h, hu, wet),
            (true, false) => self.cells_with::<true, false>(mesh, dt, h, hu, wet),
            (true, true) => self.cells_with::<true, true>(mesh, dt, h, hu, wet),
        }
    }

    /// [`SplitScheme::cells`] for K ≠ 0 (`DILATANT`) and ξ ≠ 0 (`STABILISE`), so that
    /// the loop carries no test of either.
    fn cells_with<const DILATANT: bool, const STABILISE: bool>(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &mut [f64],
        hu: &mut [f64],
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (nx, g_c) = (mesh.nx, mesh.g_n);
        let law = &self.law;
        let h_thin = self.opt.h_thin;
        let incompressible = DilatantLaw { k: 0.0, ..*law };
        let phi = &mut self.phi_new;
        let mu = &mut self.mu;
        let (lo, hi_end) = (*wet.start(), *wet.end() + 1);
        // Every index below is < hi_end + 1 ≤ nx + 2: checked once, not per cell.
        assert!(lo >= 1 && hi_end < h.len() && h.len() == hu.len() && h.len() == phi.len());
        assert!(mu.len() == h.len());
        for i in lo..hi_end {
            let hi = h[i];
            let p = phi[i];
            let wet = hi > H_DRY;
            let mut q = hu[i];
            // The friction step of the monolayer (friction.rs), with μ_eff, backward
            // Euler: I_out is the inertial number of the new discharge.
            let mut i_out = 0.0;
            if q != 0.0 {
                if !wet {
                    q = 0.0;
                } else if DILATANT && hi >= h_thin {
                    (q, i_out) = dilatant_friction(law, g_c, dt, hi, q, p, wall(law, hi));
                } else {
                    // K = 0, or a layer thinner than `h_thin`: μ(I).
                    (q, i_out) = cell_friction(&incompressible, g_c, dt, hi, q, p);
                }
            }
            hu[i] = q;
            if DILATANT && wet && hi < h_thin {
                // Thinner than the threshold of Bouchut et al. 2021, §3.3: μ(I) friction (above),
                // φ frozen; its μ_eff for the stabilisation is μ(I) + μ_w h/W.
                if STABILISE {
                    mu[i] = law.mu_of_i(i_out) + wall(law, hi);
                }
                continue;
            }
            if DILATANT && wet {
                if q == 0.0 {
                    if STABILISE {
                        // Held by the friction: μ_eff is the static threshold at (h, φ),
                        // which the dilatancy step below leaves; formed only if a
                        // stabilisation face asks (`static_mu`).
                        mu[i] = -1.0;
                    }
                    continue;
                }
                let phi_eq = law.phi_eq(i_out);
                if STABILISE {
                    // μ_eff at the state after friction (2.13–2.14, 4.1), for the
                    // stabilisation's faces.
                    let wall = wall(law, hi);
                    mu[i] = (law.mu_of_i(i_out) + wall + law.tan_psi(p, phi_eq)).max(0.0);
                }
                // (3.15)–(3.19) with γ̇* = (5/2)|v*|/h*, φ_eq* = φ_eq(I*).
                let inv_h = 1.0 / hi;
                let v = q * inv_h;
                let rate = 2.5 * v.abs() * inv_h;
                let next = relax_towards(law, self.opt.update, dt, rate, p, phi_eq);
                if !(next > 0.0 && next < 1.0) {
                    return Err(StageError::Inadmissible {
                        cell: i - 1,
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
        mu[0] = mu[1];
        mu[nx + 1] = mu[nx];
        Ok(())
    }

    /// Step 4: the viscosity (3.20)–(3.22) on wet–wet faces.
    ///
    /// A face has a drive only if one of its cells moves (v_interf = 0 otherwise), and
    /// the diffusion runs over each run of consecutive active faces (a face with no
    /// drive carries no flux): its cost follows the moving cells, not the extent of
    /// the deposit (a collapse keeps a few cells moving at both ends of a long deposit
    /// at rest). Cells next to no active face are left as they are (sending them
    /// through (φh, φ^α h) → φ, h would change them at round-off).
    #[inline(never)]
    fn stabilise(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &mut [f64],
        hu: &mut [f64],
        wet: RangeInclusive<usize>,
    ) -> Result<(), StageError> {
        let (g_c, dx) = (mesh.g_n, mesh.dx);
        let alpha = self.opt.flux.alpha;
        let law = &self.law;
        let phi = &self.phi_new;
        let (mu, z) = (&self.mu, &mesh.z);
        let (drive, active) = (&mut self.drive, &mut self.active);
        active.clear();
        // Faces start..end (between two cells of the wet range); cells start..=end.
        let (start, end) = (*wet.start(), *wet.end());
        assert!(start >= 1 && end < h.len() && end < drive.len());
        assert!(h.len() == hu.len() && h.len() == phi.len() && h.len() == mu.len());
        assert!(z.len() > end);
        // μ_eff of cell j after the friction step.
        let cell_mu = |j: usize| {
            if mu[j] < 0.0 {
                static_mu(law, h[j], phi[j])
            } else {
                mu[j]
            }
        };
        let mut largest: f64 = 0.0;
        let alpha_term = 0.5 / (alpha - 1.0);
        for k in start..end {
            let (hl, hr) = (h[k], h[k + 1]);
            if hl <= H_DRY || hr <= H_DRY || (hu[k] == 0.0 && hu[k + 1] == 0.0) {
                continue;
            }
            // v_interf (3.8), X_interf Δx (3.12), μ_eff^interf as the mean of the
            // cells'.
            let (ml, mr) = (phi[k] * hl, phi[k + 1] * hr);
            let v = (phi[k] * hu[k] + phi[k + 1] * hu[k + 1]) / (ml + mr);
            let db_hat = z[k + 1] - z[k];
            let (al, ar) = (phi_power(phi[k], alpha), phi_power(phi[k + 1], alpha));
            let x = (hl - hr - db_hat + alpha_term * (hl + hr) * (al - ar) / (al + ar)) / dx;
            let mu = 0.5 * (cell_mu(k) + cell_mu(k + 1));
            let dz = db_hat + dx * proj_friction(mu, x, v / (g_c * dt));
            let d = (v * dz).max(0.0);
            if d > 0.0 {
                drive[k] = d;
                largest = largest.max(d);
                // Capacity nx + 1, one push per face at most: no allocation.
                match active.last_mut() {
                    Some((_, last)) if *last + 1 == k => *last = k,
                    _ => active.push((k, k)),
                }
            }
        }
        if largest == 0.0 {
            return Ok(());
        }
        // Runs of consecutive active faces a..=b and their cells a..=b + 1 (wet, inside
        // the wet range); two runs share no cell.
        let (active, drive): (&[(usize, usize)], &[f64]) = (active, drive);
        let [m, q, w] = &mut self.cons;
        assert!(m.len() == h.len() && q.len() == h.len() && w.len() == h.len());
        for &(a, b) in active {
            for j in a..=b + 1 {
                let mj = phi[j] * h[j];
                m[j] = mj;
                q[j] = phi[j] * hu[j];
                w[j] = mj * phi_power(phi[j], alpha);
            }
        }
        let visc = self.opt.viscosity;
        let n = visc.substeps(largest, dt, dx).map_err(|ratio| {
            let k = drive.iter().position(|&d| d == largest).unwrap_or(0);
            StageError::Inadmissible {
                cell: k.min(mesh.nx - 1),
                quantity: "stabilisation sub-steps needed in one step (dilatancy.xi too large)",
                value: ratio,
            }
        })?;
        let r = dt / n as f64 / (dx * dx);
        for k in 0..n {
            if crate::numerics::interrupted_at(k) {
                return Err(StageError::Interrupted);
            }
            for (c, u) in [&mut *m, &mut *q, &mut *w].into_iter().enumerate() {
                let xi = visc.xi[c];
                if xi == 0.0 {
                    continue;
                }
                let rate = r * xi;
                for &(a, b) in active {
                    diffuse_run(&mut u[a..=b + 1], &drive[a..=b], rate);
                }
            }
        }
        let phi = &mut self.phi_new;
        for &(a, b) in active {
            for j in a..=b + 1 {
                let p = phi_from_ratio(w[j] / m[j], alpha);
                if !(p > 0.0 && p < 1.0) {
                    return Err(StageError::Inadmissible {
                        cell: j - 1,
                        quantity: "volume fraction φ (stabilisation step)",
                        value: p,
                    });
                }
                phi[j] = p;
                h[j] = m[j] / p;
                hu[j] = q[j] / p;
            }
        }
        fill_fraction_ghosts(&mut self.phi_new);
        Ok(())
    }
}

/// μ_w h/W of eq. (4.1) (0 without walls), the one place it is formed.
#[inline(always)]
fn wall(law: &DilatantLaw, h: f64) -> f64 {
    if law.mu_w > 0.0 {
        law.mu_w * h / law.width
    } else {
        0.0
    }
}

/// The static threshold μ_eff(0) = max(0, μ_1 + μ_w h/W + K(φ − φ_stat)) of a cell
/// (2.16): max(0, μ(I) + μ_w h/W + K(φ − φ_eq(I))) at I = 0 bit for bit (μ(0) = μ_1 + 0
/// and φ_eq(0) = φ_stat exactly for every regularisation), without μ(I) and φ_eq(I).
#[inline(always)]
fn static_mu(law: &DilatantLaw, h: f64, phi: f64) -> f64 {
    (law.mu_1 + wall(law, h) + law.tan_psi(phi, law.phi_stat)).max(0.0)
}

/// The cells that hold mass (h > 0), first to last (ghost-inclusive indices), or
/// `None` if none does: the passes after the hyperbolic step visit only these (a cell
/// outside keeps h = 0, hv = 0 and its φ).
fn wet_cells(h: &[f64], nx: usize) -> Option<RangeInclusive<usize>> {
    let h = &h[1..=nx];
    let first = h.iter().position(|&h| h > 0.0)?;
    let last = nx - 1 - h.iter().rev().position(|&h| h > 0.0).unwrap_or(0);
    Some(first + 1..=last + 1)
}

/// Ghost fractions copy the edge cells (walls and outflow alike).
fn fill_fraction_ghosts(phi: &mut [f64]) {
    let n = phi.len();
    phi[0] = phi[1];
    phi[n - 1] = phi[n - 2];
}

impl Stage<Line, DilatantState> for SplitScheme {
    fn name(&self) -> &'static str {
        "dilatant"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut DilatantState,
    ) -> Result<(), StageError> {
        // On error the run loop restores the state of tⁿ.
        self.split_step(mesh, state, clock.dt)
    }
}

/// The conservative update of φh for cells `cells` from the mass fluxes `flux` (face k
/// between cells k and k + 1) and the φ each face carries, its upwind cell's edge
/// value (`edges` = (west, east) per cell): φ_j^{n+1} = φ_j − r (𝓕_E (φ_E − φ_j) −
/// 𝓕_W (φ_W − φ_j))/h_j^{n+1}, written into `out`. Dry cells and cells that nothing
/// crosses (a mass at rest) keep the φ already copied there. A φ outside (0, 1) is
/// refused, naming its cell.
fn update_phi(
    out: &mut [f64],
    h: &[f64],
    flux: &[f64],
    phi: &[f64],
    r: f64,
    cells: std::ops::Range<usize>,
    (west, east): (&[f64], &[f64]),
) -> Result<(), StageError> {
    for j in cells {
        let (hj, f_in, f_out) = (h[j], flux[j - 1], flux[j]);
        if hj <= 0.0 || (f_in == 0.0 && f_out == 0.0) {
            continue;
        }
        let p = phi[j];
        let up_out = if f_out > 0.0 { east[j] } else { west[j + 1] };
        let up_in = if f_in > 0.0 { east[j - 1] } else { west[j] };
        let change = f_out * (up_out - p) - f_in * (up_in - p);
        let value = p - r * change / hj;
        if !(value > 0.0 && value < 1.0) {
            return Err(StageError::Inadmissible {
                cell: j - 1,
                quantity: "volume fraction φ (transport)",
                value,
            });
        }
        out[j] = value;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::dilatancy::PhiEq;
    use proptest::prelude::*;

    proptest! {
        // About 11 % of draws are at rest (prop_assume); allow for that in long runs.
        #![proptest_config(ProptestConfig { max_global_rejects: 1 << 20, ..ProptestConfig::with_cases(4000) })]

        /// Newton from u = 0 against bisection: the same root to a few ulps, for every
        /// regularisation, stiff K, walls and loose states whose μ_eff is cut at 0.
        #[test]
        fn backward_euler_speed_is_the_root_to_round_off(
            reg in 0usize..5,
            k_dil in prop_oneof![0.0f64..20.0, 0.0f64..1e3],
            phi in 0.3f64..0.7,
            wall in prop_oneof![Just(0.0), 0.0f64..0.2],
            u_star in 1e-6f64..5.0,
            c in 1e-5f64..0.5,
            k in 1e-2f64..1e4,
        ) {
            let phi_eq = [PhiEq::Linear, PhiEq::F0, PhiEq::F1, PhiEq::F2 { n: 1.0 },
                PhiEq::F2 { n: 3.0 }][reg];
            let law = DilatantLaw { k: k_dil, phi_eq, ..DilatantLaw::table1() };
            let at_rest = (law.mu_1 + wall + law.tan_psi(phi, law.phi_stat)).max(0.0);
            prop_assume!(u_star > c * at_rest * (1.0 + 1e-9));
            // Bisection on u + c max(0, G(k u)) − u* to adjacent floats.
            let reference = {
                let g = |u: f64| {
                    let (gv, _) = friction_and_slope(&law, phi, wall, k * u);
                    u + c * gv.max(0.0) - u_star
                };
                let (mut lo, mut hi) = (0.0f64, u_star);
                while hi - lo > f64::EPSILON * hi {
                    let mid = 0.5 * (lo + hi);
                    if g(mid) < 0.0 { lo = mid } else { hi = mid }
                }
                0.5 * (lo + hi)
            };
            let (u, i) = backward_euler_speed(&law, phi, wall, u_star, c, k);
            // The residual u + c G − u* is evaluated with a round-off of order ε times
            // the sum of its terms' magnitudes: u*, and c times μ(I) ≤ μ_2, the wall
            // term and the two halves of K(φ − φ_eq(I)) at the root, which cancel
            // when φ is near φ_eq. Both roots are determined to that over g'(u) ≥ 1,
            // not to ε u. (Bound ε u* alone failed on K 5.93, φ 0.456, c 0.4356,
            // u* 0.061: Newton 13 ulps and bisection 22 ulps from a 60-digit root.)
            let phi_eq_root = law.phi_eq_and_slope(k * reference).0.abs();
            let scale = u_star + c * (law.mu_2 + wall + k_dil * (phi + phi_eq_root));
            prop_assert!((u - reference).abs() <= 4.0 * f64::EPSILON * scale,
                "u {} reference {} (rel. {:e})", u, reference, (u - reference) / reference);
            prop_assert!(u > 0.0 && u <= u_star);
            prop_assert_eq!(i, k * u);
        }
    }

    #[test]
    fn backward_euler_speed_limits() {
        let law = DilatantLaw::table1();
        assert!(backward_euler_speed(&law, 0.6, 0.0, f64::NAN, 0.01, 1.0)
            .0
            .is_nan());
        // A very loose mass: μ_eff = 0 up to u*, no friction at all.
        let (u, _) = backward_euler_speed(&law, 0.3, 0.0, 1e-3, 0.01, 1.0);
        assert_eq!(u, 1e-3);
        // With K = 0 the dilatant friction is μ(I): the monolayer's closed form.
        let law0 = DilatantLaw { k: 0.0, ..law };
        let (u, _) = backward_euler_speed(&law0, 0.6, 0.0, 0.3, 0.05, 2.0);
        let closed = crate::physics::rheology::backward_euler_speed(
            law.mu_1, law.mu_2, law.i0, 0.3, 0.05, 2.0,
        );
        assert!(
            (u - closed).abs() <= 4.0 * f64::EPSILON * closed,
            "{u} {closed}"
        );
    }
}
