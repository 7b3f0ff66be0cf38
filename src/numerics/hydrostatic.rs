//! Step 1 of the splitting: the hyperbolic (hydrostatic) problem (Garres-Díaz et al. 2021, eq. 17–24,
//! Escalante et al. 2023, eq. 19–21), for the total mass and the discharge of each of the N layers
//! (N = 1: the monolayer; Escalante et al. 2023, §4 step 1 with p_nh = 0):
//!
//!   ∂_t h + ∂_X(hū) = 0,
//!   ∂_t(hu_α) + ∂_X(hu_α²) + g_n h ∂_X(h + z) = (u_{α+1/2} G_{α+1/2} − u_{α−1/2} G_{α−1/2})/l_α,
//!
//! with ū = Σ l_α u_α, the mass exchange G_{α+1/2} = Σ_{β≤α} l_β ∂_X(h(u_β − ū))
//! (Escalante et al. 2023, eq. 5, Fernández-Nieto et al. 2016, eq. 19), G_{1/2} = G_{N+1/2} = 0, and the centred interface
//! velocity u_{α+1/2} = ½(u_α + u_{α+1}). The right-hand side is the non-conservative
//! product −𝓑(U)∂_X U of Escalante et al. 2023, eq. (18); it vanishes for N = 1.
//!
//! Path-conservative finite volumes with the HLL-type PVM diffusion:
//!
//!   U_i ← U_i − Δt/Δx (𝓕_{i+1/2} − 𝓕_{i−1/2} + ½(𝓑_{i+1/2} + 𝓑_{i−1/2}) + 𝓢ᴸ_{i+1/2} + 𝓢ᴿ_{i−1/2}),
//!   𝓕 = ½(F_c(U_L) + F_c(U_R)) − ½[α_0 (Ũ⁺ − Ũ⁻) + α_1 (F_c(U_R) − F_c(U_L) + 𝓑)],
//!   𝓢ᴸ = θ_L 𝓢 − m α_1 𝓢̃,   𝓢ᴿ = θ_R 𝓢 + m α_1 𝓢̃,
//!   θ_L = h_L/(h_L + h_R),   θ_R = 1 − θ_L,   m = min(θ_L, θ_R),
//!   𝓢 = (0, g_n ½(h_L + h_R)(h⁺ − h⁻), …),   𝓢̃ the same with ĥ^±,
//!   𝓑_α = −(ũ_{α+1/2} ΔG_{α+1/2} − ũ_{α−1/2} ΔG_{α−1/2})/l_α,
//!
//! where ΔG_{α+1/2} = Σ_{β≤α} l_β (Δq_β − Δq̄) is the jump of the exchange across the
//! interface (q_β = h u_β) and ũ_{α+1/2} the mean of u_{α+1/2} on both sides, i.e.
//! 𝓑 = ½(B(U_L) + B(U_R))(U_R − U_L) (Escalante et al. 2023, eq. 19). Each layer's momentum is
//! upwinded with its own velocity through Ũ^± = (ĥ^±, ĥ^± u_α). The wave speeds are
//! those of Escalante et al. 2023 (after eq. 21) with √(g_n h) replaced, for N > 1, by
//! √(g_n h + 3 Σ l_α (u_α − ū)²), which bounds the outer eigenvalues of a sheared
//! column: with ū ± √(g_n h) alone a Bagnold profile at Froude number ≈ 1 looks
//! supercritical, the flux is fully upwinded and the uniform flow is unstable
//! (`docs/numerics.md`, Multilayer).
//!
//! with the hydrostatic reconstruction h⁻ = max(0, h_L − (Δb)_+), h⁺ = max(0, h_R − (−Δb)_+)
//! over the bed b relative to the reference plane (Escalante et al. 2023, eq. 20), the plane's own
//! slope entering 𝓢 = g_n h̄ (h⁺ − h⁻ + Δb̃) as the jump Δb̃ of the potential (zero
//! across a wall). The source enters with a minus sign: Garres-Díaz et al. 2021, eq. (20) prints "+",
//! which contradicts ∂_t(hu) = −g_n h ∂_X(h + z).
//!
//! The pressure source of a face goes to its two cells in proportion to their own
//! depths: at rest each cell takes g_n h Δη/2, and in the upwind part m α_1 𝓢̃ the
//! thinner side bounds the share. With h_L = h_R this is the printed scheme (θ = m = ½:
//! ½𝓢 each, α_1 𝓢̃ inside the flux jump). The printed split gives a film beside a thick
//! cell half of g_n h̄ Δη, h̄ ≈ h_thick/2, i.e. an acceleration ∝ h_thick/h_film: films at
//! fronts and bed steps reached 10²–10⁴ m/s and the time step collapsed
//! (`tests/properties.rs`). With the own-depth split every cell's pressure force is
//! g_n h_i × (a surface slope), the friction step can weigh h_i itself (no ĥ of Escalante et al. 2023,
//! eq. 25), and a mass at rest with |η_{i+1} − η_{i−1}| ≤ 2Δx μ_s is held exactly.
//!
//! The exchange term 𝓑 of a face (N > 1) is split the same way: the left cell takes
//! (θ_L − m α_1) 𝓑 and the right cell (θ_R + m α_1) 𝓑, which sum to 𝓑 and are the
//! printed ½(1 ∓ α_1) 𝓑 (½𝓑 each, α_1 𝓑 inside the flux jump) where h_L = h_R. 𝓑
//! carries the jump of h(u_α − ū), i.e. the shear of the thicker side: with the
//! printed split a film beside a sheared column took half of it or, upwind of a front
//! (α_1 = ±1), all of it, an impulse ∝ h_thick/h_film that only moves the layers
//! against each other (Σ l_α 𝓑_α = 0). A film 3–10 µm thick ahead of a 12 mm column
//! climbing a 30° bed (the multilayer run of nh_complex_topography.toml with 10
//! layers) grew layer velocities of ±10²–10⁴ m/s, step after step, that the viscous
//! step cannot take out (its stress is bounded by μ p, tiny in a film), and the time
//! step collapsed at t = 1.44 s. With the own-depth split a film takes at most 2 m of
//! 𝓑: the shear it gets is that of its own depth.
//!
//! Thin layers on steep beds. Where the lower side of a face is
//! thinner than the bed step (h_L < Δb, or h_R < −Δb), h^± is clipped at 0 and 𝓢 sees
//! the lower side's surface raised to the higher side's bed: a layer of depth h on a
//! bed sampled with steps Δb = b' Δx > h felt g_n h²/(2Δx) per face instead of
//! g_n h b'/2, so Coulomb films up to 3.6 mm thick stayed exactly at rest on 25–55°
//! slopes with δ = 24° (5.4 % of the mass at 300 cells, `tests/well_balanced.rs`). The clipping is right only for the
//! lower side of a shoreline (a layer against a bed that rises above its surface, the
//! lake at rest). So at a clipped face:
//! - the higher side takes its share of the unclipped g_n h̄ (η_R − η_L + Δb̃): its
//!   layer lies on the slope, whatever lies below it;
//! - the lower side takes the clipped source plus the fraction min(1, h_higher/h_lower)
//!   of the difference: the part of its face that the neighbour's layer covers (a
//!   pond below a film of 1 µm feels 1 µm's worth, two comparable films the full
//!   slope, a lake against a dry bank nothing).
//!
//! Unclipped faces keep 𝓢 as printed.
//!
//! Near-dry cells. The gravity part of a cell's source (bed and plane,
//! i.e. 𝓢 minus the flat-bed pressure g_n h̄ (h_R − h_L), which stays as it is so
//! that the shares of a face still sum to the jump of g_n h²/2 and shocks keep their
//! speed) is weighted by min(h^{n+1}, h^n)/h^n (the share of the mass that left is
//! taken back): the impulse goes to the mass that stayed in the cell for the whole
//! step. With h^n, a draining cell at the trailing edge of a
//! film on a 30° plane (h^{n+1} ≈ 0.7 h^n) gave the gravity impulse of the departed mass
//! to what remained, and its speed grew to 2.2–2.5 m/s against the bulk's 1.81 m/s
//! (`tests/properties.rs`). Now each remaining parcel gets g_n tan θ Δt, so after the
//! upwinded transport (a mass-weighted mean of the velocities that enter) no cell is
//! faster than its inflow plus the physical acceleration. At rest, and wherever the
//! depth does not fall, nothing is taken back: the source is unchanged to the bit.
//!
//! Two more departures from the printed flux, both for positivity and both
//! tested (`tests/properties.rs`, `tests/analytic.rs`):
//! - F_c is evaluated at the reconstructed states U^± = (h^±, h^± u_α) (as in Audusse
//!   et al.'s hydrostatic reconstruction), not at the cell states: with cell states a
//!   wet cell moving away from a dry step drains the dry cell, for any Δt.
//! - Reconstructing over b only (not b + b̃) keeps thin layers on steep planes
//!   visible: over b + b̃ every layer thinner than tan θ Δx (2 mm at 22° with
//!   Δx = 5 mm, thicker than the erodible beds of Fernández-Nieto et al. 2016, §4.2) would be clipped
//!   to h⁺ = 0 and feel a reduced gravity.
//!
//! Positivity: if a step would empty a cell (possible at wet/dry fronts, where the
//! Coulomb-aware diffusion and the HLL bounds stop matching), the outgoing mass and
//! momentum fluxes of that cell are scaled to what it holds (the "draining time"
//! limiter of Bollermann, Chen, Kurganov & Noelle 2013). Each interface flux is used
//! by both neighbours, so mass stays exactly conserved; steps that need no limiting
//! are untouched.
//!
//! Granular masses at rest with |∂_X(h + z)| ≤ μ_s are kept exactly at rest by the
//! Coulomb-aware reconstruction Ũ^± (Garres-Díaz et al. 2021, eq. 22–24, Escalante et al. 2023, §4 step 1): the
//! jump Δz is replaced by Δz + ΔC, ΔC = −f Δx / g_n,
//!
//!   f = −proj_{g_n μ}( u_{1/2}/Δt − g_n (η_R − η_L)/Δx ),   η = h + z,
//!
//! so that at rest ĥ⁻ = ĥ⁺ and the mass diffusion vanishes; 𝓢̃ uses ĥ^± too
//! (Escalante et al. 2023, eq. 21). We follow Escalante et al. 2023's sign of u/Δt (Garres-Díaz et al. 2021, eq. 23 has the
//! opposite sign, which would make friction accelerate a moving mass) and its
//! division by g_n (without it ΔC is not a length).
//!
//! Wave speeds S_L, S_R: Einfeldt-type bounds with Roe averages (Garres-Díaz et al. 2021, after eq. 21).
//! Wet/dry fronts: an emerging bed (h_L > 0, h_R dry, h_L + b_L < b_R, and its mirror)
//! is seen with the wet state's velocities set to zero (Escalante et al. 2023, Remark 2).
//!
//! The state of a face's friction (N = 1): μ(I) grows with I ∝ |u|/h^{3/2}, and the
//! printed scheme leaves open at which state of the face it is taken. At the Roe speed
//! and mean depth, the face between the front cell of a deposit and the dry (or film)
//! cell ahead of it saw a layer half as thick as the cell, I ≈ 2.5 times the cell's,
//! and held back more than the friction step held the cell: a front cell whose surface
//! was steeper than μ_s kept the speed at which μ(I_cell) equals its drive while its
//! faces carried no mass, for ever (a Savage–Hutter μ(I) collapse on 22° with
//! μ_s = 0.48 kept 1.27 mm/s at its front after 20 s). A monolayer face now takes the
//! cells' own μ weighted by their depths, the weights of the own-depth split below
//! ([`BasalFriction::face_mu`], `physics::rheology::depth_weighted_mu`), and μ_s at
//! Roe speed 0 as before (so masses at rest are untouched to the bit); the other laws
//! (Coulomb, Voellmy: [`BasalFriction::face_mu`]'s default) and the N > 1 faces
//! keep the Roe state (`docs/validation.md`, dil-stop). The 2-D faces
//! (`hydrostatic_2d.rs`) take the same threshold with the cells' speeds |(u, v)|.
//!
//! Per-face friction: the threshold μ of ΔC comes from a [`FaceFriction`], by default
//! the step's own law (which ignores the face, so the default step is unchanged to the
//! bit). The dilatant model (Bouchut et al. 2021) passes μ_eff = μ(I) + tan ψ with the volume
//! fraction of each face ([`HydrostaticStep::apply_with_friction`]): its static
//! threshold μ_1 + K(φ − φ_stat) (Bouchut et al. 2021, eq. 2.16) depends on φ, which a
//! `BasalFriction` of (|u|, h, p) cannot see.
//!
//! A state at rest has u_α = 0, so ΔG = 0 and 𝓑 = 0: the exchange terms keep granular
//! masses at rest exactly at rest, like the monolayer.
//!
//! Order 2 ([`HydrostaticStep::second_order`], N = 1, and
//! [`HydrostaticStep::second_order_with_layers`]): the same face kernel on the edge
//! states of the limited reconstruction of [`super::muscl`], plus each reconstructed
//! cell's interior force and, for N > 1, its interior exchange term 𝓑^c (the face's
//! 𝓑 between the cell's own edges: ∂_X G inside the cell, which the faces' O(Δx²)
//! jumps no longer carry); the time integrator is [`super::ssp_rk2`].

use super::face::{
    drained_fraction, interface, interface_with_friction, layer_momentum_flux, mass_flux,
    monolayer_fluxes, Interface, Side,
};
use super::muscl::{self, Limiter};
use super::tracer::TracerTransport;
use super::{Stage, StageError, StepClock};
use crate::grid::{BoundaryKind, Line};
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::state::layered::LayeredState;

/// The friction coefficient that the Coulomb-aware reconstruction (ΔC) uses at a face:
/// `face` k lies between the ghost-inclusive cells k and k + 1 (k = 0..=nx), `speed` is
/// the Roe-averaged |ū| there, `h` the mean depth and `p_over_rho` = g_n h. Every basal
/// friction law is one (it ignores the face); a model whose threshold depends on more
/// than (|u|, h, p), such as the dilatant μ(I) + tan ψ (Bouchut et al. 2021, eq. 2.13–2.14), supplies
/// its own through [`HydrostaticStep::apply_with_friction`].
pub trait FaceFriction {
    fn mu(&self, face: usize, speed: f64, h: f64, p_over_rho: f64) -> f64;

    /// The threshold of a monolayer face between cells with (|u_L|, h_L) and
    /// (|u_R|, h_R), of Roe speed `speed` and mean depth `h` (p_b/ρ = g_n h). By default
    /// [`Self::mu`] at the Roe state; a friction law answers with
    /// [`BasalFriction::face_mu`] (μ(I): the cells' own μ, depth-weighted).
    #[inline(always)]
    fn face_mu(
        &self,
        face: usize,
        _left: (f64, f64),
        _right: (f64, f64),
        speed: f64,
        h: f64,
        g_n: f64,
    ) -> f64 {
        self.mu(face, speed, h, g_n * h)
    }

    /// An extra jump of the potential across `face` (m), added to Δz = z_R − z_L where
    /// the face's pressure source 𝓢 and its Coulomb-aware reconstruction (ΔC) see it:
    /// a force −g_n h ∂_X ζ that is not a bed, such as the volume-fraction pressure of
    /// the dilatant model (Bouchut et al. 2021, eq. 2.4). 0 by default: the step is
    /// then unchanged to the bit.
    #[inline(always)]
    fn potential_jump(&self, _face: usize) -> f64 {
        0.0
    }
}

impl<L: BasalFriction> FaceFriction for L {
    #[inline(always)]
    fn mu(&self, _face: usize, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        BasalFriction::mu(self, speed, h, p_over_rho)
    }

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
        BasalFriction::face_mu(self, left, right, speed, h, g_n)
    }
}

/// The hydrostatic step for N ≥ 1 layers, generic over the basal friction law (used in ΔC).
#[derive(Debug)]
pub struct HydrostaticStep<L: BasalFriction> {
    law: L,
    layers: usize,
    /// N > 1 only (empty for N = 1, whose interface loop computes ū as it goes): per
    /// cell with ghosts (nx + 2) mean velocity ū and shear term 3 Σ l_α (u_α − ū)² of
    /// the wave speed; per cell and layer: u_α.
    u_mean: Vec<f64>,
    shear: Vec<f64>,
    u: Vec<f64>,
    /// 1/l_α and Σ_{β≤α} l_β (N > 1).
    inv_l: Vec<f64>,
    l_below: Vec<f64>,
    /// Per interface (nx + 1): mass flux, pressure sources of the left and right cells.
    flux_h: Vec<f64>,
    share_left: Vec<f64>,
    share_right: Vec<f64>,
    /// Per interface (nx + 1): the gravity parts (bed and plane) of those sources.
    body_left: Vec<f64>,
    body_right: Vec<f64>,
    /// N > 1, per interface (nx + 1): the fractions of 𝓑 the left and right cells take.
    exchange_left: Vec<f64>,
    exchange_right: Vec<f64>,
    /// Per interface and layer ((nx + 1)·N, interface-major): momentum flux and, for
    /// N > 1, the exchange term 𝓑.
    flux_hu: Vec<f64>,
    exchange: Vec<f64>,
    /// N > 1 with tracers: per interface and layer, the layer's departure from the
    /// mean mass flux, ½(d_L + d_R) with d_α = h(u_α − ū) (sides as the fluxes see
    /// them); empty otherwise. The tracers' layer fluxes and vertical exchange follow
    /// from it ([`TracerTransport::after_step`]).
    layer_flux: Vec<f64>,
    h_new: Vec<f64>,
    /// Draining factors θ_j ∈ [0, 1] (nx + 2), used only when a cell would empty. The
    /// ghost entries stay 1; the interior ones are all rewritten by each use.
    drain: Vec<f64>,
    /// Transport of the state's tracers (idle when it has none).
    tracers: TracerTransport,
    /// The limiter of the second-order reconstruction ([`muscl`]), `None` at first order.
    limiter: Option<Limiter>,
    /// Order 2, per cell with ghosts (nx + 2): the interior pressure force 𝓢^c of a
    /// reconstructed cell and its gravity part (0 where first order).
    interior: Vec<f64>,
    interior_body: Vec<f64>,
    /// Order 2, per cell with ghosts: the cell's west and east edge states (its mean
    /// where first order).
    west: Vec<Side>,
    east: Vec<Side>,
    /// Order 2, per cell with ghosts: the limited slopes, `None` where first order,
    /// and what the reconstruction reads of each cell.
    slopes: Vec<Option<muscl::Slopes>>,
    cells: Vec<muscl::Cell>,
    /// Order 2 with N > 1, per cell with ghosts and layer ((nx + 2)·N, cell-major):
    /// the edge velocities u_α of the west and east edges (the cell's own where first
    /// order) and the exchange term 𝓑^c_α of the cell's interior (0 where first order).
    west_u: Vec<f64>,
    east_u: Vec<f64>,
    interior_exchange: Vec<f64>,
}

/// The layer fractions as the exchange terms use them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fractions<'a> {
    /// l_α.
    pub(crate) l: &'a [f64],
    /// 1/l_α.
    pub(crate) inv: &'a [f64],
    /// Σ_{β≤α} l_β.
    pub(crate) below: &'a [f64],
}

/// The exchange terms 𝓑_α of one interface (N > 1), written into `out` (N values).
/// `u_l`, `u_r` are the layer velocities the fluxes see on each side.
///
/// ΔG_{α+1/2} = Σ_{β≤α} l_β Δq_β − (Σ_{β≤α} l_β) Δq̄ is a running sum, so the whole
/// interface costs one pass over the layers after the one for Δq̄.
#[inline(always)]
pub(crate) fn exchange_terms(
    frac: Fractions,
    h_l: f64,
    h_r: f64,
    u_l: &[f64],
    u_r: &[f64],
    out: &mut [f64],
) {
    carried_exchange_terms(frac, (h_l, h_r), (u_l, u_r), (u_l, u_r), out);
}

/// The exchange terms of a quantity t_α carried by the vertical mass exchange of one
/// interface: −(t̃_{α+1/2} ΔG_{α+1/2} − t̃_{α−1/2} ΔG_{α−1/2})/l_α, with ΔG from the
/// normal velocities `u` = (u_l, u_r) and t̃ the mean of the interface values of `t`
/// on both sides. With t = u this is [`exchange_terms`] (the same operations); on a
/// raster the tangential velocity of each layer is the t of a face
/// (`numerics::layers_2d`).
#[inline(always)]
pub(crate) fn carried_exchange_terms(
    frac: Fractions,
    (h_l, h_r): (f64, f64),
    (u_l, u_r): (&[f64], &[f64]),
    (t_l, t_r): (&[f64], &[f64]),
    out: &mut [f64],
) {
    let n = frac.l.len();
    let (l, inv_l, l_below) = (frac.l, &frac.inv[..n], &frac.below[..n]);
    let (u_l, u_r, out) = (&u_l[..n], &u_r[..n], &mut out[..n]);
    let (t_l, t_r) = (&t_l[..n], &t_r[..n]);
    let mut dq_mean = 0.0;
    for a in 0..n {
        dq_mean += l[a] * (h_r * u_r[a] - h_l * u_l[a]);
    }
    // Running Σ_{β≤α} l_β Δq_β, and the flux t̃_{α+1/2} ΔG_{α+1/2} below layer α + 1.
    let mut partial = 0.0;
    let mut below = 0.0;
    for a in 0..n - 1 {
        partial += l[a] * (h_r * u_r[a] - h_l * u_l[a]);
        let g_jump = partial - l_below[a] * dq_mean;
        let above = 0.25 * (t_l[a] + t_l[a + 1] + t_r[a] + t_r[a + 1]) * g_jump;
        out[a] = (below - above) * inv_l[a];
        below = above;
    }
    out[n - 1] = below * inv_l[n - 1];
}

impl<L: BasalFriction> HydrostaticStep<L> {
    /// The monolayer step (N = 1).
    pub fn new(law: L, nx: usize) -> Self {
        Self::with_layers(law, nx, 1)
    }

    /// The step for `layers` ≥ 1 layers.
    pub fn with_layers(law: L, nx: usize, layers: usize) -> Self {
        assert!(layers >= 1);
        let per_cell = |len: usize| {
            if layers > 1 {
                vec![0.0; len]
            } else {
                Vec::new()
            }
        };
        HydrostaticStep {
            law,
            layers,
            u_mean: per_cell(nx + 2),
            shear: per_cell(nx + 2),
            u: per_cell((nx + 2) * layers),
            inv_l: vec![0.0; layers],
            l_below: vec![0.0; layers],
            flux_h: vec![0.0; nx + 1],
            share_left: vec![0.0; nx + 1],
            share_right: vec![0.0; nx + 1],
            body_left: vec![0.0; nx + 1],
            body_right: vec![0.0; nx + 1],
            flux_hu: vec![0.0; (nx + 1) * layers],
            exchange: if layers > 1 {
                vec![0.0; (nx + 1) * layers]
            } else {
                Vec::new()
            },
            exchange_left: per_cell(nx + 1),
            exchange_right: per_cell(nx + 1),
            layer_flux: Vec::new(),
            h_new: vec![0.0; nx + 2],
            drain: vec![1.0; nx + 2],
            tracers: TracerTransport::default(),
            limiter: None,
            interior: Vec::new(),
            interior_body: Vec::new(),
            west: Vec::new(),
            east: Vec::new(),
            slopes: Vec::new(),
            cells: Vec::new(),
            west_u: Vec::new(),
            east_u: Vec::new(),
            interior_exchange: Vec::new(),
        }
    }

    /// The monolayer step with the second-order reconstruction of [`muscl`] and
    /// `limiter` (the time integrator is the caller's: [`super::ssp_rk2`]).
    pub fn second_order(law: L, nx: usize, limiter: Limiter) -> Self {
        Self::second_order_with_layers(law, nx, 1, limiter)
    }

    /// The step for `layers` ≥ 1 layers with the second-order reconstruction (N = 1:
    /// [`Self::second_order`]; N > 1: `reconstruct_layers`).
    pub fn second_order_with_layers(law: L, nx: usize, layers: usize, limiter: Limiter) -> Self {
        let mut step = Self::with_layers(law, nx, layers);
        if layers > 1 {
            step.west_u = vec![0.0; (nx + 2) * layers];
            step.east_u = vec![0.0; (nx + 2) * layers];
            step.interior_exchange = vec![0.0; (nx + 2) * layers];
        }
        let dry = Side::monolayer(0.0, 0.0, 0.0, 0.0);
        step.limiter = Some(limiter);
        step.tracers = TracerTransport::second_order(limiter);
        step.interior = vec![0.0; nx + 2];
        step.interior_body = vec![0.0; nx + 2];
        step.west = vec![dry; nx + 2];
        step.east = vec![dry; nx + 2];
        step.slopes = vec![None; nx + 2];
        step.cells = vec![muscl::Cell::new(0.0, 0.0, 0.0); nx + 2];
        step
    }

    /// N > 1: velocities u_α and ū of every cell, ghosts included, the shear term of
    /// the wave speed and the inverse layer fractions.
    fn velocities(&mut self, state: &LayeredState) {
        let n = self.layers;
        let mut sum = 0.0;
        for ((inv, below), l) in self.inv_l.iter_mut().zip(&mut self.l_below).zip(&state.l) {
            *inv = 1.0 / l;
            sum += l;
            *below = sum;
        }
        for j in 0..state.h.len() {
            let h = state.h[j];
            let u = &mut self.u[j * n..(j + 1) * n];
            if h <= H_DRY {
                u.fill(0.0);
                self.u_mean[j] = 0.0;
                self.shear[j] = 0.0;
                continue;
            }
            let inv_h = 1.0 / h;
            let mut mean = 0.0;
            for ((u, q), l) in u
                .iter_mut()
                .zip(&state.hu[j * n..(j + 1) * n])
                .zip(&state.l)
            {
                *u = q * inv_h;
                mean += l * *u;
            }
            let spread: f64 = u
                .iter()
                .zip(&state.l)
                .map(|(u, l)| l * (u - mean) * (u - mean))
                .sum();
            self.u_mean[j] = mean;
            self.shear[j] = 3.0 * spread;
        }
    }

    /// N > 1: mass flux, pressure source, and each layer's momentum flux and exchange
    /// term at every interface k (between cells k and k + 1, ghosts included).
    fn interfaces<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        l_frac: &[f64],
        h: &[f64],
        faces: &F,
    ) {
        let (nx, n) = (mesh.nx, self.layers);
        let (g_n, dx) = (mesh.g_n, mesh.dx);
        let side = |step: &Self, j: usize| Side {
            h: h[j],
            u: step.u_mean[j],
            b: mesh.b_ghost[j],
            z: mesh.z[j],
            shear: step.shear[j],
            u_base: step.u[j * n],
            sqrt_h: h[j].max(0.0).sqrt(),
        };
        let mut left = side(self, 0);
        for k in 0..=nx {
            let right = side(self, k + 1);
            let mu_of = |speed: f64, h: f64| faces.mu(k, speed, h, g_n * h);
            let extra = faces.potential_jump(k);
            let found = interface(mu_of, left, right, extra, g_n, dx, dt);
            self.store_layer_face(k, found, l_frac, false);
            left = right;
        }
    }

    /// N > 1: stores face k's mass flux, pressure and exchange shares, each layer's
    /// momentum flux and exchange term 𝓑 (and the tracers' layer fluxes) from the face
    /// kernel's result `found` (zeros where it found no flux: the cell update reads
    /// every face). The layer velocities the fluxes see are the cells' own u_α, or
    /// with `edges` the reconstruction's east and west edge velocities (order 2).
    fn store_layer_face(
        &mut self,
        k: usize,
        found: Option<(Interface, Side, Side)>,
        l_frac: &[f64],
        edges: bool,
    ) {
        let n = self.layers;
        let fluxes = &mut self.flux_hu[k * n..(k + 1) * n];
        let Some((c, l, r)) = found else {
            self.flux_h[k] = 0.0;
            (self.share_left[k], self.share_right[k]) = (0.0, 0.0);
            (self.body_left[k], self.body_right[k]) = (0.0, 0.0);
            (self.exchange_left[k], self.exchange_right[k]) = (0.0, 0.0);
            fluxes.fill(0.0);
            self.exchange[k * n..(k + 1) * n].fill(0.0);
            if !self.layer_flux.is_empty() {
                self.layer_flux[k * n..(k + 1) * n].fill(0.0);
            }
            return;
        };
        self.flux_h[k] = mass_flux(&c, l, r);
        (self.share_left[k], self.share_right[k]) = (c.share_left, c.share_right);
        (self.body_left[k], self.body_right[k]) = (c.body_left, c.body_right);
        (self.exchange_left[k], self.exchange_right[k]) = (c.exchange_left, c.exchange_right);
        let (u_l, u_r) = if edges {
            (
                &self.east_u[k * n..(k + 1) * n],
                &self.west_u[(k + 1) * n..(k + 2) * n],
            )
        } else {
            (
                &self.u[k * n..(k + 1) * n],
                &self.u[(k + 1) * n..(k + 2) * n],
            )
        };
        let seen = |u: f64, at_rest: bool| if at_rest { 0.0 } else { u };
        let exchange = &mut self.exchange[k * n..(k + 1) * n];
        if c.left_at_rest || c.right_at_rest {
            // One side at rest, the other dry: no velocity anywhere, no exchange.
            exchange.fill(0.0);
        } else {
            let frac = Fractions {
                l: l_frac,
                inv: &self.inv_l,
                below: &self.l_below,
            };
            exchange_terms(frac, l.h, r.h, u_l, u_r, exchange);
        }
        for a in 0..n {
            let (ul, ur) = (seen(u_l[a], c.left_at_rest), seen(u_r[a], c.right_at_rest));
            fluxes[a] = layer_momentum_flux(&c, c.h_minus, c.h_plus, ul, ur);
        }
        if !self.layer_flux.is_empty() {
            // d_α = h_f ½((u_α − ū)_L + (u_α − ū)_R) with the velocities as the
            // fluxes see them (0 at rest) and the thinner side's depth h_f
            // (module documentation of `tracer.rs`).
            let (ml, mr) = (l.u, r.u);
            let h_f = l.h.min(r.h);
            let out = &mut self.layer_flux[k * n..(k + 1) * n];
            for a in 0..n {
                let (ul, ur) = (seen(u_l[a], c.left_at_rest), seen(u_r[a], c.right_at_rest));
                out[a] = 0.5 * h_f * ((ul - ml) + (ur - mr));
            }
        }
    }

    /// N = 1: the interfaces and the mass update in one pass. Each cell's velocity and
    /// √h are computed once, when the loop reaches it, and carried to its second
    /// interface; cell k's h_new follows as soon as interface k is done. Returns the
    /// smallest h_new and its cell, as [`Self::update_mass`] does (same operations, same
    /// order: the results are those of the N-layer path with N = 1).
    fn monolayer_interfaces<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &[f64],
        hu: &[f64],
        r: f64,
        faces: &F,
    ) -> (f64, usize) {
        let nx = mesh.nx;
        let (g_n, dx) = (mesh.g_n, mesh.dx);
        // Equal lengths up front: no bounds checks in the loop.
        let (h, hu) = (&h[..nx + 2], &hu[..nx + 2]);
        let (b, z) = (&mesh.b_ghost[..nx + 2], &mesh.z[..nx + 2]);
        let flux_h = &mut self.flux_h[..nx + 1];
        let flux_hu = &mut self.flux_hu[..nx + 1];
        let share_left = &mut self.share_left[..nx + 1];
        let share_right = &mut self.share_right[..nx + 1];
        let body_left = &mut self.body_left[..nx + 1];
        let body_right = &mut self.body_right[..nx + 1];
        let h_new = &mut self.h_new[..nx + 2];
        let side = |j: usize| Side::monolayer(h[j], hu[j], b[j], z[j]);
        let fluxes = |k: usize, l: Side, r: Side| {
            let (cell_l, cell_r) = ((l.u.abs(), l.h), (r.u.abs(), r.h));
            let mu_of = |speed: f64, h: f64| faces.face_mu(k, cell_l, cell_r, speed, h, g_n);
            monolayer_fluxes(mu_of, l, r, faces.potential_jump(k), g_n, dx, dt)
        };
        let mut worst = (f64::INFINITY, 1usize);
        let mut left = side(0);
        let mut right = side(1);
        let (mut f_left, f_hu, s_l, s_r, b_l, b_r) = fluxes(0, left, right);
        (flux_h[0], flux_hu[0], share_left[0], share_right[0]) = (f_left, f_hu, s_l, s_r);
        (body_left[0], body_right[0]) = (b_l, b_r);
        for k in 1..=nx {
            (left, right) = (right, side(k + 1));
            let (f_right, f_hu, s_l, s_r, b_l, b_r) = fluxes(k, left, right);
            (flux_h[k], flux_hu[k], share_left[k], share_right[k]) = (f_right, f_hu, s_l, s_r);
            (body_left[k], body_right[k]) = (b_l, b_r);
            let hn = h[k] - r * (f_right - f_left);
            h_new[k] = hn;
            if hn < worst.0 {
                worst = (hn, k);
            }
            f_left = f_right;
        }
        worst
    }
}

impl<L: BasalFriction> HydrostaticStep<L> {
    /// Order 2: every cell's west and east edge states and interior force ([`muscl`]).
    /// The surface reconstructed is h + b, over the reference plane: the plane's
    /// potential z − b stays at the cell's value, so every face sees the plane's whole
    /// jump, as at order 1 (a uniform layer sliding on the plane has no slopes and is
    /// the first-order flow to the bit, at the faces beside first-order cells too).
    /// A wall's ghost takes the mirror image of its neighbour's edge (the same depth
    /// and surface, the velocity reversed: no mass crosses the wall); an outflow's
    /// ghost is first order (a copy of the edge cell's mean).
    ///
    /// A cell slower than the speed its static friction takes out in one step,
    /// |u| ≤ Δt μ_s g_n (μ_s the law at speed 0), is first order too: the friction step
    /// may stop it within the step, a non-smooth event that order 2 cannot resolve, and
    /// its first-order forces are those that hold masses at rest. Without it the back of
    /// a Coulomb deposit standing at its friction angle crept at 1.7 cm/s for ever
    /// (a force within a few per cent of the threshold, on either side), where order 1
    /// stops it. Frictionless cells (μ = 0) are reconstructed wherever they move.
    fn reconstruct(&mut self, mesh: &Line, dt: f64, h: &[f64], hu: &[f64], limiter: Limiter) {
        let nx = mesh.nx;
        let law = self.law;
        let (b, z, g_n) = (&mesh.b_ghost[..nx + 2], &mesh.z[..nx + 2], mesh.g_n);
        // Each cell's velocity once (one division), read by three stencils.
        for (j, c) in self.cells.iter_mut().enumerate() {
            *c = muscl::Cell::new(h[j], hu[j], h[j] + b[j]);
        }
        let cells = &self.cells;
        let cell = |j: usize| cells[j];
        let edge_side = |e: muscl::Edge, plane: f64| {
            let b = e.eta - e.h;
            let u = if e.h > H_DRY { e.u } else { 0.0 };
            Side {
                h: e.h,
                u,
                b,
                z: b + plane,
                shear: 0.0,
                u_base: u,
                sqrt_h: e.h.sqrt(),
            }
        };
        // Slopes where the cell is reconstructed (`None`: first order).
        for j in 0..nx + 2 {
            let stoppable = |j: usize| {
                let speed = cell(j).u.abs();
                speed <= dt * g_n * law.mu(0.0, h[j], g_n * h[j])
            };
            self.slopes[j] = if j > 0 && j <= nx && !stoppable(j) {
                muscl::slopes(limiter, cell(j - 1), cell(j), cell(j + 1))
            } else {
                None
            };
        }
        if mesh.left == BoundaryKind::Wall {
            self.slopes[0] = self.slopes[1].map(muscl::Slopes::mirrored);
        }
        if mesh.right == BoundaryKind::Wall {
            self.slopes[nx + 1] = self.slopes[nx].map(muscl::Slopes::mirrored);
        }
        // An edge is reconstructed only where both cells of its face are: at a face
        // beside a first-order cell both sides are means, the jump spans the two
        // centres and each cell takes its share as at order 1 (with one edge
        // reconstructed, the first-order cell would feel only half of the surface's
        // slope and its neighbour 5/4; module documentation of `muscl`).
        let mean_edge = |j: usize| muscl::Edge {
            h: h[j],
            u: cell(j).u,
            eta: h[j] + b[j],
        };
        for j in 0..nx + 2 {
            let mean = Side::monolayer(h[j], hu[j], b[j], z[j]);
            let Some(s) = self.slopes[j] else {
                (self.west[j], self.east[j]) = (mean, mean);
                (self.interior[j], self.interior_body[j]) = (0.0, 0.0);
                continue;
            };
            let (w, e) = muscl::edges(cell(j), s);
            let plane = z[j] - b[j];
            let west_recon = j > 0 && self.slopes[j - 1].is_some();
            let east_recon = j <= nx && self.slopes[j + 1].is_some();
            let (w, west) = if west_recon {
                (w, edge_side(w, plane))
            } else {
                (mean_edge(j), mean)
            };
            let (e, east) = if east_recon {
                (e, edge_side(e, plane))
            } else {
                (mean_edge(j), mean)
            };
            (self.west[j], self.east[j]) = (west, east);
            (self.interior[j], self.interior_body[j]) = if west_recon || east_recon {
                muscl::interior_source(g_n, w, e)
            } else {
                (0.0, 0.0)
            };
        }
    }

    /// Order 2, N = 1: the faces between the reconstructed edge states and the mass
    /// update; returns the smallest h_new and its cell.
    fn muscl_interfaces<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &[f64],
        r: f64,
        faces: &F,
    ) -> (f64, usize) {
        let nx = mesh.nx;
        let (g_n, dx) = (mesh.g_n, mesh.dx);
        let z = &mesh.z[..nx + 2];
        for k in 0..=nx {
            let (l, rt) = (self.east[k], self.west[k + 1]);
            let (cell_l, cell_r) = ((l.u.abs(), l.h), (rt.u.abs(), rt.h));
            let mu_of =
                |speed: f64, h: f64, _drive: f64| faces.face_mu(k, cell_l, cell_r, speed, h, g_n);
            // ΔC decides whether friction holds the face from the drive between the
            // cell centres, as at order 1: the jump between the edges is a fraction of
            // it (the rest is in the cells' interior forces), and a face that saw only
            // u/Δt would stop the mass flux of a mass that the friction step keeps
            // moving (module documentation of `muscl`, "ΔC").
            let centres = (h[k + 1] + z[k + 1]) - (h[k] + z[k]);
            let edges = (rt.h + rt.z) - (l.h + l.z);
            let missing = -g_n * (centres - edges) / dx;
            let friction = |drive: f64, mu: f64| {
                let threshold = g_n * mu;
                -(drive + missing).clamp(-threshold, threshold)
            };
            let extra = faces.potential_jump(k);
            let found = interface_with_friction(mu_of, l, rt, extra, friction, (g_n, g_n), dx, dt);
            let Some((c, l, rt)) = found else {
                (self.flux_h[k], self.flux_hu[k]) = (0.0, 0.0);
                (self.share_left[k], self.share_right[k]) = (0.0, 0.0);
                (self.body_left[k], self.body_right[k]) = (0.0, 0.0);
                continue;
            };
            self.flux_h[k] = mass_flux(&c, l, rt);
            self.flux_hu[k] = layer_momentum_flux(&c, c.h_minus, c.h_plus, l.u, rt.u);
            (self.share_left[k], self.share_right[k]) = (c.share_left, c.share_right);
            (self.body_left[k], self.body_right[k]) = (c.body_left, c.body_right);
        }
        self.update_mass(h, r)
    }

    /// Order 2, N = 1: [`Self::update_monolayer`] with each cell's interior force.
    fn update_muscl(&self, h: &mut [f64], hu: &mut [f64], r: f64) {
        let nx = h.len() - 2;
        for i in 1..=nx {
            let h_old = h[i];
            let hn = self.h_new[i];
            h[i] = if hn < 0.0 { 0.0 } else { hn };
            let body = self.body_left[i] + self.body_right[i - 1] + self.interior_body[i];
            // A reconstructed cell keeps its whole gravity source: the near-dry rule is
            // for first-order cells (`muscl_2d`'s update, where it cost Heun's step its
            // second order on a curved bed).
            let drained = if self.slopes[i].is_some() {
                0.0
            } else {
                drained_fraction(h[i], h_old)
            };
            let source =
                self.share_left[i] + self.share_right[i - 1] + self.interior[i] - body * drained;
            let q = hu[i] - r * (self.flux_hu[i] - self.flux_hu[i - 1] + source);
            hu[i] = if h[i] <= H_DRY { 0.0 } else { q };
        }
    }

    /// h_new = h − r (F_{i+1/2} − F_{i−1/2}); returns the smallest value and its cell.
    fn update_mass(&mut self, h: &[f64], r: f64) -> (f64, usize) {
        let mut worst = (f64::INFINITY, 1usize);
        let interior = &h[1..h.len() - 1];
        for (k, (hi, f)) in interior.iter().zip(self.flux_h.windows(2)).enumerate() {
            let hn = hi - r * (f[1] - f[0]);
            self.h_new[k + 1] = hn;
            if hn < worst.0 {
                worst = (hn, k + 1);
            }
        }
        worst
    }

    /// N = 1: h ← h_new (round-off below zero clipped), hu ← hu − r (F^hu_{i+1/2} −
    /// F^hu_{i−1/2} + 𝓢ᴸ_{i+1/2} + 𝓢ᴿ_{i−1/2}), zero in dry cells; interior cells
    /// only. One branch-free pass over equal-length slices.
    fn update_monolayer(&self, h: &mut [f64], hu: &mut [f64], r: f64) {
        let nx = h.len() - 2;
        let cells = h[1..=nx].iter_mut().zip(&mut hu[1..=nx]);
        let h_new = &self.h_new[1..=nx];
        // Cell i: its right face i carries F^hu_{i+1/2} and the left-cell share
        // 𝓢ᴸ_{i+1/2}, its left face i − 1 F^hu_{i−1/2} and the right-cell share 𝓢ᴿ_{i−1/2}.
        let (f_right, f_left) = (&self.flux_hu[1..=nx], &self.flux_hu[..nx]);
        let (s_right, s_left) = (&self.share_left[1..=nx], &self.share_right[..nx]);
        let (b_right, b_left) = (&self.body_left[1..=nx], &self.body_right[..nx]);
        let faces = f_right.iter().zip(f_left).zip(s_right.iter().zip(s_left));
        let bodies = b_right.iter().zip(b_left);
        for ((((h, hu), hn), ((f_r, f_l), (s_r, s_l))), (b_r, b_l)) in
            cells.zip(h_new).zip(faces).zip(bodies)
        {
            // Clip round-off below zero; `f64::max` would also turn a NaN into 0 and
            // hide a blow-up from the run's NaN check.
            let h_old = *h;
            *h = if *hn < 0.0 { 0.0 } else { *hn };
            let source = s_r + s_l - (b_r + b_l) * drained_fraction(*h, h_old);
            let q = *hu - r * (f_r - f_l + source);
            *hu = if *h <= H_DRY { 0.0 } else { q };
        }
    }

    /// N > 1: h ← h_new and every layer's hu_α ← hu_α − r (flux jump + source +
    /// exchange), zero in dry cells; interior cells only.
    fn update_layers(&self, state: &mut LayeredState, nx: usize, r: f64) {
        let n = self.layers;
        for i in 1..=nx {
            // Clip round-off below zero; `f64::max` would also turn a NaN into 0 and
            // hide a blow-up from the run's NaN check.
            let hn = self.h_new[i];
            let h_old = state.h[i];
            state.h[i] = if hn < 0.0 { 0.0 } else { hn };
            let body = self.body_left[i] + self.body_right[i - 1];
            let source = self.share_left[i] + self.share_right[i - 1]
                - body * drained_fraction(state.h[i], h_old);
            let (right, left) = (i * n, (i - 1) * n);
            let (w_right, w_left) = (self.exchange_left[i], self.exchange_right[i - 1]);
            let hu = &mut state.hu[i * n..(i + 1) * n];
            for (a, q) in hu.iter_mut().enumerate() {
                let exchange =
                    w_right * self.exchange[right + a] + w_left * self.exchange[left + a];
                *q -= r * (self.flux_hu[right + a] - self.flux_hu[left + a] + source + exchange);
            }
            if state.h[i] <= H_DRY {
                hu.fill(0.0);
            }
        }
    }

    /// Scales every interface flux (mass and each layer's momentum) by the draining
    /// factor of its donor cell, θ_j = min(1, h_j / (r · outflow_j)).
    fn limit_draining(&mut self, h: &[f64], r: f64) {
        let (nx, n) = (h.len() - 2, self.layers);
        let interior = &h[1..=nx];
        for (k, (hj, f)) in interior.iter().zip(self.flux_h.windows(2)).enumerate() {
            let need = r * (f[1].max(0.0) + (-f[0]).max(0.0));
            self.drain[k + 1] = if need > *hj { hj.max(0.0) / need } else { 1.0 };
        }
        for k in 0..=nx {
            let donor = if self.flux_h[k] > 0.0 { k } else { k + 1 };
            let theta = self.drain[donor];
            self.flux_h[k] *= theta;
            for f in &mut self.flux_hu[k * n..(k + 1) * n] {
                *f *= theta;
            }
            if !self.layer_flux.is_empty() {
                for f in &mut self.layer_flux[k * n..(k + 1) * n] {
                    *f *= theta;
                }
            }
        }
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for HydrostaticStep<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let law = self.law;
        self.apply_with_friction(mesh, clock.dt, state, &law)
    }
}

impl<L: BasalFriction> HydrostaticStep<L> {
    /// The step with the friction threshold of the Coulomb-aware reconstruction (ΔC)
    /// taken from `faces` at each face instead of from the step's law (module
    /// documentation, "per-face friction"). [`Stage::apply`] is this call with the law
    /// itself, which ignores the face: same operations, same results.
    pub fn apply_with_friction<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        state: &mut LayeredState,
        faces: &F,
    ) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, self.layers);
        let (nx, n) = (mesh.nx, self.layers);
        if !state.tracers.is_empty() {
            self.tracers.before_step(&state.h, n, &state.tracers);
            if n > 1 && self.layer_flux.is_empty() {
                self.layer_flux = vec![0.0; (nx + 1) * n];
            }
        }
        let r = dt / mesh.dx;
        if n == 1 {
            self.advance_monolayer(mesh, dt, &mut state.h, &mut state.hu, faces)?;
        } else if let Some(limiter) = self.limiter {
            self.velocities(state);
            self.reconstruct_layers(mesh, dt, &state.h, &state.l, limiter);
            self.muscl_layer_interfaces(mesh, dt, &state.l, &state.h, faces);
            let worst = self.update_mass(&state.h, r);
            self.refuse_negative(&state.h, r, worst)?;
            self.update_layers_muscl(state, nx, r);
        } else {
            // Mass first; limit the fluxes of cells that would empty, then refuse the
            // step (state untouched) if anything is still negative beyond round-off.
            self.velocities(state);
            self.interfaces(mesh, dt, &state.l, &state.h, faces);
            let worst = self.update_mass(&state.h, r);
            self.refuse_negative(&state.h, r, worst)?;
            self.update_layers(state, nx, r);
        }
        state.fill_ghosts(mesh);
        if !state.tracers.is_empty() {
            let layers = (n > 1).then_some((self.layer_flux.as_slice(), state.l.as_slice()));
            self.tracers
                .after_step(&self.flux_h, layers, &state.h, r, n, &mut state.tracers);
        }
        Ok(())
    }
}

impl<L: BasalFriction> HydrostaticStep<L> {
    /// The monolayer step (N = 1, no tracers) on the thickness `h` and discharge `hu`
    /// of any state (nx + 2 each, ghosts filled), with the friction threshold of
    /// `faces`; the ghosts are left to the caller (the layered state's `fill_ghosts`,
    /// the dilatant state's `fill_thickness_ghosts`: the same copy and sign). This is
    /// the path [`Stage::apply`] takes for one layer: same operations, same results.
    /// On error `h` and `hu` are unchanged.
    pub fn advance_monolayer<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &mut [f64],
        hu: &mut [f64],
        faces: &F,
    ) -> Result<(), StageError> {
        debug_assert_eq!(self.layers, 1);
        let nx = mesh.nx;
        // Mass first; limit the fluxes of cells that would empty, then refuse the step
        // (state untouched) if anything is still negative beyond round-off.
        let r = dt / mesh.dx;
        if let Some(limiter) = self.limiter {
            self.reconstruct(mesh, dt, h, hu, limiter);
            let worst = self.muscl_interfaces(mesh, dt, h, r, faces);
            self.refuse_negative(h, r, worst)?;
            self.update_muscl(&mut h[..nx + 2], &mut hu[..nx + 2], r);
            return Ok(());
        }
        let worst = self.monolayer_interfaces(mesh, dt, h, hu, r, faces);
        self.refuse_negative(h, r, worst)?;
        self.update_monolayer(&mut h[..nx + 2], &mut hu[..nx + 2], r);
        Ok(())
    }

    /// [`Self::advance_monolayer`] with the step's own law.
    pub fn advance_monolayer_with_law(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &mut [f64],
        hu: &mut [f64],
    ) -> Result<(), StageError> {
        let law = self.law;
        self.advance_monolayer(mesh, dt, h, hu, &law)
    }

    /// Given the smallest new thickness `worst` (value, cell) of the mass update: if
    /// negative, limits the draining fluxes and updates the mass again; refuses the
    /// step if h is still negative beyond round-off.
    fn refuse_negative(
        &mut self,
        h: &[f64],
        r: f64,
        mut worst: (f64, usize),
    ) -> Result<(), StageError> {
        if worst.0 < 0.0 {
            self.limit_draining(h, r);
            worst = self.update_mass(h, r);
        }
        let tolerance = -1e-14 * (1.0 + h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                cell: worst.1 - 1,
                h: worst.0,
            });
        }
        Ok(())
    }

    /// Mass fluxes 𝓕^h of the last step at the faces k = 0..=nx (face k lies between
    /// the ghost-inclusive cells k and k + 1).
    pub fn mass_flux(&self) -> &[f64] {
        &self.flux_h
    }
}

/// Order 2 with N > 1 layers (module documentation; [`super::muscl`], "N layers").
impl<L: BasalFriction> HydrostaticStep<L> {
    /// The first-order side of cell `j` (its means), as [`Self::interfaces`] sees it.
    fn mean_side(&self, mesh: &Line, h: &[f64], j: usize) -> Side {
        Side {
            h: h[j],
            u: self.u_mean[j],
            b: mesh.b_ghost[j],
            z: mesh.z[j],
            shear: self.shear[j],
            u_base: self.u[j * self.layers],
            sqrt_h: h[j].max(0.0).sqrt(),
        }
    }

    /// Order 2, N > 1: the limited slopes of h, η and every layer's u_α, each cell's
    /// west and east edge states (depth, surface, layer velocities, and from these ū,
    /// the shear of the wave speed and the basal u_1 of ΔC), its interior pressure force
    /// and its interior exchange term 𝓑^c = 𝓑(edge_W, edge_E). The rules of the
    /// monolayer ([`Self::reconstruct`]) apply per cell: first order beside a dry cell,
    /// at rest, and where any layer is slower than the static friction's impulse per
    /// step, min_α |u_α| ≤ Δt μ_s g_n (the viscous step may stop that layer within the
    /// step, which order 2 cannot resolve, and a mass at rest then sees exactly the
    /// first-order forces that hold it); mixed faces keep both means. Requires
    /// [`Self::velocities`] first.
    fn reconstruct_layers(
        &mut self,
        mesh: &Line,
        dt: f64,
        h: &[f64],
        l_frac: &[f64],
        limiter: Limiter,
    ) {
        let (nx, n) = (mesh.nx, self.layers);
        let law = self.law;
        let (b, g_n) = (&mesh.b_ghost[..nx + 2], mesh.g_n);
        for (j, c) in self.cells.iter_mut().enumerate() {
            *c = muscl::Cell {
                h: h[j],
                u: self.u_mean[j],
                eta: h[j] + b[j],
            };
        }
        for j in 0..nx + 2 {
            let slowest = self.u[j * n..(j + 1) * n]
                .iter()
                .fold(f64::INFINITY, |m, u| m.min(u.abs()));
            let slow = slowest <= dt * g_n * law.mu(0.0, h[j], g_n * h[j]);
            // Two cells from a dry cell too: the layers of a film behind a front
            // shear apart (the top layer of a 0.7 mm film reached 9 m/s against the
            // bottom's 2 m/s and the run failed) where the cell behind the front cell
            // is reconstructed against the front cell's mean.
            let near_front =
                (j >= 2 && h[j - 2] <= H_DRY) || (j + 2 <= nx + 1 && h[j + 2] <= H_DRY);
            self.slopes[j] = if j > 0 && j <= nx && !slow && !near_front {
                muscl::slopes(limiter, self.cells[j - 1], self.cells[j], self.cells[j + 1])
            } else {
                None
            };
        }
        if mesh.left == BoundaryKind::Wall {
            self.slopes[0] = self.slopes[1].map(muscl::Slopes::mirrored);
        }
        if mesh.right == BoundaryKind::Wall {
            self.slopes[nx + 1] = self.slopes[nx].map(muscl::Slopes::mirrored);
        }
        for j in 0..nx + 2 {
            let mean = self.mean_side(mesh, h, j);
            let range = j * n..(j + 1) * n;
            let Some(s) = self.slopes[j] else {
                (self.west[j], self.east[j]) = (mean, mean);
                self.west_u[range.clone()].copy_from_slice(&self.u[range.clone()]);
                self.east_u[range.clone()].copy_from_slice(&self.u[range.clone()]);
                (self.interior[j], self.interior_body[j]) = (0.0, 0.0);
                self.interior_exchange[range].fill(0.0);
                continue;
            };
            // A wall's ghost is the mirror image of its neighbour: the velocities
            // reversed, their slopes unchanged.
            let c = match j {
                0 => 1,
                j if j == nx + 1 => nx,
                j => j,
            };
            let west_recon = j > 0 && self.slopes[j - 1].is_some();
            let east_recon = j <= nx && self.slopes[j + 1].is_some();
            for a in 0..n {
                let u = |i: usize| self.u[i * n + a];
                let du = 0.5 * limiter.slope(u(c) - u(c - 1), u(c + 1) - u(c));
                let own = u(j);
                self.west_u[j * n + a] = if west_recon { own - du } else { own };
                self.east_u[j * n + a] = if east_recon { own + du } else { own };
            }
            let (w, e) = muscl::edges(self.cells[j], s);
            let mean_edge = muscl::Edge {
                h: h[j],
                u: self.u_mean[j],
                eta: h[j] + b[j],
            };
            let plane = mesh.z[j] - b[j];
            let (w, west) = if west_recon {
                (w, edge_side(w, &self.west_u[range.clone()], l_frac, plane))
            } else {
                (mean_edge, mean)
            };
            let (e, east) = if east_recon {
                (e, edge_side(e, &self.east_u[range.clone()], l_frac, plane))
            } else {
                (mean_edge, mean)
            };
            (self.west[j], self.east[j]) = (west, east);
            let out = &mut self.interior_exchange[range.clone()];
            if west_recon || east_recon {
                (self.interior[j], self.interior_body[j]) = muscl::interior_source(g_n, w, e);
                let frac = Fractions {
                    l: l_frac,
                    inv: &self.inv_l,
                    below: &self.l_below,
                };
                let (u_w, u_e) = (&self.west_u[range.clone()], &self.east_u[range]);
                exchange_terms(frac, w.h, e.h, u_w, u_e, out);
            } else {
                (self.interior[j], self.interior_body[j]) = (0.0, 0.0);
                out.fill(0.0);
            }
        }
    }

    /// Order 2, N > 1: [`Self::interfaces`] on the edge states of
    /// [`Self::reconstruct_layers`], with ΔC deciding from the drive between the cell
    /// centres as in [`Self::muscl_interfaces`].
    fn muscl_layer_interfaces<F: FaceFriction>(
        &mut self,
        mesh: &Line,
        dt: f64,
        l_frac: &[f64],
        h: &[f64],
        faces: &F,
    ) {
        let nx = mesh.nx;
        let (g_n, dx) = (mesh.g_n, mesh.dx);
        let z = &mesh.z[..nx + 2];
        for k in 0..=nx {
            let (left, right) = (self.east[k], self.west[k + 1]);
            let mu_of = |speed: f64, h: f64, _drive: f64| faces.mu(k, speed, h, g_n * h);
            let centres = (h[k + 1] + z[k + 1]) - (h[k] + z[k]);
            let edges = (right.h + right.z) - (left.h + left.z);
            let missing = -g_n * (centres - edges) / dx;
            let friction = |drive: f64, mu: f64| {
                let threshold = g_n * mu;
                -(drive + missing).clamp(-threshold, threshold)
            };
            let extra = faces.potential_jump(k);
            let found =
                interface_with_friction(mu_of, left, right, extra, friction, (g_n, g_n), dx, dt);
            self.store_layer_face(k, found, l_frac, true);
        }
    }

    /// Order 2, N > 1: [`Self::update_layers`] with each cell's interior pressure force
    /// and interior exchange term.
    fn update_layers_muscl(&self, state: &mut LayeredState, nx: usize, r: f64) {
        let n = self.layers;
        for i in 1..=nx {
            let hn = self.h_new[i];
            let h_old = state.h[i];
            state.h[i] = if hn < 0.0 { 0.0 } else { hn };
            let body = self.body_left[i] + self.body_right[i - 1] + self.interior_body[i];
            // As in the monolayer's order-2 update: a reconstructed cell keeps its whole
            // gravity source (the near-dry rule is for first-order cells).
            let drained = if self.slopes[i].is_some() {
                0.0
            } else {
                drained_fraction(state.h[i], h_old)
            };
            let source =
                self.share_left[i] + self.share_right[i - 1] + self.interior[i] - body * drained;
            let (right, left) = (i * n, (i - 1) * n);
            let (w_right, w_left) = (self.exchange_left[i], self.exchange_right[i - 1]);
            let inner = &self.interior_exchange[i * n..(i + 1) * n];
            let hu = &mut state.hu[i * n..(i + 1) * n];
            for (a, q) in hu.iter_mut().enumerate() {
                let exchange = w_right * self.exchange[right + a]
                    + w_left * self.exchange[left + a]
                    + inner[a];
                *q -= r * (self.flux_hu[right + a] - self.flux_hu[left + a] + source + exchange);
            }
            if state.h[i] <= H_DRY {
                hu.fill(0.0);
            }
        }
    }
}

/// The face state of a reconstructed edge with layer velocities `u` (N > 1): ū, the
/// shear term 3 Σ l_α (u_α − ū)² of the wave speed and the basal u_1; no velocity
/// where the edge is dry.
fn edge_side(e: muscl::Edge, u: &[f64], l_frac: &[f64], plane: f64) -> Side {
    let b = e.eta - e.h;
    let (mean, shear, base) = if e.h > H_DRY {
        let mean: f64 = u.iter().zip(l_frac).map(|(u, l)| l * u).sum();
        let spread: f64 = u
            .iter()
            .zip(l_frac)
            .map(|(u, l)| l * (u - mean) * (u - mean))
            .sum();
        (mean, 3.0 * spread, u[0])
    } else {
        (0.0, 0.0, 0.0)
    };
    Side {
        h: e.h,
        u: mean,
        b,
        z: b + plane,
        shear,
        u_base: base,
        sqrt_h: e.h.sqrt(),
    }
}
