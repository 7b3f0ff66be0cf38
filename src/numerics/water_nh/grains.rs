//! The grains' share of the water projection: the two-way coupling of the
//! non-hydrostatic water with the grain layer of the two-layer model
//! (docs/numerics.md, "Grains: both ways").
//!
//! The grains are hydrostatic in Fernández-Nieto et al. 2008; the water's pressure at
//! the interface enters their momentum as the coupling term B₄₁ ∂_x H₁ =
//! −r A₁ g H₂ cos³θ ∂_x H₁ (eq. 65), i.e. −r A₁ H₂ cos θ ∂_x p with p = g H₁cos²θ the
//! hydrostatic interface pressure over water density. The non-hydrostatic pressure
//! p_{1/2} at the interface enters the same way, as the impulse
//!
//!   δQ₂,i = −r A₁ H₂,i cos θ_i (Π_{i+1/2} − Π_{i−1/2})/Δx,   Π = Δt p_{1/2}      (G1)
//!
//! (a column with a pressure p uniform over it feels −h ∂_x p: the pressure at the bed,
//! p, is the interface's). The grain flux changes the bottom's rate, ∂_t z_b =
//! −∂_x q with q the horizontal grain discharge in vertical measure, d₂ u_x =
//! H₂ cos²θ · U₂ cos θ = cos³θ Q₂; the rate of the correction, taken at the face where
//! the constraint lives,
//!
//!   δż_{b,f} = −(cos³θ_{f+1} δQ₂,f+1 − cos³θ_f δQ₂,f)/Δx,                         (G2)
//!
//! enters the first constraint of face f (the bottom layer's, w_1 − ż_b − …) besides
//! the rate ż_b of the two-layer step. (G1) and (G2) are adjoint in the grains' kinetic
//! energy Σ m_i U₂,i²/2, m_i = H₂,i cos²θ_i/(r A₁) (the grain column's mass over
//! water density, for A₁ = 1): with v = U₂, (G2) is G δv with G_{f,f+1} = cos³θ H₂/Δx,
//! G_{f,f} = −cos³θ H₂/Δx, and (G1) is δv = m⁻¹ GᵀΠ. The coupled system is
//!
//!   (A + G m⁻¹ Gᵀ) Π = −𝒞,   (G m⁻¹ Gᵀ)_{ff} = κ_f + κ_{f+1},
//!   (G m⁻¹ Gᵀ)_{f,f+1} = −κ_{f+1},   κ_i = r A₁ cos⁴θ_i H₂,i/Δx²,
//!
//! still symmetric positive definite, and its new entries couple the bottom unknowns
//! of neighbouring faces only: inside the band of A (offset N), which is unchanged. The
//! added mass of the water is implicit: the grains' acceleration and the interface
//! pressure are solved together.
//!
//! Cells whose grains the step left at rest (Q₂ = 0: held by the Coulomb rule, or not
//! set in motion) are a fixed bottom for the projection (κ_i = 0, m_i = ∞): the static
//! friction takes the non-hydrostatic force there, so a deposit held by friction stays
//! exactly at rest. Grain films of vertical thickness below the water operator's wet
//! threshold take no part either (as the water's own films): the rate the two-layer
//! step gives a draining film (limited fluxes, desingularised velocity) is not the
//! rate (G2) expects of it, and the pressure answering the difference accelerated
//! such films without bound (docs/numerics.md). At an outflow boundary the edge face's pressure is its
//! neighbour's ([`MultilayerOperator`]), so the edge cell feels no pressure difference
//! and takes no part (κ = 0).

use std::ops::Range;

use crate::numerics::banded::StencilRow;
use crate::numerics::linalg::{BandReady, PressureRows};
use crate::numerics::projection::multilayer::{MultilayerOperator, MultilayerRows};

/// The rows of the coupled system (A + G m⁻¹ Gᵀ) Π = −𝒞: the water's rows of
/// [`MultilayerRows`] with the grains' terms added to the bottom unknowns (module
/// documentation). `kappa` has one value per cell with ghosts (0 for the ghosts and
/// the cells that take no part); `diag` and `lower` one per face: κ_f + κ_{f+1} on the
/// diagonal of face f's bottom unknown and −κ_{f+1} between it and face f + 1's, 0
/// where either face carries no unknown ([`CoupledRows::face_terms`]); `terms` the
/// faces outside which both are 0.
pub struct CoupledRows<'a> {
    pub water: MultilayerRows<'a>,
    pub op: &'a MultilayerOperator,
    pub diag: &'a [f64],
    pub lower: &'a [f64],
    pub terms: Range<usize>,
}

impl CoupledRows<'_> {
    /// The per-face terms `diag`, `lower` (nx + 1 each) from κ per cell (nx + 2) and
    /// the faces with unknowns of `op`; returns the faces outside which both are 0
    /// (those of the cells `cells` with κ > 0, `cells` spanning them).
    pub fn face_terms(
        op: &MultilayerOperator,
        kappa: &[f64],
        cells: Range<usize>,
        diag: &mut [f64],
        lower: &mut [f64],
    ) -> Range<usize> {
        let faces = kappa.len() - 1;
        let mut here = op.carries_unknowns(0);
        let terms = diag[..faces]
            .iter_mut()
            .zip(&mut lower[..faces])
            .zip(kappa.windows(2));
        for (f, ((diag, lower), k)) in terms.enumerate() {
            let next = f + 1 < faces && op.carries_unknowns(f + 1);
            *diag = if here { k[0] + k[1] } else { 0.0 };
            *lower = if here && next { k[1] } else { 0.0 };
            here = next;
        }
        // Face f holds cells f and f + 1.
        cells.start.saturating_sub(1).min(faces)..cells.end.min(faces)
    }
}

impl PressureRows for CoupledRows<'_> {
    type Row = StencilRow;

    fn active(&self) -> Range<usize> {
        self.water.active()
    }

    fn row(&self, k: usize) -> StencilRow {
        let mut row = self.water.row(k);
        let n = self.op.layers();
        let (f, j) = (k / n, k % n);
        if j != 0 || !self.op.carries_unknowns(f) {
            return row;
        }
        row.coef[1][1] += self.diag[f];
        if f >= 1 {
            row.coef[0][1] -= self.lower[f - 1];
        }
        row.coef[2][1] -= self.lower[f];
        row
    }

    /// The water's band (its own assembly), with the grains' terms added to each
    /// column as the assembly reports it final, before the solver factorises it: the
    /// diagonal of each face's bottom unknown and its entry in the row of the next
    /// face's bottom unknown (offset N in the column).
    fn assemble_band(
        &self,
        band: &mut [f64],
        rhs: &mut [f64],
        p: usize,
        stride: usize,
        ready: &mut BandReady,
    ) -> bool {
        let n = self.op.layers();
        let active = self.water.active();
        let (f0, faces) = (active.start / n, active.len() / n);
        debug_assert_eq!(active.start % n, 0);
        let (diag, lower) = (&self.diag[f0..f0 + faces], &self.lower[f0..f0 + faces]);
        // The faces with grain terms, relative to f0 (the others add exact zeros: the
        // diagonal is positive, x − 0 = x).
        let from = self.terms.start.saturating_sub(f0).min(faces);
        let to = self.terms.end.saturating_sub(f0).min(faces).max(from);
        let mut done = from; // faces before this one have their grain terms
        let mut add = |band: &mut [f64], end: usize| {
            // Faces whose bottom column (f·n) is final.
            let end = end.div_ceil(n).min(to);
            for f in done..end {
                let col = &mut band[f * n * stride..][..n + 1];
                col[0] += diag[f];
                col[n] -= lower[f];
            }
            done = done.max(end);
        };
        self.water
            .assemble_band(band, rhs, p, stride, &mut |band, rhs, c| {
                add(band, c);
                ready(band, rhs, c);
            })
    }
}

/// The grains' impulse (G1) on the cells with κ_i > 0: Q₂,i −= c H₂,i cos θ_i
/// (Π_{i+1/2} − Π_{i−1/2})/Δx with c = r A₁ and Π the bottom impulses of the faces
/// (`pi` face-major with `n` unknowns per face, 0 on faces without unknowns).
#[allow(clippy::too_many_arguments)]
pub fn push_grains(
    kappa: &[f64],
    pi: &[f64],
    n: usize,
    c: f64,
    h2: &[f64],
    cos: &[f64],
    dx: f64,
    q2: &mut [f64],
) {
    let nx = kappa.len() - 2;
    let scale = c / dx;
    for i in 1..=nx {
        if kappa[i] > 0.0 {
            q2[i] -= scale * h2[i] * cos[i] * (pi[i * n] - pi[(i - 1) * n]);
        }
    }
}
