//! The flux differences 𝒟𝓕^±_{i+1/2} of one face (Fernández-Nieto et al. 2008, eq. 73, written as in the
//! proof of Theorem 2):
//!
//!   𝒟𝓕^± = ½ (R₁ ± V),   V = P R₂,   R₂ = R₁ − T_{i+1/2} Δx,
//!
//! with R₁ of eq. (88): flux difference, the curvature terms S₃Δcos²θ + S₄Δcos θ
//! (Remark 11), the bed S₁Δb, the cos² part S₂Δcos²θ and the coupling B ΔW, all with
//! arithmetic face means H̄_k, cos θ_{i+1/2}, (cos²θ)_{i+1/2} and Roe velocities (eq. 82).
//! By the discrete product rule (eq. 89) its "static" part (everything but the
//! velocities) is identically
//!
//!   \[R₁\]₂ˢ = g cos θ̄ H̄₁ Δη,
//!   \[R₁\]₄ˢ = g cos θ̄ H̄₂ (A₂ Δ(H₂cos²θ) + r A₁ Δ(H₁cos²θ) + Δb + (1 − A₂)/4 H̄₂ Δcos²θ),
//!
//! which is how it is evaluated (one subtraction Δη: a lake at rest gives exactly 0).
//! The paper's eq. (80) prints the last term as "H̄₂ cos²θ_{i+1} − cos²θ_i"; the
//! parenthesised H̄₂(cos²θ_{i+1} − cos²θ_i) is what its own eq. (90) gives. The mass
//! rows are Δ(Q cos θ) exactly (S₄ with the mean Q̄ and eq. 89), so each layer's volume
//! is conserved.
//!
//! Coulomb term of the face (eq. 79): if |Q̄₂| > Δt σ_c/cos θ̄ the face carries the
//! friction source −N tan δ₀ sgn(Q̄₂) ([`coulomb_normal_stress`], i.e. T₁/cos θ + T₂);
//! otherwise τ_crit, which is exactly \[R₁\]₄ˢ, so that R₂ has no grain-momentum
//! component at a grain layer at rest whatever its slope.
//!
//! Own-depth split: the static parts of the momentum rows are shared by the two cells
//! in proportion to their own thicknesses, θ_L \[R₁\]ˢ and θ_R \[R₁\]ˢ (θ_L = H_L/(H_L + H_R)),
//! with the upwinded part bounded by the thinner side (m α₁ \[R₁\]ˢ, m = min θ), instead of
//! ½ each as in eq. (73): the sum over the face is unchanged (R₁), equal thicknesses give
//! eq. (73) exactly, and a film beside a thick cell is no longer pushed by half the
//! thick cell's pressure (acceleration ∝ H_thick/H_film: the Δt collapse of the
//! monolayer scheme's printed split, docs/numerics.md, seen here too in
//! `fast_slide_into_shallow_water_and_film_over_moving_grains_stay_sane`). The Coulomb
//! step then weighs each cell's own H₂ ([`super::coulomb`]).
//!
//! Upwinding V = P R₂: the paper uses the Roe matrix P = 𝒦 sgn(D) 𝒦⁻¹ (eq. 83). We use
//! its HLL-PVM counterpart (Castro & Fernández-Nieto's PVM family; "Roe/PVM-type"):
//! P ≈ α₀ 𝒜⁻¹ + α₁ I with the HLL coefficients of the speed bounds S_L, S_R, and
//! 𝒜⁻¹R₂ = ΔW − 𝒜⁻¹S approximated by the jump J of hydrostatically reconstructed
//! states (Audusse et al.) — water over the interface ζ = b + H₂cos²θ, grains over the
//! bed with the Coulomb-aware correction ΔC of Garres-Díaz et al. 2021, eq. (22–24) (Escalante et al. 2023's sign).
//! No eigenvectors are needed (𝒜 has no explicit ones, §4.1), nothing breaks where an
//! internal eigenvalue crosses zero (𝒜⁻¹ singular) or a layer is absent, and V = 0 for
//! a lake at rest over a deposit held by friction, so Theorem 2's well-balancing holds
//! for this P as for Roe's.
//!
//! Wet/dry faces (Castro et al., Fernández-Nieto et al. 2008, §5): where a layer's wet cell faces a dry cell
//! whose bottom (for water: the interface ζ; for grains: the bed b) lies above the wet
//! cell's surface, that bottom is lowered locally to the wet surface and the wet
//! velocity is seen as zero: the face is a wall for that layer, with no spurious
//! pressure force (a lake's shoreline, the upper edge of a deposit).

use crate::grid::curved::FaceGeometry;
use crate::physics::two_layer::{
    coulomb_normal_stress, max_num, min_num, speed_bounds, TwoLayerParams, H_DRY_TWO_LAYER,
};

/// One cell as a face sees it.
#[derive(Debug, Clone, Copy)]
pub struct CellView {
    pub h1: f64,
    pub q1: f64,
    pub h2: f64,
    pub q2: f64,
    pub u1: f64,
    pub u2: f64,
    pub b: f64,
    pub cos: f64,
    pub cos2: f64,
    /// √H₁, √H₂ (Roe weights, eq. 82) and the cell's speed bounds, computed once per step.
    pub sh1: f64,
    pub sh2: f64,
    pub lo: f64,
    pub hi: f64,
}

impl CellView {
    /// The view of a cell state: velocities, Roe weights and speed bounds.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        p: &TwoLayerParams,
        h1: f64,
        q1: f64,
        h2: f64,
        q2: f64,
        b: f64,
        cos: f64,
        cos2: f64,
    ) -> Self {
        let u1 = crate::physics::two_layer::layer_velocity(h1, q1);
        let u2 = crate::physics::two_layer::layer_velocity(h2, q2);
        let (lo, hi) = speed_bounds(p, cos, h1, h2, u1, u2);
        CellView {
            h1,
            q1,
            h2,
            q2,
            u1,
            u2,
            b,
            cos,
            cos2,
            sh1: max_num(h1, 0.0).sqrt(),
            sh2: max_num(h2, 0.0).sqrt(),
            lo,
            hi,
        }
    }
}

/// What a face gives its two cells: the conservative mass fluxes Φ_k and the momentum
/// flux differences 𝒟⁻ (to the left cell) and 𝒟⁺ (to the right cell).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FaceOut {
    pub phi1: f64,
    pub phi2: f64,
    pub d2_minus: f64,
    pub d2_plus: f64,
    pub d4_minus: f64,
    pub d4_plus: f64,
}

/// Which side of a wet/dry wall face (an emerging bottom) holds the layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wall {
    None,
    WetLeft,
    WetRight,
}

/// Roe-averaged velocity (eq. 82) from the weights √H, zero where the layer is absent
/// on both sides.
#[inline(always)]
fn roe_velocity(sl: f64, ul: f64, sr: f64, ur: f64) -> f64 {
    let s = sl + sr;
    if s > 0.0 {
        (sl * ul + sr * ur) / s
    } else {
        0.0
    }
}

/// Hydrostatic reconstruction of a thickness d over a bottom z (Audusse et al.).
#[inline(always)]
fn reconstruct(dl: f64, zl: f64, dr: f64, zr: f64) -> (f64, f64) {
    let top = max_num(zl, zr);
    (max_num(dl + zl - top, 0.0), max_num(dr + zr - top, 0.0))
}

/// The Roe-averaged velocities (Ū₁, Ū₂) of a face (eq. 82) seen from two cell views.
#[inline(always)]
pub fn roe_velocities(l: &CellView, r: &CellView) -> (f64, f64) {
    (
        roe_velocity(l.sh1, l.u1, r.sh1, r.u1),
        roe_velocity(l.sh2, l.u2, r.sh2, r.u2),
    )
}

/// Speed bounds (S_L, S_R) of a face: the bounds of [`speed_bounds`] at both cells and
/// at the face means (Einfeldt-type).
#[inline(always)]
pub fn face_speeds(p: &TwoLayerParams, l: &CellView, r: &CellView) -> (f64, f64) {
    let cf = 0.5 * (l.cos + r.cos);
    let (u1, u2) = roe_velocities(l, r);
    face_speeds_with(p, cf, l, r, u1, u2)
}

/// [`face_speeds`] with the face's mean cos θ and its Roe velocities already known.
#[inline(always)]
pub fn face_speeds_with(
    p: &TwoLayerParams,
    cf: f64,
    l: &CellView,
    r: &CellView,
    u1: f64,
    u2: f64,
) -> (f64, f64) {
    let (e, f) = speed_bounds(p, cf, 0.5 * (l.h1 + r.h1), 0.5 * (l.h2 + r.h2), u1, u2);
    (
        min_num(min_num(l.lo, r.lo), e),
        max_num(max_num(l.hi, r.hi), f),
    )
}

/// The constants of a step that every face uses: Δt, Δx and the cap
/// f_b tan δ₀ Δx/A₂ of the Coulomb-aware correction for both values of the buoyancy
/// factor f_b (1 − r and 1), evaluated as the face would.
#[derive(Debug, Clone, Copy)]
pub struct StepTerms {
    pub dt: f64,
    pub dx: f64,
    cap_reduced: f64,
    cap_full: f64,
}

impl StepTerms {
    pub fn new(p: &TwoLayerParams, dt: f64, dx: f64) -> Self {
        StepTerms {
            dt,
            dx,
            cap_reduced: (1.0 - p.r) * p.tan_delta * dx / p.a2,
            cap_full: 1.0 * p.tan_delta * dx / p.a2,
        }
    }
}

/// One layer's part of a face: its mass flux Φ and momentum 𝒟⁻, 𝒟⁺.
#[derive(Debug, Clone, Copy, Default)]
struct LayerOut {
    phi: f64,
    d_minus: f64,
    d_plus: f64,
}

/// The face kernel: 𝒟𝓕^± of eq. (73) with the PVM upwinding (module docs). `fg` holds
/// the face's angle terms, `roe` the Roe velocities of the two views
/// ([`roe_velocities`]), `s_l`, `s_r` its speed bounds ([`face_speeds_with`]).
///
/// A layer absent from both cells (H = Q = 0 on both sides: the water on a dry slope,
/// the grains under most of a tsunami's domain) has no flux and no momentum exchange
/// through the face: its rows are skipped (they would evaluate to zeros).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn face_flux(
    p: &TwoLayerParams,
    fg: &FaceGeometry,
    l: &CellView,
    r: &CellView,
    roe: (f64, f64),
    s_l: f64,
    s_r: f64,
    step: &StepTerms,
) -> FaceOut {
    let (d1l, d1r) = (l.h1 * l.cos2, r.h1 * r.cos2);
    let (d2l, d2r) = (l.h2 * l.cos2, r.h2 * r.cos2);
    let (h1m, h2m) = (0.5 * (l.h1 + r.h1), 0.5 * (l.h2 + r.h2));

    // HLL-PVM coefficients.
    let (alpha0, alpha1) = if s_l >= 0.0 {
        (0.0, 1.0)
    } else if s_r <= 0.0 {
        (0.0, -1.0)
    } else {
        let w = s_r - s_l;
        (-2.0 * s_r * s_l / w, (s_r + s_l) / w)
    };
    let k = FaceCoefficients {
        fg,
        d1: (d1l, d1r),
        d2: (d2l, d2r),
        h1m,
        h2m,
        alpha0,
        alpha1,
    };
    let absent = |h_l: f64, q_l: f64, h_r: f64, q_r: f64| {
        h_l == 0.0 && h_r == 0.0 && q_l == 0.0 && q_r == 0.0
    };
    let water = if absent(l.h1, l.q1, r.h1, r.q1) {
        LayerOut::default()
    } else {
        water_rows(p, &k, l, r, roe.0)
    };
    let grains = if absent(l.h2, l.q2, r.h2, r.q2) {
        LayerOut::default()
    } else {
        grain_rows(p, &k, l, r, roe.1, step)
    };
    FaceOut {
        phi1: water.phi,
        phi2: grains.phi,
        d2_minus: water.d_minus,
        d2_plus: water.d_plus,
        d4_minus: grains.d_minus,
        d4_plus: grains.d_plus,
    }
}

/// What both layers' rows of a face share.
struct FaceCoefficients<'a> {
    fg: &'a FaceGeometry,
    /// Vertical thicknesses H_k cos²θ on the left and right.
    d1: (f64, f64),
    d2: (f64, f64),
    /// Arithmetic face means H̄₁, H̄₂.
    h1m: f64,
    h2m: f64,
    alpha0: f64,
    alpha1: f64,
}

/// The water's rows (mass and momentum) of [`face_flux`]; `u_roe` the Roe velocity of
/// the views (recomputed here if a wet/dry wall zeroes a side's velocity).
#[inline(always)]
fn water_rows(
    p: &TwoLayerParams,
    k: &FaceCoefficients,
    l: &CellView,
    r: &CellView,
    u_roe: f64,
) -> LayerOut {
    let (fg, (d1l, d1r), (d2l, d2r)) = (k.fg, k.d1, k.d2);
    let (mut q1l, mut q1r) = (l.q1, r.q1);
    let (mut u1l, mut u1r) = (l.u1, r.u1);
    // Water's view of its bottom: the interface ζ, lowered at an emerging dry cell so
    // that the dry side's level equals the wet surface.
    let (mut zwl, mut zwr) = (l.b + d2l, r.b + d2r);
    let wet1 = (l.h1 > H_DRY_TWO_LAYER, r.h1 > H_DRY_TWO_LAYER);
    let mut wall1 = Wall::None;
    if wet1.0 && !wet1.1 && zwr > zwl + d1l {
        zwr = zwl + d1l - d1r;
        (u1l, q1l) = (0.0, 0.0);
        wall1 = Wall::WetLeft;
    } else if wet1.1 && !wet1.0 && zwl > zwr + d1r {
        zwl = zwr + d1r - d1l;
        (u1r, q1r) = (0.0, 0.0);
        wall1 = Wall::WetRight;
    }
    let u1 = if wall1 == Wall::None {
        u_roe
    } else {
        roe_velocity(l.sh1, u1l, r.sh1, u1r)
    };
    let cf = fg.cos;
    // R₁ (eq. 88): mass row Δ(Q cos θ); momentum row static + dynamic.
    let flux1 = (q1l * l.cos, q1r * r.cos);
    let r1_1 = flux1.1 - flux1.0;
    let static2 = p.g * cf * k.h1m * ((zwr + d1r) - (zwl + d1l));
    let dyn2 = cf * (q1r * u1r - q1l * u1l) + k.h1m * u1 * u1 * fg.dcos;
    // J ≈ 𝒜⁻¹R₂: jumps of the reconstructed states; a wall face lets nothing through.
    let (j1, j2) = if k.alpha0 == 0.0 {
        (0.0, 0.0)
    } else {
        let (e1l, e1r) = reconstruct(d1l, zwl, d1r, zwr);
        let w1 = if wall1 == Wall::None {
            fg.inv_cos2
        } else {
            0.0
        };
        ((e1r - e1l) * w1, (e1r * u1r - e1l * u1l) * w1)
    };
    let v1 = k.alpha1 * r1_1 + k.alpha0 * j1;
    let (mut d_minus, mut d_plus) =
        split_momentum(l.h1, r.h1, static2, true, dyn2, 0.0, j2, k.alpha0, k.alpha1);
    // At a wall face the wet cell's own convective flux Q U cos θ, zeroed in the face's
    // view, is restored in its 𝒟 = F(W_wet) − F_wall: the neighbouring face subtracts
    // it from the same cell, and without it a thin layer leaving a step would gain
    // Δt Q U/Δx of momentum per step (found by the stiff test's receding tail).
    match wall1 {
        Wall::WetLeft => d_minus -= l.q1 * l.u1 * l.cos,
        Wall::WetRight => d_plus += r.q1 * r.u1 * r.cos,
        Wall::None => {}
    }
    LayerOut {
        phi: 0.5 * (flux1.0 + flux1.1 - v1),
        d_minus,
        d_plus,
    }
}

/// The grains' rows (mass and momentum, with the Coulomb term of the face) of
/// [`face_flux`]; `u_roe` as in [`water_rows`].
#[inline(always)]
fn grain_rows(
    p: &TwoLayerParams,
    k: &FaceCoefficients,
    l: &CellView,
    r: &CellView,
    u_roe: f64,
    step: &StepTerms,
) -> LayerOut {
    let g = p.g;
    let (dt, dx) = (step.dt, step.dx);
    let (fg, (d1l, d1r), (d2l, d2r), h2m) = (k.fg, k.d1, k.d2, k.h2m);
    let (mut q2l, mut q2r) = (l.q2, r.q2);
    let (mut u2l, mut u2r) = (l.u2, r.u2);
    // Grains' view of the bed, lowered at an emerging grain-free cell.
    let (mut bgl, mut bgr) = (l.b, r.b);
    let wet2 = (l.h2 > H_DRY_TWO_LAYER, r.h2 > H_DRY_TWO_LAYER);
    let mut wall2 = Wall::None;
    if wet2.0 && !wet2.1 && bgr > bgl + d2l {
        bgr = bgl + d2l - d2r;
        (u2l, q2l) = (0.0, 0.0);
        wall2 = Wall::WetLeft;
    } else if wet2.1 && !wet2.0 && bgl > bgr + d2r {
        bgl = bgr + d2r - d2l;
        (u2r, q2r) = (0.0, 0.0);
        wall2 = Wall::WetRight;
    }
    let u2 = if wall2 == Wall::None {
        u_roe
    } else {
        roe_velocity(l.sh2, u2l, r.sh2, u2r)
    };
    let cf = fg.cos;

    // R₁ (eq. 88): mass row Δ(Q cos θ); momentum row static + dynamic.
    let flux2 = (q2l * l.cos, q2r * r.cos);
    let r1_3 = flux2.1 - flux2.0;
    let static4 = g
        * cf
        * h2m
        * (p.a2 * (d2r - d2l)
            + p.r * p.a1 * (d1r - d1l)
            + (bgr - bgl)
            + 0.25 * (1.0 - p.a2) * h2m * fg.dcos2);
    let dyn4 = cf * (q2r * u2r - q2l * u2l) + h2m * u2 * u2 * fg.dcos;

    // Coulomb term of the face (eq. 79), times Δx.
    let q2m = 0.5 * (q2l + q2r);
    let fb = p.buoyancy_factor(k.h1m);
    // Without friction nothing is held (δ₀ = 0: the grains are a second fluid).
    let moving = p.tan_delta == 0.0 || q2m.abs() > dt * p.tan_delta * g * fb * h2m * cf;
    // Moving: R₂ = R₁ − TΔx carries the friction; stuck: T = τ_crit = [R₁]₄ˢ cancels
    // the static part, so R₂ keeps only the dynamic part.
    let extra4 = if moving {
        coulomb_normal_stress(p, k.h1m, h2m, cf, u2, fg.dsin_dx)
            * p.tan_delta
            * dx
            * 1.0f64.copysign(q2m)
    } else {
        0.0
    };

    // J ≈ 𝒜⁻¹R₂: jumps of the reconstructed states.
    let (j3, j4) = if k.alpha0 == 0.0 {
        (0.0, 0.0)
    } else {
        // Coulomb-aware bed correction (Garres-Díaz et al. 2021, eq. 22–24 with Escalante et al. 2023's sign) on a
        // moving face: the reconstruction sees the bed tilted by the friction that
        // the face can still exert, at most f_b tan δ₀ Δx/A₂ (in interface-level
        // units), towards stopping ū₂ within Δt. A stuck face (the τ_crit branch)
        // has no grain component in R₂, hence none in 𝒜⁻¹R₂: J₃ = J₄ = 0 below.
        let dc = if moving {
            let cap = if fb == 1.0 {
                step.cap_full
            } else {
                step.cap_reduced
            };
            (u2 * dx / (g * cf * p.a2 * dt)).clamp(-cap, cap)
        } else {
            0.0
        };
        let (e2l, e2r) = reconstruct(d2l, bgl, d2r, bgr + dc);
        // A wall face lets nothing through: no diffusion of that layer.
        let w2 = if wall2 == Wall::None && moving {
            fg.inv_cos2
        } else {
            0.0
        };
        ((e2r - e2l) * w2, (e2r * u2r - e2l * u2l) * w2)
    };
    let v3 = k.alpha1 * r1_3 + k.alpha0 * j3;
    let (mut d_minus, mut d_plus) = split_momentum(
        l.h2, r.h2, static4, moving, dyn4, extra4, j4, k.alpha0, k.alpha1,
    );
    match wall2 {
        Wall::WetLeft => d_minus -= l.q2 * l.u2 * l.cos,
        Wall::WetRight => d_plus += r.q2 * r.u2 * r.cos,
        Wall::None => {}
    }
    LayerOut {
        phi: 0.5 * (flux2.0 + flux2.1 - v3),
        d_minus,
        d_plus,
    }
}

/// 𝒟⁻, 𝒟⁺ of a momentum row with R₁ = `stat` + `dyn_part` and upwinded part
/// V = α₁(stat·[stat_upwinded] + dyn_part + extra) + α₀ J (`extra` = −TΔx, the Coulomb
/// term that eq. 73 puts in the upwinded part only). The parts that do not depend on
/// the velocities are split by own thickness: 𝒟⁻ ∋ (θ_L − m α₁) stat − m α₁ extra,
/// 𝒟⁺ ∋ (θ_R + m α₁) stat + m α₁ extra, m = min(θ_L, θ_R) (½ ∓ ½α₁ for equal
/// thicknesses, i.e. eq. 73): a film beside a thick moving layer is not pushed by the
/// thick layer's friction redistribution either.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn split_momentum(
    hl: f64,
    hr: f64,
    stat: f64,
    stat_upwinded: bool,
    dyn_part: f64,
    extra: f64,
    j: f64,
    alpha0: f64,
    alpha1: f64,
) -> (f64, f64) {
    let hs = hl + hr;
    let theta_l = if hs > 0.0 { hl / hs } else { 0.5 };
    let theta_r = 1.0 - theta_l;
    let m = min_num(theta_l, theta_r) * alpha1;
    let m_stat = if stat_upwinded { m } else { 0.0 };
    let v = alpha1 * dyn_part + alpha0 * j;
    (
        (theta_l - m_stat) * stat - m * extra + 0.5 * (dyn_part - v),
        (theta_r + m_stat) * stat + m * extra + 0.5 * (dyn_part + v),
    )
}
