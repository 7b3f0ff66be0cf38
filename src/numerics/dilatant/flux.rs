//! Well-balanced left/right numerical fluxes for the shallow-water system with volume
//! fraction (Bouchut et al. 2021, §3.1 and Appendix B, eq. B.11–B.13, B.31–B.32), and the apparent
//! topography that carries the basal friction (eq. 3.6–3.12).
//!
//! Homogeneous solver 𝓕 (B.11): HLL for the first two components of
//! F(U) = (φhv, φhv² + ½ g_c φh², φ^α h v), with the wave-speed bounds
//! S_L = min(v_l − c_l, v_r − c_r), S_R = max(v_l + c_l, v_r + c_r), c = √(g_c h)
//! (v ∓ 2c on the side facing a dry state), and the upwind passive transport (B.13) for
//! the third: 𝓕² = 𝓕⁰ φ_{l/r}^{α−1}. HLL keeps φh ≥ 0 and satisfies the entropy
//! inequalities of the first two components with these bounds; Bouchut et al. 2021 uses the
//! Suliciu relaxation solver instead (a three-wave solver, less diffusive on contacts).
//! Theorem B.1 holds for any homogeneous solver with (B.13).
//!
//! Left/right fluxes (B.31)–(B.32), with U* the reconstruction of
//! `reconstruction.rs` and P = ½ g_c φ h²:
//!
//!   F_l = 𝓕(U_l*, U_r*) + (0, P(U_l) − P(U_l*) + 𝓕⁰ g_c ((Δz)₊ − Δz*₊)/v_l, 0),
//!   F_r = 𝓕(U_l*, U_r*) + (0, P(U_r) − P(U_r*) + 𝓕⁰ g_c ((−Δz)₊ − Δz*₋)/v_r, 0).
//!
//! The scheme is U_i ← U_i − Δt/Δx (F_l(U_i, U_{i+1}, Δz_{i+1/2}) − F_r(U_{i−1}, U_i, Δz_{i−1/2}))
//! (3.5). The total topography jump is Δz = Δb̂ + Δb^app (3.6) with the friction as an
//! apparent topography
//!
//!   Δb^app = Δx Proj_μ(X, v_interf/(g_c Δt))                                   (3.7)
//!   v_interf = (φ_l h_l v_l + φ_r h_r v_r)/(φ_l h_l + φ_r h_r)                   (3.8)
//!   X = (h_l − h_r − Δb̂ + (h_l + h_r)(φ_l^{α−1} − φ_r^{α−1})/(2(α−1)(φ_l^{α−1} + φ_r^{α−1})))/Δx   (3.12)
//!   Proj_μ(X, Y) = proj_μ(proj_μ(X) + 2Y/(1 + max(1, −XY/(μ|Y|))))              (3.10)
//!   proj_μ(X) = X if |X| ≤ μ, μ X/|X| otherwise                                 (3.11)
//!
//! μ = μ_eff^interf is evaluated at the interface state (h̄, v_interf, φ̄) with
//! h̄ = ½(h_l + h_r) and φ̄ = (φ_l h_l + φ_r h_r)/(h_l + h_r) (Bouchut et al. 2021 does not say which
//! state; this one is symmetric and reduces to the cell state for equal sides).

use super::reconstruction::{reconstruct, Side};
use crate::physics::dilatancy::{phi_power, pressure, Conserved, DilatantLaw, Primitive};

/// Numerical options of the finite-volume step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxOptions {
    /// α of the third conservative variable φ^α h (α > 1; Bouchut et al. 2021 uses 2).
    pub alpha: f64,
    /// λ of (B.16): 0 (classical) or 1.
    pub lambda: f64,
}

impl Default for FluxOptions {
    fn default() -> Self {
        FluxOptions {
            alpha: 2.0,
            lambda: 0.0,
        }
    }
}

/// The left and right fluxes of one interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceFlux {
    pub left: Conserved,
    pub right: Conserved,
}

#[inline(always)]
fn primitive(s: Side) -> Primitive {
    Primitive {
        h: s.h,
        v: s.v,
        phi: s.phi,
    }
}

/// HLL wave-speed bounds (S_L, S_R) of two states; both dry gives (0, 0).
#[inline(always)]
pub fn wave_bounds(l: Side, r: Side, g_c: f64) -> (f64, f64) {
    let (cl, cr) = ((g_c * l.h).sqrt(), (g_c * r.h).sqrt());
    match (l.h > 0.0, r.h > 0.0) {
        (false, false) => (0.0, 0.0),
        (true, false) => (l.v - cl, l.v + 2.0 * cl),
        (false, true) => (r.v - 2.0 * cr, r.v + cr),
        (true, true) => ((l.v - cl).min(r.v - cr), (l.v + cl).max(r.v + cr)),
    }
}

/// The homogeneous solver 𝓕(U_l, U_r): HLL on (φh, φhv), (B.13) on φ^α h.
#[inline(always)]
pub fn homogeneous_flux(l: Side, r: Side, g_c: f64, alpha: f64) -> Conserved {
    let (sl, sr) = wave_bounds(l, r, g_c);
    let (pl, pr) = (primitive(l), primitive(r));
    let (m, q) = if sl >= 0.0 {
        let f = pl.flux(g_c, alpha);
        (f.m, f.q)
    } else if sr <= 0.0 {
        let f = pr.flux(g_c, alpha);
        (f.m, f.q)
    } else {
        let (fl, fr) = (pl.flux(g_c, alpha), pr.flux(g_c, alpha));
        let (ul, ur) = (pl.conserved(alpha), pr.conserved(alpha));
        let inv = 1.0 / (sr - sl);
        (
            (sr * fl.m - sl * fr.m + sl * sr * (ur.m - ul.m)) * inv,
            (sr * fl.q - sl * fr.q + sl * sr * (ur.q - ul.q)) * inv,
        )
    };
    let upwind = if m >= 0.0 { l.phi } else { r.phi };
    Conserved {
        m,
        q,
        w: m * phi_power(upwind, alpha),
    }
}

/// F_l, F_r of (B.31)–(B.32) for the total topography jump `dz` = z_r − z_l.
#[inline(always)]
pub fn interface_flux(l: Side, r: Side, dz: f64, g_c: f64, opt: FluxOptions) -> InterfaceFlux {
    let alpha = opt.alpha;
    let rec = reconstruct(l, r, dz, opt.lambda, g_c, alpha);
    let ls = Side {
        h: rec.h_l,
        v: l.v,
        phi: rec.phi_l,
    };
    let rs = Side {
        h: rec.h_r,
        v: r.v,
        phi: rec.phi_r,
    };
    let f = homogeneous_flux(ls, rs, g_c, alpha);
    // ((Δz)₊ − Δz*₊)/v is bounded by λ|v|/(2g_c) (B.18): zero when the numerator is.
    let kinetic = |gap: f64, v: f64| if gap == 0.0 { 0.0 } else { f.m * g_c * gap / v };
    // The pressure differences are formed first, so that an unchanged side adds 0.
    let left_q = f.q
        + (pressure(g_c, l.h, l.phi) - pressure(g_c, rec.h_l, rec.phi_l))
        + kinetic(dz.max(0.0) - rec.dz_plus, l.v);
    let right_q = f.q
        + (pressure(g_c, r.h, r.phi) - pressure(g_c, rec.h_r, rec.phi_r))
        + kinetic((-dz).max(0.0) - rec.dz_minus, r.v);
    InterfaceFlux {
        left: Conserved { q: left_q, ..f },
        right: Conserved { q: right_q, ..f },
    }
}

/// proj_μ(X) of (3.11).
#[inline(always)]
pub fn proj(mu: f64, x: f64) -> f64 {
    if x.abs() <= mu {
        x
    } else {
        mu * x.signum()
    }
}

/// Proj_μ(X, Y) of (3.10) (one space dimension: X·Y = XY, |Y| = |Y|).
#[inline(always)]
pub fn proj_friction(mu: f64, x: f64, y: f64) -> f64 {
    if y == 0.0 {
        return proj(mu, proj(mu, x));
    }
    let opposing = if mu > 0.0 {
        -x * y / (mu * y.abs())
    } else if x * y < 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    proj(mu, proj(mu, x) + 2.0 / (1.0 + opposing.max(1.0)) * y)
}

/// The part of X_interf Δx (3.12) without the topography: h_l − h_r +
/// (h_l + h_r)(φ_l^{α−1} − φ_r^{α−1})/(2(α−1)(φ_l^{α−1} + φ_r^{α−1})). It is the jump Δz
/// that the friction makes of a resting interface below its threshold.
#[inline(always)]
pub fn rest_jump(l: Side, r: Side, alpha: f64) -> f64 {
    let (al, ar) = (phi_power(l.phi, alpha), phi_power(r.phi, alpha));
    let fraction_term = if al == ar {
        0.0
    } else {
        (l.h + r.h) * (al - ar) / (2.0 * (alpha - 1.0) * (al + ar))
    };
    (l.h - r.h) + fraction_term
}

/// X_interf of (3.12), times Δx.
#[inline(always)]
pub fn driving_slope_times_dx(l: Side, r: Side, db_hat: f64, alpha: f64) -> f64 {
    rest_jump(l, r, alpha) - db_hat
}

/// v_interf of (3.8) (0 between two dry cells).
#[inline(always)]
pub fn interface_velocity(l: Side, r: Side) -> f64 {
    let (ml, mr) = (l.phi * l.h, r.phi * r.h);
    let m = ml + mr;
    if m > 0.0 {
        (ml * l.v + mr * r.v) / m
    } else {
        0.0
    }
}

/// Time step and grid seen by the friction of a face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceGrid {
    pub g_c: f64,
    pub dx: f64,
    pub dt: f64,
}

/// The total topography jump Δz = Δb̂ + Δb^app of (3.6)–(3.12), and v_interf.
#[inline(always)]
pub fn total_topography_jump(
    law: &DilatantLaw,
    l: Side,
    r: Side,
    db_hat: f64,
    grid: FaceGrid,
    alpha: f64,
) -> (f64, f64) {
    let FaceGrid { g_c, dx, dt } = grid;
    let v = interface_velocity(l, r);
    let h_sum = l.h + r.h;
    if h_sum <= 0.0 {
        return (db_hat, 0.0);
    }
    let h_bar = 0.5 * h_sum;
    let phi_bar = (l.phi * l.h + r.phi * r.h) / h_sum;
    let mu = law.mu_eff(g_c, h_bar, v, phi_bar);
    let x_dx = driving_slope_times_dx(l, r, db_hat, alpha);
    let x = x_dx / dx;
    if v == 0.0 && x.abs() <= mu {
        // At rest below the threshold Δz = Δb̂ + XΔx: formed without Δb̂ − Δb̂, so that
        // the reconstruction of (3.13) data is exact whenever h_l − h_r is.
        return (rest_jump(l, r, alpha), v);
    }
    let app = dx * proj_friction(mu, x, v / (g_c * dt));
    (db_hat + app, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    const G: f64 = 9.81;

    fn side(h: f64, v: f64, phi: f64) -> Side {
        Side { h, v, phi }
    }

    fn opt(alpha: f64, lambda: f64) -> FluxOptions {
        FluxOptions { alpha, lambda }
    }

    #[test]
    fn flat_jump_gives_the_homogeneous_flux_and_consistency() {
        // Theorem B.1 (i), (vi): F_l = F_r = 𝓕 when Δz = 0, and 𝓕(U, U) = F(U).
        let (l, r) = (side(0.2, 0.5, 0.6), side(0.1, -0.3, 0.55));
        let f = interface_flux(l, r, 0.0, G, opt(2.0, 1.0));
        assert_eq!(f.left, f.right);
        assert_eq!(f.left, homogeneous_flux(l, r, G, 2.0));
        let f = interface_flux(l, l, 0.0, G, opt(2.0, 0.0));
        let exact = primitive(l).flux(G, 2.0);
        assert_relative_eq!(f.left.m, exact.m, max_relative = 1e-14);
        assert_relative_eq!(f.left.q, exact.q, max_relative = 1e-14);
        assert_relative_eq!(f.left.w, exact.w, max_relative = 1e-14);
    }

    #[test]
    fn steady_states_at_rest_give_the_physical_fluxes() {
        // (B.35): F_l = F(U_l), F_r = F(U_r) for both families of (3.13).
        for alpha in [2.0, 3.0] {
            // φ constant, h + z constant.
            // Binary-exact data: exactly the physical fluxes.
            let (l, r) = (side(0.75, 0.0, 0.6), side(0.5, 0.0, 0.6));
            let f = interface_flux(l, r, 0.25, G, opt(alpha, 0.0));
            assert_eq!(f.left.m, 0.0);
            assert_eq!(f.left.q, pressure(G, 0.75, 0.6));
            assert_eq!(f.right.q, pressure(G, 0.5, 0.6));
            // h φ^{1−α} constant.
            let (h_l, phi_l, phi_r): (f64, f64, f64) = (0.3, 0.62, 0.5);
            let h_r = h_l * (phi_r / phi_l).powf(alpha - 1.0);
            let dz = (alpha - 0.5) / (alpha - 1.0) * (h_l - h_r);
            let (l, r) = (side(h_l, 0.0, phi_l), side(h_r, 0.0, phi_r));
            for f in [
                interface_flux(l, r, dz, G, opt(alpha, 0.0)),
                interface_flux(r, l, -dz, G, opt(alpha, 1.0)),
            ] {
                // Up to the round-off of φ^{α−1} in the data.
                assert!(f.left.m.abs() < 1e-15 && f.left.w.abs() < 1e-15, "{f:?}");
            }
            let f = interface_flux(l, r, dz, G, opt(alpha, 0.0));
            assert_relative_eq!(f.left.q, pressure(G, h_l, phi_l), max_relative = 1e-12);
            assert_relative_eq!(f.right.q, pressure(G, h_r, phi_r), max_relative = 1e-12);
        }
    }

    #[test]
    fn topography_jump_is_consistent_with_the_source() {
        // (B.55): F_r¹ − F_l¹ = −g_c φ h Δz + o(Δz) at a smooth state.
        for (phi_r, v) in [(0.6, 0.0), (0.6, 0.4), (0.59, 0.4), (0.61, -0.3)] {
            let (l, r) = (side(0.2, v, 0.6), side(0.2, v, phi_r));
            let mut errors = Vec::new();
            for dz in [1e-3, 1e-4] {
                let f = interface_flux(l, r, dz, G, opt(2.0, 0.0));
                let g = interface_flux(l, r, 0.0, G, opt(2.0, 0.0));
                let jump = (f.right.q - f.left.q) - (g.right.q - g.left.q);
                errors.push((jump + G * 0.6 * 0.2 * dz).abs() / dz);
            }
            // The relative error is O(Δz) or O(Δφ): it falls with Δz or stays small.
            assert!(errors[1] < 0.2 * G * 0.6 * 0.2, "{errors:?}");
        }
    }

    #[test]
    fn friction_projection_at_rest_and_in_motion() {
        // (3.10)–(3.11): at rest the apparent slope is X below the threshold, μ above;
        // in fast motion it is μ sgn(v).
        assert_eq!(proj_friction(0.5, 0.3, 0.0), 0.3);
        assert_eq!(proj_friction(0.5, -0.8, 0.0), -0.5);
        assert_eq!(proj_friction(0.5, 0.0, 1e3), 0.5);
        assert_eq!(proj_friction(0.5, 0.0, -1e3), -0.5);
        // Y small and along X: X + Y; against X: the factor 2/(1 + |X|/μ) reduces Y.
        assert_relative_eq!(proj_friction(0.5, 0.1, 0.1), 0.2);
        assert_relative_eq!(proj_friction(0.5, 0.4, -0.1), 0.4 - 0.1);
        assert_relative_eq!(proj_friction(0.5, 1.0, -0.1), 0.5 - 2.0 / 3.0 * 0.1);
    }

    #[test]
    fn driving_slope_matches_eq_3_9() {
        // (3.12) ≈ −(∂_x(h + b̂) + h/(2φ) ∂_x φ) for a smooth profile.
        let dx = 1e-4;
        let (l, r) = (
            side(0.2, 0.0, 0.6),
            side(0.2 + 0.3 * dx, 0.0, 0.6 - 0.1 * dx),
        );
        let x = driving_slope_times_dx(l, r, 0.05 * dx, 2.0) / dx;
        assert_relative_eq!(
            x,
            -(0.3 + 0.05) + 0.2 / (2.0 * 0.6) * 0.1,
            max_relative = 1e-3
        );
    }

    fn fraction() -> impl Strategy<Value = f64> {
        0.05f64..0.95
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// (B.13), Theorem B.1 (i), (vii) and the one-interface minimum principle
        /// (B.67) with σ = S_L, S_R of the reconstructed states.
        #[test]
        fn flux_properties(
            h_l in 0.0f64..1.0, h_r in 0.0f64..1.0,
            v_l in -3.0f64..3.0, v_r in -3.0f64..3.0,
            phi_l in fraction(), phi_r in fraction(),
            dz in -0.5f64..0.5, lambda in prop_oneof![Just(0.0), Just(1.0)],
            alpha in prop_oneof![Just(2.0), Just(3.0)],
        ) {
            let (l, r) = (side(h_l, v_l, phi_l), side(h_r, v_r, phi_r));
            let f = interface_flux(l, r, dz, G, opt(alpha, lambda));
            prop_assert!(f.left.m.is_finite() && f.left.q.is_finite() && f.right.q.is_finite());
            // Conservative in the first and third components.
            prop_assert_eq!(f.left.m, f.right.m);
            prop_assert_eq!(f.left.w, f.right.w);
            // (B.13) with a reconstructed fraction in [φ_l, φ_r] (B.28).
            if f.left.m != 0.0 {
                let ratio = f.left.w / f.left.m;
                let (lo, hi) = (phi_power(phi_l.min(phi_r), alpha), phi_power(phi_l.max(phi_r), alpha));
                prop_assert!(lo * (1.0 - 1e-14) <= ratio && ratio <= hi * (1.0 + 1e-14));
            }
            // (vii): equal fractions are transported exactly.
            let g = interface_flux(side(h_l, v_l, phi_l), side(h_r, v_r, phi_l), dz, G, opt(alpha, lambda));
            prop_assert!((g.left.w - g.left.m * phi_power(phi_l, alpha)).abs() <= 1e-15 * g.left.m.abs());
            // No mass leaves a dry cell.
            if h_l == 0.0 { prop_assert!(f.left.m <= 0.0); }
            if h_r == 0.0 { prop_assert!(f.left.m >= 0.0); }
        }
    }
}
